//! Collision forensics (`bkpbs explain`): for each collision of an episode directory, the last
//! seconds of both vehicles, step by step, from its `collisions.csv` and `trace.jsonl` (written
//! by `bkpbs episode --trace`).
//!
//! A CAV's rows show what SUMO reported (its traced state), the maneuver sent and where it came
//! from, the position its plan held for the next step and where it believed the other vehicle
//! would be. HDVs are not traced themselves: their rows show what the CAVs within range read
//! (pose 0 of their prediction, the state SUMO reported to the planner) and predicted.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::controller::Source;
use crate::episode::output::{write_atomic, WriteError};
use crate::episode::trace::{self, TraceError, TraceLine, TRACE_FILE};
use crate::model::road::Road;
use crate::report::plot::{Curve, LinePanel, LinePanels};

/// How far back before a collision the story starts (s).
pub const WINDOW_S: f64 = 3.0;

/// Times closer than this are the same step.
const SAME_TIME: f64 = 1e-6;

/// Why a directory could not be explained.
#[derive(Debug, thiserror::Error)]
pub enum ExplainError {
    /// The directory has no `collisions.csv`: it is not an episode directory.
    #[error("{dir} has no collisions.csv (not an episode directory; run `bkpbs episode --trace --out {dir}` first)")]
    NoCollisions {
        /// The directory given.
        dir: PathBuf,
    },
    /// The episode was run without `--trace`, so the CAVs' plans are unknown.
    #[error("{dir} has no trace.jsonl: re-run the episode with `bkpbs episode --trace --out {dir}` (same settings)")]
    NoTrace {
        /// The episode directory.
        dir: PathBuf,
    },
    /// `collisions.csv` could not be read or parsed.
    #[error("malformed {path}: {message}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// What the CSV reader reported.
        message: String,
    },
    /// `trace.jsonl` could not be read or parsed.
    #[error(transparent)]
    Trace(#[from] TraceError),
    /// A close-up figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] super::plot::PlotError),
    /// An output file could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// One row of `collisions.csv`.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
pub struct CollisionRow {
    /// Simulation time of the step SUMO detected the collision in (s; column `time_s`).
    #[serde(rename = "time_s")]
    pub time: f64,
    /// Id of the vehicle that drove into the other.
    pub collider: String,
    /// The collider's kind: `cav`, `hdv` or `unknown`.
    pub collider_type: String,
    /// Id of the vehicle that was hit.
    pub victim: String,
    /// The victim's kind: `cav`, `hdv` or `unknown`.
    pub victim_type: String,
    /// SUMO lane id where the collision happened.
    pub lane: String,
    /// Position along that SUMO lane (m from its start; column `position_m`).
    #[serde(rename = "position_m")]
    pub position: f64,
}

/// One vehicle at one step before a collision.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Simulation time of the step (s).
    pub time: f64,
    /// A CAV's own trace line at this step (none for HDVs).
    pub cav: Option<TraceLine>,
    /// HDVs: the CAV whose prediction it was seen in, and that prediction (`[s, y]` per step,
    /// pose 0 = the reading the planner got).
    pub seen_by: Option<(String, Vec<[f64; 2]>)>,
    /// CAVs: where it believed the other vehicle of the collision to be, per step.
    pub believed_other: Option<Vec<[f64; 2]>>,
}

impl Row {
    /// The position planned (CAV) or predicted (HDV) for the next step.
    pub fn next(&self) -> Option<[f64; 2]> {
        match (&self.cav, &self.seen_by) {
            (Some(l), _) => l.planned.as_ref().and_then(|p| p.get(1).copied()),
            (None, Some((_, p))) => p.get(1).copied(),
            _ => None,
        }
    }

    /// The maneuver's source (CAVs).
    pub fn source(&self) -> Option<Source> {
        self.cav.as_ref().map(|l| l.source)
    }
}

