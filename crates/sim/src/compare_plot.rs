//! The plot of `sim compare`: per sensor, each preset's Allan deviation as the tools see it —
//! kalibr_allan's averaged non-overlapping curve, the IEEE 952 overlapping curve (mean of the
//! three axes) — over the truth: the exact Allan deviation of the simulated sequence that
//! `sim bag` wrote beside the bag (`imu.bag.truth.csv`, mean of the axes; drawn first, under
//! the tools' curves), or the model √(N²/τ + K²τ/3) when a folder has no truth file.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{Result, SimError};
use crate::noise::Preset;

/// One preset's curves for one sensor: (τ, deviation) series.
struct Curves {
    preset: &'static str,
    kalibr: Vec<(f64, f64)>,
    ieee: Vec<(f64, f64)>,
    truth: (f64, f64),
    truth_curve: Option<Vec<(f64, f64)>>,
}

const COLORS: [RGBColor; 3] = [
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
];
const SIZE: (u32, u32) = (1200, 800);

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| SimError::Input(format!("{}: {e}", path.display())))
}

/// kalibr_allan's averaged curve (`acc_avg` or `gyro_avg`) from `allan_curves.csv`.
fn kalibr_curve(path: &Path, column: &str) -> Result<Vec<(f64, f64)>> {
    let text = read(path)?;
    let csv = allan_kalibr::OutputCsv::parse(&text);
    let c = csv
        .column(column)
        .ok_or_else(|| SimError::Input(format!("{}: no {column}", path.display())))?;
    Ok(csv
        .rows()
        .filter_map(|f| Some((f.first()?.parse().ok()?, f.get(c)?.parse().ok()?)))
        .filter(|(t, v): &(f64, f64)| *t > 0.0 && v.is_finite() && *v > 0.0)
        .collect())
}

/// Mean over the three axes of the IEEE 952 overlapping deviation (`ieee952_curves.csv`).
fn ieee_curve(path: &Path, axes: [&str; 3]) -> Result<Vec<(f64, f64)>> {
    use allan_kalibr::{CURVE_ADEV, CURVE_AXIS, CURVE_M, CURVE_TAU};
    let text = read(path)?;
    let csv = allan_kalibr::OutputCsv::parse(&text);
    let [ca, cm, ct, cd] = csv
        .columns([CURVE_AXIS, CURVE_M, CURVE_TAU, CURVE_ADEV])
        .map_err(|name| SimError::Input(format!("{}: no column {name}", path.display())))?;
    let mut by_m: std::collections::BTreeMap<u64, (f64, f64, usize)> = Default::default();
    for f in csv.rows() {
        let get = |i: usize| allan_kalibr::csv_field(&f, i);
        if !axes.contains(&get(ca)) {
            continue;
        }
        let (Ok(m), Ok(tau), Ok(adev)) = (
            get(cm).parse::<u64>(),
            get(ct).parse::<f64>(),
            get(cd).parse::<f64>(),
        ) else {
            continue;
        };
        let e = by_m.entry(m).or_insert((tau, 0.0, 0));
        e.1 += adev;
        e.2 += 1;
    }
    Ok(by_m
        .values()
        .filter(|e| e.2 == 3)
        .map(|e| (e.0, e.1 / 3.0))
        .collect())
}

/// The τ and deviation ranges `(t0, t1, y0, y1)` of the tools' curves; `None` when they
/// span no area.
fn tool_bounds(curves: &[Curves]) -> Option<(f64, f64, f64, f64)> {
    let all = curves.iter().flat_map(|c| c.kalibr.iter().chain(&c.ieee));
    let (mut t0, mut t1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for &(t, v) in all {
        (t0, t1, y0, y1) = (t0.min(t), t1.max(t), y0.min(v), y1.max(v));
    }
    (t0 < t1 && y0 < y1).then_some((t0, t1, y0, y1))
}

/// The truth curve of `c` on [t0, t1]: the exact curve when there is one, else the model
/// √(N²/τ + K²τ/3) at 201 log-spaced τ.
fn truth_points(c: &Curves, t0: f64, t1: f64) -> Vec<(f64, f64)> {
    let (n, k) = c.truth;
    match &c.truth_curve {
        Some(tc) => tc
            .iter()
            .copied()
            .filter(|&(t, v)| t >= t0 && t <= t1 && v > 0.0)
            .collect(),
        None => (0..=200)
            .map(|j| {
                let t = t0 * (t1 / t0).powf(j as f64 / 200.0);
                (t, (n * n / t + k * k * t / 3.0).sqrt())
            })
            .collect(),
    }
}

/// The legend entry of the truth, by whether `c` has the exact curve.
fn truth_label(c: &Curves) -> &'static str {
    if c.truth_curve.is_some() {
        "truth: exact ADEV of the simulated sequence (sim truth.csv)"
    } else {
        "truth: sqrt(N²/τ + K²τ/3)"
    }
}

