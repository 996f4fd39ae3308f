//! One episode: SUMO and a controller in lock-step for H steps, with every vehicle accounted for.
//!
//! Each step: SUMO advances; departures, collisions and arrivals are booked; every vehicle's state
//! is read in one call and turned into a
//! [`Scene`](crate::model::scene::Scene); ramp HDVs draw their merge decisions; the
//! controller plans; its maneuvers go back to SUMO as speed and lane-change commands.

use std::time::Instant;

use crate::config::Config;
use crate::controller::{self, CavHandling, Command, Controller, PlanStats};
use crate::episode::collisions::{take_collisions, Crashes};
use crate::episode::control;
use crate::episode::demand::{self, PlannedVehicle};
use crate::episode::entry::EntryControl;
use crate::episode::error::EpisodeError;
use crate::episode::gui::GuiColours;
use crate::episode::ledger::{Departure, Expected, Ledger};
use crate::episode::merge_rule::RampMergeRule;
use crate::episode::metrics::{CollisionEvent, Outcome, SummaryInput, Timing, VehicleRecord};
use crate::episode::observer::{NoObserver, Observer};
use crate::episode::recording::Recording;
use crate::episode::step_times::StepTimes;
use crate::episode::summary::Summary;
use crate::episode::trace::Tracer;
use crate::episode::trajectories::TrajectoryFile;
use crate::model::road::Road;
use crate::model::scene::{Kind, Origin};
use crate::sumo::files::EpisodeInput;
use crate::sumo::frame::{self, SumoScene};
use crate::sumo::{Simulation, StderrCapture, SumoClient, SumoError, VehicleReadings};

/// The end of a route: the section's end, or the end of off-ramp `exit`.
fn route_end(road: &Road, exit: Option<usize>) -> (&str, f64) {
    let (edge, pos) = exit.map_or(&road.end_edge, |x| &road.exits[x].end);
    (edge, *pos)
}

/// What an episode produced.
#[derive(Debug, Clone)]
pub struct EpisodeResult {
    /// The one-row summary (the `episode.csv` row).
    pub summary: Summary,
    /// One record per inserted vehicle, in order of departure, then one per vehicle never
    /// inserted, in the demand's order (the `vehicles.csv` rows).
    pub vehicles: Vec<VehicleRecord>,
    /// Every collision SUMO reported.
    pub collisions: Vec<CollisionEvent>,
    /// Wall-clock figures (differ from run to run; not in the summary).
    pub timing: Timing,
    /// One row per vehicle and step, when `output.trajectories` asks for them.
    pub trajectories: Option<TrajectoryFile>,
    /// What SUMO printed to stderr (captured unless `sumo.verbose`).
    pub sumo_log: String,
    /// The planner's trace (`trace.jsonl` text), when `output.trace` asks.
    pub trace: Option<String>,
    /// Vehicles in the scene per step, on average.
    pub vehicles_per_step: f64,
    /// CAVs in the scene per step, on average.
    pub cavs_per_step: f64,
}

/// Who drives the CAVs: a planner by name, built by [`controller::by_name`] once SUMO has given
/// the road, or a controller the caller built (staged scenes, probes in tests).
pub enum Driver<'a> {
    /// The planner of this name (one of [`controller::PLANNERS`]).
    Named(&'a str),
    /// This controller, which the caller keeps.
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
    let outcome = (|| -> Result<EpisodeResult, EpisodeError> {
        let sim = Simulation::start(&input.command_line(config), config.sumo.stall_limit())
            .map_err(|cause| EpisodeError::Start {
                net: config
                    .scenario
                    .net_file
                    .clone()
                    .unwrap_or_else(|| "(embedded)".into()),
                cause,
            })?;
        let mut built;
        let controller: &mut dyn Controller = match driver {
            Driver::Named(name) => {
                built = controller::by_name(name, config, &road)?;
                built.as_mut()
            }
            Driver::Given(c) => c,
        };
        let mut traced = Traced {
            observer,
            tracer: config.output.trace.then(|| Tracer::new(config)),
        };
        controller.set_tracing(traced.wants_beliefs());
        let mut result = Episode::new(config, controller, planned, road, &mut traced).run(sim)?;
        result.trace = traced.tracer.map(|t| t.text().to_string());
        Ok(result)
    })();
    let sumo_log = capture.map(StderrCapture::finish).unwrap_or_default();
    let mut result = outcome.map_err(|e| e.with_sumo_log(sumo_log.clone()))?;
    result.sumo_log = sumo_log;
    result.timing.wall_s = wall.elapsed().as_secs_f64();
    Ok(result)
}

