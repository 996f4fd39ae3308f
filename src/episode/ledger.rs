//! The episode's ledger: who is where. Every vehicle SUMO inserted gets a line (its
//! [`VehicleRecord`] and where it was last seen) the step it departs; collisions and arrivals
//! close lines; every reading of a vehicle on the section updates one.
//!
//! It exists so that the accounting that `vehicles.csv`, `collisions.csv` and the summary are
//! computed from lives in one place, apart from the stepping: the ledger never talks to SUMO,
//! the runner hands it what SUMO said.

use std::collections::HashMap;
use std::sync::Arc;

use crate::config::{Config, Scenario, TStarSpeed};
use crate::episode::demand::PlannedVehicle;
use crate::episode::metrics::{CollisionEvent, FreeFlow, Outcome, VehicleRecord};
use crate::model::kinematics::free_flow_time;
use crate::model::road::Road;
use crate::model::scene::{Kind, Origin};
use crate::sumo::{frame, VehicleReadings};

/// A vehicle's line in the ledger: its record, and where it was last seen on the section
/// (for interpolating its arrival and for the distance it covered).
pub struct Tracked {
    pub id: Arc<str>,
    pub record: VehicleRecord,
    last_time: f64,
    last_front: f64,
    last_speed: f64,
    /// Frame position of its front at insertion.
    insert_front: f64,
    /// The off-ramp it leaves by, outside the frame: it arrives when SUMO says so.
    exit: Option<usize>,
    /// Route distance still ahead of it at the episode's end, as SUMO measured it.
    remaining_at_end: Option<f64>,
}

impl Tracked {
    /// Who it is, for the translation of its readings into the road frame.
    pub fn identity(&self) -> frame::Identity {
        frame::Identity {
            id: self.id.clone(),
            kind: self.record.kind,
            origin: self.record.origin,
            desired_speed: self.record.desired_speed,
        }
    }
}

/// What the demand planned for a vehicle SUMO just inserted.
pub struct Expected {
    pub origin: Origin,
    pub desired_speed: f64,
    /// The insertion speed drawn (m/s).
    pub speed: f64,
    /// The scheduled departure time (s).
    pub depart: f64,
    /// The off-ramp it leaves by, if any.
    pub exit: Option<usize>,
}

/// A vehicle SUMO just inserted, as SUMO describes it.
pub struct Departure {
    pub id: String,
    pub sumo_type: String,
    pub kind: Kind,
    /// Route distance from its insertion position to the end of its route (m).
    pub distance: f64,
    pub expected: Expected,
}

/// The ledger at the end of an episode: what its summary and CSV files are computed from.
pub struct Books {
    pub scheduled: usize,
    pub vehicles: Vec<VehicleRecord>,
    pub collisions: Vec<CollisionEvent>,
    /// Sum and count of the speeds of every reading on the section.
    pub speed_sum: f64,
    pub speed_samples: u64,
}

/// Who is where: the demand's plan, a line per inserted vehicle, the collisions.
pub struct Ledger<'a> {
    scenario: &'a Scenario,
    t_star_speed: TStarSpeed,
    section_end: f64,
    plan: &'a [PlannedVehicle],
    planned: HashMap<&'a str, &'a PlannedVehicle>,
    /// Route distance (m) from the insertion position per planned (entry, exit), as SUMO
    /// measured it for the first vehicle inserted there: every later one starts there too.
    route_distance: HashMap<(usize, Option<usize>), f64>,
    scheduled: usize,
    tracked: Vec<Tracked>,
    index: HashMap<Arc<str>, usize>,
    collisions: Vec<CollisionEvent>,
    /// Tracked index of each reading, valid for `slots_generation`.
    slots: Vec<Option<usize>>,
    slots_generation: u64,
    speed_sum: f64,
    speed_samples: u64,
}

impl<'a> Ledger<'a> {
    pub fn new(config: &'a Config, road: &Road, planned: &'a [PlannedVehicle]) -> Self {
        Ledger {
            scenario: &config.scenario,
            t_star_speed: config.metrics.t_star_speed,
            section_end: road.section_end,
            plan: planned,
            planned: planned.iter().map(|p| (p.id.as_str(), p)).collect(),
            route_distance: HashMap::new(),
            scheduled: planned.len(),
            tracked: Vec::new(),
            index: HashMap::new(),
            collisions: Vec::new(),
            slots: Vec::new(),
            slots_generation: u64::MAX,
            speed_sum: 0.0,
            speed_samples: 0,
        }
    }

