//! An episode on a user's own SUMO scenario (`scenario.sumocfg`): SUMO loads the user's
//! configuration — net, routes, flows, vehicle types, additional files, their options — and
//! bkpbs adds only what it must ([`sumo_options`]). A seeded share α of the vehicles SUMO
//! inserts are CAVs, each decided when it departs on a random stream of its own (flows decide
//! their vehicles at run time, so the share is realised, not exact; `episode.csv` reports it).
//! Inside the planned merge region the chosen planner drives the CAVs; outside, SUMO drives
//! every vehicle on its type's own model, and the HDVs everywhere (no merge rule: the user's
//! drivers are the user's).
//!
//! Each vehicle is seen with its own type's length and width. A CAV whose route leaves the
//! region by an off-ramp, or that drives on a deceleration lane, is left to SUMO (the planners
//! keep CAVs on the carriageway and plan only its lanes and the merge lanes).
//!
//! Not yet: several regions in one episode, each vehicle's own speed and acceleration limits
//! and each lane's speed limit in the planner (CAVs are planned with `scenario.v_max`), the
//! system delay within the region; campaigns over scenarios.

mod records;

use std::collections::HashMap;
use std::path::PathBuf;

use rand::{Rng, SeedableRng};

use crate::config::Config;
use crate::controller::{self, CavHandling, Command};
use crate::episode::error::EpisodeError;
use crate::episode::metrics::CollisionEvent;
use crate::model::road::Road;
use crate::model::scene::{Kind, Origin};
use crate::sumo::frame::{self, SumoScene};
use crate::sumo::sumocfg::SumoConfig;
use crate::sumo::{Simulation, StderrCapture, SumoError, VehicleReadings};

pub use records::{csv_of, ScenarioSummary, ScenarioVehicle};

/// SUMO's defaults, restored when a CAV leaves the region: every safety check on, and its
/// own lane changes (SUMO's `speedMode` 31 and `laneChangeMode` 1621).
const SPEED_MODE_SUMO: i32 = 31;
const LC_MODE_SUMO: i32 = 0b110_0101_0101;

/// What an episode on a user's scenario produced.
#[derive(Debug, Clone)]
pub struct ScenarioResult {
    /// The `episode.csv` row.
    pub summary: ScenarioSummary,
    /// One row per vehicle SUMO inserted, in order of departure.
    pub vehicles: Vec<ScenarioVehicle>,
    /// Every collision SUMO reported.
    pub collisions: Vec<CollisionEvent>,
    /// The options bkpbs gave SUMO beside the user's configuration.
    pub sumo_options: Vec<String>,
    /// What SUMO printed to stderr.
    pub sumo_log: String,
}

/// The SUMO command line: the user's configuration, then what bkpbs must set — collisions
/// reported, not acted on (the episode removes both vehicles, as for its own demand); no
/// teleports (a jam stays a jam and every trip is accounted for); lane changes taking
/// `scenario.lane_change_duration` (the planners' primitives assume it); the episode's seed;
/// the tripinfo output bkpbs reads, unfinished trips included; SUMO's progress output off.
pub fn sumo_options(config: &Config, tripinfo: &std::path::Path) -> Vec<String> {
    let s = &config.scenario;
    [
        ("--collision.action", "warn".to_string()),
        ("--collision.check-junctions", "true".into()),
        ("--collision.mingap-factor", "0".into()),
        ("--time-to-teleport", "-1".into()),
        (
            "--lanechange.duration",
            format!("{}", s.lane_change_duration),
        ),
        ("--seed", format!("{}", s.seed % (i32::MAX as u64))),
        ("--tripinfo-output", tripinfo.display().to_string()),
        ("--tripinfo-output.write-unfinished", "true".into()),
        ("--verbose", "false".into()),
        ("--no-step-log", "true".into()),
        ("--duration-log.disable", "true".into()),
        ("--no-warnings", (!config.sumo.verbose).to_string()),
    ]
    .into_iter()
    .flat_map(|(k, v)| [k.to_string(), v])
    .collect()
}

/// Whether vehicle `id` is a CAV: a draw of probability α on a stream seeded by the
/// episode's seed and the id alone, so the answer does not depend on who departed before.
pub fn is_cav(seed: u64, id: &str, alpha: f64) -> bool {
    // FNV-1a of the id, mixed with the seed: a stable, platform-independent stream key.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325 ^ seed.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    for b in id.bytes() {
        h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
    }
    rand_chacha::ChaCha8Rng::seed_from_u64(h).gen_bool(alpha.clamp(0.0, 1.0))
}

