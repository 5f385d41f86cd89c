//! The estimators users feed IMU noise figures into, each described once: its keys, what the
//! number under each key means (read from the consumer's own source, cited here, in the
//! README's units tables and in every file written for it), the unit, and the conversion from
//! the two figures the analysis measures — the continuous-time white-noise density N
//! (rad/s/√Hz, m/s²/√Hz) and bias random walk K (rad/s²/√Hz, m/s³/√Hz), Kalibr's definitions
//! (`crate::ieee952` module docs). The config writers ([`render`]), `allan_kalibr check`
//! ([`crate::check`]) and `allan_kalibr plan` ([`crate::plan`]) all take the conventions from
//! here: this module is a leaf below the analysis, which writes the files, and the commands,
//! which read them.
//!
//! | consumer | keys | the number is | from N, K |
//! |---|---|---|---|
//! | Kalibr, OpenVINS, ORB-SLAM3, Basalt | `*_noise_density`, `IMU.Noise*`, `*_noise_std` … | continuous-time N and K | N, K |
//! | VINS-Mono / VINS-Fusion | `acc_n gyr_n acc_w gyr_w` | standard deviation per IMU sample at the IMU's rate f | N·√f, K·√f |
//! | PX4 EKF2 | `EKF2_GYR_NOISE` … | rate noise σ per filter step Δt = `EKF2_PREDICT_US` (10 ms) | N/√Δt, K/√Δt |
//! | ArduPilot EKF3 | `EK3_GYRO_P_NSE` … | the same, per EKF step Δt = `EKF_TARGET_DT` (12 ms) | N/√Δt, K/√Δt |
//! | GTSAM `PreintegrationCombinedParams` | `gyroscopeCovariance` … | continuous-time covariance | N², K² |
//!
//! The per-step forms are instances of the one relation between a continuous density and a
//! per-step standard deviation, σ = N/√Δt (`sim::noise::white_to_discrete`, which `sim`
//! owns for its generator and which this crate cannot depend on: `sim` depends on it); the
//! bias form follows from a consumer adding (σ·Δt)² of bias variance per step where a random
//! walk K adds K²·Δt. A consumer whose convention its source did not establish is not here.
//! MATLAB's `insfilter`/`factorIMUParameters` and GINS-style files are not written: their
//! conventions were not read from source.

pub(crate) mod datasheet;
mod header;
pub(crate) mod read;
pub(crate) mod render;
pub(crate) mod values;

pub use header::{Provenance, RecordRate, input_text, utc_now};
pub use render::render;
pub use values::{AxisValue, ConfigValues, Origin, SensorValue};

use bag2mat::Sensor;

/// One of the four figures every consumer takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Quantity {
    /// Accelerometer white-noise density N.
    AccNoise,
    /// Accelerometer bias random walk K.
    AccWalk,
    /// Gyroscope white-noise density N.
    GyroNoise,
    /// Gyroscope bias random walk K.
    GyroWalk,
}

impl Quantity {
    /// The four, in Kalibr's file order.
    pub const ALL: [Quantity; 4] = [
        Quantity::AccNoise,
        Quantity::AccWalk,
        Quantity::GyroNoise,
        Quantity::GyroWalk,
    ];

    /// Index into arrays ordered as [`Quantity::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The sensor it describes.
    pub fn sensor(self) -> Sensor {
        match self {
            Quantity::AccNoise | Quantity::AccWalk => Sensor::Acc,
            Quantity::GyroNoise | Quantity::GyroWalk => Sensor::Gyro,
        }
    }

    /// True for the bias random walk K, false for the white-noise density N.
    pub fn is_walk(self) -> bool {
        matches!(self, Quantity::AccWalk | Quantity::GyroWalk)
    }

    /// The quantity of `sensor`, N or K.
    pub fn of(sensor: Sensor, walk: bool) -> Quantity {
        match (sensor, walk) {
            (Sensor::Acc, false) => Quantity::AccNoise,
            (Sensor::Acc, true) => Quantity::AccWalk,
            (Sensor::Gyro, false) => Quantity::GyroNoise,
            (Sensor::Gyro, true) => Quantity::GyroWalk,
        }
    }

