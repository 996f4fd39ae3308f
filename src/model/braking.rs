//! Worst-case braking along one lane, stepped as SUMO steps it: the one model the safety shield
//! judges every step by and the planners judge a later lane-change start by, so that a plan
//! never counts on a start the shield would refuse when it comes.

/// One vehicle's worst-case longitudinal motion: `first` as the speed at the end of the first
/// step (none: braking from the start), then braking at `decel` to a stop, or stopped dead after
/// `reach` metres (the end of the acceleration lane, where SUMO halts a vehicle on the spot).
#[derive(Debug, Clone, Copy)]
pub struct Braking {
    /// Speed now (m/s).
    pub speed: f64,
    /// Speed at the end of the first step, if it is not braked.
    pub first: Option<f64>,
    /// Deceleration from then on (m/s², positive).
    pub decel: f64,
    /// Metres it can drive before it stops dead (`f64::INFINITY`: no such wall).
    pub reach: f64,
}

impl Braking {
    /// Speed after `step` steps of `dt` seconds, `previous` the speed after the step before.
    fn speed_after(&self, step: usize, previous: f64, dt: f64) -> f64 {
        match (step, self.first) {
            (1, Some(v)) => v,
            _ => (previous - self.decel * dt).max(0.0),
        }
    }
}

/// Whether `back`, `gap` metres (bumper to bumper) behind `front`, stays at least `margin` behind
/// it at every step end until it stands, both moving as SUMO steps them (Euler: a step's end
/// speed times `dt`).
pub fn stays_clear(back: Braking, front: Braking, gap: f64, margin: f64, dt: f64) -> bool {
    let (mut vb, mut vf, mut gap, mut moved) = (back.speed, front.speed, gap, 0.0);
    for step in 1..=10_000 {
        vb = back.speed_after(step, vb, dt);
        vf = front.speed_after(step, vf, dt);
        let advance = (vf * dt).min(front.reach - moved).max(0.0);
        moved += advance;
        gap += advance - vb * dt;
        if gap < margin {
            return false;
        }
        if vb <= 0.0 {
            // The one behind stands; the one in front never moves backwards.
            return true;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn braking(speed: f64, decel: f64) -> Braking {
        Braking {
            speed,
            first: None,
            decel,
            reach: f64::INFINITY,
        }
    }

    #[test]
    fn a_faster_follower_braking_softer_needs_its_stopping_distances_difference() {
        // 27.7 m/s braking at 5 behind 20.6 m/s braking at 6: about 76.7 − 35.4 = 41 m (a step's
        // Euler error either way).
        let (back, front) = (braking(27.7, 5.0), braking(20.6, 6.0));
        assert!(!stays_clear(back, front, 38.0, 0.0, 0.2));
        assert!(stays_clear(back, front, 44.0, 0.0, 0.2));
    }

    #[test]
    fn a_wall_stops_the_front_dead() {
        let wall = Braking {
            reach: 0.0,
            ..braking(0.0, 6.0)
        };
        // 10 m/s at 6 m/s², stepped by 0.2 s: 8.8, 7.6, …, 0.4 m/s at the step ends, 7.36 m in all
        // (8.33 m continuously).
        assert!(stays_clear(braking(10.0, 6.0), wall, 7.9, 0.5, 0.2));
        assert!(!stays_clear(braking(10.0, 6.0), wall, 7.8, 0.5, 0.2));
    }
}