/// Runs the scenario of `config.scenario.sumocfg` with `planner` driving the CAVs in its region.
///
/// # Errors
/// An unreadable configuration, a step length other than the planners', a network without the
/// region to plan, an unknown planner, or SUMO failing.
pub fn run(config: &Config, planner: &str) -> Result<ScenarioResult, EpisodeError> {
    config.validate()?;
    let path = config
        .scenario
        .sumocfg
        .clone()
        .expect("a scenario episode has a configuration");
    let cfg = SumoConfig::read(&path)?;
    cfg.check_step(config.scenario.dt)?;
    let road = frame::scenario_road(&config.scenario)?;
    // CAVs drive no faster than the carriageway allows where they enter it.
    let mut config = config.clone();
    config.scenario.v_max = config.scenario.v_max.min(road.entries[0].speed_limit);
    let config = &config;
    let dir = tempfile::Builder::new()
        .prefix(&format!("bkpbs-scenario-{}-", std::process::id()))
        .tempdir()
        .map_err(|cause| crate::sumo::files::InputError::Write {
            path: std::env::temp_dir(),
            cause,
        })?;
    let tripinfo = dir.path().join("tripinfo.xml");
    let options = sumo_options(config, &tripinfo);
    let mut args = vec!["sumo".to_string(), "-c".into(), path.display().to_string()];
    args.extend(options.iter().cloned());
    let capture = (!config.sumo.verbose).then(StderrCapture::start).flatten();
    let outcome = (|| {
        let sim = Simulation::start(&args).map_err(|cause| EpisodeError::Start {
            net: cfg.net.clone(),
            cause,
        })?;
        let mut built = controller::by_name(planner, config, &road)?;
        let mut run = ScenarioRun::new(config, built.as_mut(), road);
        run.run(sim)?;
        Ok::<_, EpisodeError>(run.finish(&tripinfo, options.clone()))
    })();
    let sumo_log = capture.map(StderrCapture::finish).unwrap_or_default();
    let mut result = outcome
        .map_err(|e| e.with_sumo_log(sumo_log.clone()))?
        .map_err(EpisodeError::Output)?;
    result.sumo_log = sumo_log;
    Ok(result)
}

/// A vehicle of the scenario, as far as bkpbs follows it.
struct Line {
    record: ScenarioVehicle,
    kind: Kind,
    /// Where it entered the region, once it did.
    origin: Option<Origin>,
    /// Whether the planner commands it now.
    commanded: bool,
    /// Its length and width (m), from its SUMO type.
    size: (f64, f64),
    /// Whether its route leaves the region before the region's end (by an off-ramp): the
    /// planners keep a CAV on the carriageway, so SUMO drives it.
    leaves_early: bool,
}

/// The lock-step loop's state.
struct ScenarioRun<'a> {
    config: &'a Config,
    controller: &'a mut dyn controller::Controller,
    road: Road,
    lines: Vec<Line>,
    index: HashMap<String, usize>,
    readings: VehicleReadings,
    sumo_scene: SumoScene,
    commands: Vec<Command>,
    collisions: Vec<CollisionEvent>,
    /// Frame `s` from which the planner drives CAVs: the end of the region's first edge.
    control_start: f64,
}

impl<'a> ScenarioRun<'a> {
    fn new(config: &'a Config, controller: &'a mut dyn controller::Controller, road: Road) -> Self {
        // The main edges come first in the frame: the second one starts where the first ends.
        let control_start = road
            .edges
            .get(1)
            .filter(|e| !e.on_ramp)
            .and_then(|e| e.lanes.iter().flatten().map(|l| l.s0).reduce(f64::min))
            .unwrap_or(0.0);
        ScenarioRun {
            control_start,
            config,
            controller,
            sumo_scene: SumoScene::new(&road),
            road,
            lines: Vec::new(),
            index: HashMap::new(),
            readings: VehicleReadings::default(),
            commands: Vec::new(),
            collisions: Vec::new(),
        }
    }

    fn run(&mut self, mut sim: Simulation) -> Result<(), EpisodeError> {
        let (config, road) = (self.config, self.road.clone());
        crate::episode::runner::lock_step(&mut sim, &road, config, |sim, plan| {
            self.step(sim, plan)
        })?;
        let at = crate::episode::runner::step_error(config.scenario.dt);
        sim.close().map_err(at(config.scenario.steps))?;
        Ok(())
    }

