//! The episode's recording of trajectories: each step, every reading becomes a
//! [`TrajectoryRow`], and the rows of the vehicles in the scene are remembered so that the
//! maneuvers sent after planning land on the right rows.
//!
//! It exists to keep the translation from SUMO's readings to `trajectories.csv` (and its FCD
//! twin) out of the lock-step loop, which only says what it read and what it sent. The
//! planner's trace (`trace.jsonl`) is not recorded here: it is an
//! [`Observer`](crate::episode::Observer), [`Tracer`](crate::episode::trace::Tracer).

use crate::config::{Scenario, TrajectoryFormat};
use crate::controller::Command;
use crate::episode::trajectories::{Sent, TrajectoryFile, TrajectoryLog, TrajectoryRow};
use crate::sumo::frame;

/// The trajectory rows of an episode, when `output.trajectories` asks for them.
pub struct Recording {
    log: Option<TrajectoryLog>,
    /// The trajectory row of each scene vehicle in the current step.
    scene_rows: Vec<usize>,
}

impl Recording {
    /// A recording in `format`; one that records nothing for [`TrajectoryFormat::None`].
    pub fn new(format: TrajectoryFormat) -> Self {
        Recording {
            log: TrajectoryLog::new(format),
            scene_rows: Vec::new(),
        }
    }

    /// Whether rows are recorded at all.
    pub fn is_on(&self) -> bool {
        self.log.is_some()
    }

    /// Starts the rows of the step whose state is labelled `time` (SUMO's clock).
    pub fn begin_step(&mut self, time: f64) {
        self.scene_rows.clear();
        if let Some(log) = &mut self.log {
            log.begin_step(time);
        }
    }

    /// Records a reading's `row` ([`TrajectoryRow::of_reading`]); `in_scene` when it is the
    /// scene's next vehicle, whose maneuver will be sent.
    pub fn push(&mut self, row: TrajectoryRow, in_scene: bool) {
        let Some(log) = &mut self.log else {
            return;
        };
        let row = log.push(row);
        if in_scene {
            self.scene_rows.push(row);
        }
    }

    /// The maneuvers just sent, into the trajectory rows of their CAVs.
    pub fn record_sent(&mut self, commands: &[Command], sc: &Scenario) {
        let Some(log) = &mut self.log else {
            return;
        };
        for c in commands {
            log.set_sent(
                self.scene_rows[c.vehicle],
                Sent {
                    speed: frame::commanded_speed(c.maneuver.speed, sc),
                    lane_change: c.maneuver.lane_change,
                    source: c.source,
                },
            );
        }
    }

    /// The whole trajectory file, if one was recorded.
    pub fn finish(self) -> Option<TrajectoryFile> {
        self.log.map(TrajectoryLog::finish)
    }
}
