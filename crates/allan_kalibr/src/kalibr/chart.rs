//! The two charts of `gen_chart.m` (docs/upstream/kalibr_allan.md §3.3), drawn with plotters and the
//! workspace's embedded font: log-log Allan deviation of x, y, z and their average against
//! `tau1`, the −½ (red) and +½ (blue) fitted lines, the τ≈1 and τ≈3 read-off points, and
//! the two values in the legend. PNG and SVG, both written atomically.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use super::chart_fit::ChartFit;
use crate::error::Error;

/// MATLAB's default colour order (lines 1–4: x, y, z, average).
const MATLAB_COLORS: [RGBColor; 4] = [
    RGBColor(0, 114, 189),
    RGBColor(217, 83, 25),
    RGBColor(237, 177, 32),
    RGBColor(126, 47, 142),
];
/// PNG size in pixels.
const PNG_SIZE: (u32, u32) = (1400, 1000);
/// SVG size in user units.
const SVG_SIZE: (u32, u32) = (1000, 720);
/// Points on each fitted line (log-spaced over the τ range).
const FIT_LINE_POINTS: usize = 400;

/// What one chart shows.
pub struct Chart<'a> {
    /// Title: `<title> <sensor name>` as upstream (`[titlestr ' ' name]`).
    pub title: String,
    /// `acceleration` or `gyroscope` (legend: `x-acceleration`, …).
    pub name: &'a str,
    /// Unit of the deviation (`m/s^2`, `rad/s`).
    pub unit: &'a str,
    /// Units of the white-noise and random-walk values.
    pub unit_white: &'a str,
    pub unit_bias: &'a str,
    /// `tau1` of the grid.
    pub tau: &'a [f64],
    /// The three per-axis curves.
    pub axes: [&'a [f64]; 3],
    /// The fit (holds the average curve and both lines).
    pub fit: &'a ChartFit,
}

/// Draws `chart` into `<stem>.png` and `<stem>.svg` under `dir` (the workspace's PNG+SVG
/// writer); returns the two paths.
pub(crate) fn write_chart(
    outputs: &bag2mat::shared::output::Outputs,
    chart: &Chart,
    dir: &Path,
    stem: &str,
) -> Result<[PathBuf; 2], Error> {
    Ok(bag2mat::shared::plot::write_png_svg(
        outputs, chart, dir, stem, SVG_SIZE, PNG_SIZE,
    )?)
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
        Ok(draw(self, root, scale)?)
    }
}

/// Finite, positive (plottable on log axes) points of a curve.
fn positive_points(tau: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    tau.iter()
        .zip(y)
        .filter(|(t, v)| **t > 0.0 && v.is_finite() && **v > 0.0)
        .map(|(&t, &v)| (t, v))
        .collect()
}

/// The chart's log–log drawing context.
type LogLog<'a, DB> = ChartContext<
    'a,
    DB,
    plotters::coord::cartesian::Cartesian2d<
        plotters::coord::combinators::LogCoord<f64>,
        plotters::coord::combinators::LogCoord<f64>,
    >,
>;

/// A read-off point: τ, value and the colour of its line.
type Mark = (f64, f64, RGBColor);

fn draw<DB: DrawingBackend>(
    chart: &Chart,
    root: &DrawingArea<DB, Shift>,
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    root.fill(&WHITE)?;
    let curves: Vec<Vec<(f64, f64)>> = chart
        .axes
        .iter()
        .map(|y| positive_points(chart.tau, y))
        .chain([positive_points(chart.tau, &chart.fit.sigavg)])
        .collect();
    let (x0, x1, y0, y1) = axis_ranges(chart, &curves);

    let mut ctx = ChartBuilder::on(root)
        .caption(&chart.title, ("sans-serif", px(26.0)))
        .margin(px(16.0))
        .x_label_area_size(px(60.0))
        .y_label_area_size(px(95.0))
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    ctx.configure_mesh()
        .x_desc("τ [sec]")
        .y_desc(format!("Normal Allan Deviation [{}]", chart.unit))
        .label_style(("sans-serif", px(16.0)))
        .axis_desc_style(("sans-serif", px(20.0)))
        .x_label_formatter(&|v| format_tick(*v))
        .y_label_formatter(&|v| format_tick(*v))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(200, 200, 200))
        .draw()?;

    let labels = ["x", "y", "z"].map(|a| format!("{a}-{}", chart.name));
    draw_curves(&mut ctx, &curves, &labels, scale)?;
    draw_fit_lines(&mut ctx, chart, (x0, x1, y0, y1), scale)?;

    // Read-off points: σ at τ≈1 on the red line, σ_b at τ≈3 on the blue line.
    let fit = chart.fit;
    let marks = [(fit.tau_at1, fit.white, RED), (fit.tau_at2, fit.bias, BLUE)];
    draw_marks(&mut ctx, &marks, (y0, y1), scale)?;

    let position = legend_corner(&ctx, &curves, &marks, &labels, px(17.0) as i32);
    ctx.configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", px(17.0)))
        .draw()?;
    Ok(())
}

