//! The figures a dataset states for its own IMU (an EuRoC/ASL `sensor.yaml`, read by
//! [`bag2mat::sensor_yaml_for`]) printed beside the IEEE 952 values measured here, so a user
//! sees whether the dataset's numbers hold. Both are continuous-time (Kalibr's convention).

use std::fmt::Write as _;
use std::path::Path;

use super::imu::ImuAnalysis;
use crate::consumers::SensorValue;
use bag2mat::Sensor;

/// The IEEE 952 section as both analysers print it: the summary, then the figures the
/// input's `sensor.yaml` states for `topic` beside ours (`beside_ours`).
pub fn section_text(a: &ImuAnalysis, input: &Path, topic: &str) -> String {
    super::imu::summary_text(a) + &beside_ours(a, input, topic)
}

/// The lines printed after the IEEE 952 section when `input`'s topic `topic` has a
/// `sensor.yaml` stating figures; empty otherwise.
pub fn beside_ours(a: &ImuAnalysis, input: &Path, topic: &str) -> String {
    let Some(st) = bag2mat::sensor_yaml_for(input, topic) else {
        return String::new();
    };
    let mut s = format!(
        "\n=> the dataset's sensor.yaml for '{}' states (continuous time) | measured here (here/stated)\n",
        bag2mat::escape_printable(topic)
    );
    let ours = |v: Option<SensorValue>| match v {
        Some(v) if v.upper_bound => format!("< {:.4e} (95 % upper bound)", v.value),
        Some(v) => format!("{:.4e}", v.value),
        None => "-".into(),
    };
    let rows = [
        (
            "gyroscope_noise_density",
            st.gyroscope_noise_density,
            a.noise_density(Sensor::Gyro),
            Sensor::Gyro.n_unit(),
        ),
        (
            "gyroscope_random_walk",
            st.gyroscope_random_walk,
            a.random_walk(Sensor::Gyro),
            Sensor::Gyro.k_unit(),
        ),
        (
            "accelerometer_noise_density",
            st.accelerometer_noise_density,
            a.noise_density(Sensor::Acc),
            Sensor::Acc.n_unit(),
        ),
        (
            "accelerometer_random_walk",
            st.accelerometer_random_walk,
            a.random_walk(Sensor::Acc),
            Sensor::Acc.k_unit(),
        ),
    ];
    for (name, stated, here, unit) in rows {
        let Some(x) = stated else { continue };
        let ratio = here
            .filter(|v| !v.upper_bound && x > 0.0)
            .map(|v| format!("  (x{:.2})", v.value / x))
            .unwrap_or_default();
        let _ = writeln!(s, "{name:<28} {x:<12e} {unit:<18} | {}{ratio}", ours(here));
    }
    if let Some(r) = st.rate_hz {
        let here = format!("{:.4}", a.rate);
        let here = here.trim_end_matches('0').trim_end_matches('.');
        let _ = writeln!(s, "{:<28} {r:<12} {:<18} | {here}", "rate_hz", "Hz");
    }
    s
}
