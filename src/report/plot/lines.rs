//! The line-panel figure (metrics against α with confidence bands, the learning curve, a
//! collision's close-up): panels of curves in rows of two, optional shaded bands under them,
//! dots over them and red vertical marks, with one legend of curve colours beside the panels.

use std::ops::Range;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::colour::series_colour;
use super::{draw_grey_grid, drawing_failed, render, Chart, Figure, Painter, PlotError, FONT};

/// One curve of a [`LinePanel`]: points joined in order, in the colour of series `colour`;
/// thin curves are drawn lighter (e.g. one per planning step).
pub struct Curve {
    /// (x, y) points, joined in this order.
    pub points: Vec<(f64, f64)>,
    /// Index into the series palette ([`series_colour`]).
    pub colour: usize,
    /// Drawn full and wide; otherwise thin and light.
    pub thick: bool,
}

/// A shaded band of a [`LinePanel`] (e.g. a confidence interval): (x, low, high) in order of
/// x, in the light colour of series `colour`.
pub struct Band {
    /// (x, low, high), in order of x.
    pub points: Vec<(f64, f64, f64)>,
    /// Index into the series palette, drawn light.
    pub colour: usize,
}

/// Single points of a [`LinePanel`] (e.g. each seed's value where seeds are too few for a
/// band), drawn as small discs over the curves in the colour of series `colour`.
pub struct Dots {
    /// (x, y) of each point.
    pub points: Vec<(f64, f64)>,
    /// Index into the series palette.
    pub colour: usize,
}

/// One panel of line charts.
pub struct LinePanel {
    /// Caption above the panel.
    pub title: String,
    /// Title of the x axis (with its unit).
    pub x_label: String,
    /// Title of the y axis (with its unit).
    pub y_label: String,
    /// The curves, drawn in order over the bands.
    pub curves: Vec<Curve>,
    /// Drawn under the curves.
    pub bands: Vec<Band>,
    /// Drawn over the curves.
    pub dots: Vec<Dots>,
    /// x positions of vertical red marks (e.g. a collision).
    pub marks: Vec<f64>,
    /// The x axis (default: the curves' and marks' range).
    pub x_range: Option<Range<f64>>,
}

/// Line-chart panels in rows of two, with a legend of curve colours on the right.
pub struct LinePanels {
    /// The panels, left to right, then top to bottom.
    pub panels: Vec<LinePanel>,
    /// Legend: (series colour index, name, thick).
    pub legend: Vec<(usize, String, bool)>,
}

const LINE_PANEL_W: u32 = 520;
const LINE_PANEL_H: u32 = 340;
const LINE_LEGEND_W: u32 = 260;
/// The colour of the marks and of their legend entry.
const MARK_RED: RGBColor = RGBColor(214, 39, 40);

/// The range of `values` padded by 5 % (at least 0.5 each side); 0 to 1 without values.
fn padded_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return 0.0..1.0;
    }
    let pad = ((hi - lo) * 0.05).max(0.5);
    lo - pad..hi + pad
}

/// The style of a curve: its series colour, full and 2 px wide when thick, light when thin.
fn curve_style(c: &Curve) -> ShapeStyle {
    let colour = series_colour(c.colour);
    if c.thick {
        colour.stroke_width(3)
    } else {
        colour.mix(0.35).stroke_width(1)
    }
}

impl LinePanels {
    /// Renders the figure.
    pub fn render(&self) -> Result<Figure, PlotError> {
        render(self, "line panels")
    }

    fn layout(&self) -> (usize, usize) {
        (self.panels.len().max(1).div_ceil(2), 2)
    }

    /// One panel: its title, axes with a grid, then bands, curves and marks, bottom to top.
    fn paint_panel<DB: DrawingBackend>(
        panel: &LinePanel,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let (xs, ys) = panel.ranges();
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, (FONT, 20))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(xs, ys.clone())
            .map_err(drawing_failed)?;
        draw_grey_grid(&mut chart, (&panel.x_label, &panel.y_label), (14, 15))?;
        panel.draw_bands(&mut chart)?;
        panel.draw_curves(&mut chart)?;
        panel.draw_dots(&mut chart)?;
        panel.draw_marks(&mut chart, ys)
    }
}

