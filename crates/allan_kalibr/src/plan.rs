//! `allan_kalibr plan`: from an IMU's figures — N and K in Kalibr's units, or a datasheet's
//! ARW, VRW, noise density and bias instability — and its rate, how long a static record
//! must be for ±25 % and ±10 % at 95 % on each term, whether the bias instability B can be
//! resolved at all, and the parameters of every consumer ([`crate::consumers::CONSUMERS`]) from these
//! figures, marked "from a datasheet, not measured" (`-o DIR` writes the files).
//!
//! The record lengths are the analysis' own advice (`crate::ieee952::advisor`): the
//! analysis of a record whose Allan curve is exactly the figures' model is asked what it
//! would advise (`crate::ieee952::advisor::expected`), at the record length it advises
//! until the two agree — so a plan and the advice printed after a record of that sensor are
//! the same rule, not a second formula.
//!
//! A datasheet rarely gives a random walk K. Its bias instability, the minimum σ_min of the
//! Allan deviation ("in-run bias stability"), bounds it honestly: at every τ the curve is at
//! least the white noise's and the random walk's together, N²/τ + K²τ/3 ≥ 2NK/√3, so
//! K ≤ √3·σ_min²/(2N). The plan says K is at most that, never a guessed value; the record
//! for a K at its bound is a lower bound (a smaller K needs longer). Without a bias
//! instability nothing bounds K, and the plan says so.

use std::fmt::Write as _;
use std::path::PathBuf;

use crate::SensorValue;
use crate::consumers::{
    CONSUMERS, ConfigValues, Origin, Provenance, Quantity, RecordRate, datasheet, render,
};
use crate::ieee952::advisor::{self, TARGETS, duration_text};
use bag2mat::Sensor;

/// The shortest record the plan evaluates, s: shorter ones are scaled from it by the
/// advice's own 1/√T rule (a few thousand samples give the analysis its grid).
pub const MIN_EVAL_RECORD: f64 = 120.0;
/// The longest record the plan considers, s (30 days): beyond, a term is "not within a month".
pub const MAX_RECORD: f64 = 30.0 * 86_400.0;
/// The plan's record agrees with the advice at that record within this fraction.
pub const CONVERGED: f64 = 0.02;
/// Iterations at most of record → advice → record.
pub const MAX_ITER: usize = 12;

/// What the command line of `plan` says.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct PlanArgs {
    /// The IMU's output rate, Hz.
    #[arg(long, value_name = "HZ", value_parser = crate::front::rate_hz)]
    pub rate: f64,
    /// Gyro white-noise density, rad/s/sqrt(Hz) (Kalibr's gyroscope_noise_density).
    #[arg(long, value_name = "RAD_S_SQRT_HZ", value_parser = positive, group = "gyro_n")]
    pub gyro_noise_density: Option<f64>,
    /// Gyro angle random walk (datasheet), deg/sqrt(h).
    #[arg(long, value_name = "DEG_SQRT_H", value_parser = positive, group = "gyro_n")]
    pub gyro_arw: Option<f64>,
    /// Gyro noise density (datasheet), deg/s/sqrt(Hz).
    #[arg(long, value_name = "DEG_S_SQRT_HZ", value_parser = positive, group = "gyro_n")]
    pub gyro_noise_density_dps: Option<f64>,
    /// Gyro bias random walk, rad/s^2/sqrt(Hz) (Kalibr's gyroscope_random_walk).
    #[arg(long, value_name = "RAD_S2_SQRT_HZ", value_parser = positive)]
    pub gyro_random_walk: Option<f64>,
    /// Gyro bias instability (datasheet: the Allan deviation's minimum, "in-run bias
    /// stability"), deg/h.
    #[arg(long, value_name = "DEG_H", value_parser = positive)]
    pub gyro_bias_instability: Option<f64>,
    /// Accelerometer white-noise density, m/s^2/sqrt(Hz) (Kalibr's
    /// accelerometer_noise_density).
    #[arg(long, value_name = "M_S2_SQRT_HZ", value_parser = positive, group = "acc_n")]
    pub acc_noise_density: Option<f64>,
    /// Accelerometer velocity random walk (datasheet), m/s/sqrt(h).
    #[arg(long, value_name = "M_S_SQRT_H", value_parser = positive, group = "acc_n")]
    pub acc_vrw: Option<f64>,
    /// Accelerometer noise density (datasheet), ug/sqrt(Hz).
    #[arg(long, value_name = "UG_SQRT_HZ", value_parser = positive, group = "acc_n")]
    pub acc_noise_density_ug: Option<f64>,
    /// Accelerometer bias random walk, m/s^3/sqrt(Hz) (Kalibr's accelerometer_random_walk).
    #[arg(long, value_name = "M_S3_SQRT_HZ", value_parser = positive)]
    pub acc_random_walk: Option<f64>,
    /// Accelerometer bias instability (datasheet: the Allan deviation's minimum), mg.
    #[arg(long, value_name = "MG", value_parser = positive)]
    pub acc_bias_instability: Option<f64>,
    /// Also write every consumer's file from these figures into DIR (marked: from a
    /// datasheet, not measured).
    #[arg(short = 'o', long = "out-dir", value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
}

