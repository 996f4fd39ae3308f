//! The scatter figure (delay against controllable collision rate): points coloured by series
//! (planner) and shaped by a second key (λ), with the legend of both beside the plot, so the
//! trade-off between the two metrics reads off one picture.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::colour::series_colour;
use super::{draw_grey_grid, drawing_failed, render, Figure, Painter, PlotError, FONT};

/// One series of a scatter: points (x, y, marker), drawn in one colour. The marker indexes
/// [`Scatter::markers`].
pub struct ScatterSeries {
    /// Legend name of the series (e.g. the planner).
    pub name: String,
    /// (x, y, marker index) of each point.
    pub points: Vec<(f64, f64, usize)>,
}

/// A scatter plot with a legend of series (colours) and markers (shapes).
pub struct Scatter {
    /// Caption above the plot.
    pub title: String,
    /// Title of the x axis (with its unit).
    pub x_label: String,
    /// Title of the y axis (with its unit).
    pub y_label: String,
    /// The series, each in the next colour of the series palette.
    pub series: Vec<ScatterSeries>,
    /// Legend names of the marker shapes (circle, triangle, square, cross, in this order).
    pub markers: Vec<String>,
    /// Smallest upper end of the x axis (so an all-zero x still gives a readable axis).
    pub min_x_max: f64,
}

/// Marker shapes: circle, triangle, square, cross.
const MARKER_KINDS: usize = 4;
const LEGEND_W: u32 = 190;

/// Draws marker shape `kind` at each of `points` (in the coordinates of `area`).
fn draw_markers<DB, CT>(
    area: &DrawingArea<DB, CT>,
    kind: usize,
    points: &[CT::From],
    colour: RGBColor,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend,
    CT: CoordTranslate,
    CT::From: Clone,
{
    let style = colour.filled();
    for p in points.iter().cloned() {
        match kind % MARKER_KINDS {
            0 => area.draw(&Circle::new(p, 6, style))?,
            1 => area.draw(&TriangleMarker::new(p, 7, style))?,
            2 => area.draw(&(EmptyElement::at(p) + Rectangle::new([(-5, -5), (5, 5)], style)))?,
            _ => area.draw(&Cross::new(p, 6, colour.stroke_width(2)))?,
        }
    }
    Ok(())
}

impl Scatter {
    /// Renders the figure.
    pub fn render(&self) -> Result<Figure, PlotError> {
        render(self, "scatter")
    }

    fn points(&self) -> impl Iterator<Item = &(f64, f64, usize)> {
        self.series.iter().flat_map(|s| s.points.iter())
    }

    /// Upper end of the x axis: the largest x (at least [`Scatter::min_x_max`]) and 10 % more.
    fn x_max(&self) -> f64 {
        self.points()
            .map(|p| p.0)
            .fold(0.0_f64, f64::max)
            .max(self.min_x_max)
            * 1.1
    }

    /// The y axis: the points' range padded by 10 % (at least 0.5), not below 0 unless a point
    /// is; 0 to 1 without points.
    fn y_range(&self) -> (f64, f64) {
        let (lo, hi) = self
            .points()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.1), hi.max(p.1))
            });
        if lo.is_finite() {
            let pad = ((hi - lo) * 0.1).max(0.5);
            ((lo - pad).max(0.0_f64.min(lo)), hi + pad)
        } else {
            (0.0, 1.0)
        }
    }
}

/// One legend entry at height `y`: a marker of shape `kind` in `colour`, then `name`.
fn draw_legend_entry<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    y: i32,
    kind: usize,
    colour: RGBColor,
    name: &str,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let text = TextStyle::from((FONT, 16).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    draw_markers(area, kind, &[(14, y)], colour)?;
    area.draw(&Text::new(name.to_string(), (30, y), text))
}

impl Painter for Scatter {
    fn size(&self) -> (u32, u32) {
        (900 + LEGEND_W, 600)
    }

    fn side_width(&self) -> u32 {
        LEGEND_W
    }

    /// Axes with a grid, and the points of each series in its colour.
    fn paint_main<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let x_max = self.x_max();
        let (y_lo, y_hi) = self.y_range();
        let mut chart = ChartBuilder::on(area)
            .caption(&self.title, (FONT, 24))
            .margin(16)
            .x_label_area_size(56)
            .y_label_area_size(72)
            // A little room left of 0, so points without collisions stay off the axis.
            .build_cartesian_2d(-0.03 * x_max..x_max, y_lo..y_hi)
            .map_err(drawing_failed)?;
        draw_grey_grid(&mut chart, (&self.x_label, &self.y_label), (16, 18))?;
        let plot = chart.plotting_area();
        for (i, s) in self.series.iter().enumerate() {
            for kind in 0..MARKER_KINDS {
                let at: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .filter(|p| p.2 % MARKER_KINDS == kind)
                    .map(|p| (p.0, p.1))
                    .collect();
                draw_markers(plot, kind, &at, series_colour(i)).map_err(drawing_failed)?;
            }
        }
        Ok(())
    }

    /// The legend beside the plot, never over a point: series colours, then marker shapes.
    fn paint_side<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let mut y = 70;
        for (i, s) in self.series.iter().enumerate() {
            draw_legend_entry(area, y, 0, series_colour(i), &s.name).map_err(drawing_failed)?;
            y += 26;
        }
        y += 12;
        for (m, name) in self.markers.iter().enumerate() {
            draw_legend_entry(area, y, m, BLACK, name).map_err(drawing_failed)?;
            y += 26;
        }
        Ok(())
    }
}