/// The axis ranges (x0, x1, y0, y1) of the chart: the curves' points and the two read-off
/// values, padded a bit in log space.
fn axis_ranges(chart: &Chart, curves: &[Vec<(f64, f64)>]) -> (f64, f64, f64, f64) {
    let all = curves.iter().flatten();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 >= x1 || y0 > y1 {
        // Nothing plottable (cannot happen after the input checks); draw an empty frame.
        (x0, x1, y0, y1) = (1e-3, 1.0, 1e-3, 1.0);
    }
    // Pad a bit in log space; make sure the read-off points are inside.
    for v in [chart.fit.white, chart.fit.bias] {
        if v.is_finite() && v > 0.0 {
            y0 = y0.min(v);
            y1 = y1.max(v);
        }
    }
    let (y0, y1) = (y0 / 1.6, y1 * 1.6);
    let (x0, x1) = (x0 / 1.3, x1 * 1.3);
    (x0, x1, y0, y1)
}

/// The x, y, z curves and their average, in MATLAB's colours, with their legend entries.
fn draw_curves<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    curves: &[Vec<(f64, f64)>],
    labels: &[String; 3],
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    for (i, pts) in curves.iter().enumerate() {
        let color = MATLAB_COLORS[i];
        let label = if i < 3 {
            labels[i].clone()
        } else {
            "average".to_owned()
        };
        ctx.draw_series(LineSeries::new(
            pts.iter().copied(),
            color.stroke_width(px(1.5).max(1)),
        ))?
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3)));
    }
    Ok(())
}

/// The legend texts of the −½ (white) and +½ (bias) fitted lines.
fn fit_labels(chart: &Chart) -> (String, String) {
    let fit = chart.fit;
    let white_label = format!(
        "−½ fit: σ = {} {} (τ = {} s)",
        value6(fit.white),
        chart.unit_white,
        super::report::matlab_fixed(fit.tau_at1, 2)
    );
    let bias_label = if fit.bias.is_nan() {
        // kalibr_allan's +½ window starts 50 grid points past the curve's minimum: on a
        // curve that still falls at its end the window is empty (upstream's NaN)
        "+½ fit: none (the curve has no +½ slope before its end; kalibr_allan prints NaN)"
            .to_owned()
    } else {
        format!(
            "+½ fit: σ_b = {} {} (τ = {} s)",
            value6(fit.bias),
            chart.unit_bias,
            super::report::matlab_fixed(fit.tau_at2, 2)
        )
    };
    (white_label, bias_label)
}

/// The −½ (red) and +½ (blue) fitted lines over the whole τ range `(x0, x1, y0, y1)`,
/// clipped to its y range (log-spaced samples).
fn draw_fit_lines<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    chart: &Chart,
    (x0, x1, y0, y1): (f64, f64, f64, f64),
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    let fit = chart.fit;
    let line = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        (0..FIT_LINE_POINTS)
            .map(|k| {
                let t = x0 * (x1 / x0).powf(k as f64 / (FIT_LINE_POINTS - 1) as f64);
                (t, f(t))
            })
            .filter(|&(_, y)| y.is_finite() && y >= y0 && y <= y1)
            .collect()
    };
    let red = RED.mix(0.5);
    let blue = BLUE.mix(0.5);
    let (white_label, bias_label) = fit_labels(chart);
    ctx.draw_series(LineSeries::new(
        line(&|t| fit.h_fit1(t)),
        red.stroke_width(px(3.0)),
    ))?
    .label(white_label)
    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], red.stroke_width(4)));
    ctx.draw_series(LineSeries::new(
        line(&|t| fit.h_fit2(t)),
        blue.stroke_width(px(3.0)),
    ))?
    .label(bias_label)
    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], blue.stroke_width(4)));
    Ok(())
}

