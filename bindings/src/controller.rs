//! `bkpbs.Controller`: one planning step of any core planner for vehicles read by the caller's
//! own TraCI or libsumo loop, and `bkpbs.Maneuver`, what one CAV does next.

use std::collections::HashMap;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use bkpbs::config::Config;
use bkpbs::controller::{self, CavHandling, Command, Controller, LaneChange, PLANNERS};
use bkpbs::episode::sumocfg::OwnLoop;
use bkpbs::model::road::Road;
use bkpbs::model::scene::{Kind, Origin};
use bkpbs::sumo::frame;

use crate::errors::{bad_input, episode_error};
use crate::own_loop;
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
///
/// With `sumocfg=` it is a whole episode on the user's own SUMO scenario instead, stepped by the
/// caller's loop: see `start`, `step` and `finish`.
#[pyclass(name = "Controller", module = "bkpbs", unsendable)]
pub struct PyController {
    mode: Mode,
    config: Config,
}

/// What a controller plans for.
enum Mode {
    /// One merge road, for the vehicles each `plan` call is given.
    Road(Box<RoadPlanner>),
    /// Every merge region of a user's scenario, through the caller's TraCI module (`None`
    /// once finished).
    Scenario(Option<Box<OwnLoop>>, &'static str),
}

/// A core planner on one merge road.
struct RoadPlanner {
    inner: Box<dyn Controller>,
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
    /// With `sumocfg`, a SUMO configuration of the user's own, the controller is an episode on
    /// it, one planner per merge region (`alpha=`, `seed=`, `cav_types=`, `steps=` as for
    /// `run_episode`).
    #[new]
    #[pyo3(signature = (planner = "bk-pbs", config = None, model = None, net_file = None, sumocfg = None, **overrides))]
    fn new(
        planner: &str,
        config: Option<&Bound<'_, PyAny>>,
        model: Option<std::path::PathBuf>,
        net_file: Option<std::path::PathBuf>,
        sumocfg: Option<std::path::PathBuf>,
        overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let Some(name) = PLANNERS.iter().copied().find(|p| *p == planner) else {
            return Err(bad_input(controller::UnknownPlanner(planner.to_string())));
        };
        if let Some(path) = sumocfg {
            if net_file.is_some() {
                return Err(bad_input(
                    "net_file was given with sumocfg: the scenario names its own network",
                ));
            }
            let mut config = crate::scenario::resolve(&path, config, overrides)?;
            if let Some(model) = model {
                crate::predict::use_model(&mut config, &model)?;
            }
            let episode = OwnLoop::new(&config, name).map_err(|e| episode_error(&e))?;
            return Ok(PyController {
                mode: Mode::Scenario(Some(Box::new(episode)), name),
                config,
            });
        }
        let mut config = crate::config::resolve(config, overrides, toml::Table::new())?;
        if let Some(path) = model {
            crate::predict::use_model(&mut config, &path)?;
        }
        let road = road_of(&mut config, net_file)?;
        Ok(PyController {
            mode: Mode::Road(Box::new(RoadPlanner {
                inner: build(planner, &config, &road)?,
                road,
                origins: HashMap::new(),
                calls: 0,
                commands: Vec::new(),
            })),
            config,
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
        let Mode::Road(r) = &mut self.mode else {
            return Err(bad_input(
                "a Controller on a scenario of your own (sumocfg=) is stepped with \
                 step(traci), not plan(vehicles)",
            ));
        };
        r.plan(py, vehicles, time, &self.config.scenario)
    }

    /// The command line to start SUMO with (`sumocfg=` only): the scenario's configuration and
    /// the options bkpbs needs (collisions reported, no teleports, the seed, its tripinfo
    /// output).
    #[getter]
    fn sumo_command(&self) -> PyResult<Vec<String>> {
        Ok(own_loop::episode(self.mode_scenario()?)?.sumo_command())
    }

    /// The episode's length in steps (`sumocfg=` only): the scenario's interval, or `steps=`.
    #[getter]
    fn steps(&self) -> PyResult<u32> {
        Ok(own_loop::episode(self.mode_scenario()?)?.steps())
    }

    /// Once SUMO runs (`sumocfg=` only), before its first step: `traci` is the module of the
    /// caller's loop (`traci`, `libsumo` or a traci connection).
    fn start(&mut self, traci: &Bound<'_, PyAny>) -> PyResult<()> {
        own_loop::start(self.mode_scenario_mut()?, traci)
    }

    /// After each `simulationStep` (`sumocfg=` only): the step booked, every region planned
    /// and its CAVs commanded through `traci` (not after the episode's last step).
    fn step(&mut self, traci: &Bound<'_, PyAny>) -> PyResult<()> {
        own_loop::step(self.mode_scenario_mut()?, traci)
    }

    /// After SUMO is closed (`sumocfg=` only): the episode's `episode.csv` row as a dict, its
    /// files written into `out` when given (those of `bkpbs episode --sumocfg`).
    #[pyo3(signature = (out = None))]
    fn finish<'py>(
        &mut self,
        py: Python<'py>,
        out: Option<std::path::PathBuf>,
    ) -> PyResult<Bound<'py, PyDict>> {
        own_loop::finish(py, self.mode_scenario_mut()?, out)
    }

    /// The planner's name.
    #[getter]
    fn planner(&self) -> &'static str {
        match &self.mode {
            Mode::Road(r) => r.inner.name(),
            Mode::Scenario(_, name) => name,
        }
    }

    /// Whether the caller must command the CAVs (`False` for `"sumo"`, which leaves them to
    /// SUMO's own models and returns no maneuvers).
    #[getter]
    fn commands_cavs(&self) -> bool {
        match &self.mode {
            Mode::Road(r) => r.inner.handling() == CavHandling::Commanded,
            Mode::Scenario(_, name) => *name != "sumo",
        }
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
        let Mode::Road(r) = &self.mode else {
            return Err(bad_input(
                "last_stats is one planner's: a scenario's Controller has one per region",
            ));
        };
        stats_dict(py, r.inner.last_stats())
    }

    fn __repr__(&self) -> String {
        format!("Controller(planner='{}')", self.planner())
    }
}

impl PyController {
    fn mode_scenario(&self) -> PyResult<&Option<Box<OwnLoop>>> {
        match &self.mode {
            Mode::Scenario(e, _) => Ok(e),
            Mode::Road(_) => Err(own_loop::not_a_scenario()),
        }
    }

    fn mode_scenario_mut(&mut self) -> PyResult<&mut Option<Box<OwnLoop>>> {
        match &mut self.mode {
            Mode::Scenario(e, _) => Ok(e),
            Mode::Road(_) => Err(own_loop::not_a_scenario()),
        }
    }
}

impl RoadPlanner {
    /// One planning step of `vehicles` (see `Controller.plan`).
    fn plan<'py>(
        &mut self,
        py: Python<'py>,
        vehicles: &Bound<'py, PyAny>,
        time: Option<f64>,
        sc: &bkpbs::config::Scenario,
    ) -> PyResult<Bound<'py, PyDict>> {
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
}

/// The search effort of one planning round as a dict.
fn stats_dict(py: Python<'_>, s: bkpbs::controller::PlanStats) -> PyResult<Bound<'_, PyDict>> {
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

/// The planner names `Controller` and `run_episode` accept.
pub fn planners<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
    PyList::new(py, PLANNERS)
}