    /// The continuous-time unit (Kalibr's).
    pub fn unit(self) -> &'static str {
        match self {
            Quantity::AccNoise => "m/s^2/sqrt(Hz)",
            Quantity::AccWalk => "m/s^3/sqrt(Hz)",
            Quantity::GyroNoise => "rad/s/sqrt(Hz)",
            Quantity::GyroWalk => "rad/s^2/sqrt(Hz)",
        }
    }

    /// Words for it: "gyroscope noise density N".
    pub fn label(self) -> &'static str {
        match self {
            Quantity::AccNoise => "accelerometer noise density N",
            Quantity::AccWalk => "accelerometer bias random walk K",
            Quantity::GyroNoise => "gyroscope noise density N",
            Quantity::GyroWalk => "gyroscope bias random walk K",
        }
    }
}

/// What the number under a consumer's key is, in terms of the continuous N or K.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Form {
    /// The continuous-time density itself (N in unit/√Hz, K in unit/s/√Hz).
    Continuous,
    /// A standard deviation per IMU sample at the IMU's rate f: N·√f for the white noise;
    /// for the bias, the σ whose per-sample increment the consumer takes as σ/f: K·√f.
    PerSample,
    /// A standard deviation per filter step of `dt` seconds (a fixed property of the
    /// consumer, not of the IMU): N/√dt, and K/√dt for the bias (the consumer adds
    /// (σ·dt)² of bias variance per step).
    PerFilterStep {
        /// The consumer's nominal prediction step, s.
        dt: f64,
    },
    /// The continuous-time covariance: the density squared (on a 3×3 diagonal).
    Covariance,
}

impl Form {
    /// The consumer's number for a continuous value `x` of the IMU sampled at `rate` Hz
    /// (`None`: this form needs the rate and it is unknown).
    pub fn from_continuous(self, x: f64, rate: Option<f64>) -> Option<f64> {
        match self {
            Form::Continuous => Some(x),
            Form::PerSample => rate.map(|f| x * f.sqrt()),
            Form::PerFilterStep { dt } => Some(x / dt.sqrt()),
            Form::Covariance => Some(x * x),
        }
    }

    /// The continuous value behind a consumer's number `v` (inverse of
    /// [`Form::from_continuous`]).
    pub fn to_continuous(self, v: f64, rate: Option<f64>) -> Option<f64> {
        match self {
            Form::Continuous => Some(v),
            Form::PerSample => rate.map(|f| v / f.sqrt()),
            Form::PerFilterStep { dt } => Some(v * dt.sqrt()),
            Form::Covariance => Some(v.sqrt()),
        }
    }

    /// The conversion in words, for file headers and `check`.
    pub fn formula(self, walk: bool) -> String {
        let s = if walk { "K" } else { "N" };
        match self {
            Form::Continuous => format!("{s} (continuous time, as measured)"),
            Form::PerSample => {
                format!("{s}*sqrt(rate): per-sample standard deviation at the IMU's rate")
            }
            Form::PerFilterStep { dt } => format!(
                "{s}/sqrt({}): standard deviation per filter step of {} s",
                crate::yaml::yaml_float(dt),
                crate::yaml::yaml_float(dt)
            ),
            Form::Covariance => format!("{s}^2 (continuous-time covariance on the 3x3 diagonal)"),
        }
    }
}

/// One key of a consumer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    /// The key as the consumer spells it.
    pub name: &'static str,
    /// What it holds.
    pub quantity: Quantity,
    /// The unit of the number under it.
    pub unit: &'static str,
    /// The range the consumer documents for it (ground stations refuse values outside).
    pub range: Option<(f64, f64)>,
}

/// The consumers this tool writes files for and checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ConsumerId {
    /// Kalibr's `imu.yaml`.
    Kalibr,
    /// OpenVINS' `kalibr_imu_chain.yaml`.
    OpenVins,
    /// VINS-Mono / VINS-Fusion settings.
    Vins,
    /// ORB-SLAM3 settings.
    OrbSlam3,
    /// Basalt's calibration JSON.
    Basalt,
    /// PX4's EKF2 parameters.
    Px4,
    /// ArduPilot's EKF3 parameters.
    ArduPilot,
    /// GTSAM's `PreintegrationCombinedParams`.
    Gtsam,
}

/// A consumer: its keys, their convention and where the convention was read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Consumer {
    /// Which.
    pub id: ConsumerId,
    /// Its name.
    pub name: &'static str,
    /// The file this tool writes for it (before a caller's prefix).
    pub file: &'static str,
    /// What its numbers are.
    pub form: Form,
    /// Its four keys, in [`Quantity::ALL`] order.
    pub keys: [Key; 4],
    /// Its key for the IMU's rate, if it has one.
    pub rate_key: Option<&'static str>,
    /// The source files its convention was read from (repository, path, commit: what they show).
    pub sources: &'static [&'static str],
}

