//! The real-sensor noise model: every IEEE Std 952 term per axis, in continuous-time
//! parameters, plus the sensor's own signal chain (internal rate, digital low-pass, decimation).
//!
//! # Terms (per axis; U = rad/s for the gyroscope, m/s² for the accelerometer)
//!
//! | field | term | unit | Allan deviation (continuous limit) |
//! |---|---|---|---|
//! | `white_noise` | white noise density N (ARW/VRW) | U/√Hz | N/√τ |
//! | `random_walk` | bias random walk K | U/s/√Hz | K·√(τ/3) |
//! | `bias_instability` | flicker bias B between corner times | U | 0.664·B (floor) |
//! | `gauss_markov` | first-order Gauss–Markov bias (σ, T) | U, s | bump near τ ≈ 1.9·T |
//! | `rate_ramp` | deterministic ramp R | U/s | R·τ/√2 |
//! | `quantization` | IEEE 952 Q, on the integrated angle/velocity | U·s | √3·Q/τ |
//! | `resolution` | output LSB: values rounded to counts | U | white: AVAR r²/(12·m), m = τ·f |
//! | `warmup` | exponential bias settling after power-on | U, s | deterministic |
//! | `lines` | IEEE 952 sinusoidal noise A·sin(2πf₀t + φ), or with a bandwidth a lightly damped 2nd-order resonance driven by white noise (rms A/√2) | Hz, U | A²·sin⁴(πf₀τ)/(πf₀τ)² (a bump near τ ≈ 0.37/f₀, ripples beyond) |
//!
//! Where each term enters the chain (and so what the truth in [`super::truth`] computes):
//! the white noise is generated at the internal rate, low-pass filtered and decimated; the
//! bias terms (random walk, flicker, Gauss–Markov, ramp, warm-up) are generated at the output
//! rate and added after the filter (their power lies decades below any DLPF corner, so the
//! filter would change them by less than (f/f_c)⁴; leaving them out of it keeps their truth
//! exact and the generator cheap); so are the lines, whose amplitude is the one the output
//! carries (a vibration as the sensor's filter has already shaped it, what a PSD of the
//! record shows); the sum plus the motion signal is then quantised: first the integrated
//! angle/velocity (IEEE 952 Q), then the output value to its LSB.

use std::fmt::Write as _;

use crate::error::{Result, SimError};

/// The two sensors of an IMU (the workspace's one sensor type, with the units of each term).
use allan_kalibr::NoiseTerm;
use bag2mat::Sensor;

/// Axis names.
pub const AXES: [&str; 3] = ["x", "y", "z"];

/// Flicker (1/f) bias noise whose Allan deviation floor is √(2 ln 2/π)·B ≈ 0.664·B between
/// the corner times.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasInstability {
    /// B, U.
    pub b: f64,
    /// Shortest τ of the floor, s.
    pub tau_lo: f64,
    /// Longest τ of the floor, s.
    pub tau_hi: f64,
}

/// The shortest floor corner τ_lo ([`BiasInstability::tau_lo`]) must span at least this many
/// output samples (below it the discrete sampling of the fastest component of
/// [`super::flicker::components`] shapes the floor).
pub const MIN_TAU_SAMPLES: f64 = 10.0;

/// First-order Gauss–Markov bias: stationary, standard deviation σ, correlation time T.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussMarkov {
    /// σ, U.
    pub sigma: f64,
    /// T, s.
    pub tau: f64,
}

/// Bias settling after power-on: b(t) = A·e^(−t/T), directly or through a simulated
/// temperature T(t) = T₀ + ΔT·(1 − e^(−t/T)) with a bias sensitivity s (then A = −s·ΔT).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Warmup {
    /// A (U) and T (s) given directly.
    Exponential {
        /// A, U: the bias offset at power-on relative to the settled bias.
        amplitude: f64,
        /// T, s.
        tau: f64,
    },
    /// Self-heating by ΔT (K) with thermal time constant T (s), bias sensitivity s (U/K).
    Thermal {
        /// ΔT, K.
        temperature_rise: f64,
        /// T, s.
        tau: f64,
        /// s, U/K.
        sensitivity: f64,
    },
}