fn positive(s: &str) -> Result<f64, bag2mat::shared::cli::UsageError> {
    bag2mat::shared::cli::positive_f64(s)
}

/// The errors of `plan`.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// No noise density for either sensor.
    #[error(
        "nothing to plan: give a noise density of the gyro (--gyro-noise-density, --gyro-arw, --gyro-noise-density-dps) or of the accelerometer (--acc-noise-density, --acc-vrw, --acc-noise-density-ug)"
    )]
    NoFigures,
    /// A random walk or bias instability without the sensor's noise density.
    #[error("--{0}: the {1}'s plan needs its noise density too")]
    NeedsDensity(&'static str, &'static str),
    /// Writing the files failed.
    #[error(transparent)]
    Io(#[from] bag2mat::Error),
}

/// A sensor's random walk as the figures know it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Walk {
    /// Given.
    Given(f64),
    /// Not given; at most this (from the bias instability).
    Bound(f64),
    /// Not given and not bounded (no bias instability either).
    Unknown,
}

impl Walk {
    /// The value planned with (the bound for a bound).
    pub fn value(self) -> Option<f64> {
        match self {
            Walk::Given(k) | Walk::Bound(k) => Some(k),
            Walk::Unknown => None,
        }
    }
}

/// A record length for ±25 % and ±10 %, s, and whether they are lower bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Records {
    /// For ±25 % at 95 %.
    pub r25: f64,
    /// For ±10 % at 95 %.
    pub r10: f64,
    /// Lower bounds (a K at its upper bound).
    pub at_least: bool,
}

/// Whether and when B can be resolved.
#[derive(Clone, Debug, PartialEq)]
pub enum BiasPlan {
    /// No bias instability given.
    NotGiven,
    /// Resolvable: the records for ±25 % and ±10 %, and on what condition.
    Resolvable(Records, String),
    /// Not resolvable, and why.
    Not(String),
}

/// One sensor's plan.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorPlan {
    /// Which.
    pub sensor: Sensor,
    /// White-noise density N (continuous).
    pub n: f64,
    /// Random walk K.
    pub k: Walk,
    /// The datasheet's bias instability as the Allan floor σ_min, when given.
    pub floor: Option<f64>,
    /// Records for N.
    pub n_records: Option<Records>,
    /// Records for K (none when K is unknown, or not within [`MAX_RECORD`]).
    pub k_records: Option<Records>,
    /// B.
    pub b: BiasPlan,
}

/// Which of the advice's terms a record is planned for.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Term {
    N,
    K,
    B,
}

/// The record the analysis' advice asks for term `term` at target `target` (an index into
/// [`TARGETS`]) on a sensor of figures (n, b, k): record → the advice of the expected
/// analysis of that record → record, until they agree. `None`: not within [`MAX_RECORD`].
fn record_for(
    term: Term,
    target: usize,
    (n, b, k): (f64, f64, f64),
    rate: f64,
) -> Option<(f64, bool)> {
    let mut t = 3600.0f64;
    let mut last = None;
    for _ in 0..MAX_ITER {
        let (_, advice) = advisor::expected(n, b, k, rate, t);
        let a = advice?;
        let ta = match term {
            Term::N => a.n,
            Term::K => a.k,
            Term::B => a.b,
        };
        let want = if target == 0 {
            ta.record_10
        } else {
            ta.record_25
        };
        if !want.is_finite() || ta.at_least {
            // not resolved at this record (the advice then says "at least"): a longer one
            if t >= MAX_RECORD {
                return None;
            }
            let longer = if want.is_finite() {
                want.max(2.0 * t)
            } else {
                4.0 * t
            };
            t = longer.min(MAX_RECORD);
            continue;
        }
        last = Some((want, false));
        let next = want.clamp(MIN_EVAL_RECORD, MAX_RECORD);
        if (next / t - 1.0).abs() < CONVERGED || (want < MIN_EVAL_RECORD && t <= MIN_EVAL_RECORD) {
            break;
        }
        t = next;
    }
    last.filter(|(w, _)| *w <= MAX_RECORD)
}