impl Consumer {
    /// Its key for `q`.
    pub fn key(&self, q: Quantity) -> &Key {
        &self.keys[q.index()]
    }

    /// The key named `name`, if it is one of its four.
    pub fn find(&self, name: &str) -> Option<&Key> {
        self.keys.iter().find(|k| k.name == name)
    }
}

const fn key(name: &'static str, quantity: Quantity, unit: &'static str) -> Key {
    Key {
        name,
        quantity,
        unit,
        range: None,
    }
}

const fn ranged(
    name: &'static str,
    quantity: Quantity,
    unit: &'static str,
    range: (f64, f64),
) -> Key {
    Key {
        name,
        quantity,
        unit,
        range: Some(range),
    }
}

/// Kalibr's keys (also OpenVINS').
const KALIBR_KEYS: [Key; 4] = [
    key(
        "accelerometer_noise_density",
        Quantity::AccNoise,
        "m/s^2/sqrt(Hz)",
    ),
    key(
        "accelerometer_random_walk",
        Quantity::AccWalk,
        "m/s^3/sqrt(Hz)",
    ),
    key(
        "gyroscope_noise_density",
        Quantity::GyroNoise,
        "rad/s/sqrt(Hz)",
    ),
    key(
        "gyroscope_random_walk",
        Quantity::GyroWalk,
        "rad/s^2/sqrt(Hz)",
    ),
];

/// PX4's EKF2 prediction step, s: `EKF2_PREDICT_US`'s default, 10000 µs.
pub const PX4_EKF2_DT: f64 = 0.010;
/// ArduPilot's EKF3 prediction step, s: `EKF_TARGET_DT`.
pub const ARDUPILOT_EKF3_DT: f64 = 0.012;

