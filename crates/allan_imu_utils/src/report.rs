//! Upstream's terminal output and curve files (docs/upstream/imu_utils.md §5.1–5.2).
//!
//! The stdout text is rebuilt line by line in upstream's order and iostream formats (`%g`,
//! precision 6), including its typos and spacing: the double space after the axis name,
//! the trailing space in `dt ` and in the fit headers, `Gyro X` vs `Gyro y`, the mislabeled
//! rad/h line (quirk 5) and the `bias … degree/s` line with 57.3 (quirk 4).
//! The 16 `data_<name>_*.txt` files hold one `%.10g` number per line; all of them use the
//! x-axis taus and the acc `sim` curves are evaluated at all taus (quirk 11).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::analysis::{AXIS_NAMES, Analysis};
use crate::error::Error;
use crate::fit::{SECONDS_PER_HOUR, find_min_index};
use bag2mat::shared::cfmt::{g, g6};
use bag2mat::shared::output::Outputs;

/// Upstream's fit headers (capital X only; trailing space).
const FIT_HEADERS: [&str; 6] = [
    "Gyro X ", "Gyro y ", "Gyro z ", "acc X ", "acc y ", "acc z ",
];

/// Upstream's numData warning threshold and short-time threshold (minutes), quirk 14.
const TOO_FEW_NUMBER: usize = 10_000;
const TOO_SHORT_MIN: f64 = 10.0;

fn calc_block(out: &mut String, a: &crate::analysis::AxisAllan) {
    let name = a.name;
    let _ = writeln!(out, "{name}  numData {}", a.n);
    if a.n < TOO_FEW_NUMBER {
        let _ = writeln!(out, "{name}  Too few number");
    }
    let dt = a.end_t - a.start_t;
    let _ = writeln!(out, "{name}  start_t {}", g6(a.start_t));
    let _ = writeln!(out, "{name}  end_t {}", g6(a.end_t));
    let _ = writeln!(out, "{name} dt ");
    let _ = writeln!(out, "-------------{} s", g6(dt));
    let _ = writeln!(out, "-------------{} min", g6(dt / 60.0));
    let _ = writeln!(out, "-------------{} h", g6(dt / 3600.0));
    if dt / 60.0 < TOO_SHORT_MIN {
        let _ = writeln!(out, "{name}  Too short time!!!!");
    }
    let _ = writeln!(out, "{name}  freq {}", g6(a.freq));
    let _ = writeln!(out, "{name}  period {}", g6(a.period));
}

/// The whole stdout of an upstream run, from the `num of Cluster` lines on.
///
/// A sensor the topic does not carry ([`Analysis::absent`]) gets one line saying so instead
/// of its lines.
pub fn stdout_text(an: &Analysis) -> String {
    let mut out = String::new();
    for (i, name) in AXIS_NAMES.iter().enumerate() {
        if an.present(i) {
            let _ = writeln!(out, "{name}  num of Cluster {}", an.max_cluster);
        }
    }
    out.push_str("wait for imu data.\n");
    if let Some(s) = an.absent {
        let _ = writeln!(out, "{}: absent from this topic (not analysed)", s.name());
    }
    if an.present(0) {
        for i in 0..3 {
            calc_block(&mut out, &an.axes[i]);
        }
        for i in 0..3 {
            gyro_fit_block(&mut out, an, i, true);
        }
    }
    out.push_str("==============================================\n");
    out.push_str("==============================================\n");
    if an.present(3) {
        for i in 3..6 {
            calc_block(&mut out, &an.axes[i]);
        }
        for i in 3..6 {
            acc_fit_block(&mut out, an, i);
        }
    }
    out
}

