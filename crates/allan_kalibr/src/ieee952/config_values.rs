//! The values and caveats every configuration file of the section carries (Kalibr, VINS,
//! ORB-SLAM3 in [`super::files`]; OpenVINS, Basalt in [`super::vio_files`]): one value per
//! sensor and term, and the comments saying where each is not a plain fitted value.

use super::imu::{ImuAnalysis, SensorValue};
use bag2mat::Sensor;

fn note(name: &str, v: Option<SensorValue>) -> Option<String> {
    let v = v?;
    match (v.upper_bound, v.region) {
        (true, false) => Some(format!(
            "{name} is NOT RESOLVED by this record: 95 % upper bound."
        )),
        (true, true) => Some(format!(
            "{name} is NOT RESOLVED (no reliable fit; IEEE 952 region rule): 95 % upper bound."
        )),
        (false, true) => Some(format!(
            "{name} is an IEEE 952 region reading: the model did not fit an axis."
        )),
        (false, false) => None,
    }
}

pub(super) fn inline_note(v: Option<SensorValue>) -> &'static str {
    match v {
        Some(SensorValue {
            upper_bound: true, ..
        }) => " NOT RESOLVED: 95 % upper bound",
        Some(SensorValue { region: true, .. }) => " IEEE 952 region reading (no reliable fit)",
        _ => "",
    }
}

/// The four values and the comments every configuration file carries.
pub(super) struct FileValues {
    pub(super) acc_n: Option<SensorValue>,
    pub(super) acc_w: Option<SensorValue>,
    pub(super) gyr_n: Option<SensorValue>,
    pub(super) gyr_w: Option<SensorValue>,
    pub(super) comments: Vec<String>,
}

pub(super) fn file_values(a: &ImuAnalysis, names: [&str; 4]) -> FileValues {
    let v = FileValues {
        acc_n: a.noise_density(Sensor::Acc),
        acc_w: a.random_walk(Sensor::Acc),
        gyr_n: a.noise_density(Sensor::Gyro),
        gyr_w: a.random_walk(Sensor::Gyro),
        comments: Vec::new(),
    };
    let mut comments = Vec::new();
    for s in [Sensor::Gyro, Sensor::Acc] {
        if a.sensor_axes(s).next().is_none() {
            comments.push(format!(
                "No {} curves were analysed: its keys are left out.",
                s.name()
            ));
            continue;
        }
        let failed = a.failed_axes(s);
        if !failed.is_empty() {
            comments.push(format!(
                "NO RELIABLE FIT on {}: values from those axes are IEEE 952 region readings.",
                failed.join(", ")
            ));
        }
        let cut = a.truncated_axes(s);
        if !cut.is_empty() {
            comments.push(format!(
                "TRUNCATED FIT on {}: the model describes the curve only up to there; a random walk it does not resolve is the whole curve's 95 % bound.",
                cut.join(", ")
            ));
        }
        let approx = a.approximate_axes(s);
        if !approx.is_empty() {
            comments.push(format!(
                "APPROXIMATE FIT on {}: the model misses the curve beyond its statistics there; those values are approximate.",
                approx.join(", ")
            ));
        }
    }
    for (name, x) in names.iter().zip([v.acc_n, v.acc_w, v.gyr_n, v.gyr_w]) {
        comments.extend(note(name, x));
    }
    // what the record breaks of the analysis' assumptions (bag2mat::check_record)
    for f in a.warnings() {
        comments.push(format!(
            "RECORD CHECK: {}; the values above carry it (the tool's warning says what to do).",
            f.short()
        ));
    }
    FileValues { comments, ..v }
}
