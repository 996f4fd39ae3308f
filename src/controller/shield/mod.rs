//! The safety shield (the paper's "safety envelope"): a last check of every CAV's next step
//! against bounded worst-case behaviour of the others, in the spirit of responsibility-sensitive
//! safety, before a search-based planner's maneuvers go to SUMO.
//!
//! Two rooms: [`check`] is the pure worst-case check of one maneuver (and its least intrusive
//! safe replacement); this module puts it to work, as a [`Controller`] decorator ([`Shielded`])
//! between any controller and SUMO, and as the search's [`StartGuard`], so that no plan counts
//! on a lane-change start the shield would withdraw.

pub mod check;
pub mod cut_in;
pub mod far_side;

pub use check::WorstCase;

use self::check::{bit, is_safe, replacement, Sent};
use super::{CavBelief, CavHandling, Command, Controller, LaneChange, Maneuver, PlanStats, Source};
use crate::config::Config;
use crate::model::scene::Scene;
use crate::planner::guard::StartGuard;

/// The shield as the search's [`StartGuard`]: a lane change may be planned only if the shield
/// would let it start, so no plan (which other CAVs are planned against) counts on a start the
/// shield would then withdraw.
impl StartGuard for WorstCase {
    fn admits(&self, scene: &Scene, agent: usize, lane_offset: i32, first_speed: f64) -> bool {
        let lane_change = match lane_offset {
            1 => Some(LaneChange::Left),
            -1 => Some(LaneChange::Right),
            _ => None,
        };
        let m = Maneuver {
            speed: first_speed,
            lane_change,
        };
        // The hardest braking is what the shield would send instead: always admitted.
        let strongest = (scene.vehicles[agent].speed - self.cav_decel * self.dt).max(0.0);
        let hardest = lane_change.is_none() && first_speed <= strongest + 1e-9;
        hardest || is_safe(scene, agent, &m, self, &[])
    }
}

/// The shield's worst cases as the lane-change guard of the search, when `config` turns it on.
pub fn start_guard(config: &Config) -> Option<WorstCase> {
    config.safety.shield.then(|| WorstCase::from_config(config))
}

/// Any controller with the shield between it and SUMO: its commands checked and, when unsafe,
/// replaced (marked [`Source::Shield`], counted in [`PlanStats::shield_overrides`]).
pub struct Shielded {
    inner: Box<dyn Controller>,
    bounds: WorstCase,
    overrides: u64,
    /// Wall time of the last step's checks (ms).
    last_ms: f64,
}

impl Shielded {
    /// `inner` behind the shield of `config`'s worst cases.
    pub fn new(inner: Box<dyn Controller>, config: &Config) -> Self {
        Shielded {
            inner,
            bounds: WorstCase::from_config(config),
            overrides: 0,
            last_ms: 0.0,
        }
    }
}

impl Controller for Shielded {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn handling(&self) -> CavHandling {
        self.inner.handling()
    }

    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>) {
        let start = out.len();
        self.inner.plan(scene, out);
        let started = std::time::Instant::now();
        self.overrides = 0;
        // What was let through so far this step, per scene vehicle.
        let mut sent = vec![Sent::default(); scene.vehicles.len()];
        for c in &mut out[start..] {
            if let Some(m) = replacement(scene, c.vehicle, &c.maneuver, &self.bounds, &sent) {
                if c.maneuver.lane_change.is_some() && m.lane_change.is_none() {
                    self.inner
                        .lane_change_cancelled(&scene.vehicles[c.vehicle].id);
                }
                c.maneuver = m;
                c.source = Source::Shield;
                self.overrides += 1;
            }
            let v = &mut sent[c.vehicle];
            v.speed = Some(c.maneuver.speed);
            if let Some(lc) = c.maneuver.lane_change {
                v.entering |= bit(scene.vehicles[c.vehicle].lane + lc.offset());
            }
        }
        self.last_ms = started.elapsed().as_secs_f64() * 1e3;
    }

    fn last_shield_ms(&self) -> f64 {
        self.last_ms
    }

    fn last_stats(&self) -> PlanStats {
        PlanStats {
            shield_overrides: self.overrides,
            ..self.inner.last_stats()
        }
    }

    fn set_tracing(&mut self, on: bool) {
        self.inner.set_tracing(on);
    }

    fn beliefs(&self) -> Vec<CavBelief> {
        self.inner.beliefs()
    }

    fn lane_change_cancelled(&mut self, id: &str) {
        self.inner.lane_change_cancelled(id);
    }
}

#[cfg(test)]
mod tests;
