//! The motion-primitive library: the maneuvers a CAV may choose, each rolled out with the
//! bicycle model over whole planning steps.
//!
//! Longitudinal primitives hold an acceleration for one step while a steering law keeps the
//! vehicle on its lane's centre line. A lane change spans `lane_change_steps` steps (1 s, SUMO's
//! `--lanechange.duration`) at constant forward speed; its steering law tracks the path SUMO
//! executes for the same command, a constant lateral speed of one lane width per second, and its
//! throttle keeps the forward (along-road) speed constant as SUMO does, so planner and simulator
//! agree (tested against SUMO in `tests/primitives_sumo.rs`). Below
//! `min_lane_change_speed` the bicycle cannot move one lane sideways within that second; SUMO
//! still executes the change at any speed, standing included (one lane width per second, the car
//! keeping its forward speed), so there a lane change is a *slide*: the same lateral path with
//! the body kept along the road. Without it a ramp CAV that had slowed down could never merge and
//! stood at the end of the acceleration lane while gaps passed. By default only merges out of
//! the acceleration lane may slide (`planner.low_speed_lane_changes`): the guide's planners
//! chapter (docs/src/planners.md) tells the deadlock this prevents.

use crate::config::{Scenario, PAPER_ACCEL};
use crate::model::kinematics::{Bicycle, BicycleState, Input};
use crate::model::math::{wrap_angle, Point};
use crate::model::scene::Limits;

/// A maneuver of the library.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Primitive {
    /// Hold the library's `accel` for one step, keeping the lane.
    Accelerate,
    /// Keep the speed and the lane for one step.
    Idle,
    /// Brake at the library's `decel` for one step, keeping the lane.
    Decelerate,
    /// Change one lane to the left, over `lane_change_steps` steps at constant forward speed.
    LaneChangeLeft,
    /// Change one lane to the right, as [`Primitive::LaneChangeLeft`].
    LaneChangeRight,
    /// Brake at the library's `emergency_decel` for one step, keeping the lane.
    EmergencyBrake,
}

impl Primitive {
    /// All six, in the order the planner tries them.
    pub const ALL: [Primitive; 6] = [
        Primitive::Accelerate,
        Primitive::Idle,
        Primitive::Decelerate,
        Primitive::LaneChangeLeft,
        Primitive::LaneChangeRight,
        Primitive::EmergencyBrake,
    ];

    /// Lanes moved: +1 left, −1 right, 0 otherwise.
    pub fn lane_offset(self) -> i32 {
        match self {
            Primitive::LaneChangeLeft => 1,
            Primitive::LaneChangeRight => -1,
            _ => 0,
        }
    }

    /// The longitudinal acceleration the primitive holds, given the library's three magnitudes
    /// (positive): lane changes keep the speed, as SUMO executes them.
    pub fn acceleration(self, accel: f64, decel: f64, emergency_decel: f64) -> f64 {
        match self {
            Primitive::Accelerate => accel,
            Primitive::Idle | Primitive::LaneChangeLeft | Primitive::LaneChangeRight => 0.0,
            Primitive::Decelerate => -decel,
            Primitive::EmergencyBrake => -emergency_decel,
        }
    }

    /// Whether it is one of the two lane changes.
    pub fn is_lane_change(self) -> bool {
        self.lane_offset() != 0
    }

    /// Its name as policy model files spell their actions (`accelerate`, `lane-change-left`, …).
    pub fn name(self) -> &'static str {
        match self {
            Primitive::Accelerate => "accelerate",
            Primitive::Idle => "idle",
            Primitive::Decelerate => "decelerate",
            Primitive::LaneChangeLeft => "lane-change-left",
            Primitive::LaneChangeRight => "lane-change-right",
            Primitive::EmergencyBrake => "emergency-brake",
        }
    }
}

/// Parameters of the library, and a table of lane-change rollouts by speed (see
/// [`Library::rollout_settled`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Library {
    /// The vehicle model the primitives are rolled out with.
    pub bicycle: Bicycle,
    /// Planning step (s).
    pub dt: f64,
    /// Acceleration of `Accelerate` (m/s²).
    pub accel: f64,
    /// Whether a vehicle with an acceleration limit of its own accelerates at it rather than at
    /// `accel` ([`Library::limited`]; `[planner] accel` unset).
    pub accel_own: bool,
    /// Deceleration of `Decelerate` (m/s², positive).
    pub decel: f64,
    /// Deceleration of `EmergencyBrake` (m/s², positive).
    pub emergency_decel: f64,
    /// Steps a lane change takes.
    pub lane_change_steps: usize,
    /// Lane width (m): how far a lane change moves sideways.
    pub lane_width: f64,
    /// Slowest speed (m/s) at which the bicycle steers a lane change (10 m/s by default).
    pub min_lane_change_speed: f64,
    /// Whether a lane change below `min_lane_change_speed` is a slide (else unavailable).
    pub slides_below_min_speed: bool,
    /// Control updates per step of the steering law.
    pub control_substeps: u32,
    /// Left lane changes from a settled state at speeds `min_lane_change_speed + k·TABLE_DV`:
    /// per step, the displacement, heading and path speed.
    /// Shared: a vehicle's own library ([`Library::limited`]) keeps the planner's table.
    table: std::sync::Arc<[Vec<BicycleState>]>,
}