    /// What the demand planned for `id`, departing at `now`; a vehicle it did not plan counts
    /// as a main-road one wanting `v_max`, inserted standing, on time.
    pub fn expected(&self, id: &str, now: f64) -> Expected {
        let planned = self.planned.get(id).copied();
        Expected {
            origin: planned.map_or(Origin::Main, |p| p.origin),
            desired_speed: planned.map_or(self.scenario.v_max, |p| p.desired_speed),
            speed: planned.map_or(0.0, |p| p.depart_speed),
            depart: planned.map_or(now, |p| p.depart),
            exit: planned.and_then(|p| p.exit),
        }
    }

    /// Opens the line of a vehicle that departed at `now`.
    pub fn book_departure(&mut self, d: Departure, now: f64) {
        let sc = self.scenario;
        let e = d.expected;
        let record = VehicleRecord {
            id: d.id.clone(),
            kind: d.kind,
            sumo_type: d.sumo_type,
            origin: e.origin,
            scheduled_depart: e.depart,
            scheduled_speed: e.speed,
            // Lane and speed are filled in from the first reading, in this same step.
            insert_lane: -1,
            insert_time: now,
            insert_speed: f64::NAN,
            desired_speed: e.desired_speed,
            distance: d.distance,
            t_star: free_flow_time(d.distance, e.speed, sc.free_flow_accel, sc.v_max),
            covered: 0.0,
            system_delay: None,
            own_speed_delay: None,
            outcome: Outcome::Present,
            arrival_time: None,
            crash_time: None,
            crashed_with: Vec::new(),
            controllable_crash: false,
        };
        if let Some(p) = self.planned.get(d.id.as_str()) {
            self.route_distance
                .entry((p.entry, p.exit))
                .or_insert(d.distance);
        }
        let key: Arc<str> = Arc::from(d.id.as_str());
        self.index.insert(key.clone(), self.tracked.len());
        let front = self.section_end - d.distance;
        self.tracked.push(Tracked {
            id: key,
            record,
            last_time: now,
            last_front: front,
            last_speed: e.speed,
            insert_front: front,
            exit: e.exit,
            remaining_at_end: None,
        });
    }

    /// The kind of vehicle `id`, if it has a line: a collision's vehicle whose SUMO type does
    /// not say.
    pub fn kind_of(&self, id: &str) -> Option<Kind> {
        self.index.get(id).map(|&k| self.tracked[k].record.kind)
    }

    /// Books the collisions of a step ([`crate::episode::collisions`]): each vehicle in one is
    /// marked crashed, with whom, and the events kept.
    pub fn book_collisions(&mut self, events: Vec<CollisionEvent>) {
        for event in events {
            let controllable = event.controllable();
            for (me, other) in event.pairs() {
                if let Some(&k) = self.index.get(me) {
                    let r = &mut self.tracked[k].record;
                    r.outcome = Outcome::Crashed;
                    r.crash_time.get_or_insert(event.time);
                    r.crashed_with.push(other.to_string());
                    r.controllable_crash |= controllable;
                }
            }
            self.collisions.push(event);
        }
    }

    /// Books the vehicles SUMO reported arrived at `now`, at the time their front crossed the
    /// section's end.
    pub fn book_arrivals(&mut self, arrived: Vec<String>, now: f64) {
        let end = self.section_end;
        for id in arrived {
            let Some(&k) = self.index.get(id.as_str()) else {
                continue;
            };
            let t = &mut self.tracked[k];
            if t.record.outcome != Outcome::Present {
                continue; // SUMO 1.15 lists vehicles removed by a collision as arrived too
            }
            // The front crossed the end within the last step: interpolate at the last speed.
            let remaining = (end - t.last_front).max(0.0);
            let crossing = if t.exit.is_some() {
                now
            } else if t.last_speed > 0.1 {
                (t.last_time + remaining / t.last_speed).min(now)
            } else {
                now
            };
            t.record.outcome = Outcome::Arrived;
            t.record.arrival_time = Some(crossing.max(t.last_time));
        }
    }

    /// Matches this step's readings to lines (again only when the set of vehicles changed).
    pub fn match_readings(&mut self, readings: &VehicleReadings) {
        if self.slots_generation != readings.generation {
            self.slots.clear();
            self.slots.extend(
                readings
                    .ids
                    .iter()
                    .map(|id| self.index.get(id.as_str()).copied()),
            );
            self.slots_generation = readings.generation;
        }
    }

    /// The line of reading `i`, as [`Ledger::match_readings`] matched it; `None` for a vehicle
    /// without one.
    pub fn slot(&self, i: usize) -> Option<usize> {
        self.slots.get(i).copied().flatten()
    }

    /// Line `k`.
    pub fn tracked(&self, k: usize) -> &Tracked {
        &self.tracked[k]
    }

