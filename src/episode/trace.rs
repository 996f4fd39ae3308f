//! `trace.jsonl`: one JSON line per step and CAV, for collision forensics (`bkpbs explain`).
//!
//! Each line holds what SUMO reported for the CAV (its state in the road frame), the speed and
//! lane change sent back, where that maneuver came from ([`Source`]), the trajectory the planner
//! planned for it and the trajectories it predicted (HDVs) or planned (CAVs) for the vehicles
//! within [`BELIEF_RANGE`](crate::controller::execute::BELIEF_RANGE) it was checked against.
//! Poses are `[s, y]` at steps of `scenario.dt`, pose 0 being the step's time; every number is
//! rounded to 2 decimals.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::config::{Config, Scenario};
use crate::controller::{CavBelief, Command, Controller, LaneChange, Source};
use crate::episode::Observer;
use crate::io::{write_atomic, WriteError};
use crate::model::scene::Scene;
use crate::model::trajectory::Trajectory;
use crate::sumo::frame;

/// The trace's file name in an episode directory.
pub const TRACE_FILE: &str = "trace.jsonl";

/// A CAV's state as SUMO reported it, in the road frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceState {
    /// Longitudinal position of the centre (m).
    pub s: f64,
    /// Road-frame lane (0 = ramp / acceleration lane).
    pub lane: i32,
    /// Offset from the lane centre (m, positive to the left).
    pub lateral: f64,
    /// Speed (m/s).
    pub speed: f64,
}

/// Another vehicle as the planner saw it: its predicted (HDV) or planned (CAV) trajectory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceOther {
    /// SUMO vehicle id.
    pub id: String,
    /// `cav` or `hdv`.
    pub kind: String,
    /// `[s, y]` per step, pose 0 at the line's time.
    pub predicted: Vec<[f64; 2]>,
}

/// One line of `trace.jsonl`: one CAV at one step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceLine {
    /// Time of the state (SUMO's clock, as in the CSV files).
    pub time: f64,
    /// SUMO id of the CAV.
    pub id: String,
    /// The speed sent to SUMO for the end of the next step (m/s).
    pub speed_sent: f64,
    /// `left`, `right` or null.
    pub lane_change: Option<String>,
    /// Where the maneuver came from.
    pub source: Source,
    /// The CAV's state as SUMO reported it at `time`.
    pub state: TraceState,
    /// `[s, y]` per step of the CAV's planned trajectory; null without a plan.
    pub planned: Option<Vec<[f64; 2]>>,
    /// The vehicles it was checked against (within the belief range); empty without beliefs.
    pub others: Vec<TraceOther>,
}

/// `x` rounded to 2 decimals.
fn r2(x: f64) -> f64 {
    (x * 100.0).round() / 100.0
}

fn poses(t: &Trajectory) -> Vec<[f64; 2]> {
    t.poses.iter().map(|p| [r2(p.s), r2(p.y)]).collect()
}

/// The trace line of `command`, given the scene it was planned on and the planner's belief
/// about that CAV (if it keeps any).
pub fn line(
    scene: &Scene,
    command: &Command,
    belief: Option<&CavBelief>,
    scenario: &Scenario,
) -> TraceLine {
    let v = &scene.vehicles[command.vehicle];
    let others = belief.map_or_else(Vec::new, |b| {
        b.others
            .iter()
            .map(|(j, t)| TraceOther {
                id: scene.vehicles[*j].id.to_string(),
                kind: scene.vehicles[*j].kind.as_str().to_string(),
                predicted: poses(t),
            })
            .collect()
    });
    TraceLine {
        time: r2(scene.time),
        id: v.id.to_string(),
        speed_sent: r2(frame::commanded_speed(command.maneuver.speed, scenario)),
        lane_change: command.maneuver.lane_change.map(|d| {
            match d {
                LaneChange::Left => "left",
                LaneChange::Right => "right",
            }
            .to_string()
        }),
        source: command.source,
        state: TraceState {
            s: r2(v.s),
            lane: v.lane,
            lateral: r2(v.lateral),
            speed: r2(v.speed),
        },
        planned: belief.and_then(|b| b.planned.as_ref()).map(poses),
        others,
    }
}

/// An [`Observer`] that records the trace of an episode in memory; [`Tracer::write`] saves it
/// once the episode has finished.
pub struct Tracer {
    scenario: Scenario,
    text: String,
}

impl Tracer {
    /// An empty trace for an episode of `config` (whose `scenario.v_max` bounds the speeds
    /// sent, as the runner bounds them).
    pub fn new(config: &Config) -> Self {
        Tracer {
            scenario: config.scenario.clone(),
            text: String::new(),
        }
    }

