//! The page and the log–log panels both IEEE 952 charts are drawn on (the Allan chart,
//! [`super::plot`], and the PSD chart, [`super::psd_plot`]): the titled white page split
//! into panels, each panel's axes and grid, and its legend.

use plotters::coord::Shift;
use plotters::prelude::*;

/// A chart's white page with `title` across the top and the panels of `axes` axes below it,
/// three to a row.
pub(crate) fn titled_panels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    axes: usize,
    scale: f64,
) -> Result<Vec<DrawingArea<DB, Shift>>, bag2mat::shared::plot::DrawError>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    root.fill(&WHITE)?;
    let (top, body) = root.split_vertically(px(40.0));
    top.draw(&Text::new(
        title.to_string(),
        (px(12.0) as i32, px(10.0) as i32),
        ("sans-serif", px(18.0)),
    ))?;
    Ok(body.split_evenly((axes.div_ceil(3).max(1), 3)))
}

/// A panel of the section's charts: log–log axes over `x` × `y`, its caption, the axis
/// descriptions `desc` (x, y) and the light grid, sized for `scale` (see
/// [`bag2mat::shared::plot::Figure`]).
pub(crate) fn log_log_panel<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    caption: String,
    x: (f64, f64),
    y: (f64, f64),
    desc: (&str, &str),
    scale: f64,
) -> Result<LogLog<'a, DB>, Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| (v * scale).round() as u32;
    let mut ctx = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", px(15.0)))
        .margin(px(8.0))
        .x_label_area_size(px(34.0))
        .y_label_area_size(px(62.0))
        .build_cartesian_2d((x.0..x.1).log_scale(), (y.0..y.1).log_scale())?;
    ctx.configure_mesh()
        .x_desc(desc.0)
        .y_desc(desc.1)
        .label_style(("sans-serif", px(11.0)))
        .axis_desc_style(("sans-serif", px(12.0)))
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()?;
    Ok(ctx)
}

/// A log–log panel's drawing context.
pub(crate) type LogLog<'a, DB> = ChartContext<
    'a,
    DB,
    plotters::coord::cartesian::Cartesian2d<
        plotters::coord::combinators::LogCoord<f64>,
        plotters::coord::combinators::LogCoord<f64>,
    >,
>;

/// The legend of a panel, lower left, sized for `scale`.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a>(
    ctx: &mut LogLog<'a, DB>,
    scale: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    ctx.configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.5))
        .label_font(("sans-serif", (10.0 * scale).round() as u32))
        .draw()?;
    Ok(())
}
