//! The real-sensor noise flags of `sim bag` (clap derive) and their resolution into an
//! [`ImuModel`]: profile or preset, then `--noise-spec`, then explicit flags.

// The argument docs are clap's help texts, which write units as `[Hz]`, `[s]` and defaults
// as `<stem>`: rustdoc would read those as links and HTML tags, and escaping them would
// show the escapes in `--help`.
#![allow(rustdoc::broken_intra_doc_links)]

use bag2mat::Sensor;
use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::noise_args::{NoiseArgs, PresetArg};
use crate::error::{Result, SimError};
use crate::noise::model::{
    AxisModel, BiasInstability, Chain, Filter, GaussMarkov, ImuModel, Warmup,
};
use crate::noise::profiles::Profile;

/// Sensor profiles (`sim sensors` lists their figures and sources).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SensorArg {
    /// The seed's low preset (white noise + random walk).
    Low,
    /// The seed's medium preset (vio_data_simulation ros_version param.h).
    Medium,
    /// The seed's high preset.
    High,
    /// Bosch BMI088 (consumer MEMS).
    Bmi088,
    /// Analog Devices ADIS16470 (industrial MEMS).
    Adis16470,
    /// Safran Sensonor STIM300 (tactical grade).
    Stim300,
    /// The ADIS16470 with vibration lines (mid-curve and short-τ; assumed).
    Vibration,
}

impl SensorArg {
    /// The profile.
    pub(crate) fn profile(self) -> Profile {
        match self {
            SensorArg::Low => Profile::Low,
            SensorArg::Medium => Profile::Medium,
            SensorArg::High => Profile::High,
            SensorArg::Bmi088 => Profile::Bmi088,
            SensorArg::Adis16470 => Profile::Adis16470,
            SensorArg::Stim300 => Profile::Stim300,
            SensorArg::Vibration => Profile::Vibration,
        }
    }
}

/// Real-sensor noise model flags of `sim bag`. Units: gyroscope rad/s-based, accelerometer
/// m/s²-based; every value applies to the three axes of its sensor.
#[derive(Debug, Clone, Default, Args)]
#[command(next_help_heading = "Real-sensor noise model")]
pub struct ModelArgs {
    /// Sensor profile from datasheet figures (see `sim sensors`); replaces --preset.
    #[arg(long, value_enum, value_name = "NAME", conflicts_with = "preset")]
    pub sensor: Option<SensorArg>,
    /// YAML noise model: every term, per sensor, optionally per axis (`sim sensors
    /// --spec-example` prints every key with its unit); applied on top of --sensor/--preset
    /// when given, else on its own `base:` or on nothing. A `<bag>.truth.yaml` works too. The
    /// flags below override it.
    #[arg(long, value_name = "FILE.yaml")]
    pub noise_spec: Option<PathBuf>,
    /// Internal sample rate of both sensors [Hz]; an integer multiple of --rate.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub internal_rate: Option<f64>,
    /// Gyro low-pass: 2nd-order Butterworth −3 dB frequency at the internal rate [Hz]; 0 = none.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub gyro_lpf: Option<f64>,
    /// Accelerometer low-pass −3 dB frequency [Hz]; 0 = none.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub acc_lpf: Option<f64>,
    /// Gyro bias instability B [rad/s] (flicker noise; Allan floor 0.664·B).
    #[arg(long, value_name = "B", allow_negative_numbers = true)]
    pub gyro_bias_instability: Option<f64>,
    /// Accelerometer bias instability B [m/s²].
    #[arg(long, value_name = "B", allow_negative_numbers = true)]
    pub acc_bias_instability: Option<f64>,
    /// Corner times of the gyro flicker floor [s] (default 1,1000 when B is new).
    #[arg(long, value_name = "LO,HI", value_delimiter = ',')]
    pub gyro_bi_taus: Option<Vec<f64>>,
    /// Corner times of the accelerometer flicker floor [s].
    #[arg(long, value_name = "LO,HI", value_delimiter = ',')]
    pub acc_bi_taus: Option<Vec<f64>>,
    /// Gyro first-order Gauss–Markov bias: σ [rad/s], correlation time [s] (replaces the base's).
    #[arg(long, value_name = "SIGMA,TAU", value_delimiter = ',')]
    pub gyro_gm: Option<Vec<f64>>,
    /// Accelerometer Gauss–Markov bias: σ [m/s²], correlation time [s].
    #[arg(long, value_name = "SIGMA,TAU", value_delimiter = ',')]
    pub acc_gm: Option<Vec<f64>>,
    /// Gyro rate ramp R [rad/s²] (deterministic).
    #[arg(long, value_name = "R", allow_negative_numbers = true)]
    pub gyro_ramp: Option<f64>,
    /// Accelerometer ramp R [m/s³].
    #[arg(long, value_name = "R", allow_negative_numbers = true)]
    pub acc_ramp: Option<f64>,
    /// Gyro quantization Q [rad] (IEEE 952: the integrated angle in steps of √12·Q).
    #[arg(long, value_name = "Q", allow_negative_numbers = true)]
    pub gyro_quantization: Option<f64>,
    /// Accelerometer quantization Q [m/s] (integrated velocity).
    #[arg(long, value_name = "Q", allow_negative_numbers = true)]
    pub acc_quantization: Option<f64>,
    /// Gyro output LSB [rad/s]: values rounded to counts of it; 0 = none.
    #[arg(long, value_name = "LSB", allow_negative_numbers = true)]
    pub gyro_resolution: Option<f64>,
    /// Accelerometer output LSB [m/s²].
    #[arg(long, value_name = "LSB", allow_negative_numbers = true)]
    pub acc_resolution: Option<f64>,
    /// Gyro warm-up: bias A·exp(−t/T) after power-on; A [rad/s], T [s].
    #[arg(
        long,
        value_name = "A,T",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    pub gyro_warmup: Option<Vec<f64>>,
    /// Accelerometer warm-up: A [m/s²], T [s].
    #[arg(
        long,
        value_name = "A,T",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    pub acc_warmup: Option<Vec<f64>>,
}