/// Speed spacing of the lane-change table (m/s).
const TABLE_DV: f64 = 0.25;

impl Library {
    /// The library for a step `dt`, lanes `lane_width` wide and lane changes taking
    /// `lane_change_duration` seconds.
    pub fn new(dt: f64, lane_width: f64, lane_change_duration: f64, v_max: f64) -> Self {
        let mut lib = Library {
            bicycle: Bicycle {
                v_max,
                substeps: 1,
                ..Bicycle::default()
            },
            dt,
            accel: PAPER_ACCEL,
            accel_own: false,
            decel: 2.0,
            emergency_decel: 6.0,
            lane_change_steps: Scenario::lane_change_steps_of(lane_change_duration, dt),
            lane_width,
            min_lane_change_speed: 10.0,
            slides_below_min_speed: false,
            control_substeps: 10,
            table: std::sync::Arc::from(Vec::new()),
        };
        lib.build_table();
        lib
    }

    /// The library of a vehicle that can do no more than `limits`: its primitives'
    /// accelerations lowered to the vehicle's where they are lower, and its `Accelerate` the
    /// vehicle's own where `accel_own` says so and it has one (`None`: nothing changes; the
    /// lane-change table, at constant speed, is the same).
    pub fn limited(&self, limits: &Limits) -> Option<Library> {
        let accel = if self.accel_own && limits.accel.is_finite() {
            limits.accel
        } else {
            self.accel.min(limits.accel)
        };
        let decel = self.decel.min(limits.decel);
        let emergency_decel = self.emergency_decel.min(limits.emergency_decel);
        let same =
            (accel, decel, emergency_decel) == (self.accel, self.decel, self.emergency_decel);
        (!same).then(|| Library {
            accel,
            decel,
            emergency_decel,
            ..self.clone()
        })
    }

    /// The same library after its parameters were changed: the table is rebuilt.
    pub fn rebuilt(mut self) -> Self {
        self.build_table();
        self
    }

    /// Tabulates left lane changes from settled states (origin, lane centre at y = 0).
    fn build_table(&mut self) {
        let v_max = self.bicycle.v_max;
        let mut table = Vec::new();
        let mut v = self.min_lane_change_speed;
        while v <= v_max + 1e-9 {
            let start = BicycleState {
                pos: Point::new(0.0, 0.0),
                heading: 0.0,
                speed: v,
            };
            table.push(self.rollout(Primitive::LaneChangeLeft, &start, 0.0));
            v += TABLE_DV;
        }
        self.table = table.into();
    }

    /// Like [`Library::rollout`], for a *settled* start (on its lane's centre line, heading along
    /// the road), as every node inside a search is: longitudinal primitives in closed form, lane
    /// changes from the table (linear in speed between entries, within millimetres of the full
    /// rollout). The final state of a lane change is settled onto the new centre line, which the
    /// vehicle reaches within 0.11 m under lane keeping.
    pub fn rollout_settled(&self, p: Primitive, start: &BicycleState) -> Vec<BicycleState> {
        if !p.is_lane_change() {
            return vec![self.longitudinal(start, self.accel_of(p), self.dt)];
        }
        if self.slides(p, start) {
            let target_y = start.pos.y + p.lane_offset() as f64 * self.lane_width;
            return self.slide(start, target_y);
        }
        let v = start
            .speed
            .clamp(self.min_lane_change_speed, self.bicycle.v_max);
        let f = (v - self.min_lane_change_speed) / TABLE_DV;
        let k = (f.floor() as usize).min(self.table.len() - 1);
        let k1 = (k + 1).min(self.table.len() - 1);
        let w = (f - k as f64).clamp(0.0, 1.0);
        let dir = p.lane_offset() as f64;
        let mut out: Vec<BicycleState> = (0..self.lane_change_steps)
            .map(|i| {
                let (a, b) = (&self.table[k][i], &self.table[k1][i]);
                let lerp = |x: f64, y: f64| x + w * (y - x);
                BicycleState {
                    pos: Point::new(
                        start.pos.x + lerp(a.pos.x, b.pos.x),
                        start.pos.y + dir * lerp(a.pos.y, b.pos.y),
                    ),
                    heading: dir * lerp(a.heading, b.heading),
                    speed: lerp(a.speed, b.speed),
                }
            })
            .collect();
        let last = out
            .last_mut()
            .expect("a lane change spans at least one step");
        last.pos.y = start.pos.y + dir * self.lane_width;
        last.heading = 0.0;
        last.speed = v;
        out
    }

