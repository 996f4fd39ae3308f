//! One episode: SUMO and a controller in lock-step for H steps, with every vehicle accounted for.
//!
//! Each step: SUMO advances; departures, collisions and arrivals are booked; every vehicle's state
//! is read in one call and turned into a [`Scene`]; ramp HDVs draw their merge decisions; the
//! controller plans; its maneuvers go back to SUMO as speed and lane-change commands.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use crate::config::{Config, ConfigError, TStarSpeed};
use crate::controller::{self, BuildError, CavHandling, Command, Controller, PlanStats};
use crate::episode::demand::{self, PlannedVehicle};
use crate::episode::entry::EntryControl;
use crate::episode::gui::GuiColours;
use crate::episode::merge_rule::RampMergeRule;
use crate::episode::metrics::{
    percentile, CollisionEvent, Outcome, Summary, SummaryInput, Timing, VehicleRecord,
};
use crate::episode::trajectories::{
    FrameState, Sent, TrajectoryFile, TrajectoryLog, TrajectoryRow,
};
use crate::model::kinematics::free_flow_time;
use crate::model::road::Road;
use crate::model::scene::{Kind, Origin, Scene};
use crate::sumo::files::{EpisodeInput, InputError};
use crate::sumo::frame::{self, NetworkError, SumoScene};
use crate::sumo::{RawVehicleState, Simulation, StderrCapture, SumoError, VehicleReadings};

/// SUMO speed mode for commanded CAVs: no checks at all, the commanded speed is the speed.
const SPEED_MODE_COMMANDED: i32 = 0;
/// SUMO lane-change mode for commanded CAVs: no own changes; requests obeyed without checks.
const LC_MODE_COMMANDED: i32 = 0;
/// SUMO lane-change mode for ramp HDVs: no own changes (the merge rule decides when), requests
/// executed only into safe gaps, adapting speed to find one.
const LC_MODE_RAMP_HDV: i32 = 0b10_0000_0000;
/// The same for a ramp HDV stuck at the lane end: requests executed avoiding only immediate
/// collisions (see `merge_rule`).
const LC_MODE_RAMP_HDV_FORCED: i32 = 0b01_0000_0000;

