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
    pub speed: f64,
}

/// Poses at steps 0, 1, …, of one vehicle (step 0 = now), with its body size.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    pub poses: Vec<Pose>,
    pub length: f64,
    pub width: f64,
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

/// The earliest collision found: vehicles `i < j` overlap at `step`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FirstCollision {
    pub step: usize,
    pub i: usize,
    pub j: usize,
}

/// The earliest step (from 1) at which two trajectories overlap, among pairs `relevant(i, j)`
/// accepts; ties go to the smallest `(i, j)`. Steps 1..=`horizon` are checked (step 0 is the
/// present, which no plan can change).
pub fn first_collision(
    trajectories: &[Trajectory],
    horizon: usize,
    dt: f64,
    relevant: impl Fn(usize, usize) -> bool,
) -> Option<FirstCollision> {
    let n = trajectories.len();
    for step in 1..=horizon {
        let bodies: Vec<OrientedBox> = trajectories.iter().map(|t| t.body(step, dt)).collect();
        // Sweep along s: only pairs whose centres are within the sum of radii can overlap.
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| {
            bodies[a]
                .centre
                .x
                .total_cmp(&bodies[b].centre.x)
                .then(a.cmp(&b))
        });
        let mut best: Option<(usize, usize)> = None;
        for (k, &a) in order.iter().enumerate() {
            for &b in &order[k + 1..] {
                let reach = bodies[a].bounding_radius() + bodies[b].bounding_radius();
                if bodies[b].centre.x - bodies[a].centre.x > reach {
                    break;
                }
                let (i, j) = (a.min(b), a.max(b));
                if best.is_some_and(|p| p <= (i, j)) || !relevant(i, j) {
                    continue;
                }
                if intersection_test_obb_obb(&bodies[a], &bodies[b]) {
                    best = Some((i, j));
                }
            }
        }
        if let Some((i, j)) = best {
            return Some(FirstCollision { step, i, j });
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(s0: f64, y: f64, speed: f64, steps: usize) -> Trajectory {
        Trajectory::straight(s0, y, speed, steps, 0.2)
    }

    #[test]
    fn finds_the_earliest_pair() {
        // 0 catches 1 (closing 10 m/s from 20 m: bumpers meet after 1.5 s, step 8);
        // 2 and 3 are in another lane and meet later (closing 5 m/s from 20 m: step 15).
        let ts = vec![
            straight(0.0, 0.0, 30.0, 20),
            straight(20.0, 0.0, 20.0, 20),
            straight(100.0, 4.5, 25.0, 20),
            straight(120.0, 4.5, 20.0, 20),
        ];
        let c = first_collision(&ts, 20, 0.2, |_, _| true).unwrap();
        assert_eq!(
            c,
            FirstCollision {
                step: 8,
                i: 0,
                j: 1
            }
        );
        // Ignoring pairs with vehicle 0 leaves the later one.
        let c = first_collision(&ts, 20, 0.2, |i, _| i != 0).unwrap();
        assert_eq!(
            c,
            FirstCollision {
                step: 15,
                i: 2,
                j: 3
            }
        );
    }

    #[test]
    fn near_miss_and_adjacent_lanes_are_not_collisions() {
        // Following at constant 6 m gap, and side by side in adjacent lanes.
        let ts = vec![
            straight(0.0, 0.0, 30.0, 15),
            straight(11.0, 0.0, 30.0, 15),
            straight(0.0, 4.5, 30.0, 15),
        ];
        assert!(first_collision(&ts, 15, 0.2, |_, _| true).is_none());
    }

    #[test]
    fn ties_in_time_go_to_the_lowest_pair() {
        let ts = vec![
            straight(50.0, 0.0, 20.0, 10),
            straight(0.0, 4.5, 30.0, 10),
            straight(20.0, 4.5, 20.0, 10),
            straight(30.0, 0.0, 30.0, 10),
        ];
        // Pairs (1,2) and (0,3) both close 10 m/s from 15 m bumper gap: same step; (0,3) first.
        let c = first_collision(&ts, 10, 0.2, |_, _| true).unwrap();
        assert_eq!((c.step, c.i, c.j), (8, 0, 3));
    }

    #[test]
    fn short_trajectory_extends_at_its_last_speed() {
        let t = straight(0.0, 0.0, 10.0, 2);
        assert!((t.at(5, 0.2).s - 10.0).abs() < 1e-12);
    }
}
