//! The analysis' charts, through the workspace's one PNG+SVG writer:
//!
//! * `operating_psd.{png,svg}`: per axis the residual's PSD (averaged over log-spaced bins
//!   with the largest bin as an envelope, as the IEEE 952 PSD chart draws it), its floor, the
//!   spline's estimated error, the operating level 2·N_op² and the static level 2·N_static²
//!   as horizontal lines, the band's edges, and each line found.
//! * `operating_spectrogram.{png,svg}`: per sensor the signal's PSD (summed over the axes)
//!   against time and frequency, in decibels, with the phases marked.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{AxisOperating, Operating};
use crate::ieee952::chart_panels;
use crate::ieee952::psd_plot::{draw_binned, log_bins, positive};

/// Panel size of the PSD chart in SVG units.
const PANEL: (u32, u32) = (560, 420);
/// PNG pixels per SVG unit.
const PNG_SCALE: f64 = 1.5;
/// Log bins per PSD panel.
const CHART_BINS: usize = 400;
/// Spectrogram cells drawn: time columns and frequency rows at most.
const CELLS: (usize, usize) = (160, 100);
/// Spectrogram panel size in SVG units.
const SPEC_PANEL: (u32, u32) = (1100, 330);

/// Writes both charts into `dir`.
pub(crate) fn write(
    outputs: &bag2mat::shared::output::Outputs,
    op: &Operating,
    title: &str,
    dir: &Path,
) -> Result<Vec<PathBuf>, bag2mat::Error> {
    let mut out = Vec::new();
    let rows = op.axes.len().div_ceil(3).max(1) as u32;
    let size = (PANEL.0 * 3, PANEL.1 * rows + 40);
    let psize = scaled(size);
    out.extend(bag2mat::shared::plot::write_png_svg(
        outputs,
        &PsdChart { op, title },
        dir,
        "operating_psd",
        size,
        psize,
    )?);
    if !op.spectrogram.sensors.is_empty() {
        let n = op.spectrogram.sensors.len() as u32;
        let size = (SPEC_PANEL.0, SPEC_PANEL.1 * n + 40);
        out.extend(bag2mat::shared::plot::write_png_svg(
            outputs,
            &SpecChart { op, title },
            dir,
            "operating_spectrogram",
            size,
            scaled(size),
        )?);
    }
    Ok(out)
}

fn scaled(s: (u32, u32)) -> (u32, u32) {
    (
        (s.0 as f64 * PNG_SCALE) as u32,
        (s.1 as f64 * PNG_SCALE) as u32,
    )
}

struct PsdChart<'a> {
    op: &'a Operating,
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
        let panels = chart_panels::titled_panels(
            root,
            &format!(
                "{} — operating noise: residual PSD{}; level 2N² of N_op and of the static N",
                self.title,
                if self.op.reference.is_some() {
                    " against the reference"
                } else {
                    " above the motion"
                }
            ),
            self.op.axes.len(),
            scale,
        )?;
        for (i, ax) in self.op.axes.iter().enumerate() {
            psd_panel(ax, &panels[i], scale)?;
        }
        Ok(())
    }
}

