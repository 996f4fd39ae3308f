//! The rule a planned CAV keeps toward every other vehicle, shared by M-A* (toward obstacles)
//! and BK-PBS (to decide which pairs of trajectories conflict).
//!
//! Clear means: the bodies do not overlap (the CAV's inflated by the planner's margins), and in
//! its lane the CAV keeps a safe gap to the vehicle in front, and, after it changed lanes (a cut
//! in), to the vehicle behind: gap ≥ `safe_gap` + v_back·`reaction_time` +
//! (v_back²/(2·b) − v_front²/(2·b_front))⁺, so that either could stop if the one in front
//! brakes as hard as it can. b is the CAVs' emergency deceleration; b_front is the front
//! vehicle's, b too unless its trajectory says otherwise (an HDV may brake at SUMO's
//! emergencyDecel, harder than a CAV: the safety shield assumes it, and a plan that did not
//! would be overridden by the shield step after step).
//!
//! The vehicle behind in its own lane is that vehicle's business, even when a constant-speed
//! prediction drives it into the CAV: a follower brakes (SUMO's IDM does), and only a CAV that
//! cut in is responsible for the gap behind it. That follower is checked as braking at
//! `follower_brake` from the start of the plan (responsibility-sensitive safety: it sees the
//! change begin), the same braking the safety shield asks of it at most; checked at its
//! predicted constant speed instead, it would close on a slow merger until no gap behind was
//! ever enough, and a ramp CAV that had slowed down could not merge in front of traffic however
//! far back.

use crate::config::PlannerSettings;
use crate::model::geometry::{intersection_test_obb_obb, OrientedBox};
use crate::model::math::Point;
use crate::model::trajectory::{Pose, Trajectory};

/// Parameters of the rule.
#[derive(Debug, Clone, PartialEq)]
pub struct SafetyRule {
    /// The CAV's box is inflated by this much along the road (m, each end).
    pub margin_long: f64,
    /// The same across the road (m, each side); also widens the same-lane test.
    pub margin_lat: f64,
    /// Smallest bumper gap kept on top of the reaction and braking terms (m).
    pub safe_gap: f64,
    /// Reaction time of the vehicle behind in the gap rule (s).
    pub reaction_time: f64,
    /// Emergency deceleration b (m/s², positive).
    pub brake: f64,
    /// Braking (m/s², positive) a CAV's cut-in may ask of the vehicle it cuts in front of, which
    /// is taken to brake so from the start of the plan (it sees the change begin); the safety
    /// shield asks no more of it (`idm.decel`, set by [`crate::planner::mastar::Mastar::from_config`]).
    pub follower_brake: f64,
    /// Lane width (m): moved more than half of it sideways since the start, the CAV cut in.
    pub lane_width: f64,
}

/// A vehicle at one step: where it is, how big it is and how hard it may brake.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Where it is at this step.
    pub pose: Pose,
    /// Body length (m).
    pub length: f64,
    /// Body width (m).
    pub width: f64,
    /// See [`Trajectory::brake`].
    pub brake: Option<f64>,
    /// See [`Trajectory::committed`].
    pub committed: bool,
    /// Speed along the road (m/s): `pose.speed · cos(pose.heading)`, computed once with the
    /// body, since the rule asks for it at almost every check and a cosine is most of a check's
    /// cost.
    forward: f64,
}

impl Body {
    /// A body at `pose`, `length` × `width` (m), braking at most at `brake` (m/s², `None`: as
    /// hard as a CAV).
    pub fn new(pose: Pose, length: f64, width: f64, brake: Option<f64>) -> Body {
        Body {
            pose,
            length,
            width,
            brake,
            committed: false,
            forward: pose.speed * pose.heading.cos(),
        }
    }

    /// The body of `t` at `step`.
    pub fn of(t: &Trajectory, step: usize, dt: f64) -> Body {
        Body {
            committed: t.committed,
            ..Body::new(t.at(step, dt), t.length, t.width, t.brake)
        }
    }

    /// Speed along the road (m/s).
    pub fn forward_speed(&self) -> f64 {
        self.forward
    }
}

/// Beyond this distance along the road no pair can be in conflict (m).
pub const REACH: f64 = 120.0;

impl SafetyRule {
    /// The rule of the planner `settings`, on lanes `lane_width` wide (m).
    pub fn new(settings: &PlannerSettings, lane_width: f64) -> Self {
        SafetyRule {
            margin_long: settings.margin_long,
            margin_lat: settings.margin_lat,
            safe_gap: settings.safe_gap,
            reaction_time: settings.reaction_time,
            brake: settings.emergency_decel,
            follower_brake: settings.emergency_decel,
            lane_width,
        }
    }

    /// Gap the vehicle behind needs to the one in front (m), both braking as hard as a CAV.
    pub fn needed_gap(&self, v_back: f64, v_front: f64) -> f64 {
        self.needed_gap_to(v_back, v_front, self.brake)
    }

