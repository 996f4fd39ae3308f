//! `bkpbs.load_predictor`: the planners' HDV predictor (the learned lane-change model b_θ or
//! constant speed), for predicting from the caller's own vehicle readings.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use bkpbs::config::{Config, PredictorKind};
use bkpbs::model::road::Road;
use bkpbs::model::scene::{Kind, Origin, Scene};
use bkpbs::model::trajectory::{Pose, Trajectory};
use bkpbs::predict::{ConstantSpeed, LaneChangeModel, Learned, Predictor};

use crate::errors::bad_input;
use crate::scene::scene_of;

fn load_model(path: &Path) -> PyResult<LaneChangeModel> {
    LaneChangeModel::load(path).map_err(bad_input)
}

/// Makes `config` use the learned predictor with the model file at `path` in place of the
/// embedded model of its kind (conditioned on CAV plans or not).
///
/// # Errors
/// [`crate::errors::BkpbsError`] when the file is missing or is not a model.
pub fn use_model(config: &mut Config, path: &Path) -> PyResult<()> {
    let model = load_model(path)?;
    let p = &mut config.predictor;
    p.kind = PredictorKind::Learned;
    if model.conditioned() {
        p.conditioned_model = Some(path.to_path_buf());
    } else {
        p.unconditioned_model = Some(path.to_path_buf());
    }
    Ok(())
}

/// The predictor behind a [`PyPredictor`].
enum Model {
    Constant(ConstantSpeed),
    Learned(Learned),
}

impl Model {
    fn as_predictor(&self) -> &dyn Predictor {
        match self {
            Model::Constant(c) => c,
            Model::Learned(l) => l,
        }
    }
}

/// An HDV predictor over the merge network's road frame.
#[pyclass(name = "Predictor", module = "bkpbs", unsendable)]
pub struct PyPredictor {
    model: Model,
    config: Config,
    road: Road,
    origins: HashMap<String, Origin>,
}

/// A pose as Python sees it: `(s, y, heading, speed)`.
type PoseTuple = (f64, f64, f64, f64);

/// Higher-priority CAV plans as trajectories: per plan, `(s, y, heading, speed)` from step 0.
fn plans_of(config: &Config, plans: Option<Vec<Vec<PoseTuple>>>) -> Vec<Trajectory> {
    let sc = &config.scenario;
    plans
        .unwrap_or_default()
        .into_iter()
        .map(|poses| Trajectory {
            poses: poses
                .into_iter()
                .map(|(s, y, heading, speed)| Pose {
                    s,
                    y,
                    heading,
                    speed,
                })
                .collect(),
            length: sc.vehicle_length,
            width: sc.vehicle_width,
            brake: None,
            committed: true,
        })
        .collect()
}

impl PyPredictor {
    /// The scene and the index of HDV `vehicle_id` in it.
    fn hdv(&mut self, vehicles: &Bound<'_, PyAny>, vehicle_id: &str) -> PyResult<(Scene, usize)> {
        let sc = &self.config.scenario;
        let scene = scene_of(vehicles, &self.road, sc, &mut self.origins, 0.0)?.scene;
        let Some(i) = scene.vehicles.iter().position(|v| &*v.id == vehicle_id) else {
            return Err(bad_input(format!(
                "vehicle '{vehicle_id}' is not among the vehicles on the merge section"
            )));
        };
        if scene.vehicles[i].kind != Kind::Hdv {
            return Err(bad_input(format!(
                "vehicle '{vehicle_id}' is a CAV: predictions are for HDVs"
            )));
        }
        Ok((scene, i))
    }
}

