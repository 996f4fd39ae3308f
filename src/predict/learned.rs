//! The learned predictor: b_θ's lane-change decisions rolled out over the horizon.
//!
//! Longitudinally every vehicle keeps its speed (paper IV.D). Laterally, the HDV's state is
//! rolled forward step by step, and at each step k the model is evaluated on the rolled-out
//! scene: graph (a) from the other vehicles at constant speed in their lanes (CAVs whose plans
//! are given: at their planned poses), sequence (b) from the given plans over the 15 steps after
//! k. The per-step probabilities p_k are hazards: the HDV is predicted to start its lane change
//! at the first step at which the probability that it has started, 1 − Π_{j≤k}(1 − p_j),
//! reaches `predictor.decision_probability` (default ½: the median start, as the
//! constant-speed predictor does for ramp merges). The change is then executed as SUMO does it:
//! one lane at constant lateral speed over the lane-change duration (5 steps of 0.9 m), towards
//! the only lane the HDV can go to (acceleration lane and right main lane: left; left main lane:
//! right), and by a standing HDV only once the lane beside it is free ([`super::blocked`]). At
//! most one lane change is predicted per horizon. A vehicle already changing lanes
//! finishes its manoeuvre in the direction of its heading, and nothing more is predicted.
//!
//! With plans of higher-priority CAVs given, the conditioned model is used, otherwise the
//! unconditioned one (BK-M-A*, the PBS root).

use std::cell::RefCell;
use std::sync::Arc;

use super::blocked::Blocking;
use super::features::{
    cav_node, ego_of, lane_change_direction, neighbours, select_cavs, Agent, Observation, PREVIEW,
    SENSING_RANGE,
};
use super::infer::Workspace;
use super::longitudinal::Longitudinal;
use super::model_file::{LaneChangeModel, ModelError};
use super::Predictor;
use crate::config::{Config, PredictorKind};
use crate::model::road::Road;
use crate::model::scene::{Kind, Origin, Scene, VehicleState};
use crate::model::trajectory::Trajectory;

/// b_θ as a [`Predictor`].
#[derive(Debug, Clone)]
pub struct Learned {
    conditioned: Arc<LaneChangeModel>,
    unconditioned: Arc<LaneChangeModel>,
    dt: f64,
    lane_change_steps: usize,
    /// Hardest braking of an HDV (SUMO's emergencyDecel), carried by its predictions.
    hdv_brake: f64,
    decision_probability: f64,
    /// How predicted HDVs move along their lane.
    longitudinal: Longitudinal,
    /// When a standing HDV can start its change.
    blocking: Blocking,
}

/// Per-thread buffers, so predicting allocates nothing but the trajectory it returns.
#[derive(Default)]
struct Buffers {
    ws: Workspace,
    /// Scene vehicles other than the HDV (now), and whether a given plan replaces each.
    others: Vec<(Agent, bool)>,
    /// Everyone else at the rollout step.
    moved: Vec<Agent>,
    /// Plan agents at the rollout step (candidates of sequence (b)).
    plan_agents: Vec<(usize, Agent)>,
    chosen: Vec<usize>,
}

thread_local! {
    static BUFFERS: RefCell<Buffers> = RefCell::new(Buffers::default());
}

/// What the rollout decided for one HDV.
#[derive(Debug, Clone, PartialEq)]
pub struct Rollout {
    /// The model's probability at each rollout step evaluated (step 0 = now); empty when the
    /// rollout was run for a trajectory only.
    pub probabilities: Vec<f64>,
    /// The step at which the lane change is predicted to start (lateral motion from the next
    /// step on), if within the horizon.
    pub start: Option<usize>,
    /// Lateral direction: +1 left, −1 right.
    pub direction: i32,
}

impl Learned {
    /// With given models.
    pub fn with_models(
        config: &Config,
        conditioned: Arc<LaneChangeModel>,
        unconditioned: Arc<LaneChangeModel>,
    ) -> Learned {
        let s = &config.scenario;
        Learned {
            conditioned,
            unconditioned,
            dt: s.dt,
            lane_change_steps: s.lane_change_steps(),
            decision_probability: config.predictor.decision_probability,
            hdv_brake: config.idm.max_decel,
            longitudinal: Longitudinal::ConstantSpeed,
            blocking: Blocking::new(config),
        }
    }

    /// The same predictor with HDVs moving along their lane by `longitudinal`.
    pub fn with_longitudinal(mut self, longitudinal: Longitudinal) -> Learned {
        self.longitudinal = longitudinal;
        self
    }