    /// Notes a reading of line `k` on the section at `now`: front bumper at `front` on road
    /// lane `lane`, at `speed`. The first one gives the insertion lane and speed.
    pub fn note_reading(
        &mut self,
        k: usize,
        now: f64,
        (front, lane): (f64, i32),
        speed: f64,
    ) -> &Tracked {
        let sc = self.scenario;
        let t = &mut self.tracked[k];
        if t.record.insert_lane < 0 {
            t.record.insert_lane = lane;
            t.record.insert_speed = speed;
            if self.t_star_speed == TStarSpeed::Inserted {
                let r = &mut t.record;
                r.t_star = free_flow_time(r.distance, speed, sc.free_flow_accel, sc.v_max);
            }
        }
        t.last_time = now;
        t.last_front = front;
        t.last_speed = speed;
        self.speed_sum += speed;
        self.speed_samples += 1;
        t
    }

    /// The lines still in the network, with the off-ramp each leaves by (if any): the
    /// runner asks SUMO how far each still has to go.
    pub fn present(&self) -> impl Iterator<Item = (usize, &str, Option<usize>)> {
        self.tracked
            .iter()
            .enumerate()
            .filter(|(_, t)| t.record.outcome == Outcome::Present)
            .map(|(k, t)| (k, &*t.id, t.exit))
    }

    /// Notes the route distance line `k` still had ahead at the episode's end (m, SUMO's
    /// measure): what it covered is its distance at insertion less this.
    pub fn note_remaining(&mut self, k: usize, remaining: f64) {
        self.tracked[k].remaining_at_end = Some(remaining);
    }

    /// The ledger closed at `end`, the time of the episode's last state: its records in order
    /// of departure, each settled, then one per planned vehicle never inserted (in the plan's
    /// order); and the collisions.
    pub fn close(self, end: f64) -> Books {
        let sc = self.scenario;
        let ff = FreeFlow {
            accel: sc.free_flow_accel,
            v_max: sc.v_max,
        };
        let t_star_speed = self.t_star_speed;
        let mut vehicles: Vec<VehicleRecord> = Vec::with_capacity(self.plan.len());
        for t in self.tracked {
            let covered = t.covered();
            let mut r = t.record;
            let v0 = match t_star_speed {
                TStarSpeed::Inserted if r.insert_speed.is_finite() => r.insert_speed,
                _ => r.scheduled_speed,
            };
            r.settle(end, covered, v0, ff);
            vehicles.push(r);
        }
        for p in self.plan {
            if !self.index.contains_key(p.id.as_str()) {
                let distance = self.route_distance.get(&(p.entry, p.exit)).copied();
                let mut r = never_inserted(p, distance.unwrap_or(f64::NAN), ff);
                r.settle(end, 0.0, p.depart_speed, ff);
                vehicles.push(r);
            }
        }
        Books {
            scheduled: self.scheduled,
            vehicles,
            collisions: self.collisions,
            speed_sum: self.speed_sum,
            speed_samples: self.speed_samples,
        }
    }
}

impl Tracked {
    /// The route distance it covered from insertion (m): all of it once arrived; for a vehicle
    /// still in the network what SUMO measured at the end (its route distance, exact on a
    /// curved ramp where the frame's `s` is scaled), else its last front less its first.
    fn covered(&self) -> f64 {
        let r = &self.record;
        match (r.outcome, self.remaining_at_end) {
            (Outcome::Arrived, _) => r.distance,
            (Outcome::Present, Some(left)) if (0.0..=r.distance + 1.0).contains(&left) => {
                (r.distance - left).max(0.0)
            }
            _ => (self.last_front - self.insert_front).clamp(0.0, r.distance),
        }
    }
}

/// The record of planned vehicle `p`, never inserted: as the demand planned it, its route
/// `distance` that of the vehicles inserted at its entry.
fn never_inserted(p: &PlannedVehicle, distance: f64, ff: FreeFlow) -> VehicleRecord {
    VehicleRecord {
        id: p.id.clone(),
        kind: p.kind,
        sumo_type: p.kind.as_str().into(),
        origin: p.origin,
        scheduled_depart: p.depart,
        scheduled_speed: p.depart_speed,
        insert_lane: -1,
        insert_time: f64::NAN,
        insert_speed: f64::NAN,
        desired_speed: p.desired_speed,
        distance,
        t_star: ff.time(distance, p.depart_speed),
        covered: 0.0,
        system_delay: None,
        own_speed_delay: None,
        outcome: Outcome::NeverInserted,
        arrival_time: None,
        crash_time: None,
        crashed_with: Vec::new(),
        controllable_crash: false,
    }
}
