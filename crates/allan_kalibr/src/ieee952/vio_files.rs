//! The files two VIO stacks read as they are, written beside the Kalibr/VINS/ORB-SLAM3
//! files ([`super::files`]) from the same IEEE 952 values:
//!
//! * `openvins_kalibr_imu_chain_ieee952.yaml`: OpenVINS' `kalibr_imu_chain.yaml`
//!   (`%YAML:1.0`, an `imu0:` block with `T_i_b`, the four Kalibr noise keys, `rostopic`,
//!   `time_offset`, `update_rate`, `model`), parsed by OpenVINS with OpenCV's `FileStorage`.
//!   CONTINUOUS-TIME values (OpenVINS discretises them with the IMU period), one per sensor
//!   (the largest axis), said in its header comments.
//! * `basalt_imu_noise_ieee952.json`: Basalt's calibration noise fields, per axis x y z, in
//!   Basalt's convention (basalt-headers `calibration.hpp`): `accel_noise_std`/
//!   `gyro_noise_std` are continuous-time noise densities (Basalt's discrete σ is the value
//!   × √`imu_update_rate`), `accel_bias_std`/`gyro_bias_std` continuous-time bias random
//!   walks. JSON has no comments, so the file says its convention in a `"_convention"`
//!   member (and which values are 95 % upper bounds in `"_not_resolved"`): Basalt loads its
//!   calibration with cereal, whose JSON archive looks members up by name, so such extra
//!   members are ignored. The file is a fragment: its `value0` members are merged into the
//!   `value0` object of the user's full calibration (cameras, `T_imu_cam`, …). Checked in
//!   the tests (`tests/consumers.rs`) with cereal itself: merged into a calibration, cereal's
//!   JSON archive reads it as Basalt reads `basalt::Calibration` (its twelve members by name,
//!   each fixed-size vector a JSON array of exactly its length, as basalt-headers'
//!   `eigen_io.h` requires), with our values; the fragment alone fails on `T_imu_cam`. Keys
//!   with no value (a sensor not analysed) are left out, so the merge keeps the user's.

use std::fmt::Write as _;

use super::config_values::{FileValues, file_values, inline_note};
use super::imu::{ImuAnalysis, SensorValue};
use crate::yaml::yaml_float;
use bag2mat::Sensor;

/// OpenVINS file name (before the caller's prefix).
pub const OPENVINS_FILE: &str = "openvins_kalibr_imu_chain_ieee952.yaml";
/// Basalt file name (before the caller's prefix).
pub const BASALT_FILE: &str = "basalt_imu_noise_ieee952.json";

/// OpenVINS' `kalibr_imu_chain.yaml` with the IEEE 952 values.
pub(crate) fn openvins_yaml(a: &ImuAnalysis, rostopic: &str) -> String {
    let v: FileValues = file_values(
        a,
        [
            "accelerometer_noise_density",
            "accelerometer_random_walk",
            "gyroscope_noise_density",
            "gyroscope_random_walk",
        ],
    );
    let mut o = String::from("%YAML:1.0\n\n");
    for c in [
        "OpenVINS kalibr_imu_chain.yaml from the IEEE 952 fit of the overlapping Allan deviation",
        "(largest of the three axes). CONTINUOUS-TIME noise densities and random walks, as",
        "Kalibr states them; OpenVINS discretises them with the IMU period. T_i_b is identity",
        "(the IMU is the body frame). Static data give optimistic values: inflate before use.",
    ] {
        let _ = writeln!(o, "# {c}");
    }
    for c in &v.comments {
        let _ = writeln!(o, "# {c}");
    }
    o.push_str("\nimu0:\n  T_i_b:\n");
    for r in 0..4 {
        let row: Vec<&str> = (0..4).map(|c| if r == c { "1.0" } else { "0.0" }).collect();
        let _ = writeln!(o, "    - [{}]", row.join(", "));
    }
    let line = |o: &mut String, key: &str, x: Option<SensorValue>, c: &str| {
        if let Some(x) = x {
            let _ = writeln!(
                o,
                "  {key}: {}   # {c}{}",
                yaml_float(x.value),
                inline_note(Some(x))
            );
        }
    };
    line(
        &mut o,
        "accelerometer_noise_density",
        v.acc_n,
        "[ m / s^2 / sqrt(Hz) ] (accel white noise)",
    );
    line(
        &mut o,
        "accelerometer_random_walk",
        v.acc_w,
        "[ m / s^3 / sqrt(Hz) ] (accel bias diffusion)",
    );
    line(
        &mut o,
        "gyroscope_noise_density",
        v.gyr_n,
        "[ rad / s / sqrt(Hz) ] (gyro white noise)",
    );
    line(
        &mut o,
        "gyroscope_random_walk",
        v.gyr_w,
        "[ rad / s^2 / sqrt(Hz) ] (gyro bias diffusion)",
    );
    let _ = writeln!(o, "  rostopic: {}", crate::yaml::yaml_str(rostopic));
    o.push_str("  time_offset: 0.0\n");
    let _ = writeln!(o, "  update_rate: {}   # [Hz]", yaml_float(a.rate));
    o.push_str("  model: \"kalibr\"\n");
    o
}

