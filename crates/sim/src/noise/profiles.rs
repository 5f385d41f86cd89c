//! Sensor profiles: the seed's presets and three real IMUs built from public datasheet
//! figures (`sim bag --sensor NAME`, `sim sensors`).
//!
//! Each figure carries its source next to it. "Datasheet" means a value printed in the named
//! document; "assumed" means the datasheet gives no such figure and the value is our choice,
//! with the reason. Datasheets quote noise densities in °/s/√Hz, °/√h, µg/√Hz or m/s/√h;
//! they are converted here to the continuous-time SI densities of [`super::model`]
//! (ARW °/√h ÷ 60 → °/√s; VRW m/s/√h ÷ 60 → m/s²/√Hz). The BMI088 datasheet does not give
//! the order or type of its digital low-pass filter, and the STIM300's says only "CIC type
//! filters with linear phase response" (TS1524 rev. 31): a 2nd-order Butterworth at the
//! datasheet's −3 dB bandwidth stands for both (same corner, not the same phase). The
//! ADIS16470's decimation stage is an average, modelled as such. The figures were checked
//! against the documents named in [`Profile::source`] on 2026-11-30.

use super::model::{
    AxisModel, BiasInstability, Chain, Filter, GaussMarkov, ImuModel, Line, SensorModel, Warmup,
};
use super::{ContinuousNoise, Preset};

const DEG: f64 = std::f64::consts::PI / 180.0;
/// °/h → rad/s.
const DEG_PER_H: f64 = DEG / 3600.0;
/// °/√h → rad/√s.
const DEG_PER_SQRT_H: f64 = DEG / 60.0;
/// Standard gravity (m/s²) for µg/mg figures.
const G0: f64 = 9.806_65;

/// Every profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Profile {
    /// The seed's low preset (white noise + random walk).
    Low,
    /// The seed's medium preset (vio_data_simulation ros_version param.h).
    Medium,
    /// The seed's high preset.
    High,
    /// Bosch BMI088, consumer MEMS.
    Bmi088,
    /// Analog Devices ADIS16470, industrial MEMS IMU.
    Adis16470,
    /// Safran Sensonor STIM300, tactical-grade MEMS IMU.
    Stim300,
    /// The ADIS16470 on a running machine: vibration lines in the middle of the curve and at
    /// short τ (IEEE 952 sinusoidal noise; assumed figures).
    Vibration,
}

impl Profile {
    /// All profiles, in `sim sensors` order.
    pub const ALL: [Profile; 7] = [
        Profile::Low,
        Profile::Medium,
        Profile::High,
        Profile::Bmi088,
        Profile::Adis16470,
        Profile::Stim300,
        Profile::Vibration,
    ];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Profile::Low => "low",
            Profile::Medium => "medium",
            Profile::High => "high",
            Profile::Bmi088 => "bmi088",
            Profile::Adis16470 => "adis16470",
            Profile::Stim300 => "stim300",
            Profile::Vibration => "vibration",
        }
    }

    /// By name.
    pub(crate) fn from_name(name: &str) -> Option<Profile> {
        Profile::ALL.into_iter().find(|p| p.name() == name)
    }

    /// One line: what it is and where its figures come from.
    pub fn source(self) -> &'static str {
        match self {
            Profile::Low | Profile::Medium | Profile::High => {
                "the seed's preset: white noise and bias random walk only (vio_data_simulation model)"
            }
            Profile::Bmi088 => {
                "Bosch BMI088 (consumer MEMS), data sheet BST-BMI088-DS001 rev. 1.4 and Bosch's product flyer; gyro 200 Hz ODR / 23 Hz bandwidth, accel 200 Hz ODR normal mode / 80 Hz"
            }
            Profile::Adis16470 => {
                "Analog Devices ADIS16470 (industrial MEMS IMU), data sheet Rev. C, Table 1; 2000 SPS internal, averaging decimation to the output rate, 32-bit output registers"
            }
            Profile::Stim300 => {
                "Safran Sensonor STIM300 (tactical-grade MEMS IMU), noise figures of data sheet TS1524 rev. 9 (10 g accelerometers; rev. 31 quotes a quieter accelerometer); 2000 SPS internal, 66 Hz low-pass"
            }
            Profile::Vibration => {
                "the adis16470 profile on a running pump (assumed): accelerometer lines at 0.5 Hz and 1.7 Hz (a shoulder in the middle of the Allan curve, ripples after it), a 45 Hz gyroscope resonance 1 Hz wide (short tau); valid from a 90 Hz output rate"
            }
        }
    }

    /// The model.
    pub fn model(self) -> ImuModel {
        match self {
            Profile::Low => legacy(self, Preset::Low.params()),
            Profile::Medium => legacy(self, Preset::Medium.params()),
            Profile::High => legacy(self, Preset::High.params()),
            Profile::Bmi088 => bmi088(),
            Profile::Adis16470 => adis16470(),
            Profile::Stim300 => stim300(),
            Profile::Vibration => vibration(),
        }
    }
}