/// The last seconds of one vehicle of a collision.
#[derive(Debug, Clone, PartialEq)]
pub struct Story {
    /// The vehicle's id.
    pub id: String,
    /// `cav`, `hdv` or `unknown` (as in `collisions.csv`).
    pub kind: String,
    /// One row per traced step of the [`WINDOW_S`] before the collision (its own step
    /// excluded), in time order; a step where no trace line shows the vehicle has none.
    pub rows: Vec<Row>,
}

/// One collision and the stories of both vehicles.
#[derive(Debug, Clone, PartialEq)]
pub struct Explanation {
    /// 1-based, in the order of `collisions.csv`.
    pub number: usize,
    /// The collision's row of `collisions.csv`.
    pub collision: CollisionRow,
    /// The collider's story, then the victim's.
    pub stories: [Story; 2],
    /// Step length (s), from the trace's times.
    pub dt: f64,
    /// Lane width (m), from the trace's plans (the paper's road without any).
    pub lane_width: f64,
}

/// Reads `collisions.csv`.
pub fn read_collisions(path: &Path) -> Result<Vec<CollisionRow>, ExplainError> {
    let bad = |message: String| ExplainError::Csv {
        path: path.to_path_buf(),
        message,
    };
    let mut r = csv::Reader::from_reader(
        crate::io::bounded::open(path, crate::io::bounded::FileKind::Data)
            .map_err(|e| bad(e.to_string()))?,
    );
    r.deserialize()
        .map(|row| row.map_err(|e| bad(e.to_string())))
        .collect()
}

/// Reads `DIR/collisions.csv` and `DIR/trace.jsonl` and explains every collision.
pub fn explain_dir(dir: &Path) -> Result<Vec<Explanation>, ExplainError> {
    let (collisions, lines) = read_dir(dir)?;
    Ok(explain(&collisions, &lines))
}

/// The traced merge regions of an episode on a scenario of the user's own
/// (`<dir>/trajectories/<region>/` holding a `trace.jsonl`), in name order; none for any other
/// directory.
pub fn traced_regions(dir: &Path) -> Vec<PathBuf> {
    let mut found = crate::episode::sumocfg::region_dirs(dir);
    found.retain(|p| p.join(TRACE_FILE).is_file());
    found
}

/// [`explain_dir`] of one region's directory: the episode's collisions there (its
/// `collisions.csv` is the whole episode's) that a vehicle of the region's trace took part in,
/// a CAV the region planned or a vehicle one of them was checked against.
///
/// # Errors
/// As [`explain_dir`].
pub fn explain_region_dir(dir: &Path) -> Result<Vec<Explanation>, ExplainError> {
    let (collisions, lines) = read_dir(dir)?;
    let seen: std::collections::HashSet<&str> = lines
        .iter()
        .flat_map(|l| std::iter::once(l.id.as_str()).chain(l.others.iter().map(|o| o.id.as_str())))
        .collect();
    let here: Vec<CollisionRow> = collisions
        .into_iter()
        .filter(|c| seen.contains(c.collider.as_str()) || seen.contains(c.victim.as_str()))
        .collect();
    Ok(explain(&here, &lines))
}

/// The collisions and the trace of directory `dir`.
fn read_dir(dir: &Path) -> Result<(Vec<CollisionRow>, Vec<TraceLine>), ExplainError> {
    let collisions = dir.join("collisions.csv");
    if !collisions.is_file() {
        return Err(ExplainError::NoCollisions {
            dir: dir.to_path_buf(),
        });
    }
    let trace_path = dir.join(TRACE_FILE);
    if !trace_path.is_file() {
        return Err(ExplainError::NoTrace {
            dir: dir.to_path_buf(),
        });
    }
    let collisions = read_collisions(&collisions)?;
    let lines = trace::read(&trace_path)?;
    Ok((collisions, lines))
}

/// The step length of a trace: the smallest gap between its times (0.2 s without one).
fn step_length(lines: &[TraceLine]) -> f64 {
    let mut times: Vec<f64> = lines.iter().map(|l| l.time).collect();
    times.sort_by(f64::total_cmp);
    times
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > SAME_TIME)
        .fold(None, |m: Option<f64>, d| Some(m.map_or(d, |m| m.min(d))))
        .unwrap_or(0.2)
}