#[pymethods]
impl PyPredictor {
    /// `"learned"` (b_θ) or `"constant"`.
    #[getter]
    fn name(&self) -> &'static str {
        self.model.as_predictor().name()
    }

    /// Per-step probabilities (hazards) that HDV `vehicle_id` starts a lane change at step k,
    /// given that it has not started before, for k = 0, 1, … until the change is predicted to
    /// start (the probability that it has started reaches `predictor.decision_probability`) or
    /// the horizon ends. `vehicles` is the list `Controller.plan` takes; `plans` are the
    /// trajectories of higher-priority CAVs, `(s, y, heading, speed)` per step from now (given:
    /// the conditioned model). The constant-speed predictor answers 0 or 1. `horizon` defaults
    /// to the planner's.
    #[pyo3(signature = (vehicles, vehicle_id, horizon = None, plans = None))]
    fn predict(
        &mut self,
        vehicles: &Bound<'_, PyAny>,
        vehicle_id: &str,
        horizon: Option<usize>,
        plans: Option<Vec<Vec<PoseTuple>>>,
    ) -> PyResult<Vec<f64>> {
        let (scene, i) = self.hdv(vehicles, vehicle_id)?;
        let horizon = horizon.unwrap_or(self.config.planner.horizon);
        let plans = plans_of(&self.config, plans);
        let refs: Vec<&Trajectory> = plans.iter().collect();
        match &self.model {
            Model::Learned(l) => Ok(l.rollout(&scene, i, &refs, horizon).probabilities),
            Model::Constant(c) => {
                // Deterministic: the lane change starts where the trajectory leaves its lane.
                let t = c.predict(&scene, i, &refs, horizon);
                let y0 = t.poses[0].y;
                let start = (0..horizon)
                    .find(|&k| t.poses.get(k + 1).is_some_and(|p| (p.y - y0).abs() > 1e-9));
                let n = start.map_or(horizon, |k| k + 1);
                Ok((0..n).map(|k| f64::from(Some(k) == start)).collect())
            }
        }
    }

    /// The predicted poses of HDV `vehicle_id` at steps 0 … horizon: `(s, y, heading, speed)`
    /// in the road frame (`y` = lane · lane width + lateral offset). Arguments as `predict`.
    #[pyo3(signature = (vehicles, vehicle_id, horizon = None, plans = None))]
    fn trajectory(
        &mut self,
        vehicles: &Bound<'_, PyAny>,
        vehicle_id: &str,
        horizon: Option<usize>,
        plans: Option<Vec<Vec<PoseTuple>>>,
    ) -> PyResult<Vec<PoseTuple>> {
        let (scene, i) = self.hdv(vehicles, vehicle_id)?;
        let horizon = horizon.unwrap_or(self.config.planner.horizon);
        let plans = plans_of(&self.config, plans);
        let refs: Vec<&Trajectory> = plans.iter().collect();
        let t = self.model.as_predictor().predict(&scene, i, &refs, horizon);
        Ok(t.poses
            .iter()
            .map(|p| (p.s, p.y, p.heading, p.speed))
            .collect())
    }

    fn __repr__(&self) -> String {
        format!("Predictor(name='{}')", self.name())
    }
}

/// The planners' HDV predictor. `path` is a b_θ model file (JSON, as in `models/`), which
/// replaces the embedded model of its kind (conditioned on CAV plans or not); without it, the
/// predictor the configuration selects (`predictor.kind`: `"learned"`, with the configured or
/// embedded models, or `"constant"`). `config` and keyword overrides as for `Controller`. A
/// model trained under another step length than the configuration's `scenario.dt` is refused.
#[pyfunction]
#[pyo3(signature = (path = None, *, config = None, **overrides))]
pub fn load_predictor(
    path: Option<PathBuf>,
    config: Option<&Bound<'_, PyAny>>,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyPredictor> {
    let config = crate::config::resolve(config, overrides, toml::Table::new())?;
    let model = match path {
        Some(p) => {
            let m = Arc::new(load_model(&p)?);
            // A model trained under another step length is refused, as by the binary.
            m.check_step_length(config.scenario.dt).map_err(bad_input)?;
            let (c, u) = if m.conditioned() {
                (m, LaneChangeModel::embedded(false))
            } else {
                (LaneChangeModel::embedded(true), m)
            };
            Model::Learned(Learned::with_models(&config, c, u))
        }
        None => match config.predictor.kind {
            PredictorKind::Constant => Model::Constant(ConstantSpeed::new(&config)),
            PredictorKind::Learned => {
                // The core checks the configured files (kinds, shapes); the same files again
                // here, since rollout probabilities need the concrete predictor.
                bkpbs::predict::configured(&config).map_err(bad_input)?;
                let p = &config.predictor;
                let model = |path: &Option<PathBuf>, conditioned| match path {
                    Some(path) => load_model(path).map(Arc::new),
                    None => Ok(LaneChangeModel::embedded(conditioned)),
                };
                let c = model(&p.conditioned_model, true)?;
                let u = model(&p.unconditioned_model, false)?;
                Model::Learned(Learned::with_models(&config, c, u))
            }
        },
    };
    Ok(PyPredictor {
        model,
        config,
        road: Road::paper_default(),
        origins: HashMap::new(),
    })
}
