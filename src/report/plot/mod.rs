//! Figures of the report, as PNG and SVG, and the small painter framework they share.
//!
//! Each figure is plain data ([`Heatmap`], [`Scatter`], [`LinePanels`], and the episode
//! figures of [`crate::report::timespace`]) that implements `Painter`: a main area and a
//! strip on its right for the colour bar or legend, so nothing explaining a plot is drawn over
//! it. `render` paints a painter twice, into an in-memory bitmap encoded here as PNG and into
//! an SVG string, so the caller writes both files atomically and they always show the same.
//!
//! - [`fonts`]: the TrueType font every text is set in.
//! - [`colour`]: the viridis scale, the series palette and the colour bar.
//! - [`heatmap`], [`scatter`], [`lines`]: one figure each.

pub mod colour;
pub mod fonts;
pub mod heatmap;
pub mod lines;
pub mod scatter;
#[cfg(test)]
pub(in crate::report) mod tests;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

pub(in crate::report) use colour::ColourBar;
pub use colour::{series_colour, viridis};
pub(in crate::report) use fonts::FONT;
pub use fonts::FONT_ENV;
pub use heatmap::{HeatPanel, Heatmap};
pub use lines::{Band, Curve, Dots, LinePanel, LinePanels};
pub use scatter::{Scatter, ScatterSeries};

/// Why a figure could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// No TrueType font was found to set the figure's text in.
    #[error("no font for figures: {0} (install Debian's fonts-dejavu-core or set {FONT_ENV} to a .ttf file)")]
    Font(String),
    /// plotters failed while drawing or encoding the figure.
    #[error("drawing {figure}: {message}")]
    Draw {
        /// Which figure (e.g. "heat map").
        figure: &'static str,
        /// plotters' (or the PNG encoder's) error, as text.
        message: String,
    },
}

/// A rendered figure.
pub struct Figure {
    /// The figure as an 8-bit RGB PNG file's bytes.
    pub png: Vec<u8>,
    /// The same figure as an SVG document.
    pub svg: String,
}

/// Something drawable on any plotters backend: a main area and a strip on its right (colour
/// bar or legend), so that nothing explaining the plot is ever drawn over it.
pub(super) trait Painter {
    /// Width and height of the whole figure, in pixels.
    fn size(&self) -> (u32, u32);
    /// Width of the strip on the right, in pixels.
    fn side_width(&self) -> u32;
    fn paint_main<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static;
    fn paint_side<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static;
}

/// Paints the white background, then the main area, then the strip on its right.
fn paint<DB: DrawingBackend>(p: &impl Painter, root: &DrawingArea<DB, Shift>) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(drawing_failed)?;
    let (w, _) = p.size();
    let (main, side) = root.split_horizontally(w - p.side_width());
    p.paint_main(&main)?;
    p.paint_side(&side)
}

/// A plotters drawing error as text, which is all [`PlotError::Draw`] keeps of it.
pub(super) fn drawing_failed<E: std::error::Error + Send + Sync>(
    e: DrawingAreaErrorKind<E>,
) -> String {
    e.to_string()
}

/// Paints `p` as PNG and as SVG; `figure` names it in errors.
pub(super) fn render(p: &impl Painter, figure: &'static str) -> Result<Figure, PlotError> {
    fonts::ensure_font()?;
    let err = |message: String| PlotError::Draw { figure, message };
    let (w, h) = p.size();
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        paint(p, &root).map_err(err)?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    let png = encode_png(&buf, w, h).map_err(err)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        paint(p, &root).map_err(err)?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    Ok(Figure { png, svg })
}

/// An RGB buffer as an 8-bit PNG.
fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(rgb).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(out)
}

/// A chart with f64 axes, as the scatter, the line panels and the lane figures draw them.
pub(in crate::report) type Chart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The axes of a chart with a light grey grid (one light line between bold ones), labelled
/// `x_label` and `y_label`: tick numbers in font size `sizes.0`, the labels in `sizes.1`.
fn draw_grey_grid<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    (x_label, y_label): (&str, &str),
    sizes: (u32, u32),
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style((FONT, sizes.0))
        .axis_desc_style((FONT, sizes.1))
        .max_light_lines(1)
        .light_line_style(RGBColor(240, 240, 240))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()
        .map_err(drawing_failed)
}
