//! Plot setup shared by every binary that draws: the lean `plotters` build has no system
//! fonts, so the DejaVu Sans font shipped in `assets/` is embedded and registered here.

use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../../assets/DejaVuSans.ttf");

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
