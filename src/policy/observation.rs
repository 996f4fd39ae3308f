//! What the RL-PPO policy sees of one CAV's surroundings (the paper's "up to 14 surrounding
//! vehicles"): the ego state, then the 14 nearest vehicles in the road frame, each relative to
//! the ego, nearest first, zero-padded with `present = 0` when fewer are around. Every feature
//! is scaled by a fixed constant of the scenario (speed limit, lane width, merge-zone length),
//! not by running statistics, so an observation means the same in training and at test time,
//! in Rust and in Python.

use crate::model::scene::{Kind, Scene};

/// Vehicles observed around the ego.
pub const NEIGHBOURS: usize = 14;
/// Features of the ego.
pub const EGO_FEATURES: usize = 8;
/// Features of each neighbour.
pub const NEIGHBOUR_FEATURES: usize = 5;
/// Length of an observation vector.
pub const OBS_DIM: usize = EGO_FEATURES + NEIGHBOURS * NEIGHBOUR_FEATURES;

/// Scale of longitudinal distances (m).
const DISTANCE_SCALE: f64 = 100.0;
/// Largest scaled longitudinal distance: vehicles farther away look this far.
const DISTANCE_CLIP: f64 = 3.0;
/// Scale of accelerations (m/s²).
const ACCEL_SCALE: f64 = 5.0;

/// Names of the features, in order (for documentation and the Python observation space).
pub fn feature_names() -> Vec<String> {
    let mut names: Vec<String> = [
        "ego_speed",
        "ego_lane",
        "ego_lateral",
        "ego_on_merge_lane",
        "ego_to_merge_end",
        "ego_progress",
        "ego_changing_lanes",
        "ego_accel",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for k in 0..NEIGHBOURS {
        for f in ["ds", "dy", "dv", "is_cav", "present"] {
            names.push(format!("n{k}_{f}"));
        }
    }
    names
}

/// Writes the observation of scene vehicle `i` into `out` (length [`OBS_DIM`]). `changing`:
/// the vehicle is executing a lane change it was told to make. `v_max`: the speed limit.
pub fn observe(scene: &Scene, i: usize, changing: bool, v_max: f64, out: &mut [f32]) {
    assert_eq!(out.len(), OBS_DIM, "observation buffer");
    out.fill(0.0);
    let road = &scene.road;
    let me = &scene.vehicles[i];
    let merge = road.zone_for(me.lane, me.front());
    let zone = (merge.end - merge.start).max(1.0);
    let on_merge_lane = road.is_auxiliary(me.lane);
    let ego = [
        me.speed / v_max,
        f64::from(me.lane) / f64::from(road.top_lane()),
        me.lateral / road.lane_width,
        f64::from(u8::from(on_merge_lane)),
        if on_merge_lane {
            ((merge.end - me.front()) / zone).clamp(0.0, 2.0)
        } else {
            0.0
        },
        (me.s / road.section_end).clamp(-1.0, 1.5),
        f64::from(u8::from(changing)),
        (me.accel / ACCEL_SCALE).clamp(-2.0, 2.0),
    ];
    for (o, e) in out.iter_mut().zip(ego) {
        *o = e as f32;
    }
    let y = |k: usize| {
        let v = &scene.vehicles[k];
        f64::from(v.lane) * road.lane_width + v.lateral
    };
    let my_y = y(i);
    let mut near: Vec<(f64, usize)> = (0..scene.vehicles.len())
        .filter(|&k| k != i)
        .map(|k| {
            let ds = scene.vehicles[k].s - me.s;
            let dy = (y(k) - my_y) / road.lane_width * 4.0;
            (ds.hypot(dy), k)
        })
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    for (slot, &(_, k)) in near.iter().take(NEIGHBOURS).enumerate() {
        let v = &scene.vehicles[k];
        let f = [
            ((v.s - me.s) / DISTANCE_SCALE).clamp(-DISTANCE_CLIP, DISTANCE_CLIP),
            (y(k) - my_y) / road.lane_width,
            (v.speed - me.speed) / v_max,
            f64::from(u8::from(v.kind == Kind::Cav)),
            1.0,
        ];
        let at = EGO_FEATURES + slot * NEIGHBOUR_FEATURES;
        for (o, x) in out[at..at + NEIGHBOUR_FEATURES].iter_mut().zip(f) {
            *o = x as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scene::{Origin, VehicleState};

    #[test]
    fn nearest_first_relative_and_padded() {
        let cav = VehicleState::on_lane("c", Kind::Cav, Origin::Main, 200.0, 1, 30.0);
        let far = VehicleState::on_lane("far", Kind::Hdv, Origin::Main, 300.0, 1, 25.0);
        let near = VehicleState::on_lane("near", Kind::Cav, Origin::Main, 190.0, 2, 33.0);
        let scene = Scene::on_paper_road(10.0, vec![far, cav, near]);
        let mut o = vec![9.0; OBS_DIM];
        observe(&scene, 1, false, 35.0, &mut o);
        assert!((o[0] - 30.0 / 35.0).abs() < 1e-6);
        assert_eq!(o[1], 0.5);
        let n0 = &o[EGO_FEATURES..EGO_FEATURES + 5];
        assert_eq!(n0, &[-0.1, 1.0, 3.0 / 35.0, 1.0, 1.0]);
        let n1 = &o[EGO_FEATURES + 5..EGO_FEATURES + 10];
        assert_eq!(n1, &[1.0, 0.0, -5.0 / 35.0, 0.0, 1.0]);
        assert!(o[EGO_FEATURES + 10..].iter().all(|&x| x == 0.0));
        assert_eq!(feature_names().len(), OBS_DIM);
    }
}