/// Upstream's fit block of gyro axis `i` (header, `C` line, the four value lines and, when
/// the samples were at hand, the `bias` line).
fn gyro_fit_block(out: &mut String, an: &Analysis, i: usize, bias: bool) {
    let fit = &an.fits[i];
    let a = &an.axes[i];
    let _ = writeln!(out, "{}", FIT_HEADERS[i]);
    let _ = writeln!(out, "{}", crate::fit::init::c_line(&fit.start));
    let _ = writeln!(
        out,
        " Bias Instability {} rad/s",
        g6(fit.gyro_b_line_value())
    );
    let at = a.taus[find_min_index(&fit.sim(&a.taus))];
    let _ = writeln!(
        out,
        " Bias Instability {} rad/s, at {} s",
        g6(fit.bias_instability()),
        g6(at)
    );
    let _ = writeln!(out, " White Noise {} rad/s", g6(fit.gyro_n_line_value()));
    let _ = writeln!(out, " White Noise {} rad/s", g6(fit.white_noise()));
    if bias {
        let _ = writeln!(
            out,
            "  bias {} degree/s",
            g6(an.gyro_mean[i] / SECONDS_PER_HOUR)
        );
    }
    out.push_str("-------------------\n");
}

/// Upstream's fit block of accelerometer axis `i` (3–5).
fn acc_fit_block(out: &mut String, an: &Analysis, i: usize) {
    let fit = &an.fits[i];
    let _ = writeln!(out, "{}", FIT_HEADERS[i]);
    let _ = writeln!(out, "{}", crate::fit::init::c_line(&fit.start));
    let _ = writeln!(
        out,
        " Bias Instability {} m/s^2",
        g6(fit.bias_instability())
    );
    let _ = writeln!(out, " White Noise {} m/s^2", g6(fit.white_noise()));
    out.push_str("-------------------\n");
}

/// The fit blocks alone, as upstream prints them after its Allan step, for curves read from
/// an imu_utils data directory (no samples: no `calc()` blocks, no `bias` line).
pub fn fit_text(an: &Analysis) -> String {
    let mut out = String::new();
    for i in 0..3 {
        gyro_fit_block(&mut out, an, i, false);
    }
    out.push_str("==============================================\n");
    out.push_str("==============================================\n");
    for i in 3..6 {
        acc_fit_block(&mut out, an, i);
    }
    out
}

/// One curve file's content: `%.10g` per line.
pub fn curve_text(values: &[f64]) -> String {
    let mut s = String::with_capacity(values.len() * 16);
    for &v in values {
        s.push_str(&g(v, 10));
        s.push('\n');
    }
    s
}

/// The 16 curve files (8 of the sensor a one-sensor topic carries) (file name, content) in upstream's write order: sim_gyr, gyr,
/// sim_acc, acc.
pub fn curve_files(an: &Analysis, name: &str) -> Vec<(String, String)> {
    let mut files = Vec::with_capacity(16);
    for (sensor, base) in [("gyr", 0usize), ("acc", 3usize)] {
        if !an.present(base) {
            continue;
        }
        let taus = &an.axes[base].taus;
        // sim: fitted deviation of each axis at the x-axis taus (all of them).
        files.push((format!("data_{name}_sim_{sensor}_t.txt"), curve_text(taus)));
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            let sim = an.fits[base + k].sim(taus);
            files.push((
                format!("data_{name}_sim_{sensor}_{axis}.txt"),
                curve_text(&sim),
            ));
        }
        files.push((format!("data_{name}_{sensor}_t.txt"), curve_text(taus)));
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            files.push((
                format!("data_{name}_{sensor}_{axis}.txt"),
                curve_text(&an.axes[base + k].deviation()),
            ));
        }
    }
    // Upstream order: sim_gyr, gyr, sim_acc, acc — the loop above produces exactly that.
    files
}

/// Writes one text file atomically among the run's `outputs`.
pub fn write_text(outputs: &Outputs, path: &Path, text: &str) -> Result<(), Error> {
    outputs
        .write_atomic(path, |w| w.write_all(text.as_bytes()))
        .map_err(Error::from)
}