    /// Straight motion at acceleration `a` for `dt`, speed held within [0, v_max].
    fn longitudinal(&self, s: &BicycleState, a: f64, dt: f64) -> BicycleState {
        let v_max = self.bicycle.v_max;
        let v_end = (s.speed + a * dt).clamp(0.0, v_max);
        let t_free = if a != 0.0 {
            ((v_end - s.speed) / a).clamp(0.0, dt)
        } else {
            dt
        };
        let dist = s.speed * t_free + 0.5 * a * t_free * t_free + v_end * (dt - t_free);
        BicycleState {
            pos: Point::new(s.pos.x + dist, s.pos.y),
            heading: 0.0,
            speed: v_end,
        }
    }

    /// Steps the primitive spans.
    pub fn steps(&self, p: Primitive) -> usize {
        if p.is_lane_change() {
            self.lane_change_steps
        } else {
            1
        }
    }

    /// Longitudinal acceleration of the primitive.
    pub fn accel_of(&self, p: Primitive) -> f64 {
        p.acceleration(self.accel, self.decel, self.emergency_decel)
    }

    /// Whether the primitive can start from `state`: a lane change needs the bicycle's minimum
    /// speed unless slow changes slide (see the module's doc).
    pub fn available(&self, p: Primitive, state: &BicycleState) -> bool {
        self.slides_below_min_speed
            || !p.is_lane_change()
            || state.speed >= self.min_lane_change_speed
    }

    /// Whether a lane change from `state` is a slide: too slow for the bicycle to steer it.
    fn slides(&self, p: Primitive, state: &BicycleState) -> bool {
        self.slides_below_min_speed
            && p.is_lane_change()
            && state.speed < self.min_lane_change_speed
    }

    /// A lane change as SUMO executes it at low speed: the forward speed held, the lateral
    /// position linear to `target_y` over the change's steps, the body along the road.
    fn slide(&self, start: &BicycleState, target_y: f64) -> Vec<BicycleState> {
        let steps = self.lane_change_steps;
        let vx = start.speed * start.heading.cos();
        (1..=steps)
            .map(|k| {
                let f = k as f64 / steps as f64;
                BicycleState {
                    pos: Point::new(
                        start.pos.x + vx * self.dt * k as f64,
                        start.pos.y + f * (target_y - start.pos.y),
                    ),
                    heading: 0.0,
                    speed: vx,
                }
            })
            .collect()
    }

    /// Rolls `p` out from `start`, whose lane centre is at lateral position `lane_y`; returns the
    /// state at the end of each step it spans.
    pub fn rollout(&self, p: Primitive, start: &BicycleState, lane_y: f64) -> Vec<BicycleState> {
        let steps = self.steps(p);
        let target_y = lane_y + p.lane_offset() as f64 * self.lane_width;
        if self.slides(p, start) {
            return self.slide(start, target_y);
        }
        let total = steps as f64 * self.dt;
        let y0 = start.pos.y;
        let reference = |t: f64| -> (f64, f64) {
            if p.is_lane_change() {
                let f = (t / total).min(1.0);
                let rate = if t < total {
                    (target_y - y0) / total
                } else {
                    0.0
                };
                (y0 + f * (target_y - y0), rate)
            } else {
                (lane_y, 0.0)
            }
        };
        let throttle = if p.is_lane_change() {
            Throttle::HoldForwardSpeed(start.speed * start.heading.cos())
        } else {
            Throttle::Accel(self.accel_of(p))
        };
        self.track(start, throttle, steps, reference)
    }

