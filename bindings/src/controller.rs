//! `bkpbs.Controller`: one planning step of any core planner for vehicles read by the caller's
//! own TraCI or libsumo loop, and `bkpbs.Maneuver`, what one CAV does next.

use std::collections::HashMap;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use bkpbs::config::Config;
use bkpbs::controller::{self, CavHandling, Command, Controller, LaneChange, PLANNERS};
use bkpbs::model::road::Road;
use bkpbs::model::scene::{Kind, Origin};
use bkpbs::sumo::frame;

use crate::errors::bad_input;
use crate::scene::scene_of;

/// What one CAV does during the next step.
#[pyclass(name = "Maneuver", module = "bkpbs", frozen, eq)]
#[derive(Debug, Clone, PartialEq)]
pub struct PyManeuver {
    /// Speed to command with `setSpeed` (m/s), already clamped to [0, v_max].
    #[pyo3(get)]
    pub speed: f64,
    /// `None`, `"left"` or `"right"`: start a lane change now.
    #[pyo3(get)]
    pub lane_change: Option<&'static str>,
    /// Target lane index on the vehicle's current SUMO edge (its current lane without a lane
    /// change); `None` when that edge has no such lane.
    #[pyo3(get)]
    pub sumo_lane_index: Option<i32>,
}

#[pymethods]
impl PyManeuver {
    fn __repr__(&self) -> String {
        let opt = |x: Option<String>| x.unwrap_or_else(|| "None".into());
        format!(
            "Maneuver(speed={:?}, lane_change={}, sumo_lane_index={})",
            self.speed,
            opt(self.lane_change.map(|l| format!("'{l}'"))),
            opt(self.sumo_lane_index.map(|i| i.to_string())),
        )
    }
}

/// A core planner driven one step at a time by the caller.
///
/// The road frame is read from the network the configuration names (`net_file=`, or
/// `scenario.net_file`), else it is that of the shipped merge network.
#[pyclass(name = "Controller", module = "bkpbs", unsendable)]
pub struct PyController {
    inner: Box<dyn Controller>,
    config: Config,
    road: Road,
    /// Where each vehicle seen in the last call entered; replaced by every call, so a vehicle
    /// absent from one call (removed, arrived) is forgotten.
    origins: HashMap<String, Origin>,
    calls: u64,
    commands: Vec<Command>,
}

/// Builds the core controller `planner` for `config` on `road`.
fn build(planner: &str, config: &Config, road: &Road) -> PyResult<Box<dyn Controller>> {
    controller::by_name(planner, config, road).map_err(bad_input)
}

/// The road of `config`'s network, `net_file` (when given) replacing the configured one.
pub fn road_of(config: &mut Config, net_file: Option<std::path::PathBuf>) -> PyResult<Road> {
    if net_file.is_some() {
        config.scenario.net_file = net_file;
    }
    frame::scenario_road(&config.scenario).map_err(bad_input)
}

#[pymethods]
impl PyController {
    /// Builds planner `planner` (one of `bkpbs.PLANNERS`) with the configuration `config` (a
    /// dict, TOML text or a TOML file) and keyword overrides; `model` is a predictor model file;
    /// `net_file` the SUMO network the caller's loop runs (default: the shipped merge network).
    #[new]
    #[pyo3(signature = (planner = "bk-pbs", config = None, model = None, net_file = None, **overrides))]
    fn new(
        planner: &str,
        config: Option<&Bound<'_, PyAny>>,
        model: Option<std::path::PathBuf>,
        net_file: Option<std::path::PathBuf>,
        overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        if !PLANNERS.contains(&planner) {
            return Err(bad_input(controller::UnknownPlanner(planner.to_string())));
        }
        let mut config = crate::config::resolve(config, overrides, toml::Table::new())?;
        if let Some(path) = model {
            crate::predict::use_model(&mut config, &path)?;
        }
        let road = road_of(&mut config, net_file)?;
        Ok(PyController {
            inner: build(planner, &config, &road)?,
            config,
            road,
            origins: HashMap::new(),
            calls: 0,
            commands: Vec::new(),
        })
    }

    /// Plans one step for `vehicles` (what the caller's loop read after `simulationStep`) and
    /// returns a `Maneuver` per CAV on the merge section, keyed by vehicle id: only vehicles of
    /// this call's `vehicles` (the core's commands index this call's scene), nothing for a
    /// vehicle of an earlier call. `time` is the simulation time (default: one step of `dt` per
    /// call).
    #[pyo3(signature = (vehicles, time = None))]
    fn plan<'py>(
        &mut self,
        py: Python<'py>,
        vehicles: &Bound<'py, PyAny>,
        time: Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let sc = &self.config.scenario;
        self.calls += 1;
        let time = time.unwrap_or(self.calls as f64 * sc.dt);
        let framed = scene_of(vehicles, &self.road, sc, &mut self.origins, time)?;
        let scene = &framed.scene;
        let max = bkpbs::model::scene::MAX_SCENE_VEHICLES;
        if scene.vehicles.len() > max {
            return Err(bad_input(format!(
                "{} vehicles on the merge section in one plan call: at most {max} (a section \
                 holds a few hundred; planning time grows faster than their number)",
                scene.vehicles.len()
            )));
        }
        self.commands.clear();
        self.inner.plan(scene, &mut self.commands);
        let out = PyDict::new(py);
        for c in &self.commands {
            let v = &scene.vehicles[c.vehicle];
            debug_assert_eq!(v.kind, Kind::Cav, "a command for HDV {}", v.id);
            let m = c.maneuver;
            let target = v.lane + m.lane_change.map_or(0, LaneChange::offset);
            let maneuver = PyManeuver {
                speed: frame::commanded_speed(m.speed, sc),
                lane_change: m.lane_change.map(|l| match l {
                    LaneChange::Left => "left",
                    LaneChange::Right => "right",
                }),
                sumo_lane_index: framed.sumo_lane_index(c.vehicle, target),
            };
            out.set_item(&*v.id, maneuver)?;
        }
        Ok(out)
    }

    /// The planner's name.
    #[getter]
    fn planner(&self) -> &'static str {
        self.inner.name()
    }

    /// Whether the caller must command the CAVs (`False` for `"sumo"`, which leaves them to
    /// SUMO's own models and returns no maneuvers).
    #[getter]
    fn commands_cavs(&self) -> bool {
        self.inner.handling() == CavHandling::Commanded
    }

    /// The step length the planner assumes (s); SUMO must run with it.
    #[getter]
    fn dt(&self) -> f64 {
        self.config.scenario.dt
    }

    /// The speed limit v_max (m/s).
    #[getter]
    fn v_max(&self) -> f64 {
        self.config.scenario.v_max
    }

    /// The search effort of the last `plan` call (all zero for rule-based planners).
    fn last_stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.inner.last_stats();
        let d = PyDict::new(py);
        for (k, v) in [
            ("searches", s.searches),
            ("nodes_expanded", s.nodes_expanded),
            ("phase2_plans", s.phase2_plans),
            ("fallbacks", s.fallbacks),
            ("pbs_nodes", s.pbs_nodes),
            ("pbs_depth", s.pbs_depth),
            ("predictions", s.predictions),
            ("pbs_fallbacks", s.pbs_fallbacks),
            ("time_budget_hits", s.time_budget_hits),
            ("shield_overrides", s.shield_overrides),
        ] {
            d.set_item(k, v)?;
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!("Controller(planner='{}')", self.inner.name())
    }
}

/// The planner names `Controller` and `run_episode` accept.
pub fn planners<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
    PyList::new(py, PLANNERS)
}
