//! The Intelligent Driver Model (Treiber et al., 2000).

use crate::config::Idm;

/// The vehicle ahead as IDM sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leader {
    /// Bumper-to-bumper gap (m).
    pub gap: f64,
    /// Leader speed (m/s).
    pub speed: f64,
}

/// IDM acceleration of a vehicle at speed `v` wanting `v0`, behind `leader` if any.
///
/// a = A·[1 − (v/v0)^δ − (s*/s)²], s* = s0 + max(0, v·T + v·Δv / (2√(A·b))), clamped to
/// [−max_decel, A]; a non-positive gap gives −max_decel.
pub fn acceleration(p: &Idm, v: f64, v0: f64, leader: Option<Leader>) -> f64 {
    let free = 1.0 - (v / v0.max(1e-6)).powf(p.delta);
    let interaction = match leader {
        None => 0.0,
        Some(l) if l.gap <= 0.0 => return -p.max_decel,
        Some(l) => {
            let s_star = p.min_gap
                + (v * p.time_headway + v * (v - l.speed) / (2.0 * (p.accel * p.decel).sqrt()))
                    .max(0.0);
            (s_star / l.gap).powi(2)
        }
    };
    (p.accel * (free - interaction)).clamp(-p.max_decel, p.accel)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> Idm {
        Idm::default() // a = 3, b = 5, s0 = 5, T = 1.5, δ = 4, max 9
    }

    #[test]
    fn free_road_hand_computed() {
        // a = 3·(1 − (20/35)^4) = 3·(1 − 0.106622) = 2.680133
        let a = acceleration(&p(), 20.0, 35.0, None);
        assert!((a - 2.680_133).abs() < 1e-5, "{a}");
        assert_eq!(acceleration(&p(), 35.0, 35.0, None), 0.0);
    }

    #[test]
    fn following_hand_computed() {
        // v = 30, v0 = 35, leader at gap 50 m with speed 25:
        // s* = 5 + 30·1.5 + 30·5 / (2·√15) = 5 + 45 + 19.364917 = 69.364917
        // a = 3·(1 − (30/35)^4 − (69.364917/50)^2) = 3·(1 − 0.539775 − 1.924597) = −4.393115
        let a = acceleration(
            &p(),
            30.0,
            35.0,
            Some(Leader {
                gap: 50.0,
                speed: 25.0,
            }),
        );
        assert!((a + 4.393_115).abs() < 1e-5, "{a}");
    }

    #[test]
    fn overlap_or_tiny_gap_brakes_at_the_limit() {
        assert_eq!(
            acceleration(
                &p(),
                10.0,
                35.0,
                Some(Leader {
                    gap: 0.0,
                    speed: 0.0
                })
            ),
            -9.0
        );
        assert_eq!(
            acceleration(
                &p(),
                30.0,
                35.0,
                Some(Leader {
                    gap: 1.0,
                    speed: 0.0
                })
            ),
            -9.0
        );
    }
}
