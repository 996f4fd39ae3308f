//! Step times: how long SUMO's steps and the controller's planning rounds took, for
//! `timing.csv`.
//!
//! Apart from the runner so that the stopwatches are one part with one job: the lock-step loop
//! asks it to run SUMO's step or a planning round and does not handle clocks itself. Nothing
//! measured here changes what the episode computes.

use std::time::Instant;

use crate::episode::metrics::{percentile, Timing};
use crate::sumo::{Simulation, SumoError};

/// The durations of an episode's SUMO steps and planning rounds.
pub struct StepTimes {
    /// Each planning round, in order (ms).
    plan_ms: Vec<f64>,
    /// The safety shield's part of each planning round (ms).
    shield_ms: Vec<f64>,
    /// Time inside SUMO's steps, all together (s).
    sumo_s: f64,
}

impl StepTimes {
    /// Stopwatches for an episode of `steps` steps.
    pub fn new(steps: u32) -> Self {
        StepTimes {
            plan_ms: Vec::with_capacity(steps as usize),
            shield_ms: Vec::with_capacity(steps as usize),
            sumo_s: 0.0,
        }
    }

    /// Advances SUMO by one step, timed.
    ///
    /// # Errors
    /// SUMO failing to step.
    pub fn sumo_step(&mut self, sim: &mut Simulation) -> Result<(), SumoError> {
        let t0 = Instant::now();
        sim.step()?;
        self.sumo_s += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// A planning round (every region's planner in one step): it took
    /// `plan_ms`, of which the shields' part `shield_ms`.
    pub fn add_round(&mut self, plan_ms: f64, shield_ms: f64) {
        self.plan_ms.push(plan_ms);
        self.shield_ms.push(shield_ms);
    }

    /// The episode's timing, given the stepping loop's duration `loop_s` over `steps` steps;
    /// `wall_s` is left to the caller, who saw SUMO start and close.
    pub fn timing(self, loop_s: f64, steps: u32) -> Timing {
        let mut plan = self.plan_ms;
        let mut shield = self.shield_ms;
        let plan_ms_total = plan.iter().sum();
        Timing {
            plan_ms_median: percentile(&mut plan, 50.0),
            plan_ms_p99: percentile(&mut plan, 99.0),
            plan_ms_max: plan.last().copied().unwrap_or(0.0),
            plan_ms_total,
            sumo_ms_per_step: self.sumo_s * 1e3 / steps as f64,
            episode_ms_per_step: loop_s * 1e3 / steps as f64,
            wall_s: 0.0,
            shield_ms_median: percentile(&mut shield, 50.0),
            shield_ms_p99: percentile(&mut shield, 99.0),
            shield_ms_max: shield.last().copied().unwrap_or(0.0),
        }
    }
}