fn psd_panel<DB: DrawingBackend>(
    ax: &AxisOperating,
    area: &DrawingArea<DB, Shift>,
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    let b = &ax.band;
    let p = &b.psd;
    let bins = log_bins(&p.freq, &p.density, CHART_BINS);
    let floor = log_bins(&p.freq, &p.floor, CHART_BINS);
    let spl = log_bins(&p.freq, &b.spline_psd, CHART_BINS);
    let op_level = 2.0 * b.n * b.n;
    let st_level = ax.static_n.map(|s| 2.0 * s.value * s.value);
    let (mut y0, mut y1) = (f64::MAX, f64::MIN);
    for v in bins
        .iter()
        .flat_map(|x| [x.mean, x.max])
        .chain([op_level])
        .chain(st_level)
    {
        if positive(v) {
            y0 = y0.min(v);
            y1 = y1.max(v);
        }
    }
    let (x0, x1) = (p.freq[0] / 1.2, p.freq[p.freq.len() - 1] * 1.2);
    if y0.partial_cmp(&y1) != Some(std::cmp::Ordering::Less) {
        (y0, y1) = (1e-12, 1.0);
    }
    let (y0, y1) = (y0 / 3.0, y1 * 3.0);
    let label = ax.sensor.axis_label(ax.axis);
    let mut ctx = chart_panels::log_log_panel(
        area,
        format!("{label}: N_op {:.3e} [{:.2e}, {:.2e}]", b.n, b.lo, b.hi),
        (x0, x1),
        (y0, y1),
        ("f [Hz]", &format!("PSD [({})²/Hz]", ax.sensor.unit())),
        scale,
    )?;
    draw_binned(&mut ctx, &bins, &floor, None, "residual PSD", scale)?;
    let grey = RGBColor(120, 120, 120);
    let purple = RGBColor(140, 60, 170);
    if spl.iter().any(|b| positive(b.mean) && b.mean > y0) {
        ctx.draw_series(LineSeries::new(
            spl.iter()
                .filter(|b| positive(b.mean) && b.mean > y0)
                .map(|b| (b.freq, b.mean)),
            purple.stroke_width(px(1.0).max(1)),
        ))?
        .label("spline error (estimated)")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], purple.stroke_width(2)));
    }
    ctx.draw_series(LineSeries::new(
        [(x0, op_level), (x1, op_level)],
        BLACK.stroke_width(px(2.0)),
    ))?
    .label(format!("2·N_op², band {:.2}–{:.0} Hz", b.band.0, b.band.1))
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(2)));
    if let Some(s) = st_level.filter(|v| positive(*v)) {
        let green = RGBColor(30, 140, 60);
        ctx.draw_series(DashedLineSeries::new(
            [(x0, s), (x1, s)],
            px(6.0),
            px(4.0),
            green.stroke_width(px(2.0)),
        ))?
        .label("2·N_static²")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], green.stroke_width(2)));
    }
    for edge in [b.band.0, b.band.1] {
        if edge > x0 && edge < x1 {
            ctx.draw_series(DashedLineSeries::new(
                [(edge, y0), (edge, y1)],
                px(2.0),
                px(4.0),
                grey.stroke_width(px(1.0).max(1)),
            ))?;
        }
    }
    let red = RGBColor(214, 39, 40);
    for (k, l) in b.lines.iter().enumerate() {
        let f = l.line.frequency;
        if !(f > x0 && f < x1) {
            continue;
        }
        let s = ctx.draw_series(DashedLineSeries::new(
            [(f, y0), (f, y1)],
            px(3.0),
            px(3.0),
            red.stroke_width(px(1.0).max(1)),
        ))?;
        if k < 3 {
            s.label(format!("line {:.3} Hz, A {:.2e}", f, l.line.amplitude))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], red));
        }
    }
    chart_panels::draw_legend(&mut ctx, scale)
}

struct SpecChart<'a> {
    op: &'a Operating,
    title: &'a str,
}

/// A colour for `x` in [0, 1]: dark blue through teal and green to yellow.
fn colour(x: f64) -> RGBColor {
    let stops = [
        (0.0, (40, 20, 80)),
        (0.35, (30, 110, 140)),
        (0.7, (80, 180, 90)),
        (1.0, (250, 230, 40)),
    ];
    let x = x.clamp(0.0, 1.0);
    for w in stops.windows(2) {
        let ((a, ca), (b, cb)) = (w[0], w[1]);
        if x <= b {
            let t = (x - a) / (b - a);
            let m = |p: u8, q: u8| (p as f64 + (q as f64 - p as f64) * t).round() as u8;
            return RGBColor(m(ca.0, cb.0), m(ca.1, cb.1), m(ca.2, cb.2));
        }
    }
    RGBColor(250, 230, 40)
}

impl bag2mat::shared::plot::Figure for SpecChart<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        scale: f64,
    ) -> Result<(), bag2mat::shared::plot::DrawError>
    where
        DB::ErrorType: 'static,
    {
        let px = |v: f64| (v * scale).round() as u32;
        root.fill(&WHITE)?;
        let (top, body) = root.split_vertically(px(40.0));
        top.draw(&Text::new(
            format!(
                "{} — spectrogram (PSD summed over the axes, dB); phases: still, vibrating, moving",
                self.title
            ),
            (px(12.0) as i32, px(10.0) as i32),
            ("sans-serif", px(18.0)),
        ))?;
        let spec = &self.op.spectrogram;
        let areas = body.split_evenly((spec.sensors.len().max(1), 1));
        for ((sensor, win), area) in spec.sensors.iter().zip(&areas) {
            spec_panel(self.op, *sensor, win, area, scale)
                .map_err(bag2mat::shared::plot::DrawError::from)?;
        }
        Ok(())
    }
}

