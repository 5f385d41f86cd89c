//! `--noise-spec FILE.yaml`: a user's own model, every term, per sensor, optionally per axis.
//!
//! ```yaml
//! # units: gyroscope terms in rad/s-based units, accelerometer in m/s^2-based units
//! base: bmi088                  # optional: start from a profile (default: every term off)
//! gyroscope:
//!   internal_rate_hz: 2000      # optional; default the output rate
//!   filter: {kind: butterworth2, cutoff_hz: 23}   # or {kind: none} / {kind: average}
//!   white_noise: 2.44e-4        # N [rad/s/sqrt(Hz)]
//!   random_walk: 4.0e-7         # K [rad/s^2/sqrt(Hz)]
//!   bias_instability: {value: 9.7e-6, tau_lo_s: 5, tau_hi_s: 500}   # B [rad/s]; value 0 = off
//!   gauss_markov: [{sigma: 3.0e-5, tau_s: 20}]                      # [] = off
//!   rate_ramp: 0.0              # R [rad/s^2]
//!   quantization: 0.0           # Q [rad]
//!   resolution: 1.065e-3        # output LSB [rad/s]
//!   warmup: {amplitude: 2.6e-4, tau_s: 300}           # [rad/s], or
//!   # warmup: {temperature_rise_k: 1, tau_s: 300, bias_per_k: 2.6e-4}
//!   lines: [{frequency_hz: 0.5, amplitude: 2.0e-4}, {frequency_hz: 17, amplitude: 1.0e-3, bandwidth_hz: 0.5}]
//!                               # vibration lines [Hz, rad/s]; bandwidth: a resonance; [] = off
//!   axes:                       # optional per-axis overrides, same keys as above
//!     z: {white_noise: 3.0e-4}
//! accelerometer: { ... }        # the same keys, m/s^2-based units
//! ```
//! Keys given at the sensor level apply to the three axes, then `axes` overrides one axis;
//! keys not given keep the base's value. Unknown keys are errors (a typo must not silently
//! drop a term). A `<bag>.truth.yaml` written by `sim bag` is also accepted: its `model`
//! section is such a spec.

use bag2mat::Sensor;
use serde::Deserialize;
use std::path::Path;

use super::model::{
    AxisModel, BiasInstability, Chain, Filter, GaussMarkov, ImuModel, Line, SensorModel, Warmup,
};
use super::profiles::Profile;
use crate::error::{Result, SimError, SpecError};

/// `bias_instability:` in a spec.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BiSpec {
    /// B.
    pub value: f64,
    /// Shortest τ of the floor, s.
    pub tau_lo_s: f64,
    /// Longest τ of the floor, s.
    pub tau_hi_s: f64,
}

/// One entry of `gauss_markov:`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GmSpec {
    /// σ.
    pub sigma: f64,
    /// T, s.
    pub tau_s: f64,
}

/// One entry of `lines:`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LineSpec {
    /// f₀, Hz.
    pub frequency_hz: f64,
    /// A.
    pub amplitude: f64,
    /// −3 dB bandwidth of a resonance, Hz (absent or 0: a sinusoid).
    pub bandwidth_hz: Option<f64>,
}

/// `warmup:` — either `amplitude` or `temperature_rise_k` with `bias_per_k`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WarmupSpec {
    /// A.
    pub amplitude: Option<f64>,
    /// T, s.
    pub tau_s: f64,
    /// ΔT, K.
    pub temperature_rise_k: Option<f64>,
    /// Bias sensitivity, unit per K.
    pub bias_per_k: Option<f64>,
}

/// `filter:`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilterSpec {
    /// `none`, `butterworth2` or `average`.
    pub kind: String,
    /// −3 dB frequency for `butterworth2`, Hz.
    pub cutoff_hz: Option<f64>,
}

