//! The PSD chart, `ieee952_psd.{png,svg}`: one panel per axis with the Welch PSD the
//! section computed (the numbers are in `ieee952_psd.csv`), its local floor, the fitted
//! model's PSD and a mark at each line found. Engineers look for vibration lines in the PSD
//! first (issue 17); the Allan chart hides them in a bump and ripples.
//!
//! The PSD has thousands of bins per axis; the chart draws it averaged over
//! [`CHART_BINS`] log-spaced frequency bins (a Welch average of more segments, the way the
//! eye reads a PSD on a log axis) with the largest bin of each drawn as a faint envelope, so
//! that a line one bin wide still shows at its height.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use super::Analysis;
use super::chart_panels::LogLog;
use super::imu::{AxisResult, ImuAnalysis};

/// Panel size in SVG user units (the PNG is drawn at [`PNG_SCALE`]).
const PANEL: (u32, u32) = (560, 420);
/// PNG pixels per SVG unit.
const PNG_SCALE: f64 = 1.5;
/// Log-spaced frequency bins per panel.
const CHART_BINS: usize = 400;
/// File stem.
pub const STEM: &str = "ieee952_psd";

/// Draws `<dir>/<prefix>ieee952_psd.{png,svg}`; `None` when no axis has a PSD (a curve
/// given without its samples).
pub(crate) fn write_psd_chart(
    outputs: &bag2mat::shared::output::Outputs,
    a: &ImuAnalysis,
    title: &str,
    dir: &Path,
    prefix: &str,
) -> Result<Option<[PathBuf; 2]>, bag2mat::Error> {
    if a.axes.iter().all(|x| x.analysis.psd.is_none()) {
        return Ok(None);
    }
    let rows = a.axes.len().div_ceil(3).max(1) as u32;
    let size = (PANEL.0 * 3, PANEL.1 * rows + 40);
    let psize = (
        (size.0 as f64 * PNG_SCALE) as u32,
        (size.1 as f64 * PNG_SCALE) as u32,
    );
    bag2mat::shared::plot::write_png_svg(
        outputs,
        &PsdChart { a, title },
        dir,
        &format!("{prefix}{STEM}"),
        size,
        psize,
    )
    .map(Some)
}

struct PsdChart<'a> {
    a: &'a ImuAnalysis,
    title: &'a str,
}

impl bag2mat::shared::plot::Figure for PsdChart<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        scale: f64,
    ) -> Result<(), bag2mat::shared::plot::DrawError>
    where
        DB::ErrorType: 'static,
    {
        let panels = super::chart_panels::titled_panels(
            root,
            &format!(
                "{} — Welch PSD, one-sided (white noise N: level 2N²); lines found marked",
                self.title
            ),
            self.a.axes.len(),
            scale,
        )?;
        for (i, ax) in self.a.axes.iter().enumerate() {
            panel(ax, &panels[i], scale)?;
        }
        Ok(())
    }
}

/// One log bin of the chart: its centre frequency, the mean and the largest density in it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bin {
    pub(crate) freq: f64,
    pub(crate) mean: f64,
    pub(crate) max: f64,
}

/// `(freq, density)` averaged over `bins` log-spaced bins between the first and the last
/// frequency (bins holding no point are left out; a bin's frequency is its points' mean).
pub(crate) fn log_bins(freq: &[f64], density: &[f64], bins: usize) -> Vec<Bin> {
    let (Some(&f0), Some(&f1)) = (freq.first(), freq.last()) else {
        return Vec::new();
    };
    if !(f0 > 0.0 && f1 > f0) || bins == 0 {
        return freq
            .iter()
            .zip(density)
            .map(|(&f, &d)| Bin {
                freq: f,
                mean: d,
                max: d,
            })
            .collect();
    }
    let step = (f1 / f0).ln() / bins as f64;
    let mut out: Vec<Bin> = Vec::new();
    let (mut cur, mut n, mut sf, mut sd, mut mx) = (usize::MAX, 0usize, 0.0, 0.0, 0.0f64);
    for (&f, &d) in freq.iter().zip(density) {
        let b = (((f / f0).ln() / step) as usize).min(bins - 1);
        if b != cur && n > 0 {
            out.push(Bin {
                freq: sf / n as f64,
                mean: sd / n as f64,
                max: mx,
            });
            (n, sf, sd, mx) = (0, 0.0, 0.0, 0.0);
        }
        cur = b;
        n += 1;
        sf += f;
        sd += d;
        mx = mx.max(d);
    }
    if n > 0 {
        out.push(Bin {
            freq: sf / n as f64,
            mean: sd / n as f64,
            max: mx,
        });
    }
    out
}