/// The caller's observer and, when `output.trace` asks, the episode's own trace beside it.
struct Traced<'a> {
    observer: &'a mut dyn Observer,
    tracer: Option<Tracer>,
}

impl Observer for Traced<'_> {
    fn observe(&mut self, scene: &crate::model::scene::Scene) {
        self.observer.observe(scene);
    }
    fn planned(
        &mut self,
        scene: &crate::model::scene::Scene,
        commands: &[Command],
        c: &dyn Controller,
    ) {
        self.observer.planned(scene, commands, c);
        if let Some(t) = &mut self.tracer {
            t.planned(scene, commands, c);
        }
    }
    fn removed_in_collision(&mut self, id: &str) {
        self.observer.removed_in_collision(id);
    }
    fn wants_beliefs(&self) -> bool {
        self.observer.wants_beliefs() || self.tracer.is_some()
    }
}

/// The episode being run: the lock-step loop's own state, and the parts it composes.
struct Episode<'a> {
    config: &'a Config,
    controller: &'a mut dyn Controller,
    observer: &'a mut dyn Observer,
    road: Road,
    entry: EntryControl,
    merge_rule: RampMergeRule,
    readings: VehicleReadings,
    /// This step's scene, with the SUMO edge of each vehicle for the commands back.
    sumo_scene: SumoScene,
    commands: Vec<Command>,
    /// Who is where: every vehicle's record, the collisions.
    ledger: Ledger<'a>,
    /// The planner's search effort, over all rounds.
    plan_stats: PlanStats,
    times: StepTimes,
    recording: Recording,
    /// CAV colours in sumo-gui, when shown there.
    gui: Option<GuiColours>,
    /// Steps seen, and the vehicles and CAVs in their scenes.
    occupancy: (u64, u64, u64),
}

impl<'a> Episode<'a> {
    fn new(
        config: &'a Config,
        controller: &'a mut dyn Controller,
        planned: &'a [PlannedVehicle],
        road: Road,
        observer: &'a mut dyn Observer,
    ) -> Self {
        Episode {
            config,
            controller,
            observer,
            entry: EntryControl::new(config, &road, planned),
            merge_rule: RampMergeRule::new(config),
            readings: VehicleReadings::default(),
            sumo_scene: SumoScene::new(&road),
            commands: Vec::new(),
            ledger: Ledger::new(config, &road, planned),
            plan_stats: PlanStats::default(),
            times: StepTimes::new(config.scenario.steps),
            recording: Recording::new(config.output.trajectories),
            gui: config.sumo.gui.then(GuiColours::default),
            occupancy: (0, 0, 0),
            road,
        }
    }

    fn run(mut self, mut sim: Simulation) -> Result<EpisodeResult, EpisodeError> {
        let loop_start = Instant::now();
        let (config, road) = (self.config, self.road.clone());
        lock_step(&mut sim, &frame::edge_names(&road), config, |sim, plan| {
            // The time of the state this step produces, on SUMO's clock: SUMO's own outputs
            // (FCD, tripinfo, collisions) label the state after a step with the time the step
            // started, and a vehicle added now departs at this time. `sim.time()` after the
            // step is one step later.
            let now = sim.time()?;
            self.admit(sim, now)?;
            self.times.sumo_step(sim)?;
            self.after_step(sim, now, plan)
        })?;
        let steps = config.scenario.steps;
        let at = |step| step_error(config.scenario.dt, step);
        let loop_s = loop_start.elapsed().as_secs_f64();
        let stranded = self.standing_on_acceleration_lane();
        self.measure_remaining(&sim).map_err(at(steps))?;
        sim.close().map_err(at(steps))?;
        Ok(self.finish(loop_s, stranded))
    }

