//! The figures every traffic paper has, from an episode's [`LaneTracks`]: the time–space
//! diagram (s against t per lane, one line per vehicle coloured by speed, CAVs thick and HDVs
//! thin, lane changes and collisions marked) and the speed field (mean speed over s and t per
//! lane).

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::lane_tracks::LaneTracks;
use super::plot::{
    drawing_failed, render, viridis, Chart, ColourBar, Figure, Painter, PlotError, FONT,
};

const PANEL_W: u32 = 1000;
const PANEL_H: u32 = 280;
const SIDE_W: u32 = 220;
/// Bin sizes of the speed field.
const FIELD_DT_S: f64 = 4.0;
const FIELD_DS_M: f64 = 25.0;

/// Which of the two figures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// s against t per lane, one line per vehicle coloured by its speed.
    TimeSpace,
    /// Mean speed per 4 s × 25 m bin of t and s, per lane.
    SpeedField,
}

/// A figure of an episode's lanes, top panel the leftmost lane.
pub struct LaneFigure<'a> {
    /// The episode's trajectories.
    pub tracks: &'a LaneTracks,
    /// Which figure to draw of them.
    pub view: View,
    /// Title line above the panels' own (e.g. planner, α, λ, seed).
    pub title: String,
}

/// The lane's name in panel titles.
fn lane_name(lane: i32) -> String {
    match lane {
        0 => "lane 0 (ramp and acceleration lane)".into(),
        1 => "lane 1 (right main lane)".into(),
        l => format!("lane {l}"),
    }
}

impl LaneFigure<'_> {
    /// Renders the figure.
    pub fn render(&self) -> Result<Figure, PlotError> {
        render(self, "time–space diagram")
    }

    fn speed_max(&self) -> f64 {
        self.tracks.max_speed().max(1.0)
    }

    fn ranges(&self) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
        let (mut t0, mut t1, mut s0, mut s1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for &(t, s, _) in self.tracks.samples() {
            (t0, t1, s0, s1) = (t0.min(t), t1.max(t), s0.min(s), s1.max(s));
        }
        if !t0.is_finite() {
            return (0.0..1.0, 0.0..1.0);
        }
        (t0..t1.max(t0 + 1.0), s0.min(0.0)..s1.max(s0 + 1.0))
    }

    fn paint_lane<DB: DrawingBackend>(
        &self,
        lane: i32,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let (ts, ss) = self.ranges();
        let mut chart = ChartBuilder::on(area)
            .caption(lane_name(lane), (FONT, 18))
            .margin(8)
            .x_label_area_size(40)
            .y_label_area_size(64)
            .build_cartesian_2d(ts, ss)
            .map_err(drawing_failed)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc("s (m)")
            .x_label_formatter(&|t| format!("{t:.0}"))
            .y_label_formatter(&|s| format!("{s:.0}"))
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 15))
            .max_light_lines(1)
            .light_line_style(RGBColor(245, 245, 245))
            .bold_line_style(RGBColor(225, 225, 225))
            .draw()
            .map_err(drawing_failed)?;
        let vmax = self.speed_max();
        match self.view {
            View::TimeSpace => self.draw_lines(&mut chart, lane, vmax)?,
            View::SpeedField => self.draw_field(&mut chart, lane, vmax)?,
        }
        self.draw_marks(&mut chart, lane)
    }

    /// One segment per pair of consecutive samples, coloured by speed on 0..`vmax`; HDVs first,
    /// so CAVs stay on top.
    fn draw_lines<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<'_, DB>,
        lane: i32,
        vmax: f64,
    ) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let stretches = self.tracks.lanes.get(&lane).map_or(&[][..], |v| &v[..]);
        for cav in [false, true] {
            let width = if cav { 4 } else { 1 };
            let segments = stretches.iter().filter(|st| st.cav == cav).flat_map(|st| {
                st.points.windows(2).map(move |w| {
                    let colour = viridis(0.5 * (w[0].2 + w[1].2) / vmax);
                    PathElement::new(
                        vec![(w[0].0, w[0].1), (w[1].0, w[1].1)],
                        colour.stroke_width(width),
                    )
                })
            });
            chart.draw_series(segments).map_err(drawing_failed)?;
        }
        Ok(())
    }

    /// Lane changes (black triangles) and collisions (red crosses).
    fn draw_marks<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<'_, DB>,
        lane: i32,
    ) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let on_lane = |m: &&super::lane_tracks::Mark| m.lane == lane;
        chart
            .draw_series(
                self.tracks
                    .lane_changes
                    .iter()
                    .filter(on_lane)
                    .map(|m| TriangleMarker::new((m.t, m.s), 4, BLACK.filled())),
            )
            .map_err(drawing_failed)?;
        chart
            .draw_series(
                self.tracks
                    .collisions
                    .iter()
                    .filter(on_lane)
                    .map(|m| Cross::new((m.t, m.s), 8, RED.stroke_width(3))),
            )
            .map_err(drawing_failed)?;
        Ok(())
    }

    /// Mean speed per bin of [`FIELD_DT_S`] × [`FIELD_DS_M`], coloured on 0..`vmax`; empty bins
    /// stay white.
    fn draw_field<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<'_, DB>,
        lane: i32,
        vmax: f64,
    ) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let mut bins: std::collections::BTreeMap<(i64, i64), (f64, u32)> = Default::default();
        for st in self.tracks.lanes.get(&lane).into_iter().flatten() {
            for &(t, s, v) in &st.points {
                let key = (
                    (t / FIELD_DT_S).floor() as i64,
                    (s / FIELD_DS_M).floor() as i64,
                );
                let e = bins.entry(key).or_insert((0.0, 0));
                (e.0, e.1) = (e.0 + v, e.1 + 1);
            }
        }
        let cells = bins.into_iter().map(|((i, j), (sum, n))| {
            let (t, s) = (i as f64 * FIELD_DT_S, j as f64 * FIELD_DS_M);
            Rectangle::new(
                [(t, s), (t + FIELD_DT_S, s + FIELD_DS_M)],
                viridis(sum / n as f64 / vmax).filled(),
            )
        });
        chart.draw_series(cells).map_err(drawing_failed)?;
        Ok(())
    }
}

