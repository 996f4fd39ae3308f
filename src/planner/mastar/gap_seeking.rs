//! Gap seeking on the acceleration lane (`[planner] gap_seeking`, on by default on a scenario
//! of the user's own, off on the paper's demand): a ramp CAV keeps behind the
//! nearest vehicle ahead of it in the lane it merges into, as if that vehicle drove in its own
//! lane, so it lines up behind a gap at the target lane's speed instead of racing down an empty
//! acceleration lane past a slow lane 1 and braking to a stand at its end (IDM+MOBIL's CAVs and
//! SUMO's drivers adapt their speed so).
//!
//! Measured on SUMO's `ramp` game (α 0.6, seeds 400–409, `--trajectories`): without it a ramp
//! CAV ran the acceleration lane at 22 m/s beside a lane 1 crawling at 4 m/s, braked at 6 m/s²
//! to 2.6 m/s at the lane's end and merged from there, and after the game's demand steps up
//! 136 of 177 ramp-CAV merges started below 5 m/s; lane 1 at the merge broke down. The guide's
//! "Your own scenario" chapter gives the paired comparisons.

use crate::model::braking::{stays_clear, Braking};
use crate::model::kinematics::BicycleState;
use crate::model::trajectory::Trajectory;
use crate::planner::mastar::obstacles::Obstacles;
use crate::planner::mastar::{Mastar, Request};

impl Mastar {
    /// The vehicle a ramp CAV on its auxiliary lane keeps behind: the nearest one in the lane
    /// it merges into whose rear is ahead of the CAV's front, before the lane's end, carried
    /// over into the CAV's lane (its trajectory, at the CAV's lane centre). `None` when gap
    /// seeking is off, for a CAV not yet on the acceleration lane, one already changing lanes,
    /// and where no such vehicle is among `req.obstacles`.
    pub(super) fn gap_leader(&self, req: &Request) -> Option<Trajectory> {
        let seeks = self.seeks_gaps && req.must_merge && req.ongoing.is_none();
        if !seeks || !self.road.is_auxiliary(req.lane) {
            return None;
        }
        let front = req.start.pos.x + 0.5 * req.length;
        let zone = self.road.zone_on(req.lane, front)?;
        if front < zone.start {
            return None;
        }
        let target = self.road.toward_main(req.lane);
        let leader = (req.obstacles.iter())
            .filter(|t| self.road.lane_at(t.poses[0].y) == target)
            .filter(|t| t.poses[0].s - 0.5 * t.length > front && t.poses[0].s < zone.end)
            .min_by(|a, b| a.poses[0].s.total_cmp(&b.poses[0].s))?;
        let own_y = self.lane_y(req.lane);
        let mut beside = Trajectory::clone(leader);
        beside.poses.iter_mut().for_each(|p| p.y = own_y);
        beside.committed = false;
        Some(beside)
    }

    /// Whether a ramp CAV at `st` (`length` long) may start its merge into lane `target` at
    /// `step` of its plan, with gap seeking on: the nearest obstacle behind it in `target` then
    /// (as predicted) must stay clear of it braking at `rule.follower_brake` while the CAV drives
    /// one step and brakes at its emergency deceleration, the check the safety shield makes of
    /// the new follower when the start comes ([`crate::model::braking`]). The safety rule alone
    /// has that follower braking from the plan's start, as if it saw the change coming; SUMO's
    /// drivers do not open gaps for a CAV under TraCI control, so plans kept promising merges a
    /// few steps ahead that the shield refused when they came (SUMO's `ramp` game, seed 407:
    /// 2 486 plans moved over later after the shield had refused the move now, 250 moved now).
    /// True with gap seeking off and at the plan's first step, which the start guard judges.
    pub(super) fn merge_start_admitted(
        &self,
        (st, length): (&BicycleState, f64),
        target: i32,
        step: usize,
        obstacles: &Obstacles,
    ) -> bool {
        if !self.seeks_gaps || step == 0 {
            return true;
        }
        let target_y = self.lane_y(target);
        let follower = (obstacles.at(step).iter())
            .filter(|o| (o.pose.y - target_y).abs() < self.road.lane_width - 1e-6)
            .filter(|o| o.pose.s <= st.pos.x)
            .max_by(|a, b| a.pose.s.total_cmp(&b.pose.s));
        follower.is_none_or(|f| {
            let back = Braking {
                speed: f.forward_speed(),
                first: None,
                decel: self.rule.follower_brake,
                reach: f64::INFINITY,
            };
            let speed = st.speed * st.heading.cos();
            let front = Braking {
                speed,
                first: Some(speed),
                decel: self.rule.brake,
                reach: f64::INFINITY,
            };
            let gap = (st.pos.x - 0.5 * length) - (f.pose.s + 0.5 * f.length);
            stays_clear(back, front, gap, self.rule.margin_long, self.library.dt)
        })
    }
}