impl Warmup {
    /// A, U (b(t) = A·e^(−t/T) relative to the settled bias).
    pub(crate) fn amplitude(&self) -> f64 {
        match *self {
            Warmup::Exponential { amplitude, .. } => amplitude,
            Warmup::Thermal {
                temperature_rise,
                sensitivity,
                ..
            } => -sensitivity * temperature_rise,
        }
    }

    /// T, s.
    pub(crate) fn tau(&self) -> f64 {
        match *self {
            Warmup::Exponential { tau, .. } | Warmup::Thermal { tau, .. } => tau,
        }
    }
}

/// A vibration line (IEEE 952 sinusoidal noise) at the output: a sinusoid of amplitude A at
/// f₀ with a random phase, or with a bandwidth, a lightly damped 2nd-order resonance driven
/// by white noise (centre f₀, −3 dB width B, damping ζ = B/(2f₀), variance A²/2: the
/// sinusoid of the same power).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// f₀, Hz (below half the output rate).
    pub frequency: f64,
    /// A, U.
    pub amplitude: f64,
    /// B, Hz (0: a sinusoid; below f₀).
    pub bandwidth: f64,
}

/// Every term of one axis (module doc for units). Zero / `None` / empty = term off.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct AxisModel {
    /// N, U/√Hz.
    pub white_noise: f64,
    /// K, U/s/√Hz.
    pub random_walk: f64,
    /// B and its corner times.
    pub bias_instability: Option<BiasInstability>,
    /// Gauss–Markov biases.
    pub gauss_markov: Vec<GaussMarkov>,
    /// R, U/s.
    pub rate_ramp: f64,
    /// Q, U·s.
    pub quantization: f64,
    /// Output LSB, U.
    pub resolution: f64,
    /// Warm-up.
    pub warmup: Option<Warmup>,
    /// Vibration lines.
    pub lines: Vec<Line>,
}

impl AxisModel {
    /// Only white noise and random walk (the ideal IMU of vio_data_simulation).
    pub fn ideal(white_noise: f64, random_walk: f64) -> Self {
        AxisModel {
            white_noise,
            random_walk,
            ..Default::default()
        }
    }

    /// True when nothing but N and K is on.
    pub fn is_ideal(&self) -> bool {
        self.bias_instability.is_none()
            && self.gauss_markov.is_empty()
            && self.rate_ramp == 0.0
            && self.quantization == 0.0
            && self.resolution == 0.0
            && self.warmup.is_none()
            && self.lines.is_empty()
    }
}

/// The sensor's digital low-pass filter, run at the internal rate before decimation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Filter {
    /// None: decimation is plain sub-sampling (aliases the white noise).
    None,
    /// 2nd-order Butterworth low-pass, bilinear transform with pre-warping; −3 dB at the cutoff.
    Butterworth2 {
        /// −3 dB frequency, Hz.
        cutoff_hz: f64,
    },
    /// Average of the internal samples of each output sample (boxcar decimation filter, as
    /// the ADIS1647x decimation stage).
    Average,
}

/// Internal rate and filter of one sensor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chain {
    /// Internal sample rate, Hz; `None` = the output rate (no decimation).
    pub internal_rate_hz: Option<f64>,
    /// The digital low-pass filter.
    pub filter: Filter,
}

impl Chain {
    /// No internal rate, no filter: samples are generated at the output rate.
    pub const DIRECT: Chain = Chain {
        internal_rate_hz: None,
        filter: Filter::None,
    };

    /// True for [`Chain::DIRECT`] (or an internal rate equal to `output_rate` without filter).
    pub fn is_direct(&self, output_rate: f64) -> bool {
        self.filter == Filter::None
            && self
                .internal_rate_hz
                .is_none_or(|r| (r - output_rate).abs() <= 1e-9 * output_rate)
    }