    /// Integrates the bicycle over `steps` steps under `throttle` while steering to follow the
    /// lateral reference `reference(t) = (y_ref, ẏ_ref)`.
    pub fn track(
        &self,
        start: &BicycleState,
        throttle: Throttle,
        steps: usize,
        reference: impl Fn(f64) -> (f64, f64),
    ) -> Vec<BicycleState> {
        let h = self.dt / self.control_substeps as f64;
        let mut s = *start;
        let mut out = Vec::with_capacity(steps);
        let mut t = 0.0;
        for _ in 0..steps {
            for _ in 0..self.control_substeps {
                let steer = self.steering(&s, reference(t), reference(t + h));
                let accel = match throttle {
                    Throttle::Accel(a) => a,
                    Throttle::HoldForwardSpeed(v) => {
                        let beta = (steer.tan() / 2.0).atan();
                        K_V * (v / (s.heading + beta).cos().max(0.5) - s.speed)
                    }
                };
                s = self.bicycle.step(&s, Input { accel, steer }, h);
                t += h;
            }
            out.push(s);
        }
        out
    }

    /// The lateral steering law: a desired lateral velocity from the reference's rate and its
    /// error, turned into a desired travel direction, then a yaw rate, then a steering angle.
    fn steering(&self, s: &BicycleState, now: (f64, f64), next: (f64, f64)) -> f64 {
        // Gains chosen by a sweep for the smallest deviation from SUMO's path during and after
        // a lane change at 12–30 m/s (≤ 0.13 m; the vehicle ends the change slightly angled and
        // settles within 0.11 m of the new centre line).
        const K_Y: f64 = 10.0; // 1/s: lateral error to lateral speed
        const K_PSI: f64 = 15.0; // 1/s: heading error to yaw rate
        if s.speed < 0.5 {
            return 0.0;
        }
        let vy = next.1 + K_Y * (now.0 - s.pos.y);
        let heading_wanted = (vy / s.speed).clamp(-0.6, 0.6).asin();
        let yaw_rate = K_PSI * wrap_angle(heading_wanted - s.heading);
        (yaw_rate * self.bicycle.length / s.speed).atan()
    }
}

/// Gain of the forward-speed hold (1/s).
const K_V: f64 = 20.0;

/// How the rollout sets the acceleration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Throttle {
    /// A constant acceleration (m/s²).
    Accel(f64),
    /// Whatever keeps the along-road speed at this value (m/s).
    HoldForwardSpeed(f64),
}