/// Default flicker corner times when B is set by a flag on a model without them, s.
pub const DEFAULT_BI_TAUS: (f64, f64) = (1.0, 1000.0);

impl ModelArgs {
    /// The model: base (profile, preset, or medium), spec, then flags; validated at `rate`.
    pub(crate) fn resolve(&self, noise: &NoiseArgs, rate: f64) -> Result<ImuModel> {
        let mut m = self.base_and_spec(noise)?;
        apply_white_and_random_walk(&mut m, noise);
        self.apply_chain(&mut m);
        self.apply_terms(&mut m)?;
        m.validate(rate)?;
        Ok(m)
    }

    /// The base (profile, preset, or medium), then the spec on it.
    fn base_and_spec(&self, noise: &NoiseArgs) -> Result<ImuModel> {
        // Checks the N/K flags the way every subcommand does.
        noise.resolve(PresetArg::Medium)?;
        let base = match (self.sensor, noise.preset) {
            (Some(s), _) => Some(s.profile().model()),
            (None, Some(p)) => Some(ImuModel::from_continuous(
                &format!("{p:?}").to_lowercase(),
                &noise.resolve(p)?,
            )),
            (None, None) if self.noise_spec.is_none() => Some(Profile::Medium.model()),
            (None, None) => None,
        };
        Ok(match &self.noise_spec {
            Some(path) => {
                let spec = crate::noise::spec::read(path)?;
                crate::noise::spec::apply(&spec, base, path)?
            }
            None => base.expect("a base without a spec"),
        })
    }

