//! `allan_kalibr check CONFIG…`: reads the config files users already have (Kalibr
//! `imu.yaml` and `imu_chain`, OpenVINS, VINS, ORB-SLAM3, Basalt JSON, PX4 `.params`,
//! ArduPilot `.param`, GTSAM, imu_utils' yaml) and says, one line per key on stdout, what the
//! number is under that consumer's convention ([`crate::consumers::CONSUMERS`]) and what is wrong with
//! it: a value the consumer will not read as a number, a discrete (per-sample) value where it
//! wants a continuous density (or the other way), a variance where it wants a standard
//! deviation, imu_utils' bias instability where a random walk belongs, a rate that disagrees
//! with the record, a value no IMU has. With `--against` (an analysis folder of this tool, or
//! an IMU log analysed on the spot) each value is set against the measured one: its ratio,
//! and what that ratio does to the estimator ("×10.2: inflated"). Findings are the output,
//! not an error: the exit code is 0 unless a file cannot be read.
//!
//! A line is `FILE: KEY = VALUE: ok: …` or `FILE: KEY = VALUE: finding (WHAT): …`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::consumers::read::{self, Entry, Kind};
use crate::consumers::{Consumer, ConsumerId, Form, Key, Quantity, consumer, datasheet};
use crate::ieee952::csv_back::OutputCsv;
use crate::ieee952::files as terms;

/// A value within this factor of the measured one agrees with it (the 95 % precision of K
/// from a few hours of data is ±25–50 %; a config that close is the measurement).
pub const AGREE_FACTOR: f64 = 1.5;
/// A value this close to a telltale multiple of the measured one (√rate, a square) is that
/// mistake: tighter than [`AGREE_FACTOR`], so that the two readings do not overlap for rates
/// above 9 Hz.
pub const MISTAKE_FACTOR: f64 = 1.25;
/// A variance (the square of the value a consumer wants) is named as such only where the
/// value is below this: its square is then at least tenfold smaller, not a mere deflation.
pub const SQUARE_APART: f64 = 0.1;
/// A file's rate within this fraction of the record's is the record's rate.
pub const RATE_REL_TOL: f64 = 0.01;

/// The continuous values IMUs have, per quantity (in [`Quantity::ALL`] order): from a
/// navigation-grade part (gyro 0.0002 °/√h, accelerometer 1 µg/√Hz) to the noisiest MEMS
/// inflated fifty-fold; a value outside is a unit or convention mistake.
pub const PLAUSIBLE: [(f64, f64); 4] = [(1e-6, 1.0), (1e-9, 1.0), (3e-8, 0.5), (1e-11, 0.1)];
/// The sample rates IMUs have, Hz.
pub const PLAUSIBLE_RATE: (f64, f64) = (1.0, 1e5);

/// What the command line of `check` says.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct CheckArgs {
    /// The config files to check (Kalibr imu.yaml or imu_chain, OpenVINS, VINS, ORB-SLAM3,
    /// Basalt .json, PX4 .params, ArduPilot .param, GTSAM, imu_utils' yaml).
    #[arg(required = true, value_name = "CONFIG")]
    pub configs: Vec<PathBuf>,
    /// What to compare each value with: an analysis folder this tool wrote (its
    /// ieee952_terms.csv), or an IMU log (a bag, .mat or log allan_kalibr reads), analysed
    /// now (nothing written).
    #[arg(long, value_name = "DIR|LOG")]
    pub against: Option<PathBuf>,
    /// The topic of the log given with --against [default: as allan_kalibr chooses].
    #[arg(long, value_name = "TOPIC", requires = "against")]
    pub topic: Option<String>,
    /// The IMU's sample rate, Hz, where neither the file nor --against says it (VINS' and
    /// imu_utils' per-sample values depend on it).
    #[arg(long, value_name = "HZ", value_parser = crate::front::rate_hz)]
    pub rate: Option<f64>,
}

/// The errors of `check`: a file that cannot be read or a reference that cannot be had.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// A config file could not be read.
    #[error("{path}: {what}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        what: String,
    },
    /// `--against` gave no measured values.
    #[error("--against {path}: {what}")]
    Against {
        /// The folder or log.
        path: PathBuf,
        /// Why.
        what: String,
    },
    /// Analysing the `--against` log failed.
    #[error("--against {path}: {source}")]
    Analysis {
        /// The log.
        path: PathBuf,
        /// Why the analysis failed.
        source: crate::Error,
    },
}

/// A measured value: its value, its 95 % interval, and whether it is only an upper bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// The value (continuous time).
    pub value: f64,
    /// 95 % interval, lower end.
    pub lo: f64,
    /// 95 % interval, upper end (the bound itself for an unresolved term).
    pub hi: f64,
    /// Not resolved: `hi` is a 95 % upper bound.
    pub bound: bool,
}

/// What an analysis measured, for the comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    /// Per quantity, as the files take it (the largest axis; a bound when no axis resolves).
    pub values: [Option<Measured>; 4],
    /// Per quantity and axis x y z.
    pub axes: [[Option<Measured>; 3]; 4],
    /// Per sensor (acc, gyro), what a bias-instability figure of it may be: the resolved B
    /// and its floor 0.664·B, and each axis' lowest Allan deviation (imu_utils' `*_w`).
    pub floors: [Vec<f64>; 2],
    /// The record's rate, Hz.
    pub rate: Option<f64>,
    /// What was measured ("the analysis in out/").
    pub what: String,
}

