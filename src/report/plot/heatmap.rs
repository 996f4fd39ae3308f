//! The heat map figure (the paper's fig. 3, and the calibration matrix): one panel per
//! planner over the same two axes, every cell coloured and numbered on one shared viridis
//! scale, so panels compare at a glance; the colour bar sits beside the panels, never over one.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::colour::{text_colour_on, viridis, ColourBar};
use super::{drawing_failed, render, Figure, Painter, PlotError, FONT};

/// One panel of a heat map: `values[row][column]`, `None` for a cell without data.
pub struct HeatPanel {
    /// Caption above the panel (e.g. the planner).
    pub title: String,
    /// Cell values by row (top to bottom) then column (left to right).
    pub values: Vec<Vec<Option<f64>>>,
}

/// Heat maps sharing axes and one colour scale from 0 to the largest value.
pub struct Heatmap {
    /// The panels, in rows of three.
    pub panels: Vec<HeatPanel>,
    /// Labels of the rows, top to bottom.
    pub row_labels: Vec<String>,
    /// Labels of the columns, left to right.
    pub col_labels: Vec<String>,
    /// Title of the vertical (row) axis.
    pub row_axis: String,
    /// Title of the horizontal (column) axis.
    pub col_axis: String,
    /// Label of the colour bar.
    pub scale_label: String,
    /// Decimals of the numbers printed in the cells.
    pub decimals: usize,
    /// Upper end of the scale when every value is 0 (or missing).
    pub min_scale_max: f64,
}

const PANEL_W: u32 = 400;
const PANEL_H: u32 = 300;
const BAR_W: u32 = 150;
const PANELS_PER_ROW: usize = 3;

/// The odd centres of `n` heat map cells, where the axis labels go: the chart's coordinates
/// are integers, cell i spanning [2i, 2i + 2].
fn cell_centres(n: usize) -> Vec<i32> {
    (0..n as i32).map(|i| 2 * i + 1).collect()
}

/// The index of the cell holding chart coordinate `v`.
fn cell_index(v: &i32) -> usize {
    (v.max(&0) / 2) as usize
}

impl Heatmap {
    fn layout(&self) -> (usize, usize) {
        let n = self.panels.len().max(1);
        let cols = n.min(PANELS_PER_ROW);
        (n.div_ceil(cols), cols)
    }

    fn scale_max(&self) -> f64 {
        let max = self
            .panels
            .iter()
            .flat_map(|p| p.values.iter().flatten().flatten())
            .copied()
            .fold(0.0_f64, f64::max);
        if max > 0.0 {
            max
        } else {
            self.min_scale_max
        }
    }

    /// Renders the figure.
    pub fn render(&self) -> Result<Figure, PlotError> {
        render(self, "heat map")
    }

    /// A value as printed in the cells and on the colour bar.
    fn number(&self, v: f64) -> String {
        format!("{v:.prec$}", prec = self.decimals)
    }

    fn col_label(&self, x: &i32) -> String {
        self.col_labels
            .get(cell_index(x))
            .cloned()
            .unwrap_or_default()
    }

    /// Row 0 is at the top, the chart's y axis points up.
    fn row_label(&self, y: &i32) -> String {
        self.row_labels
            .len()
            .checked_sub(cell_index(y) + 1)
            .and_then(|r| self.row_labels.get(r))
            .cloned()
            .unwrap_or_default()
    }

    /// One panel: its title, labelled axes and a coloured, numbered cell per value.
    fn paint_panel<DB: DrawingBackend>(
        &self,
        panel: &HeatPanel,
        area: &DrawingArea<DB, Shift>,
        vmax: f64,
    ) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let nx = self.col_labels.len();
        let ny = self.row_labels.len();
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, (FONT, 22))
            .margin(10)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(
                (0..2 * nx as i32).with_key_points(cell_centres(nx)),
                (0..2 * ny as i32).with_key_points(cell_centres(ny)),
            )
            .map_err(drawing_failed)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(&self.col_axis)
            .y_desc(&self.row_axis)
            .x_label_formatter(&|x| self.col_label(x))
            .y_label_formatter(&|y| self.row_label(y))
            .label_style((FONT, 16))
            .axis_desc_style((FONT, 17))
            .draw()
            .map_err(drawing_failed)?;
        let plot = chart.plotting_area();
        for (r, row) in panel.values.iter().enumerate() {
            let y = 2 * (ny - 1 - r) as i32;
            for (c, v) in row.iter().enumerate() {
                self.draw_cell(plot, (2 * c as i32, y), *v, vmax)
                    .map_err(drawing_failed)?;
            }
        }
        Ok(())
    }

    /// The cell with lower left corner `(x, y)`: filled with the colour of `value` and labelled
    /// with it, or grey with a dash when there is no value.
    fn draw_cell<DB, CT>(
        &self,
        area: &DrawingArea<DB, CT>,
        (x, y): (i32, i32),
        value: Option<f64>,
        vmax: f64,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
    where
        DB: DrawingBackend,
        CT: CoordTranslate<From = (i32, i32)>,
    {
        let (fill, text) = match value {
            Some(v) => (viridis(v / vmax), self.number(v)),
            None => (RGBColor(220, 220, 220), "–".to_string()),
        };
        area.draw(&Rectangle::new([(x, y), (x + 2, y + 2)], fill.filled()))?;
        let ink = text_colour_on(fill);
        let style = TextStyle::from((FONT, 18).into_font())
            .color(&ink)
            .pos(Pos::new(HPos::Center, VPos::Center));
        area.draw(&Text::new(text, (x + 1, y + 1), style))
    }
}

impl Painter for Heatmap {
    fn size(&self) -> (u32, u32) {
        let (rows, cols) = self.layout();
        (cols as u32 * PANEL_W + BAR_W, rows as u32 * PANEL_H)
    }

    fn side_width(&self) -> u32 {
        BAR_W
    }

    /// The panels, in rows of at most [`PANELS_PER_ROW`].
    fn paint_main<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let vmax = self.scale_max();
        for (panel, area) in self.panels.iter().zip(area.split_evenly(self.layout())) {
            self.paint_panel(panel, &area, vmax)?;
        }
        Ok(())
    }

    /// The colour bar all panels share.
    fn paint_side<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let bar = ColourBar {
            label: &self.scale_label,
            margins: (40, 58, 10),
            label_area: 84,
            font: 15,
        };
        bar.paint(area, self.scale_max(), &|v| self.number(v))
    }
}