/// A panel's axis ranges (x0, x1, y0, y1).
type Ranges = (f64, f64, f64, f64);

fn panel<DB: DrawingBackend>(
    ax: &AxisResult,
    area: &DrawingArea<DB, Shift>,
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    let an = &ax.analysis;
    let label = ax.sensor.axis_label(ax.axis);
    let Some(p) = &an.psd else {
        area.draw(&Text::new(
            format!("{label}: no PSD (no samples behind the curve)"),
            (px(20.0) as i32, px(20.0) as i32),
            ("sans-serif", px(13.0)),
        ))?;
        return Ok(());
    };
    let bins = log_bins(&p.freq, &p.density, CHART_BINS);
    let floor = log_bins(&p.freq, &p.floor, CHART_BINS);
    let model = model_points(an, &bins);
    let r = panel_ranges(&bins, &model);
    let (x0, x1, y0, y1) = r;
    let mut ctx = super::chart_panels::log_log_panel(
        area,
        format!("{label} — {} segments of {}", p.segments, p.segment),
        (x0, x1),
        (y0, y1),
        ("f [Hz]", &format!("PSD [({})²/Hz]", ax.sensor.unit())),
        scale,
    )?;
    draw_psd(&mut ctx, &bins, &floor, &model, scale)?;
    mark_lines(&mut ctx, an, r, scale)?;
    super::chart_panels::draw_legend(&mut ctx, scale)
}

/// Whether a density is plottable on a log axis.
pub(crate) fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// The fitted model's PSD at the bins' frequencies (positive values only); none when the
/// model does not fit.
fn model_points(an: &Analysis, bins: &[Bin]) -> Vec<(f64, f64)> {
    let fit = an.fit.as_ref().filter(|_| an.verdict.fits());
    fit.map_or_else(Vec::new, |x| {
        bins.iter()
            .map(|b| {
                (
                    b.freq,
                    super::psd::model_psd(b.freq, &x.coef, &x.shapes, an.tau0),
                )
            })
            .filter(|&(_, v)| v.is_finite() && v > 0.0)
            .collect()
    })
}

/// The axis ranges of a panel: the bins' frequencies, their mean and largest densities and
/// the model's, padded in log space.
fn panel_ranges(bins: &[Bin], model: &[(f64, f64)]) -> Ranges {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for b in bins {
        x0 = x0.min(b.freq);
        x1 = x1.max(b.freq);
        for v in [b.mean, b.max] {
            if positive(v) {
                y0 = y0.min(v);
                y1 = y1.max(v);
            }
        }
    }
    for &(_, v) in model {
        y0 = y0.min(v);
        y1 = y1.max(v);
    }
    if !(x0 < x1 && y0 < y1) {
        (x0, x1, y0, y1) = (1e-2, 1.0, 1e-6, 1.0);
    }
    let (x0, x1) = (x0 / 1.2, x1 * 1.2);
    let (y0, y1) = (y0 / 3.0, y1 * 3.0);
    (x0, x1, y0, y1)
}

/// The PSD's envelope (largest bin) and mean, its local floor and the fitted model.
fn draw_psd<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    bins: &[Bin],
    floor: &[Bin],
    model: &[(f64, f64)],
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    draw_binned(ctx, bins, floor, Some("PSD, largest bin"), "PSD", scale)?;
    if !model.is_empty() {
        ctx.draw_series(LineSeries::new(
            model.iter().copied(),
            BLACK.stroke_width(px(2.0)),
        ))?
        .label("fitted model")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(2)));
    }
    Ok(())
}