impl Reference {
    /// The measured values of an `ieee952_terms.csv` (the rows of every axis; the largest
    /// axis per sensor, resolved values first, as the config files take them), and the
    /// floors of its `ieee952_curves.csv` when given.
    pub fn from_terms_csv(
        text: &str,
        curves: Option<&str>,
        what: &str,
    ) -> Result<Reference, String> {
        let csv = OutputCsv::parse(text);
        let [cs, ca, ct, cv, clo, chi, cr] = csv
            .columns([
                terms::COL_SENSOR,
                terms::COL_AXIS,
                terms::COL_TERM,
                terms::COL_VALUE,
                terms::COL_CI95_LO,
                terms::COL_CI95_HI,
                terms::COL_RESOLVED,
            ])
            .map_err(|name| format!("no column {name}: not an ieee952_terms.csv"))?;
        let mut axes = [[None; 3]; 4];
        let mut floors: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
        for f in csv.rows() {
            if f.len() < csv.width() {
                continue;
            }
            let num = |i: usize| f[i].parse::<f64>().unwrap_or(f64::NAN);
            let sensor = match f[cs] {
                "gyroscope" => bag2mat::Sensor::Gyro,
                "accelerometer" => bag2mat::Sensor::Acc,
                _ => continue,
            };
            let Some(axis) = ["x", "y", "z"].iter().position(|a| *a == f[ca]) else {
                continue;
            };
            let resolved = f[cr] == "true";
            match f[ct] {
                "N" | "K" => {
                    let q = Quantity::of(sensor, f[ct] == "K");
                    let m = if resolved {
                        Measured {
                            value: num(cv),
                            lo: num(clo),
                            hi: num(chi),
                            bound: false,
                        }
                    } else {
                        Measured {
                            value: num(chi),
                            lo: 0.0,
                            hi: num(chi),
                            bound: true,
                        }
                    };
                    if m.value.is_finite() {
                        axes[q.index()][axis] = Some(m);
                    }
                }
                "B" if resolved => {
                    let v = num(cv);
                    if v.is_finite() && v > 0.0 {
                        let i = usize::from(sensor == bag2mat::Sensor::Gyro);
                        floors[i].extend([v, crate::B_FLOOR_FACTOR * v]);
                    }
                }
                _ => {}
            }
        }
        // the files' rule: the largest resolved axis, else the largest bound
        let values = axes.map(|a| {
            let resolved = a
                .iter()
                .flatten()
                .filter(|m| !m.bound)
                .max_by(|x, y| x.value.total_cmp(&y.value));
            resolved
                .or_else(|| {
                    a.iter()
                        .flatten()
                        .max_by(|x, y| x.value.total_cmp(&y.value))
                })
                .copied()
        });
        if values.iter().all(Option::is_none) {
            return Err("no N or K rows".into());
        }
        let rate = text
            .lines()
            .take_while(|l| l.starts_with('#'))
            .find_map(|l| {
                l.split(|c: char| c == ',' || c.is_whitespace())
                    .find_map(|w| w.strip_prefix("rate="))
                    .and_then(|v| v.parse().ok())
            });
        // each axis' lowest deviation (`axis,m,tau,adev` rows, axis gx … az)
        let mut minima = [[f64::INFINITY; 3]; 2];
        for l in curves
            .unwrap_or("")
            .lines()
            .filter(|l| !l.starts_with('#'))
            .skip(1)
        {
            let f: Vec<&str> = l.split(',').collect();
            let (Some(code), Some(Ok(adev))) = (f.first(), f.get(3).map(|x| x.parse::<f64>()))
            else {
                continue;
            };
            let i = match code.as_bytes().first() {
                Some(b'g') => 1,
                Some(b'a') => 0,
                _ => continue,
            };
            let Some(k) = ["x", "y", "z"]
                .iter()
                .position(|a| code.get(1..) == Some(*a))
            else {
                continue;
            };
            if adev.is_finite() && adev > 0.0 {
                minima[i][k] = minima[i][k].min(adev);
            }
        }
        for (f, m) in floors.iter_mut().zip(minima) {
            f.extend(m.into_iter().filter(|x| x.is_finite()));
        }
        for f in floors.iter_mut() {
            f.sort_by(f64::total_cmp);
        }
        Ok(Reference {
            values,
            axes,
            floors,
            rate,
            what: what.to_string(),
        })
    }
}

