//! The IEEE 952 chart, `ieee952_allan.{png,svg}`: one panel per axis with the Allan deviation
//! and its 95 % band, the τ the fit left out shaded, the fitted model over the range it was
//! fitted, each fitted term's own line (Q: −1, N: −½, B: flat, K: +½, R: +1), and the truth
//! curve when `sim` wrote one.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use super::chart_panels::{LogLog, draw_legend, log_log_panel, titled_panels};
use super::imu::{AxisResult, ImuAnalysis};
use super::term::NoiseTerm;
use super::{Analysis, Point};

/// Panel size in SVG user units (the PNG is drawn at [`PNG_SCALE`]).
const PANEL: (u32, u32) = (560, 420);
/// PNG pixels per SVG unit.
const PNG_SCALE: f64 = 1.5;
/// Points on each model or term line.
const LINE_POINTS: usize = 200;
/// File stem.
pub const STEM: &str = "ieee952_allan";

/// Term line colours (Q, N, B, K, R).
const TERM_COLORS: [RGBColor; 5] = [
    RGBColor(148, 103, 189),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(255, 127, 14),
];

/// A truth curve per axis, in the order of [`ImuAnalysis::axes`]: (τ s, σ).
pub type Truth = Vec<Vec<(f64, f64)>>;

/// The truth `sim` wrote beside the input: `<input>.truth.csv`, or for a `.mat` converted
/// from a sim bag, `<stem>.bag.truth.csv`. Columns `tau_s` and `gyro_x` … `acc_z` (the total
/// Allan deviation of each axis); `None` when there is no such file or it does not read.
pub fn find_truth(input: &Path, a: &ImuAnalysis) -> Option<Truth> {
    let mut candidates = vec![PathBuf::from(format!("{}.truth.csv", input.display()))];
    if input.extension().is_some_and(|e| e == "mat") {
        candidates.push(input.with_extension("bag.truth.csv"));
    }
    let path = candidates.into_iter().find(|p| p.is_file())?;
    read_truth(&std::fs::read_to_string(path).ok()?, a)
}

/// Parses a `sim` truth CSV for the axes of `a`.
pub(crate) fn read_truth(text: &str, a: &ImuAnalysis) -> Option<Truth> {
    let csv = super::csv_back::OutputCsv::parse(text);
    let col = |name: &str| csv.column(name);
    let tau_c = col("tau_s")?;
    let cols: Vec<usize> = a
        .axes
        .iter()
        .map(|ax| {
            col(&format!(
                "{}_{}",
                ax.sensor.short(),
                ["x", "y", "z"][ax.axis]
            ))
        })
        .collect::<Option<_>>()?;
    let mut out: Truth = vec![Vec::new(); cols.len()];
    for f in csv.rows() {
        let tau: f64 = f.get(tau_c)?.parse().ok()?;
        for (k, &c) in cols.iter().enumerate() {
            let v: f64 = f.get(c)?.parse().ok()?;
            out[k].push((tau, v));
        }
    }
    Some(out)
}

/// Draws the chart into `<dir>/<prefix>ieee952_allan.{png,svg}` (the workspace's PNG+SVG
/// writer) and, where the analysis has PSDs, the PSD chart beside it
/// (`psd_plot`), the two rendered in parallel; returns the paths.
pub fn write_chart(
    outputs: &bag2mat::shared::output::Outputs,
    a: &ImuAnalysis,
    title: &str,
    truth: Option<&Truth>,
    dir: &Path,
    prefix: &str,
) -> Result<Vec<PathBuf>, bag2mat::Error> {
    let rows = a.axes.len().div_ceil(3).max(1) as u32;
    let size = (PANEL.0 * 3, PANEL.1 * rows + 40);
    let psize = (
        (size.0 as f64 * PNG_SCALE) as u32,
        (size.1 as f64 * PNG_SCALE) as u32,
    );
    let (allan, psd) = rayon::join(
        || {
            bag2mat::shared::plot::write_png_svg(
                outputs,
                &Chart { a, title, truth },
                dir,
                &format!("{prefix}{STEM}"),
                size,
                psize,
            )
        },
        || super::psd_plot::write_psd_chart(outputs, a, title, dir, prefix),
    );
    let mut out = allan?.to_vec();
    out.extend(psd?.into_iter().flatten());
    Ok(out)
}

/// What the chart shows.
struct Chart<'a> {
    a: &'a ImuAnalysis,
    title: &'a str,
    truth: Option<&'a Truth>,
}

impl bag2mat::shared::plot::Figure for Chart<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        scale: f64,
    ) -> Result<(), bag2mat::shared::plot::DrawError>
    where
        DB::ErrorType: 'static,
    {
        draw(self.a, self.title, self.truth, root, scale)
    }
}

