//! The planning side of an episode, whatever its traffic: its merge regions (each with its
//! scene, planner, commands, trajectories and trace), the caller's [`Observer`], the optional
//! [`Round`] that plans every region at once, and what they cost (planning times, search
//! effort, vehicles per step).
//!
//! The paper's merge is one region; a user's scenario has one per merge. Each step the traffic
//! source fills the regions' scenes ([`TrafficSource::build_scenes`](crate::episode::lockstep::TrafficSource));
//! then every region is planned, in parallel when there are several (each region's planner
//! sees only its own scene and keeps its own state, so the rounds are independent and each is
//! deterministic), and the commanded regions' maneuvers go to SUMO.

use std::sync::Arc;
use std::time::Instant;

use crate::config::TrajectoryFormat;
use crate::controller::Command;
use crate::controller::PlanStats;
use crate::episode::metrics::Timing;
use crate::episode::observer::Observer;
use crate::episode::recording::Recording;
use crate::episode::region::Region;
use crate::episode::round::{plan_together, Round};
use crate::episode::step_times::StepTimes;
use crate::episode::trajectories::TrajectoryFile;
use crate::model::scene::Kind;
use crate::sumo::frame::{self, SumoScene};
use crate::sumo::{Simulation, SumoClient, SumoError};

/// A region's file: its name and its content.
pub type RegionFile<T> = (String, T);

/// The regions of an episode and their planning.
pub struct Planning<'a> {
    pub(crate) regions: Vec<Region<'a>>,
    observer: Box<dyn Observer + 'a>,
    /// Plans every region at once in place of their own planners, when given.
    round: Option<Box<dyn Round>>,
    /// The vehicles removed in collisions since the last planning round.
    crashed: Vec<Arc<str>>,
    times: StepTimes,
    /// The episode's timing, once its loop has ended.
    pub(crate) timing: Option<Timing>,
    /// The planners' search effort, over every round of every region.
    pub(crate) plan_stats: PlanStats,
    /// Steps seen, and the vehicles and CAVs in the regions' scenes over them.
    occupancy: (u64, u64, u64),
}

impl<'a> Planning<'a> {
    /// The planning of `regions` over `steps` steps, shown to `observer`, by `round` when
    /// given. Each region's edges get codes after the previous region's; each planner keeps its
    /// beliefs when its trace or the observer wants them.
    pub fn new(
        mut regions: Vec<Region<'a>>,
        observer: Box<dyn Observer + 'a>,
        round: Option<Box<dyn Round>>,
        steps: u32,
    ) -> Self {
        let mut offset = 0;
        for r in &mut regions {
            r.code_offset = offset;
            offset += r.road.edges.len() as i32;
            let beliefs = r.trace.is_some() || observer.wants_beliefs();
            if let Some(c) = &mut r.controller {
                c.set_tracing(beliefs);
            }
        }
        Planning {
            regions,
            observer,
            round,
            crashed: Vec::new(),
            times: StepTimes::new(steps),
            timing: None,
            plan_stats: PlanStats::default(),
            occupancy: (0, 0, 0),
        }
    }

    /// Shows every region's scenes to `observer` from now on, in place of the one given.
    pub fn observe_with(&mut self, observer: Box<dyn Observer + 'a>) {
        for r in &mut self.regions {
            if let Some(c) = &mut r.controller {
                c.set_tracing(r.trace.is_some() || observer.wants_beliefs());
            }
        }
        self.observer = observer;
    }

    /// The names of every region's edges, in the order of their codes in the readings.
    pub fn edge_names(&self) -> Vec<String> {
        self.regions
            .iter()
            .flat_map(|r| frame::edge_names(&r.road))
            .map(String::from)
            .collect()
    }

    /// Advances SUMO by one step, timed.
    pub(crate) fn sumo_step(&mut self, sim: &mut Simulation) -> Result<(), SumoError> {
        self.times.sumo_step(sim)
    }

    /// Starts the step whose state is labelled `time`: every region's scene empty.
    pub(crate) fn begin_step(&mut self, time: f64) {
        for r in &mut self.regions {
            r.begin_step(time);
        }
    }

    /// Vehicle `id` was removed in a collision: the observer hears of it, the round will.
    pub(crate) fn removed_in_collision(&mut self, id: &str) {
        self.observer.removed_in_collision(id);
        self.crashed.push(Arc::from(id));
    }