/// The read-off points inside the y range `(y0, y1)`: a filled circle ringed in black.
fn draw_marks<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    marks: &[Mark; 2],
    (y0, y1): (f64, f64),
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    for &(t, v, c) in marks {
        if t > 0.0 && v.is_finite() && v >= y0 && v <= y1 {
            ctx.draw_series(std::iter::once(Circle::new((t, v), px(7.0), c.filled())))?;
            ctx.draw_series(std::iter::once(Circle::new(
                (t, v),
                px(9.0),
                BLACK.stroke_width(1),
            )))?;
        }
    }
    Ok(())
}

/// Legend in the corner that hides the fewest curve points and neither read-off point
/// (upstream uses "southeast", which often covers the +1/2 read-off); `font` is the legend's
/// font size in pixels.
fn legend_corner<'a, DB: DrawingBackend + 'a>(
    ctx: &LogLog<'a, DB>,
    curves: &[Vec<(f64, f64)>],
    marks: &[Mark; 2],
    labels: &[String; 3],
    font: i32,
) -> SeriesLabelPosition {
    let longest = [labels[0].len(), 16, 60].into_iter().max().unwrap_or(60) as i32;
    let legend_w = longest * font * 55 / 100 + 50;
    let legend_h = 6 * (font + 10) + 16;
    let (xr, yr) = ctx.plotting_area().get_pixel_range();
    let mut weighted: Vec<((i32, i32), usize)> = curves
        .iter()
        .flatten()
        .map(|p| (ctx.backend_coord(p), 1))
        .collect();
    for &(t, v, _) in marks {
        if t > 0.0 && v.is_finite() {
            weighted.push((ctx.backend_coord(&(t, v)), 100_000));
        }
    }
    let corners = [
        (
            SeriesLabelPosition::LowerRight,
            xr.end - legend_w,
            yr.end - legend_h,
        ),
        (SeriesLabelPosition::UpperRight, xr.end - legend_w, yr.start),
        (SeriesLabelPosition::LowerLeft, xr.start, yr.end - legend_h),
        (SeriesLabelPosition::UpperLeft, xr.start, yr.start),
    ];
    let cost = |bx: i32, by: i32| -> usize {
        weighted
            .iter()
            .filter(|((x, y), _)| {
                *x >= bx && *x <= bx + legend_w && *y >= by && *y <= by + legend_h
            })
            .map(|(_, w)| w)
            .sum()
    };
    corners
        .into_iter()
        .min_by_key(|(_, bx, by)| cost(*bx, *by))
        .map(|(p, _, _)| p)
        .unwrap_or(SeriesLabelPosition::LowerRight)
}

/// `%.6f` as upstream's text box, but NaN spelled out.
fn value6(v: f64) -> String {
    super::report::matlab_fixed(v, 6)
}

/// Tick labels on log axes: powers of ten as `1e-3`, others compactly.
fn format_tick(v: f64) -> String {
    let l = v.log10();
    if (l - l.round()).abs() < 1e-9 {
        let e = l.round() as i32;
        return match e {
            -2..=3 => format!("{}", 10f64.powi(e)),
            _ => format!("1e{e}"),
        };
    }
    format!("{v:.2e}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels() {
        assert_eq!(format_tick(1000.0), "1000");
        assert_eq!(format_tick(0.01), "0.01");
        assert_eq!(format_tick(1e-5), "1e-5");
    }

    #[test]
    fn non_positive_points_are_dropped() {
        let p = positive_points(&[0.0, 1.0, 2.0, 3.0], &[f64::NAN, 1.0, f64::NAN, 0.0]);
        assert_eq!(p, vec![(1.0, 1.0)]);
    }
}
