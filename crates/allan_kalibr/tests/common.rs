//! Shared helpers: the reference cases and their files.

use std::path::PathBuf;

/// `testdata/` at the workspace top.
pub fn testdata() -> PathBuf {
    bag2mat::test_tools::testdata()
}

/// A public reference case: directory name, bag topic, update_rate given to the scripts.
pub struct Case {
    pub name: &'static str,
    pub topic: &'static str,
    pub rate: f64,
}

pub const CASES: [Case; 4] = [
    Case {
        name: "p1_high_200hz",
        topic: "imu",
        rate: 200.0,
    },
    Case {
        name: "p2_medium_100hz",
        topic: "/imu/data",
        rate: 100.0,
    },
    Case {
        name: "p3_short_61s",
        topic: "imu",
        rate: 200.0,
    },
    Case {
        name: "p4_high_100hz_60min",
        topic: "imu",
        rate: 100.0,
    },
];

impl Case {
    pub fn dir(&self) -> PathBuf {
        testdata().join(self.name)
    }
    pub fn bag(&self) -> PathBuf {
        self.dir().join(format!("{}.bag", self.name))
    }
    pub fn kalibr(&self, file: &str) -> String {
        let p = self.dir().join("kalibr").join(file);
        std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
    }
}

/// `final_full.txt`: the four numbers and the grid facts.
pub struct FinalFull {
    pub values: [f64; 4],
    pub minid_acc: usize,
    pub minid_gyr: usize,
    pub taumax: u64,
    pub m0_count: usize,
}

fn parse_f64(s: &str) -> f64 {
    match s.trim() {
        "NaN" => f64::NAN,
        "Inf" => f64::INFINITY,
        "-Inf" => f64::NEG_INFINITY,
        v => v
            .parse()
            .unwrap_or_else(|e| panic!("bad number {v:?}: {e}")),
    }
}

pub fn final_full(case: &Case) -> FinalFull {
    let text = case.kalibr("final_full.txt");
    let get = |key: &str| -> String {
        text.lines()
            .find_map(|l| {
                l.strip_prefix(key)
                    .and_then(|r| r.trim_start().strip_prefix('='))
            })
            .unwrap_or_else(|| panic!("{}: no {key} in final_full.txt", case.name))
            .trim()
            .to_owned()
    };
    FinalFull {
        values: [
            parse_f64(&get("accelerometer_noise_density")),
            parse_f64(&get("accelerometer_random_walk")),
            parse_f64(&get("gyroscope_noise_density")),
            parse_f64(&get("gyroscope_random_walk")),
        ],
        minid_acc: get("minid_acc").parse().unwrap(),
        minid_gyr: get("minid_gyr").parse().unwrap(),
        taumax: get("taumax").parse().unwrap(),
        m0_count: get("m0_count").parse().unwrap(),
    }
}

/// `ref_curves.csv`: tau1 and the six sig2 curves, 2000 rows.
pub struct RefCurves {
    pub tau1: Vec<f64>,
    pub sig2: [Vec<f64>; 6],
}

pub fn ref_curves(case: &Case) -> RefCurves {
    let text = case.kalibr("ref_curves.csv");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("tau1,ax,ay,az,wx,wy,wz"),
        "{}: header",
        case.name
    );
    let mut tau1 = Vec::new();
    let mut sig2: [Vec<f64>; 6] = Default::default();
    for l in lines.filter(|l| !l.is_empty()) {
        let v: Vec<f64> = l.split(',').map(parse_f64).collect();
        assert_eq!(v.len(), 7, "{}: row {l}", case.name);
        tau1.push(v[0]);
        for a in 0..6 {
            sig2[a].push(v[a + 1]);
        }
    }
    assert_eq!(tau1.len(), 2000, "{}: rows", case.name);
    RefCurves { tau1, sig2 }
}

/// N rows of bagconvert's matrix (`bagconvert_mat.json` "shape").
pub fn n_rows(case: &Case) -> usize {
    let text = case.kalibr("bagconvert_mat.json");
    let i = text
        .find("\"shape\"")
        .expect("shape in bagconvert_mat.json");
    let rest = &text[i..];
    let open = rest.find('[').unwrap();
    let comma = rest.find(',').unwrap();
    rest[open + 1..comma].trim().parse().unwrap()
}

/// The eight gen_chart lines (`tau = …`, `h_fit… = …`) of process.log, in order.
pub fn process_lines(case: &Case) -> Vec<String> {
    case.kalibr("process.log")
        .lines()
        .filter(|l| l.starts_with("tau = ") || l.starts_with("h_fit"))
        .map(str::to_owned)
        .collect()
}

/// `|a-b|/|b|`, 0 when both are equal (including both NaN), inf when only one is NaN.
pub fn rel_err(a: f64, b: f64) -> f64 {
    if a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()) {
        0.0
    } else if a.is_nan() || b.is_nan() {
        f64::INFINITY
    } else {
        ((a - b) / b).abs()
    }
}

/// `sim bag ARGS…` through sim's library as its binary runs it (its outputs written in
/// place).
pub fn sim_bag(args: &[&str]) {
    let argv = ["sim", "bag"].iter().chain(args);
    let cli = <sim::Cli as clap::Parser>::try_parse_from(argv).unwrap();
    let sim::Command::Bag(a) = cli.command else {
        unreachable!("a bag command")
    };
    let cfg = sim::BagConfig::try_from(*a).unwrap();
    sim::run_bag(&cfg, &bag2mat::shared::output::Outputs::direct()).unwrap();
}

/// `sim bag` with a moving IMU (its ellipse, the medium preset) for `seconds`.
pub fn sim_ellipse_bag(path: &std::path::Path, seconds: u32) {
    let seconds = seconds.to_string();
    sim_bag(&[
        "-o",
        path.to_str().unwrap(),
        "--motion",
        "ellipse",
        "--duration",
        &seconds,
        "--preset",
        "medium",
        "-q",
    ]);
}