    /// The chain at a given output rate: internal rate, decimation factor.
    pub fn resolve(&self, sensor: Sensor, output_rate: f64) -> Result<ResolvedChain> {
        let internal = self.internal_rate_hz.unwrap_or(output_rate);
        let bad = |msg: String| SimError::InvalidArgument(format!("{}: {msg}", sensor.name()));
        if !(internal.is_finite() && internal > 0.0) {
            return Err(bad(format!(
                "internal rate must be a positive number of Hz, got {internal}"
            )));
        }
        let ratio = internal / output_rate;
        let d = ratio.round();
        if d < 1.0 || (ratio - d).abs() > 1e-9 * ratio {
            return Err(bad(format!(
                "internal rate {internal} Hz is not an integer multiple of the output rate {output_rate} Hz"
            )));
        }
        if let Filter::Butterworth2 { cutoff_hz } = self.filter
            && !(cutoff_hz.is_finite() && cutoff_hz > 0.0 && cutoff_hz < 0.5 * internal)
        {
            return Err(bad(format!(
                "low-pass cutoff {cutoff_hz} Hz must be positive and below half the internal rate ({} Hz)",
                0.5 * internal
            )));
        }
        Ok(ResolvedChain {
            internal_rate: internal,
            decimation: d as usize,
            filter: self.filter,
        })
    }
}

/// A [`Chain`] at a known output rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResolvedChain {
    /// Internal rate, Hz.
    pub internal_rate: f64,
    /// Internal samples per output sample.
    pub decimation: usize,
    /// The filter.
    pub filter: Filter,
}

/// One sensor: its chain and its three axes.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorModel {
    /// Internal rate and filter.
    pub chain: Chain,
    /// x, y, z.
    pub axes: [AxisModel; 3],
}

impl SensorModel {
    /// The same terms on every axis, generated at the output rate.
    pub fn uniform(axis: AxisModel) -> Self {
        SensorModel {
            chain: Chain::DIRECT,
            axes: [axis.clone(), axis.clone(), axis],
        }
    }
}

/// A whole IMU noise model.
#[derive(Debug, Clone, PartialEq)]
pub struct ImuModel {
    /// What it is (profile name, "spec FILE", …), written into the truth file.
    pub label: String,
    /// Gyroscope.
    pub gyro: SensorModel,
    /// Accelerometer.
    pub acc: SensorModel,
}

impl ImuModel {
    /// The sensor model by kind.
    pub fn sensor(&self, s: Sensor) -> &SensorModel {
        match s {
            Sensor::Gyro => &self.gyro,
            Sensor::Acc => &self.acc,
        }
    }

    /// Mutable sensor model by kind.
    pub(crate) fn sensor_mut(&mut self, s: Sensor) -> &mut SensorModel {
        match s {
            Sensor::Gyro => &mut self.gyro,
            Sensor::Acc => &mut self.acc,
        }
    }

    /// The ideal model of vio_data_simulation (white noise + bias random walk, same on every
    /// axis, at the output rate).
    pub fn from_continuous(label: &str, c: &super::ContinuousNoise) -> Self {
        ImuModel {
            label: label.to_string(),
            gyro: SensorModel::uniform(AxisModel::ideal(c.gyro_noise, c.gyro_bias_rw)),
            acc: SensorModel::uniform(AxisModel::ideal(c.acc_noise, c.acc_bias_rw)),
        }
    }

    /// When the model is exactly vio_data_simulation's (only N and K, equal on the three axes
    /// of each sensor, no chain), its four numbers: such models are generated by the original
    /// [`super::NoiseGenerator`] so that presets keep byte-identical output.
    pub fn legacy(&self, output_rate: f64) -> Option<super::ContinuousNoise> {
        let one = |s: &SensorModel| {
            let a = &s.axes[0];
            (s.chain.is_direct(output_rate) && s.axes.iter().all(|x| x.is_ideal() && x == a))
                .then_some((a.white_noise, a.random_walk))
        };
        let (gn, gk) = one(&self.gyro)?;
        let (an, ak) = one(&self.acc)?;
        Some(super::ContinuousNoise {
            gyro_noise: gn,
            gyro_bias_rw: gk,
            acc_noise: an,
            acc_bias_rw: ak,
        })
    }

