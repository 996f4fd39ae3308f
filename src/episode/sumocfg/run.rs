//! The lock-step loop of an episode on a user's scenario: SUMO steps, departures get their
//! CAV draw, collisions and arrivals are booked, and each merge region's vehicles are read into
//! its own scene and planned by its own controller, the regions in parallel (each
//! deterministic, and none sees another's vehicles or state).

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use crate::config::Config;
use crate::controller::PlanStats;
use crate::episode::error::EpisodeError;
use crate::episode::metrics::{CollisionEvent, Outcome, Timing};
use crate::episode::step_times::StepTimes;
use crate::episode::trajectories::TrajectoryFile;
use crate::episode::Observer;
use crate::model::road::MERGE_LANE;
use crate::model::scene::{Kind, Limits, Origin, VehicleState};
use crate::sumo::frame;
use crate::sumo::{RawVehicleState, Simulation, SumoClient, SumoError, VehicleReadings};

use super::never_inserted::{never_inserted_rows, to_ms};
use super::passage::{enter, first_region_on, own_desired_speed, passage, Entry};
use super::records::{self, ScenarioVehicle};
pub use super::region::Region;
use super::region_books::region_books;
use super::round::{crosses_a_region, plan_together, Fleet, Round};
use super::{becomes_cav, has_cavs, ScenarioResult, SumoOptions};
use crate::episode::collisions::{take_collisions, Crashes};
use crate::episode::control;
use crate::episode::summary::Summary;

/// A vehicle of the scenario, as far as bkpbs follows it.
struct Line {
    record: ScenarioVehicle,
    /// Its length and width (m), from its SUMO type.
    size: (f64, f64),
    /// Its own top speed (m/s), from its SUMO type.
    max_speed: f64,
    /// Its own speed factor: its desired speed over the lane's limit, drawn by SUMO.
    speed_factor: f64,
    /// Its own accelerations, from its SUMO type.
    limits: Limits,
    /// The region it entered first, and where and how: its frame position and speed then.
    entry: Option<Entry>,
    /// The region whose planner commands it now.
    commanded: Option<usize>,
}

/// A region's trace: its name and its `trace.jsonl` text.
type RegionTrace = (String, String);

/// The loop's state.
pub struct ScenarioRun {
    config: Config,
    regions: Vec<Region>,
    lines: Vec<Line>,
    index: HashMap<String, usize>,
    readings: VehicleReadings,
    collisions: Vec<CollisionEvent>,
    times: StepTimes,
    /// Steps seen, and the vehicles and planned CAVs in the regions' scenes over them.
    occupancy: (u64, u64, u64),
    timing: Option<Timing>,
    /// Plans every region at once in place of their own planners, when given.
    round: Option<Box<dyn Round>>,
    /// Which departing vehicles are CAVs.
    fleet: Fleet,
    /// The vehicles removed in collisions since the last planning round.
    crashed: Vec<Arc<str>>,
    /// The vehicles whose departure time had come but which SUMO had not inserted, after the
    /// last step seen: at the end, the vehicles never inserted.
    pending: Vec<String>,
    /// SUMO's time after the last step seen (s): at the end, the episode's end.
    end: f64,
    /// Where each vehicle that ever waited would enter a region first (by its route): which
    /// region, and by which of its road's entries; none for a route through no region.
    waiting: HashMap<String, Option<(usize, usize)>>,
    /// The planners' search effort, over every round of every region.
    plan_stats: PlanStats,
    /// Whether the episode removes the vehicles of a collision (with CAVs; without, SUMO's
    /// own `collision.action` does what the configuration says).
    removes_crashed: bool,
}

impl ScenarioRun {
    pub fn new(config: &Config, mut regions: Vec<Region>) -> Self {
        let mut offset = 0;
        for r in &mut regions {
            r.code_offset = offset;
            offset += r.road.edges.len() as i32;
        }
        ScenarioRun {
            config: config.clone(),
            regions,
            lines: Vec::new(),
            index: HashMap::new(),
            readings: VehicleReadings::default(),
            collisions: Vec::new(),
            times: StepTimes::new(config.scenario.steps),
            occupancy: (0, 0, 0),
            timing: None,
            round: None,
            fleet: Fleet::Drawn,
            crashed: Vec::new(),
            pending: Vec::new(),
            end: 0.0,
            waiting: HashMap::new(),
            plan_stats: PlanStats::default(),
            removes_crashed: has_cavs(&config.scenario),
        }
    }

