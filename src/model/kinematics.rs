//! The kinematic bicycle model of the paper (eq. 2), used to roll out motion primitives.
//!
//! ẋ = v·cos(ψ + β), ẏ = v·sin(ψ + β), v̇ = a, ψ̇ = v·cos β·tan δ / ℓ, β = atan(tan δ / 2),
//! with ℓ = 5 m, integrated by fourth-order Runge–Kutta over fixed sub-steps. Inputs are clamped
//! to the model's limits and the speed stays within [0, v_max].

use crate::model::math::Point;

/// Position of the vehicle's centre (road frame), heading ψ (rad, 0 = along the road), speed v.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BicycleState {
    /// Position of the centre (road frame, m).
    pub pos: Point,
    /// Heading ψ (rad, 0 = along the road, positive to the left).
    pub heading: f64,
    /// Speed v (m/s).
    pub speed: f64,
}

/// Control inputs: acceleration a (m/s²) and front-wheel steering angle δ (rad).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Input {
    /// Acceleration a (m/s², negative to brake).
    pub accel: f64,
    /// Front-wheel steering angle δ (rad, positive to the left).
    pub steer: f64,
}

/// Model constants and limits.
#[derive(Debug, Clone, PartialEq)]
pub struct Bicycle {
    /// ℓ in the paper (m).
    pub length: f64,
    /// Largest acceleration (m/s²).
    pub max_accel: f64,
    /// Largest deceleration (m/s², positive).
    pub max_decel: f64,
    /// Largest steering angle magnitude (rad).
    pub max_steer: f64,
    /// Largest speed (m/s); the speed is kept within [0, v_max].
    pub v_max: f64,
    /// RK4 sub-steps per call of [`Bicycle::step`].
    pub substeps: u32,
}

impl Default for Bicycle {
    fn default() -> Self {
        Bicycle {
            length: 5.0,
            max_accel: 6.0,
            max_decel: 6.0,
            max_steer: 0.5,
            v_max: 35.0,
            substeps: 8,
        }
    }
}

impl Bicycle {
    /// The input actually applied: clamped to the limits.
    pub fn clamp(&self, u: Input) -> Input {
        Input {
            accel: u.accel.clamp(-self.max_decel, self.max_accel),
            steer: u.steer.clamp(-self.max_steer, self.max_steer),
        }
    }

    /// Time derivative (ẋ, ẏ, ψ̇, v̇) at state `s` under input `u` (already clamped).
    pub fn derivative(&self, s: &BicycleState, u: Input) -> [f64; 4] {
        let beta = (u.steer.tan() / 2.0).atan();
        let v = s.speed;
        // The speed saturates at its bounds instead of crossing them.
        let vdot = if (v <= 0.0 && u.accel < 0.0) || (v >= self.v_max && u.accel > 0.0) {
            0.0
        } else {
            u.accel
        };
        [
            v * (s.heading + beta).cos(),
            v * (s.heading + beta).sin(),
            v * beta.cos() * u.steer.tan() / self.length,
            vdot,
        ]
    }

    /// Advances `s` by `dt` seconds under constant input `u`.
    pub fn step(&self, s: &BicycleState, u: Input, dt: f64) -> BicycleState {
        let u = self.clamp(u);
        let h = dt / self.substeps.max(1) as f64;
        let mut s = *s;
        for _ in 0..self.substeps.max(1) {
            let add = |s: &BicycleState, k: &[f64; 4], f: f64| BicycleState {
                pos: Point::new(s.pos.x + f * k[0], s.pos.y + f * k[1]),
                heading: s.heading + f * k[2],
                speed: s.speed + f * k[3],
            };
            let k1 = self.derivative(&s, u);
            let k2 = self.derivative(&add(&s, &k1, h / 2.0), u);
            let k3 = self.derivative(&add(&s, &k2, h / 2.0), u);
            let k4 = self.derivative(&add(&s, &k3, h), u);
            let mut k = [0.0; 4];
            for i in 0..4 {
                k[i] = (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) / 6.0;
            }
            s = add(&s, &k, h);
            s.speed = s.speed.clamp(0.0, self.v_max);
        }
        s
    }
}

