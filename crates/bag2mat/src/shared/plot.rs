//! Plot setup shared by every binary that draws: the lean `plotters` build has no system
//! fonts, so the DejaVu Sans font shipped in `assets/` is embedded and registered here.

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

/// Draws a PNG atomically. plotters' bitmap backend writes to a path and picks the encoder
/// from the extension, so `draw` paints into a temporary `.png` beside `target`
/// ([`crate::shared::output::TempPath`]), which is put in place only after a successful
/// encode (and removed otherwise, on a signal too).
pub fn png_atomic<F>(
    target: &std::path::Path,
    size: (u32, u32),
    draw: F,
) -> Result<(), crate::Error>
where
    F: FnOnce(
        plotters::drawing::DrawingArea<plotters::prelude::BitMapBackend<'_>, plotters::coord::Shift>,
    ) -> Result<(), String>,
{
    use plotters::prelude::{BitMapBackend, IntoDrawingArea};
    register_font();
    let tmp = crate::shared::output::TempPath::beside(target, ".tmp.png")?;
    let plot_err = |what: String| crate::Error::Plot {
        path: target.to_path_buf(),
        what,
    };
    draw(BitMapBackend::new(tmp.path(), size).into_drawing_area()).map_err(plot_err)?;
    tmp.commit()
}