    /// The episode with `round` planning every region (theirs without planners) and `fleet`
    /// deciding the CAVs.
    pub fn planned_together(
        config: &Config,
        regions: Vec<Region>,
        round: Box<dyn Round>,
        fleet: Fleet,
    ) -> Self {
        ScenarioRun {
            round: Some(round),
            fleet,
            ..ScenarioRun::new(config, regions)
        }
    }

    /// The names of every region's edges, in the order of their codes in the readings.
    pub fn edge_names(&self) -> Vec<String> {
        self.regions
            .iter()
            .flat_map(|r| frame::edge_names(&r.road))
            .map(String::from)
            .collect()
    }

    /// Runs the episode's steps, then closes SUMO (which writes the tripinfo output).
    pub fn run(&mut self, mut sim: Simulation) -> Result<(), EpisodeError> {
        let config = self.config.clone();
        let names = self.edge_names();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let start = std::time::Instant::now();
        crate::episode::runner::lock_step(&mut sim, &names, &config, |sim, plan| {
            let now = sim.time()?;
            self.times.sumo_step(sim)?;
            self.after_step(sim, now, plan)
        })?;
        self.close_timing(start.elapsed().as_secs_f64());
        let (dt, steps) = (config.scenario.dt, config.scenario.steps);
        sim.close()
            .map_err(crate::episode::runner::step_error(dt, steps))?;
        Ok(())
    }

    /// The episode ran `steps` steps (a caller's own loop may stop before the configured
    /// number): the summary says so.
    pub fn ran_steps(&mut self, steps: u32) {
        self.config.scenario.steps = steps;
    }

    /// Ends the episode's timing, its loop having taken `loop_s` seconds.
    pub fn close_timing(&mut self, loop_s: f64) {
        let times = std::mem::replace(&mut self.times, StepTimes::new(0));
        self.timing = Some(times.timing(loop_s, self.config.scenario.steps));
    }

