//! Shared plotting set-up: plotters renders text with the `ab_glyph` feature, which needs a
//! registered font. The DejaVu Sans font ships in `assets/fonts/` (license beside it), so no
//! system font is needed on a fresh machine.

use plotters::style::FontStyle;
use std::sync::Once;

static FONT: Once = Once::new();

/// Registers the shipped font as `sans-serif` (once per process).
pub(crate) fn register_font() {
    FONT.call_once(|| {
        // The shipped font is a valid TrueType file; a failure would only lose the text.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            include_bytes!("../assets/fonts/DejaVuSans.ttf"),
        );
    });
}
