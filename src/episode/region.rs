//! One merge region: its road frame, its planner, this step's scene and the commands for it,
//! where the planner takes CAVs over and hands them back, its trajectories and trace. The
//! paper's merge is one region whose planner drives every CAV from its insertion on; a user's
//! scenario has one per merge the network has (or the configuration selects).

use crate::config::Config;
use crate::controller::{CavHandling, Command, Controller};
use crate::episode::gui::GuiColours;
use crate::episode::nose::NoseCommitments;
use crate::episode::recording::Recording;
use crate::episode::trace::Tracer;
use crate::episode::trajectories::TrajectoryRow;
use crate::episode::Observer;
use crate::model::road::{EdgeFrame, Road};
use crate::model::scene::Kind;
use crate::sumo::frame::SumoScene;
use crate::sumo::RawVehicleState;

/// One merge region: its frame, its planner, this step's scene and commands.
pub struct Region<'a> {
    /// The region's configuration: the episode's, `v_max` capped at the region's limit on a
    /// user's scenario.
    pub config: Config,
    /// Its road frame.
    pub road: Road,
    /// Its own planner (owned, or the caller's); `None` when the episode's
    /// [`Round`](crate::episode::round::Round) plans every region together.
    pub controller: Option<Box<dyn Controller + 'a>>,
    pub(crate) scene: SumoScene,
    pub(crate) commands: Vec<Command>,
    /// Frame `s` from which the planner drives CAVs: the end of the region's first edge.
    pub(crate) control_start: f64,
    /// Frame `s` up to which it drives them (their fronts): the start of the region's last
    /// edge, or the region's end where that edge holds a merge zone's end.
    pub(crate) control_end: f64,
    /// Its edges' codes start here in the codes registered with SUMO.
    pub(crate) code_offset: i32,
    /// The edges its on-ramps join, its name in the results.
    pub(crate) name: String,
    /// Its vehicles' trajectories, in its own road frame, when `output.trajectories` asks.
    pub(crate) recording: Recording,
    /// Its planners' trace (`trace.jsonl`), when `output.trace` asks.
    pub(crate) trace: Option<Tracer>,
    /// Its CAVs' colours in sumo-gui, when `sumo.gui` shows the episode there.
    pub(crate) gui: Option<GuiColours>,
    /// Its CAVs committed to merging at a nose (`episode::nose`), carried from step to step.
    pub(crate) nose: NoseCommitments,
}

impl<'a> Region<'a> {
    /// The region of `road`, planned by `controller` (or the episode's round) under `config`.
    pub fn new(
        config: Config,
        road: Road,
        mut controller: Option<Box<dyn Controller + 'a>>,
    ) -> Region<'a> {
        let trace = config.output.trace.then(|| Tracer::new(&config));
        let gui = config.sumo.gui.then(GuiColours::default);
        if let (Some(c), Some(t)) = (&mut controller, &trace) {
            c.set_tracing(t.wants_beliefs());
        }
        let control_start = control_start(&road);
        let control_end = control_end(&road);
        let recording = Recording::new(config.output.trajectories);
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
            recording,
            trace,
            gui,
            nose: NoseCommitments::default(),
        }
    }

    /// Whether a planner commands the region's CAVs (rather than leaving them to SUMO): a
    /// round's always do.
    pub(crate) fn commanded(&self) -> bool {
        self.controller
            .as_ref()
            .is_none_or(|c| c.handling() == CavHandling::Commanded)
    }

    /// Records the vehicle just pushed into the scene: its reading and frame state, its own
    /// kind (a CAV SUMO drives is still a CAV here).
    pub(crate) fn record(&mut self, raw: &RawVehicleState, kind: Kind) {
        if !self.recording.is_on() {
            return;
        }
        let v = self.scene.scene.vehicles.last().expect("just pushed");
        let identity = (v.id.clone(), kind, v.origin);
        let row = TrajectoryRow::of_reading(&self.road, identity, raw, Some(v));
        self.recording.push(row, true);
    }

    /// The maneuvers just sent, into the trajectory rows of their CAVs.
    pub(crate) fn record_sent(&mut self) {
        (self.recording).record_sent(&self.commands, &self.config.scenario);
    }

    /// Starts the step whose state is labelled `time`: an empty scene, no rows yet.
    pub(crate) fn begin_step(&mut self, time: f64) {
        self.scene.clear(time);
        self.recording.begin_step(time);
    }

    /// The reading with its edge code counted within this region, if it is on one of its edges.
    pub(crate) fn local(&self, raw: &RawVehicleState) -> Option<RawVehicleState> {
        let code = raw.edge_code - self.code_offset;
        (raw.edge_code >= 0 && (0..self.road.edges.len() as i32).contains(&code)).then_some({
            RawVehicleState {
                edge_code: code,
                ..*raw
            }
        })
    }
}

/// The edges the region's on-ramps join: the first edge of each ramp's route off the ramp.
fn merge_edges(road: &Road) -> Vec<String> {
    let joins = road.entries.iter().skip(1).filter_map(|e| {
        e.route
            .iter()
            .find(|edge| road.edge(edge).is_some_and(|f| !f.on_ramp))
            .map(|edge| edge.to_string())
    });
    let drops = road.zones.iter().filter(|z| !z.ramp).filter_map(|z| {
        // The last carriageway edge holding the dropped lane: where it ends.
        let mut main = road
            .edges
            .iter()
            .filter(|e| !e.on_ramp && !e.name.starts_with(':'));
        let holds = |e: &&EdgeFrame| {
            e.lanes
                .iter()
                .flatten()
                .any(|l| l.lane == z.lane && l.s0 < z.end)
        };
        main.rfind(holds).map(|e| e.name.to_string())
    });
    joins.chain(drops).collect()
}

/// Frame `s` from which the planner drives CAVs: the end of the region's first edge (the main
/// edges come first in the frame: the second one starts where the first ends), or earlier,
/// where a ramp joins at the nose: a nose zone's length before the zone (clamped at the
/// region's start), so that main-road CAVs are planned with the ramp's. Where the first edge
/// ends at the nose, as it does where a user's network joins a ramp at a node, control began
/// only past it.
fn control_start(road: &Road) -> f64 {
    let second = road
        .edges
        .get(1)
        .filter(|e| !e.on_ramp)
        .and_then(|e| e.lanes.iter().flatten().map(|l| l.s0).reduce(f64::min))
        .unwrap_or(0.0);
    let noses = road.zones.iter().filter(|z| z.nose);
    let before_noses = noses
        .map(|z| z.start - (z.end - z.start))
        .fold(second, f64::min);
    before_noses.max(0.0)
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
