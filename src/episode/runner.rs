//! An episode of the paper's generated demand on its merge: the demand is the source of
//! traffic ([`TrafficSource`]) of the one lock-step loop ([`Lockstep`]), its merge one region planned
//! by the chosen controller.
//!
//! What the demand does its own way: its entry gate inserts the vehicles the demand scheduled,
//! the planner takes every CAV over as SUMO inserts it, each HDV drives at its drawn desired
//! speed and a ramp HDV changes lanes only when the merge rule says, every vehicle is seen with
//! the config's size, and the [`Ledger`] books each scheduled departure (a vehicle never
//! inserted included) and the distance each covered.

use std::time::Instant;

use crate::config::Config;
use crate::controller::{self, Controller};
use crate::episode::control;
use crate::episode::demand::{self, PlannedVehicle};
use crate::episode::entry::EntryControl;
use crate::episode::error::EpisodeError;
use crate::episode::ledger::{Departure, Expected, Ledger, Tracked};
use crate::episode::lockstep::{Lockstep, TrafficSource};
use crate::episode::merge_rule::RampMergeRule;
use crate::episode::metrics::{CollisionEvent, Outcome, SummaryInput, Timing, VehicleRecord};
use crate::episode::observer::{NoObserver, Observer};
use crate::episode::planning::Planning;
use crate::episode::region::Region;
use crate::episode::round::Round;
use crate::episode::summary::Summary;
use crate::episode::trajectories::{TrajectoryFile, TrajectoryRow};
use crate::model::road::Road;
use crate::model::scene::{Kind, Origin};
use crate::sumo::files::EpisodeInput;
use crate::sumo::frame;
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
/// the road, a controller the caller built (staged scenes, probes in tests, training rollouts),
/// or a round deciding from outside (the stepped RL environment).
pub enum Driver<'a> {
    /// The planner of this name (one of [`controller::PLANNERS`]).
    Named(&'a str),
    /// This controller, which the caller keeps.
    Given(&'a mut dyn Controller),
    /// This round, as on a user's scenario; the name is the planner column of the rows.
    Round(&'a str, Box<dyn Round>),
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
        let (name, planners) = match driver {
            Driver::Named(name) => {
                let c = controller::by_name(name, config, &road)?;
                (c.name(), Planners::Own(c))
            }
            Driver::Given(c) => (c.name(), Planners::Own(Box::new(c))),
            Driver::Round(name, round) => (name, Planners::Round(round)),
        };
        let mut episode = demand_episode(config, planned, road, planners, Box::new(observer));
        episode.run(sim, config)?;
        Ok(finish(episode, name))
    })();
    let sumo_log = capture.map(StderrCapture::finish).unwrap_or_default();
    let mut result = outcome.map_err(|e| e.with_sumo_log(sumo_log.clone()))?;
    result.sumo_log = sumo_log;
    result.timing.wall_s = wall.elapsed().as_secs_f64();
    Ok(result)
}

/// Who plans the merge's CAVs: its own controller, or a round from outside.
enum Planners<'a> {
    Own(Box<dyn Controller + 'a>),
    Round(Box<dyn Round>),
}

/// The episode of `planned` on the merge of `road`, `planners` driving its CAVs and `observer`
/// watching.
fn demand_episode<'a>(
    config: &'a Config,
    planned: &'a [PlannedVehicle],
    road: Road,
    planners: Planners<'a>,
    observer: Box<dyn Observer + 'a>,
) -> Lockstep<'a, Demand<'a>> {
    let demand = Demand::new(config, planned, &road);
    let (controller, round) = match planners {
        Planners::Own(c) => (Some(c), None),
        Planners::Round(r) => (None, Some(r)),
    };
    let region = Region::new(config.clone(), road, controller);
    let planning = Planning::new(vec![region], observer, round, config.scenario.steps);
    Lockstep::new(demand, planning)
}

/// The paper's generated demand on its merge, as the loop's source of traffic: the entry gate
/// inserts the demand's vehicles, the planner takes every CAV over as SUMO inserts it, ramp
/// HDVs change lanes only when the merge rule says, and the [`Ledger`] keeps the books.
struct Demand<'a> {
    config: &'a Config,
    entry: EntryControl,
    merge_rule: RampMergeRule,
    /// Who is where: every vehicle's record, the collisions.
    ledger: Ledger<'a>,
    /// Vehicles standing on the acceleration lane after the last step (a jam indicator).
    stranded: usize,
}