    /// The trace so far, one JSON line per step and CAV.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Writes `trace.jsonl` into `dir` (atomically); returns its path.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, WriteError> {
        let path = dir.join(TRACE_FILE);
        write_atomic(&path, self.text.as_bytes())?;
        Ok(path)
    }
}

impl Observer for Tracer {
    fn observe(&mut self, _scene: &Scene) {}

    fn planned(&mut self, scene: &Scene, commands: &[Command], controller: &dyn Controller) {
        let beliefs = controller.beliefs();
        for c in commands {
            let belief = beliefs.iter().find(|b| b.vehicle == c.vehicle);
            let l = line(scene, c, belief, &self.scenario);
            self.text
                .push_str(&serde_json::to_string(&l).expect("a trace line serializes"));
            self.text.push('\n');
        }
    }

    fn wants_beliefs(&self) -> bool {
        true
    }
}

/// Why a trace could not be read.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// The file could not be read.
    #[error("cannot read {path}: {cause}")]
    Read {
        /// The trace file.
        path: PathBuf,
        /// The I/O error.
        cause: std::io::Error,
    },
    /// A line is not a trace line.
    #[error("malformed {path}, line {line}: {cause}")]
    Parse {
        /// The trace file.
        path: PathBuf,
        /// Line number in the file (1 the first).
        line: usize,
        /// The JSON error.
        cause: serde_json::Error,
    },
}

/// Parses the lines of a trace (`path` names it in errors).
pub fn parse(text: &str, path: &Path) -> Result<Vec<TraceLine>, TraceError> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|cause| TraceError::Parse {
                path: path.to_path_buf(),
                line: i + 1,
                cause,
            })
        })
        .collect()
}

/// Reads `trace.jsonl` at `path`.
pub fn read(path: &Path) -> Result<Vec<TraceLine>, TraceError> {
    let text = crate::io::bounded::read_text(path, crate::io::bounded::FileKind::Data).map_err(
        |cause| TraceError::Read {
            path: path.to_path_buf(),
            cause,
        },
    )?;
    parse(&text, path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::Maneuver;
    use crate::model::scene::{Kind, Origin, VehicleState};

    fn scene() -> Scene {
        Scene::on_paper_road(
            12.4,
            vec![
                VehicleState::on_lane("cav.1", Kind::Cav, Origin::Main, 100.004, 1, 20.0),
                VehicleState::on_lane("hdv.2", Kind::Hdv, Origin::Main, 130.0, 1, 15.0),
                VehicleState::on_lane("hdv.far", Kind::Hdv, Origin::Main, 300.0, 1, 15.0),
            ],
        )
    }

    #[test]
    fn a_line_has_the_documented_fields_rounded() {
        let s = scene();
        let c = Command {
            vehicle: 0,
            maneuver: Maneuver {
                speed: 20.456,
                lane_change: Some(LaneChange::Left),
            },
            source: Source::PbsSolution,
        };
        let me = Trajectory::straight(100.004, 4.5, 20.0, 2, 0.2);
        let them = [
            (1, Trajectory::straight(130.0, 4.5, 15.0, 1, 0.2)),
            (2, Trajectory::straight(300.0, 4.5, 15.0, 1, 0.2)),
        ];
        let belief =
            crate::controller::execute::belief(&s, 0, Some(&me), them.iter().map(|(j, t)| (*j, t)));
        let l = line(&s, &c, Some(&belief), &Config::default().scenario);
        let json = serde_json::to_string(&l).unwrap();
        assert_eq!(
            json,
            r#"{"time":12.4,"id":"cav.1","speed_sent":20.46,"lane_change":"left","source":"pbs-solution","state":{"s":100.0,"lane":1,"lateral":0.0,"speed":20.0},"planned":[[100.0,4.5],[104.0,4.5],[108.0,4.5]],"others":[{"id":"hdv.2","kind":"hdv","predicted":[[130.0,4.5],[133.0,4.5]]}]}"#
        );
        let back = parse(&format!("{json}\n\n"), Path::new("t")).unwrap();
        assert_eq!(back, vec![l]);
    }

    #[test]
    fn a_controller_without_beliefs_gives_null_plan_and_no_others() {
        let s = scene();
        let c = Command {
            vehicle: 0,
            maneuver: Maneuver {
                speed: 50.0,
                lane_change: None,
            },
            source: Source::Rule,
        };
        let json = serde_json::to_string(&line(&s, &c, None, &Config::default().scenario)).unwrap();
        assert!(json.contains(r#""speed_sent":35.0"#), "{json}");
        assert!(json.contains(r#""lane_change":null"#), "{json}");
        assert!(json.contains(r#""planned":null,"others":[]"#), "{json}");
        let e = parse("{\"time\":1}\n", Path::new("x.jsonl")).unwrap_err();
        assert!(e.to_string().contains("x.jsonl, line 1"), "{e}");
    }
}