fn records(term: Term, figs: (f64, f64, f64), rate: f64) -> Option<Records> {
    let (r10, a10) = record_for(term, 0, figs, rate)?;
    let (r25, a25) = record_for(term, 1, figs, rate)?;
    Some(Records {
        r25,
        r10,
        at_least: a10 || a25,
    })
}

/// The plan of one sensor of noise density `n`, random walk `k` (given, or bounded by the
/// bias instability `floor`), at `rate` Hz.
pub fn plan_sensor(
    sensor: Sensor,
    n: f64,
    k: Option<f64>,
    floor: Option<f64>,
    rate: f64,
) -> SensorPlan {
    let walk = match (k, floor) {
        (Some(k), _) => Walk::Given(k),
        (None, Some(f)) => Walk::Bound(3f64.sqrt() * f * f / (2.0 * n)),
        (None, None) => Walk::Unknown,
    };
    let b = floor.map_or(0.0, |f| f / crate::B_FLOOR_FACTOR);
    let figs = (n, b, walk.value().unwrap_or(0.0));
    let n_records = records(Term::N, figs, rate);
    let k_records = walk
        .value()
        .and_then(|_| records(Term::K, figs, rate))
        .map(|r| Records {
            at_least: r.at_least || matches!(walk, Walk::Bound(_)),
            ..r
        });
    // B: with the random walk given, as it is; with K only bounded or unknown, at best (no
    // random walk), for a K at its bound hides any floor the bound comes from
    let b_plan = match floor {
        None => BiasPlan::NotGiven,
        Some(f) => {
            let k_for_b = match walk {
                Walk::Given(k) => k,
                _ => 0.0,
            };
            let figs_b = (n, b, k_for_b);
            let (a, _) = advisor::expected(n, b, k_for_b, rate, MAX_RECORD);
            let caveat = match walk {
                Walk::Given(_) => "",
                _ => {
                    " (if the random walk is far below its bound; with K at its bound the floor never shows)"
                }
            };
            if a.terms.b.verdict == crate::Verdict::Resolved {
                match records(Term::B, figs_b, rate) {
                    Some(r) => BiasPlan::Resolvable(
                        Records {
                            at_least: !matches!(walk, Walk::Given(_)),
                            ..r
                        },
                        caveat.to_string(),
                    ),
                    None => BiasPlan::Not("not within a month of record".into()),
                }
            } else {
                BiasPlan::Not(format!(
                    "its floor {:.3e} {} never dominates the curve: the white noise and the random walk meet at {:.3e} {}, so no record shows the floor on its own",
                    f,
                    sensor.unit(),
                    (2.0 * n * k_for_b / 3f64.sqrt()).sqrt(),
                    sensor.unit()
                ))
            }
        }
    };
    SensorPlan {
        sensor,
        n,
        k: walk,
        floor,
        n_records,
        k_records,
        b: b_plan,
    }
}

/// A sensor's figures from the command line: the sensor, N, K, the Allan floor, and the
/// flags they came from.
type Figures = (Sensor, f64, Option<f64>, Option<f64>, String);

