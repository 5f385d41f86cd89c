//! The noise flags every subcommand shares: a continuous-time preset plus explicit N/K
//! overrides and the seed. Below both [`super::model_args`] (which builds on them) and the
//! subcommands' arguments in [`super`].

use clap::{Args, ValueEnum};

use crate::error::{Result, SeedError, SimError};
use crate::noise::{ContinuousNoise, DEFAULT_SEED, MASTER_PARAMS, Preset};

/// Noise parameter presets (continuous time).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PresetArg {
    /// gyro 0.01 rad/s/√Hz, 1e-5 rad/s²/√Hz; acc 0.01 m/s²/√Hz, 1e-4 m/s³/√Hz.
    Low,
    /// gyro 0.015, 5e-5; acc 0.019, 5e-4 (ros_version param.h).
    Medium,
    /// gyro 0.03, 1e-4; acc 0.03, 1e-3.
    High,
    /// gyro 0.015, 1e-5; acc 0.019, 1e-4 (master param.h, the 20 s trajectory run).
    Master,
}

impl PresetArg {
    fn params(self) -> ContinuousNoise {
        match self {
            PresetArg::Low => Preset::Low.params(),
            PresetArg::Medium => Preset::Medium.params(),
            PresetArg::High => Preset::High.params(),
            PresetArg::Master => MASTER_PARAMS,
        }
    }
}

/// `--seed`: a whole number from 0 to 2^64 − 1, said so (not the parser's "unexpected
/// argument" for a negative one).
fn seed_value(s: &str) -> std::result::Result<u64, SeedError> {
    s.trim().parse().map_err(|_| SeedError(s.to_string()))
}

/// Noise flags shared by the subcommands: a preset plus explicit overrides.
#[derive(Debug, Clone, Args)]
pub struct NoiseArgs {
    /// Noise preset (continuous-time parameters); explicit flags below override it.
    #[arg(long, value_enum)]
    pub preset: Option<PresetArg>,
    /// Gyro white-noise density σ_g [rad/s/√Hz].
    #[arg(allow_negative_numbers = true, long, value_name = "S")]
    pub gyro_noise: Option<f64>,
    /// Gyro bias random walk σ_bg [rad/s²/√Hz].
    #[arg(allow_negative_numbers = true, long, value_name = "S")]
    pub gyro_bias_rw: Option<f64>,
    /// Accelerometer white-noise density σ_a [m/s²/√Hz].
    #[arg(allow_negative_numbers = true, long, value_name = "S")]
    pub acc_noise: Option<f64>,
    /// Accelerometer bias random walk σ_ba [m/s³/√Hz].
    #[arg(allow_negative_numbers = true, long, value_name = "S")]
    pub acc_bias_rw: Option<f64>,
    /// RNG seed (the same flags and seed give identical output).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SEED, allow_negative_numbers = true, value_parser = seed_value)]
    pub seed: u64,
}

impl NoiseArgs {
    /// Resolve against a default preset; rejects negative or non-finite values.
    pub(crate) fn resolve(&self, default: PresetArg) -> Result<ContinuousNoise> {
        let mut c = self.preset.unwrap_or(default).params();
        for (name, v, slot) in [
            ("--gyro-noise", self.gyro_noise, &mut c.gyro_noise),
            ("--gyro-bias-rw", self.gyro_bias_rw, &mut c.gyro_bias_rw),
            ("--acc-noise", self.acc_noise, &mut c.acc_noise),
            ("--acc-bias-rw", self.acc_bias_rw, &mut c.acc_bias_rw),
        ] {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(SimError::InvalidArgument(format!(
                        "{name} must be a non-negative number, got {v}"
                    )));
                }
                *slot = v;
            }
        }
        Ok(c)
    }
}