    /// Asks SUMO, for every vehicle still in the network, how far it still has to go along
    /// its route: what it covered counts in its system delay.
    fn measure_remaining(&mut self, sim: &impl SumoClient) -> Result<(), SumoError> {
        let present: Vec<(usize, String, Option<usize>)> = self
            .ledger
            .present()
            .map(|(k, id, exit)| (k, id.to_string(), exit))
            .collect();
        for (k, id, exit) in present {
            let (edge, pos) = route_end(&self.road, exit);
            let remaining = sim.driving_distance(&id, edge, pos)?;
            self.ledger.note_remaining(k, remaining);
        }
        Ok(())
    }

    /// Vehicles standing on the acceleration lane: at the end, the stranded (a jam indicator).
    fn standing_on_acceleration_lane(&self) -> usize {
        self.sumo_scene
            .scene
            .vehicles
            .iter()
            .filter(|v| !v.on_ramp && v.lane == crate::model::road::MERGE_LANE && v.speed < 1.0)
            .count()
    }

    /// What follows a SUMO step that began at `now`: departures, collisions and arrivals
    /// booked, the scene read and, when `plan` (not after the last step), one planning round.
    fn after_step(
        &mut self,
        sim: &mut impl SumoClient,
        now: f64,
        plan: bool,
    ) -> Result<(), SumoError> {
        self.book_departures(sim, now)?;
        // Read before the collided vehicles are removed: their state at this time counts, as
        // in SUMO's own outputs (a vehicle may collide in the step it was inserted).
        sim.read_vehicles(&mut self.readings)?;
        self.book_collisions(sim, now)?;
        self.ledger.book_arrivals(sim.arrived()?, now);
        self.build_scene(now);
        self.count_occupancy();
        self.observer.observe(&self.sumo_scene.scene);
        if plan {
            self.plan(sim)?;
        }
        Ok(())
    }

    /// Counts this step's scene: its vehicles and CAVs.
    fn count_occupancy(&mut self) {
        let vehicles = &self.sumo_scene.scene.vehicles;
        let cavs = vehicles.iter().filter(|v| v.kind == Kind::Cav).count();
        self.occupancy.0 += 1;
        self.occupancy.1 += vehicles.len() as u64;
        self.occupancy.2 += cavs as u64;
    }

    /// Adds the vehicles the entry gate lets in at `now`.
    fn admit(&mut self, sim: &mut impl SumoClient, now: f64) -> Result<(), SumoError> {
        for a in self.entry.admit(now, &self.sumo_scene.scene) {
            let v = &a.vehicle;
            let through = match v.origin {
                Origin::Main => self.road.first_through_lane(),
                Origin::Ramp => 0,
            };
            sim.add_vehicle(crate::sumo::NewVehicle {
                id: &v.id,
                route: &demand::route_name(&self.road, v),
                type_id: v.kind.as_str(),
                lane: (v.depart_lane as usize + through) as i32,
                speed: a.speed,
            })?;
        }
        Ok(())
    }

    /// One planning round on this step's scene: ramp HDVs' merge requests, then the
    /// controller's maneuvers, sent to SUMO when it commands the CAVs.
    fn plan(&mut self, sim: &mut impl SumoClient) -> Result<(), SumoError> {
        for m in self.merge_rule.requests(&self.sumo_scene.scene) {
            let v = &self.sumo_scene.scene.vehicles[m.vehicle];
            if m.forced {
                control::ramp_hdv_forced(sim, &v.id)?;
            }
            sim.change_lane(&v.id, 1, self.config.scenario.dt)?;
        }
        self.commands.clear();
        let scene = &self.sumo_scene.scene;
        self.times.plan(self.controller, scene, &mut self.commands);
        self.plan_stats += self.controller.last_stats();
        self.observer
            .planned(&self.sumo_scene.scene, &self.commands, &*self.controller);
        if self.controller.handling() == CavHandling::Commanded {
            self.apply(sim)?;
            self.recording
                .record_sent(&self.commands, &self.config.scenario);
            if let Some(gui) = &mut self.gui {
                gui.update(sim, &self.sumo_scene.scene, &self.commands)?;
            }
        }
        Ok(())
    }