    /// What follows a SUMO step that began at time `now`: departures, collisions and
    /// arrivals booked, every region's scene read and, when `plan`, one planning round per
    /// region with its commands sent.
    pub fn after_step(
        &mut self,
        sim: &mut impl SumoClient,
        now: f64,
        plan: bool,
    ) -> Result<(), SumoError> {
        self.end = now + self.config.scenario.dt;
        self.book_departures(sim, now)?;
        self.note_waiting(sim)?;
        sim.read_vehicles(&mut self.readings)?;
        self.book_collisions(sim, now)?;
        for id in sim.arrived()? {
            if let Some(&k) = self.index.get(&id) {
                let r = &mut self.lines[k].record;
                if r.outcome == Outcome::Present {
                    r.outcome = Outcome::Arrived;
                    r.arrival_s = Some(now);
                }
            }
        }
        self.build_scenes(sim, now)?;
        if plan {
            self.plan_regions();
            for r in &mut self.regions {
                if r.commanded() {
                    crate::episode::runner::send_commands(
                        sim,
                        &r.scene,
                        &r.commands,
                        &r.config.scenario,
                    )?;
                    r.record_sent();
                    if let Some(gui) = &mut r.gui {
                        gui.update(sim, &r.scene.scene, &r.commands)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// One planning round of every region, in parallel (each region's planner sees only its
    /// own scene and keeps its own state, so the rounds are independent and each is
    /// deterministic), timed together: the step's planning time.
    fn plan_regions(&mut self) {
        use rayon::prelude::*;
        let start = std::time::Instant::now();
        let crashed = std::mem::take(&mut self.crashed);
        if let Some(round) = &mut self.round {
            plan_together(round.as_mut(), &mut self.regions, &crashed);
        }
        self.regions.par_iter_mut().for_each(|r| {
            if let Some(c) = &mut r.controller {
                r.commands.clear();
                c.plan(&r.scene.scene, &mut r.commands);
                if let Some(t) = &mut r.trace {
                    t.planned(&r.scene.scene, &r.commands, c.as_ref());
                }
            }
        });
        let controllers = || self.regions.iter().filter_map(|r| r.controller.as_ref());
        let shield_ms = controllers().map(|c| c.last_shield_ms()).sum();
        for c in controllers() {
            self.plan_stats += c.last_stats();
        }
        self.times
            .add_round(start.elapsed().as_secs_f64() * 1e3, shield_ms);
        self.occupancy.0 += 1;
        for r in &self.regions {
            let vehicles = &r.scene.scene.vehicles;
            self.occupancy.1 += vehicles.len() as u64;
            self.occupancy.2 += vehicles.iter().filter(|v| v.kind == Kind::Cav).count() as u64;
        }
    }

    /// Reads the vehicles SUMO holds back now, and where each new one would enter a region.
    fn note_waiting(&mut self, sim: &impl SumoClient) -> Result<(), SumoError> {
        self.pending = sim.pending()?;
        for id in &self.pending {
            if !self.waiting.contains_key(id) {
                let route = sim.vehicle_route(id)?;
                let entry = first_region_on(&self.regions, &route);
                self.waiting.insert(id.clone(), entry);
            }
        }
        Ok(())
    }

    fn book_departures(&mut self, sim: &mut impl SumoClient, now: f64) -> Result<(), SumoError> {
        let s = &self.config.scenario;
        let (index, lines, regions) = (&mut self.index, &mut self.lines, &self.regions);
        for id in sim.departed()? {
            let sumo_type = sim.vehicle_type(&id)?;
            let size = sim.vehicle_size(&id)?;
            let max_speed = sim.vehicle_max_speed(&id)?;
            let speed_factor = sim.vehicle_speed_factor(&id)?;
            let limits = sim.vehicle_limits(&id)?;
            let drawn = becomes_cav(s, &id, &sumo_type);
            let crosses = || crosses_a_region(sim, &id, regions);
            let kind = if self.fleet.is_cav(&id, now, drawn, crosses)? {
                Kind::Cav
            } else {
                Kind::Hdv
            };
            index.insert(id.clone(), lines.len());
            lines.push(Line {
                record: ScenarioVehicle {
                    id,
                    sumo_type,
                    kind,
                    depart_s: Some(now),
                    ..ScenarioVehicle::default()
                },
                size,
                max_speed,
                speed_factor,
                limits,
                entry: None,
                commanded: None,
            });
        }
        Ok(())
    }

    /// Books each collision (a CAV in it makes it controllable) and, in an episode with CAVs,
    /// removes both vehicles; without, SUMO does what its `collision.action` says.
    fn book_collisions(&mut self, sim: &mut impl SumoClient, now: f64) -> Result<(), SumoError> {
        let mut crashes = ScenarioCrashes {
            index: &self.index,
            lines: &self.lines,
            removes: self.removes_crashed,
            crashed: &mut self.crashed,
        };
        for event in take_collisions(sim, now, &mut crashes)? {
            let controllable = event.controllable();
            for (me, other) in event.pairs() {
                let Some(&k) = self.index.get(me) else {
                    continue;
                };
                let r = &mut self.lines[k].record;
                if self.removes_crashed && r.outcome == Outcome::Present {
                    r.outcome = Outcome::Crashed;
                    r.crash_time_s = Some(now);
                }
                if !r.crashed_with.is_empty() {
                    r.crashed_with.push(' ');
                }
                r.crashed_with.push_str(other);
                r.controllable_crash |= controllable;
            }
            self.collisions.push(event);
        }
        Ok(())
    }

    /// This step's scene of every region: each vehicle read on its edges, with its own size;
    /// a CAV entering the part a planner drives is taken over, one leaving it handed back.
    fn build_scenes(&mut self, sim: &mut impl SumoClient, now: f64) -> Result<(), SumoError> {
        for r in &mut self.regions {
            r.scene.clear(now);
            r.log_rows.clear();
            if let Some(log) = &mut r.log {
                log.begin_step(now);
            }
        }
        let mut planned_by: Vec<Option<usize>> = vec![None; self.lines.len()];
        // Taken out for the loop, which places vehicles into `self`, and put back after it.
        let readings = std::mem::take(&mut self.readings);
        for (id, raw) in readings.ids.iter().zip(&readings.states) {
            let Some(&k) = self.index.get(id) else {
                continue;
            };
            if self.lines[k].record.outcome != Outcome::Present {
                continue;
            }
            let found = self.regions.iter().enumerate().find_map(|(g, r)| {
                let local = r.local(raw)?;
                frame::frame_position(&r.road, &local).map(|p| (g, local, p))
            });
            let Some((g, local, position)) = found else {
                continue;
            };
            match self.place(sim, k, g, &local, position, now) {
                Ok(true) => planned_by[k] = Some(g),
                Ok(false) => {}
                Err(e) => {
                    self.readings = readings;
                    return Err(e);
                }
            }
        }
        self.readings = readings;
        self.hand_back(sim, &planned_by)
    }

    /// Puts vehicle `k`, read at `position` in region `g`, in that region's scene; whether
    /// the region's planner drives it. The planners have no lane for a CAV on a deceleration
    /// lane (lane 0 outside a merge zone), nor a way off the carriageway: there SUMO drives it,
    /// and the planner sees it as any vehicle SUMO drives. On the region's first edge it is
    /// SUMO's too: the planner sees no one behind the region's start, so a CAV taken over there
    /// could brake in front of a follower it cannot see.
    fn place(
        &mut self,
        sim: &mut impl SumoClient,
        k: usize,
        g: usize,
        raw: &RawVehicleState,
        (front, lane): (f64, i32),
        now: f64,
    ) -> Result<bool, SumoError> {
        let region = &mut self.regions[g];
        let line = &mut self.lines[k];
        if line.entry.is_none() {
            line.entry = Some(enter(&line.record.id, sim, g, region, raw, front, now)?);
            line.record.region = region.name.clone();
        }
        let mut entry = line.entry.expect("set on entry");
        let first = entry.region == g;
        if first {
            entry.last = (now, front);
            line.entry = Some(entry);
        }
        let planned = line.record.kind == Kind::Cav
            && !(first && entry.leaves_early)
            && front >= region.control_start
            && front < region.control_end
            && region.road.lanes_at(front).contains(&lane);
        let commanded = region.commanded();
        if planned && commanded && line.commanded != Some(g) {
            control::take_over(sim, &line.record.id)?;
            line.commanded = Some(g);
        }
        let ramp = first && entry.origin == Origin::Ramp;
        let vehicle = scene_vehicle(region, line, raw, (front, lane), planned, ramp);
        region.scene.push(vehicle, raw.edge_code);
        region.record(raw, line.record.kind);
        Ok(planned)
    }

    /// Hands every commanded CAV that no region's planner drives now back to SUMO.
    fn hand_back(
        &mut self,
        sim: &mut impl SumoClient,
        planned_by: &[Option<usize>],
    ) -> Result<(), SumoError> {
        for (k, line) in self.lines.iter_mut().enumerate() {
            if line.commanded.is_some() && line.commanded != planned_by[k] {
                line.commanded = None;
                if line.record.outcome == Outcome::Present {
                    control::hand_back(sim, &line.record.id)?;
                }
            }
        }
        Ok(())
    }

    /// Each region's trajectories and trace, taken out of it (region name, file).
    fn take_region_files(&mut self) -> (Vec<(String, TrajectoryFile)>, Vec<RegionTrace>) {
        let trajectories = self
            .regions
            .iter_mut()
            .filter_map(|r| Some((r.name.clone(), r.log.take()?.finish())))
            .collect();
        let traces = self
            .regions
            .iter_mut()
            .filter_map(|r| Some((r.name.clone(), r.trace.take()?.text().to_string())))
            .collect();
        (trajectories, traces)
    }

    /// Where each vehicle still waiting at the end would enter a region first: the region and
    /// the entry of its road (those whose routes enter none left out).
    fn never_inserted_entries(&self) -> Vec<(usize, usize)> {
        (self.pending.iter())
            .filter_map(|id| *self.waiting.get(id)?)
            .collect()
    }

    /// The rows of the vehicles still waiting at the end, SUMO's `trips` giving their waits;
    /// each of the kind the draw would have made it (a single agent is one that departed).
    fn never_inserted(&self, trips: &BTreeMap<String, records::Trip>) -> Vec<ScenarioVehicle> {
        let drawn = matches!(self.fleet, Fleet::Drawn);
        never_inserted_rows(&self.pending, trips, self.end, |id, sumo_type| {
            match drawn && becomes_cav(&self.config.scenario, id, sumo_type) {
                true => Kind::Cav,
                false => Kind::Hdv,
            }
        })
    }

    /// The records of the vehicles SUMO inserted, with SUMO's trip figures and each one's
    /// passage through its first region, then those of the vehicles never inserted.
    fn vehicle_records(&mut self, trips: &BTreeMap<String, records::Trip>) -> Vec<ScenarioVehicle> {
        let mut vehicles: Vec<ScenarioVehicle> = std::mem::take(&mut self.lines)
            .into_iter()
            .map(|l| {
                let mut v = l.record;
                if let Some(t) = trips.get(&v.id) {
                    v.time_loss_s = Some(t.time_loss);
                    v.route_length_m = Some(t.route_length);
                    v.depart_delay_s = Some(t.depart_delay);
                    v.scheduled_depart_s = v.depart_s.map(|d| to_ms(d - t.depart_delay));
                }
                if let Some(e) = l.entry {
                    let region = &self.regions[e.region];
                    let own = own_desired_speed(l.speed_factor, l.max_speed, &region.road);
                    passage(&mut v, &e, region, own);
                }
                v
            })
            .collect();
        vehicles.extend(self.never_inserted(trips));
        vehicles
    }

    /// The records with SUMO's trip figures and each vehicle's delay in its region, the books
    /// of each region and entry, and the summary.
    pub fn finish(
        mut self,
        planner: &str,
        options: &SumoOptions,
    ) -> Result<ScenarioResult, String> {
        let trips = records::read_trips(&options.tripinfo)?;
        let (trajectories, traces) = self.take_region_files();
        let vehicles = self.vehicle_records(&trips);
        let hdv_collisions = self.collisions.iter().filter(|c| !c.controllable()).count();
        let names: Vec<String> = self.regions.iter().map(|r| r.name.clone()).collect();
        let head = Summary::head_of_scenario(&self.config, planner, &names);
        let (steps, in_scenes, cavs) = self.occupancy;
        let per_step = |n: u64| n as f64 / steps.max(1) as f64;
        let waiting = self.never_inserted_entries();
        let (regions, entries) = region_books(&head, &self.regions, &vehicles, &waiting);
        let summary = Summary {
            plan_stats: self.plan_stats,
            ..Summary::of_scenario(head, &vehicles, hdv_collisions, self.end)
        };
        Ok(ScenarioResult {
            summary,
            regions,
            entries,
            vehicles,
            collisions: self.collisions,
            sumo_options: options.args.clone(),
            sumo_notes: options.notes.clone(),
            sumo_log: String::new(),
            timing: self.timing.expect("timed when the episode ran"),
            vehicles_per_step: per_step(in_scenes),
            cavs_per_step: per_step(cavs),
            trajectories,
            traces,
        })
    }
}

/// A scenario's vehicles in a collision: told apart by their draw, removed (once, while
/// present) only in an episode with CAVs.
struct ScenarioCrashes<'a> {
    index: &'a HashMap<String, usize>,
    lines: &'a [Line],
    removes: bool,
    crashed: &'a mut Vec<Arc<str>>,
}

impl Crashes for ScenarioCrashes<'_> {
    fn kind_of(&self, id: &str, _type_id: &str) -> Option<Kind> {
        self.index.get(id).map(|&k| self.lines[k].record.kind)
    }
    fn removes(&self, id: &str) -> bool {
        let present = |&k: &usize| self.lines[k].record.outcome == Outcome::Present;
        self.removes && self.index.get(id).is_some_and(present)
    }
    fn removed(&mut self, id: &str) {
        self.crashed.push(Arc::from(id));
    }
}

/// Vehicle `line` read at `raw`, `(front, lane)` in `region`'s frame, as its planner sees it: a
/// CAV when `planned`, else a vehicle SUMO drives; from the ramp when it entered the region there
/// (`ramp`) or drives on an acceleration lane.
fn scene_vehicle(
    region: &Region,
    line: &Line,
    raw: &RawVehicleState,
    (front, lane): (f64, i32),
    planned: bool,
    ramp: bool,
) -> VehicleState {
    // On an acceleration lane every vehicle must merge, wherever it came from: one SUMO
    // inserted there (A10KW's boundary routes depart on it) was seen as a main-road car,
    // which the planners never merge and the shield never expects to move over (A10KW,
    // bk-mastar, α 0.6, seed 102: such an HDV, standing at the lane end, moved into lane 1
    // as a CAV from lane 2 did, 25 m behind it at 27.6 m/s; a controllable crash).
    let merging = lane == MERGE_LANE && region.road.lanes_at(front).contains(&MERGE_LANE);
    // No faster than its type, nor than the lane it drives on allows (a CAV above that, as
    // it entered a slower lane, may hold its speed: it does not brake ahead of one).
    let top = line.max_speed.min(frame::speed_limit(
        &region.road,
        raw.edge_code,
        raw.lane_index,
    ));
    let who = frame::Identity {
        id: line.record.id.as_str().into(),
        kind: if planned { Kind::Cav } else { Kind::Hdv },
        origin: if merging || ramp {
            Origin::Ramp
        } else {
            Origin::Main
        },
        desired_speed: region.config.scenario.v_max.min(top),
    };
    VehicleState {
        max_speed: top,
        limits: line.limits,
        ..frame::state_sized(&region.road, who, raw, (front, lane), line.size)
    }
}