    /// The model used with (`true`) or without plans to condition on.
    pub fn model(&self, conditioned: bool) -> &LaneChangeModel {
        if conditioned {
            &self.conditioned
        } else {
            &self.unconditioned
        }
    }

    /// Rolls the lane-change decision of HDV `i` out over `horizon` steps.
    pub fn rollout(
        &self,
        scene: &Scene,
        i: usize,
        conditioned_on: &[&Trajectory],
        horizon: usize,
    ) -> Rollout {
        BUFFERS.with(|b| {
            self.rollout_with(&mut b.borrow_mut(), scene, i, conditioned_on, horizon, true)
        })
    }

    /// The rollout behind [`Learned::rollout`] and [`Predictor::predict`], with the caller's
    /// buffers; `record` keeps the per-step probabilities (predicting needs only the start).
    fn rollout_with(
        &self,
        buf: &mut Buffers,
        scene: &Scene,
        i: usize,
        plans: &[&Trajectory],
        horizon: usize,
        record: bool,
    ) -> Rollout {
        let road = &scene.road;
        let v = &scene.vehicles[i];
        let direction = lane_change_direction(road, v.lane);
        let mut out = Rollout {
            probabilities: Vec::new(),
            start: None,
            direction,
        };
        let model = self.model(!plans.is_empty());
        let ego0 = Agent::of(v, road.lane_width);
        self.collect_others(&mut buf.others, scene, i, plans);
        self.drop_never_neighbours(&mut buf.others, &ego0, v.speed, horizon);
        let mut obs = Observation {
            ego: ego_of(v, road),
            ..Observation::default()
        };
        obs.ego.lateral = 0.0;
        let mut undecided = 1.0;
        for k in 0..horizon {
            let dk = v.speed * self.dt * k as f64;
            let Some(zone_end) = lane_change_zone_end(road, v, dk) else {
                if record {
                    out.probabilities.push(0.0);
                }
                continue;
            };
            let ego = Agent {
                s: ego0.s + dk,
                ..ego0
            };
            obs.ego.to_merge_end = (zone_end - v.front() - dk) as f32;
            self.observe_at(buf, &mut obs, &ego, plans, k, road);
            let p = model.probability(&obs, &mut buf.ws);
            if record {
                out.probabilities.push(p);
            }
            undecided *= 1.0 - p;
            if 1.0 - undecided >= self.decision_probability {
                out.start = Some(k);
                break;
            }
        }
        out
    }

    /// Leaves out of `others` every vehicle that stays beyond the sensing range of the HDV at
    /// `ego0` driving at `speed` over the whole rollout of `horizon` steps (a metre to spare over
    /// rounding): it is never a neighbour, so each step scans only the few that can be, not every
    /// vehicle of a full corridor.
    fn drop_never_neighbours(
        &self,
        others: &mut Vec<(Agent, bool)>,
        ego0: &Agent,
        speed: f64,
        horizon: usize,
    ) {
        let span = self.dt * horizon as f64;
        others.retain(|(a, _)| {
            (a.s - ego0.s).abs() <= SENSING_RANGE + 1.0 + (a.speed - speed).abs() * span
        });
    }

    /// Every scene vehicle but `i`, now, and whether a given plan replaces it: a scene vehicle
    /// at a plan's first pose is that plan's CAV, so it must not be counted twice.
    fn collect_others(
        &self,
        others: &mut Vec<(Agent, bool)>,
        scene: &Scene,
        i: usize,
        plans: &[&Trajectory],
    ) {
        let w = scene.road.lane_width;
        others.clear();
        for (j, o) in scene.vehicles.iter().enumerate() {
            if j == i {
                continue;
            }
            let a = Agent::of(o, w);
            let planned = plans.iter().any(|t| {
                let p = t.at(0, self.dt);
                (p.s - a.s).abs() < 0.5 && (p.y - a.y).abs() < 0.5
            });
            others.push((a, planned));
        }
    }

    /// Fills the surroundings of the rolled-out HDV `ego` at rollout step `k` into `obs`: graph
    /// (a) from the unplanned vehicles at constant speed and the planned CAVs at their plans'
    /// poses, and, with plans given, sequence (b) from the plans over the preview after `k`.
    fn observe_at(
        &self,
        buf: &mut Buffers,
        obs: &mut Observation,
        ego: &Agent,
        plans: &[&Trajectory],
        k: usize,
        road: &Road,
    ) {
        buf.moved.clear();
        buf.moved.extend(
            buf.others
                .iter()
                .filter(|(_, planned)| !planned)
                .map(|(a, _)| Agent {
                    s: a.s + a.speed * self.dt * k as f64,
                    ..*a
                }),
        );
        buf.plan_agents.clear();
        for (n, t) in plans.iter().enumerate() {
            let a = self.plan_agent(t, k, road);
            buf.moved.push(a);
            buf.plan_agents.push((n, a));
        }
        obs.neighbours = neighbours(ego, buf.moved.iter());
        if !plans.is_empty() {
            select_cavs(ego, buf.plan_agents.iter().copied(), &mut buf.chosen);
            obs.cavs = Default::default();
            for (slot, &n) in buf.chosen.iter().enumerate() {
                for j in 1..=PREVIEW {
                    let a = self.plan_agent(plans[n], k + j, road);
                    obs.cavs[j - 1][slot] = cav_node(ego, j, self.dt, a.s, a.y, a.speed);
                }
            }
        }
    }

