//! When SUMO lets an HDV change lanes in front of a CAV: its lane-change model's back-gap check
//! (LC2013, as `MSLaneChanger::checkChange` applies it), bounded from below, as the shield's worst
//! case of a main-road HDV cutting in.
//!
//! SUMO lets a vehicle change into a lane when the bumper gap to its new follower, less the
//! follower's minGap, is at least the follower's secure gap times the changer's safety factor
//! (`1 / lcAssertive`). The follower's secure gap is its brake gap (at its vType `decel`, plus
//! `tau` of reaction, or without it when it is braking already) less the changer's brake gap
//! (at the larger of both decels). The shield takes the smallest this can be (no reaction
//! time, both brake gaps at the CAV's own `decel`), so that every cut-in SUMO may allow is
//! one the shield expects; the acceptance is only ever underestimated.
//!
//! Why it matters. With SUMO's default `lcAssertive = 1` a changer needs more room than a CAV
//! braking at `planner.emergency_decel` needs to stop (`decel` 5 against 6 m/s², plus the
//! minGap), so no cut-in SUMO allows can hit it, and this bound never binds. The `paper` profile
//! sets `lcAssertive = 3`: a third of the secure gap, about 35 m at 26.3 m/s for a CAV that
//! needs 55 m to stop for a standing car. A standing main-road HDV (`paper`, α 0.4, λ 3000,
//! seed 7192) pulled out of a lane-1 queue into lane 2 at 75.8 s, 50 m in front of a CAV at
//! 26.3 m/s, as soon as the HDV passing it had cleared its front; the CAV, braking at 6 m/s²,
//! hit it at 79.0 s.

/// SUMO's acceptance of a cut-in, bounded: everything the check needs of the configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutIn {
    /// The follower's minGap, which SUMO takes off the bumper gap first (m): the CAV type's.
    pub min_gap: f64,
    /// The changer's safety factor at its smallest: `1 / lcAssertive` of the most assertive
    /// HDV driver type.
    pub factor: f64,
    /// The deceleration of both brake gaps of the secure gap (m/s², positive): the CAV type's
    /// `decel`.
    pub secure_decel: f64,
    /// How hard an HDV that cut in may brake (m/s², positive): the larger of both types'
    /// `decel`, what SUMO's secure gap credits it with.
    pub brake_decel: f64,
}

/// SUMO's brake gap of a vehicle at `speed` braking at `decel`, stepped by `dt` as SUMO's
/// (semi-implicit) Euler steps it, with no reaction time: `MSCFModel::brakeGapEuler`.
pub fn brake_gap(speed: f64, decel: f64, dt: f64) -> f64 {
    let reduction = decel * dt;
    let steps = (speed / reduction).floor();
    dt * (steps * speed - reduction * steps * (steps + 1.0) / 2.0)
}

impl CutIn {
    /// Whether SUMO may let a vehicle at `changer_speed` change in `gap` metres (bumper to
    /// bumper) in front of a follower at `follower_speed`, Euler-stepped by `dt`.
    pub fn allows(&self, gap: f64, follower_speed: f64, changer_speed: f64, dt: f64) -> bool {
        let secure = brake_gap(follower_speed, self.secure_decel, dt)
            - brake_gap(changer_speed, self.secure_decel, dt);
        gap - self.min_gap >= self.factor * secure.max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> CutIn {
        CutIn {
            min_gap: 5.0,
            factor: 1.0 / 3.0,
            secure_decel: 5.0,
            brake_decel: 5.0,
        }
    }

    #[test]
    fn brake_gap_hand_computed() {
        // 3 m/s at 5 m/s² in 0.2 s steps: 2, 1, 0 m/s at the step ends, 0.4 + 0.2 m.
        assert!((brake_gap(3.0, 5.0, 0.2) - 0.6).abs() < 1e-12);
        assert_eq!(brake_gap(0.0, 5.0, 0.2), 0.0);
        // Below the continuous v²/2b, by about v·dt/2.
        let v: f64 = 26.73;
        let g = brake_gap(v, 5.0, 0.2);
        assert!(g < v * v / 10.0 && g > v * v / 10.0 - v * 0.2, "{g}");
    }

    #[test]
    fn the_gap_sumo_accepted_in_front_of_the_cav_is_allowed() {
        let c = paper();
        // The seed-7192 cut-in: 49.9 m in front of a CAV at 26.3 m/s, from a standstill.
        assert!(c.allows(49.9, 26.33, 0.0, 0.2));
        // Never inside the follower's minGap; at equal speeds at any gap beyond it.
        assert!(!c.allows(4.9, 10.0, 10.0, 0.2));
        assert!(c.allows(5.0, 30.0, 30.0, 0.2));
        // At lcAssertive 1 the same standing car needs the whole brake gap and more.
        let safe = CutIn { factor: 1.0, ..c };
        assert!(!safe.allows(49.9, 26.33, 0.0, 0.2));
        assert!(safe.allows(5.0 + brake_gap(26.33, 5.0, 0.2), 26.33, 0.0, 0.2));
    }
}