impl<'a> Demand<'a> {
    fn new(config: &'a Config, planned: &'a [PlannedVehicle], road: &Road) -> Self {
        Demand {
            config,
            entry: EntryControl::new(config, road, planned),
            merge_rule: RampMergeRule::new(config),
            ledger: Ledger::new(config, road, planned),
            stranded: 0,
        }
    }

    /// Sets how SUMO drives a vehicle just inserted: an HDV at its desired speed (a ramp HDV
    /// changing lanes only when the merge rule says), a commanded CAV exactly as commanded.
    fn take_control(
        sim: &mut impl SumoClient,
        id: &str,
        kind: Kind,
        expected: &Expected,
        commanded: bool,
    ) -> Result<(), SumoError> {
        match kind {
            Kind::Hdv => {
                sim.set_max_speed(id, expected.desired_speed)?;
                if expected.origin == Origin::Ramp {
                    control::ramp_hdv_waits_for_the_rule(sim, id)?;
                }
            }
            Kind::Cav if commanded => control::take_over(sim, id)?,
            Kind::Cav => {}
        }
        Ok(())
    }

    /// Asks SUMO, for every vehicle still in the network, how far it still has to go along
    /// its route: what it covered counts in its system delay.
    fn measure_remaining(&mut self, sim: &impl SumoClient, road: &Road) -> Result<(), SumoError> {
        let present: Vec<(usize, String, Option<usize>)> = self
            .ledger
            .present()
            .map(|(k, id, exit)| (k, id.to_string(), exit))
            .collect();
        for (k, id, exit) in present {
            let (edge, pos) = route_end(road, exit);
            let remaining = sim.driving_distance(&id, edge, pos)?;
            self.ledger.note_remaining(k, remaining);
        }
        Ok(())
    }
}