/// The reference `--against` names: the terms of an analysis folder, or a log analysed now.
fn reference(args: &CheckArgs) -> Result<Option<Reference>, CheckError> {
    let Some(p) = &args.against else {
        return Ok(None);
    };
    let against = |what: String| CheckError::Against {
        path: p.clone(),
        what,
    };
    if p.is_dir() && !is_log_dir(p) {
        let found: Vec<PathBuf> = std::fs::read_dir(p)
            .map_err(|e| against(e.to_string()))?
            .flatten()
            .map(|e| e.path())
            .filter(|f| {
                f.file_name()
                    .is_some_and(|n| n.to_string_lossy().ends_with(terms::TERMS_FILE))
            })
            .collect();
        let file = match found.as_slice() {
            [one] => one,
            [] => {
                return Err(against(format!(
                    "no {} in it (an analysis folder of allan_kalibr or allan_imu_utils)",
                    terms::TERMS_FILE
                )));
            }
            _ => {
                return Err(against(format!(
                    "several analyses in it ({}): name one with --against FILE",
                    found
                        .iter()
                        .map(|f| f.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
        };
        return read_terms(file, p);
    }
    if p.file_name()
        .is_some_and(|n| n.to_string_lossy().ends_with(terms::TERMS_FILE))
    {
        return read_terms(p, p);
    }
    let mut config = crate::Config::new(crate::Input::Samples(p.clone()), "");
    if let Some(t) = &args.topic {
        config.common.topics = bag2mat::TopicSelector {
            topics: vec![t.clone()],
            ..Default::default()
        };
    }
    config.common.rate = args.rate;
    let an = crate::run::section_only(&config)
        .map_err(|source| CheckError::Analysis {
            path: p.clone(),
            source,
        })?
        .map_err(against)?;
    let text = terms::terms_csv(&an);
    let curves = terms::curves_csv(&an);
    Reference::from_terms_csv(
        &text,
        Some(&curves),
        &format!("the IEEE 952 analysis of {}", p.display()),
    )
    .map(Some)
    .map_err(against)
}

/// A directory that is an input log (a ROS 2 bag, an EuRoC dataset), not an analysis folder.
fn is_log_dir(p: &Path) -> bool {
    p.join("metadata.yaml").exists() || p.join("mav0").exists()
}

fn read_terms(file: &Path, p: &Path) -> Result<Option<Reference>, CheckError> {
    let text = std::fs::read_to_string(file).map_err(|e| CheckError::Against {
        path: p.to_path_buf(),
        what: format!("{}: {e}", file.display()),
    })?;
    // its curves beside it, under the same prefix
    let curves = file
        .file_name()
        .map(|n| {
            n.to_string_lossy()
                .replace(terms::TERMS_FILE, terms::CURVES_FILE)
        })
        .and_then(|n| std::fs::read_to_string(file.with_file_name(n)).ok());
    Reference::from_terms_csv(
        &text,
        curves.as_deref(),
        &format!("the analysis in {}", p.display()),
    )
    .map(Some)
    .map_err(|what| CheckError::Against {
        path: p.to_path_buf(),
        what: format!("{}: {what}", file.display()),
    })
}

/// A judgement of one value.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Nothing wrong: what the value is.
    Ok(String),
    /// Something wrong: a short name of the mistake, and what it is and does.
    Finding(&'static str, String),
}

/// One line of the output: the file, the key, the value as written, the verdict.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// The file.
    pub file: String,
    /// The key (its path in the file).
    pub key: String,
    /// The value as written.
    pub raw: String,
    /// The judgement.
    pub verdict: Verdict,
}

impl std::fmt::Display for Line {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let head = if self.raw.is_empty() {
            format!("{}: {}", self.file, self.key)
        } else {
            format!("{}: {} = {}", self.file, self.key, self.raw)
        };
        match &self.verdict {
            Verdict::Ok(t) => write!(f, "{head}: ok: {t}"),
            Verdict::Finding(what, t) => write!(f, "{head}: finding ({what}): {t}"),
        }
    }
}

/// A number for the text: four significant digits.
fn n(x: f64) -> String {
    format!("{x:.3e}")
}

/// The ratio r as "×10.2" (or "×0.31").
fn times(r: f64) -> String {
    if r >= 10.0 {
        format!("x{r:.1}")
    } else {
        format!("x{r:.2}")
    }
}

fn near(a: f64, b: f64, factor: f64) -> bool {
    a > 0.0 && b > 0.0 && (a / b).ln().abs() <= factor.ln()
}

/// What one key's value is and what is wrong with it.
struct Judge<'a> {
    consumer: &'a Consumer,
    form: Form,
    key: &'a Key,
    rate: Option<f64>,
    measured: Option<Measured>,
    floors: &'a [f64],
    what: &'a str,
}

impl Judge<'_> {
    fn judge(&self, v: f64) -> Verdict {
        let k = self.key;
        let q = k.quantity;
        let c = self.consumer;
        if !v.is_finite() {
            return Verdict::Finding(
                "not a number",
                format!(
                    "{} would run with {v}: its {} is undefined",
                    c.name,
                    q.label()
                ),
            );
        }
        if v <= 0.0 {
            return Verdict::Finding(
                "not positive",
                format!(
                    "a noise figure is positive; {v} switches the {} off in {}",
                    q.label(),
                    c.name
                ),
            );
        }
        let Some(x) = self.form.to_continuous(v, self.rate) else {
            return Verdict::Ok(format!(
                "{} takes the {} per IMU sample ({}*sqrt(rate)); the rate is not known here, so its continuous value is not either (give --rate HZ or --against)",
                c.name,
                q.label(),
                if q.is_walk() { "K" } else { "N" }
            ));
        };
        let meaning = format!(
            "{} reads it as {}; continuous {} = {} {} ({})",
            c.name,
            self.form.formula(q.is_walk()),
            if q.is_walk() { "K" } else { "N" },
            n(x),
            q.unit(),
            datasheet::describe(q, x)
        );
        let range = k
            .range
            .filter(|(lo, hi)| v < *lo || v > *hi)
            .map(|(lo, hi)| format!("; outside the {lo} .. {hi} {} {} documents: its ground station may refuse or clamp it", k.unit, c.name))
            .unwrap_or_default();
        match self.measured {
            Some(m) => self.against(v, x, m, &meaning, &range),
            None => self.alone(x, &meaning, &range),
        }
    }

    /// Without a measurement: what the value means, and whether any IMU has it.
    fn alone(&self, x: f64, meaning: &str, range: &str) -> Verdict {
        let q = self.key.quantity;
        let (lo, hi) = PLAUSIBLE[q.index()];
        if (lo..=hi).contains(&x) {
            return Verdict::Ok(format!("{meaning}{range}"));
        }
        let mut hints = Vec::new();
        let ok = |y: f64| (lo..=hi).contains(&y);
        if ok(x.sqrt()) {
            hints.push(format!(
                "a variance? its square root {} is a {}",
                n(x.sqrt()),
                q.label()
            ));
        }
        if let Some(f) = self.rate
            && self.form == Form::Continuous
            && !q.is_walk()
            && ok(x / f.sqrt())
        {
            hints.push(format!(
                "a per-sample value at {f} Hz? divided by sqrt({f}) it is {}",
                n(x / f.sqrt())
            ));
        }
        let (unit_scale, unit_name) = match q.sensor() {
            bag2mat::Sensor::Gyro => (std::f64::consts::PI / 180.0, "degrees"),
            bag2mat::Sensor::Acc => (datasheet::G0, "g"),
        };
        if ok(x * unit_scale) {
            hints.push(format!(
                "in {unit_name}? converted it is {}",
                n(x * unit_scale)
            ));
        }
        Verdict::Finding(
            "no IMU has it",
            format!(
                "{meaning}, outside {} .. {} {} (a navigation-grade part to the noisiest MEMS inflated fifty-fold){}",
                n(lo),
                n(hi),
                q.unit(),
                if hints.is_empty() {
                    String::new()
                } else {
                    format!(": {}", hints.join("; "))
                }
            ),
        )
    }

    /// Against a measurement `m`: the ratio, the mistake it reveals, what it does.
    fn against(&self, v: f64, x: f64, m: Measured, meaning: &str, range: &str) -> Verdict {
        let q = self.key.quantity;
        let c = self.consumer;
        let r = x / m.value;
        let measured = if m.bound {
            format!(
                "{} measured a 95 % upper bound {} (not resolved)",
                self.what,
                n(m.hi)
            )
        } else {
            format!(
                "{} measured {} [95 %: {}, {}]",
                self.what,
                n(m.value),
                n(m.lo),
                n(m.hi)
            )
        };
        let base = format!("{meaning}; {measured}");
        if !m.bound && near(x, m.value, AGREE_FACTOR) {
            return Verdict::Ok(format!("{base}: {}{range}", times(r)));
        }
        if m.bound && near(x, m.hi, MISTAKE_FACTOR) {
            return Verdict::Ok(format!("{base}: at the bound{range}"));
        }
        // imu_utils' *_w pasted where a random walk belongs: the record's Allan floor
        let on_floor = |y: f64| {
            self.floors
                .iter()
                .find(|f| near(y, **f, MISTAKE_FACTOR))
                .filter(|_| q.is_walk())
        };
        let floor = on_floor(v).or_else(|| on_floor(x));
        // Where the record bounds K without resolving it, the bound and the Allan floor are
        // of one size (a random walk's bound is the floor times √(3/τ) near the floor's τ):
        // a continuous value inside the bound is what the record allows, whatever its origin,
        // and the floor only a caution. A consumer that converts (VINS' per-sample value,
        // a filter step, a covariance) tells them apart: there the floor itself as the raw
        // value is the pasted figure.
        let converts = !near(v, x, MISTAKE_FACTOR);
        if m.bound && x <= m.hi && !(converts && on_floor(v).is_some()) {
            let caution = floor
                .map(|f| {
                    format!(
                        " (it is also near the record's Allan floor {} {}: if it was copied from imu_utils' gyr_w/acc_w, that is a bias instability, not a random walk, though the record allows it)",
                        n(*f),
                        q.sensor().unit()
                    )
                })
                .unwrap_or_default();
            return Verdict::Ok(format!("{base}: within the bound{caution}{range}"));
        }
        if let Some(f) = floor {
            return Verdict::Finding(
                "bias instability",
                format!(
                    "{base}: the value is the record's bias-instability floor ({} {}: the lowest Allan deviation, or 0.664 B; imu_utils' gyr_w/acc_w is that floor), not a random walk: {} the random walk it stands for",
                    n(*f),
                    q.sensor().unit(),
                    times(r)
                ),
            );
        }
        if m.bound && x <= m.hi * AGREE_FACTOR {
            return Verdict::Ok(format!("{base}: within the bound{range}"));
        }
        let e = self
            .form
            .from_continuous(m.value, self.rate)
            .unwrap_or(f64::NAN);
        // the telltale mistakes, each a fixed multiple of the measured value
        if let Some(f) = self.rate.filter(|f| *f > 9.0) {
            let s = f.sqrt();
            match self.form {
                Form::Continuous | Form::Covariance
                    if !q.is_walk() && near(r, s, MISTAKE_FACTOR) =>
                {
                    return Verdict::Finding(
                        "discrete value",
                        format!(
                            "{base}: {} = sqrt({f}): a per-sample standard deviation at {f} Hz where {} wants the continuous density; divide by sqrt({f}): {}. As it is, {} weighs the IMU {:.1}x less than the data support",
                            times(r),
                            c.name,
                            n(x / s),
                            c.name,
                            s
                        ),
                    );
                }
                Form::Continuous | Form::Covariance
                    if q.is_walk() && near(r, 1.0 / s, MISTAKE_FACTOR) =>
                {
                    return Verdict::Finding(
                        "discrete value",
                        format!(
                            "{base}: {} = 1/sqrt({f}): the bias step per sample (K*sqrt(dt)) where {} wants the continuous random walk; multiply by sqrt({f}): {}",
                            times(r),
                            c.name,
                            n(x * s)
                        ),
                    );
                }
                Form::PerSample if near(r, 1.0 / s, MISTAKE_FACTOR) => {
                    return Verdict::Finding(
                        "continuous value",
                        format!(
                            "{base}: {} = 1/sqrt({f}): the continuous value where {} wants the per-sample standard deviation at {f} Hz; multiply by sqrt({f}): {}. As it is, {} trusts the IMU {:.1}x more than the data support",
                            times(r),
                            c.name,
                            n(v * s),
                            c.name,
                            s
                        ),
                    );
                }
                Form::PerFilterStep { dt } if near(r, dt.sqrt(), MISTAKE_FACTOR) => {
                    return Verdict::Finding(
                        "continuous value",
                        format!(
                            "{base}: {}: the continuous value where {} wants the standard deviation per {} s step; divide by sqrt({}): {}",
                            times(r),
                            c.name,
                            dt,
                            dt,
                            n(v / dt.sqrt())
                        ),
                    );
                }
                Form::PerFilterStep { dt }
                    if !q.is_walk() && near(r, (f * dt).sqrt(), MISTAKE_FACTOR) =>
                {
                    return Verdict::Finding(
                        "per-sample value",
                        format!(
                            "{base}: {}: the standard deviation per IMU sample at {f} Hz where {} wants it per {} s filter step; multiply by sqrt({} / {f}): {}",
                            times(r),
                            c.name,
                            dt,
                            1.0 / dt,
                            n(v * (1.0 / (f * dt)).sqrt())
                        ),
                    );
                }
                _ => {}
            }
        }
        // a square and its root differ by the value itself: told apart from a plain
        // deflation or inflation only where that is at least tenfold
        if self.form == Form::Covariance
            && e < SQUARE_APART * SQUARE_APART
            && near(v, e.sqrt(), MISTAKE_FACTOR)
        {
            return Verdict::Finding(
                "standard deviation",
                format!(
                    "{base}: the standard deviation where {} wants the covariance (its square): {}",
                    c.name,
                    n(v * v)
                ),
            );
        }
        if self.form != Form::Covariance
            && e < SQUARE_APART
            && near(v, e * e, MISTAKE_FACTOR * MISTAKE_FACTOR)
        {
            return Verdict::Finding(
                "variance",
                format!(
                    "{base}: the square of the value {} wants, a variance where it wants a standard deviation: take its square root, {}",
                    c.name,
                    n(v.sqrt())
                ),
            );
        }
        if m.bound || r > 1.0 {
            Verdict::Finding(
                "inflated",
                format!(
                    "{base}: {}{}: {} weighs the IMU {:.1}x less (its covariance {:.0}x) than the data support: a safety margin for vibration, temperature and unmodelled errors (Kalibr's wiki advises x10 on static data); fine if meant{range}",
                    times(r),
                    if m.bound { " of the bound" } else { "" },
                    c.name,
                    r,
                    r * r
                ),
            )
        } else {
            Verdict::Finding(
                "deflated",
                format!(
                    "{base}: {}: {} trusts the IMU {:.1}x more than the data support: overconfident, it will reject good camera or GNSS updates and may diverge{range}",
                    times(r),
                    c.name,
                    1.0 / r
                ),
            )
        }
    }
}

/// The rate a consumer's file states and what is wrong with it.
fn judge_rate(c: &Consumer, e: &Entry, record: Option<(f64, &str)>) -> Verdict {
    let Ok(v) = e.value else {
        return Verdict::Finding("not a number", e.value.clone().err().unwrap_or_default());
    };
    if !(PLAUSIBLE_RATE.0..=PLAUSIBLE_RATE.1).contains(&v) {
        return Verdict::Finding(
            "no IMU has it",
            format!(
                "{v} Hz: IMUs sample at {} to {} Hz",
                PLAUSIBLE_RATE.0, PLAUSIBLE_RATE.1
            ),
        );
    }
    if c.id == ConsumerId::OrbSlam3 && (v.fract() != 0.0 || e.raw.contains(['.', 'e', 'E'])) {
        return Verdict::Finding(
            "not an integer",
            format!(
                "ORB-SLAM3's legacy settings reader takes IMU.Frequency only as an integer (node.isInt()); write {}",
                v.round()
            ),
        );
    }
    match record {
        Some((r, what)) if (v / r - 1.0).abs() > RATE_REL_TOL => Verdict::Finding(
            "rate",
            format!(
                "{} discretises with {v} Hz, {what} {r} Hz: every per-sample sigma it derives is off by sqrt({v}/{r}) = {:.3}",
                c.name,
                (v / r).sqrt()
            ),
        ),
        Some((r, what)) => Verdict::Ok(format!("{v} Hz; {what} {r} Hz")),
        None => Verdict::Ok(format!("{v} Hz, the rate {} discretises with", c.name)),
    }
}

/// The lines of one file.
fn check_file(
    path: &Path,
    text: &str,
    reference: Option<&Reference>,
    given_rate: Option<f64>,
) -> Vec<Line> {
    let name = path.display().to_string();
    let file = read::read(&name, text);
    let line = |key: &str, raw: &str, verdict: Verdict| Line {
        file: name.clone(),
        key: key.to_string(),
        raw: raw.to_string(),
        verdict,
    };
    let Some(kind) = &file.kind else {
        return vec![line(
            "(file)",
            "",
            Verdict::Finding(
                "unknown",
                "no IMU noise key of a consumer this tool knows (Kalibr, OpenVINS, VINS, ORB-SLAM3, Basalt, PX4 EKF2, ArduPilot EKF3, GTSAM, imu_utils)".into(),
            ),
        )];
    };
    let record_rate = reference
        .and_then(|r| r.rate.map(|x| (x, "the record is")))
        .or(given_rate.map(|x| (x, "--rate says")));
    let mut out = Vec::new();
    match kind {
        Kind::Consumer(id) => {
            let c = consumer(*id);
            // the blocks the keys are in (OpenVINS' and Kalibr's imu0/, imu1/ …; Basalt's
            // value0/): each is checked
            let mut prefixes: Vec<String> = Vec::new();
            for e in &file.entries {
                for k in &c.keys {
                    if let Some(p) = e
                        .path
                        .strip_suffix(k.name)
                        .filter(|p| p.is_empty() || p.ends_with('/'))
                        .map(str::to_string)
                        && !prefixes.contains(&p)
                    {
                        prefixes.push(p);
                    }
                }
            }
            if prefixes.is_empty() {
                prefixes.push(String::new());
            }
            for prefix in prefixes {
                let rate_entry = c.rate_key.and_then(|k| file.get(&format!("{prefix}{k}")));
                // the rate the consumer uses: its own key, else the record's
                let rate = rate_entry
                    .and_then(|e| e.value.as_ref().ok().copied())
                    .filter(|r| *r > 0.0)
                    .or(record_rate.map(|r| r.0));
                // PX4's prediction step, when the file sets it
                let mut form = c.form;
                if *id == ConsumerId::Px4
                    && let Some(Ok(us)) = file.get("EKF2_PREDICT_US").map(|e| e.value.clone())
                    && us > 0.0
                {
                    form = Form::PerFilterStep { dt: us * 1e-6 };
                    out.push(line(
                        "EKF2_PREDICT_US",
                        &file
                            .get("EKF2_PREDICT_US")
                            .map_or(String::new(), |e| e.raw.clone()),
                        Verdict::Ok(format!(
                            "the EKF steps every {} s: the values are per step of that",
                            us * 1e-6
                        )),
                    ));
                }
                for k in &c.keys {
                    let q = k.quantity;
                    let judge = |axis: Option<usize>| Judge {
                        consumer: c,
                        form,
                        key: k,
                        rate,
                        measured: reference.and_then(|r| match axis {
                            Some(a) => r.axes[q.index()][a],
                            None => r.values[q.index()],
                        }),
                        floors: reference.map_or(&[][..], |r| {
                            &r.floors[usize::from(q.sensor() == bag2mat::Sensor::Gyro)][..]
                        }),
                        what: reference.map_or("", |r| r.what.as_str()),
                    };
                    let path = format!("{prefix}{}", k.name);
                    if *id == ConsumerId::Basalt {
                        let mut any = false;
                        for a in 0..3 {
                            let p = format!("{path}[{a}]");
                            if let Some(e) = file.get(&p) {
                                any = true;
                                out.push(line(
                                    &p,
                                    &e.raw,
                                    entry_verdict(e, c, |v| judge(Some(a)).judge(v)),
                                ));
                            }
                        }
                        if !any {
                            out.push(line(&path, "", missing(c, k)));
                        }
                        continue;
                    }
                    match file.get(&path) {
                        Some(e) => out.push(line(
                            &path,
                            &e.raw,
                            entry_verdict(e, c, |v| judge(None).judge(v)),
                        )),
                        None => out.push(line(&path, "", missing(c, k))),
                    }
                }
                if let (Some(k), Some(e)) = (c.rate_key, rate_entry) {
                    out.push(line(
                        &format!("{prefix}{k}"),
                        &e.raw,
                        judge_rate(c, e, record_rate),
                    ));
                }
            }
        }
        Kind::ImuUtils { continuous } => out.extend(
            imu_utils(&file, *continuous, reference, record_rate)
                .into_iter()
                .map(|(k, raw, v)| line(&k, &raw, v)),
        ),
    }
    out
}

/// A key the consumer needs that the file lacks.
fn missing(c: &Consumer, k: &Key) -> Verdict {
    Verdict::Finding(
        "missing",
        format!("{} needs its {} here", c.name, k.quantity.label()),
    )
}

/// An entry's verdict: the reader's complaint, PyYAML's for Kalibr, else `judge`.
fn entry_verdict(e: &Entry, c: &Consumer, judge: impl Fn(f64) -> Verdict) -> Verdict {
    match &e.value {
        Err(why) => Verdict::Finding(
            "not a number",
            format!("{} will not read a number here: {why}", c.name),
        ),
        Ok(_) if c.id == ConsumerId::Kalibr && !read::yaml11_number(&e.raw) => Verdict::Finding(
            "a string to PyYAML",
            format!(
                "Kalibr loads imu.yaml with PyYAML (YAML 1.1), which reads {} as a string, not a number: write it with a '.' and a signed exponent ({})",
                e.raw,
                crate::yaml::yaml_sci(e.value.clone().unwrap_or(f64::NAN))
            ),
        ),
        Ok(v) => judge(*v),
    }
}

/// The lines of imu_utils' yaml: its `*_n` per sample at the record's rate, its `*_w` the
/// bias-instability floor (upstream's file); this project's continuous file as continuous N
/// and K.
fn imu_utils(
    file: &read::File,
    continuous: bool,
    reference: Option<&Reference>,
    record_rate: Option<(f64, &str)>,
) -> Vec<(String, String, Verdict)> {
    let mut out = Vec::new();
    let kalibr = consumer(ConsumerId::Kalibr);
    for (block, s, sensor) in [
        ("Gyr", "gyr", bag2mat::Sensor::Gyro),
        ("Acc", "acc", bag2mat::Sensor::Acc),
    ] {
        for walk in [false, true] {
            let q = Quantity::of(sensor, walk);
            let path = format!("{block}/avg-axis/{s}_{}", if walk { "w" } else { "n" });
            let Some(e) = file.get(&path) else { continue };
            let Ok(v) = e.value.clone() else {
                out.push((
                    path,
                    e.raw.clone(),
                    Verdict::Finding("not a number", e.value.clone().err().unwrap_or_default()),
                ));
                continue;
            };
            let key = kalibr.key(q);
            let judge = Judge {
                consumer: kalibr,
                form: Form::Continuous,
                key,
                rate: record_rate.map(|r| r.0),
                measured: reference.and_then(|r| r.values[q.index()]),
                floors: reference.map_or(&[][..], |r| {
                    &r.floors[usize::from(sensor == bag2mat::Sensor::Gyro)][..]
                }),
                what: reference.map_or("", |r| r.what.as_str()),
            };
            let verdict = match (continuous, walk, record_rate) {
                (true, _, _) => judge.judge(v),
                (false, false, Some((f, _))) => Verdict::Finding(
                    "discrete value",
                    format!(
                        "imu_utils writes the noise per sample at the record's rate (N*sqrt(rate)); where a continuous density belongs (Kalibr, OpenVINS, ORB-SLAM3, Basalt) use {} = {}/sqrt({f}): {}",
                        key.name,
                        e.raw,
                        match judge.judge(v / f.sqrt()) {
                            Verdict::Ok(t) => t,
                            Verdict::Finding(w, t) => format!("{w}: {t}"),
                        }
                    ),
                ),
                (false, false, None) => Verdict::Finding(
                    "discrete value",
                    "imu_utils writes the noise per sample at the record's rate (N*sqrt(rate)): divide by sqrt(rate) where a continuous density belongs (give --rate HZ for the value)".into(),
                ),
                (false, true, _) => Verdict::Finding(
                    "bias instability",
                    format!(
                        "imu_utils' {s}_w is the bias-instability floor of the Allan curve (in {}), not a random walk: no consumer's random-walk key takes it ({} measures K: its kalibr_imu_ieee952.yaml)",
                        sensor.unit(),
                        crate::run::TOOL
                    ),
                ),
            };
            out.push((path, e.raw.clone(), verdict));
        }
    }
    out
}

/// The whole command: every file's lines, the reference said first (on stderr).
pub fn run(args: &CheckArgs) -> Result<Vec<Line>, CheckError> {
    let reference = reference(args)?;
    let mut out = Vec::new();
    for p in &args.configs {
        let text = std::fs::read_to_string(p).map_err(|e| CheckError::Read {
            path: p.clone(),
            what: bag2mat::shared::output::describe(&e),
        })?;
        out.extend(check_file(p, &text, reference.as_ref(), args.rate));
    }
    Ok(out)
}

/// `allan_kalibr check`: the lines on stdout, a count on stderr; exit 0 with findings.
pub fn main(args: &CheckArgs) -> std::process::ExitCode {
    match run(args) {
        Ok(lines) => {
            let mut text = String::new();
            for l in &lines {
                let _ = writeln!(text, "{l}");
            }
            let findings = lines
                .iter()
                .filter(|l| matches!(l.verdict, Verdict::Finding(..)))
                .count();
            if let Err(e) = bag2mat::shared::cli::print(&text) {
                return bag2mat::shared::cli::fail(crate::run::TOOL, &e);
            }
            eprintln!(
                "check: {findings} finding(s) in {} value(s) of {} file(s)",
                lines.len(),
                args.configs.len()
            );
            std::process::ExitCode::SUCCESS
        }
        Err(e) => bag2mat::shared::cli::fail(crate::run::TOOL, &e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Kalibr's imu_chain (and OpenVINS') holds one block per IMU: each is checked.
    #[test]
    fn every_imu_of_a_chain_is_checked() {
        let text = "imu0:\n  accelerometer_noise_density: 2.0e-03\n  accelerometer_random_walk: 3.0e-05\n  gyroscope_noise_density: 1.7e-04\n  gyroscope_random_walk: 2.0e-06\n  update_rate: 200.0\nimu1:\n  accelerometer_noise_density: 2.0e-03\n  accelerometer_random_walk: 3.0e-05\n  gyroscope_noise_density: 57.0\n  gyroscope_random_walk: 2.0e-06\n  update_rate: 400.0\n";
        let lines = check_file(Path::new("chain.yaml"), text, None, None);
        assert_eq!(lines.len(), 10, "{lines:#?}");
        let bad: Vec<&Line> = lines
            .iter()
            .filter(|l| matches!(l.verdict, Verdict::Finding(..)))
            .collect();
        assert_eq!(bad.len(), 1, "{lines:#?}");
        assert_eq!(bad[0].key, "imu1/gyroscope_noise_density");
    }

    /// The telltale ratios against a measured reference, from the judge itself: √rate for a
    /// discrete value in a continuous key, 1/√rate for the reverse in VINS, the square.
    #[test]
    fn telltale_ratios_name_their_mistake() {
        let m = Measured {
            value: 1.0e-3,
            lo: 0.9e-3,
            hi: 1.1e-3,
            bound: false,
        };
        let judge = |id: ConsumerId, v: f64| {
            let c = consumer(id);
            Judge {
                consumer: c,
                form: c.form,
                key: c.key(Quantity::AccNoise),
                rate: Some(400.0),
                measured: Some(m),
                floors: &[],
                what: "the test",
            }
            .judge(v)
        };
        let name = |v: Verdict| match v {
            Verdict::Ok(_) => "ok",
            Verdict::Finding(w, _) => w,
        };
        assert_eq!(name(judge(ConsumerId::Kalibr, 1.0e-3)), "ok");
        assert_eq!(name(judge(ConsumerId::Kalibr, 20e-3)), "discrete value");
        assert_eq!(name(judge(ConsumerId::Kalibr, 1.0e-6)), "variance");
        assert_eq!(name(judge(ConsumerId::Kalibr, 5.0e-3)), "inflated");
        assert_eq!(name(judge(ConsumerId::Kalibr, 0.3e-3)), "deflated");
        assert_eq!(name(judge(ConsumerId::Vins, 1.0e-3)), "continuous value");
        assert_eq!(name(judge(ConsumerId::Vins, 20e-3)), "ok");
        assert_eq!(name(judge(ConsumerId::Px4, 1.0e-3)), "continuous value");
        assert_eq!(name(judge(ConsumerId::Px4, 20e-3)), "per-sample value");
        assert_eq!(name(judge(ConsumerId::Gtsam, 1.0e-3)), "standard deviation");
    }

    /// A random walk the record only bounds: a continuous value inside the bound is allowed
    /// even where it matches the Allan floor (the two are of one size); the floor as the raw
    /// value of a consumer that converts (VINS' per-sample `gyr_w`) is imu_utils' figure;
    /// above the bound the floor is named.
    #[test]
    fn a_floor_inside_a_random_walk_bound_is_named_only_where_it_can_be_told_apart() {
        let m = Measured {
            value: 1.3e-3,
            lo: 0.0,
            hi: 1.3e-3,
            bound: true,
        };
        let floors = [1.0e-3];
        let judge = |id: ConsumerId, v: f64, m: Measured| {
            let c = consumer(id);
            Judge {
                consumer: c,
                form: c.form,
                key: c.key(Quantity::GyroWalk),
                rate: Some(400.0),
                measured: Some(m),
                floors: &floors,
                what: "the test",
            }
            .judge(v)
        };
        let name = |v: Verdict| match v {
            Verdict::Ok(t) if t.contains("Allan floor") => "ok, cautioned",
            Verdict::Ok(_) => "ok",
            Verdict::Finding(w, _) => w,
        };
        assert_eq!(name(judge(ConsumerId::Kalibr, 0.9e-3, m)), "ok, cautioned");
        assert_eq!(name(judge(ConsumerId::Kalibr, 0.5e-3, m)), "ok");
        assert_eq!(name(judge(ConsumerId::Vins, 1.0e-3, m)), "bias instability");
        assert_eq!(name(judge(ConsumerId::Vins, 0.4e-3 * 20.0, m)), "ok");
        let low = Measured {
            value: 0.4e-3,
            hi: 0.4e-3,
            ..m
        };
        assert_eq!(
            name(judge(ConsumerId::Kalibr, 1.0e-3, low)),
            "bias instability"
        );
    }
}
