//! The colours of the figures: the viridis scale for magnitudes (heat map cells, speeds), the
//! ink that stays readable on a scale colour, Tableau's categorical palette for series, and the
//! colour bar that explains a scale beside the figure.
//!
//! One place for them so that every figure of a report speaks the same colour language: the
//! same planner is the same colour in the scatter and the line panels.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{drawing_failed, FONT};

/// Viridis (perceptually uniform, colour-blind safe), sampled at nine stops.
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (71, 44, 122),
    (59, 81, 139),
    (44, 113, 142),
    (33, 144, 141),
    (39, 173, 129),
    (92, 200, 99),
    (170, 220, 50),
    (253, 231, 37),
];

/// The colour of `t` ∈ [0, 1] on the viridis scale.
pub fn viridis(t: f64) -> RGBColor {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: u8, q: u8| (p as f64 + f * (q as f64 - p as f64)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Black on light colours, white on dark ones.
pub(super) fn text_colour_on(c: RGBColor) -> RGBColor {
    let luma = 0.299 * c.0 as f64 + 0.587 * c.1 as f64 + 0.114 * c.2 as f64;
    if luma > 140.0 {
        BLACK
    } else {
        WHITE
    }
}

/// Tableau's ten categorical colours.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The colour of series `i`.
pub fn series_colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// A vertical viridis colour bar from 0 to a maximum, its numbers on the right.
pub(in crate::report) struct ColourBar<'a> {
    pub label: &'a str,
    /// Top, bottom and left margins (px).
    pub margins: (u32, u32, u32),
    /// Width of the numbers and label on the right (px).
    pub label_area: u32,
    /// Size of the numbers; the label is one larger.
    pub font: u32,
}

impl ColourBar<'_> {
    pub(in crate::report) fn paint<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        vmax: f64,
        number: &dyn Fn(f64) -> String,
    ) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let (top, bottom, left) = self.margins;
        let mut scale = ChartBuilder::on(area)
            .margin_top(top)
            .margin_bottom(bottom)
            .margin_left(left)
            .margin_right(10)
            .right_y_label_area_size(self.label_area)
            .build_cartesian_2d(0.0..1.0, 0.0..vmax)
            .map_err(drawing_failed)?;
        scale
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(self.label)
            .y_labels(6)
            .y_label_formatter(&|v| number(*v))
            .label_style((FONT, self.font))
            .axis_desc_style((FONT, self.font + 1))
            .draw()
            .map_err(drawing_failed)?;
        const STEPS: usize = 100;
        scale
            .draw_series((0..STEPS).map(|i| {
                let lo = vmax * i as f64 / STEPS as f64;
                let hi = vmax * (i + 1) as f64 / STEPS as f64;
                Rectangle::new(
                    [(0.0, lo), (1.0, hi)],
                    viridis((i as f64 + 0.5) / STEPS as f64).filled(),
                )
            }))
            .map_err(drawing_failed)?;
        Ok(())
    }
}