    /// The CAV following plan `t`, at step `k`.
    fn plan_agent(&self, t: &Trajectory, k: usize, road: &Road) -> Agent {
        let p = t.at(k, self.dt);
        Agent {
            s: p.s,
            y: p.y,
            lane: road.lane_at(p.y),
            speed: p.speed,
            is_cav: true,
        }
    }

    fn trajectory(
        &self,
        scene: &Scene,
        i: usize,
        lateral: impl Fn(usize) -> f64,
        horizon: usize,
    ) -> Trajectory {
        let v = &scene.vehicles[i];
        let poses = self.longitudinal.poses(scene, i, horizon, self.dt, lateral);
        Trajectory {
            poses,
            length: v.length,
            width: v.width,
            brake: (v.kind == Kind::Hdv).then_some(self.hdv_brake),
            committed: false,
        }
    }

    /// HDV `i`, caught mid-manoeuvre at lateral position `y0`: SUMO finishes the change at
    /// constant lateral speed in the direction of its heading (without one: back to its lane's
    /// centre), and nothing more is predicted.
    fn finishing_manoeuvre(&self, scene: &Scene, i: usize, y0: f64, horizon: usize) -> Trajectory {
        let v = &scene.vehicles[i];
        let w = scene.road.lane_width;
        let step = w / self.lane_change_steps as f64;
        let dir = if v.heading.abs() > 1e-6 {
            v.heading.signum()
        } else {
            -v.lateral.signum()
        };
        let target = if dir > 0.0 {
            (y0 / w).ceil() * w
        } else {
            (y0 / w).floor() * w
        };
        self.trajectory(
            scene,
            i,
            |k| {
                let y = y0 + dir * step * k as f64;
                if dir > 0.0 {
                    y.min(target)
                } else {
                    y.max(target)
                }
            },
            horizon,
        )
    }

    /// HDV `i` at lateral position `y0` executing the rollout's decision `r`: from the step after
    /// the predicted start, one lane in `r.direction` over the lane-change duration; without a
    /// start, its lane kept.
    fn executing_decision(
        &self,
        scene: &Scene,
        i: usize,
        y0: f64,
        r: &Rollout,
        horizon: usize,
    ) -> Trajectory {
        let w = scene.road.lane_width;
        let lc = self.lane_change_steps as f64;
        self.trajectory(
            scene,
            i,
            |k| match r.start {
                Some(m) if k > m => y0 + r.direction as f64 * w * ((k - m) as f64 / lc).min(1.0),
                _ => y0,
            },
            horizon,
        )
    }
}

impl Predictor for Learned {
    fn name(&self) -> &'static str {
        "learned"
    }

    fn predict(
        &self,
        scene: &Scene,
        i: usize,
        conditioned_on: &[&Trajectory],
        horizon: usize,
    ) -> Trajectory {
        let v = &scene.vehicles[i];
        let y0 = v.lane as f64 * scene.road.lane_width + v.lateral;
        if v.kind != Kind::Hdv {
            return self.trajectory(scene, i, |_| y0, horizon);
        }
        if !v.on_lane_centre() {
            return self.finishing_manoeuvre(scene, i, y0, horizon);
        }
        let r = BUFFERS.with(|b| {
            self.rollout_with(
                &mut b.borrow_mut(),
                scene,
                i,
                conditioned_on,
                horizon,
                false,
            )
        });
        let target = v.lane + r.direction;
        let start = self.blocking.first_free(scene, i, target, r.start, horizon);
        self.executing_decision(scene, i, y0, &Rollout { start, ..r }, horizon)
    }
}