/// Writes the curve files into `dir`; returns their paths.
pub fn write_curve_files(
    outputs: &Outputs,
    an: &Analysis,
    name: &str,
    dir: &Path,
) -> Result<Vec<PathBuf>, Error> {
    use rayon::prelude::*;
    curve_files(an, name)
        .into_par_iter()
        .map(|(file, text)| {
            let p = dir.join(file);
            write_text(outputs, &p, &text).map(|()| p)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::AxisAllan;
    use crate::fit::AxisFit;
    use bag2mat::Sensor;

    /// A small synthetic analysis: white noise only; axis y gets its own taus to expose
    /// which taus the files use.
    fn analysis(n: usize) -> Analysis {
        let period = 0.005;
        let factors = crate::factors::factors(n, 100);
        let axes: Vec<AxisAllan> = AXIS_NAMES
            .iter()
            .enumerate()
            .map(|(i, &name)| {
                let scale = if i % 3 == 1 { 1.01 } else { 1.0 };
                let taus: Vec<f64> = factors.iter().map(|&m| m as f64 * period * scale).collect();
                let variance = taus.iter().map(|t| 0.09 / t).collect();
                AxisAllan {
                    name,
                    n,
                    start_t: 1.6e9,
                    end_t: 1.6e9 + (n - 1) as f64 * period,
                    freq: 1.0 / period,
                    period,
                    factors: factors.clone(),
                    taus,
                    variance,
                    noise_ids: Vec::new(),
                }
            })
            .collect();
        let fits = axes
            .iter()
            .enumerate()
            .map(|(i, a)| {
                AxisFit::fit(
                    if i < 3 { Sensor::Gyro } else { Sensor::Acc },
                    &a.taus,
                    &a.variance,
                    a.freq,
                )
            })
            .collect();
        Analysis {
            max_cluster: 100,
            axes,
            gyro_mean: [1.0, 2.0, 3.0],
            fits,
            absent: None,
        }
    }

    /// Quirk 11: every curve file uses the x-axis taus, also for y/z and the sim curves.
    #[test]
    fn quirk_11_all_curve_files_use_x_axis_taus() {
        let an = analysis(4000);
        let files = curve_files(&an, "t");
        assert_eq!(files.len(), 16);
        let x_taus = curve_text(&an.axes[0].taus);
        let get = |f: &str| {
            files
                .iter()
                .find(|(n, _)| n == f)
                .map(|(_, t)| t.clone())
                .unwrap()
        };
        assert_eq!(get("data_t_gyr_t.txt"), x_taus);
        assert_eq!(get("data_t_sim_gyr_t.txt"), x_taus);
        let sim_y = curve_text(&an.fits[1].sim(&an.axes[0].taus));
        assert_eq!(get("data_t_sim_gyr_y.txt"), sim_y);
        let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            &names[..2],
            &["data_t_sim_gyr_t.txt", "data_t_sim_gyr_x.txt"]
        );
        assert_eq!(names[8], "data_t_sim_acc_t.txt");
    }

    /// Quirk 14: short data only warns, with upstream's exact lines and spacing.
    #[test]
    fn quirk_14_short_data_only_warns() {
        let text = stdout_text(&analysis(4000));
        assert!(
            text.contains("gyr x  numData 4000\ngyr x  Too few number\ngyr x  start_t 1.6e+09\n"),
            "{text}"
        );
        assert!(
            text.contains("-------------19.995 s\n-------------0.33325 min\n"),
            "{text}"
        );
        assert!(
            text.contains("gyr x  Too short time!!!!\ngyr x  freq 200\ngyr x  period 0.005\n"),
            "{text}"
        );
        assert!(text.contains("gyr x dt \n"));
        assert!(text.starts_with("gyr x  num of Cluster 100\n"));
        assert_eq!(
            text.matches("==============================================\n")
                .count(),
            2
        );
        assert!(text.contains("Gyro X \nC ") && text.contains("acc z \nC "));
    }
}
