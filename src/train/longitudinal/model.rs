//! Open-loop longitudinal predictions of one HDV over 3 s, given its leader's real course: the
//! IDM with given parameters, and constant speed, the planner's present assumption.

pub use crate::predict::longitudinal::IdmParams;

/// Steps of a sample's horizon and where its checkpoints lie (1 s and 3 s at 0.2 s steps).
pub const HORIZON_STEPS: usize = 15;
/// The step of the 1 s checkpoint.
pub const STEPS_1S: usize = 5;

/// One follower at one instant and what followed: its start and its actual speed and gap
/// after 1 s and 3 s; its leader's real rear position and speed over the horizon.
#[derive(Debug, Clone, PartialEq)]
pub struct FollowSample {
    /// The vehicle (for per-vehicle fits).
    pub vehicle: String,
    /// Its desired speed (known to the planner: the scene carries it).
    pub desired_speed: f64,
    /// Its front bumper's position along the road at the start (m).
    pub front: f64,
    /// Its speed at the start (m/s).
    pub speed: f64,
    /// The leader's rear and speed at steps 0..=HORIZON_STEPS; `None` on a free road.
    pub leader: Option<Vec<(f64, f64)>>,
    /// What happened: speed after 1 s and 3 s, gap after 3 s (bumper to bumper; free road:
    /// not used).
    pub speed_1s: f64,
    /// Its actual speed after 3 s (m/s).
    pub speed_3s: f64,
    /// Its actual gap to the leader after 3 s, bumper to bumper (m; unused on a free road).
    pub gap_3s: f64,
}

/// Speed after 1 s, speed after 3 s, gap after 3 s (the gap is NaN on a free road).
pub type Prediction = [f64; 3];

/// The IDM's open-loop course from the sample's start (Euler steps of `dt`, as SUMO's default
/// integration: the position advances with the new speed).
pub fn predict_idm(p: &IdmParams, s: &FollowSample, dt: f64) -> Prediction {
    let v0 = p.v0_factor * s.desired_speed;
    let (mut x, mut v) = (s.front, s.speed);
    let mut v_1s = v;
    for k in 0..HORIZON_STEPS {
        let leader = s.leader.as_ref().map(|l| (l[k].0 - x, v - l[k].1));
        v = (v + p.acceleration(v, v0, leader) * dt).max(0.0);
        x += v * dt;
        if k + 1 == STEPS_1S {
            v_1s = v;
        }
    }
    let gap = s
        .leader
        .as_ref()
        .map_or(f64::NAN, |l| l[HORIZON_STEPS].0 - x);
    [v_1s, v, gap]
}

/// Constant speed: the planner's present HDV model.
pub fn predict_constant_speed(s: &FollowSample, dt: f64) -> Prediction {
    let x = s.front + s.speed * dt * HORIZON_STEPS as f64;
    let gap = s
        .leader
        .as_ref()
        .map_or(f64::NAN, |l| l[HORIZON_STEPS].0 - x);
    [s.speed, s.speed, gap]
}

/// Root mean square errors of predictions against what happened: speed at 1 s, speed at 3 s,
/// gap at 3 s (over the samples with a leader).
pub fn rmse(samples: &[FollowSample], predict: impl Fn(&FollowSample) -> Prediction) -> [f64; 3] {
    let mut sums = [0.0; 3];
    let mut with_leader = 0usize;
    for s in samples {
        let p = predict(s);
        sums[0] += (p[0] - s.speed_1s).powi(2);
        sums[1] += (p[1] - s.speed_3s).powi(2);
        if s.leader.is_some() {
            sums[2] += (p[2] - s.gap_3s).powi(2);
            with_leader += 1;
        }
    }
    let n = samples.len().max(1) as f64;
    [
        (sums[0] / n).sqrt(),
        (sums[1] / n).sqrt(),
        (sums[2] / with_leader.max(1) as f64).sqrt(),
    ]
}