    /// Opens a ledger line for each vehicle SUMO inserted in this step, after taking control
    /// of it.
    fn book_departures(&mut self, sim: &mut impl SumoClient, now: f64) -> Result<(), SumoError> {
        for id in sim.departed()? {
            let sumo_type = sim.vehicle_type(&id)?;
            let kind = Kind::from_type_id(&sumo_type).unwrap_or(Kind::Hdv);
            let expected = self.ledger.expected(&id, now);
            self.take_control(sim, &id, kind, &expected)?;
            let (end_edge, end_pos) = route_end(&self.road, expected.exit);
            let distance = sim.driving_distance(&id, end_edge, end_pos)?;
            let departure = Departure {
                id,
                sumo_type,
                kind,
                distance,
                expected,
            };
            self.ledger.book_departure(departure, now);
        }
        Ok(())
    }

    /// Sets how SUMO drives a vehicle just inserted: an HDV at its desired speed (a ramp HDV
    /// changing lanes only when the merge rule says), a commanded CAV exactly as commanded.
    fn take_control(
        &self,
        sim: &mut impl SumoClient,
        id: &str,
        kind: Kind,
        expected: &Expected,
    ) -> Result<(), SumoError> {
        match kind {
            Kind::Hdv => {
                sim.set_max_speed(id, expected.desired_speed)?;
                if expected.origin == Origin::Ramp {
                    control::ramp_hdv_waits_for_the_rule(sim, id)?;
                }
            }
            Kind::Cav if self.controller.handling() == CavHandling::Commanded => {
                control::take_over(sim, id)?;
            }
            Kind::Cav => {}
        }
        Ok(())
    }

    /// Removes the vehicles of this step's collisions from SUMO (telling the observer), then
    /// books the collisions.
    fn book_collisions(&mut self, sim: &mut impl SumoClient, now: f64) -> Result<(), SumoError> {
        let mut crashes = DemandCrashes {
            ledger: &self.ledger,
            observer: &mut *self.observer,
        };
        let events = take_collisions(sim, now, &mut crashes)?;
        self.ledger.book_collisions(events);
        Ok(())
    }

    /// This step's scene from the readings: each reading of a vehicle on the section is noted
    /// in the ledger, recorded, and (unless it just crashed) put in the scene.
    fn build_scene(&mut self, now: f64) {
        self.ledger.match_readings(&self.readings);
        let sc = &self.config.scenario;
        self.sumo_scene.clear(now);
        self.recording.begin_step(now);
        for (i, raw) in self.readings.states.iter().enumerate() {
            let Some(k) = self.ledger.slot(i) else {
                continue;
            };
            let Some(position) = frame::frame_position(&self.road, raw) else {
                let t = self.ledger.tracked(k);
                self.recording.push(&self.road, t, raw, None, false);
                continue;
            };
            let t = self.ledger.note_reading(k, now, position, raw.speed);
            // Removed from SUMO after this reading: not in the scene.
            let in_scene = t.record.outcome != Outcome::Crashed;
            if !in_scene && !self.recording.is_on() {
                continue;
            }
            // One translation into the road frame, for the scene and the trajectory row alike.
            let (front, lane) = position;
            let vehicle = frame::state_at(&self.road, sc, t.identity(), raw, front, lane);
            self.recording
                .push(&self.road, t, raw, Some(&vehicle), in_scene);
            if in_scene {
                self.sumo_scene.push(vehicle, raw.edge_code);
            }
        }
    }

    /// Sends the controller's maneuvers to SUMO.
    fn apply(&mut self, sim: &mut impl SumoClient) -> Result<(), SumoError> {
        send_commands(sim, &self.sumo_scene, &self.commands, &self.config.scenario)
    }