/// Every consumer, in the order the files are written.
pub const CONSUMERS: [Consumer; 8] = [
    Consumer {
        id: ConsumerId::Kalibr,
        name: "Kalibr",
        file: "kalibr_imu_ieee952.yaml",
        form: Form::Continuous,
        keys: KALIBR_KEYS,
        rate_key: Some("update_rate"),
        sources: &[
            "ethz-asl/kalibr aslam_offline_calibration/kalibr/python/kalibr_common/ConfigReader.py @ ea2791f: getGyroStatistics/getAccelerometerStatistics take the noise density as continuous (discrete sigma = noise_density / sqrt(1/update_rate)) and the random walk as continuous",
        ],
    },
    Consumer {
        id: ConsumerId::OpenVins,
        name: "OpenVINS",
        file: "openvins_kalibr_imu_chain_ieee952.yaml",
        form: Form::Continuous,
        keys: KALIBR_KEYS,
        rate_key: Some("update_rate"),
        sources: &[
            "rpng/open_vins ov_msckf/src/state/Propagator.cpp @ b9c2509: Qc = sigma_w^2/dt, sigma_a^2/dt, sigma_wb^2/dt, sigma_ab^2/dt, then Qd = G Qc G^T with G ~ dt: continuous-time densities",
        ],
    },
    Consumer {
        id: ConsumerId::Vins,
        name: "VINS-Mono / VINS-Fusion",
        file: "vins_imu_ieee952.yaml",
        form: Form::PerSample,
        keys: [
            key("acc_n", Quantity::AccNoise, "m/s^2"),
            key("acc_w", Quantity::AccWalk, "m/s^3"),
            key("gyr_n", Quantity::GyroNoise, "rad/s"),
            key("gyr_w", Quantity::GyroWalk, "rad/s^2"),
        ],
        rate_key: None,
        sources: &[
            "HKUST-Aerial-Robotics/VINS-Fusion vins_estimator/src/factor/integration_base.h @ 939f012 (and VINS-Mono's @ bd7f50c): midPointIntegration adds V*noise*V^T per IMU sample with noise = diag(ACC_N^2, GYR_N^2, ACC_N^2, GYR_N^2, ACC_W^2, GYR_W^2) and V = 0.5*R*dt for the measurements, dt for the biases: a standard deviation per sample at the IMU's rate",
        ],
    },
    Consumer {
        id: ConsumerId::OrbSlam3,
        name: "ORB-SLAM3",
        file: "orbslam3_imu_ieee952.yaml",
        form: Form::Continuous,
        keys: [
            key("IMU.NoiseAcc", Quantity::AccNoise, "m/s^2/sqrt(Hz)"),
            key("IMU.AccWalk", Quantity::AccWalk, "m/s^3/sqrt(Hz)"),
            key("IMU.NoiseGyro", Quantity::GyroNoise, "rad/s/sqrt(Hz)"),
            key("IMU.GyroWalk", Quantity::GyroWalk, "rad/s^2/sqrt(Hz)"),
        ],
        rate_key: Some("IMU.Frequency"),
        sources: &[
            "UZ-SLAMLab/ORB_SLAM3 src/Tracking.cc @ ef97841: IMU::Calib(Tbc, Ng*sf, Na*sf, Ngw/sf, Naw/sf) with sf = sqrt(IMU.Frequency): continuous-time values; its legacy settings reader takes IMU.Frequency only as an integer (node.isInt()), src/Settings.cc @ 1464d8f readIMU as a number",
        ],
    },
    Consumer {
        id: ConsumerId::Basalt,
        name: "Basalt",
        file: "basalt_imu_noise_ieee952.json",
        form: Form::Continuous,
        keys: [
            key("accel_noise_std", Quantity::AccNoise, "m/s^2/sqrt(Hz)"),
            key("accel_bias_std", Quantity::AccWalk, "m/s^3/sqrt(Hz)"),
            key("gyro_noise_std", Quantity::GyroNoise, "rad/s/sqrt(Hz)"),
            key("gyro_bias_std", Quantity::GyroWalk, "rad/s^2/sqrt(Hz)"),
        ],
        rate_key: Some("imu_update_rate"),
        sources: &[
            "VladyslavUsenko/basalt-headers include/basalt/calibration/calibration.hpp @ 12b6290: \"All noise parameters are continous time\"; dicrete_time_gyro_noise_std() = gyro_noise_std * sqrt(imu_update_rate)",
        ],
    },
    Consumer {
        id: ConsumerId::Px4,
        name: "PX4 EKF2",
        file: "px4_ekf2_ieee952.params",
        form: Form::PerFilterStep { dt: PX4_EKF2_DT },
        keys: [
            ranged("EKF2_ACC_NOISE", Quantity::AccNoise, "m/s^2", (0.01, 1.0)),
            ranged("EKF2_ACC_B_NOISE", Quantity::AccWalk, "m/s^3", (0.0, 0.01)),
            ranged(
                "EKF2_GYR_NOISE",
                Quantity::GyroNoise,
                "rad/s",
                (0.0001, 0.1),
            ),
            ranged(
                "EKF2_GYR_B_NOISE",
                Quantity::GyroWalk,
                "rad/s^2",
                (0.0, 0.01),
            ),
        ],
        rate_key: None,
        sources: &[
            "PX4/PX4-Autopilot src/modules/ekf2/EKF/covariance.cpp @ 765f284 (predictCovariance): gyro_var = EKF2_GYR_NOISE^2 enters the delta-angle covariance as gyro_var*dt^2 per step (EKF/python/ekf_derivation/derivation.py @ 1263e1a); the bias state gets (dt*EKF2_GYR_B_NOISE)^2 per step; dt is the EKF step",
            "PX4/PX4-Autopilot src/modules/ekf2/module.yaml: EKF2_PREDICT_US = 10000 us; EKF2_GYR_NOISE 0.0001..0.1 rad/s, EKF2_ACC_NOISE 0.01..1.0 m/s^2; params_gyro_bias.yaml, params_accel_bias.yaml @ 15c4f08: EKF2_GYR_B_NOISE 0..0.01 rad/s^2, EKF2_ACC_B_NOISE 0..0.01 m/s^3",
        ],
    },
    Consumer {
        id: ConsumerId::ArduPilot,
        name: "ArduPilot EKF3",
        file: "ardupilot_ekf3_ieee952.param",
        form: Form::PerFilterStep {
            dt: ARDUPILOT_EKF3_DT,
        },
        keys: [
            ranged("EK3_ACC_P_NSE", Quantity::AccNoise, "m/s^2", (0.01, 1.0)),
            ranged(
                "EK3_ABIAS_P_NSE",
                Quantity::AccWalk,
                "m/s^3",
                (0.00001, 0.02),
            ),
            ranged(
                "EK3_GYRO_P_NSE",
                Quantity::GyroNoise,
                "rad/s",
                (0.0001, 0.1),
            ),
            ranged(
                "EK3_GBIAS_P_NSE",
                Quantity::GyroWalk,
                "rad/s^2",
                (0.00001, 0.001),
            ),
        ],
        rate_key: None,
        sources: &[
            "ArduPilot/ardupilot libraries/AP_NavEKF3/AP_NavEKF3_core.cpp @ 363e7e9 (CovariancePrediction): daxVar = (dt*EK3_GYRO_P_NSE)^2, dvxVar = (dt*EK3_ACC_P_NSE)^2, and (dt^2*EK3_GBIAS_P_NSE)^2, (dt^2*EK3_ABIAS_P_NSE)^2 on the delta-angle and delta-velocity bias states (bias*dt); dt the EKF step",
            "ArduPilot/ardupilot libraries/AP_NavEKF3/AP_NavEKF3_core.h @ 92f2515: EKF_TARGET_DT = 0.012 s; AP_NavEKF3.cpp @ 83c544f: ranges GYRO_P_NSE 0.0001..0.1 rad/s, ACC_P_NSE 0.01..1.0 m/s/s, GBIAS_P_NSE 0.00001..0.001 rad/s/s, ABIAS_P_NSE 0.00001..0.02 m/s/s/s",
        ],
    },
    Consumer {
        id: ConsumerId::Gtsam,
        name: "GTSAM PreintegrationCombinedParams",
        file: "gtsam_imu_params_ieee952.yaml",
        form: Form::Covariance,
        keys: [
            key("accelerometerCovariance", Quantity::AccNoise, "m^2/s^4/Hz"),
            key("biasAccCovariance", Quantity::AccWalk, "m^2/s^6/Hz"),
            key("gyroscopeCovariance", Quantity::GyroNoise, "rad^2/s^2/Hz"),
            key("biasOmegaCovariance", Quantity::GyroWalk, "rad^2/s^4/Hz"),
        ],
        rate_key: None,
        sources: &[
            "borglab/gtsam gtsam/navigation/PreintegratedRotation.h @ a90dbc7: gyroscopeCovariance, \"Continuous-time Covariance\", sigma in rad/s/sqrt(Hz); PreintegrationParams.h @ eadfbac: accelerometerCovariance, sigma in m/s^2/sqrt(Hz)",
            "borglab/gtsam gtsam/navigation/PreintegrationCombinedParams.h @ 191db15: biasAccCovariance, biasOmegaCovariance, \"continuous-time Covariance describing\" the bias random walk (discretised as Sigma*dt per step)",
        ],
    },
];