/// The lane width of a trace's road: a plan's pose 0 lies at `lane · width + lateral`.
fn lane_width(lines: &[TraceLine]) -> f64 {
    let mut widths: Vec<f64> = lines
        .iter()
        .filter(|l| l.state.lane != 0)
        .filter_map(|l| {
            let p0 = l.planned.as_ref()?.first()?;
            Some((p0[1] - l.state.lateral) / l.state.lane as f64)
        })
        .filter(|w| *w > 0.5)
        .collect();
    if widths.is_empty() {
        return Road::paper_default().lane_width;
    }
    widths.sort_by(f64::total_cmp);
    widths[widths.len() / 2]
}

/// Explains each collision from the trace lines.
pub fn explain(collisions: &[CollisionRow], lines: &[TraceLine]) -> Vec<Explanation> {
    let dt = step_length(lines);
    let lane_width = lane_width(lines);
    collisions
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let window: Vec<&TraceLine> = lines
                .iter()
                .filter(|l| l.time < c.time - SAME_TIME && l.time >= c.time - WINDOW_S - SAME_TIME)
                .collect();
            let a = story(&c.collider, &c.collider_type, &c.victim, &window);
            let b = story(&c.victim, &c.victim_type, &c.collider, &window);
            Explanation {
                number: k + 1,
                collision: c.clone(),
                stories: [a, b],
                dt,
                lane_width,
            }
        })
        .collect()
}

/// The distinct times of `window`, in order.
fn times(window: &[&TraceLine]) -> Vec<f64> {
    let mut t: Vec<f64> = window.iter().map(|l| l.time).collect();
    t.sort_by(f64::total_cmp);
    t.dedup_by(|a, b| (*a - *b).abs() < SAME_TIME);
    t
}

/// What `viewer` (a CAV's line) held about vehicle `id`.
fn seen_in(viewer: &TraceLine, id: &str) -> Option<Vec<[f64; 2]>> {
    viewer
        .others
        .iter()
        .find(|o| o.id == id)
        .map(|o| o.predicted.clone())
}

/// The rows of vehicle `id` (of type `kind`) over `window`; `other` is the vehicle it hit.
fn story(id: &str, kind: &str, other: &str, window: &[&TraceLine]) -> Story {
    let rows = times(window)
        .into_iter()
        .filter_map(|t| {
            let now: Vec<&TraceLine> = window
                .iter()
                .copied()
                .filter(|l| (l.time - t).abs() < SAME_TIME)
                .collect();
            if let Some(own) = now.iter().find(|l| l.id == id) {
                return Some(Row {
                    time: t,
                    cav: Some((*own).clone()),
                    seen_by: None,
                    believed_other: seen_in(own, other),
                });
            }
            // Seen by the other vehicle of the collision first, else by any CAV in range.
            let mut viewers = now.clone();
            viewers.sort_by_key(|l| l.id != other);
            let seen_by = viewers
                .iter()
                .find_map(|l| seen_in(l, id).map(|p| (l.id.clone(), p)))?;
            Some(Row {
                time: t,
                cav: None,
                seen_by: Some(seen_by),
                believed_other: None,
            })
        })
        .collect();
    Story {
        id: id.to_string(),
        kind: kind.to_string(),
        rows,
    }
}

fn pair(p: Option<[f64; 2]>) -> String {
    p.map_or_else(|| "—".to_string(), |[s, y]| format!("{s:8.2} {y:6.2}"))
}