impl LinePanel {
    /// The axes: x as given or spanning the curves and marks, y spanning curves, bands and dots.
    fn ranges(&self) -> (Range<f64>, Range<f64>) {
        let all = || self.curves.iter().flat_map(|c| c.points.iter());
        let band_ys = self
            .bands
            .iter()
            .flat_map(|b| b.points.iter().flat_map(|p| [p.1, p.2]));
        let xs = self
            .x_range
            .clone()
            .unwrap_or_else(|| padded_range(all().map(|p| p.0).chain(self.marks.iter().copied())));
        let dot_ys = self.dots.iter().flat_map(|d| d.points.iter().map(|p| p.1));
        let ys = padded_range(all().map(|p| p.1).chain(band_ys).chain(dot_ys));
        (xs, ys)
    }

    /// Each band as a light polygon: along its upper edge, back along its lower one.
    fn draw_bands<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        chart
            .draw_series(self.bands.iter().map(|b| {
                let upper = b.points.iter().map(|p| (p.0, p.2));
                let lower = b.points.iter().rev().map(|p| (p.0, p.1));
                Polygon::new(
                    upper.chain(lower).collect::<Vec<_>>(),
                    series_colour(b.colour).mix(0.18).filled(),
                )
            }))
            .map_err(drawing_failed)?;
        Ok(())
    }

    /// Thin curves first, so the thick ones stay on top.
    fn draw_curves<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        for thick in [false, true] {
            let curves = self.curves.iter().filter(|c| c.thick == thick);
            chart
                .draw_series(curves.map(|c| PathElement::new(c.points.clone(), curve_style(c))))
                .map_err(drawing_failed)?;
        }
        Ok(())
    }

    /// The dots as discs with a white rim, so that overlapping ones stay countable.
    fn draw_dots<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        for d in &self.dots {
            let fill = series_colour(d.colour).mix(0.85).filled();
            chart
                .draw_series(d.points.iter().map(|&p| Circle::new(p, 5, WHITE.filled())))
                .map_err(drawing_failed)?;
            chart
                .draw_series(d.points.iter().map(|&p| Circle::new(p, 4, fill)))
                .map_err(drawing_failed)?;
        }
        Ok(())
    }

    /// The marks as red vertical lines across the y range `ys`.
    fn draw_marks<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<'_, DB>,
        ys: Range<f64>,
    ) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let red = MARK_RED.stroke_width(2);
        chart
            .draw_series(
                self.marks
                    .iter()
                    .map(|&x| PathElement::new(vec![(x, ys.start), (x, ys.end)], red)),
            )
            .map_err(drawing_failed)?;
        Ok(())
    }
}

impl Painter for LinePanels {
    fn size(&self) -> (u32, u32) {
        let (rows, cols) = self.layout();
        (
            cols as u32 * LINE_PANEL_W + LINE_LEGEND_W,
            rows as u32 * LINE_PANEL_H,
        )
    }

    fn side_width(&self) -> u32 {
        LINE_LEGEND_W
    }

    fn paint_main<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        for (panel, area) in self.panels.iter().zip(area.split_evenly(self.layout())) {
            Self::paint_panel(panel, &area)?;
        }
        Ok(())
    }

    /// The legend: a short line in each curve colour and its name.
    fn paint_side<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let text = TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        let mut y = 60;
        for (colour, name, thick) in &self.legend {
            let c = Curve {
                points: Vec::new(),
                colour: *colour,
                thick: *thick,
            };
            area.draw(&PathElement::new(vec![(8, y), (36, y)], curve_style(&c)))
                .map_err(drawing_failed)?;
            area.draw(&Text::new(name.clone(), (44, y), text.clone()))
                .map_err(drawing_failed)?;
            y += 24;
        }
        if self.panels.iter().any(|p| !p.dots.is_empty()) {
            let grey =
                TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
            area.draw(&Circle::new((22, y + 10), 4, BLACK.mix(0.6).filled()))
                .map_err(drawing_failed)?;
            area.draw(&Text::new("one seed's value", (44, y + 10), grey))
                .map_err(drawing_failed)?;
            y += 24;
        }
        if self.panels.iter().any(|p| !p.marks.is_empty()) {
            let red = TextStyle::from((FONT, 15).into_font())
                .color(&MARK_RED)
                .pos(Pos::new(HPos::Left, VPos::Center));
            area.draw(&Text::new("| collision", (10, y + 10), red))
                .map_err(drawing_failed)?;
        }
        Ok(())
    }
}