    /// `--internal-rate` and the low-pass flags.
    fn apply_chain(&self, m: &mut ImuModel) {
        if let Some(r) = self.internal_rate {
            m.gyro.chain.internal_rate_hz = Some(r);
            m.acc.chain.internal_rate_hz = Some(r);
        }
        for (s, lpf) in [(Sensor::Gyro, self.gyro_lpf), (Sensor::Acc, self.acc_lpf)] {
            if let Some(fc) = lpf {
                let c = &mut m.sensor_mut(s).chain;
                *c = Chain {
                    filter: if fc == 0.0 {
                        Filter::None
                    } else {
                        Filter::Butterworth2 { cutoff_hz: fc }
                    },
                    ..*c
                };
            }
        }
    }

    /// The per-sensor term flags (bias instability, Gauss–Markov, ramp, quantization,
    /// resolution, warm-up), checked; the gyro's first.
    fn apply_terms(&self, m: &mut ImuModel) -> Result<()> {
        for flags in self.term_flags() {
            flags.check()?;
            for a in m.sensor_mut(flags.sensor).axes.iter_mut() {
                flags.apply(a);
            }
        }
        Ok(())
    }

    /// The term flags of each sensor, gyro then accelerometer.
    fn term_flags(&self) -> [TermFlags<'_>; 2] {
        [
            TermFlags {
                sensor: Sensor::Gyro,
                bias_instability: self.gyro_bias_instability,
                bi_taus: &self.gyro_bi_taus,
                gm: &self.gyro_gm,
                ramp: self.gyro_ramp,
                quantization: self.gyro_quantization,
                resolution: self.gyro_resolution,
                warmup: &self.gyro_warmup,
            },
            TermFlags {
                sensor: Sensor::Acc,
                bias_instability: self.acc_bias_instability,
                bi_taus: &self.acc_bi_taus,
                gm: &self.acc_gm,
                ramp: self.acc_ramp,
                quantization: self.acc_quantization,
                resolution: self.acc_resolution,
                warmup: &self.acc_warmup,
            },
        ]
    }
}

/// One sensor's term flags (`--gyro-…` or `--acc-…`), as given.
struct TermFlags<'a> {
    sensor: Sensor,
    bias_instability: Option<f64>,
    bi_taus: &'a Option<Vec<f64>>,
    gm: &'a Option<Vec<f64>>,
    ramp: Option<f64>,
    quantization: Option<f64>,
    resolution: Option<f64>,
    warmup: &'a Option<Vec<f64>>,
}

impl TermFlags<'_> {
    /// The pairs have two numbers, Q, LSB and B are non-negative; the error names the flag.
    fn check(&self) -> Result<()> {
        let flag = |name: &str| format!("--{}-{name}", self.sensor.short());
        for (name, v) in [
            ("bi-taus", self.bi_taus),
            ("gm", self.gm),
            ("warmup", self.warmup),
        ] {
            if let Some(v) = v
                && v.len() != 2
            {
                return Err(SimError::InvalidArgument(format!(
                    "{} takes two comma-separated numbers, got {}",
                    flag(name),
                    v.len()
                )));
            }
        }
        for (name, v) in [
            ("quantization", self.quantization),
            ("resolution", self.resolution),
            ("bias-instability", self.bias_instability),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && v >= 0.0)
            {
                return Err(SimError::InvalidArgument(format!(
                    "{} must be a non-negative number, got {v}",
                    flag(name)
                )));
            }
        }
        Ok(())
    }

    /// The given flags on axis `a` (checked first by [`TermFlags::check`]): B and its corner
    /// times merge with the axis' own (defaults [`DEFAULT_BI_TAUS`]); B, σ or A of 0 turn the
    /// term off.
    fn apply(&self, a: &mut AxisModel) {
        let b = self.bias_instability;
        if b.is_some() || self.bi_taus.is_some() {
            let old = a.bias_instability;
            let (lo, hi) = match (self.bi_taus, old) {
                (Some(t), _) => (t[0], t[1]),
                (None, Some(o)) => (o.tau_lo, o.tau_hi),
                (None, None) => DEFAULT_BI_TAUS,
            };
            let bv = b.or(old.map(|o| o.b)).unwrap_or(0.0);
            a.bias_instability = (bv != 0.0).then_some(BiasInstability {
                b: bv,
                tau_lo: lo,
                tau_hi: hi,
            });
        }
        if let Some(g) = self.gm {
            a.gauss_markov = if g[0] == 0.0 {
                Vec::new()
            } else {
                vec![GaussMarkov {
                    sigma: g[0],
                    tau: g[1],
                }]
            };
        }
        if let Some(r) = self.ramp {
            a.rate_ramp = r;
        }
        if let Some(q) = self.quantization {
            a.quantization = q;
        }
        if let Some(l) = self.resolution {
            a.resolution = l;
        }
        if let Some(w) = self.warmup {
            a.warmup = (w[0] != 0.0).then_some(Warmup::Exponential {
                amplitude: w[0],
                tau: w[1],
            });
        }
    }
}