    /// Checks every parameter (finite, non-negative where it must be, corner times ordered,
    /// chain compatible with the output rate). Messages name sensor, axis and field.
    pub(crate) fn validate(&self, output_rate: f64) -> Result<()> {
        for s in Sensor::BOTH {
            let sm = self.sensor(s);
            sm.chain.resolve(s, output_rate)?;
            for (axis, a) in AXES.iter().zip(&sm.axes) {
                let at = |field: &str, msg: String| {
                    SimError::InvalidArgument(format!("{} {axis} {field}: {msg}", s.name()))
                };
                a.validate(output_rate, &at)?;
            }
        }
        Ok(())
    }

    /// Human-readable table of every term, continuous and discrete at `rate` Hz (printed by
    /// `sim bag` and `sim sensors`).
    pub fn describe(&self, rate: f64) -> String {
        if let Some(c) = self.legacy(rate) {
            return c.describe(rate);
        }
        let mut o = String::new();
        let dt = 1.0 / rate;
        let _ = writeln!(
            o,
            "noise model '{}' (continuous time; output rate {rate} Hz):",
            self.label
        );
        for s in Sensor::BOTH {
            let sm = self.sensor(s);
            let chain = match sm.chain.resolve(s, rate) {
                Ok(c) => describe_chain(&c),
                Err(e) => format!("invalid: {e}"),
            };
            let _ = writeln!(o, "  {} [{}]: {chain}", s.name(), s.unit());
            for (axis, a) in AXES.iter().zip(&sm.axes) {
                a.describe_into(&mut o, s, axis, dt);
            }
        }
        o.pop();
        o
    }
}

/// Builds the error of one field of one axis: `at(field, message)`.
type FieldError<'a> = &'a dyn Fn(&str, String) -> SimError;

