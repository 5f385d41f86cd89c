//! The IEEE 952 analysis of a whole IMU (3 gyro + 3 accelerometer axes), as both binaries
//! print and write it next to their compat outputs: the printed section, the per-axis terms
//! and curves (CSV), and the configuration files users feed the numbers into — Kalibr
//! `imu.yaml`, VINS-Mono/VINS-Fusion keys and ORB-SLAM3 keys — each saying whether its
//! values are continuous-time or discrete at the given rate (field.md §3–4).
//!
//! One value per sensor goes into the configuration files: the largest of the three axes
//! (the conservative choice, as allan_variance_ros writes). A random walk that no axis
//! resolves is written as its 95 % upper bound, and the file says so.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::{Analysis, Config, Ieee952Error, Term, Verdict, analyse};
use crate::yaml::{ImuYaml, yaml_float};

/// Axis labels in analysis order.
pub const AXES: [&str; 6] = ["gyro x", "gyro y", "gyro z", "acc x", "acc y", "acc z"];

/// The analysis of all six axes.
#[derive(Debug, Clone)]
pub struct ImuAnalysis {
    /// Sample rate, Hz (1/τ0).
    pub rate: f64,
    /// gx, gy, gz (rad/s), ax, ay, az (m/s²).
    pub axes: Vec<Analysis>,
}

/// Analyses six rate series (gyro x y z in rad/s, then acc x y z in m/s²) at `rate` Hz,
/// axes in parallel.
pub fn analyse_imu(
    series: [&[f64]; 6],
    rate: f64,
    cfg: &Config,
) -> Result<ImuAnalysis, Ieee952Error> {
    let axes = series
        .par_iter()
        .map(|y| analyse(y, 1.0 / rate, cfg))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(ImuAnalysis { rate, axes })
}

/// [`analyse_imu`] with the default settings, as both binaries run it beside their compat
/// output: data the analysis cannot use (too short, non-finite) only cost the section, and
/// the reason is added to `notes`.
pub fn analyse_section(
    series: [&[f64]; 6],
    rate: f64,
    notes: &mut Vec<String>,
) -> Option<ImuAnalysis> {
    match analyse_imu(series, rate, &Config::default()) {
        Ok(an) => Some(an),
        Err(e) => {
            notes.push(format!("IEEE 952 analysis skipped: {e}"));
            None
        }
    }
}

/// The two sensors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sensor {
    /// Axes 0–2.
    Gyro,
    /// Axes 3–5.
    Acc,
}

impl Sensor {
    fn axes(self) -> std::ops::Range<usize> {
        match self {
            Sensor::Gyro => 0..3,
            Sensor::Acc => 3..6,
        }
    }
    fn n_unit(self) -> &'static str {
        match self {
            Sensor::Gyro => "rad/s/sqrt(Hz)",
            Sensor::Acc => "m/s^2/sqrt(Hz)",
        }
    }
    fn k_unit(self) -> &'static str {
        match self {
            Sensor::Gyro => "rad/s^2/sqrt(Hz)",
            Sensor::Acc => "m/s^3/sqrt(Hz)",
        }
    }
    fn unit(self) -> &'static str {
        match self {
            Sensor::Gyro => "rad/s",
            Sensor::Acc => "m/s^2",
        }
    }
    fn name(self) -> &'static str {
        match self {
            Sensor::Gyro => "gyroscope",
            Sensor::Acc => "accelerometer",
        }
    }
}

/// One number per sensor for the configuration files.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorValue {
    /// The value.
    pub value: f64,
    /// True when the value is a 95 % upper bound (no axis resolved the term).
    pub upper_bound: bool,
}

/// The four numbers every configuration file takes.
struct FileValues {
    acc_n: SensorValue,
    acc_w: SensorValue,
    gyr_n: SensorValue,
    gyr_w: SensorValue,
}

impl ImuAnalysis {
    fn file_values(&self) -> FileValues {
        FileValues {
            acc_n: self.noise_density(Sensor::Acc),
            acc_w: self.random_walk(Sensor::Acc),
            gyr_n: self.noise_density(Sensor::Gyro),
            gyr_w: self.random_walk(Sensor::Gyro),
        }
    }

    /// White-noise density N of a sensor: the largest axis value.
    pub fn noise_density(&self, s: Sensor) -> SensorValue {
        let v = s
            .axes()
            .map(|a| self.axes[a].terms.n.value)
            .fold(f64::NAN, f64::max);
        SensorValue {
            value: v,
            upper_bound: false,
        }
    }

    /// Random walk K of a sensor: the largest resolved axis value, or the largest 95 % upper
    /// bound when no axis resolves it.
    pub fn random_walk(&self, s: Sensor) -> SensorValue {
        let resolved = s
            .axes()
            .filter_map(|a| self.axes[a].terms.k.reported())
            .fold(f64::NAN, f64::max);
        if resolved.is_finite() {
            return SensorValue {
                value: resolved,
                upper_bound: false,
            };
        }
        let hi = s
            .axes()
            .map(|a| self.axes[a].terms.k.hi)
            .fold(f64::NAN, f64::max);
        SensorValue {
            value: hi,
            upper_bound: true,
        }
    }
}