/// One chart: axes, the truth, the tools' curves over it, the legend.
fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    unit: &str,
    curves: &[Curves],
) -> std::result::Result<(), bag2mat::shared::plot::DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let Some((t0, t1, y0, y1)) = tool_bounds(curves) else {
        return Err("no curve points to draw".into());
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 30))
        .margin(20)
        .x_label_area_size(60)
        .y_label_area_size(100)
        .build_cartesian_2d((t0..t1).log_scale(), (y0 / 1.5..y1 * 1.5).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("τ [s]")
        .y_desc(format!("Allan deviation [{unit}]"))
        .label_style(("sans-serif", 18))
        .axis_desc_style(("sans-serif", 22))
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    // The truth first, under the tools' curves.
    for (i, c) in curves.iter().enumerate() {
        let truth = chart.draw_series(LineSeries::new(
            truth_points(c, t0, t1),
            BLACK.stroke_width(2),
        ))?;
        if i == 0 {
            truth.label(truth_label(c)).legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2))
            });
        }
    }
    // The IEEE 952 points first, as open circles, and kalibr_allan's curve over them: a
    // filled dot hid the line it sits on.
    for (i, c) in curves.iter().enumerate() {
        let col = COLORS[i % COLORS.len()];
        chart
            .draw_series(
                c.ieee
                    .iter()
                    .map(|&p| Circle::new(p, 4, col.stroke_width(1))),
            )?
            .label(format!("{}: IEEE 952 overlapping (mean of axes)", c.preset))
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, col.stroke_width(1)));
        chart
            .draw_series(LineSeries::new(
                c.kalibr.iter().copied(),
                col.mix(0.8).stroke_width(2),
            ))?
            .label(format!("{}: kalibr_allan (non-overlapping, avg)", c.preset))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], col.mix(0.8).stroke_width(3))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .label_font(("sans-serif", 16))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    bag2mat::shared::plot::present(&root)
}

/// What one comparison chart draws.
struct Compare<'a> {
    title: &'a str,
    unit: &'a str,
    curves: &'a [Curves],
}

impl bag2mat::shared::plot::Figure for Compare<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _scale: f64,
    ) -> std::result::Result<(), bag2mat::shared::plot::DrawError>
    where
        DB::ErrorType: 'static,
    {
        draw(root.clone(), self.title, self.unit, self.curves)
    }
}

/// Writes `compare_gyro.{png,svg}` and `compare_acc.{png,svg}` into the comparison `root`
/// (the presets' folders under it; `rate` and `duration` of the bags for the title).
pub fn plot(
    outputs: &bag2mat::shared::output::Outputs,
    root: &Path,
    presets: &[Preset],
    rate: f64,
    duration: f64,
) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for (sensor, column, axes, unit) in [
        ("gyro", "gyro_avg", ["gx", "gy", "gz"], "rad/s"),
        ("acc", "acc_avg", ["ax", "ay", "az"], "m/s^2"),
    ] {
        let mut curves = Vec::new();
        for &p in presets {
            let dir = root.join(p.name()).join("kalibr");
            let t = p.params();
            let (_, csv) = crate::noise::truth_file::paths(&root.join(p.name()).join("imu.bag"));
            let sensor_kind = if sensor == "gyro" {
                bag2mat::Sensor::Gyro
            } else {
                bag2mat::Sensor::Acc
            };
            let truth_curve = if csv.exists() {
                let tc = crate::noise::truth_file::read_curves(&csv)?;
                tc.sensor_mean(sensor_kind)
                    .map(|v| tc.tau.iter().copied().zip(v).collect())
            } else {
                None
            };
            curves.push(Curves {
                preset: p.name(),
                kalibr: kalibr_curve(&dir.join("allan_curves.csv"), column)?,
                ieee: ieee_curve(&dir.join(allan_kalibr::CURVES_FILE), axes)?,
                truth: if sensor == "gyro" {
                    (t.gyro_noise, t.gyro_bias_rw)
                } else {
                    (t.acc_noise, t.acc_bias_rw)
                },
                truth_curve,
            });
        }
        let title = format!(
            "{sensor}: {} Hz, {} s — kalibr_allan, IEEE 952 and the truth",
            rate, duration
        );
        files.extend(bag2mat::shared::plot::write_png_svg(
            outputs,
            &Compare {
                title: &title,
                unit,
                curves: &curves,
            },
            root,
            &format!("compare_{sensor}"),
            SIZE,
            SIZE,
        )?);
    }
    Ok(files)
}