    fn finish(self, loop_s: f64, stranded: usize) -> EpisodeResult {
        let sc = &self.config.scenario;
        // The time of the last state: a vehicle still in the network was last seen then.
        let end = self.sumo_scene.scene.time;
        let books = self.ledger.close(end);
        let summary = Summary::compute(&SummaryInput {
            planner: self.controller.name(),
            hdv_profile: &self.config.hdv.profile,
            sumo_version: crate::sumo::version::BUILT,
            alpha: sc.alpha,
            lambda: sc.lambda,
            seed: sc.seed,
            steps: sc.steps,
            end,
            scheduled: books.scheduled,
            vehicles: &books.vehicles,
            collisions: &books.collisions,
            speed_sum: books.speed_sum,
            speed_samples: books.speed_samples,
            stranded,
            plan_stats: self.plan_stats,
        });
        let (steps, vehicles, cavs) = self.occupancy;
        let per_step = |n: u64| n as f64 / steps.max(1) as f64;
        EpisodeResult {
            summary,
            vehicles: books.vehicles,
            collisions: books.collisions,
            timing: self.times.timing(loop_s, sc.steps),
            trajectories: self.recording.finish(),
            sumo_log: String::new(),
            trace: None,
            vehicles_per_step: per_step(vehicles),
            cavs_per_step: per_step(cavs),
        }
    }
}

/// The paper demand's vehicles in a collision: told apart by their SUMO type (`cav`, `hdv`) or
/// their line, every one removed, the observer told.
struct DemandCrashes<'a, 'b> {
    ledger: &'a Ledger<'b>,
    observer: &'a mut dyn Observer,
}

impl Crashes for DemandCrashes<'_, '_> {
    fn kind_of(&self, id: &str, type_id: &str) -> Option<Kind> {
        Kind::from_type_id(type_id).or_else(|| self.ledger.kind_of(id))
    }
    fn removes(&self, _id: &str) -> bool {
        true
    }
    fn removed(&mut self, id: &str) {
        self.observer.removed_in_collision(id);
    }
}

/// Sends `commands` for the vehicles of `scene` to SUMO: speeds in one batch, then lane changes
/// (into the SUMO lane of the target frame lane, where there is one).
pub(crate) fn send_commands(
    sim: &mut impl SumoClient,
    scene: &SumoScene,
    commands: &[Command],
    sc: &crate::config::Scenario,
) -> Result<(), SumoError> {
    let vehicles = &scene.scene.vehicles;
    let speeds: Vec<(&str, f64)> = commands
        .iter()
        .map(|c| {
            let speed = frame::commanded_speed(c.maneuver.speed, sc);
            (&*vehicles[c.vehicle].id, speed)
        })
        .collect();
    sim.set_speeds(&speeds)?;
    for c in commands {
        let v = &vehicles[c.vehicle];
        if let Some(dir) = c.maneuver.lane_change {
            let target = v.lane + dir.offset();
            if let Some(idx) = scene.sumo_lane_index(c.vehicle, target) {
                sim.change_lane(&v.id, idx, sc.dt)?;
            }
        }
    }
    Ok(())
}

/// The error of SUMO failing at `step`, on a clock of `dt` seconds per step.
pub(crate) fn step_error(dt: f64, step: u32) -> impl Fn(SumoError) -> EpisodeError {
    move |cause| EpisodeError::Step {
        step,
        time: step as f64 * dt,
        cause,
    }
}

/// The lock-step loop of an episode: `scenario.steps` calls of `step` (told whether to plan:
/// not after the last), the frame's `edge_names` registered first (readings carry their
/// codes), and a stop signal seen between two steps ending it.
pub(crate) fn lock_step(
    sim: &mut Simulation,
    edge_names: &[&str],
    config: &Config,
    mut step: impl FnMut(&mut Simulation, bool) -> Result<(), SumoError>,
) -> Result<(), EpisodeError> {
    let steps = config.scenario.steps;
    let at = |step| step_error(config.scenario.dt, step);
    sim.set_edge_codes(edge_names).map_err(at(0))?;
    let mut progress = config.output.progress.then(|| {
        let user = crate::io::watchdog::user_stderr();
        crate::io::progress::Progress::on_fd("episode", steps.into(), "steps", user)
    });
    for k in 0..steps {
        if let Some(signal) = crate::io::interrupt::requested() {
            return Err(EpisodeError::Interrupted { step: k, signal });
        }
        step(sim, k + 1 < steps).map_err(at(k))?;
        if let Some(p) = &mut progress {
            p.advance(1);
        }
    }
    if let Some(p) = &progress {
        p.finish();
    }
    Ok(())
}

#[cfg(test)]
#[path = "runner_tests.rs"]
mod tests;
