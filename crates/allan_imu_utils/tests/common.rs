//! Shared helpers: where the reference cases live and how their dumps are parsed.

use std::path::{Path, PathBuf};

/// The workspace's testdata directory.
pub fn testdata() -> PathBuf {
    bag2mat::test_tools::testdata()
}

/// One reference case and the arguments upstream ran with (testdata/README.md, docs/upstream/imu_utils.md §8).
pub struct Case {
    pub dir: &'static str,
    pub topic: &'static str,
    pub max_time_min: u32,
    pub name: &'static str,
}

pub const CASES: &[Case] = &[
    Case {
        dir: "p1_high_200hz",
        topic: "imu",
        max_time_min: 14,
        name: "p1",
    },
    Case {
        dir: "p2_medium_100hz",
        topic: "/imu/data",
        max_time_min: 11,
        name: "p2",
    },
    Case {
        dir: "p3_short_61s",
        topic: "imu",
        max_time_min: 120,
        name: "p3",
    },
    Case {
        dir: "p4_high_100hz_60min",
        topic: "imu",
        max_time_min: 59,
        name: "p4",
    },
];

pub const AXES: [&str; 6] = ["gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z"];

impl Case {
    pub fn ref_dir(&self) -> PathBuf {
        testdata().join(self.dir).join("imu_utils")
    }

    pub fn bag(&self) -> PathBuf {
        testdata().join(self.dir).join(format!("{}.bag", self.dir))
    }

    pub fn read(&self, file: &str) -> String {
        let p = self.ref_dir().join(file);
        std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
    }

    /// (taus, variances) of `ref_dump_<axis>_tau_var.txt`.
    pub fn tau_var(&self, axis: &str) -> (Vec<f64>, Vec<f64>) {
        let text = self.read(&format!("ref_dump_{axis}_tau_var.txt"));
        let mut t = Vec::new();
        let mut v = Vec::new();
        for line in text.lines().filter(|l| !l.trim().is_empty()) {
            let mut it = line.split_whitespace().map(parse_c_float);
            t.push(it.next().unwrap());
            v.push(it.next().unwrap());
        }
        (t, v)
    }

    /// The key/value pairs of the summary line starting with `axis`.
    pub fn summary_values(&self, axis: &str) -> Vec<(String, f64)> {
        let text = self.read("ref_dump_summary.txt");
        let line = text
            .lines()
            .find(|l| l.starts_with(&format!("{axis} ")))
            .unwrap_or_else(|| panic!("{}: no summary line for {axis}", self.dir));
        let toks: Vec<&str> = line.split_whitespace().skip(1).collect();
        toks.chunks(2)
            .map(|c| (c[0].to_string(), parse_c_float(c[1])))
            .collect()
    }

    pub fn summary_value(&self, axis: &str, key: &str) -> f64 {
        self.summary_values(axis)
            .into_iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v)
            .unwrap()
    }

    /// The factor list of the summary.
    pub fn factors(&self) -> Vec<usize> {
        let text = self.read("ref_dump_summary.txt");
        let line = text.lines().find(|l| l.starts_with("factors(")).unwrap();
        let (_, list) = line.split_once("):").unwrap();
        list.split_whitespace()
            .map(|s| s.parse().unwrap())
            .collect()
    }
}

/// Parses C's float spellings, including `-nan`, `nan`, `inf`.
pub fn parse_c_float(s: &str) -> f64 {
    match s {
        "-nan" | "nan" => f64::NAN,
        "inf" => f64::INFINITY,
        "-inf" => f64::NEG_INFINITY,
        _ => s.parse().unwrap_or_else(|_| panic!("not a number: {s:?}")),
    }
}

/// Relative error, with NaN equal to NaN.
pub fn rel_err(actual: f64, expected: f64) -> f64 {
    if actual.is_nan() && expected.is_nan() || actual == expected {
        return 0.0;
    }
    ((actual - expected) / expected).abs()
}

/// allan_imu_utils' settings for `topic` of `bag` into `out` (IMU name `x`, header time,
/// quiet, no plots), as the command line would give them.
pub fn imu_utils_config(bag: &Path, topic: &str, out: &Path) -> allan_imu_utils::Config {
    let mut c = allan_imu_utils::Config::new(allan_kalibr::Input::Samples(bag.to_path_buf()), out);
    c.common.topics = bag2mat::TopicSelector::one(topic);
    c.name = "x".into();
    c.plots = false;
    c
}

/// allan_kalibr's settings for `topic` of `bag` into `out` (record time, rate from the
/// stamps, quiet), as the command line would give them.
pub fn kalibr_config(bag: &Path, topic: &str, out: &Path) -> allan_kalibr::Config {
    let mut c = allan_kalibr::Config::new(allan_kalibr::Input::Samples(bag.to_path_buf()), out);
    c.common.topics = bag2mat::TopicSelector::one(topic);
    c.title = "t".into();
    c
}