impl AxisModel {
    /// Checks this axis' terms in the model's order, one rule each (output rate
    /// `output_rate` Hz); `at` names sensor, axis and field in the error.
    fn validate(&self, output_rate: f64, at: FieldError<'_>) -> Result<()> {
        for (field, v) in [
            (NoiseTerm::WhiteNoise.name(), self.white_noise),
            (NoiseTerm::RandomWalk.name(), self.random_walk),
            (NoiseTerm::Quantization.name(), self.quantization),
            ("resolution", self.resolution),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(at(field, format!("must be a non-negative number, got {v}")));
            }
        }
        if !self.rate_ramp.is_finite() {
            return Err(at(
                NoiseTerm::Ramp.name(),
                format!("must be finite, got {}", self.rate_ramp),
            ));
        }
        if let Some(bi) = self.bias_instability {
            bi.validate(output_rate, at)?;
        }
        for gm in &self.gauss_markov {
            if !(gm.sigma.is_finite() && gm.sigma >= 0.0 && gm.tau.is_finite() && gm.tau > 0.0) {
                return Err(at(
                    NoiseTerm::GaussMarkov.name(),
                    format!(
                        "sigma must be >= 0 and tau > 0 s, got sigma {} tau {}",
                        gm.sigma, gm.tau
                    ),
                ));
            }
        }
        for l in &self.lines {
            l.validate(output_rate, at)?;
        }
        if let Some(w) = self.warmup {
            let ok = w.amplitude().is_finite() && w.tau().is_finite() && w.tau() > 0.0;
            if !ok {
                return Err(at(
                    "warmup",
                    format!(
                        "needs a finite amplitude and a time constant > 0 s, got {:?}",
                        w
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Appends this axis' line of [`ImuModel::describe`]: N and K, every other term that is
    /// on, then the discrete white noise and bias step per sample of `dt` s.
    fn describe_into(&self, o: &mut String, s: Sensor, axis: &str, dt: f64) {
        let _ = write!(
            o,
            "    {axis}: N {:.4e} {}, K {:.4e} {}",
            self.white_noise,
            NoiseTerm::WhiteNoise.unit(s),
            self.random_walk,
            NoiseTerm::RandomWalk.unit(s)
        );
        if let Some(bi) = self.bias_instability {
            let _ = write!(
                o,
                ", B {:.4e} {} ({} .. {} s)",
                bi.b,
                s.unit(),
                bi.tau_lo,
                bi.tau_hi
            );
        }
        for gm in &self.gauss_markov {
            let _ = write!(o, ", GM {:.4e} {} / {} s", gm.sigma, s.unit(), gm.tau);
        }
        if self.rate_ramp != 0.0 {
            let _ = write!(o, ", R {:.4e} {}", self.rate_ramp, NoiseTerm::Ramp.unit(s));
        }
        if self.quantization != 0.0 {
            let _ = write!(
                o,
                ", Q {:.4e} {} (step {:.4e})",
                self.quantization,
                NoiseTerm::Quantization.unit(s),
                super::quantization_step(self.quantization)
            );
        }
        if self.resolution != 0.0 {
            let _ = write!(o, ", LSB {:.4e} {}", self.resolution, s.unit());
        }
        if let Some(w) = self.warmup {
            let _ = write!(
                o,
                ", warm-up {:.4e} {} / {} s",
                w.amplitude(),
                s.unit(),
                w.tau()
            );
        }
        for l in &self.lines {
            let _ = write!(
                o,
                ", line {} Hz amplitude {:.4e} {}",
                l.frequency,
                l.amplitude,
                s.unit()
            );
            if l.bandwidth > 0.0 {
                let _ = write!(o, " (resonance, bandwidth {} Hz)", l.bandwidth);
            }
        }
        let _ = writeln!(
            o,
            "; per sample: white {:.4e}, bias step {:.4e} {}",
            super::white_to_discrete(self.white_noise, dt),
            super::random_walk_to_discrete(self.random_walk, dt),
            s.unit()
        );
    }
}

impl BiasInstability {
    /// B non-negative, corner times ordered, τ_lo at least [`MIN_TAU_SAMPLES`] output samples.
    fn validate(&self, output_rate: f64, at: FieldError<'_>) -> Result<()> {
        let min_tau = MIN_TAU_SAMPLES / output_rate;
        if !(self.b.is_finite() && self.b >= 0.0) {
            return Err(at(
                NoiseTerm::BiasInstability.name(),
                format!("B must be a non-negative number, got {}", self.b),
            ));
        }
        if !(self.tau_lo.is_finite()
            && self.tau_hi.is_finite()
            && self.tau_lo >= min_tau
            && self.tau_hi > self.tau_lo)
        {
            return Err(at(
                NoiseTerm::BiasInstability.name(),
                format!(
                    "corner times must satisfy {min_tau} s ({} output samples) <= tau_lo < tau_hi, got {} .. {}",
                    MIN_TAU_SAMPLES, self.tau_lo, self.tau_hi
                ),
            ));
        }
        Ok(())
    }
}

impl Line {
    /// Below half the output rate, amplitude non-negative, lightly damped (bandwidth < f₀).
    fn validate(&self, output_rate: f64, at: FieldError<'_>) -> Result<()> {
        if !(self.frequency.is_finite()
            && self.frequency > 0.0
            && self.frequency < 0.5 * output_rate
            && self.amplitude.is_finite()
            && self.amplitude >= 0.0
            && self.bandwidth.is_finite()
            && self.bandwidth >= 0.0
            && self.bandwidth < self.frequency)
        {
            return Err(at(
                NoiseTerm::Line(0).name(),
                format!(
                    "a line needs 0 < frequency < {} Hz (half the output rate), amplitude >= 0 and 0 <= bandwidth < frequency (lightly damped), got frequency {} Hz, amplitude {}, bandwidth {} Hz",
                    0.5 * output_rate,
                    self.frequency,
                    self.amplitude,
                    self.bandwidth
                ),
            ));
        }
        Ok(())
    }
}

/// One line about a resolved chain.
pub fn describe_chain(c: &ResolvedChain) -> String {
    let filter = match c.filter {
        Filter::None if c.decimation == 1 => return "generated at the output rate".to_string(),
        Filter::None => "no filter (plain sub-sampling)".to_string(),
        Filter::Butterworth2 { cutoff_hz } => format!("2nd-order Butterworth {cutoff_hz} Hz"),
        Filter::Average => "averaging decimation filter".to_string(),
    };
    format!(
        "internal {} Hz, {filter}, decimation {}",
        c.internal_rate, c.decimation
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::{ContinuousNoise, Preset};

    #[test]
    fn presets_are_legacy_and_a_chain_is_not() {
        let m = ImuModel::from_continuous("medium", &Preset::Medium.params());
        assert_eq!(m.legacy(200.0), Some(Preset::Medium.params()));
        let mut f = m.clone();
        f.gyro.chain = Chain {
            internal_rate_hz: Some(1000.0),
            filter: Filter::Butterworth2 { cutoff_hz: 50.0 },
        };
        assert_eq!(f.legacy(200.0), None);
        let mut a = m.clone();
        a.acc.axes[2].white_noise = 0.5;
        assert_eq!(a.legacy(200.0), None, "per-axis values are not legacy");
        let mut q = m;
        q.gyro.axes[0].quantization = 1e-6;
        assert_eq!(q.legacy(200.0), None);
        let z = ImuModel::from_continuous("zero", &ContinuousNoise::ZERO);
        assert_eq!(z.legacy(100.0), Some(ContinuousNoise::ZERO));
    }

    #[test]
    fn chain_resolution_checks_rates_and_cutoff() {
        let c = Chain {
            internal_rate_hz: Some(1000.0),
            filter: Filter::Butterworth2 { cutoff_hz: 50.0 },
        };
        let r = c.resolve(Sensor::Gyro, 200.0).unwrap();
        assert_eq!((r.internal_rate, r.decimation), (1000.0, 5));
        let e = c.resolve(Sensor::Gyro, 300.0).unwrap_err().to_string();
        assert!(e.contains("not an integer multiple"), "{e}");
        let bad = Chain {
            internal_rate_hz: Some(1000.0),
            filter: Filter::Butterworth2 { cutoff_hz: 600.0 },
        };
        assert!(bad.resolve(Sensor::Acc, 200.0).is_err());
        assert_eq!(
            Chain::DIRECT
                .resolve(Sensor::Acc, 123.0)
                .unwrap()
                .decimation,
            1
        );
    }

    #[test]
    fn validation_names_sensor_axis_and_field() {
        let mut m = ImuModel::from_continuous("t", &Preset::Low.params());
        m.acc.axes[1].bias_instability = Some(BiasInstability {
            b: 1e-4,
            tau_lo: 100.0,
            tau_hi: 10.0,
        });
        let e = m.validate(200.0).unwrap_err().to_string();
        assert!(e.contains("accelerometer y bias_instability"), "{e}");
        let mut m = ImuModel::from_continuous("t", &Preset::Low.params());
        m.gyro.axes[0].resolution = -1.0;
        let e = m.validate(200.0).unwrap_err().to_string();
        assert!(e.contains("gyroscope x resolution"), "{e}");
    }

    #[test]
    fn thermal_warmup_amplitude() {
        let w = Warmup::Thermal {
            temperature_rise: 5.0,
            tau: 300.0,
            sensitivity: 2e-4,
        };
        assert_eq!(w.amplitude(), -1e-3);
        assert_eq!(w.tau(), 300.0);
    }
}
