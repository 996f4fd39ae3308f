//! The one font every figure uses, found and registered once per process.
//!
//! Text is laid out with `ab_glyph` from a TrueType file read at run time (Debian's
//! `fonts-dejavu-core`, or the file named by [`FONT_ENV`]), so no system font library is
//! needed and every machine with the same file draws the same pixels.

use std::sync::OnceLock;

use plotters::style::FontStyle;

use super::PlotError;

/// Environment variable naming a TrueType font file to use instead of DejaVu Sans.
pub const FONT_ENV: &str = "BKPBS_FONT";

/// Where distributions put DejaVu Sans (Debian first).
const FONT_CANDIDATES: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
];

/// The family name the font is registered under; figures name it in every text style.
pub(in crate::report) const FONT: &str = "sans-serif";

/// Loads and registers the font once per process.
pub(super) fn ensure_font() -> Result<(), PlotError> {
    static LOADED: OnceLock<Result<(), String>> = OnceLock::new();
    LOADED
        .get_or_init(|| {
            let candidates: Vec<String> = match std::env::var(FONT_ENV) {
                Ok(p) if !p.is_empty() => vec![p],
                _ => FONT_CANDIDATES.iter().map(|s| s.to_string()).collect(),
            };
            for path in &candidates {
                if let Ok(bytes) = std::fs::read(path) {
                    // Plotters keeps fonts for the process's lifetime.
                    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                    return plotters::style::register_font(FONT, FontStyle::Normal, bytes)
                        .map_err(|_| format!("{path} is not a usable TrueType font"));
                }
            }
            Err(format!("none of {} found", candidates.join(", ")))
        })
        .clone()
        .map_err(PlotError::Font)
}