/// The end of the merge zone ahead of HDV `v` once it has driven `dk` further, or `None` where
/// it cannot change lanes: on the single-lane ramp edge, before the zone, no lane change is
/// possible, and a main-road vehicle on lane 0 is on a deceleration lane, leaving, and does not
/// come back.
fn lane_change_zone_end(road: &Road, v: &VehicleState, dk: f64) -> Option<f64> {
    let zone = road.zone_for(v.lane, v.front() + dk);
    let auxiliary = road.is_auxiliary(v.lane);
    let leaving = auxiliary && v.origin == Origin::Main;
    if auxiliary && v.front() + dk < zone.start || leaving {
        None
    } else {
        Some(zone.end)
    }
}

/// A predictor model file the configuration names cannot be used.
#[derive(Debug, thiserror::Error)]
#[error("{field}: {cause}")]
pub struct PredictorError {
    /// The setting that names the file.
    pub field: &'static str,
    /// Why the file cannot be used.
    pub cause: ModelError,
}

/// b_θ trained on the profile SUMO runs, when `predictor.calibrations` names a directory of
/// per-profile calibrations that holds one (`DIR/<profile>/gcn-conditioned.json`,
/// `gcn-unconditioned.json`); else the configured or embedded model is used.
fn profile_model(config: &Config, conditioned: bool) -> Option<std::path::PathBuf> {
    let file = if conditioned {
        "gcn-conditioned.json"
    } else {
        "gcn-unconditioned.json"
    };
    let dir = config.predictor.calibrations.as_ref()?;
    let path = dir.join(&config.hdv.profile).join(file);
    path.is_file().then_some(path)
}

/// The conditioned and unconditioned b_θ `config.predictor` selects: the named files, those
/// of the profile SUMO runs (`predictor.calibrations`), or the embedded ones; each checked to
/// be of its kind and trained under the run's step length.
///
/// # Errors
/// A model file that cannot be used, naming the setting and the file.
pub fn configured_models(
    config: &Config,
) -> Result<(Arc<LaneChangeModel>, Arc<LaneChangeModel>), PredictorError> {
    let p = &config.predictor;
    let dt = config.scenario.dt;
    let load = |path: &Option<std::path::PathBuf>, field, conditioned| {
        let model = match path.clone().or_else(|| profile_model(config, conditioned)) {
            Some(path) => LaneChangeModel::load(&path).map(Arc::new),
            None => Ok(LaneChangeModel::embedded(conditioned)),
        };
        model
            .and_then(|m| m.check_step_length(dt).map(|()| m))
            .map_err(|cause| PredictorError { field, cause })
    };
    let c = load(&p.conditioned_model, "predictor.conditioned_model", true)?;
    let u = load(
        &p.unconditioned_model,
        "predictor.unconditioned_model",
        false,
    )?;
    if !c.conditioned() || u.conditioned() {
        return Err(PredictorError {
            field: "predictor",
            cause: ModelError::Shape {
                path: if c.conditioned() {
                    u.source.clone().into()
                } else {
                    c.source.clone().into()
                },
                what: "conditioned_model must be a conditioned model and unconditioned_model an unconditioned one".into(),
            },
        });
    }
    Ok((c, u))
}

/// The HDV predictor `config.predictor` selects: b_θ (with the configured or the embedded
/// models) or constant speed.
///
/// # Errors
/// A model file that cannot be used, naming the setting and the file.
pub fn configured(config: &Config) -> Result<Box<dyn Predictor>, PredictorError> {
    let longitudinal = Longitudinal::from_config(config).map_err(|cause| PredictorError {
        field: "predictor.calibration",
        cause,
    })?;
    match config.predictor.kind {
        PredictorKind::Constant => Ok(Box::new(
            super::ConstantSpeed::new(config).with_longitudinal(longitudinal),
        )),
        PredictorKind::Learned => {
            let (c, u) = configured_models(config)?;
            Ok(Box::new(
                Learned::with_models(config, c, u).with_longitudinal(longitudinal),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `predictor.calibrations` picks b_θ trained on the profile SUMO runs where the directory
    /// has one, and leaves the default model otherwise.
    #[test]
    fn calibrations_directory_selects_the_profile_s_models() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/profiles");
        let mut c = Config::default();
        c.predictor.calibrations = Some(dir.clone());
        c.hdv.profile = "paper".into();
        assert_eq!(
            profile_model(&c, true),
            Some(dir.join("paper/gcn-conditioned.json"))
        );
        assert_eq!(
            profile_model(&c, false),
            Some(dir.join("paper/gcn-unconditioned.json"))
        );
        c.hdv.profile = "sumo-safe".into(); // trained on it: the embedded models
        assert_eq!(profile_model(&c, true), None);
        c.predictor.calibrations = None;
        c.hdv.profile = "paper".into();
        assert_eq!(profile_model(&c, true), None);
        configured(&c).unwrap();
    }
}