/// The rows of a traced CAV.
fn format_cav(out: &mut String, story: &Story, other: &str) {
    let _ = writeln!(
        out,
        "{} (cav): SUMO's state, the maneuver sent and its source, the plan's next pose, \
         where it believed {other} would be next",
        story.id
    );
    let _ = writeln!(
        out,
        "  {:>6} {:>8} {:>4} {:>7} {:>6} | {:>6} {:>5} {:<13} | {:>16} | {:>15}",
        "t [s]",
        "s [m]",
        "lane",
        "lat [m]",
        "v",
        "sent v",
        "lc",
        "source",
        "planned next s y",
        "believed s y"
    );
    for r in &story.rows {
        let Some(l) = &r.cav else { continue };
        let believed = r
            .believed_other
            .as_ref()
            .map_or_else(|| "not seen".to_string(), |p| pair(p.get(1).copied()));
        let _ = writeln!(
            out,
            "  {:>6.2} {:>8.2} {:>4} {:>7.2} {:>6.2} | {:>6.2} {:>5} {:<13} | {:>16} | {:>15}",
            r.time,
            l.state.s,
            l.state.lane,
            l.state.lateral,
            l.state.speed,
            l.speed_sent,
            l.lane_change.as_deref().unwrap_or("-"),
            l.source.as_str(),
            pair(r.next()),
            believed
        );
    }
}

/// The rows of an HDV (or any vehicle without a trace of its own), as the CAVs saw it.
fn format_seen(out: &mut String, story: &Story, dt: f64) {
    let _ = writeln!(
        out,
        "{} ({}): not traced (only CAVs are); what SUMO reported is known only as the CAVs in \
         range read it (pose 0 of their prediction), next to what they predicted (v: the \
         predicted speed over the next step)",
        story.id, story.kind
    );
    let _ = writeln!(
        out,
        "  {:>6} {:>8} {:>6} {:<14} | {:>15} {:>6}",
        "t [s]", "s [m]", "y [m]", "seen by", "predicted next", "v"
    );
    for r in &story.rows {
        let Some((by, p)) = &r.seen_by else { continue };
        let [s, y] = p.first().copied().unwrap_or([f64::NAN, f64::NAN]);
        let v = r
            .next()
            .map_or_else(|| "—".into(), |n| format!("{:.2}", (n[0] - s) / dt));
        let _ = writeln!(
            out,
            "  {:>6.2} {:>8.2} {:>6.2} {:<14} | {:>15} {:>6}",
            r.time,
            s,
            y,
            by,
            pair(r.next()),
            v
        );
    }
}

/// The explanation as text: a heading, then the rows of both vehicles.
pub fn format(e: &Explanation) -> String {
    let c = &e.collision;
    let mut out = format!(
        "collision {} at t = {:.2} s: {} ({}) hit {} ({}) on {} at {:.2} m\n\
         the {WINDOW_S:.1} s before it (step {:.2} s; both vehicles were removed at the collision, \
         so its own step is not traced)\n",
        e.number,
        c.time,
        c.collider,
        c.collider_type,
        c.victim,
        c.victim_type,
        c.lane,
        c.position,
        e.dt
    );
    for (story, other) in [
        (&e.stories[0], &e.stories[1]),
        (&e.stories[1], &e.stories[0]),
    ] {
        out.push('\n');
        if story.rows.iter().any(|r| r.cav.is_some()) {
            format_cav(&mut out, story, &other.id);
        } else if story.rows.is_empty() {
            let _ = writeln!(
                out,
                "{} ({}): nothing traced in these {WINDOW_S:.1} s (a CAV is traced while a planner \
                 commands it, which `--planner sumo` never does; an HDV only as seen by a CAV \
                 within 60 m)",
                story.id, story.kind
            );
        } else {
            format_seen(&mut out, story, e.dt);
        }
    }
    out
}

/// Writes `explain_<n>.png` and `.svg` of each explanation into `dir`; returns their paths.
pub fn write_plots(dir: &Path, explanations: &[Explanation]) -> Result<Vec<PathBuf>, ExplainError> {
    let mut paths = Vec::new();
    for e in explanations {
        let fig = figure(e).render()?;
        let png = dir.join(format!("explain_{}.png", e.number));
        let svg = dir.join(format!("explain_{}.svg", e.number));
        write_atomic(&png, &fig.png)?;
        write_atomic(&svg, fig.svg.as_bytes())?;
        paths.extend([png, svg]);
    }
    Ok(paths)
}