fn legacy(p: Profile, c: ContinuousNoise) -> ImuModel {
    ImuModel::from_continuous(p.name(), &c)
}

/// The Bosch BMI088: its two axis models and their signal chains.
fn bmi088() -> ImuModel {
    let gyro_axis = bmi088_gyro_axis();
    ImuModel {
        label: "bmi088".into(),
        gyro: SensorModel {
            // Gyro data path at 2000 Hz (its highest ODR, 532 Hz "unfiltered" in the register
            // table, 523 Hz in Table 5); the 200 Hz ODR with 23 Hz bandwidth setting
            // (GYRO_BANDWIDTH = 0x04).
            chain: Chain {
                internal_rate_hz: Some(2000.0),
                filter: Filter::Butterworth2 { cutoff_hz: 23.0 },
            },
            axes: [gyro_axis.clone(), gyro_axis.clone(), gyro_axis],
        },
        acc: SensorModel {
            // Accelerometer at its highest ODR 1600 Hz internally; ODR 200 Hz, normal mode:
            // 80 Hz bandwidth (ACC_CONF table).
            chain: Chain {
                internal_rate_hz: Some(1600.0),
                filter: Filter::Butterworth2 { cutoff_hz: 80.0 },
            },
            axes: [
                bmi088_acc_axis(160.0),
                bmi088_acc_axis(160.0),
                bmi088_acc_axis(190.0),
            ],
        },
    }
}

/// The BMI088 gyroscope axis, transcribed figure by figure with its sources.
fn bmi088_gyro_axis() -> AxisModel {
    // Gyroscope. Datasheet rev. 1.4, Table 5: output noise "BW = 47 Hz (@ 0.014 °/s/√Hz)
    // 0.1 °/s"; the product flyer gives the same 0.014 °/s/√Hz.
    let gyro_n = 0.014 * DEG;
    // Bias instability: not in the datasheet's tables; Bosch's product flyer claims "bias
    // stability of less than 2 °/h", an upper bound taken here as the value. Corner times
    // assumed (floor seen from ≈ 5 s to 500 s on consumer MEMS Allan curves such as
    // ../shared/reference/real_curves/BMI160).
    let gyro_b = 2.0 * DEG_PER_H;
    // Random walk: not in the datasheet. Assumed 4e-7 rad/s²/√Hz, which makes the +½ slope
    // rise out of the floor near 1000 s.
    let gyro_k = 4e-7;
    // Output LSB: 16-bit at the default ±2000 °/s range (register 0x0F = 0x00): 16.384 LSB
    // per °/s.
    let gyro_lsb = DEG / 16.384;
    // Warm-up: zero-rate offset temperature coefficient ±0.015 °/s per K at ±2000 °/s
    // (datasheet Table 5, TCO); the self-heating of 1 K with a 300 s time constant is
    // assumed.
    let gyro_warm = Warmup::Thermal {
        temperature_rise: 1.0,
        tau: 300.0,
        sensitivity: 0.015 * DEG,
    };
    // A Gauss–Markov bump (σ 3e-5 rad/s, T 20 s): assumed, for the bumps real consumer
    // curves show (../shared/reference/real_curves README); not a datasheet figure.
    AxisModel {
        white_noise: gyro_n,
        random_walk: gyro_k,
        bias_instability: Some(BiasInstability {
            b: gyro_b,
            tau_lo: 5.0,
            tau_hi: 500.0,
        }),
        gauss_markov: vec![GaussMarkov {
            sigma: 3e-5,
            tau: 20.0,
        }],
        resolution: gyro_lsb,
        warmup: Some(gyro_warm),
        ..Default::default()
    }
}

/// The BMI088 accelerometer axis of white noise density `ug` µg/√Hz. Datasheet Table 4:
/// output noise density 160 µg/√Hz on x and y, 190 µg/√Hz on z (normal mode, ±3 g; the
/// flyer's 230 µg/√Hz is at ±24 g).
fn bmi088_acc_axis(ug: f64) -> AxisModel {
    AxisModel {
        white_noise: ug * 1e-6 * G0,
        // Not in the datasheet; assumed 1e-5 m/s³/√Hz (+½ slope from ≈ 1000 s).
        random_walk: 1e-5,
        // Not in the datasheet; assumed 30 µg, a typical consumer-MEMS accelerometer floor.
        bias_instability: Some(BiasInstability {
            b: 30e-6 * G0,
            tau_lo: 5.0,
            tau_hi: 500.0,
        }),
        // 16-bit at the reset range ±6 g (ACC_RANGE = 0x01).
        resolution: 6.0 * G0 / 32768.0,
        // Zero-g offset temperature drift 0.2 mg/K (datasheet); 1 K / 300 s self-heating
        // assumed as for the gyro.
        warmup: Some(Warmup::Thermal {
            temperature_rise: 1.0,
            tau: 300.0,
            sensitivity: 0.2e-3 * G0,
        }),
        ..Default::default()
    }
}