    /// One SUMO step and, unless it is the last, one planning round.
    fn step(&mut self, sim: &mut Simulation, plan: bool) -> Result<(), SumoError> {
        let now = sim.time()?;
        sim.step()?;
        self.book_departures(sim, now)?;
        sim.read_vehicles(&mut self.readings)?;
        self.book_collisions(sim, now)?;
        for id in sim.arrived()? {
            if let Some(&k) = self.index.get(&id) {
                let r = &mut self.lines[k].record;
                if r.outcome == "present" {
                    r.outcome = "arrived".into();
                    r.arrival_s = Some(now);
                }
            }
        }
        self.build_scene(sim, now)?;
        if plan {
            self.plan(sim)?;
        }
        Ok(())
    }

    fn book_departures(&mut self, sim: &mut Simulation, now: f64) -> Result<(), SumoError> {
        let s = &self.config.scenario;
        for id in sim.departed()? {
            let sumo_type = sim.vehicle_type(&id)?;
            let size = sim.vehicle_size(&id)?;
            let kind = if is_cav(s.seed, &id, s.alpha) {
                Kind::Cav
            } else {
                Kind::Hdv
            };
            self.index.insert(id.clone(), self.lines.len());
            self.lines.push(Line {
                record: ScenarioVehicle {
                    id,
                    sumo_type,
                    kind: kind.as_str().into(),
                    depart_s: now,
                    outcome: "present".into(),
                    ..ScenarioVehicle::default()
                },
                kind,
                origin: None,
                commanded: false,
                size,
                leaves_early: false,
            });
        }
        Ok(())
    }

    /// Removes both vehicles of each collision and books it (a CAV in it makes it
    /// controllable).
    fn book_collisions(&mut self, sim: &mut Simulation, now: f64) -> Result<(), SumoError> {
        for c in sim.collisions()? {
            let kind = |id: &str| self.index.get(id).map(|&k| self.lines[k].kind);
            let event = CollisionEvent {
                time: now,
                collider_kind: kind(&c.collider),
                victim_kind: kind(&c.victim),
                collider: c.collider.clone(),
                victim: c.victim.clone(),
                lane: c.lane.clone(),
                position: c.position,
            };
            for (me, other) in [(&c.collider, &c.victim), (&c.victim, &c.collider)] {
                let Some(&k) = self.index.get(me) else {
                    continue;
                };
                let r = &mut self.lines[k].record;
                if r.outcome == "present" {
                    sim.remove_vehicle(me)?;
                    r.outcome = "crashed".into();
                    r.crash_time_s = Some(now);
                }
                if !r.crashed_with.is_empty() {
                    r.crashed_with.push(' ');
                }
                r.crashed_with.push_str(other);
                r.controllable_crash |= event.controllable();
            }
            self.collisions.push(event);
        }
        Ok(())
    }

    /// This step's scene: every vehicle read on the region's edges, with its own size; a CAV
    /// entering it is taken over, one leaving it (or the lanes the planners plan on) handed
    /// back to SUMO.
    fn build_scene(&mut self, sim: &mut Simulation, now: f64) -> Result<(), SumoError> {
        let sc = &self.config.scenario;
        let commanded = self.controller.handling() == CavHandling::Commanded;
        self.sumo_scene.clear(now);
        let mut planned_now = vec![false; self.lines.len()];
        for (id, raw) in self.readings.ids.iter().zip(&self.readings.states) {
            let Some(&k) = self.index.get(id) else {
                continue;
            };
            let line = &mut self.lines[k];
            let Some((front, lane)) = frame::frame_position(&self.road, raw) else {
                continue;
            };
            if line.record.outcome != "present" {
                continue;
            }
            if line.origin.is_none() {
                enter_region(line, sim, &self.road, raw.edge_code, now)?;
            }
            let origin = line.origin.expect("set on entry");
            line.record.region_origin = origin.as_str().into();
            line.record.region_leave_s = Some(now);
            // The planners have no lane for it on a deceleration lane (lane 0 outside a merge
            // zone), nor a way off the carriageway: there SUMO drives it, and the planner
            // sees it as any vehicle SUMO drives. On the region's first edge it is SUMO's too:
            // the planner sees no one behind the region's start, so a CAV taken over there
            // could brake in front of a follower it cannot see.
            let planned = line.kind == Kind::Cav
                && !line.leaves_early
                && front >= self.control_start
                && self.road.lanes_at(front).contains(&lane);
            if planned {
                planned_now[k] = true;
                if commanded && !line.commanded {
                    sim.set_speed_mode(id, 0)?;
                    sim.set_lane_change_mode(id, 0)?;
                    line.commanded = true;
                }
            }
            let who = frame::Identity {
                id: id.as_str().into(),
                kind: if planned { Kind::Cav } else { Kind::Hdv },
                origin,
                desired_speed: sc.v_max,
            };
            let vehicle = frame::state_sized(&self.road, who, raw, (front, lane), line.size);
            self.sumo_scene.push(vehicle, raw.edge_code);
        }
        self.hand_back(sim, &planned_now)
    }