/// A number as the config files write it: scientific notation with the shortest digits
/// that read back to the same f64, which YAML 1.1 and 1.2, OpenCV and JSON all read as a real.
pub fn sci(x: f64) -> String {
    crate::yaml::yaml_sci(x)
}

/// The consumer `id`.
pub fn consumer(id: ConsumerId) -> &'static Consumer {
    CONSUMERS
        .iter()
        .find(|c| c.id == id)
        .expect("every ConsumerId is in CONSUMERS")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_invert_each_other() {
        for c in &CONSUMERS {
            for k in &c.keys {
                for x in [1e-12, 3.3e-7, 1.7e-4, 0.02, 1e3] {
                    let v = c.form.from_continuous(x, Some(200.0)).unwrap();
                    let back = c.form.to_continuous(v, Some(200.0)).unwrap();
                    assert!(
                        (back / x - 1.0).abs() < 1e-14,
                        "{} {}: {x} -> {v} -> {back}",
                        c.name,
                        k.name
                    );
                }
            }
        }
        // VINS needs the rate; the others do not
        assert_eq!(Form::PerSample.from_continuous(1e-3, None), None);
        assert_eq!(
            Form::PerSample.from_continuous(1e-3, Some(400.0)),
            Some(2e-2)
        );
        // PX4: N = 1.5e-3 rad/s/sqrt(Hz) at a 10 ms step is 0.015 rad/s, its default
        let px4 = consumer(ConsumerId::Px4);
        let v = px4.form.from_continuous(1.5e-3, None).unwrap();
        assert!((v - 0.015).abs() < 1e-15, "{v}");
    }

    #[test]
    fn every_consumer_names_each_quantity_once_in_order() {
        for c in &CONSUMERS {
            for (k, q) in c.keys.iter().zip(Quantity::ALL) {
                assert_eq!(k.quantity, q, "{}", c.name);
                assert_eq!(c.find(k.name), Some(k));
            }
            assert!(!c.sources.is_empty(), "{}: no source", c.name);
        }
    }
}