fn adis16470() -> ImuModel {
    // Gyroscope, Table 1 (the same in Rev. A and Rev. C): angular random walk 0.34 °/√h
    // (= 0.008 °/s/√Hz rate noise density, 10–40 Hz, /√2); in-run bias stability 8 °/h.
    let gyro = AxisModel {
        white_noise: 0.34 * DEG_PER_SQRT_H,
        // Not in the datasheet; assumed 1e-6 rad/s²/√Hz (+½ slope near 2000 s).
        random_walk: 1e-6,
        // Corner times assumed: the floor is reached above ≈ 15 s (where N/√τ meets 0.664·B).
        bias_instability: Some(BiasInstability {
            b: 8.0 * DEG_PER_H,
            tau_lo: 2.0,
            tau_hi: 2000.0,
        }),
        // 32-bit gyro output (GYRO_OUT + GYRO_LOW): 0.1 °/s per 16-bit LSB / 65536. The 16-bit
        // register alone (0.1 °/s) would be coarser than the per-sample noise.
        resolution: 0.1 * DEG / 65536.0,
        // Assumed: 2 K self-heating in 600 s with 0.002 °/s/K (Table 1 gives only the bias
        // error over −10…+75 °C, 0.2 °/s 1σ, ≈ 0.0024 °/s/K).
        warmup: Some(Warmup::Thermal {
            temperature_rise: 2.0,
            tau: 600.0,
            sensitivity: 0.002 * DEG,
        }),
        ..Default::default()
    };
    // Accelerometer, Table 1: velocity random walk 0.037 m/s/√h; in-run bias stability 13 µg.
    let acc = AxisModel {
        white_noise: 0.037 / 60.0,
        // Not in the datasheet; assumed 3e-6 m/s³/√Hz (+½ slope near 2000 s).
        random_walk: 3e-6,
        bias_instability: Some(BiasInstability {
            b: 13e-6 * G0,
            tau_lo: 5.0,
            tau_hi: 2000.0,
        }),
        // 32-bit accelerometer output: 1.25 mg per 16-bit LSB / 65536.
        resolution: 1.25e-3 * G0 / 65536.0,
        warmup: Some(Warmup::Exponential {
            amplitude: 0.1e-3 * G0,
            tau: 600.0,
        }),
        ..Default::default()
    };
    // 2000 SPS internal sample rate, averaging decimation filter (DEC_RATE) to the output rate.
    let chain = Chain {
        internal_rate_hz: Some(2000.0),
        filter: Filter::Average,
    };
    ImuModel {
        label: "adis16470".into(),
        gyro: SensorModel {
            chain,
            axes: [gyro.clone(), gyro.clone(), gyro],
        },
        acc: SensorModel {
            chain,
            axes: [acc.clone(), acc.clone(), acc],
        },
    }
}

fn stim300() -> ImuModel {
    // Gyroscope, TS1524 rev. 9 (as quoted by NavToolkit's stim300_model; rev. 31, Table
    // 5-3, gives the same): bias instability 0.5 °/h (rev. 31: 0.3 °/h minimum, 0.5 °/h at
    // 600 s), angular random walk 0.15 °/√h (Sensonor's FAQ: measured per IEEE 952 over
    // 18 h at 1000 SPS with a 131 Hz low-pass).
    let gyro = AxisModel {
        white_noise: 0.15 * DEG_PER_SQRT_H,
        // Not in the datasheet; assumed 2e-8 rad/s²/√Hz (+½ slope only beyond ≈ 5 h).
        random_walk: 2e-8,
        // Corner times assumed; the floor lies under the white noise below ≈ 700 s.
        bias_instability: Some(BiasInstability {
            b: 0.5 * DEG_PER_H,
            tau_lo: 100.0,
            tau_hi: 20000.0,
        }),
        // 24-bit gyro output: resolution 0.22 °/h.
        resolution: 0.22 * DEG_PER_H,
        // Assumed: 3 °/h settling in 600 s (the datasheet's bias error over temperature
        // gradients is 10 °/h rms).
        warmup: Some(Warmup::Exponential {
            amplitude: 3.0 * DEG_PER_H,
            tau: 600.0,
        }),
        ..Default::default()
    };
    // Accelerometer (10 g), rev. 9: bias instability 0.05 mg, velocity random walk
    // 0.06 m/s/√h. Rev. 31 (Table 5-5) quotes a quieter part: 0.006 mg at 600 s and
    // 0.024 m/s/√h, with an internal accelerometer rate of 8000 SPS. The rev. 9 figures are
    // kept so that the profile stays the one the studies were run on; a rev. 31 unit is a
    // `--noise-spec` with `base: stim300` and an `accelerometer:` section with those two
    // figures and `internal_rate_hz: 8000` (the 66 Hz filter kept).
    let acc = AxisModel {
        white_noise: 0.06 / 60.0,
        // Not in the datasheet; assumed 5e-6 m/s³/√Hz (+½ slope near 3.5 h).
        random_walk: 5e-6,
        bias_instability: Some(BiasInstability {
            b: 0.05e-3 * G0,
            tau_lo: 20.0,
            tau_hi: 5000.0,
        }),
        // 24-bit accelerometer output at 10 g: 1.9 µg.
        resolution: 1.9e-6 * G0,
        ..Default::default()
    };
    // 2000 SPS internal rate; the −3 dB frequency 66 Hz is one of the configurable ones
    // (16, 33, 66, 131, 262 Hz) and the one below the 100 Hz Nyquist of a 200 Hz output.
    // (The STIM300's own output rates are 125…2000 SPS; 200 Hz needs its external trigger.)
    let chain = Chain {
        internal_rate_hz: Some(2000.0),
        filter: Filter::Butterworth2 { cutoff_hz: 66.0 },
    };
    ImuModel {
        label: "stim300".into(),
        gyro: SensorModel {
            chain,
            axes: [gyro.clone(), gyro.clone(), gyro],
        },
        acc: SensorModel {
            chain,
            axes: [acc.clone(), acc.clone(), acc],
        },
    }
}