macro_rules! term_struct {
    ($(#[$meta:meta])* $name:ident { $($extra:tt)* }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Default, PartialEq, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            /// N.
            pub white_noise: Option<f64>,
            /// K.
            pub random_walk: Option<f64>,
            /// B and its corners.
            pub bias_instability: Option<BiSpec>,
            /// Gauss–Markov biases.
            pub gauss_markov: Option<Vec<GmSpec>>,
            /// R.
            pub rate_ramp: Option<f64>,
            /// Q.
            pub quantization: Option<f64>,
            /// LSB.
            pub resolution: Option<f64>,
            /// Warm-up.
            pub warmup: Option<WarmupSpec>,
            /// Vibration lines.
            pub lines: Option<Vec<LineSpec>>,
            $($extra)*
        }
    };
}

term_struct!(
    /// One axis's overrides.
    AxisSpec {}
);

/// `axes:`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxesSpec {
    /// x.
    pub x: Option<AxisSpec>,
    /// y.
    pub y: Option<AxisSpec>,
    /// z.
    pub z: Option<AxisSpec>,
}

term_struct!(
    /// One sensor.
    SensorSpec {
        /// Internal rate, Hz.
        pub internal_rate_hz: Option<f64>,
        /// Filter.
        pub filter: Option<FilterSpec>,
        /// Per-axis overrides.
        pub axes: Option<AxesSpec>,
    }
);

/// A whole spec file.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpecFile {
    /// Profile to start from.
    pub base: Option<String>,
    /// Gyroscope.
    pub gyroscope: Option<SensorSpec>,
    /// Accelerometer.
    pub accelerometer: Option<SensorSpec>,
}

/// A truth file seen as a spec: only its format tag and model section.
#[derive(Debug, Deserialize)]
struct TruthAsSpec {
    format: Option<String>,
    model: Option<SpecFile>,
}

/// The format tag of `<bag>.truth.yaml`.
pub const TRUTH_FORMAT: &str = "sim-truth-1";

fn err(path: &Path, msg: impl std::fmt::Display) -> SimError {
    SimError::Spec {
        path: path.to_path_buf(),
        msg: msg.to_string(),
    }
}

/// Reads and parses a spec (or truth) file.
pub(crate) fn read(path: &Path) -> Result<SpecFile> {
    let text = std::fs::read_to_string(path).map_err(|e| SimError::io(path, e))?;
    parse(&text).map_err(|m| err(path, m))
}

/// Parses spec text; the message says what is wrong and where.
pub(crate) fn parse(text: &str) -> std::result::Result<SpecFile, SpecError> {
    if let Ok(t) = serde_saphyr::from_str::<TruthAsSpec>(text)
        && t.format.as_deref() == Some(TRUTH_FORMAT)
    {
        return t.model.ok_or(SpecError::TruthWithoutModel);
    }
    serde_saphyr::from_str::<SpecFile>(text).map_err(|e| SpecError::Yaml(e.to_string()))
}

fn apply_terms(a: &mut AxisModel, s: &AxisSpecRef<'_>) -> std::result::Result<(), SpecError> {
    if let Some(v) = s.white_noise {
        a.white_noise = v;
    }
    if let Some(v) = s.random_walk {
        a.random_walk = v;
    }
    if let Some(b) = s.bias_instability {
        a.bias_instability = (b.value != 0.0).then_some(BiasInstability {
            b: b.value,
            tau_lo: b.tau_lo_s,
            tau_hi: b.tau_hi_s,
        });
    }
    if let Some(g) = s.gauss_markov {
        a.gauss_markov = g
            .iter()
            .map(|g| GaussMarkov {
                sigma: g.sigma,
                tau: g.tau_s,
            })
            .collect();
    }
    if let Some(v) = s.rate_ramp {
        a.rate_ramp = v;
    }
    if let Some(v) = s.quantization {
        a.quantization = v;
    }
    if let Some(v) = s.resolution {
        a.resolution = v;
    }
    if let Some(l) = s.lines {
        a.lines = l
            .iter()
            .map(|l| Line {
                frequency: l.frequency_hz,
                amplitude: l.amplitude,
                bandwidth: l.bandwidth_hz.unwrap_or(0.0),
            })
            .collect();
    }
    if let Some(w) = s.warmup {
        a.warmup = match (w.amplitude, w.temperature_rise_k, w.bias_per_k) {
            (Some(0.0), None, None) => None,
            (Some(amplitude), None, None) => Some(Warmup::Exponential {
                amplitude,
                tau: w.tau_s,
            }),
            (None, Some(t), Some(s)) => Some(Warmup::Thermal {
                temperature_rise: t,
                tau: w.tau_s,
                sensitivity: s,
            }),
            _ => {
                return Err(SpecError::Warmup);
            }
        };
    }
    Ok(())
}