/// A binned PSD as both PSD charts draw it (this one and the operating analysis'): its
/// envelope (largest bin, faint; in the legend as `envelope` when given), its mean
/// (`mean`) and its local floor (dashed grey).
pub(crate) fn draw_binned<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    bins: &[Bin],
    floor: &[Bin],
    envelope: Option<&str>,
    mean: &str,
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    let data = RGBColor(0, 90, 170);
    let env = ctx.draw_series(LineSeries::new(
        bins.iter()
            .filter(|b| positive(b.max))
            .map(|b| (b.freq, b.max)),
        data.mix(0.3).stroke_width(px(1.0).max(1)),
    ))?;
    if let Some(label) = envelope {
        env.label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], data.mix(0.3)));
    }
    ctx.draw_series(LineSeries::new(
        bins.iter()
            .filter(|b| positive(b.mean))
            .map(|b| (b.freq, b.mean)),
        data.stroke_width(px(1.5).max(1)),
    ))?
    .label(mean)
    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], data.stroke_width(2)));
    let grey = RGBColor(120, 120, 120);
    ctx.draw_series(DashedLineSeries::new(
        floor
            .iter()
            .filter(|b| positive(b.mean))
            .map(|b| (b.freq, b.mean)),
        px(4.0),
        px(3.0),
        grey.stroke_width(px(1.0).max(1)),
    ))?
    .label("local floor")
    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], grey.stroke_width(2)));
    Ok(())
}

/// A dashed mark at each line found inside the panel's frequencies; the legend names the
/// strongest (all of them when there are at most three).
fn mark_lines<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    an: &Analysis,
    (x0, x1, y0, y1): Ranges,
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    let red = RGBColor(214, 39, 40);
    for (k, l) in an.lines.iter().enumerate() {
        if !(l.frequency > x0 && l.frequency < x1) {
            continue;
        }
        let s = ctx.draw_series(DashedLineSeries::new(
            [(l.frequency, y0), (l.frequency, y1)],
            px(3.0),
            px(3.0),
            red.stroke_width(px(1.0).max(1)),
        ))?;
        if k == 0 || an.lines.len() <= 3 {
            s.label(format!(
                "line {:.3} Hz, A {:.2e}, {:.0}× the floor",
                l.frequency, l.amplitude, l.peak_ratio
            ))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], red));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The slow reference: every point's bin found by search over the bin edges.
    fn log_bins_slow(freq: &[f64], density: &[f64], bins: usize) -> Vec<(f64, f64, f64)> {
        let (f0, f1) = (freq[0], freq[freq.len() - 1]);
        let edge = |i: usize| f0 * (f1 / f0).powf(i as f64 / bins as f64);
        (0..bins)
            .filter_map(|i| {
                let pts: Vec<(f64, f64)> = freq
                    .iter()
                    .zip(density)
                    .filter(|&(&f, _)| {
                        f >= edge(i) * (1.0 - 1e-12) && (f < edge(i + 1) || i == bins - 1)
                    })
                    .map(|(&f, &d)| (f, d))
                    .collect();
                (!pts.is_empty()).then(|| {
                    let n = pts.len() as f64;
                    (
                        pts.iter().map(|p| p.0).sum::<f64>() / n,
                        pts.iter().map(|p| p.1).sum::<f64>() / n,
                        pts.iter().map(|p| p.1).fold(0.0, f64::max),
                    )
                })
            })
            .collect()
    }

    /// Relative agreement of the two binnings (only rounding of the bin edges differs).
    const BIN_REL_TOL: f64 = 1e-12;

    #[test]
    fn log_bins_match_the_slow_binning_and_keep_a_one_bin_line() {
        let freq: Vec<f64> = (1..=8192).map(|k| k as f64 * 200.0 / 16384.0).collect();
        let mut density: Vec<f64> = freq.iter().map(|f| 1e-6 * (1.0 + 0.1 * f.sin())).collect();
        density[3000] = 1e-3;
        let fast = log_bins(&freq, &density, 400);
        let slow = log_bins_slow(&freq, &density, 400);
        assert_eq!(fast.len(), slow.len());
        for (a, b) in fast.iter().zip(&slow) {
            for (x, y) in [(a.freq, b.0), (a.mean, b.1), (a.max, b.2)] {
                assert!((x - y).abs() <= BIN_REL_TOL * y.abs(), "{a:?} vs {b:?}");
            }
        }
        assert!(fast.iter().any(|b| b.max == 1e-3), "the line's bin is kept");
        // the lowest log bins are narrower than a PSD bin: some hold none
        assert!(fast.len() < 400 && fast.len() > 200, "{}", fast.len());
    }
}