/// Legend colours of the figure's curves.
const ACTUAL_CAV: usize = 0;
const PLANNED_CAV: usize = 1;
const READ_HDV: usize = 2;
const PREDICTED_HDV: usize = 3;

/// `(t, s)` and `(t, y)` of the poses of a trajectory starting at `t0`, up to `until`.
fn timed(poses: &[[f64; 2]], t0: f64, dt: f64, until: f64) -> [Vec<(f64, f64)>; 2] {
    let kept = poses
        .iter()
        .enumerate()
        .map(|(k, p)| (t0 + k as f64 * dt, p))
        .take_while(|(t, _)| *t <= until + SAME_TIME);
    let (mut s, mut y) = (Vec::new(), Vec::new());
    for (t, p) in kept {
        s.push((t, p[0]));
        y.push((t, p[1]));
    }
    [s, y]
}

/// The s–t and y–t curves of one vehicle: its actual course (thick) and each step's plan or
/// prediction (thin), up to the collision.
fn curves(e: &Explanation, story: &Story) -> [Vec<Curve>; 2] {
    let until = e.collision.time;
    let mut out: [Vec<Curve>; 2] = [Vec::new(), Vec::new()];
    let mut actual: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
    for r in &story.rows {
        let (now, ahead, colour) = match (&r.cav, &r.seen_by) {
            (Some(l), _) => {
                let y = l.state.lane as f64 * e.lane_width + l.state.lateral;
                ([l.state.s, y], l.planned.clone(), PLANNED_CAV)
            }
            (None, Some((_, p))) => (p[0], Some(p.clone()), PREDICTED_HDV),
            _ => continue,
        };
        actual[0].push((r.time, now[0]));
        actual[1].push((r.time, now[1]));
        let Some(ahead) = ahead else { continue };
        for (panel, points) in timed(&ahead, r.time, e.dt, until).into_iter().enumerate() {
            out[panel].push(Curve {
                points,
                colour,
                thick: false,
            });
        }
    }
    let colour = if story.rows.iter().any(|r| r.cav.is_some()) {
        ACTUAL_CAV
    } else {
        READ_HDV
    };
    for (panel, points) in actual.into_iter().enumerate() {
        out[panel].push(Curve {
            points,
            colour,
            thick: true,
        });
    }
    out
}