    /// Gap the vehicle behind (braking as hard as a CAV) needs to one in front that may brake at
    /// `front_brake` (m).
    pub fn needed_gap_to(&self, v_back: f64, v_front: f64, front_brake: f64) -> f64 {
        let stops = v_back * v_back / (2.0 * self.brake) - v_front * v_front / (2.0 * front_brake);
        self.safe_gap + v_back * self.reaction_time + stops.max(0.0)
    }

    /// Whether the CAV `me`, `t` seconds into its plan, is clear of `other`; `me_now` and
    /// `other_now` are where both are at the start of the plan.
    ///
    /// A gap that is already too small now (e.g. someone merged in front) cannot be repaired at
    /// once: the gap required is then at most the one the CAV keeps by braking at the emergency
    /// deceleration from now on, so braking hard is always an acceptable answer to it.
    pub fn clear(&self, me: &Body, me_now: &Body, other: &Body, other_now: &Body, t: f64) -> bool {
        let (p, o) = (&me.pose, &other.pose);
        if (o.s - p.s).abs() > REACH {
            return true;
        }
        let same_lane = self.same_lane(me, other);
        let cut_in = (p.y - me_now.pose.y).abs() > 0.5 * self.lane_width;
        // The vehicle the CAV cuts in front of brakes (RSS): it is checked braking from the
        // start of the plan, not driven on at its predicted speed into (or through) the CAV,
        // which would forbid every slow merge in front of traffic however far back it is. One
        // predicted clear ahead by then was merged in behind, and is a leader like any other.
        // A committed plan does not brake for the CAV: it is checked as planned.
        let passed = o.s - p.s > 0.5 * (me.length + other.length) + self.margin_long;
        let yields = same_lane && cut_in && !other.committed;
        let braked;
        let (other, o) = if yields && other_now.pose.s <= me_now.pose.s && !passed {
            braked = self.braking(other_now, other, t);
            (&braked, &braked.pose)
        } else {
            (other, o)
        };
        // In front: now, or at the start (so driving through a vehicle between two steps still
        // counts as hitting it).
        let ahead = o.s > p.s || other_now.pose.s > me_now.pose.s;
        if same_lane && !ahead && !cut_in {
            return true;
        }
        let mine = OrientedBox::vehicle(
            Point::new(p.s, p.y),
            p.heading,
            me.length + 2.0 * self.margin_long,
            me.width + 2.0 * self.margin_lat,
        );
        let theirs =
            OrientedBox::vehicle(Point::new(o.s, o.y), o.heading, other.length, other.width);
        if intersection_test_obb_obb(&mine, &theirs) {
            return false;
        }
        if !same_lane {
            return true;
        }
        let (v, vo) = (me.forward_speed(), other.forward_speed());
        if ahead {
            let required = self.needed_gap_to(v, vo, other.brake.unwrap_or(self.brake));
            gap(me, other) >= self.relaxed(required, me_now, other_now, other, t)
        } else if cut_in {
            gap(other, me) >= self.needed_gap(vo, v)
        } else {
            true
        }
    }

    /// `later` (the predicted pose at `t`) moved along the road as if braking at
    /// `follower_brake` from `now` instead.
    fn braking(&self, now: &Body, later: &Body, t: f64) -> Body {
        let stopping = braked(now, self.follower_brake, t);
        let pose = Pose {
            s: stopping.pose.s,
            speed: stopping.pose.speed,
            heading: 0.0,
            ..later.pose
        };
        Body::new(pose, later.length, later.width, later.brake)
    }

    fn same_lane(&self, a: &Body, b: &Body) -> bool {
        (a.pose.y - b.pose.y).abs() < 0.5 * (a.width + b.width) + self.margin_lat
    }

    /// `required`, lowered to the gap an emergency stop from now would leave to `front` at `t`,
    /// if `back_now` already follows `front_now` too closely in the same lane.
    fn relaxed(
        &self,
        required: f64,
        back_now: &Body,
        front_now: &Body,
        front: &Body,
        t: f64,
    ) -> f64 {
        if !self.same_lane(back_now, front_now) || front_now.pose.s <= back_now.pose.s {
            return required;
        }
        let v0 = back_now.forward_speed();
        let front_brake = front_now.brake.unwrap_or(self.brake);
        if gap(back_now, front_now)
            >= self.needed_gap_to(v0, front_now.forward_speed(), front_brake)
        {
            return required;
        }
        let stopping = braked(back_now, self.brake, t);
        // A hair below, so the braking plan itself passes despite rounding.
        required.min(gap(&stopping, front) - 1e-6)
    }
}

/// `body` after braking at `decel` for `t` seconds from its forward speed (standing once
/// stopped): where it is and how fast it goes.
fn braked(body: &Body, decel: f64, t: f64) -> Body {
    let v0 = body.forward_speed();
    let t_stop = (v0 / decel).min(t);
    let pose = Pose {
        s: body.pose.s + v0 * t_stop - 0.5 * decel * t_stop * t_stop,
        speed: v0 - decel * t_stop,
        ..body.pose
    };
    Body::new(pose, body.length, body.width, body.brake)
}

