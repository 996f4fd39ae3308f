//! `bkpbs._bkpbs.MergeEnvCore`: the core's stepped merge environment
//! (`bkpbs::train::ppo::env`), under `bkpbs.gym`'s Gymnasium and PettingZoo classes. Arrays
//! cross as bytes (float32 observations, uint8 masks, RGB frames) for numpy to wrap without a
//! per-vehicle Python loop.

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use bkpbs::config::Config;
use bkpbs::planner::primitives::Primitive;
use bkpbs::policy::observation::{feature_names, OBS_DIM};
use bkpbs::train::ppo::env::{Agents, EnvError, MergeEnv};
use bkpbs::train::ppo::reward::RewardSettings;

use crate::errors::{bad_input, episode_error};
use crate::run_slot::Slot;

/// The merge scenario stepped one decision at a time.
#[pyclass(name = "MergeEnvCore", module = "bkpbs", unsendable)]
pub struct PyMergeEnv {
    env: Option<MergeEnv>,
    slot: Option<Slot>,
    config: Config,
    agents: Agents,
}

fn env_error(e: EnvError) -> PyErr {
    match e {
        EnvError::Episode(e) => episode_error(&e),
        other => bad_input(other),
    }
}

impl PyMergeEnv {
    fn running(&self) -> PyResult<&MergeEnv> {
        self.env
            .as_ref()
            .ok_or_else(|| bad_input("the environment has not been reset"))
    }
}

#[pymethods]
impl PyMergeEnv {
    /// `agents`: "single" (one CAV among HDVs, the paper's training set-up) or "all" (every
    /// CAV). α, λ (veh/h; 3000 unless given), `config` and keyword overrides as for
    /// `run_episode`; with `sumocfg` the episode is the user's own scenario (no `lam`), its
    /// interval the episode's length unless `steps=` shortens it.
    #[new]
    #[pyo3(signature = (agents = "single", alpha = 0.5, lam = None, config = None, sumocfg = None, **overrides))]
    fn new(
        agents: &str,
        alpha: f64,
        lam: Option<f64>,
        config: Option<&Bound<'_, PyAny>>,
        sumocfg: Option<std::path::PathBuf>,
        overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let agents = match agents {
            "single" => Agents::Single,
            "all" => Agents::AllCavs,
            other => {
                return Err(bad_input(format!(
                    "agents '{other}': use 'single' or 'all'"
                )))
            }
        };
        let config = match sumocfg {
            Some(path) => {
                if let Some(lam) = lam {
                    return Err(crate::scenario::lam_with_sumocfg(lam));
                }
                let cell = crate::run_slot::cell_table(alpha, None, 0)?;
                crate::scenario::resolve_with(&path, config, overrides, cell)?
            }
            None => {
                let cell = crate::run_slot::cell_table(alpha, Some(lam.unwrap_or(3000.0)), 0)?;
                crate::config::resolve(config, overrides, cell)?
            }
        };
        Ok(PyMergeEnv {
            env: None,
            slot: None,
            config,
            agents,
        })
    }

    /// Starts a new episode with demand seed `seed` (ending the running one) and runs it to the
    /// first step with an agent.
    fn reset(&mut self, py: Python<'_>, seed: u64) -> PyResult<()> {
        self.close();
        self.env = None;
        self.slot = Some(Slot::claim()?);
        let mut config = self.config.clone();
        config.scenario.seed = seed;
        let agents = self.agents;
        let started = py.detach(|| MergeEnv::start(&config, agents, RewardSettings::default()));
        match started {
            Ok(env) => {
                self.env = Some(env);
                Ok(())
            }
            Err(e) => {
                self.slot = None;
                Err(env_error(e))
            }
        }
    }

    /// The agents of the current step, in the order `step` takes their actions.
    fn agents(&self) -> PyResult<Vec<String>> {
        Ok(self
            .running()?
            .agents()
            .iter()
            .map(|a| a.id.to_string())
            .collect())
    }

    /// Every vehicle that may become an agent in this episode.
    fn possible_agents(&self) -> PyResult<Vec<String>> {
        Ok(self
            .running()?
            .possible_agents()
            .iter()
            .map(|a| a.to_string())
            .collect())
    }

    /// The agents' observations: float32, agents × OBS_DIM, row-major.
    fn observations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes: Vec<u8> = self
            .running()?
            .agents()
            .iter()
            .flat_map(|a| a.obs.iter().flat_map(|x| x.to_le_bytes()))
            .collect();
        Ok(PyBytes::new(py, &bytes))
    }

    /// The agents' action masks: uint8, agents × 6 (1 = allowed).
    fn masks<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes: Vec<u8> = self
            .running()?
            .agents()
            .iter()
            .flat_map(|a| a.mask.iter().map(|&m| u8::from(m)))
            .collect();
        Ok(PyBytes::new(py, &bytes))
    }

    /// One primitive per agent; returns (rewards as (agent, reward) pairs, terminated agents,
    /// truncated agents, done).
    #[allow(clippy::type_complexity)]
    fn step(
        &mut self,
        py: Python<'_>,
        actions: Vec<usize>,
    ) -> PyResult<(Vec<(String, f64)>, Vec<String>, Vec<String>, bool)> {
        let env = self
            .env
            .as_mut()
            .ok_or_else(|| bad_input("the environment has not been reset"))?;
        let r = py.detach(|| env.step(&actions)).map_err(env_error)?;
        let names = |v: Vec<std::sync::Arc<str>>| v.into_iter().map(|a| a.to_string()).collect();
        let rewards = r
            .rewards
            .into_iter()
            .map(|(a, x)| (a.to_string(), x))
            .collect();
        Ok((rewards, names(r.terminated), names(r.truncated), r.done))
    }

    /// The current step as an RGB frame (height × width × 3 bytes), the agents in red.
    #[pyo3(signature = (width = 600, height = 150))]
    fn render_rgb<'py>(
        &self,
        py: Python<'py>,
        width: usize,
        height: usize,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let env = self.running()?;
        let ids: Vec<&str> = env.agents().iter().map(|a| &*a.id).collect();
        let bytes = match env.scene() {
            Some(scene) => bkpbs::report::raster::section_rgb(scene, &ids, width, height),
            None => vec![0; width * height * 3],
        };
        Ok(PyBytes::new(py, &bytes))
    }

    /// The finished episode's summary (the values of `episode.csv`, at full precision), once done.
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let ran = self.env.as_ref().and_then(|e| e.result());
        ran.map(|r| crate::episode::summary_dict(py, r.summary()))
            .transpose()
    }

    /// Ends the running episode (its agents idle to the end) and frees the simulation; the
    /// episode's `summary` stays readable until the next `reset`.
    fn close(&mut self) {
        if let Some(env) = &mut self.env {
            env.close();
        }
        self.slot = None;
    }

    /// Length of an observation.
    #[classattr]
    const OBS_DIM: usize = OBS_DIM;

    /// Names of the observation's entries.
    #[staticmethod]
    fn feature_names() -> Vec<String> {
        feature_names()
    }

    /// Names of the actions (motion primitives), in action order.
    #[staticmethod]
    fn action_names() -> Vec<&'static str> {
        Primitive::ALL.iter().map(|p| p.name()).collect()
    }
}