fn spec_panel<DB: DrawingBackend>(
    op: &Operating,
    sensor: bag2mat::Sensor,
    win: &[Vec<f64>],
    area: &DrawingArea<DB, Shift>,
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    let spec = &op.spectrogram;
    let (nt, nf) = (win.len(), spec.freq.len());
    if nt == 0 || nf == 0 {
        return Ok(());
    }
    let t_end = spec.step * (nt - 1) as f64 + spec.window;
    let f_top = spec.freq[nf - 1];
    let (ct, cf) = (CELLS.0.min(nt), CELLS.1.min(nf));
    // mean PSD per cell, in dB
    let mut cells = vec![vec![f64::NAN; cf]; ct];
    for (i, row) in cells.iter_mut().enumerate() {
        let (a, b) = (i * nt / ct, ((i + 1) * nt / ct).max(i * nt / ct + 1));
        for (j, c) in row.iter_mut().enumerate() {
            let (fa, fb) = (j * nf / cf, ((j + 1) * nf / cf).max(j * nf / cf + 1));
            // the largest bin of the cell's frequencies (a line one bin wide stays
            // visible), averaged over its windows
            let mut s = 0.0;
            for w in &win[a..b] {
                s += w[fa..fb].iter().copied().fold(0.0, f64::max);
            }
            let v = s / (b - a) as f64;
            *c = if v > 0.0 { 10.0 * v.log10() } else { f64::NAN };
        }
    }
    let mut vals: Vec<f64> = cells
        .iter()
        .flatten()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    vals.sort_by(f64::total_cmp);
    let (lo, hi) = if vals.is_empty() {
        (0.0, 1.0)
    } else {
        (
            vals[vals.len() / 50],
            // the motion's few cells saturate; the floor and the lines get the colours
            vals[vals.len() - 1 - vals.len() / 50],
        )
    };
    let mut ctx = ChartBuilder::on(area)
        .caption(
            format!(
                "{} [({})²/Hz, dB {:.0} … {:.0}]",
                sensor.name(),
                sensor.unit(),
                lo,
                hi
            ),
            ("sans-serif", px(14.0)),
        )
        .margin(px(8.0))
        .x_label_area_size(px(30.0))
        .y_label_area_size(px(55.0))
        .build_cartesian_2d(0.0..t_end, 0.0..f_top)?;
    ctx.configure_mesh()
        .disable_mesh()
        .x_desc("t [s]")
        .y_desc("f [Hz]")
        .label_style(("sans-serif", px(11.0)))
        .axis_desc_style(("sans-serif", px(12.0)))
        .draw()?;
    let (dt, dfq) = (t_end / ct as f64, f_top / cf as f64);
    ctx.draw_series(cells.iter().enumerate().flat_map(|(i, row)| {
        row.iter().enumerate().map(move |(j, v)| {
            let c = if v.is_finite() {
                colour((v - lo) / (hi - lo).max(1e-9))
            } else {
                RGBColor(40, 20, 80)
            };
            Rectangle::new(
                [
                    (i as f64 * dt, j as f64 * dfq),
                    ((i + 1) as f64 * dt, (j + 1) as f64 * dfq),
                ],
                c.filled(),
            )
        })
    }))?;
    for p in &op.phases {
        let t = p.start as f64 / op.rate;
        ctx.draw_series(LineSeries::new(
            [(t, 0.0), (t, f_top)],
            WHITE.stroke_width(px(1.5).max(1)),
        ))?;
        ctx.draw_series(std::iter::once(Text::new(
            p.kind.name().to_string(),
            (t + spec.step, f_top * 0.95),
            ("sans-serif", px(11.0)).into_font().color(&WHITE),
        )))?;
    }
    Ok(())
}