/// The term fields of either struct, borrowed.
struct AxisSpecRef<'a> {
    white_noise: Option<f64>,
    random_walk: Option<f64>,
    bias_instability: Option<BiSpec>,
    gauss_markov: Option<&'a Vec<GmSpec>>,
    rate_ramp: Option<f64>,
    quantization: Option<f64>,
    resolution: Option<f64>,
    warmup: Option<WarmupSpec>,
    lines: Option<&'a Vec<LineSpec>>,
}

macro_rules! terms_ref {
    ($s:expr) => {
        AxisSpecRef {
            white_noise: $s.white_noise,
            random_walk: $s.random_walk,
            bias_instability: $s.bias_instability,
            gauss_markov: $s.gauss_markov.as_ref(),
            rate_ramp: $s.rate_ramp,
            quantization: $s.quantization,
            resolution: $s.resolution,
            warmup: $s.warmup,
            lines: $s.lines.as_ref(),
        }
    };
}

fn apply_sensor(m: &mut SensorModel, s: &SensorSpec) -> std::result::Result<(), SpecError> {
    if let Some(r) = s.internal_rate_hz {
        m.chain.internal_rate_hz = Some(r);
    }
    if let Some(f) = &s.filter {
        m.chain.filter = match (f.kind.as_str(), f.cutoff_hz) {
            ("none", None) => Filter::None,
            ("average", None) => Filter::Average,
            ("butterworth2", Some(c)) => Filter::Butterworth2 { cutoff_hz: c },
            ("butterworth2", None) => return Err(SpecError::CutoffMissing),
            ("none" | "average", Some(_)) => {
                return Err(SpecError::CutoffUnused(f.kind.clone()));
            }
            (k, _) => {
                return Err(SpecError::FilterKind(k.to_string()));
            }
        };
    }
    let common = terms_ref!(s);
    for a in m.axes.iter_mut() {
        apply_terms(a, &common)?;
    }
    if let Some(axes) = &s.axes {
        for (i, ax) in [&axes.x, &axes.y, &axes.z].into_iter().enumerate() {
            if let Some(ax) = ax {
                apply_terms(&mut m.axes[i], &terms_ref!(ax)).map_err(|e| SpecError::Axis {
                    axis: super::model::AXES[i],
                    error: Box::new(e),
                })?;
            }
        }
    }
    Ok(())
}

/// An all-zero model generated at the output rate.
pub(crate) fn zero_model(label: &str) -> ImuModel {
    ImuModel {
        label: label.to_string(),
        gyro: SensorModel::uniform(AxisModel::default()),
        acc: SensorModel::uniform(AxisModel::default()),
    }
}

