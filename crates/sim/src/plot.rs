//! Plots of `sim integrate`: ground truth and the integrated trajectories (top view, z over
//! time, position error over time), PNG and SVG, with bag2mat's embedded font.

use crate::error::Result;
use crate::textio::PoseRow;
use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// One integrated trajectory to draw.
pub struct Track<'a> {
    /// Legend label.
    pub label: &'a str,
    /// Positions (world, m), one per truth row.
    pub positions: &'a [Vector3<f64>],
}

const SIZE: (u32, u32) = (1800, 600);
const COLORS: [RGBColor; 3] = [
    RGBColor(0, 0, 0),
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
];

fn range(it: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in it {
        if v.is_finite() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
        lo -= 1.0;
        hi += 1.0;
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// What drawing one panel can fail with (plotters' own error).
type PanelResult<DB> = std::result::Result<
    (),
    plotters::drawing::DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>,
>;

/// The top view: truth and tracks in x–y, the start as a red dot.
fn top_view<DB: DrawingBackend>(
    panel: &DrawingArea<DB, Shift>,
    truth: &[PoseRow],
    tracks: &[Track],
) -> PanelResult<DB>
where
    DB::ErrorType: 'static,
{
    let label_font = ("sans-serif", 20);
    let xs = truth
        .iter()
        .map(|r| r.p.x)
        .chain(tracks.iter().flat_map(|t| t.positions.iter().map(|p| p.x)));
    let ys = truth
        .iter()
        .map(|r| r.p.y)
        .chain(tracks.iter().flat_map(|t| t.positions.iter().map(|p| p.y)));
    let (x0, x1) = range(xs);
    let (y0, y1) = range(ys);
    let mut c = ChartBuilder::on(panel)
        .caption("top view", ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    c.configure_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]")
        .label_style(label_font)
        .draw()?;
    let series = |i: usize| -> Vec<(f64, f64)> {
        if i == 0 {
            truth.iter().map(|r| (r.p.x, r.p.y)).collect()
        } else {
            tracks[i - 1].positions.iter().map(|p| (p.x, p.y)).collect()
        }
    };
    for i in 0..=tracks.len() {
        let col = COLORS[i % COLORS.len()];
        let label = if i == 0 {
            "ground truth"
        } else {
            tracks[i - 1].label
        };
        let width = if i == 0 { 3 } else { 2 };
        c.draw_series(LineSeries::new(series(i), col.stroke_width(width)))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 25, y)], col.stroke_width(3)));
    }
    c.draw_series(std::iter::once(Circle::new(
        (truth[0].p.x, truth[0].p.y),
        6,
        RED.filled(),
    )))?;
    c.configure_series_labels()
        .position(SeriesLabelPosition::MiddleMiddle)
        .label_font(label_font)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// z over time, truth under the tracks; `t` the time range.
fn z_over_time<DB: DrawingBackend>(
    panel: &DrawingArea<DB, Shift>,
    truth: &[PoseRow],
    tracks: &[Track],
    (t0, t1): (f64, f64),
) -> PanelResult<DB>
where
    DB::ErrorType: 'static,
{
    let label_font = ("sans-serif", 20);
    let (z0, z1) = range(
        truth
            .iter()
            .map(|r| r.p.z)
            .chain(tracks.iter().flat_map(|t| t.positions.iter().map(|p| p.z))),
    );
    let mut c = ChartBuilder::on(panel)
        .caption("z over time", ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(t0..t1, z0..z1)?;
    c.configure_mesh()
        .x_desc("t [s]")
        .y_desc("z [m]")
        .label_style(label_font)
        .draw()?;
    c.draw_series(LineSeries::new(
        truth.iter().map(|r| (r.t, r.p.z)),
        COLORS[0].stroke_width(4),
    ))?;
    for (i, tr) in tracks.iter().enumerate() {
        c.draw_series(LineSeries::new(
            truth.iter().zip(tr.positions).map(|(r, p)| (r.t, p.z)),
            COLORS[(i + 1) % 3].stroke_width(2),
        ))?;
    }
    Ok(())
}

/// |p − p_true| over time on a log scale; `t` the time range.
fn position_error<DB: DrawingBackend>(
    panel: &DrawingArea<DB, Shift>,
    truth: &[PoseRow],
    tracks: &[Track],
    (t0, t1): (f64, f64),
) -> PanelResult<DB>
where
    DB::ErrorType: 'static,
{
    let label_font = ("sans-serif", 20);
    let errs: Vec<Vec<(f64, f64)>> = tracks
        .iter()
        .map(|tr| {
            truth
                .iter()
                .zip(tr.positions)
                .map(|(r, p)| (r.t, (p - r.p).norm()))
                .collect()
        })
        .collect();
    // Log scale so that errors orders of magnitude apart (Euler vs midpoint) are both visible.
    let emax = errs
        .iter()
        .flatten()
        .map(|p| p.1)
        .fold(0.0f64, f64::max)
        .max(1e-9)
        * 1.5;
    let emin = errs
        .iter()
        .flatten()
        .map(|p| p.1)
        .filter(|&v| v > 0.0)
        .fold(f64::INFINITY, f64::min)
        .max(emax * 1e-7);
    let errs: Vec<Vec<(f64, f64)>> = errs
        .into_iter()
        .map(|v| v.into_iter().map(|(t, e)| (t, e.max(emin))).collect())
        .collect();
    let mut c = ChartBuilder::on(panel)
        .caption("position error |p - p_true|", ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(t0..t1, (emin..emax).log_scale())?;
    c.configure_mesh()
        .x_desc("t [s]")
        .y_desc("error [m] (log)")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(label_font)
        .draw()?;
    for (i, (tr, pts)) in tracks.iter().zip(errs).enumerate() {
        let col = COLORS[(i + 1) % 3];
        c.draw_series(LineSeries::new(pts, col.stroke_width(2)))?
            .label(tr.label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 25, y)], col.stroke_width(3)));
    }
    c.configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .label_font(label_font)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Three panels side by side under the title: top view, z over time, position error.
fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    truth: &[PoseRow],
    tracks: &[Track],
) -> std::result::Result<(), bag2mat::shared::plot::DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 28))?;
    let panels = root.split_evenly((1, 3));
    let (t0, t1) = range(truth.iter().map(|r| r.t));
    top_view(&panels[0], truth, tracks)?;
    z_over_time(&panels[1], truth, tracks, (t0, t1))?;
    position_error(&panels[2], truth, tracks, (t0, t1))?;
    bag2mat::shared::plot::present(&root)?;
    Ok(())
}

/// Draw `stem.png` and `stem.svg` (the workspace's PNG+SVG writer, atomically).
pub fn plot_integration(
    outputs: &bag2mat::shared::output::Outputs,
    stem: &Path,
    title: &str,
    truth: &[PoseRow],
    tracks: &[Track],
) -> Result<()> {
    let dir = match stem.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = stem
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    bag2mat::shared::plot::write_png_svg(
        outputs,
        &Integration {
            title,
            truth,
            tracks,
        },
        dir,
        &name,
        SIZE,
        SIZE,
    )?;
    Ok(())
}

/// What [`plot_integration`] draws.
struct Integration<'a> {
    title: &'a str,
    truth: &'a [PoseRow],
    tracks: &'a [Track<'a>],
}

impl bag2mat::shared::plot::Figure for Integration<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _scale: f64,
    ) -> std::result::Result<(), bag2mat::shared::plot::DrawError>
    where
        DB::ErrorType: 'static,
    {
        draw(root.clone(), self.title, self.truth, self.tracks)
    }
}
