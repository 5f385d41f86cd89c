//! `allan_gyr.{png,svg}` and `allan_acc.{png,svg}`: per-axis Allan deviation points and the
//! fitted model curves on log-log axes, as imu_utils' MATLAB scripts (`draw_allan.m`) draw
//! the `data_*` and `data_*_sim_*` files. Gyro values stay in imu_utils' pseudo-deg/h
//! (57.3-based) like the files they mirror; acc in m/s².

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::analysis::Analysis;
use crate::error::Error;

const COLORS: [RGBColor; 3] = [
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(31, 119, 180),
];
const SIZE: (u32, u32) = (1000, 700);

struct Curves<'a> {
    title: String,
    y_label: &'a str,
    taus: &'a [f64],
    data: [Vec<f64>; 3],
    fit: [Vec<f64>; 3],
}

/// A value a log axis can show.
fn finite_pos(v: &f64) -> bool {
    v.is_finite() && *v > 0.0
}

/// The deviation range of every data and fit point a log axis can show; (1e-3, 1) when
/// there is none.
fn value_range(c: &Curves<'_>) -> (f64, f64) {
    let all: Vec<f64> = c
        .data
        .iter()
        .chain(c.fit.iter())
        .flatten()
        .copied()
        .filter(finite_pos)
        .collect();
    let (mut lo, mut hi) = all
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    if all.is_empty() {
        (lo, hi) = (1e-3, 1.0);
    }
    (lo, hi)
}

/// The τ axis range: the positive cluster times widened by 1.3 each way; (1e-3, 1) when
/// there is none.
fn tau_range(c: &Curves<'_>) -> (f64, f64) {
    let taus: Vec<f64> = c.taus.iter().copied().filter(finite_pos).collect();
    let (tlo, thi) = taus
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    if taus.is_empty() {
        (1e-3, 1.0)
    } else {
        (tlo / 1.3, thi * 1.3)
    }
}

/// The (τ, value) points of one series that a log-log chart can show.
fn log_points(taus: &[f64], values: &[f64]) -> Vec<(f64, f64)> {
    taus.iter()
        .zip(values)
        .filter(|(t, v)| finite_pos(t) && finite_pos(v))
        .map(|(t, v)| (*t, *v))
        .collect()
}

/// One sensor's chart: each axis' data as circles and its fit as a line, legend top right.
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    c: &Curves<'_>,
) -> Result<(), bag2mat::shared::plot::DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (lo, hi) = value_range(c);
    let (tlo, thi) = tau_range(c);
    let mut chart = ChartBuilder::on(root)
        .caption(&c.title, ("sans-serif", 26))
        .margin(20)
        .x_label_area_size(55)
        .y_label_area_size(90)
        .build_cartesian_2d((tlo..thi).log_scale(), (lo / 1.5..hi * 1.5).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("cluster time τ (s)")
        .y_desc(c.y_label)
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 18))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let col = COLORS[k];
        let pts = log_points(c.taus, &c.data[k]);
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, col.stroke_width(1))))?
            .label(format!("{axis} data"))
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, col.stroke_width(1)));
        let line = log_points(c.taus, &c.fit[k]);
        chart
            .draw_series(LineSeries::new(line, col.stroke_width(2)))?
            .label(format!("{axis} fit"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 16))
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    bag2mat::shared::plot::present(root)
}

fn curves<'a>(an: &'a Analysis, name: &str, base: usize) -> Curves<'a> {
    let taus = &an.axes[base].taus;
    let gyro = base == 0;
    Curves {
        title: format!(
            "{name}: {} Allan deviation and imu_utils fit",
            if gyro { "gyroscope" } else { "accelerometer" }
        ),
        y_label: if gyro {
            "Allan deviation (deg/h, imu_utils 57.3 units)"
        } else {
            "Allan deviation (m/s²)"
        },
        taus,
        data: [0, 1, 2].map(|k| an.axes[base + k].deviation()),
        fit: [0, 1, 2].map(|k| an.fits[base + k].sim(taus)),
    }
}

impl bag2mat::shared::plot::Figure for Curves<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _scale: f64,
    ) -> Result<(), bag2mat::shared::plot::DrawError>
    where
        DB::ErrorType: 'static,
    {
        draw(root, self)
    }
}

/// Writes the four plot files into `dir` (the workspace's PNG+SVG writer, the two sensors in
/// parallel); returns their paths.
pub fn write_plots(
    outputs: &bag2mat::shared::output::Outputs,
    an: &Analysis,
    name: &str,
    dir: &Path,
) -> Result<Vec<PathBuf>, Error> {
    use rayon::prelude::*;
    let jobs = [("allan_gyr", 0), ("allan_acc", 3)];
    let files: Vec<[PathBuf; 2]> = jobs
        .par_iter()
        .filter(|(_, base)| an.present(*base))
        .map(|&(stem, base)| {
            bag2mat::shared::plot::write_png_svg(
                outputs,
                &curves(an, name, base),
                dir,
                stem,
                SIZE,
                SIZE,
            )
        })
        .collect::<Result<_, _>>()?;
    Ok(files.into_iter().flatten().collect())
}