/// The figures of `args` per sensor.
fn figures(args: &PlanArgs) -> Result<Vec<Figures>, PlanError> {
    let mut out = Vec::new();
    let gyro_n = args
        .gyro_noise_density
        .map(|x| (x, format!("--gyro-noise-density {x}")))
        .or(args.gyro_arw.map(|x| {
            (
                datasheet::from_arw(x),
                format!("--gyro-arw {x} deg/sqrt(h)"),
            )
        }))
        .or(args.gyro_noise_density_dps.map(|x| {
            (
                datasheet::from_dps_density(x),
                format!("--gyro-noise-density-dps {x} deg/s/sqrt(Hz)"),
            )
        }));
    let acc_n = args
        .acc_noise_density
        .map(|x| (x, format!("--acc-noise-density {x}")))
        .or(args
            .acc_vrw
            .map(|x| (datasheet::from_vrw(x), format!("--acc-vrw {x} m/s/sqrt(h)"))))
        .or(args.acc_noise_density_ug.map(|x| {
            (
                datasheet::from_ug_density(x),
                format!("--acc-noise-density-ug {x} ug/sqrt(Hz)"),
            )
        }));
    for (sensor, n, k, b, kname, bname) in [
        (
            Sensor::Gyro,
            gyro_n,
            args.gyro_random_walk,
            args.gyro_bias_instability.map(|x| {
                (
                    datasheet::from_deg_per_h(x),
                    format!("--gyro-bias-instability {x} deg/h"),
                )
            }),
            "gyro-random-walk",
            "gyro-bias-instability",
        ),
        (
            Sensor::Acc,
            acc_n,
            args.acc_random_walk,
            args.acc_bias_instability.map(|x| {
                (
                    datasheet::from_mg(x),
                    format!("--acc-bias-instability {x} mg"),
                )
            }),
            "acc-random-walk",
            "acc-bias-instability",
        ),
    ] {
        match n {
            Some((n, nwhat)) => {
                let mut what = vec![nwhat];
                what.extend(k.map(|k| format!("--{kname} {k}")));
                what.extend(b.as_ref().map(|b| b.1.clone()));
                out.push((sensor, n, k, b.map(|b| b.0), what.join(", ")));
            }
            None if k.is_some() => return Err(PlanError::NeedsDensity(kname, sensor.name())),
            None if b.is_some() => return Err(PlanError::NeedsDensity(bname, sensor.name())),
            None => {}
        }
    }
    if out.is_empty() {
        return Err(PlanError::NoFigures);
    }
    Ok(out)
}

fn records_text(r: Option<&Records>) -> String {
    match r {
        Some(r) => format!(
            "{}{} / {}",
            if r.at_least { "at least " } else { "" },
            duration_text(r.r25),
            duration_text(r.r10)
        ),
        None => "not within a month of record".into(),
    }
}