/// Bumper gap from `back` to `front` (m).
fn gap(back: &Body, front: &Body) -> f64 {
    (front.pose.s - 0.5 * front.length) - (back.pose.s + 0.5 * back.length)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(s: f64, y: f64, speed: f64) -> Body {
        let pose = Pose {
            s,
            y,
            heading: 0.0,
            speed,
        };
        Body::new(pose, 5.0, 2.0, None)
    }

    fn rule() -> SafetyRule {
        SafetyRule::new(&PlannerSettings::default(), 4.5)
    }

    #[test]
    fn needed_gap_hand_computed() {
        // 2 + 30·0.2 + (900 − 400)/12 = 49.6667
        assert!((rule().needed_gap(30.0, 20.0) - 49.666_667).abs() < 1e-5);
        assert!((rule().needed_gap(20.0, 30.0) - 6.0).abs() < 1e-12);
    }

    #[test]
    fn front_gap_is_kept_rear_only_after_a_lane_change() {
        let r = rule();
        let me = body(100.0, 4.5, 30.0);
        let from_lane = |y: f64| body(80.0, y, 30.0);
        let far = body(300.0, 4.5, 20.0);
        // Leader 50 m ahead (gap 45) at 20 m/s: needs 49.67 → not clear; 55 m ahead → clear.
        assert!(!r.clear(&me, &from_lane(4.5), &body(150.0, 4.5, 20.0), &far, 1.0));
        assert!(r.clear(&me, &from_lane(4.5), &body(155.0, 4.5, 20.0), &far, 1.0));
        // A faster car close behind in the same lane: its business, even a predicted rear-end
        // overlap. After a cut-in, the CAV's, checked as braking (6 m/s² here) from the plan's
        // start: from 55 m at 35 m/s it is at 87 m at 29 m/s after 1 s, 8 m behind (needs 7.8);
        // from 62 m, 1 m behind.
        let (behind, was_behind) = (body(90.0, 4.5, 35.0), body(55.0, 4.5, 35.0));
        assert!(r.clear(&me, &from_lane(4.5), &behind, &was_behind, 1.0));
        assert!(r.clear(&me, &from_lane(0.0), &behind, &was_behind, 1.0));
        let (rear_end, was_close) = (body(97.0, 4.5, 35.0), body(62.0, 4.5, 35.0));
        assert!(r.clear(&me, &from_lane(4.5), &rear_end, &was_close, 1.0));
        assert!(!r.clear(&me, &from_lane(0.0), &rear_end, &was_close, 1.0));
        // But a car that was in front and is now "behind" was driven through: not clear.
        assert!(!r.clear(
            &me,
            &from_lane(4.5),
            &body(99.0, 4.5, 0.0),
            &body(99.0, 4.5, 0.0),
            1.0
        ));
        // Other lane: only the bodies matter.
        assert!(r.clear(&me, &from_lane(4.5), &body(104.0, 9.0, 10.0), &far, 1.0));
        assert!(!r.clear(&me, &from_lane(4.5), &body(104.0, 6.0, 10.0), &far, 1.0));
    }

    #[test]
    fn an_hdv_in_front_may_brake_harder_than_a_cav() {
        let r = rule();
        // Both at 30 m/s, the front one braking at 9 m/s²: 2 + 6 + 900/12 − 900/18 = 33 m;
        // braking like a CAV (6 m/s²), only 8 m.
        assert!((r.needed_gap_to(30.0, 30.0, 9.0) - 33.0).abs() < 1e-9);
        assert!((r.needed_gap_to(30.0, 30.0, 6.0) - 8.0).abs() < 1e-9);
        let me = body(100.0, 4.5, 30.0);
        let cav_like = body(125.0, 4.5, 30.0); // gap 20 m
        let hdv = Body {
            brake: Some(9.0),
            ..cav_like
        };
        // (A second ago both were 50 m further back, the CAV 70 m behind: no gap to repair.)
        let (me_then, cav_then) = (body(50.0, 4.5, 30.0), body(95.0, 4.5, 30.0));
        let hdv_then = Body {
            brake: Some(9.0),
            ..cav_then
        };
        assert!(r.clear(&me, &me_then, &cav_like, &cav_then, 1.0));
        assert!(!r.clear(&me, &me_then, &hdv, &hdv_then, 1.0));
    }

    #[test]
    fn a_gap_too_small_already_asks_for_hard_braking_only() {
        let r = rule();
        // Now: 20 m gap at 30 m/s behind a 25 m/s car (needs 2 + 6 + 275/12 = 30.9).
        let (me_now, lead_now) = (body(100.0, 4.5, 30.0), body(125.0, 4.5, 25.0));
        let lead = body(155.0, 4.5, 25.0);
        // One second later, braking at 6 m/s² from now puts the CAV at 127 m (gap 23 m): fine.
        assert!(r.clear(&body(127.0, 4.5, 24.0), &me_now, &lead, &lead_now, 1.0));
        // Holding 30 m/s instead (at 130 m, gap 20 m) is not.
        assert!(!r.clear(&body(130.0, 4.5, 30.0), &me_now, &lead, &lead_now, 1.0));
    }
}