/// The existing N/K flags (shared with traj/spline, validated there) on every axis.
fn apply_white_and_random_walk(m: &mut ImuModel, noise: &NoiseArgs) {
    for (s, n, k) in [
        (Sensor::Gyro, noise.gyro_noise, noise.gyro_bias_rw),
        (Sensor::Acc, noise.acc_noise, noise.acc_bias_rw),
    ] {
        for a in m.sensor_mut(s).axes.iter_mut() {
            if let Some(n) = n {
                a.white_noise = n;
            }
            if let Some(k) = k {
                a.random_walk = k;
            }
        }
    }
}

/// `sim sensors`.
#[derive(Debug, Clone, Args)]
pub struct SensorsArgs {
    /// Output rate the per-sample figures are given at [Hz].
    #[arg(long, default_value_t = 200.0)]
    pub rate: f64,
    /// Print a commented `--noise-spec` example (every key, with units) instead.
    #[arg(long)]
    pub spec_example: bool,
}

/// The `sim sensors --spec-example` text: every key of a `--noise-spec` file with its unit.
pub const SPEC_EXAMPLE: &str = "\
# sim noise spec (sim bag --noise-spec FILE.yaml). Units: gyroscope terms rad/s-based,
# accelerometer terms m/s^2-based, times in s, rates in Hz. Every key is optional.
base: bmi088                 # start from a profile (sim sensors); default: every term off
gyroscope:
  internal_rate_hz: 2000     # internal sample rate, an integer multiple of the output rate
  filter: {kind: butterworth2, cutoff_hz: 23}   # or {kind: none}, {kind: average}
  white_noise: 2.44e-4       # N [rad/s/sqrt(Hz)]
  random_walk: 4.0e-7        # K [rad/s^2/sqrt(Hz)]
  bias_instability: {value: 9.7e-6, tau_lo_s: 5, tau_hi_s: 500}   # B [rad/s]; value 0 = off
  gauss_markov: [{sigma: 3.0e-5, tau_s: 20}]   # first-order Gauss-Markov biases; [] = none
  rate_ramp: 0.0             # R [rad/s^2]
  quantization: 0.0          # Q [rad] (integrated angle in steps of sqrt(12)*Q)
  resolution: 1.065e-3       # output LSB [rad/s]; 0 = none
  warmup: {temperature_rise_k: 1, tau_s: 300, bias_per_k: 2.6e-4}   # or {amplitude: A, tau_s: T}
  lines: [{frequency_hz: 17, amplitude: 1.0e-3, bandwidth_hz: 0.5}]   # vibration lines at the output:
                             # amplitude A [rad/s] of A*sin(2*pi*f*t + random phase); bandwidth_hz
                             # > 0: a 2nd-order resonance of that -3 dB width (rms A/sqrt(2)); [] = none
  axes:                      # per-axis overrides, same keys
    z: {white_noise: 3.0e-4}
accelerometer:
  white_noise: 1.57e-3       # N [m/s^2/sqrt(Hz)]
  random_walk: 1.0e-5        # K [m/s^3/sqrt(Hz)]
  resolution: 1.8e-3         # LSB [m/s^2]
  lines: [{frequency_hz: 0.5, amplitude: 2.0e-3}]   # a pump or fan at 0.5 Hz [Hz, m/s^2]
";