/// Why an episode could not complete.
#[derive(Debug, thiserror::Error)]
pub enum EpisodeError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error(transparent)]
    Input(#[from] InputError),
    #[error(transparent)]
    Controller(#[from] BuildError),
    #[error("cannot start SUMO on net {net}: {cause}")]
    Start {
        net: std::path::PathBuf,
        cause: SumoError,
    },
    #[error(transparent)]
    Road(#[from] NetworkError),
    #[error("SUMO failed at step {step} (t = {time:.1} s): {cause}")]
    Step {
        step: u32,
        time: f64,
        cause: SumoError,
    },
    /// `sumo.gui` asked for sumo-gui where it cannot run.
    #[error("cannot show the episode: {0}")]
    NoGui(String),
    /// A stop signal (Ctrl-C, `kill`) arrived: the episode ended early, SUMO was closed and
    /// its input removed; nothing was written.
    #[error("interrupted by {} at step {step}; nothing written", crate::io::interrupt::name(*.signal))]
    Interrupted { step: u32, signal: i32 },
    /// A failure with SUMO's own reason: libsumo reports only "Process Error", the reason goes
    /// to SUMO's (captured) console.
    #[error("{cause}; SUMO said: {said}")]
    Sumo {
        cause: Box<EpisodeError>,
        said: String,
        /// All SUMO printed, for `sumo.log`.
        log: String,
    },
}

impl EpisodeError {
    /// This error with SUMO's error messages from `log` (what it printed meanwhile), if any.
    pub fn with_sumo_log(self, log: String) -> EpisodeError {
        match sumo_errors(&log) {
            Some(said) => EpisodeError::Sumo {
                cause: Box::new(self),
                said,
                log,
            },
            None => self,
        }
    }

    /// What SUMO printed before the failure, when it said why.
    pub fn sumo_log(&self) -> Option<&str> {
        match self {
            EpisodeError::Sumo { log, .. } => Some(log),
            _ => None,
        }
    }
}

/// SUMO's `Error:` messages in `log`, with their indented continuation lines ("In file …"), on
/// one line.
pub fn sumo_errors(log: &str) -> Option<String> {
    let mut parts: Vec<&str> = Vec::new();
    let mut in_error = false;
    for line in log.lines() {
        if let Some(message) = line.strip_prefix("Error: ") {
            parts.push(message.trim());
            in_error = true;
        } else if in_error && line.starts_with(' ') && !line.trim().is_empty() {
            parts.push(line.trim());
        } else {
            in_error = false;
        }
    }
    (!parts.is_empty()).then(|| parts.join(" "))
}

/// What an episode produced.
#[derive(Debug, Clone)]
pub struct EpisodeResult {
    pub summary: Summary,
    pub vehicles: Vec<VehicleRecord>,
    pub collisions: Vec<CollisionEvent>,
    pub timing: Timing,
    /// One row per vehicle and step, when `output.trajectories` asks for them.
    pub trajectories: Option<TrajectoryFile>,
    /// What SUMO printed to stderr (captured unless `sumo.verbose`).
    pub sumo_log: String,
}

/// Who drives the CAVs: a planner by name, built by [`controller::by_name`] once SUMO has given
/// the road, or a controller the caller built (staged scenes, probes in tests).
pub enum Driver<'a> {
    Named(&'a str),
    Given(&'a mut dyn Controller),
}

/// Runs one episode of the planner `planner` with the demand drawn from the config's (λ, α, seed).
///
/// # Errors
/// An invalid config, an unknown planner or unusable predictor, or SUMO failing.
pub fn run(config: &Config, planner: &str) -> Result<EpisodeResult, EpisodeError> {
    config.validate()?;
    let planned = demand::generate_for(config)?;
    run_observed(config, Driver::Named(planner), &planned, &mut NoObserver)
}

/// Sees the scene of every step, before the controller plans: for recording data (e.g. the
/// predictor's training set) without touching the runner.
pub trait Observer {
    fn observe(&mut self, scene: &Scene);

    /// Sees what the controller decided in the step whose scene was just observed, and what it
    /// believed (when tracing; see [`Controller::set_tracing`]).
    fn planned(&mut self, _scene: &Scene, _commands: &[Command], _controller: &dyn Controller) {}

    /// Hears of each vehicle removed in a collision, in the step it happened (before the
    /// scene of that step is observed).
    fn removed_in_collision(&mut self, _id: &str) {}

    /// Whether [`Observer::planned`] needs the controller's beliefs (turns its tracing on).
    fn wants_beliefs(&self) -> bool {
        false
    }
}

/// An observer that looks away.
pub struct NoObserver;

impl Observer for NoObserver {
    fn observe(&mut self, _scene: &Scene) {}
}

/// Runs one episode of a controller the caller built, with a given demand (for staged scenes
/// and tests).
pub fn run_with_demand(
    config: &Config,
    controller: &mut dyn Controller,
    planned: &[PlannedVehicle],
) -> Result<EpisodeResult, EpisodeError> {
    run_observed(config, Driver::Given(controller), planned, &mut NoObserver)
}

/// Runs one episode with a given demand, showing every step's scene to `observer`.
pub fn run_observed(
    config: &Config,
    driver: Driver<'_>,
    planned: &[PlannedVehicle],
    observer: &mut dyn Observer,
) -> Result<EpisodeResult, EpisodeError> {
    let wall = Instant::now();
    if let Some(why) = config
        .sumo
        .gui
        .then(crate::sumo::files::gui_unavailable)
        .flatten()
    {
        return Err(EpisodeError::NoGui(why));
    }
    let road = frame::scenario_road(&config.scenario)?;
    let input = EpisodeInput::write(config, &road)?;
    let capture = if config.sumo.verbose {
        None
    } else {
        StderrCapture::start()
    };
    let outcome = (|| {
        let sim = Simulation::start(&input.command_line(config)).map_err(|cause| {
            EpisodeError::Start {
                net: config
                    .scenario
                    .net_file
                    .clone()
                    .unwrap_or_else(|| "(embedded)".into()),
                cause,
            }
        })?;
        let mut built;
        let controller: &mut dyn Controller = match driver {
            Driver::Named(name) => {
                built = controller::by_name(name, config, &road)?;
                built.as_mut()
            }
            Driver::Given(c) => c,
        };
        controller.set_tracing(observer.wants_beliefs());
        Episode::new(config, controller, planned, road, observer).run(sim)
    })();
    let sumo_log = capture.map(StderrCapture::finish).unwrap_or_default();
    let mut result = outcome.map_err(|e| e.with_sumo_log(sumo_log.clone()))?;
    result.sumo_log = sumo_log;
    result.timing.wall_s = wall.elapsed().as_secs_f64();
    Ok(result)
}

/// A reading as a trajectory row (without the maneuver, which comes after planning).
fn trajectory_row(
    road: &Road,
    sc: &crate::config::Scenario,
    id: &Arc<str>,
    record: &VehicleRecord,
    raw: &RawVehicleState,
    position: Option<(f64, i32)>,
) -> TrajectoryRow {
    TrajectoryRow {
        id: id.clone(),
        kind: record.kind,
        origin: record.origin,
        edge: usize::try_from(raw.edge_code)
            .ok()
            .and_then(|c| road.edges.get(c))
            .map(|e| e.name.clone()),
        sumo_lane: raw.lane_index,
        pos: raw.lane_position,
        x: raw.x,
        y: raw.y,
        angle: raw.angle,
        // The scene's own translation into the road frame, so the two never disagree.
        frame: position.map(|(front, lane)| {
            let who = frame::Identity {
                id: id.clone(),
                kind: record.kind,
                origin: record.origin,
                desired_speed: record.desired_speed,
            };
            let v = frame::state_at(road, sc, who, raw, front, lane);
            FrameState {
                s: v.s,
                lane: v.lane,
                lateral: v.lateral,
                heading: v.heading,
            }
        }),
        speed: raw.speed,
        accel: raw.acceleration,
        sent: None,
    }
}

/// Per-vehicle bookkeeping beyond the record.
struct Tracked {
    id: Arc<str>,
    record: VehicleRecord,
    last_time: f64,
    last_front: f64,
    last_speed: f64,
    /// It leaves by an off-ramp, outside the frame: it arrives when SUMO says so.
    leaves: bool,
}

struct Episode<'a> {
    config: &'a Config,
    controller: &'a mut dyn Controller,
    observer: &'a mut dyn Observer,
    planned: HashMap<&'a str, &'a PlannedVehicle>,
    scheduled: usize,
    road: Road,
    tracked: Vec<Tracked>,
    index: HashMap<Arc<str>, usize>,
    collisions: Vec<CollisionEvent>,
    merge_rule: RampMergeRule,
    entry: EntryControl,
    readings: VehicleReadings,
    /// Tracked index of each reading, valid for `slots_generation`.
    slots: Vec<Option<usize>>,
    slots_generation: u64,
    /// This step's scene, with the SUMO edge of each vehicle for the commands back.
    sumo_scene: SumoScene,
    commands: Vec<Command>,
    plan_ms: Vec<f64>,
    shield_ms: Vec<f64>,
    plan_stats: PlanStats,
    sumo_s: f64,
    speed_sum: f64,
    speed_samples: u64,
    trajectories: Option<TrajectoryLog>,
    /// The trajectory row of each scene vehicle in the current step.
    scene_rows: Vec<usize>,
    /// CAV colours in sumo-gui, when shown there.
    gui: Option<GuiColours>,
}

impl<'a> Episode<'a> {
    fn new(
        config: &'a Config,
        controller: &'a mut dyn Controller,
        planned: &'a [PlannedVehicle],
        road: Road,
        observer: &'a mut dyn Observer,
    ) -> Self {
        let entry = EntryControl::new(config, &road, planned);
        Episode {
            config,
            controller,
            observer,
            planned: planned.iter().map(|p| (p.id.as_str(), p)).collect(),
            scheduled: planned.len(),
            sumo_scene: SumoScene::new(&road),
            road,
            tracked: Vec::new(),
            index: HashMap::new(),
            collisions: Vec::new(),
            merge_rule: RampMergeRule::new(config),
            entry,
            readings: VehicleReadings::default(),
            slots: Vec::new(),
            slots_generation: u64::MAX,
            commands: Vec::new(),
            plan_ms: Vec::with_capacity(config.scenario.steps as usize),
            shield_ms: Vec::with_capacity(config.scenario.steps as usize),
            plan_stats: PlanStats::default(),
            sumo_s: 0.0,
            speed_sum: 0.0,
            speed_samples: 0,
            trajectories: TrajectoryLog::new(config.output.trajectories),
            scene_rows: Vec::new(),
            gui: config.sumo.gui.then(GuiColours::default),
        }
    }

    fn run(&mut self, mut sim: Simulation) -> Result<EpisodeResult, EpisodeError> {
        let loop_start = Instant::now();
        let steps = self.config.scenario.steps;
        sim.set_edge_codes(&frame::edge_names(&self.road))
            .map_err(|cause| EpisodeError::Step {
                step: 0,
                time: 0.0,
                cause,
            })?;
        for step in 0..steps {
            if let Some(signal) = crate::io::interrupt::requested() {
                return Err(EpisodeError::Interrupted { step, signal });
            }
            let at = |cause| EpisodeError::Step {
                step,
                time: step as f64 * self.config.scenario.dt,
                cause,
            };
            self.step(&mut sim, step + 1 < steps).map_err(at)?;
        }
        let loop_s = loop_start.elapsed().as_secs_f64();
        // Vehicles standing on the acceleration lane at the end: a jam indicator.
        let ramp_queue_end = self
            .sumo_scene
            .scene
            .vehicles
            .iter()
            .filter(|v| !v.on_ramp && v.lane == crate::model::road::MERGE_LANE && v.speed < 1.0)
            .count();
        sim.close().map_err(|cause| EpisodeError::Step {
            step: steps,
            time: steps as f64 * self.config.scenario.dt,
            cause,
        })?;
        Ok(self.finish(loop_s, ramp_queue_end))
    }

    /// One SUMO step and, unless it is the last, one planning round.
    fn step(&mut self, sim: &mut Simulation, plan: bool) -> Result<(), SumoError> {
        // The time of the state this step produces, on SUMO's clock: SUMO's own outputs (FCD,
        // tripinfo, collisions) label the state after a step with the time the step started,
        // and a vehicle added now departs at this time. `sim.time()` after the step is one
        // step later.
        let now = sim.time()?;
        for a in self.entry.admit(now, &self.sumo_scene.scene) {
            let v = &a.vehicle;
            sim.add_vehicle(
                &v.id,
                &demand::route_name(&self.road, v),
                v.kind.as_str(),
                v.depart_lane as i32,
                a.speed,
            )?;
        }
        let t0 = Instant::now();
        sim.step()?;
        self.sumo_s += t0.elapsed().as_secs_f64();
        self.book_departures(sim, now)?;
        // Read before the collided vehicles are removed: their state at this time counts, as
        // in SUMO's own outputs (a vehicle may collide in the step it was inserted).
        sim.read_vehicles(&mut self.readings)?;
        self.book_collisions(sim, now)?;
        self.book_arrivals(sim, now)?;
        self.build_scene(now);
        self.observer.observe(&self.sumo_scene.scene);
        if !plan {
            return Ok(());
        }
        for m in self.merge_rule.requests(&self.sumo_scene.scene) {
            let v = &self.sumo_scene.scene.vehicles[m.vehicle];
            if m.forced {
                sim.set_lane_change_mode(&v.id, LC_MODE_RAMP_HDV_FORCED)?;
            }
            sim.change_lane(&v.id, 1, self.config.scenario.dt)?;
        }
        self.commands.clear();
        let t1 = Instant::now();
        self.controller
            .plan(&self.sumo_scene.scene, &mut self.commands);
        self.plan_ms.push(t1.elapsed().as_secs_f64() * 1e3);
        self.shield_ms.push(self.controller.last_shield_ms());
        self.plan_stats += self.controller.last_stats();
        self.observer
            .planned(&self.sumo_scene.scene, &self.commands, &*self.controller);
        if self.controller.handling() == CavHandling::Commanded {
            self.apply(sim)?;
            self.record_sent();
            if let Some(gui) = &mut self.gui {
                gui.update(sim, &self.sumo_scene.scene, &self.commands)?;
            }
        }
        Ok(())
    }

    fn book_departures(&mut self, sim: &mut Simulation, now: f64) -> Result<(), SumoError> {
        let commanded = self.controller.handling() == CavHandling::Commanded;
        for id in sim.departed()? {
            let sumo_type = sim.vehicle_type(&id)?;
            let kind = Kind::from_type_id(&sumo_type).unwrap_or(Kind::Hdv);
            let planned = self.planned.get(id.as_str()).copied();
            let origin = planned.map_or(Origin::Main, |p| p.origin);
            let desired = planned.map_or(self.config.scenario.v_max, |p| p.desired_speed);
            let speed = planned.map_or(0.0, |p| p.depart_speed);
            let scheduled_depart = planned.map_or(now, |p| p.depart);
            match kind {
                Kind::Hdv => {
                    sim.set_max_speed(&id, desired)?;
                    if origin == Origin::Ramp {
                        sim.set_lane_change_mode(&id, LC_MODE_RAMP_HDV)?;
                    }
                }
                Kind::Cav if commanded => {
                    sim.set_speed_mode(&id, SPEED_MODE_COMMANDED)?;
                    sim.set_lane_change_mode(&id, LC_MODE_COMMANDED)?;
                }
                Kind::Cav => {}
            }
            // To the end of its route: the section's end, or the end of its off-ramp.
            let exit = planned.and_then(|p| p.exit);
            let (end_edge, end_pos) = exit.map_or(&self.road.end_edge, |x| &self.road.exits[x].end);
            let distance = sim.driving_distance(&id, end_edge, *end_pos)?;
            let sc = &self.config.scenario;
            let record = VehicleRecord {
                id: id.clone(),
                kind,
                sumo_type,
                origin,
                scheduled_depart,
                scheduled_speed: speed,
                // Lane and speed are filled in from the first reading, in this same step.
                insert_lane: -1,
                insert_time: now,
                insert_speed: f64::NAN,
                desired_speed: desired,
                distance,
                t_star: free_flow_time(distance, speed, sc.free_flow_accel, sc.v_max),
                outcome: Outcome::Present,
                arrival_time: None,
                crash_time: None,
                crashed_with: Vec::new(),
                controllable_crash: false,
            };
            let key: Arc<str> = Arc::from(id.as_str());
            self.index.insert(key.clone(), self.tracked.len());
            self.tracked.push(Tracked {
                id: key,
                record,
                last_time: now,
                last_front: self.road.section_end - distance,
                last_speed: speed,
                leaves: exit.is_some(),
            });
        }
        Ok(())
    }

    fn book_collisions(&mut self, sim: &mut Simulation, now: f64) -> Result<(), SumoError> {
        let collisions = sim.collisions()?;
        let mut removed: Vec<&str> = Vec::new();
        for c in &collisions {
            for id in [c.collider.as_str(), c.victim.as_str()] {
                if !removed.contains(&id) {
                    sim.remove_vehicle(id)?;
                    self.observer.removed_in_collision(id);
                    removed.push(id);
                }
            }
        }
        for c in collisions {
            let kind_of = |id: &str, type_id: &str| {
                Kind::from_type_id(type_id)
                    .or_else(|| self.index.get(id).map(|&k| self.tracked[k].record.kind))
            };
            let event = CollisionEvent {
                time: now,
                collider_kind: kind_of(&c.collider, &c.collider_type),
                victim_kind: kind_of(&c.victim, &c.victim_type),
                collider: c.collider,
                victim: c.victim,
                lane: c.lane,
                position: c.position,
            };
            let controllable = event.controllable();
            for (me, other) in [
                (&event.collider, &event.victim),
                (&event.victim, &event.collider),
            ] {
                if let Some(&k) = self.index.get(me.as_str()) {
                    let r = &mut self.tracked[k].record;
                    r.outcome = Outcome::Crashed;
                    r.crash_time.get_or_insert(now);
                    r.crashed_with.push(other.clone());
                    r.controllable_crash |= controllable;
                }
            }
            self.collisions.push(event);
        }
        Ok(())
    }

    fn book_arrivals(&mut self, sim: &Simulation, now: f64) -> Result<(), SumoError> {
        let end = self.road.section_end;
        for id in sim.arrived()? {
            let Some(&k) = self.index.get(id.as_str()) else {
                continue;
            };
            let t = &mut self.tracked[k];
            if t.record.outcome != Outcome::Present {
                continue; // SUMO 1.15 lists vehicles removed by a collision as arrived too
            }
            // The front crossed the end within the last step: interpolate at the last speed.
            let remaining = (end - t.last_front).max(0.0);
            let crossing = if t.leaves {
                now
            } else if t.last_speed > 0.1 {
                (t.last_time + remaining / t.last_speed).min(now)
            } else {
                now
            };
            t.record.outcome = Outcome::Arrived;
            t.record.arrival_time = Some(crossing.max(t.last_time));
        }
        Ok(())
    }

    fn build_scene(&mut self, now: f64) {
        if self.slots_generation != self.readings.generation {
            self.slots.clear();
            self.slots.extend(
                self.readings
                    .ids
                    .iter()
                    .map(|id| self.index.get(id.as_str()).copied()),
            );
            self.slots_generation = self.readings.generation;
        }
        let sc = &self.config.scenario;
        self.sumo_scene.clear(now);
        self.scene_rows.clear();
        if let Some(log) = &mut self.trajectories {
            log.begin_step(now);
        }
        for (raw, slot) in self.readings.states.iter().zip(&self.slots) {
            let Some(k) = *slot else { continue };
            let position = frame::frame_position(&self.road, raw);
            let row = self.trajectories.as_mut().map(|log| {
                let r = &self.tracked[k].record;
                let id = &self.tracked[k].id;
                log.push(trajectory_row(&self.road, sc, id, r, raw, position))
            });
            let Some((front, lane)) = position else {
                continue;
            };
            let t = &mut self.tracked[k];
            if t.record.insert_lane < 0 {
                t.record.insert_lane = lane;
                t.record.insert_speed = raw.speed;
                if self.config.metrics.t_star_speed == TStarSpeed::Inserted {
                    let r = &mut t.record;
                    r.t_star = free_flow_time(r.distance, raw.speed, sc.free_flow_accel, sc.v_max);
                }
            }
            t.last_time = now;
            t.last_front = front;
            t.last_speed = raw.speed;
            self.speed_sum += raw.speed;
            self.speed_samples += 1;
            if t.record.outcome == Outcome::Crashed {
                continue; // removed from SUMO after this reading: not in the scene
            }
            let who = frame::Identity {
                id: t.id.clone(),
                kind: t.record.kind,
                origin: t.record.origin,
                desired_speed: t.record.desired_speed,
            };
            let vehicle = frame::state_at(&self.road, sc, who, raw, front, lane);
            self.sumo_scene.push(vehicle, raw.edge_code);
            self.scene_rows.extend(row);
        }
    }

    /// The maneuvers just sent, into the trajectory rows of their CAVs.
    fn record_sent(&mut self) {
        let Some(log) = &mut self.trajectories else {
            return;
        };
        let sc = &self.config.scenario;
        for c in &self.commands {
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

    fn apply(&mut self, sim: &mut Simulation) -> Result<(), SumoError> {
        let sc = &self.config.scenario;
        let vehicles = &self.sumo_scene.scene.vehicles;
        sim.set_speeds(self.commands.iter().map(|c| {
            let speed = frame::commanded_speed(c.maneuver.speed, sc);
            (&*vehicles[c.vehicle].id, speed)
        }))?;
        for c in &self.commands {
            let v = &vehicles[c.vehicle];
            if let Some(dir) = c.maneuver.lane_change {
                let target = v.lane + dir.offset();
                if let Some(idx) = self.sumo_scene.sumo_lane_index(c.vehicle, target) {
                    sim.change_lane(&v.id, idx, self.config.scenario.dt)?;
                }
            }
        }
        Ok(())
    }

    fn finish(&mut self, loop_s: f64, ramp_queue_end: usize) -> EpisodeResult {
        let sc = &self.config.scenario;
        let vehicles: Vec<VehicleRecord> = self.tracked.iter().map(|t| t.record.clone()).collect();
        let summary = Summary::compute(&SummaryInput {
            planner: self.controller.name(),
            hdv_profile: &self.config.hdv.profile,
            alpha: sc.alpha,
            lambda: sc.lambda,
            seed: sc.seed,
            steps: sc.steps,
            dt: sc.dt,
            scheduled: self.scheduled,
            vehicles: &vehicles,
            collisions: &self.collisions,
            speed_sum: self.speed_sum,
            speed_samples: self.speed_samples,
            ramp_queue_end,
            plan_stats: self.plan_stats,
        });
        let mut plan = std::mem::take(&mut self.plan_ms);
        let mut shield = std::mem::take(&mut self.shield_ms);
        let plan_ms_total = plan.iter().sum();
        let timing = Timing {
            plan_ms_median: percentile(&mut plan, 50.0),
            plan_ms_p99: percentile(&mut plan, 99.0),
            plan_ms_max: plan.last().copied().unwrap_or(0.0),
            plan_ms_total,
            sumo_ms_per_step: self.sumo_s * 1e3 / sc.steps as f64,
            episode_ms_per_step: loop_s * 1e3 / sc.steps as f64,
            wall_s: 0.0,
            shield_ms_median: percentile(&mut shield, 50.0),
            shield_ms_p99: percentile(&mut shield, 99.0),
            shield_ms_max: shield.last().copied().unwrap_or(0.0),
        };
        EpisodeResult {
            summary,
            vehicles,
            collisions: std::mem::take(&mut self.collisions),
            timing,
            trajectories: self.trajectories.take().map(TrajectoryLog::finish),
            sumo_log: String::new(),
        }
    }
}

#[cfg(test)]
mod sumo_error_tests {
    use super::*;

    #[test]
    fn sumo_errors_are_read_off_sumo_s_console() {
        let log = "Warning: something\nError: invalid document structure\n In file 'x.net.xml'\n \
                   At line/column 2/1.\n\nQuitting (on error).\n";
        assert_eq!(
            sumo_errors(log).unwrap(),
            "invalid document structure In file 'x.net.xml' At line/column 2/1."
        );
        assert_eq!(sumo_errors("Warning: only this\n"), None);
    }
}