/// Applies `spec` on top of `base` (or on the spec's own `base:` profile, or on the zero model).
pub(crate) fn apply(spec: &SpecFile, base: Option<ImuModel>, path: &Path) -> Result<ImuModel> {
    let mut m = match (base, &spec.base) {
        (Some(b), _) => b,
        (None, Some(name)) => Profile::from_name(name)
            .ok_or_else(|| {
                err(
                    path,
                    format!(
                        "unknown base profile '{name}' (known: {})",
                        Profile::ALL.map(|p| p.name()).join(", ")
                    ),
                )
            })?
            .model(),
        (None, None) => zero_model("spec"),
    };
    for (s, spec_s) in [
        (Sensor::Gyro, &spec.gyroscope),
        (Sensor::Acc, &spec.accelerometer),
    ] {
        if let Some(ss) = spec_s {
            apply_sensor(m.sensor_mut(s), ss)
                .map_err(|e| err(path, format!("{}: {e}", s.name())))?;
        }
    }
    m.label = format!("{} + spec {}", m.label, path.display());
    Ok(m)
}

impl Chain {
    /// Helper for the spec writer: the filter as spec keys.
    pub fn filter_spec(&self) -> (&'static str, Option<f64>) {
        match self.filter {
            Filter::None => ("none", None),
            Filter::Average => ("average", None),
            Filter::Butterworth2 { cutoff_hz } => ("butterworth2", Some(cutoff_hz)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sensor_level_then_axis_overrides_on_a_base() {
        let text = "
base: medium
gyroscope:
  internal_rate_hz: 1000
  filter: {kind: butterworth2, cutoff_hz: 50}
  bias_instability: {value: 1.0e-5, tau_lo_s: 1, tau_hi_s: 100}
  axes:
    z: {white_noise: 0.5, warmup: {temperature_rise_k: 2, tau_s: 60, bias_per_k: 1.0e-4}}
accelerometer:
  quantization: 1.0e-6
  lines: [{frequency_hz: 0.5, amplitude: 2.0e-3}, {frequency_hz: 17, amplitude: 1.0e-3, bandwidth_hz: 0.5}]
";
        let s = parse(text).unwrap();
        let m = apply(&s, None, Path::new("t.yaml")).unwrap();
        assert_eq!(m.gyro.chain.internal_rate_hz, Some(1000.0));
        assert_eq!(m.gyro.axes[0].white_noise, 0.015, "base kept");
        assert_eq!(m.gyro.axes[2].white_noise, 0.5);
        assert!(m.gyro.axes.iter().all(|a| a.bias_instability.is_some()));
        assert_eq!(m.gyro.axes[2].warmup.unwrap().amplitude(), -2e-4);
        assert!(m.gyro.axes[0].warmup.is_none());
        assert!(m.acc.axes.iter().all(|a| a.quantization == 1e-6));
        assert_eq!(m.acc.axes[1].random_walk, 5e-4);
        assert_eq!(
            m.acc.axes[2].lines,
            vec![
                Line {
                    frequency: 0.5,
                    amplitude: 2e-3,
                    bandwidth: 0.0
                },
                Line {
                    frequency: 17.0,
                    amplitude: 1e-3,
                    bandwidth: 0.5
                }
            ]
        );
        assert!(m.gyro.axes[0].lines.is_empty());
    }

    #[test]
    fn bad_specs_give_clear_errors() {
        for (text, needle) in [
            ("gyroscope: {white_nose: 1}", "white_nose"),
            (
                "gyroscope: {filter: {kind: chebyshev}}",
                "unknown filter kind",
            ),
            (
                "gyroscope: {filter: {kind: butterworth2}}",
                "needs cutoff_hz",
            ),
            ("base: bmi999", "unknown base profile"),
            ("gyroscope: {warmup: {tau_s: 3}}", "warmup needs"),
            ("gyroscope: {white_noise: abc}", "white_noise"),
            ("gyroscope: [1, 2]", "gyroscope"),
        ] {
            let r = parse(text)
                .map_err(|e| e.to_string())
                .and_then(|s| apply(&s, None, Path::new("x.yaml")).map_err(|e| e.to_string()));
            let e = r.expect_err(text);
            assert!(e.contains(needle), "{text}: {e}");
        }
    }
}
