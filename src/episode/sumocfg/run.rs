//! A user's SUMO scenario as the source of traffic of the one lock-step loop
//! ([`Lockstep`]): SUMO inserts the scenario's vehicles, each gets its CAV draw as it
//! departs, and each merge region's vehicles are read into its own scene (each with its own
//! type's size and limits) and planned by its own controller, the regions in parallel (each
//! deterministic, and none sees another's vehicles or state). A region's planner takes a CAV
//! over as it enters the part it drives and hands it back as it leaves.

use std::collections::{BTreeMap, HashMap};

use crate::config::Config;
use crate::episode::lockstep::{Lockstep, TrafficSource};
use crate::episode::metrics::{CollisionEvent, Outcome};
use crate::episode::planning::Planning;
use crate::episode::region::Region;
use crate::episode::round::Round;
use crate::episode::{NoObserver, Observer};
use crate::model::scene::{Kind, Limits, Origin, VehicleState};
use crate::sumo::frame;
use crate::sumo::{RawVehicleState, SumoClient, SumoError, VehicleReadings};

use super::fleet::{crosses_a_region, Fleet};
use super::never_inserted::{never_inserted_rows, to_ms};
use super::passage::{enter, first_region_on, own_desired_speed, passage, Entry};
use super::records::{self, ScenarioVehicle};
use super::region_books::region_books;
use super::{becomes_cav, has_cavs, ScenarioResult, SumoOptions};
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

/// A user's scenario as the loop's source of traffic: its books.
pub struct ScenarioTraffic {
    config: Config,
    lines: Vec<Line>,
    index: HashMap<String, usize>,
    collisions: Vec<CollisionEvent>,
    /// Which departing vehicles are CAVs.
    fleet: Fleet,
    /// The vehicles whose departure time had come but which SUMO had not inserted, after the
    /// last step seen: at the end, the vehicles never inserted.
    pending: Vec<String>,
    /// SUMO's time after the last step seen (s): at the end, the episode's end.
    end: f64,
    /// Where each vehicle that ever waited would enter a region first (by its route): which
    /// region, and by which of its road's entries; none for a route through no region.
    waiting: HashMap<String, Option<(usize, usize)>>,
    /// Whether the episode removes the vehicles of a collision (with CAVs; without, SUMO's
    /// own `collision.action` does what the configuration says).
    removes_crashed: bool,
}

/// An episode on a user's scenario: its traffic in lock-step with its regions' planning.
pub type ScenarioRun<'a> = Lockstep<'a, ScenarioTraffic>;

impl<'a> ScenarioRun<'a> {
    /// The episode of `config`'s scenario with `regions`, each planned by its own planner.
    pub fn of_regions(config: &Config, regions: Vec<Region<'a>>) -> Self {
        Self::with_round(config, regions, None, Fleet::Drawn)
    }

    /// The episode with each region planned by its own planner, every region's scene shown to
    /// `observer` each step.
    pub fn observed(
        config: &Config,
        regions: Vec<Region<'a>>,
        observer: Box<dyn Observer + 'a>,
    ) -> Self {
        let mut run = Self::of_regions(config, regions);
        run.planning.observe_with(observer);
        run
    }

    /// The episode with `round` planning every region (theirs without planners) and `fleet`
    /// deciding the CAVs.
    pub fn planned_together(
        config: &Config,
        regions: Vec<Region<'a>>,
        round: Box<dyn Round>,
        fleet: Fleet,
    ) -> Self {
        Self::with_round(config, regions, Some(round), fleet)
    }

    fn with_round(
        config: &Config,
        regions: Vec<Region<'a>>,
        round: Option<Box<dyn Round>>,
        fleet: Fleet,
    ) -> Self {
        let traffic = ScenarioTraffic {
            config: config.clone(),
            lines: Vec::new(),
            index: HashMap::new(),
            collisions: Vec::new(),
            fleet,
            pending: Vec::new(),
            end: 0.0,
            waiting: HashMap::new(),
            removes_crashed: has_cavs(&config.scenario),
        };
        let steps = config.scenario.steps;
        let planning = Planning::new(regions, Box::new(NoObserver), round, steps);
        Lockstep::new(traffic, planning)
    }

    /// The episode ran `steps` steps (a caller's own loop may stop before the configured
    /// number): the summary says so.
    pub fn ran_steps(&mut self, steps: u32) {
        self.traffic.config.scenario.steps = steps;
    }

    /// Ends the episode's timing, its loop having taken `loop_s` seconds.
    pub fn close_timing(&mut self, loop_s: f64) {
        let steps = self.traffic.config.scenario.steps;
        self.planning.close_timing(loop_s, steps);
    }