fn draw<DB: DrawingBackend>(
    a: &ImuAnalysis,
    title: &str,
    truth: Option<&Truth>,
    root: &DrawingArea<DB, Shift>,
    scale: f64,
) -> Result<(), bag2mat::shared::plot::DrawError>
where
    DB::ErrorType: 'static,
{
    let panels = titled_panels(
        root,
        &format!("{title} — IEEE 952 (95 % band; shaded: τ not described by the model)"),
        a.axes.len(),
        scale,
    )?;
    for (i, ax) in a.axes.iter().enumerate() {
        let t = truth.and_then(|t| t.get(i)).map(|v| v.as_slice());
        panel(ax, t, &panels[i], scale)?;
    }
    Ok(())
}

/// A panel's axis ranges (x0, x1, y0, y1).
type Ranges = (f64, f64, f64, f64);

fn panel<DB: DrawingBackend>(
    ax: &AxisResult,
    truth: Option<&[(f64, f64)]>,
    area: &DrawingArea<DB, Shift>,
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let an = &ax.analysis;
    let pts: Vec<_> = an
        .curve
        .iter()
        .filter(|p| p.tau > 0.0 && p.adev > 0.0 && p.adev.is_finite())
        .collect();
    let r = panel_ranges(&pts, truth);
    let (x0, x1, y0, y1) = r;
    let caption = format!(
        "{} — {}",
        ax.sensor.axis_label(ax.axis),
        match &an.verdict {
            super::AxisVerdict::Fits { .. } => "model fits".to_string(),
            super::AxisVerdict::NoReliableFit { .. } => "no reliable fit".to_string(),
        }
    );
    let mut ctx = log_log_panel(
        area,
        caption,
        (x0, x1),
        (y0, y1),
        ("τ [s]", &format!("Allan deviation [{}]", ax.sensor.unit())),
        scale,
    )?;
    shade_undescribed(&mut ctx, an, r)?;
    draw_data(&mut ctx, &pts, scale)?;
    draw_model(&mut ctx, an, r, scale)?;
    if let Some(tr) = truth {
        draw_truth(&mut ctx, tr, (x0, x1), scale)?;
    }
    draw_legend(&mut ctx, scale)
}

/// The axis ranges of a panel: the curve's τ and its deviations with their 95 % bands, and
/// the truth inside that τ range, padded in log space.
fn panel_ranges(pts: &[&Point], truth: Option<&[(f64, f64)]>) -> Ranges {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in pts {
        x0 = x0.min(p.tau);
        x1 = x1.max(p.tau);
        for v in [p.adev, p.lo95, p.hi95] {
            if v.is_finite() && v > 0.0 {
                y0 = y0.min(v);
                y1 = y1.max(v);
            }
        }
    }
    if let Some(tr) = truth {
        for &(t, v) in tr {
            if t >= x0 && t <= x1 && v > 0.0 {
                y0 = y0.min(v);
                y1 = y1.max(v);
            }
        }
    }
    if !(x0 < x1 && y0 <= y1) {
        (x0, x1, y0, y1) = (1e-3, 1.0, 1e-3, 1.0);
    }
    let (x0, x1) = (x0 / 1.3, x1 * 1.3);
    let (y0, y1) = (y0 / 2.0, y1 * 2.0);
    (x0, x1, y0, y1)
}

/// Shades the τ the model does not describe: outside the verdict's range, or all of the
/// panel without one.
fn shade_undescribed<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    an: &Analysis,
    (x0, x1, y0, y1): Ranges,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let shade = RGBColor(200, 200, 200).mix(0.45).filled();
    match an.verdict.range() {
        Some((lo, hi)) => {
            if lo > x0 {
                ctx.draw_series(std::iter::once(Rectangle::new([(x0, y0), (lo, y1)], shade)))?;
            }
            if hi < x1 {
                ctx.draw_series(std::iter::once(Rectangle::new([(hi, y0), (x1, y1)], shade)))?;
            }
        }
        None => {
            ctx.draw_series(std::iter::once(Rectangle::new([(x0, y0), (x1, y1)], shade)))?;
        }
    }
    Ok(())
}