    /// The step's scenes are built: counted, and shown to the observer.
    pub(crate) fn scenes_built(&mut self) {
        self.occupancy.0 += 1;
        for r in &mut self.regions {
            r.nose
                .apply(&mut r.scene.scene, r.config.scenario.lane_change_duration);
        }
        for (k, r) in self.regions.iter().enumerate() {
            let vehicles = &r.scene.scene.vehicles;
            self.occupancy.1 += vehicles.len() as u64;
            self.occupancy.2 += vehicles.iter().filter(|v| v.kind == Kind::Cav).count() as u64;
            self.observer.observe_region(k, &r.scene.scene);
        }
    }

    /// One planning round of every region, then each commanded region's maneuvers sent to
    /// SUMO (recorded in its trajectories, shown in sumo-gui).
    pub(crate) fn plan(&mut self, sim: &mut impl SumoClient) -> Result<(), SumoError> {
        self.plan_regions();
        for r in &mut self.regions {
            if let Some(c) = &r.controller {
                self.observer
                    .planned(&r.scene.scene, &r.commands, c.as_ref());
            }
        }
        for r in &mut self.regions {
            if r.commanded() {
                let sc = &r.config.scenario;
                send_commands(sim, &r.scene, &r.commands, sc)?;
                r.nose.note(&r.scene, &r.commands);
                r.record_sent();
                if let Some(gui) = &mut r.gui {
                    gui.update(sim, &r.scene.scene, &r.commands)?;
                }
            }
        }
        Ok(())
    }

    /// Every region's planner (or the round) on its scene, timed together: the step's
    /// planning time, with the shields' part of it.
    fn plan_regions(&mut self) {
        use rayon::prelude::*;
        let start = Instant::now();
        let crashed = std::mem::take(&mut self.crashed);
        if let Some(round) = &mut self.round {
            plan_together(round.as_mut(), &mut self.regions, &crashed);
        }
        let plan = |r: &mut Region<'a>| {
            if let Some(c) = &mut r.controller {
                r.commands.clear();
                c.plan(&r.scene.scene, &mut r.commands);
                if let Some(t) = &mut r.trace {
                    t.planned(&r.scene.scene, &r.commands, c.as_ref());
                }
            }
        };
        // One region plans on this thread; several in parallel.
        match self.regions.as_mut_slice() {
            [one] => plan(one),
            all => all.par_iter_mut().for_each(plan),
        }
        let controllers = || self.regions.iter().filter_map(|r| r.controller.as_ref());
        let shield_ms = controllers().map(|c| c.last_shield_ms()).sum();
        for c in controllers() {
            self.plan_stats += c.last_stats();
        }
        self.times
            .add_round(start.elapsed().as_secs_f64() * 1e3, shield_ms);
    }

    /// Ends the episode's timing, its loop having taken `loop_s` seconds over `steps` steps.
    pub fn close_timing(&mut self, loop_s: f64, steps: u32) {
        let times = std::mem::replace(&mut self.times, StepTimes::new(0));
        self.timing = Some(times.timing(loop_s, steps));
    }

    /// Vehicles and CAVs in the regions' scenes per step, on average.
    pub(crate) fn per_step(&self) -> (f64, f64) {
        let (steps, vehicles, cavs) = self.occupancy;
        let per_step = |n: u64| n as f64 / steps.max(1) as f64;
        (per_step(vehicles), per_step(cavs))
    }

    /// Each region's trajectories and trace, taken out of it.
    pub(crate) fn take_files(
        &mut self,
    ) -> (Vec<RegionFile<TrajectoryFile>>, Vec<RegionFile<String>>) {
        let trajectories = (self.regions.iter_mut())
            .filter_map(|r| {
                let file =
                    std::mem::replace(&mut r.recording, Recording::new(TrajectoryFormat::None))
                        .finish()?;
                Some((r.name.clone(), file))
            })
            .collect();
        let traces = (self.regions.iter_mut())
            .filter_map(|r| Some((r.name.clone(), r.trace.take()?.text().to_string())))
            .collect();
        (trajectories, traces)
    }
}

/// Sends `commands` for the vehicles of `scene` to SUMO: speeds in one batch, then lane changes
/// (into the SUMO lane of the target frame lane, where there is one).
fn send_commands(
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