/// Free-flow travel time t* over `distance` from speed `v0`: accelerate at `accel` up to
/// `v_max`, then cruise, ignoring every other vehicle.
pub fn free_flow_time(distance: f64, v0: f64, accel: f64, v_max: f64) -> f64 {
    if distance <= 0.0 {
        return 0.0;
    }
    let v0 = v0.min(v_max).max(0.0);
    let d_acc = (v_max * v_max - v0 * v0) / (2.0 * accel);
    if d_acc >= distance {
        // Still accelerating at the end: v0·t + a·t²/2 = distance.
        (-v0 + (v0 * v0 + 2.0 * accel * distance).sqrt()) / accel
    } else {
        (v_max - v0) / accel + (distance - d_acc) / v_max
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_flow_time_hand_computed() {
        // From 25 m/s at 3 m/s² to 35 m/s: 10/3 s over (35² − 25²)/6 = 100 m, then 355 m at 35.
        // t* = 3.333333 + 10.142857 = 13.476190
        let t = free_flow_time(455.0, 25.0, 3.0, 35.0);
        assert!((t - 13.476_190).abs() < 1e-5, "{t}");
        // Already at v_max: plain cruise.
        assert!((free_flow_time(350.0, 35.0, 3.0, 35.0) - 10.0).abs() < 1e-12);
        // Short distance, still accelerating: 25t + 1.5t² = 50 -> t = (−25 + √925)/3 = 1.804604 s.
        let t = free_flow_time(50.0, 25.0, 3.0, 35.0);
        assert!((25.0 * t + 1.5 * t * t - 50.0).abs() < 1e-9 && (t - 1.804_604).abs() < 1e-5);
    }

    fn start(speed: f64) -> BicycleState {
        BicycleState {
            pos: Point::new(10.0, 2.0),
            heading: 0.0,
            speed,
        }
    }

    #[test]
    fn straight_run_matches_closed_form() {
        let m = Bicycle::default();
        let mut s = start(20.0);
        for _ in 0..10 {
            s = m.step(
                &s,
                Input {
                    accel: 2.0,
                    steer: 0.0,
                },
                0.2,
            );
        }
        // x = 10 + 20·2 + ½·2·2² = 54, v = 24.
        assert!((s.pos.x - 54.0).abs() < 1e-9 && (s.speed - 24.0).abs() < 1e-9);
        assert!((s.pos.y - 2.0).abs() < 1e-12 && s.heading == 0.0);
    }

    #[test]
    fn constant_steer_turn_matches_the_circle() {
        let m = Bicycle::default();
        let (v, delta, t) = (10.0, 0.1_f64, 2.0);
        let beta = (delta.tan() / 2.0).atan();
        let omega = v * beta.cos() * delta.tan() / m.length;
        let r = v / omega;
        let mut s = start(v);
        for _ in 0..10 {
            s = m.step(
                &s,
                Input {
                    accel: 0.0,
                    steer: delta,
                },
                t / 10.0,
            );
        }
        // Centre of gravity moves on a circle of radius v/ω with velocity angle ψ + β.
        let x = 10.0 + r * ((beta + omega * t).sin() - beta.sin());
        let y = 2.0 - r * ((beta + omega * t).cos() - beta.cos());
        assert!(
            (s.pos.x - x).abs() < 1e-6 && (s.pos.y - y).abs() < 1e-6,
            "{s:?} vs ({x}, {y})"
        );
        assert!((s.heading - omega * t).abs() < 1e-9);
    }

    #[test]
    fn inputs_and_speed_are_limited() {
        let m = Bicycle::default();
        let s = m.step(
            &start(1.0),
            Input {
                accel: -20.0,
                steer: 0.0,
            },
            1.0,
        );
        assert_eq!(s.speed, 0.0);
        assert!(
            s.pos.x > 10.0 && s.pos.x < 10.5,
            "stops instead of reversing: {}",
            s.pos.x
        );
        let s = m.step(
            &start(34.0),
            Input {
                accel: 20.0,
                steer: 0.0,
            },
            1.0,
        );
        assert_eq!(s.speed, 35.0);
        assert_eq!(
            m.clamp(Input {
                accel: 0.0,
                steer: 3.0
            })
            .steer,
            0.5
        );
    }
}