/// The plan as printed, and the figures the consumers' files get.
pub fn plan(args: &PlanArgs) -> Result<(String, Vec<SensorPlan>, ConfigValues), PlanError> {
    let figs = figures(args)?;
    let plans: Vec<(SensorPlan, String)> = figs
        .into_iter()
        .map(|(s, n, k, f, what)| (plan_sensor(s, n, k, f, args.rate), what))
        .collect();
    let mut t = String::new();
    let _ = writeln!(
        t,
        "=> plan of a static record from figures (FROM A DATASHEET, NOT MEASURED), {} Hz; record lengths for +-{:.0} % / +-{:.0} % at 95 %, by the analysis' own advice rule",
        args.rate,
        100.0 * TARGETS[1],
        100.0 * TARGETS[0]
    );
    let mut values = [None; 4];
    for (p, what) in &plans {
        let qn = Quantity::of(p.sensor, false);
        let qk = Quantity::of(p.sensor, true);
        let _ = writeln!(t, "{} ({what}):", p.sensor.name());
        let _ = writeln!(
            t,
            "  N = {:.4e} {} ({})",
            p.n,
            qn.unit(),
            datasheet::describe(qn, p.n)
        );
        match p.k {
            Walk::Given(k) => {
                let _ = writeln!(
                    t,
                    "  K = {k:.4e} {} ({})",
                    qk.unit(),
                    datasheet::describe(qk, k)
                );
            }
            Walk::Bound(k) => {
                let _ = writeln!(
                    t,
                    "  K: not given; at most {k:.3e} {} (sqrt(3)*floor^2/(2N): the Allan deviation's minimum bounds the random walk; the datasheet's bias instability taken as that minimum, as datasheets quote it — if yours quotes IEEE's B, the floor is 0.664 B and the bound 0.44x this)",
                    qk.unit()
                );
            }
            Walk::Unknown => {
                let _ = writeln!(
                    t,
                    "  K: not given, and nothing bounds it (no bias instability given): measure it (a record of several hours)"
                );
            }
        }
        if let Some(f) = p.floor {
            let _ = writeln!(
                t,
                "  B = {:.4e} {} (IEEE 952's coefficient: the datasheet's bias instability {:.4e} {} as the Allan floor, over 0.664)",
                f / crate::B_FLOOR_FACTOR,
                p.sensor.unit(),
                f,
                p.sensor.unit()
            );
        }
        let _ = writeln!(t, "  record for N: {}", records_text(p.n_records.as_ref()));
        match (p.k, &p.k_records) {
            (Walk::Unknown, _) => {
                let _ = writeln!(t, "  record for K: unknown (no K, no bound)");
            }
            (Walk::Bound(_), r) => {
                let _ = writeln!(
                    t,
                    "  record for K: {} (for a K at its bound; a smaller K needs longer)",
                    records_text(r.as_ref())
                );
            }
            (Walk::Given(_), r) => {
                let _ = writeln!(t, "  record for K: {}", records_text(r.as_ref()));
            }
        }
        match &p.b {
            BiasPlan::NotGiven => {}
            BiasPlan::Resolvable(r, caveat) => {
                let _ = writeln!(t, "  record for B: {}{caveat}", records_text(Some(r)));
            }
            BiasPlan::Not(why) => {
                let _ = writeln!(t, "  B cannot be resolved: {why}");
            }
        }
        values[qn.index()] = Some(SensorValue {
            value: p.n,
            upper_bound: false,
            region: false,
        });
        values[qk.index()] = p.k.value().map(|k| SensorValue {
            value: k,
            upper_bound: matches!(p.k, Walk::Bound(_)),
            region: false,
        });
    }
    let mut cv = ConfigValues::plain(values.map(|v| v.map(|s| s.value)), Origin::Datasheet);
    cv.values = values;
    for (q, v) in Quantity::ALL.into_iter().zip(values) {
        if let (Some(v), Some(axes)) = (v, cv.axes[q.index()].as_mut()) {
            for a in axes.iter_mut() {
                a.upper_bound = v.upper_bound;
            }
        }
    }
    if plans.iter().any(|(p, _)| matches!(p.k, Walk::Bound(_))) {
        cv.comments.push(
            "A random walk marked as an upper bound comes from the datasheet's bias instability (K <= sqrt(3)*floor^2/(2N)), not from a datasheet figure.".into(),
        );
    }
    let _ = writeln!(
        t,
        "=> parameters from these figures (FROM A DATASHEET, NOT MEASURED):"
    );
    for c in &CONSUMERS {
        let mut keys = Vec::new();
        for k in &c.keys {
            let v = values[k.quantity.index()].and_then(|v| {
                c.form
                    .from_continuous(v.value, Some(args.rate))
                    .map(|x| (x, v.upper_bound))
            });
            if let Some((x, bound)) = v {
                keys.push(format!(
                    "{} {x:.4e}{}",
                    k.name,
                    if bound { " (upper bound)" } else { "" }
                ));
            }
        }
        let _ = writeln!(t, "  {}: {}", c.name, keys.join(", "));
    }
    Ok((t, plans.into_iter().map(|(p, _)| p).collect(), cv))
}

/// `allan_kalibr plan`: the plan on stdout; with `-o DIR` every consumer's file.
pub fn main(args: &PlanArgs) -> std::process::ExitCode {
    let tool = crate::run::TOOL;
    let (text, _, values) = match plan(args) {
        Ok(p) => p,
        Err(e) => return bag2mat::shared::cli::fail(tool, &e),
    };
    if let Some(dir) = &args.out_dir {
        let outputs = bag2mat::shared::output::Outputs::staged();
        let prov = Provenance::new(
            &format!("{tool} plan"),
            "datasheet figures (allan_kalibr plan)",
            RecordRate::Given(args.rate),
        );
        let written = (|| -> Result<Vec<PathBuf>, bag2mat::Error> {
            outputs.ensure_dir(dir)?;
            let mut w = Vec::new();
            for c in &CONSUMERS {
                let p = dir.join(c.file);
                let text = render(c.id, &values, &prov, crate::front::DEFAULT_TOPIC);
                outputs.write_atomic(&p, |f| f.write_all(text.as_bytes()))?;
                w.push(p);
            }
            Ok(w)
        })();
        let written = match written.and_then(|w| outputs.commit().map(|()| w)) {
            Ok(w) => w,
            Err(e) => return bag2mat::shared::cli::fail(tool, &e),
        };
        eprintln!(
            "wrote {} files to {}/ (from a datasheet, not measured)",
            written.len(),
            dir.display()
        );
    }
    match bag2mat::shared::cli::print(&text) {
        Ok(_) => std::process::ExitCode::SUCCESS,
        Err(e) => bag2mat::shared::cli::fail(tool, &e),
    }
}
