//! Follow samples from SUMO episodes: an episode [`Observer`] keeps each step's main-road
//! vehicles, and [`FollowRecorder::samples`] turns every HDV, once a second, into a
//! [`FollowSample`] when the next 3 s are clean: it keeps its lane and its leader (no cut-in,
//! nobody leaves), or drives a free road (nobody within [`FREE_ROAD_M`] ahead) throughout.
//! The acceleration lane is left out: its vehicles brake for the lane's end, not a leader.
//! A recorder reads the scenes it sees as one road's: on a user's scenario of several merge
//! regions each region has its own ([`PerRegion`](crate::episode::PerRegion)), and
//! [`of_regions`] puts their samples together.

use std::collections::HashMap;
use std::sync::Arc;

use super::model::{FollowSample, HORIZON_STEPS, STEPS_1S};
use crate::episode::Observer;
use crate::model::scene::{Kind, Scene};

/// Beyond this distance (m) a vehicle ahead does not count as a leader.
pub const FREE_ROAD_M: f64 = 150.0;
/// Steps between the samples of one vehicle (1 s): neighbouring starts would repeat each other.
pub const STRIDE: usize = 5;

/// A vehicle on the main road at one step.
#[derive(Debug, Clone)]
struct Seen {
    id: Arc<str>,
    hdv: bool,
    lane: i32,
    front: f64,
    rear: f64,
    speed: f64,
    desired: f64,
}

/// Records the main-road vehicles of every step.
#[derive(Default)]
pub struct FollowRecorder {
    steps: Vec<Vec<Seen>>,
}

impl Observer for FollowRecorder {
    fn observe(&mut self, scene: &Scene) {
        let seen = scene
            .vehicles
            .iter()
            .filter(|v| !scene.road.is_auxiliary(v.lane) && !v.on_ramp)
            .map(|v| Seen {
                id: v.id.clone(),
                hdv: v.kind == Kind::Hdv,
                lane: v.lane,
                front: v.front(),
                rear: v.rear(),
                speed: v.speed,
                desired: v.desired_speed,
            })
            .collect();
        self.steps.push(seen);
    }
}

/// The samples of each merge region's recorder, in region order.
pub fn of_regions(regions: &[FollowRecorder]) -> Vec<FollowSample> {
    regions.iter().flat_map(FollowRecorder::samples).collect()
}

/// The nearest vehicle ahead of `f` on its lane within [`FREE_ROAD_M`], if any.
fn leader_of<'a>(step: &'a [Seen], f: &Seen) -> Option<&'a Seen> {
    step.iter()
        .filter(|u| u.lane == f.lane && u.front > f.front && u.rear - f.front < FREE_ROAD_M)
        .min_by(|a, b| a.front.total_cmp(&b.front))
}

impl FollowRecorder {
    /// The clean follow samples of the recorded episode.
    pub fn samples(&self) -> Vec<FollowSample> {
        let index: Vec<HashMap<&str, usize>> = self
            .steps
            .iter()
            .map(|s| s.iter().enumerate().map(|(i, v)| (&*v.id, i)).collect())
            .collect();
        let mut out = Vec::new();
        for k in (0..self.steps.len().saturating_sub(HORIZON_STEPS)).step_by(STRIDE) {
            for f in self.steps[k].iter().filter(|v| v.hdv) {
                if let Some(s) = self.sample_at(&index, k, f) {
                    out.push(s);
                }
            }
        }
        out
    }

    /// The sample of follower `f` starting at step `k`, if its next 3 s are clean.
    fn sample_at(
        &self,
        index: &[HashMap<&str, usize>],
        k: usize,
        f: &Seen,
    ) -> Option<FollowSample> {
        let leader_id = leader_of(&self.steps[k], f).map(|l| l.id.clone());
        let mut course = Vec::with_capacity(HORIZON_STEPS + 1);
        let mut own = Vec::with_capacity(HORIZON_STEPS + 1);
        for n in 0..=HORIZON_STEPS {
            let step = &self.steps[k + n];
            let me = &step[*index[k + n].get(&*f.id)?];
            if me.lane != f.lane {
                return None;
            }
            let leader = leader_of(step, me);
            if leader.map(|l| &l.id) != leader_id.as_ref() {
                return None;
            }
            if let Some(l) = leader {
                course.push((l.rear, l.speed));
            }
            own.push((me.front, me.speed));
        }
        Some(FollowSample {
            vehicle: f.id.to_string(),
            desired_speed: f.desired,
            front: f.front,
            speed: f.speed,
            gap_3s: course
                .last()
                .map_or(f64::NAN, |l| l.0 - own[HORIZON_STEPS].0),
            leader: leader_id.map(|_| course),
            speed_1s: own[STEPS_1S].1,
            speed_3s: own[HORIZON_STEPS].1,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::episode::PerRegion;
    use crate::model::scene::{Origin, VehicleState};

    /// Step `k` of a region where HDV `id` follows `id-lead` 30 m ahead, both at 25 m/s.
    fn following(id: &str, k: usize) -> Scene {
        let s = 100.0 + 25.0 * 0.2 * k as f64;
        let v = |name: &str, at| VehicleState::on_lane(name, Kind::Hdv, Origin::Main, at, 1, 25.0);
        let lead = format!("{id}-lead");
        Scene::on_paper_road(0.2 * k as f64, vec![v(id, s), v(&lead, s + 30.0)])
    }

    /// The vehicles of `samples`, in order.
    fn vehicles(samples: &[FollowSample]) -> Vec<&str> {
        samples.iter().map(|s| s.vehicle.as_str()).collect()
    }

    /// Two regions' scenes arrive interleaved, step by step, as the episode loop shows them:
    /// one recorder per region samples each as if it had run alone, region 0's samples first;
    /// one recorder for both would read them as one road's steps and find nobody's next 3 s.
    #[test]
    fn each_region_is_sampled_apart_and_its_samples_come_in_region_order() {
        let mut per_region = PerRegion::new(|_| FollowRecorder::default());
        let mut shared = FollowRecorder::default();
        let mut alone = [FollowRecorder::default(), FollowRecorder::default()];
        for k in 0..HORIZON_STEPS + 1 + STRIDE {
            for (r, id) in ["a", "b"].into_iter().enumerate() {
                let scene = following(id, k);
                per_region.observe_region(r, &scene);
                shared.observe_region(r, &scene);
                alone[r].observe(&scene);
            }
        }
        let got = of_regions(&per_region.into_regions());
        let want: Vec<FollowSample> = alone.iter().flat_map(FollowRecorder::samples).collect();
        assert_eq!(
            vehicles(&want),
            ["a", "a-lead", "a", "a-lead", "b", "b-lead", "b", "b-lead"]
        );
        assert_eq!(format!("{got:?}"), format!("{want:?}"));
        assert!(shared.samples().is_empty());
    }
}