/// The curve's 95 % band (where it has one) and the curve itself.
fn draw_data<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    pts: &[&Point],
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    let band: Vec<(f64, f64)> = pts
        .iter()
        .filter(|p| p.lo95 > 0.0 && p.hi95.is_finite())
        .map(|p| (p.tau, p.hi95))
        .chain(
            pts.iter()
                .rev()
                .filter(|p| p.lo95 > 0.0 && p.hi95.is_finite())
                .map(|p| (p.tau, p.lo95)),
        )
        .collect();
    let data_color = RGBColor(0, 90, 170);
    if band.len() > 2 {
        ctx.draw_series(std::iter::once(Polygon::new(
            band,
            data_color.mix(0.18).filled(),
        )))?
        .label("95 % band")
        .legend(move |(x, y)| {
            Rectangle::new([(x, y - 4), (x + 16, y + 4)], data_color.mix(0.18).filled())
        });
    }
    ctx.draw_series(LineSeries::new(
        pts.iter().map(|p| (p.tau, p.adev)),
        data_color.stroke_width(px(1.5).max(1)),
    ))?
    .label("data")
    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], data_color.stroke_width(2)));
    Ok(())
}

/// `f` at [`LINE_POINTS`] log-spaced τ from `a` to `b`, the points inside `y0..=y1` kept.
fn line_over(a: f64, b: f64, (y0, y1): (f64, f64), f: &dyn Fn(f64) -> f64) -> Vec<(f64, f64)> {
    (0..LINE_POINTS)
        .map(|k| {
            let t = a * (b / a).powf(k as f64 / (LINE_POINTS - 1) as f64);
            (t, f(t))
        })
        .filter(|&(_, y)| y.is_finite() && y >= y0 && y <= y1)
        .collect()
}

/// Where there is a fit and a fitted range: each fitted term's line over the whole τ axis,
/// the Gauss–Markov bias's, and the model over the fitted range.
fn draw_model<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    an: &Analysis,
    (x0, x1, y0, y1): Ranges,
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    let (Some(f), Some((lo, hi))) = (&an.fit, an.verdict.range()) else {
        return Ok(());
    };
    let coef = f.coef;
    // each fitted term's line, over the whole τ axis
    for (j, term) in NoiseTerm::POWER_LAWS.into_iter().enumerate() {
        let Some(fitted) = an.terms.get(term) else {
            continue;
        };
        let v = fitted.value;
        if !super::fit::is_positive(v) || coef[term] <= 0.0 {
            continue;
        }
        let c = TERM_COLORS[j];
        let name = term.symbol();
        ctx.draw_series(DashedLineSeries::new(
            line_over(x0, x1, (y0, y1), &|t| {
                v * super::fit::term_basis_at(term, t, &f.shapes).sqrt()
            }),
            px(5.0),
            px(4.0),
            c.stroke_width(px(1.0).max(1)),
        ))?
        .label(term_label(name, &fitted))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
    }
    if coef[NoiseTerm::GaussMarkov] > 0.0 {
        let (sigma, tg) = (an.terms.g.value, f.shapes.gm_t);
        let c = TERM_COLORS[NoiseTerm::BiasInstability.index()];
        ctx.draw_series(DashedLineSeries::new(
            line_over(x0, x1, (y0, y1), &|t| {
                sigma * super::fit::gm_basis(t, tg).sqrt()
            }),
            px(2.0),
            px(4.0),
            c.stroke_width(px(1.0).max(1)),
        ))?
        .label(format!("Gauss–Markov σ = {sigma:.2e}, T = {tg:.3} s"))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
    }
    let model = |t: f64| f.predict(t).max(0.0).sqrt();
    ctx.draw_series(LineSeries::new(
        line_over(lo, hi, (y0, y1), &model),
        BLACK.stroke_width(px(2.0)),
    ))?
    .label("model (fitted range)")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(2)));
    Ok(())
}

/// A fitted term's legend entry, as stdout and the files state it: a resolved term (or a
/// region reading) its value, any other its 95 % upper bound — the dashed line is the fit's
/// component, but the number a reader takes from the legend is the one the record supports.
pub(crate) fn term_label(name: &str, t: &super::Term) -> String {
    match t.reported() {
        Some(v) => format!("{name} = {v:.2e}"),
        None if t.hi.is_finite() => format!("{name} < {:.2e} (not resolved, 95 % bound)", t.hi),
        None => format!("{name}: not resolved"),
    }
}

/// The truth curve `sim` wrote, inside the τ range `(x0, x1)`.
fn draw_truth<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    tr: &[(f64, f64)],
    (x0, x1): (f64, f64),
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    let grey = RGBColor(90, 90, 90);
    ctx.draw_series(DashedLineSeries::new(
        tr.iter()
            .copied()
            .filter(|&(t, v)| t >= x0 && t <= x1 && v > 0.0),
        px(2.0),
        px(3.0),
        grey.stroke_width(px(1.5).max(1)),
    ))?
    .label("truth (sim)")
    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], grey.stroke_width(2)));
    Ok(())
}