impl Painter for LaneFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let lanes = self.tracks.lanes.len().max(1) as u32;
        (PANEL_W + SIDE_W, lanes * PANEL_H + 50)
    }

    fn side_width(&self) -> u32 {
        SIDE_W
    }

    /// The title, then one panel per lane, the leftmost lane on top.
    fn paint_main<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let (title, panels) = area.split_vertically(50);
        title
            .draw(&Text::new(
                self.title.clone(),
                (PANEL_W as i32 / 2, 25),
                TextStyle::from((FONT, 20).into_font()).pos(Pos::new(HPos::Center, VPos::Center)),
            ))
            .map_err(drawing_failed)?;
        let lanes: Vec<i32> = self.tracks.lanes.keys().rev().copied().collect();
        let areas = panels.split_evenly((lanes.len().max(1), 1));
        for (lane, area) in lanes.iter().zip(&areas) {
            self.paint_lane(*lane, area)?;
        }
        Ok(())
    }

    /// The speed colour bar and the legend of line widths and marks.
    fn paint_side<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let (bar, legend) = area.split_vertically(area.dim_in_pixel().1.min(420) as i32 - 150);
        let speed_bar = ColourBar {
            label: "speed (m/s)",
            margins: (60, 20, 60),
            label_area: 70,
            font: 14,
        };
        speed_bar.paint(&bar, self.speed_max(), &|v| format!("{v:.0}"))?;
        let text = TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        let grey = RGBColor(90, 90, 90);
        let mut y = 20;
        let entries: [(&str, Option<u32>); 4] = [
            ("CAV", Some(4)),
            ("HDV", Some(1)),
            ("lane change", None),
            ("collision", None),
        ];
        // The speed field has no lines, only the marks.
        let skip = if self.view == View::SpeedField { 2 } else { 0 };
        for (k, (name, width)) in entries.iter().enumerate().skip(skip) {
            let at = |dx: i32| (20 + dx, y);
            let drawn = match (k, width) {
                (_, Some(w)) => legend.draw(&PathElement::new(
                    vec![at(0), at(36)],
                    grey.stroke_width(*w),
                )),
                (2, None) => legend.draw(&TriangleMarker::new(at(18), 5, BLACK.filled())),
                _ => legend.draw(&Cross::new(at(18), 7, RED.stroke_width(3))),
            };
            drawn.map_err(drawing_failed)?;
            legend
                .draw(&Text::new(name.to_string(), at(48), text.clone()))
                .map_err(drawing_failed)?;
            y += 28;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::lane_tracks::{Mark, Stretch};
    use crate::report::plot::tests::assert_valid_and_deterministic;

    /// Two lanes: a CAV that changes from lane 0 to lane 1 and collides, an HDV on lane 1.
    fn tracks() -> LaneTracks {
        let stretch = |id: &str, cav, points: &[(f64, f64, f64)]| Stretch {
            id: id.into(),
            cav,
            points: points.to_vec(),
        };
        let mut t = LaneTracks {
            dt: 1.0,
            ..Default::default()
        };
        t.lanes.insert(
            0,
            vec![stretch("c", true, &[(0.0, 0.0, 20.0), (1.0, 20.0, 21.0)])],
        );
        t.lanes.insert(
            1,
            vec![
                stretch("c", true, &[(2.0, 41.0, 22.0), (3.0, 60.0, 18.0)]),
                stretch("h", false, &[(0.0, 30.0, 10.0), (3.0, 61.0, 11.0)]),
            ],
        );
        let mark = |lane, t, s| Mark { lane, t, s };
        t.lane_changes = vec![mark(0, 2.0, 41.0), mark(1, 2.0, 41.0)];
        t.collisions = vec![mark(1, 3.0, 60.0)];
        t
    }

    #[test]
    fn both_views_render_valid_and_deterministic() {
        let tracks = tracks();
        for view in [View::TimeSpace, View::SpeedField] {
            let figure = LaneFigure {
                tracks: &tracks,
                view,
                title: "bk-pbs, α = 0.5".into(),
            };
            assert_valid_and_deterministic(|| figure.render());
        }
    }
}
