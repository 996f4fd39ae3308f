//! Figures of the report, as PNG and SVG: heat maps with one panel per planner and a shared
//! colour scale (the paper's fig. 3), and a scatter of points coloured by series.
//!
//! Text is laid out with `ab_glyph` from a TrueType file read at run time (Debian's
//! `fonts-dejavu-core`, or the file named by `BKPBS_FONT`), so no system font library is
//! needed. PNGs are drawn into memory and encoded here, so both files are written atomically
//! by the caller.

use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Environment variable naming a TrueType font file to use instead of DejaVu Sans.
pub const FONT_ENV: &str = "BKPBS_FONT";

/// Where distributions put DejaVu Sans (Debian first).
const FONT_CANDIDATES: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
];

pub(super) const FONT: &str = "sans-serif";

/// Why a figure could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("no font for figures: {0} (install Debian's fonts-dejavu-core or set {FONT_ENV} to a .ttf file)")]
    Font(String),
    #[error("drawing {figure}: {message}")]
    Draw {
        figure: &'static str,
        message: String,
    },
}

/// A rendered figure.
pub struct Figure {
    pub png: Vec<u8>,
    pub svg: String,
}

/// Loads and registers the font once per process.
fn ensure_font() -> Result<(), PlotError> {
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

pub(super) fn render(p: &impl Painter, figure: &'static str) -> Result<Figure, PlotError> {
    ensure_font()?;
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
fn text_colour_on(c: RGBColor) -> RGBColor {
    let luma = 0.299 * c.0 as f64 + 0.587 * c.1 as f64 + 0.114 * c.2 as f64;
    if luma > 140.0 {
        BLACK
    } else {
        WHITE
    }
}

/// One panel of a heat map: `values[row][column]`, `None` for a cell without data.
pub struct HeatPanel {
    pub title: String,
    pub values: Vec<Vec<Option<f64>>>,
}

/// Heat maps sharing axes and one colour scale from 0 to the largest value.
pub struct Heatmap {
    pub panels: Vec<HeatPanel>,
    /// Labels of the rows, top to bottom.
    pub row_labels: Vec<String>,
    pub col_labels: Vec<String>,
    pub row_axis: String,
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

/// A vertical viridis colour bar from 0 to a maximum, its numbers on the right.
pub(super) struct ColourBar<'a> {
    pub label: &'a str,
    /// Top, bottom and left margins (px).
    pub margins: (u32, u32, u32),
    /// Width of the numbers and label on the right (px).
    pub label_area: u32,
    /// Size of the numbers; the label is one larger.
    pub font: u32,
}

impl ColourBar<'_> {
    pub(super) fn paint<DB: DrawingBackend>(
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

/// One series of a scatter: points (x, y, marker), drawn in one colour. The marker indexes
/// [`Scatter::markers`].
pub struct ScatterSeries {
    pub name: String,
    pub points: Vec<(f64, f64, usize)>,
}

/// A scatter plot with a legend of series (colours) and markers (shapes).
pub struct Scatter {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<ScatterSeries>,
    /// Legend names of the marker shapes (circle, triangle, square, cross, in this order).
    pub markers: Vec<String>,
    /// Smallest upper end of the x axis (so an all-zero x still gives a readable axis).
    pub min_x_max: f64,
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
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style((FONT, 16))
            .axis_desc_style((FONT, 18))
            .max_light_lines(1)
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(215, 215, 215))
            .draw()
            .map_err(drawing_failed)?;
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

/// One curve of a [`LinePanel`]: points joined in order, in the colour of series `colour`;
/// thin curves are drawn lighter (e.g. one per planning step).
pub struct Curve {
    pub points: Vec<(f64, f64)>,
    pub colour: usize,
    pub thick: bool,
}

/// A shaded band of a [`LinePanel`] (e.g. a confidence interval): (x, low, high) in order of
/// x, in the light colour of series `colour`.
pub struct Band {
    pub points: Vec<(f64, f64, f64)>,
    pub colour: usize,
}

/// One panel of line charts.
pub struct LinePanel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub curves: Vec<Curve>,
    /// Drawn under the curves.
    pub bands: Vec<Band>,
    /// x positions of vertical red marks (e.g. a collision).
    pub marks: Vec<f64>,
    /// The x axis (default: the curves' and marks' range).
    pub x_range: Option<std::ops::Range<f64>>,
}

/// Line-chart panels in rows of two, with a legend of curve colours on the right.
pub struct LinePanels {
    pub panels: Vec<LinePanel>,
    /// Legend: (series colour index, name, thick).
    pub legend: Vec<(usize, String, bool)>,
}

const LINE_PANEL_W: u32 = 520;
const LINE_PANEL_H: u32 = 340;
const LINE_LEGEND_W: u32 = 260;

/// The range of `values` padded by 5 % (at least 0.5 each side); 0 to 1 without values.
fn padded_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
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

    fn paint_panel<DB: DrawingBackend>(
        panel: &LinePanel,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let all = || panel.curves.iter().flat_map(|c| c.points.iter());
        let band_ys = panel
            .bands
            .iter()
            .flat_map(|b| b.points.iter().flat_map(|p| [p.1, p.2]));
        let xs = panel
            .x_range
            .clone()
            .unwrap_or_else(|| padded_range(all().map(|p| p.0).chain(panel.marks.iter().copied())));
        let ys = padded_range(all().map(|p| p.1).chain(band_ys));
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, (FONT, 20))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(xs, ys.clone())
            .map_err(drawing_failed)?;
        chart
            .configure_mesh()
            .x_desc(&panel.x_label)
            .y_desc(&panel.y_label)
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 15))
            .max_light_lines(1)
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(215, 215, 215))
            .draw()
            .map_err(drawing_failed)?;
        chart
            .draw_series(panel.bands.iter().map(|b| {
                let upper = b.points.iter().map(|p| (p.0, p.2));
                let lower = b.points.iter().rev().map(|p| (p.0, p.1));
                Polygon::new(
                    upper.chain(lower).collect::<Vec<_>>(),
                    series_colour(b.colour).mix(0.18).filled(),
                )
            }))
            .map_err(drawing_failed)?;
        // Thin curves first, so the thick ones stay on top.
        for thick in [false, true] {
            let curves = panel.curves.iter().filter(|c| c.thick == thick);
            chart
                .draw_series(curves.map(|c| PathElement::new(c.points.clone(), curve_style(c))))
                .map_err(drawing_failed)?;
        }
        let red = RGBColor(214, 39, 40).stroke_width(2);
        chart
            .draw_series(
                panel
                    .marks
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
        if self.panels.iter().any(|p| !p.marks.is_empty()) {
            let red = TextStyle::from((FONT, 15).into_font())
                .color(&RGBColor(214, 39, 40))
                .pos(Pos::new(HPos::Left, VPos::Center));
            area.draw(&Text::new("| collision", (10, y + 10), red))
                .map_err(drawing_failed)?;
        }
        Ok(())
    }
}