fn term_text(t: &Term, unit: &str) -> String {
    match t.verdict {
        Verdict::Resolved => format!(
            "{:.4e} ± {:.1e} {unit} [95 %: {:.4e}, {:.4e}]",
            t.value, t.std_err, t.lo, t.hi
        ),
        Verdict::NotSignificant => format!("not resolved (95 % upper bound {:.2e} {unit})", t.hi),
        Verdict::NeverDominant => format!(
            "not resolved: never dominant in this record ({:.2e} {unit}, 95 % up to {:.2e})",
            t.value, t.hi
        ),
        Verdict::NotFitted => "not in the fitted model".to_string(),
    }
}

/// The section both binaries print after their compat output.
pub fn summary_text(a: &ImuAnalysis) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n=> IEEE 952 noise terms (overlapping Allan deviation, Greenhall EDF, GLS fit), continuous time, {} Hz",
        a.rate
    );
    for (i, an) in a.axes.iter().enumerate() {
        let sensor = if i < 3 { Sensor::Gyro } else { Sensor::Acc };
        let _ = writeln!(
            s,
            "{:<7} white noise N  = {}",
            AXES[i],
            term_text(&an.terms.n, sensor.n_unit())
        );
        let _ = writeln!(
            s,
            "{:<7} random walk K  = {}",
            "",
            term_text(&an.terms.k, sensor.k_unit())
        );
        let b = &an.terms.b;
        if b.verdict != Verdict::NotFitted {
            let _ = writeln!(
                s,
                "{:<7} bias instab. B = {}",
                "",
                term_text(b, sensor.unit())
            );
        }
    }
    for sensor in [Sensor::Gyro, Sensor::Acc] {
        let (n, k) = (a.noise_density(sensor), a.random_walk(sensor));
        let _ = writeln!(
            s,
            "{}_noise_density = {:.8e} {}   {}_random_walk = {:.8e} {}{}",
            sensor.name(),
            n.value,
            sensor.n_unit(),
            sensor.name(),
            k.value,
            sensor.k_unit(),
            if k.upper_bound {
                " (not resolved: 95 % upper bound)"
            } else {
                ""
            }
        );
    }
    s
}

/// Writes the terms and curves CSVs and the three configuration files into `dir`, each name
/// prefixed with `prefix`; returns the paths.
pub fn write_outputs(
    a: &ImuAnalysis,
    dir: &Path,
    prefix: &str,
    rostopic: &str,
) -> Result<Vec<PathBuf>, bag2mat::Error> {
    let mut files = Vec::new();
    let mut put = |name: String, text: String| -> Result<(), bag2mat::Error> {
        let p = dir.join(format!("{prefix}{name}"));
        bag2mat::shared::output::write_atomic(&p, |w| w.write_all(text.as_bytes()))?;
        files.push(p);
        Ok(())
    };
    put("ieee952_terms.csv".into(), terms_csv(a))?;
    put("ieee952_curves.csv".into(), curves_csv(a))?;
    put("kalibr_imu_ieee952.yaml".into(), kalibr_yaml(a, rostopic))?;
    put("vins_imu_ieee952.yaml".into(), vins_yaml(a))?;
    put("orbslam3_imu_ieee952.yaml".into(), orbslam3_yaml(a))?;
    Ok(files)
}

/// Per axis and term: value, standard error, 95 % interval, verdict, unit. Rust's `{}` float
/// output is the shortest text that reads back to the same double.
pub fn terms_csv(a: &ImuAnalysis) -> String {
    let mut s = String::from(
        "# IEEE 952 terms per axis, continuous time (N: noise density, K: random walk, B: bias instability, Q: quantization, R: ramp)\nsensor,axis,term,value,std_err,ci95_lo,ci95_hi,resolved,verdict,unit\n",
    );
    for (i, an) in a.axes.iter().enumerate() {
        let sensor = if i < 3 { Sensor::Gyro } else { Sensor::Acc };
        let axis = ["x", "y", "z"][i % 3];
        let (u, us) = (
            sensor.unit(),
            if sensor == Sensor::Gyro { "rad" } else { "m/s" },
        );
        let units = [
            ("Q", &an.terms.q, us.to_string()),
            ("N", &an.terms.n, sensor.n_unit().to_string()),
            ("B", &an.terms.b, u.to_string()),
            ("K", &an.terms.k, sensor.k_unit().to_string()),
            ("R", &an.terms.r, format!("{u}/s")),
        ];
        for (name, t, unit) in units {
            let _ = writeln!(
                s,
                "{},{axis},{name},{},{},{},{},{},{:?},{unit}",
                sensor.name(),
                t.value,
                t.std_err,
                t.lo,
                t.hi,
                t.verdict == Verdict::Resolved,
                t.verdict
            );
        }
    }
    s
}

