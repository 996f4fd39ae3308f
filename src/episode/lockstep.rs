//! The one loop of every episode: SUMO and the planners in lock-step, over a source of traffic.
//!
//! Each step, whatever the traffic: the source adds what it inserts itself (the paper's entry
//! gate); SUMO advances; the source books its departures (taking control of the vehicles it
//! drives); every vehicle's state is read in one call; collisions are booked and their
//! vehicles removed ([`take_collisions`]); arrivals are booked; the source builds each merge
//! region's scene from the readings; the planners plan ([`Planning`]) after the source's own
//! rules (the paper's ramp HDVs' merge requests), and their maneuvers go back to SUMO.
//!
//! Two sources implement [`TrafficSource`]: the paper's generated demand on its merge, one region
//! (`episode::runner`), and a user's SUMO scenario with a region per merge
//! (`episode::sumocfg`). What they do differently is theirs: which vehicles are CAVs and when a
//! planner takes them over, how each is seen in a scene (sizes and limits from the config where
//! the paper says so, from SUMO on a user's scenario), and their books.

use std::time::Instant;

use crate::config::Config;
use crate::episode::collisions::{take_collisions, Crashes};
use crate::episode::error::EpisodeError;
use crate::episode::metrics::CollisionEvent;
use crate::episode::planning::Planning;
use crate::episode::region::Region;
use crate::model::scene::Kind;
use crate::sumo::{Simulation, SumoClient, SumoError, VehicleReadings};

/// A source of traffic and its books: what an episode of the paper's demand and one of a
/// user's scenario do differently, each step of the one loop.
pub trait TrafficSource {
    /// Before SUMO's step that starts at `now`: the vehicles the source inserts itself.
    fn admit(
        &mut self,
        _sim: &mut impl SumoClient,
        _now: f64,
        _regions: &[Region],
    ) -> Result<(), SumoError> {
        Ok(())
    }

    /// The vehicles SUMO inserted in the step that began at `now`, booked (and taken over
    /// where the source's planners drive them from their insertion on).
    fn book_departures(
        &mut self,
        sim: &mut impl SumoClient,
        now: f64,
        regions: &[Region],
    ) -> Result<(), SumoError>;

    /// A vehicle in a collision: its kind, by its SUMO type `type_id` or the source's books.
    fn kind_of(&self, id: &str, type_id: &str) -> Option<Kind>;

    /// Whether vehicle `id`, in a collision, is removed from SUMO now.
    fn removes(&self, id: &str) -> bool;

    /// The step's collisions, booked (their vehicles already removed where [`Self::removes`]).
    fn book_collisions(&mut self, events: Vec<CollisionEvent>, now: f64);

    /// The vehicles that arrived in the step that began at `now`.
    fn book_arrivals(&mut self, arrived: Vec<String>, now: f64);

    /// Each region's scene of this step from `readings` (the regions' scenes are empty on
    /// entry), taking CAVs over or handing them back where the source says.
    fn build_scenes(
        &mut self,
        sim: &mut impl SumoClient,
        readings: &VehicleReadings,
        regions: &mut [Region],
        now: f64,
    ) -> Result<(), SumoError>;

    /// Before the planners plan on this step's scenes: the source's own rules for the
    /// vehicles SUMO drives (the paper's ramp HDVs' merge requests).
    fn before_plan(
        &mut self,
        _sim: &mut impl SumoClient,
        _regions: &[Region],
    ) -> Result<(), SumoError> {
        Ok(())
    }

    /// After the last step, before SUMO closes (the paper's distances still to go).
    fn at_the_end(&mut self, _sim: &impl SumoClient, _regions: &[Region]) -> Result<(), SumoError> {
        Ok(())
    }
}

/// An episode in lock-step: its traffic and its planning.
pub struct Lockstep<'a, T> {
    pub(crate) traffic: T,
    pub(crate) planning: Planning<'a>,
    readings: VehicleReadings,
}

impl<'a, T: TrafficSource> Lockstep<'a, T> {
    /// The episode of `traffic` planned by `planning`.
    pub fn new(traffic: T, planning: Planning<'a>) -> Self {
        Lockstep {
            traffic,
            planning,
            readings: VehicleReadings::default(),
        }
    }

    /// Runs the episode's `config.scenario.steps` steps, then closes SUMO (which writes its
    /// own outputs).
    ///
    /// # Errors
    /// SUMO failing at a step, or a stop signal between two steps.
    pub fn run(&mut self, mut sim: Simulation, config: &Config) -> Result<(), EpisodeError> {
        let names = self.planning.edge_names();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let start = Instant::now();
        lock_step(&mut sim, &names, config, |sim, plan| {
            // The time of the state this step produces, on SUMO's clock: SUMO's own outputs
            // (FCD, tripinfo, collisions) label the state after a step with the time the step
            // started, and a vehicle added now departs at this time. `sim.time()` after the
            // step is one step later.
            let now = sim.time()?;
            self.traffic.admit(sim, now, &self.planning.regions)?;
            self.planning.sumo_step(sim)?;
            self.after_step(sim, now, plan)
        })?;
        let (dt, steps) = (config.scenario.dt, config.scenario.steps);
        self.planning
            .close_timing(start.elapsed().as_secs_f64(), steps);
        (self.traffic)
            .at_the_end(&sim, &self.planning.regions)
            .map_err(step_error(dt, steps))?;
        sim.close().map_err(step_error(dt, steps))
    }

    /// What follows a SUMO step that began at `now`: departures, collisions and arrivals
    /// booked, every region's scene built and, when `plan` (not after the last step), one
    /// planning round with its commands sent.
    pub fn after_step(
        &mut self,
        sim: &mut impl SumoClient,
        now: f64,
        plan: bool,
    ) -> Result<(), SumoError> {
        let regions = &self.planning.regions;
        self.traffic.book_departures(sim, now, regions)?;
        // Read before the collided vehicles are removed: their state at this time counts, as
        // in SUMO's own outputs (a vehicle may collide in the step it was inserted).
        sim.read_vehicles(&mut self.readings)?;
        let mut crashes = Crashed {
            traffic: &self.traffic,
            planning: &mut self.planning,
        };
        let events = take_collisions(sim, now, &mut crashes)?;
        self.traffic.book_collisions(events, now);
        self.traffic.book_arrivals(sim.arrived()?, now);
        self.planning.begin_step(now);
        let regions = &mut self.planning.regions;
        (self.traffic).build_scenes(sim, &self.readings, regions, now)?;
        self.planning.scenes_built();
        if plan {
            self.traffic.before_plan(sim, &self.planning.regions)?;
            self.planning.plan(sim)?;
        }
        Ok(())
    }
}

/// The vehicles of a collision, as the traffic tells them apart and removes them; each one
/// removed is told to the planning.
struct Crashed<'t, 'p, 'a, T> {
    traffic: &'t T,
    planning: &'p mut Planning<'a>,
}

impl<T: TrafficSource> Crashes for Crashed<'_, '_, '_, T> {
    fn kind_of(&self, id: &str, type_id: &str) -> Option<Kind> {
        self.traffic.kind_of(id, type_id)
    }
    fn removes(&self, id: &str) -> bool {
        self.traffic.removes(id)
    }
    fn removed(&mut self, id: &str) {
        self.planning.removed_in_collision(id);
    }
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