/// The figure of an explanation: per vehicle, s over t and y over t, planned vs actual.
pub fn figure(e: &Explanation) -> LinePanels {
    let mut panels = Vec::new();
    for story in &e.stories {
        let [s, y] = curves(e, story);
        for (curves, what, unit) in [(s, "position", "s [m]"), (y, "lateral position", "y [m]")] {
            panels.push(LinePanel {
                title: format!("{} ({}): {what}", story.id, story.kind),
                x_label: "t [s]".into(),
                y_label: unit.into(),
                curves,
                bands: Vec::new(),
                dots: Vec::new(),
                marks: vec![e.collision.time],
                x_range: Some(e.collision.time - WINDOW_S - e.dt..e.collision.time + e.dt),
            });
        }
    }
    let legend = [
        (ACTUAL_CAV, "CAV: SUMO's state", true),
        (PLANNED_CAV, "CAV: plan of each step", false),
        (READ_HDV, "HDV: as a CAV read it", true),
        (PREDICTED_HDV, "HDV: prediction of each step", false),
    ];
    LinePanels {
        panels,
        legend: legend
            .into_iter()
            .map(|(c, n, t)| (c, n.to_string(), t))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const COLLISIONS: &str =
        "time_s,collider,collider_type,victim,victim_type,lane,position_m,controllable
1.00,hdv.1,hdv,cav.0,cav,main_in_0,40.00,true
";

    /// cav.0 at 20 m/s planned straight on, hdv.1 behind it, seen by cav.0, 0.0 to 0.8 s.
    fn trace() -> String {
        (0..5)
            .map(|k| {
                let t = k as f64 * 0.2;
                let s = 20.0 + 4.0 * t * 5.0;
                let h = 10.0 + 6.0 * t * 5.0;
                let source = if k == 4 { "brake" } else { "pbs-solution" };
                format!(
                    r#"{{"time":{t:.1},"id":"cav.0","speed_sent":20.0,"lane_change":null,"source":"{source}","state":{{"s":{s},"lane":1,"lateral":0.0,"speed":20.0}},"planned":[[{s},4.5],[{},4.5]],"others":[{{"id":"hdv.1","kind":"hdv","predicted":[[{h},4.5],[{},4.5]]}}]}}"#,
                    s + 4.0,
                    h + 6.0
                )
            })
            .map(|l| l + "\n")
            .collect()
    }

    fn explained() -> Explanation {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("collisions.csv"), COLLISIONS).unwrap();
        std::fs::write(d.path().join(TRACE_FILE), trace()).unwrap();
        explain_dir(d.path()).unwrap().remove(0)
    }

    #[test]
    fn both_vehicles_have_their_rows_with_sources_and_beliefs() {
        let e = explained();
        assert!((e.dt - 0.2).abs() < 1e-9 && (e.lane_width - 4.5).abs() < 1e-9);
        let [hdv, cav] = &e.stories;
        assert_eq!((hdv.id.as_str(), cav.id.as_str()), ("hdv.1", "cav.0"));
        assert_eq!(cav.rows.len(), 5);
        assert_eq!(hdv.rows.len(), 5);
        assert_eq!(cav.rows[4].source(), Some(Source::Brake));
        assert_eq!(cav.rows[0].next(), Some([24.0, 4.5]));
        assert_eq!(hdv.rows[1].seen_by.as_ref().unwrap().0, "cav.0");
        assert_eq!(hdv.rows[1].next(), Some([22.0, 4.5]));
        let text = format(&e);
        println!("{text}");
        assert!(text.starts_with("collision 1 at t = 1.00 s: hdv.1 (hdv) hit cav.0 (cav)"));
        assert!(text.contains("hdv.1 (hdv): not traced"), "{text}");
        assert!(
            text.contains("where it believed hdv.1 would be next"),
            "{text}"
        );
        let row = text
            .lines()
            .find(|l| l.trim_start().starts_with("0.80") && l.contains("brake"));
        assert!(
            row.is_some_and(|r| r.contains("36.00") && r.contains("40.00")),
            "{text}"
        );
        assert_eq!(text.matches("pbs-solution").count(), 4, "{text}");
        let hdv_row = text
            .lines()
            .find(|l| l.trim_start().starts_with("0.20") && l.contains("cav.0"));
        assert!(
            hdv_row.is_some_and(|r| r.contains("16.00") && r.contains("22.00")),
            "{text}"
        );
    }

    #[test]
    fn only_the_window_before_the_collision_counts() {
        let lines = trace::parse(&trace(), Path::new("t")).unwrap();
        let mut c = read_collisions_text(COLLISIONS);
        c[0].time = 0.6;
        let e = explain(&c, &lines).remove(0);
        let times: Vec<f64> = e.stories[1].rows.iter().map(|r| r.time).collect();
        assert_eq!(times, vec![0.0, 0.2, 0.4]);
        let fig = figure(&e);
        assert_eq!(fig.panels.len(), 4);
        assert!(fig.panels[2]
            .curves
            .iter()
            .any(|c| c.thick && c.points.len() == 3));
    }

    fn read_collisions_text(text: &str) -> Vec<CollisionRow> {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("c.csv");
        std::fs::write(&p, text).unwrap();
        read_collisions(&p).unwrap()
    }

    #[test]
    fn a_directory_without_trace_or_collisions_is_named() {
        let d = tempfile::tempdir().unwrap();
        let e = explain_dir(d.path()).unwrap_err().to_string();
        assert!(e.contains("no collisions.csv"), "{e}");
        std::fs::write(d.path().join("collisions.csv"), COLLISIONS).unwrap();
        let e = explain_dir(d.path()).unwrap_err().to_string();
        assert!(e.contains("no trace.jsonl") && e.contains("--trace"), "{e}");
    }
}