    /// The records with SUMO's trip figures and each vehicle's delay in its region, the books
    /// of each region and entry, and the summary.
    pub fn finish(
        mut self,
        planner: &str,
        options: &SumoOptions,
    ) -> Result<ScenarioResult, String> {
        let trips = records::read_trips(&options.tripinfo)?;
        let (trajectories, traces) = self.planning.take_files();
        let (mut traffic, planning) = (self.traffic, self.planning);
        let regions = &planning.regions;
        let vehicles = traffic.vehicle_records(&trips, regions);
        let hdv_collisions = (traffic.collisions.iter())
            .filter(|c| !c.controllable())
            .count();
        let names: Vec<String> = regions.iter().map(|r| r.name.clone()).collect();
        let head = Summary::head_of_scenario(&traffic.config, planner, &names);
        let (vehicles_per_step, cavs_per_step) = planning.per_step();
        let waiting = traffic.never_inserted_entries();
        let (regions, entries) = region_books(&head, regions, &vehicles, &waiting);
        let summary = Summary {
            plan_stats: planning.plan_stats,
            ..Summary::of_scenario(head, &vehicles, hdv_collisions, traffic.end)
        };
        Ok(ScenarioResult {
            summary,
            regions,
            entries,
            vehicles,
            collisions: traffic.collisions,
            sumo_options: options.args.clone(),
            sumo_notes: options.notes.clone(),
            sumo_log: String::new(),
            timing: planning.timing.expect("timed when the episode ran"),
            vehicles_per_step,
            cavs_per_step,
            trajectories,
            traces,
        })
    }
}

impl TrafficSource for ScenarioTraffic {
    /// Each vehicle SUMO inserted gets its CAV draw and its line; the vehicles SUMO holds back
    /// are noted.
    fn book_departures(
        &mut self,
        sim: &mut impl SumoClient,
        now: f64,
        regions: &[Region],
    ) -> Result<(), SumoError> {
        self.end = now + self.config.scenario.dt;
        self.book_inserted(sim, now, regions)?;
        self.note_waiting(sim, regions)
    }

    /// Told apart by their draw.
    fn kind_of(&self, id: &str, _type_id: &str) -> Option<Kind> {
        self.index.get(id).map(|&k| self.lines[k].record.kind)
    }

    /// Removed (once, while present) only in an episode with CAVs.
    fn removes(&self, id: &str) -> bool {
        let present = |&k: &usize| self.lines[k].record.outcome == Outcome::Present;
        self.removes_crashed && self.index.get(id).is_some_and(present)
    }

    /// Books each collision (a CAV in it makes it controllable); in an episode with CAVs its
    /// vehicles were removed.
    fn book_collisions(&mut self, events: Vec<CollisionEvent>, now: f64) {
        for event in events {
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
    }

    fn book_arrivals(&mut self, arrived: Vec<String>, now: f64) {
        for id in arrived {
            if let Some(&k) = self.index.get(&id) {
                let r = &mut self.lines[k].record;
                if r.outcome == Outcome::Present {
                    r.outcome = Outcome::Arrived;
                    r.arrival_s = Some(now);
                }
            }
        }
    }

    /// This step's scene of every region: each vehicle read on its edges, with its own size;
    /// a CAV entering the part a planner drives is taken over, one leaving it handed back.
    fn build_scenes(
        &mut self,
        sim: &mut impl SumoClient,
        readings: &VehicleReadings,
        regions: &mut [Region],
        now: f64,
    ) -> Result<(), SumoError> {
        let mut planned_by: Vec<Option<usize>> = vec![None; self.lines.len()];
        for (id, raw) in readings.ids.iter().zip(&readings.states) {
            let Some(&k) = self.index.get(id) else {
                continue;
            };
            if self.lines[k].record.outcome != Outcome::Present {
                continue;
            }
            let found = regions.iter().enumerate().find_map(|(g, r)| {
                let local = r.local(raw)?;
                frame::frame_position(&r.road, &local).map(|p| (g, local, p))
            });
            let Some((g, local, position)) = found else {
                continue;
            };
            if self.place(sim, k, (g, &mut regions[g]), &local, position, now)? {
                planned_by[k] = Some(g);
            }
        }
        self.hand_back(sim, &planned_by)
    }
}

impl ScenarioTraffic {
    /// Reads the vehicles SUMO holds back now, and where each new one would enter a region.
    fn note_waiting(&mut self, sim: &impl SumoClient, regions: &[Region]) -> Result<(), SumoError> {
        self.pending = sim.pending()?;
        for id in &self.pending {
            if !self.waiting.contains_key(id) {
                let route = sim.vehicle_route(id)?;
                let entry = first_region_on(regions, &route);
                self.waiting.insert(id.clone(), entry);
            }
        }
        Ok(())
    }

    /// Each vehicle SUMO inserted in the step that began at `now`: its draw, its line.
    fn book_inserted(
        &mut self,
        sim: &mut impl SumoClient,
        now: f64,
        regions: &[Region],
    ) -> Result<(), SumoError> {
        let s = &self.config.scenario;
        let (index, lines) = (&mut self.index, &mut self.lines);
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
        (g, region): (usize, &mut Region),
        raw: &RawVehicleState,
        (front, lane): (f64, i32),
        now: f64,
    ) -> Result<bool, SumoError> {
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
            && region.road.lane_exists(lane, front);
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
    fn vehicle_records(
        &mut self,
        trips: &BTreeMap<String, records::Trip>,
        regions: &[Region],
    ) -> Vec<ScenarioVehicle> {
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
                    let region = &regions[e.region];
                    let own = own_desired_speed(l.speed_factor, l.max_speed, &region.road);
                    passage(&mut v, &e, region, own);
                }
                v
            })
            .collect();
        vehicles.extend(self.never_inserted(trips));
        vehicles
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
    let merging = region.road.is_auxiliary(lane) && region.road.lane_exists(lane, front);
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
