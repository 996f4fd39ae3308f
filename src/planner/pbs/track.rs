//! A trajectory as BK-PBS checks it: its bodies at every step of the horizon, the stretch of
//! road it covers and its progress, computed once when the agent is planned or predicted.
//!
//! A round compares every pair of nearby agents at every step, node after node, and most
//! agents keep their root trajectories through the whole round: reading poses (and their
//! cosines) off the trajectories at each comparison cost more than the comparisons.

use std::sync::Arc;

use rayon::prelude::*;

use crate::model::trajectory::Trajectory;
use crate::planner::safety::Body;

/// One agent's trajectory with what the search reads of it, steps 0..=horizon.
#[derive(Debug)]
pub(super) struct Track {
    pub trajectory: Arc<Trajectory>,
    /// The body at each step 0..=horizon.
    pub bodies: Vec<Body>,
    /// Lowest and highest `s` of the centre over the steps: two tracks farther apart than
    /// `safety::REACH` never conflict.
    pub extent: (f64, f64),
    /// Σ forward speeds over steps 1..=horizon (a node's cost is minus the sum over agents).
    pub progress: f64,
}

impl Track {
    pub fn new(trajectory: Arc<Trajectory>, horizon: usize, dt: f64) -> Track {
        let bodies: Vec<Body> = (0..=horizon)
            .map(|k| Body::of(&trajectory, k, dt))
            .collect();
        let extent = bodies
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), b| {
                (lo.min(b.pose.s), hi.max(b.pose.s))
            });
        let progress = bodies[1..].iter().map(Body::forward_speed).sum::<f64>();
        Track {
            trajectory,
            bodies,
            extent,
            progress,
        }
    }

    /// Tracks of `trajectories`, in order (made in parallel).
    pub fn all(trajectories: &[Arc<Trajectory>], horizon: usize, dt: f64) -> Vec<Arc<Track>> {
        trajectories
            .par_iter()
            .map(|t| Arc::new(Track::new(t.clone(), horizon, dt)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_track_reads_its_trajectory_once_and_extends_a_short_one() {
        let t = Arc::new(Trajectory::straight(10.0, 4.5, 20.0, 3, 0.2));
        let track = Track::new(t, 5, 0.2);
        assert_eq!(track.bodies.len(), 6);
        // Steps 4 and 5 lie past the trajectory's end: held at its last speed.
        assert!((track.bodies[5].pose.s - 30.0).abs() < 1e-12);
        assert!((track.extent.0 - 10.0).abs() < 1e-12 && (track.extent.1 - 30.0).abs() < 1e-12);
        assert!((track.progress - 100.0).abs() < 1e-9);
    }
}
