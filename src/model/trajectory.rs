//! Space-time trajectories (one pose per planning step) and the search for the first collision.

use crate::model::geometry::{intersection_test_obb_obb, OrientedBox};
use crate::model::math::Point;

/// Where a vehicle is at one step: centre in the road frame and heading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Longitudinal position of the centre (m).
    pub s: f64,
    /// Lateral position of the centre (m): lane k's centre is at k·lane_width.
    pub y: f64,
    /// Heading relative to the road (rad).
    pub heading: f64,
    /// Speed (m/s).
    pub speed: f64,
}

/// Poses at steps 0, 1, …, of one vehicle (step 0 = now), with its body size.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// The pose at each planning step, step 0 first.
    pub poses: Vec<Pose>,
    /// Body length (m).
    pub length: f64,
    /// Body width (m).
    pub width: f64,
    /// Hardest braking (m/s², positive) of the vehicle driving it, where it differs from a CAV's
    /// (an HDV may brake at SUMO's emergencyDecel): the gap a CAV keeps behind it must let the
    /// CAV stop if it does. `None`: as hard as the planner's CAVs.
    pub brake: Option<f64>,
    /// A CAV's plan of this round, which it keeps to: a vehicle that cuts in front of it is
    /// checked against the plan as it is, not against the braking the safety rule assumes of a
    /// predicted follower (see [`crate::planner::safety`]). PBS plans a CAV around the plans of
    /// those with priority over it, which never yield; assuming they brake gave plans PBS then
    /// had to refuse.
    pub committed: bool,
}

impl Trajectory {
    /// A 5 m × 2 m vehicle driving straight at constant `speed` along lateral position `y`, from
    /// `s0`, for `steps` steps of `dt`: for scenes built by hand.
    pub fn straight(s0: f64, y: f64, speed: f64, steps: usize, dt: f64) -> Trajectory {
        let poses = (0..=steps)
            .map(|k| Pose {
                s: s0 + speed * dt * k as f64,
                y,
                heading: 0.0,
                speed,
            })
            .collect();
        Trajectory {
            poses,
            length: 5.0,
            width: 2.0,
            brake: None,
            committed: false,
        }
    }

    /// The pose at `step`; past the end the vehicle is assumed to hold its last pose's speed
    /// and heading (so a shorter trajectory still blocks space).
    pub fn at(&self, step: usize, dt: f64) -> Pose {
        match self.poses.get(step) {
            Some(p) => *p,
            None => {
                let last = *self
                    .poses
                    .last()
                    .expect("a trajectory has at least one pose");
                let extra = (step + 1 - self.poses.len()) as f64 * dt;
                Pose {
                    s: last.s + last.speed * last.heading.cos() * extra,
                    ..last
                }
            }
        }
    }

    /// The body at `step`.
    pub fn body(&self, step: usize, dt: f64) -> OrientedBox {
        let p = self.at(step, dt);
        OrientedBox::vehicle(Point::new(p.s, p.y), p.heading, self.length, self.width)
    }

    /// Number of steps covered (poses − 1).
    pub fn horizon(&self) -> usize {
        self.poses.len().saturating_sub(1)
    }
}

/// Whether two poses' bodies overlap.
pub fn bodies_overlap(a: &Trajectory, b: &Trajectory, step: usize, dt: f64) -> bool {
    intersection_test_obb_obb(&a.body(step, dt), &b.body(step, dt))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(s0: f64, y: f64, speed: f64, steps: usize) -> Trajectory {
        Trajectory::straight(s0, y, speed, steps, 0.2)
    }

    #[test]
    fn catching_up_overlaps_from_the_step_the_bumpers_meet() {
        // Closing 10 m/s from a 15 m bumper gap: the boxes touch after 1.5 s, step 8 of 0.2 s.
        let (a, b) = (straight(0.0, 0.0, 30.0, 20), straight(20.0, 0.0, 20.0, 20));
        assert!(!bodies_overlap(&a, &b, 7, 0.2));
        assert!(bodies_overlap(&a, &b, 8, 0.2));
    }

    #[test]
    fn near_miss_and_adjacent_lanes_do_not_overlap() {
        // Following at a constant 6 m gap, and side by side in adjacent lanes.
        let lead = straight(11.0, 0.0, 30.0, 15);
        let (follow, beside) = (straight(0.0, 0.0, 30.0, 15), straight(0.0, 4.5, 30.0, 15));
        assert!((0..=15).all(|k| !bodies_overlap(&follow, &lead, k, 0.2)));
        assert!((0..=15).all(|k| !bodies_overlap(&follow, &beside, k, 0.2)));
    }

    #[test]
    fn short_trajectory_extends_at_its_last_speed() {
        let t = straight(0.0, 0.0, 10.0, 2);
        assert!((t.at(5, 0.2).s - 10.0).abs() < 1e-12);
    }
}