/// A JSON number (finite; the callers leave non-finite values out): Rust's `{:e}` is the
/// shortest text that reads back to the same double, and valid JSON as it is (`1.5e-4`).
fn json_num(x: f64) -> String {
    format!("{x:e}")
}

fn json_str(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(o, "\\u{:04x}", c as u32);
            }
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// A term per axis (x y z) of a sensor: the resolved value, else its 95 % upper bound
/// (named in `bounds`); `None` when the sensor is absent or an axis has neither.
fn per_axis(
    a: &ImuAnalysis,
    s: Sensor,
    term: fn(&super::Terms) -> &super::Term,
    key: &str,
    bounds: &mut Vec<String>,
) -> Option<[f64; 3]> {
    let mut v = [f64::NAN; 3];
    for ax in a.sensor_axes(s) {
        let t = term(&ax.analysis.terms);
        v[ax.axis] = match t.reported() {
            Some(x) => x,
            None => {
                bounds.push(format!("{key}[{}]", ax.axis));
                t.hi
            }
        };
    }
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// Basalt's calibration noise fields, per axis, with the convention stated in the file.
pub(crate) fn basalt_json(a: &ImuAnalysis) -> String {
    let mut bounds = Vec::new();
    let fields = [
        (
            "accel_noise_std",
            per_axis(a, Sensor::Acc, |t| &t.n, "accel_noise_std", &mut bounds),
        ),
        (
            "gyro_noise_std",
            per_axis(a, Sensor::Gyro, |t| &t.n, "gyro_noise_std", &mut bounds),
        ),
        (
            "accel_bias_std",
            per_axis(a, Sensor::Acc, |t| &t.k, "accel_bias_std", &mut bounds),
        ),
        (
            "gyro_bias_std",
            per_axis(a, Sensor::Gyro, |t| &t.k, "gyro_bias_std", &mut bounds),
        ),
    ];
    let left_out: Vec<&str> = fields
        .iter()
        .filter(|(_, v)| v.is_none())
        .map(|(k, _)| *k)
        .collect();
    let mut convention = String::from(
        "CONTINUOUS-TIME, per axis [x, y, z], from the IEEE 952 fit of the overlapping Allan deviation, in Basalt's convention (basalt-headers calibration.hpp): accel_noise_std [m/s^2/sqrt(Hz)] and gyro_noise_std [rad/s/sqrt(Hz)] are noise densities (Basalt's discrete sigma = value * sqrt(imu_update_rate)); accel_bias_std [m/s^3/sqrt(Hz)] and gyro_bias_std [rad/s^2/sqrt(Hz)] are bias random walks. A fragment: merge these value0 members into the value0 object of your Basalt calibration JSON (cereal looks members up by name, so the _convention and _not_resolved members are ignored). Static data give optimistic values: inflate before use.",
    );
    if !left_out.is_empty() {
        let _ = write!(
            convention,
            " Left out (no curves or no value for an axis): {}.",
            left_out.join(", ")
        );
    }
    let mut o = String::from("{\n  \"value0\": {\n");
    let _ = writeln!(o, "    \"_convention\": {},", json_str(&convention));
    let _ = writeln!(
        o,
        "    \"_not_resolved\": [{}],",
        bounds
            .iter()
            .map(|b| json_str(&format!("{b}: 95 % upper bound")))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = write!(o, "    \"imu_update_rate\": {}", json_num(a.rate));
    for (k, v) in fields {
        if let Some(v) = v {
            let _ = write!(
                o,
                ",\n    \"{k}\": [{}, {}, {}]",
                json_num(v[0]),
                json_num(v[1]),
                json_num(v[2])
            );
        }
    }
    o.push_str("\n  }\n}\n");
    o
}