/// The ADIS16470 with the lines of a machine it is bolted to (none of this is a datasheet
/// figure): what a static record on a factory floor or a vehicle with its engine running
/// shows — the case IEEE 952's sinusoidal term is for. Amplitudes are what the output carries.
fn vibration() -> ImuModel {
    let mut m = adis16470();
    m.label = "vibration".into();
    // Accelerometer: a pump at 0.5 Hz, its Allan bump (0.725·A at τ ≈ 0.74 s) about 6× the
    // white noise's deviation there (N/√τ ≈ 7.2e-4 m/s²), and a line at 1.7 Hz about 2×.
    for a in m.acc.axes.iter_mut() {
        a.lines = vec![
            Line {
                frequency: 0.5,
                amplitude: 6e-3,
                bandwidth: 0.0,
            },
            Line {
                frequency: 1.7,
                amplitude: 3e-3,
                bandwidth: 0.0,
            },
        ];
    }
    // Gyroscope: a structural resonance at 45 Hz, 1 Hz wide; at 200 Hz its Allan bump
    // (τ ≈ 10 ms) is about 6× the white noise's deviation there.
    for a in m.gyro.axes.iter_mut() {
        a.lines = vec![Line {
            frequency: 45.0,
            amplitude: 8e-3,
            bandwidth: 1.0,
        }];
    }
    m
}

/// The `sim sensors` listing: every profile with its figures at `rate` Hz.
pub fn listing(rate: f64) -> String {
    let mut o = String::new();
    for p in Profile::ALL {
        o.push_str(&format!("{} — {}\n", p.name(), p.source()));
        o.push_str(&p.model().describe(rate));
        o.push_str("\n\n");
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_profile_is_valid_at_200_hz_and_presets_are_legacy() {
        for p in Profile::ALL {
            let m = p.model();
            m.validate(200.0)
                .unwrap_or_else(|e| panic!("{}: {e}", p.name()));
            let is_preset = matches!(p, Profile::Low | Profile::Medium | Profile::High);
            assert_eq!(m.legacy(200.0).is_some(), is_preset, "{}", p.name());
            assert_eq!(Profile::from_name(p.name()), Some(p));
        }
        assert_eq!(
            Profile::Medium.model().legacy(200.0),
            Some(Preset::Medium.params())
        );
    }

    #[test]
    fn unit_conversions_of_the_datasheet_figures() {
        // 0.34 °/√h = 9.89e-5 rad/√s; 0.014 °/s/√Hz = 2.443e-4 rad/s/√Hz; 13 µg = 1.275e-4 m/s².
        let a = adis16470();
        assert!((a.gyro.axes[0].white_noise - 9.8902e-5).abs() < 1e-8);
        assert!((bmi088().gyro.axes[0].white_noise - 2.4435e-4).abs() < 1e-8);
        let b = a.acc.axes[0].bias_instability.unwrap().b;
        assert!((b - 1.2749e-4).abs() < 1e-8, "{b}");
        // 0.5 °/h = 2.424e-6 rad/s.
        let s = stim300().gyro.axes[0].bias_instability.unwrap().b;
        assert!((s - 2.4241e-6).abs() < 1e-9, "{s}");
    }
}