/// A state in the road frame at the centre of lane `lane`.
pub fn on_lane(s: f64, lane: i32, lane_width: f64, speed: f64) -> BicycleState {
    BicycleState {
        pos: Point::new(s, lane as f64 * lane_width),
        heading: 0.0,
        speed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lib() -> Library {
        Library::new(0.2, 4.5, 1.0, 35.0)
    }

    #[test]
    fn longitudinal_primitives_hand_computed() {
        let l = lib();
        let s0 = on_lane(100.0, 1, 4.5, 30.0);
        for (p, a) in [
            (Primitive::Accelerate, 2.0),
            (Primitive::Idle, 0.0),
            (Primitive::Decelerate, -2.0),
            (Primitive::EmergencyBrake, -6.0),
        ] {
            let r = l.rollout(p, &s0, 4.5);
            assert_eq!(r.len(), 1, "{p:?}");
            let e = r[0];
            // x = x0 + v·dt + a·dt²/2, v = v0 + a·dt, lane kept exactly.
            assert!(
                (e.pos.x - (100.0 + 6.0 + a * 0.02)).abs() < 1e-9,
                "{p:?} {e:?}"
            );
            assert!((e.speed - (30.0 + 0.2 * a)).abs() < 1e-9);
            assert!(e.pos.y == 4.5 && e.heading == 0.0);
        }
    }

    #[test]
    fn speed_limits_hold() {
        let l = lib();
        let r = l.rollout(Primitive::Accelerate, &on_lane(0.0, 1, 4.5, 34.9), 4.5);
        assert_eq!(r[0].speed, 35.0);
        let r = l.rollout(Primitive::EmergencyBrake, &on_lane(0.0, 1, 4.5, 0.5), 4.5);
        assert_eq!(r[0].speed, 0.0);
    }

    #[test]
    fn lane_change_moves_one_lane_in_one_second_like_sumo() {
        let l = lib();
        for (p, dir) in [
            (Primitive::LaneChangeLeft, 1.0),
            (Primitive::LaneChangeRight, -1.0),
        ] {
            let s0 = on_lane(50.0, 1, 4.5, 25.0);
            let r = l.rollout(p, &s0, 4.5);
            assert_eq!(r.len(), 5);
            for (k, st) in r.iter().enumerate() {
                // SUMO: constant lateral speed 4.5 m/s, longitudinal progress v·t.
                let t = 0.2 * (k + 1) as f64;
                let y_sumo = 4.5 + dir * 4.5 * t;
                assert!(
                    (st.pos.y - y_sumo).abs() < 0.15,
                    "{p:?} step {k}: {} vs {y_sumo}",
                    st.pos.y
                );
                assert!(
                    (st.pos.x - (50.0 + 25.0 * t)).abs() < 0.3,
                    "{p:?} step {k}: x {}",
                    st.pos.x
                );
                assert!((st.speed * st.heading.cos() - 25.0).abs() < 0.1, "{st:?}");
            }
            // The bicycle cannot straighten instantly as SUMO does: it ends slightly angled
            // and settles on the new centre line under lane keeping.
            let mut s = r[4];
            assert!((s.pos.y - (4.5 + dir * 4.5)).abs() < 0.15, "{s:?}");
            for _ in 0..5 {
                s = l.rollout(Primitive::Idle, &s, 4.5 + dir * 4.5)[0];
                assert!((s.pos.y - (4.5 + dir * 4.5)).abs() < 0.15, "{s:?}");
            }
            assert!(s.heading.abs() < 0.01, "{s:?}");
        }
    }

    #[test]
    fn settled_rollouts_match_the_full_ones() {
        let l = lib();
        for v in [10.0, 13.37, 22.1, 29.9, 35.0] {
            let s0 = on_lane(80.0, 1, 4.5, v);
            for p in Primitive::ALL {
                let full = l.rollout(p, &s0, 4.5);
                let fast = l.rollout_settled(p, &s0);
                assert_eq!(full.len(), fast.len());
                let n = full.len();
                for (k, (a, b)) in full.iter().zip(&fast).enumerate() {
                    let tol = if k + 1 == n && p.is_lane_change() {
                        0.15
                    } else {
                        0.005
                    };
                    assert!(
                        (a.pos - b.pos).norm() < tol,
                        "{p:?} v={v} step {k}: {a:?} vs {b:?}"
                    );
                }
            }
        }
        // Braking to a stop within the step, in closed form: 0.5 m/s at 6 m/s² stops after
        // 1/12 s having covered 0.5²/12 = 0.020833 m.
        let s = l.rollout_settled(Primitive::EmergencyBrake, &on_lane(0.0, 1, 4.5, 0.5))[0];
        assert!((s.pos.x - 0.5 * 0.5 / 12.0).abs() < 1e-12 && s.speed == 0.0);
    }

    #[test]
    fn a_slow_lane_change_slides_as_sumo_moves_it() {
        // Measured in SUMO 1.15 (lane-change mode 0, `changeLane` with a 1 s duration): at 3 m/s
        // and standing alike the car moves 0.9 m sideways per 0.2 s step and keeps its forward
        // speed; below the bicycle's minimum speed the planner does the same.
        let mut l = lib();
        assert!(!l.available(Primitive::LaneChangeLeft, &on_lane(0.0, 1, 4.5, 5.0)));
        l.slides_below_min_speed = true;
        for v in [0.0, 3.0, 9.9] {
            let start = on_lane(50.0, 0, 4.5, v);
            assert!(l.available(Primitive::LaneChangeLeft, &start));
            for seg in [
                l.rollout(Primitive::LaneChangeLeft, &start, 0.0),
                l.rollout_settled(Primitive::LaneChangeLeft, &start),
            ] {
                assert_eq!(seg.len(), 5);
                for (k, st) in seg.iter().enumerate() {
                    assert!(
                        (st.pos.y - 0.9 * (k + 1) as f64).abs() < 1e-9,
                        "{v}: {seg:?}"
                    );
                    assert!((st.pos.x - (50.0 + v * 0.2 * (k + 1) as f64)).abs() < 1e-9);
                    assert_eq!((st.heading, st.speed), (0.0, v));
                }
            }
        }
        // From the minimum speed on, the bicycle steers the change (heading off the road).
        let steered = l.rollout(Primitive::LaneChangeLeft, &on_lane(50.0, 0, 4.5, 15.0), 0.0);
        assert!(steered.iter().any(|st| st.heading.abs() > 0.01));
    }

    #[test]
    fn lane_keeping_pulls_back_to_the_centre() {
        let l = lib();
        let mut s = on_lane(0.0, 1, 4.5, 25.0);
        s.pos.y += 0.8;
        for _ in 0..10 {
            s = l.rollout(Primitive::Idle, &s, 4.5)[0];
        }
        assert!(
            (s.pos.y - 4.5).abs() < 0.05 && s.heading.abs() < 0.02,
            "{s:?}"
        );
    }
}