/// The overlapping Allan deviation of every axis with its 68.3 % bounds.
pub fn curves_csv(a: &ImuAnalysis) -> String {
    let mut s = String::from("axis,m,tau,adev,adev_lo,adev_hi,edf,alpha\n");
    for (i, an) in a.axes.iter().enumerate() {
        let axis = ["gx", "gy", "gz", "ax", "ay", "az"][i];
        for p in &an.curve {
            let _ = writeln!(
                s,
                "{axis},{},{},{},{},{},{},{}",
                p.m, p.tau, p.adev, p.lo, p.hi, p.edf, p.alpha
            );
        }
    }
    s
}

fn bound_note(v: SensorValue) -> &'static str {
    if v.upper_bound {
        " NOT RESOLVED by this record: 95 % upper bound"
    } else {
        ""
    }
}

/// Kalibr `imu.yaml` (continuous-time, as Kalibr expects), in the same layout as the
/// compat file ([`crate::yaml::ImuYaml`]).
pub fn kalibr_yaml(a: &ImuAnalysis, rostopic: &str) -> String {
    let (aw, gw) = (a.random_walk(Sensor::Acc), a.random_walk(Sensor::Gyro));
    let y = ImuYaml {
        accelerometer_noise_density: a.noise_density(Sensor::Acc).value,
        accelerometer_random_walk: aw.value,
        gyroscope_noise_density: a.noise_density(Sensor::Gyro).value,
        gyroscope_random_walk: gw.value,
        rostopic: rostopic.to_string(),
        update_rate: a.rate,
    };
    let mut comments = vec![
        "IMU noise model for Kalibr from the IEEE 952 fit of the overlapping Allan deviation",
        "(largest of the three axes). These are CONTINUOUS-TIME values; Kalibr discretises",
        "them with update_rate. Values from static data are optimistic: users commonly",
        "inflate them (x10 or more) before use.",
    ];
    if aw.upper_bound {
        comments
            .push("accelerometer_random_walk is NOT RESOLVED by this record: 95 % upper bound.");
    }
    if gw.upper_bound {
        comments.push("gyroscope_random_walk is NOT RESOLVED by this record: 95 % upper bound.");
    }
    y.render_with(&comments)
}

/// VINS-Mono / VINS-Fusion keys. Their comments say "standard deviation"; VINS uses them as
/// continuous-time densities (it multiplies by the integration period), so these are the
/// continuous-time values, stated in the file.
pub fn vins_yaml(a: &ImuAnalysis) -> String {
    let FileValues {
        acc_n: an,
        acc_w: aw,
        gyr_n: gn,
        gyr_w: gw,
    } = a.file_values();
    format!(
        "%YAML:1.0\n\
         # VINS-Mono / VINS-Fusion IMU parameters from the IEEE 952 fit (largest of the three axes).\n\
         # CONTINUOUS-TIME noise densities and random walks, not per-sample values at {rate} Hz.\n\
         # Static data give optimistic values: inflate before use.\n\
         acc_n: {}   # accelerometer noise density [m/s^2/sqrt(Hz)]\n\
         gyr_n: {}   # gyroscope noise density [rad/s/sqrt(Hz)]\n\
         acc_w: {}   # accelerometer bias random walk [m/s^3/sqrt(Hz)]{}\n\
         gyr_w: {}   # gyroscope bias random walk [rad/s^2/sqrt(Hz)]{}\n\
         g_norm: 9.81   # gravity magnitude [m/s^2]\n",
        yaml_float(an.value),
        yaml_float(gn.value),
        yaml_float(aw.value),
        bound_note(aw),
        yaml_float(gw.value),
        bound_note(gw),
        rate = a.rate
    )
}

/// ORB-SLAM3 settings keys (continuous-time densities; ORB-SLAM3 discretises with
/// IMU.Frequency).
pub fn orbslam3_yaml(a: &ImuAnalysis) -> String {
    let FileValues {
        acc_n: an,
        acc_w: aw,
        gyr_n: gn,
        gyr_w: gw,
    } = a.file_values();
    format!(
        "%YAML:1.0\n\
         # ORB-SLAM3 IMU noise from the IEEE 952 fit (largest of the three axes).\n\
         # CONTINUOUS-TIME values; ORB-SLAM3 discretises them with IMU.Frequency.\n\
         # Static data give optimistic values: inflate before use.\n\
         IMU.NoiseGyro: {}   # [rad/s/sqrt(Hz)]\n\
         IMU.NoiseAcc: {}   # [m/s^2/sqrt(Hz)]\n\
         IMU.GyroWalk: {}   # [rad/s^2/sqrt(Hz)]{}\n\
         IMU.AccWalk: {}   # [m/s^3/sqrt(Hz)]{}\n\
         IMU.Frequency: {}   # [Hz]\n",
        yaml_float(gn.value),
        yaml_float(an.value),
        yaml_float(gw.value),
        bound_note(gw),
        yaml_float(aw.value),
        bound_note(aw),
        yaml_float(a.rate)
    )
}