    /// Hands every commanded CAV the planner no longer drives (not in `planned`) back to SUMO.
    fn hand_back(&mut self, sim: &mut Simulation, planned: &[bool]) -> Result<(), SumoError> {
        for (k, line) in self.lines.iter_mut().enumerate() {
            if line.commanded && !planned[k] {
                line.commanded = false;
                if line.record.outcome == "present" {
                    sim.set_speed(&line.record.id, -1.0)?;
                    sim.set_speed_mode(&line.record.id, SPEED_MODE_SUMO)?;
                    sim.set_lane_change_mode(&line.record.id, LC_MODE_SUMO)?;
                }
            }
        }
        Ok(())
    }

    /// The controller's maneuvers for this scene, sent to SUMO when it commands the CAVs.
    fn plan(&mut self, sim: &mut Simulation) -> Result<(), SumoError> {
        self.commands.clear();
        self.controller
            .plan(&self.sumo_scene.scene, &mut self.commands);
        if self.controller.handling() == CavHandling::Commanded {
            crate::episode::runner::send_commands(
                sim,
                &self.sumo_scene,
                &self.commands,
                &self.config.scenario,
            )?;
        }
        Ok(())
    }

    /// The records with SUMO's trip figures, and the summary.
    fn finish(
        self,
        tripinfo: &std::path::Path,
        sumo_options: Vec<String>,
    ) -> Result<ScenarioResult, String> {
        let trips = records::read_trips(tripinfo)?;
        let mut vehicles: Vec<ScenarioVehicle> = self.lines.into_iter().map(|l| l.record).collect();
        for v in &mut vehicles {
            if let Some(t) = trips.get(&v.id) {
                v.time_loss_s = Some(t.time_loss);
                v.route_length_m = Some(t.route_length);
            }
        }
        let sc = &self.config.scenario;
        let hdv_collisions = self.collisions.iter().filter(|c| !c.controllable()).count();
        let head = ScenarioSummary {
            planner: self.controller.name().into(),
            alpha: sc.alpha,
            seed: sc.seed,
            steps: sc.steps,
            region: merge_edges(&self.road).join(" "),
            ..ScenarioSummary::default()
        };
        Ok(ScenarioResult {
            summary: ScenarioSummary::of(head, &vehicles, hdv_collisions),
            vehicles,
            collisions: self.collisions,
            sumo_options,
            sumo_log: String::new(),
        })
    }
}

/// Books a vehicle's first reading in the region: when, from where, and whether its route
/// leaves the region early.
fn enter_region(
    line: &mut Line,
    sim: &Simulation,
    road: &Road,
    edge_code: i32,
    now: f64,
) -> Result<(), SumoError> {
    line.record.region_enter_s = Some(now);
    line.origin = Some(if frame::is_on_ramp(road, edge_code) {
        Origin::Ramp
    } else {
        Origin::Main
    });
    let (end, pos) = (&road.end_edge.0, road.end_edge.1);
    // SUMO answers a negative distance for an edge off the vehicle's route.
    line.leaves_early = sim.driving_distance(&line.record.id, end, pos)? < 0.0;
    Ok(())
}

/// The edges the region's on-ramps join: the first edge of each ramp's route off the ramp.
fn merge_edges(road: &Road) -> Vec<String> {
    road.entries
        .iter()
        .skip(1)
        .filter_map(|e| {
            e.route
                .iter()
                .find(|edge| road.edge(edge).is_some_and(|f| !f.on_ramp))
                .map(|edge| edge.to_string())
        })
        .collect()
}

/// Writes the episode's files into `dir` as one set, `episode.csv` last.
pub fn write(
    result: &ScenarioResult,
    dir: &std::path::Path,
) -> Result<Vec<PathBuf>, crate::io::WriteError> {
    let episode = csv_of(std::slice::from_ref(&result.summary));
    let vehicles = csv_of(&result.vehicles);
    let collisions = crate::episode::output::collisions_csv(&result.collisions);
    let options = result.sumo_options.join(" ") + "\n";
    let log = (!result.sumo_log.is_empty()).then_some(result.sumo_log.as_bytes());
    crate::io::replace_together(
        dir,
        &[
            ("sumo.log", log),
            ("sumo_options.txt", Some(options.as_bytes())),
            ("vehicles.csv", Some(&vehicles[..])),
            ("collisions.csv", Some(&collisions[..])),
            ("episode.csv", Some(&episode[..])),
        ],
    )
}