impl TrafficSource for Demand<'_> {
    /// Adds the vehicles the entry gate lets in at `now`.
    fn admit(
        &mut self,
        sim: &mut impl SumoClient,
        now: f64,
        regions: &[Region],
    ) -> Result<(), SumoError> {
        let (road, scene) = (&regions[0].road, &regions[0].scene.scene);
        for a in self.entry.admit(now, scene) {
            let v = &a.vehicle;
            let through = match v.origin {
                Origin::Main => road.first_through_lane(),
                Origin::Ramp => 0,
            };
            sim.add_vehicle(crate::sumo::NewVehicle {
                id: &v.id,
                route: &demand::route_name(road, v),
                type_id: v.kind.as_str(),
                lane: (v.depart_lane as usize + through) as i32,
                speed: a.speed,
            })?;
        }
        Ok(())
    }

    /// Opens a ledger line for each vehicle SUMO inserted in this step, after taking control
    /// of it.
    fn book_departures(
        &mut self,
        sim: &mut impl SumoClient,
        now: f64,
        regions: &[Region],
    ) -> Result<(), SumoError> {
        let road = &regions[0].road;
        let commanded = regions[0].commanded();
        for id in sim.departed()? {
            let sumo_type = sim.vehicle_type(&id)?;
            let kind = Kind::from_type_id(&sumo_type).unwrap_or(Kind::Hdv);
            let expected = self.ledger.expected(&id, now);
            Self::take_control(sim, &id, kind, &expected, commanded)?;
            let (end_edge, end_pos) = route_end(road, expected.exit);
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

    /// Told apart by their SUMO type (`cav`, `hdv`) or their line.
    fn kind_of(&self, id: &str, type_id: &str) -> Option<Kind> {
        Kind::from_type_id(type_id).or_else(|| self.ledger.kind_of(id))
    }

    /// Every vehicle of a collision is removed.
    fn removes(&self, _id: &str) -> bool {
        true
    }

    fn book_collisions(&mut self, events: Vec<CollisionEvent>, _now: f64) {
        self.ledger.book_collisions(events);
    }

    fn book_arrivals(&mut self, arrived: Vec<String>, now: f64) {
        self.ledger.book_arrivals(arrived, now);
    }

    /// The merge's scene from the readings: each reading of a vehicle on the section is noted
    /// in the ledger, recorded, and (unless it just crashed) put in the scene, with the
    /// config's vehicle size.
    fn build_scenes(
        &mut self,
        _sim: &mut impl SumoClient,
        readings: &VehicleReadings,
        regions: &mut [Region],
        now: f64,
    ) -> Result<(), SumoError> {
        let region = &mut regions[0];
        let sc = &self.config.scenario;
        self.ledger.match_readings(readings);
        for (i, raw) in readings.states.iter().enumerate() {
            let Some(k) = self.ledger.slot(i) else {
                continue;
            };
            let Some(position) = frame::frame_position(&region.road, raw) else {
                let row = trajectory_row(&region.road, self.ledger.tracked(k), raw, None);
                region.recording.push(row, false);
                continue;
            };
            let t = self.ledger.note_reading(k, now, position, raw.speed);
            // Removed from SUMO after this reading: not in the scene.
            let in_scene = t.record.outcome != Outcome::Crashed;
            if !in_scene && !region.recording.is_on() {
                continue;
            }
            // One translation into the road frame, for the scene and the trajectory row alike.
            let (front, lane) = position;
            let vehicle = frame::state_at(&region.road, sc, t.identity(), raw, front, lane);
            let row = trajectory_row(&region.road, t, raw, Some(&vehicle));
            region.recording.push(row, in_scene);
            if in_scene {
                region.scene.push(vehicle, raw.edge_code);
            }
        }
        Ok(())
    }

    /// The ramp HDVs' merge requests on this step's scene.
    fn before_plan(
        &mut self,
        sim: &mut impl SumoClient,
        regions: &[Region],
    ) -> Result<(), SumoError> {
        let scene = &regions[0].scene.scene;
        for m in self.merge_rule.requests(scene) {
            let v = &scene.vehicles[m.vehicle];
            if m.forced {
                control::ramp_hdv_forced(sim, &v.id)?;
            }
            sim.change_lane(&v.id, 1, self.config.scenario.dt)?;
        }
        Ok(())
    }

    /// The vehicles stranded on the acceleration lane, and how far each vehicle still in the
    /// network has to go.
    fn at_the_end(&mut self, sim: &impl SumoClient, regions: &[Region]) -> Result<(), SumoError> {
        self.stranded = standing_on_acceleration_lane(&regions[0].scene.scene);
        self.measure_remaining(sim, &regions[0].road)
    }
}

/// Vehicles standing on the acceleration lane: at the end, the stranded (a jam indicator).
fn standing_on_acceleration_lane(scene: &crate::model::scene::Scene) -> usize {
    (scene.vehicles.iter())
        .filter(|v| !v.on_ramp && scene.road.is_auxiliary(v.lane) && v.speed < 1.0)
        .count()
}

/// A reading of a vehicle of the ledger as a trajectory row (without the maneuver, which comes
/// after planning). `state` is the scene's own translation into the road frame, so the two
/// never disagree.
fn trajectory_row(
    road: &Road,
    who: &Tracked,
    raw: &crate::sumo::RawVehicleState,
    state: Option<&crate::model::scene::VehicleState>,
) -> TrajectoryRow {
    let record = &who.record;
    let identity = (who.id.clone(), record.kind, record.origin);
    TrajectoryRow::of_reading(road, identity, raw, state)
}

/// What the episode of `demand` produced, once SUMO has closed; `planner` names it.
fn finish(episode: Lockstep<'_, Demand<'_>>, planner: &str) -> EpisodeResult {
    let Lockstep {
        traffic,
        mut planning,
        ..
    } = episode;
    let sc = &traffic.config.scenario;
    let region = &planning.regions[0];
    // The time of the last state: a vehicle still in the network was last seen then.
    let end = region.scene.scene.time;
    let books = traffic.ledger.close(end);
    let summary = Summary::compute(&SummaryInput {
        planner,
        hdv_profile: &traffic.config.hdv.profile,
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
        stranded: traffic.stranded,
        plan_stats: planning.plan_stats,
    });
    let (vehicles_per_step, cavs_per_step) = planning.per_step();
    let (mut trajectories, mut traces) = planning.take_files();
    EpisodeResult {
        summary,
        vehicles: books.vehicles,
        collisions: books.collisions,
        timing: planning.timing.take().expect("timed when the episode ran"),
        trajectories: trajectories.pop().map(|(_, file)| file),
        sumo_log: String::new(),
        trace: traces.pop().map(|(_, text)| text),
        vehicles_per_step,
        cavs_per_step,
    }
}

#[cfg(test)]
#[path = "runner_tests.rs"]
mod tests;
