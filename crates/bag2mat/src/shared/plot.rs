//! Plot output shared by every binary that draws: the lean `plotters` build has no system
//! fonts, so the DejaVu Sans font shipped in `assets/` is embedded and registered here; and
//! the one PNG+SVG writer ([`write_png_svg`]) every chart of the workspace goes through — a
//! chart implements [`Figure`] (drawing on any plotters backend) and gets both files,
//! written atomically.

use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../../../assets/DejaVuSans.ttf");

/// Registers the embedded font as "sans-serif" (all styles). Call before drawing; idempotent.
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        use plotters::style::FontStyle;
        for style in [
            FontStyle::Normal,
            FontStyle::Bold,
            FontStyle::Italic,
            FontStyle::Oblique,
        ] {
            // The bytes are a valid TrueType font checked in with the sources; failure here
            // would be a build defect, and then text is simply not drawn.
            let _ = plotters::style::register_font("sans-serif", style, FONT);
        }
    });
}

pub use crate::error::DrawError;

/// The bitmap backend's error type (plotters does not name it).
type BitmapError =
    <plotters::prelude::BitMapBackend<'static> as plotters::prelude::DrawingBackend>::ErrorType;

/// Finishes a drawing (`root.present()`: a bitmap backend encodes and writes its file here).
/// A failed write is said as every tool says an I/O error (a full disk: "no space left on
/// the device"), not as the backend's debug text.
pub fn present<DB>(
    root: &plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
) -> Result<(), DrawError>
where
    DB: plotters::prelude::DrawingBackend,
    DB::ErrorType: 'static,
{
    use plotters::drawing::DrawingAreaErrorKind;
    use plotters_backend::DrawingErrorKind;
    root.present().map_err(|e| {
        if let DrawingAreaErrorKind::BackendError(DrawingErrorKind::DrawingError(inner)) = &e
            && let Some(b) = (inner as &dyn std::any::Any).downcast_ref::<BitmapError>()
        {
            match *b {
                BitmapError::IOError(ref io) => {
                    return DrawError(crate::shared::output::describe(io));
                }
                // The encoder's I/O error, as its text (the image crate keeps no source).
                BitmapError::ImageError(ref ie) => {
                    return DrawError(crate::shared::output::without_errno(&ie.to_string()));
                }
                _ => {}
            }
        }
        DrawError::from(e)
    })
}

/// A chart drawn the same way on any plotters backend (the SVG and the PNG of one figure).
pub trait Figure {
    /// Draws onto `root`. `scale` multiplies every size in pixels: 1 for the SVG (its user
    /// units), the PNG's width over the SVG's for the PNG.
    fn draw<DB: plotters::prelude::DrawingBackend>(
        &self,
        root: &plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
        scale: f64,
    ) -> Result<(), DrawError>
    where
        DB::ErrorType: 'static;
}

/// Writes `<dir>/<stem>.png` (`png_size` pixels) and `<dir>/<stem>.svg` (`svg_size` user
/// units) of `fig`, each atomically among the run's `outputs`; returns `[png, svg]`.
pub fn write_png_svg(
    outputs: &crate::shared::output::Outputs,
    fig: &impl Figure,
    dir: &std::path::Path,
    stem: &str,
    svg_size: (u32, u32),
    png_size: (u32, u32),
) -> Result<[std::path::PathBuf; 2], crate::Error> {
    use plotters::prelude::{IntoDrawingArea, SVGBackend};
    register_font();
    let png = dir.join(format!("{stem}.png"));
    let svg = dir.join(format!("{stem}.svg"));
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, svg_size).into_drawing_area();
        fig.draw(&root, 1.0)
            .and_then(|()| present(&root))
            .map_err(|what| crate::Error::Plot {
                path: svg.clone(),
                what,
            })?;
    }
    outputs.write_atomic(&svg, |w| w.write_all(text.as_bytes()))?;
    let scale = png_size.0 as f64 / svg_size.0.max(1) as f64;
    png_atomic(outputs, &png, png_size, |root| {
        fig.draw(&root, scale)?;
        present(&root)
    })?;
    Ok([png, svg])
}

/// Draws a PNG atomically. plotters' bitmap backend writes to a path and picks the encoder
/// from the extension, so `draw` paints into a temporary `.png` beside `target`
/// ([`crate::shared::output::TempPath`]), which is put in place only after a successful
/// encode (and removed otherwise, on a signal too).
pub fn png_atomic<F>(
    outputs: &crate::shared::output::Outputs,
    target: &std::path::Path,
    size: (u32, u32),
    draw: F,
) -> Result<(), crate::Error>
where
    F: FnOnce(
        plotters::drawing::DrawingArea<plotters::prelude::BitMapBackend<'_>, plotters::coord::Shift>,
    ) -> Result<(), DrawError>,
{
    use plotters::prelude::{BitMapBackend, IntoDrawingArea};
    register_font();
    let tmp = crate::shared::output::TempPath::beside(outputs, target, ".tmp.png")?;
    let plot_err = |what: DrawError| crate::Error::Plot {
        path: target.to_path_buf(),
        what,
    };
    draw(BitMapBackend::new(tmp.path(), size).into_drawing_area()).map_err(plot_err)?;
    tmp.commit()
}
