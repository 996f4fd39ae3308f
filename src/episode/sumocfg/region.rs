//! One merge region of a scenario: its road frame, its planner, this step's scene and the
//! commands for it, where the planner takes CAVs over and hands them back, and its
//! trajectories.

use crate::config::Config;
use crate::controller::{CavHandling, Command, Controller};
use crate::episode::gui::GuiColours;
use crate::episode::trace::Tracer;
use crate::episode::trajectories::{Sent, TrajectoryLog, TrajectoryRow};
use crate::episode::Observer;
use crate::model::road::Road;
use crate::model::scene::Kind;
use crate::sumo::frame::{self, SumoScene};
use crate::sumo::RawVehicleState;

use super::merge_edges;

/// One merge region: its frame, its planner, this step's scene and commands.
pub struct Region {
    /// The region's configuration: the episode's, `v_max` capped at the region's limit.
    pub config: Config,
    pub road: Road,
    /// Its own planner; `None` when the episode's [`super::round::Round`] plans every region
    /// together.
    pub controller: Option<Box<dyn Controller>>,
    pub(super) scene: SumoScene,
    pub(super) commands: Vec<Command>,
    /// Frame `s` from which the planner drives CAVs: the end of the region's first edge.
    pub(super) control_start: f64,
    /// Frame `s` up to which it drives them (their fronts): the start of the region's last
    /// edge, or the region's end where that edge holds a merge zone's end.
    pub(super) control_end: f64,
    /// Its edges' codes start here in the codes registered with SUMO.
    pub(super) code_offset: i32,
    /// The edges its on-ramps join, its name in the results.
    pub(super) name: String,
    /// Its vehicles' trajectories, in its own road frame, when `output.trajectories` asks.
    pub(super) log: Option<TrajectoryLog>,
    /// The trajectory row of each scene vehicle in the current step.
    pub(super) log_rows: Vec<usize>,
    /// Its planners' trace (`trace.jsonl`), when `output.trace` asks.
    pub(super) trace: Option<Tracer>,
    /// Its CAVs' colours in sumo-gui, when `sumo.gui` shows the episode there.
    pub(super) gui: Option<GuiColours>,
}

impl Region {
    /// The region of `road`, planned by `controller` (or the episode's round) under `config`.
    pub fn new(config: Config, road: Road, mut controller: Option<Box<dyn Controller>>) -> Region {
        let trace = config.output.trace.then(|| Tracer::new(&config));
        let gui = config.sumo.gui.then(GuiColours::default);
        if let (Some(c), Some(t)) = (&mut controller, &trace) {
            c.set_tracing(t.wants_beliefs());
        }
        // The main edges come first in the frame: the second one starts where the first ends.
        let control_start = road
            .edges
            .get(1)
            .filter(|e| !e.on_ramp)
            .and_then(|e| e.lanes.iter().flatten().map(|l| l.s0).reduce(f64::min))
            .unwrap_or(0.0);
        let control_end = control_end(&road);
        let log = TrajectoryLog::new(config.output.trajectories);
        Region {
            control_end,
            scene: SumoScene::new(&road),
            name: merge_edges(&road).join(" "),
            config,
            road,
            controller,
            commands: Vec::new(),
            control_start,
            code_offset: 0,
            log,
            log_rows: Vec::new(),
            trace,
            gui,
        }
    }

    /// Whether a planner commands the region's CAVs (rather than leaving them to SUMO): a
    /// round's always do.
    pub(super) fn commanded(&self) -> bool {
        self.controller
            .as_ref()
            .is_none_or(|c| c.handling() == CavHandling::Commanded)
    }

    /// Records the vehicle just pushed into the scene: its reading and frame state, its own
    /// kind (a CAV SUMO drives is still a CAV here).
    pub(super) fn record(&mut self, raw: &RawVehicleState, kind: Kind) {
        let Some(log) = &mut self.log else {
            return;
        };
        let v = self.scene.scene.vehicles.last().expect("just pushed");
        let identity = (v.id.clone(), kind, v.origin);
        let row = TrajectoryRow::of_reading(&self.road, identity, raw, Some(v));
        self.log_rows.push(log.push(row));
    }

    /// The maneuvers just sent, into the trajectory rows of their CAVs.
    pub(super) fn record_sent(&mut self) {
        let Some(log) = &mut self.log else {
            return;
        };
        for c in &self.commands {
            log.set_sent(
                self.log_rows[c.vehicle],
                Sent {
                    speed: frame::commanded_speed(c.maneuver.speed, &self.config.scenario),
                    lane_change: c.maneuver.lane_change,
                    source: c.source,
                },
            );
        }
    }

    /// The reading with its edge code counted within this region, if it is on one of its edges.
    pub(super) fn local(&self, raw: &RawVehicleState) -> Option<RawVehicleState> {
        let code = raw.edge_code - self.code_offset;
        (raw.edge_code >= 0 && (0..self.road.edges.len() as i32).contains(&code)).then_some({
            RawVehicleState {
                edge_code: code,
                ..*raw
            }
        })
    }
}

/// Where the planner of `road`'s region stops driving CAVs: the start of its last edge, so that
/// SUMO takes a CAV back while the vehicles ahead of it are still in the region's scene. The
/// planner sees nobody past the region's end: a CAV planned up to there drove on, planning as if
/// the road ahead were empty, into a truck that had just left the region (SUMO's `ramp` game,
/// bk-mastar, seed 2: a controllable crash 12 m past the end, 0.6 s after the hand-back).
/// Where that edge holds the end of a merge zone, the region's end.
fn control_end(road: &Road) -> f64 {
    let region_end = road.section_end;
    let last_start = road
        .edge(&road.end_edge.0)
        .and_then(|e| e.lanes.iter().flatten().map(|l| l.s0).reduce(f64::min))
        .unwrap_or(region_end);
    let merges_end = road.zones.iter().map(|z| z.end).fold(f64::MIN, f64::max);
    if last_start >= merges_end {
        last_start
    } else {
        region_end
    }
}
