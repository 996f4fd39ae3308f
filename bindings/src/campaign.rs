//! Campaigns for other schedulers (Ray, `python -m bkpbs.campaign`): `Campaign` lists the grid
//! and its unfinished episodes and collects the directory; a `CampaignTask` runs one episode in
//! the calling process. All of it is the core's `campaign::tasks` (the paper's demand and
//! scenarios of the user's own alike), so the directory is the one `bkpbs campaign` writes and
//! `bkpbs report` reads.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyString, PyTuple};

use bkpbs::campaign::collect::cell_dir;
use bkpbs::campaign::portable;
use bkpbs::campaign::worker::{self, Outcome, Request};
use bkpbs::campaign::{tasks, CampaignError, CampaignSpec, Overrides, Settings, SettingsError};
use bkpbs::report::{self as core_report, ReportError};

use crate::errors::bad_input;
use crate::run_slot::Slot;

fn campaign_error(e: CampaignError) -> PyErr {
    match e {
        CampaignError::Write(_) => pyo3::exceptions::PyOSError::new_err(e.to_string()),
        _ => bad_input(e),
    }
}

fn settings_error(e: SettingsError) -> PyErr {
    bad_input(e)
}

/// A grid axis given as a list (or a comma-separated string), as the flag's text; entries are
/// strings, numbers or paths.
fn axis(v: Option<&Bound<'_, PyAny>>) -> PyResult<Option<String>> {
    let Some(v) = v.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(Some(s.to_cow()?.to_string()));
    }
    let mut parts = Vec::new();
    for item in v.try_iter()? {
        let item = item?;
        if let Ok(s) = item.cast::<PyString>() {
            parts.push(s.to_cow()?.to_string());
        } else if let Ok(x) = item.extract::<f64>() {
            parts.push(format!("{x}"));
        } else if let Ok(path) = item.extract::<PathBuf>() {
            // A scenario given as a `pathlib.Path` (or any `os.PathLike`).
            parts.push(path.display().to_string());
        } else {
            return Err(bad_input(format!(
                "grid values must be strings, numbers or paths, got {}",
                item.repr()?
            )));
        }
    }
    Ok(Some(parts.join(",")))
}

/// A planners × α × λ × seeds campaign in directory `out`, or planners × scenarios × α ×
/// seeds with `sumocfg`.
#[pyclass(name = "Campaign", module = "bkpbs", frozen)]
pub struct PyCampaign {
    settings: Box<Settings>,
    out: PathBuf,
}

#[pymethods]
impl PyCampaign {
    /// The settings of `bkpbs campaign`: `config` is a campaign TOML file, the keywords its
    /// flags (lists or comma-separated strings; `shard` is `"k/n"`). Everything is checked now.
    #[new]
    #[pyo3(signature = (out, *, config = None, planners = None, alphas = None, lambdas = None, seeds = None, seed_base = None, steps = None, shard = None, sumocfg = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        out: PathBuf,
        config: Option<PathBuf>,
        planners: Option<&Bound<'_, PyAny>>,
        alphas: Option<&Bound<'_, PyAny>>,
        lambdas: Option<&Bound<'_, PyAny>>,
        seeds: Option<u64>,
        seed_base: Option<u64>,
        steps: Option<u32>,
        shard: Option<String>,
        sumocfg: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let overrides = Overrides {
            planners: axis(planners)?,
            alphas: axis(alphas)?,
            lambdas: axis(lambdas)?,
            seeds,
            seed_base,
            steps,
            workers: None,
            // Ray schedules the tasks; a wall-clock limit is its business (`ray.get(timeout=…)`).
            episode_timeout: None,
            // From the config file's `[output]` table, if any.
            trajectories: None,
            // Like the HDV profiles, from the config file's `[campaign]` table, if any.
            hdv_profiles: None,
            predictors: None,
            shard,
            sumocfg: axis(sumocfg)?,
        };
        let settings =
            Box::new(Settings::resolve(config.as_deref(), &overrides).map_err(settings_error)?);
        Ok(PyCampaign { settings, out })
    }

    /// The campaign directory.
    #[getter]
    fn out(&self) -> PathBuf {
        self.out.clone()
    }

    /// Episodes in the whole grid.
    #[getter]
    fn grid_size(&self) -> usize {
        self.settings.grid.len()
    }

    /// This run's shard, `"k/n"`.
    #[getter]
    fn shard(&self) -> String {
        self.settings.shard.to_string()
    }

    /// The settings as `campaign.toml` holds them.
    fn settings_toml(&self) -> String {
        self.settings.to_toml()
    }

    /// Every cell of the grid in grid order, each with its directory: planner, α, λ, seed
    /// (planner, then α, λ, seed ascending); over scenarios planner, scenario (its file), α,
    /// seed.
    fn cells<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        let cells = self.settings.grid.cells();
        for (position, c) in cells.iter().enumerate() {
            let d = PyDict::new(py);
            d.set_item("position", position)?;
            d.set_item("planner", &c.planner)?;
            if let Some(scenario) = &c.scenario {
                d.set_item("scenario", scenario)?;
            }
            d.set_item("alpha", c.alpha)?;
            if c.scenario.is_none() {
                d.set_item("lambda", c.lambda)?;
            }
            d.set_item("seed", c.seed)?;
            d.set_item("dir", cell_dir(&self.out, c))?;
            out.append(d)?;
        }
        Ok(out)
    }

    /// Readies the directory (checks an earlier run's settings, writes `campaign.toml`) and
    /// returns the unfinished episodes of this shard as tasks, in grid order.
    fn prepare(&self) -> PyResult<Vec<PyCampaignTask>> {
        let requests = tasks::prepare(self.settings.as_ref(), &self.out)
            .map(|p| p.requests)
            .map_err(campaign_error)?;
        Ok(requests
            .into_iter()
            .map(|request| PyCampaignTask { request })
            .collect())
    }

    /// Gathers every finished episode into the collected files (grid order: `episodes.csv`,
    /// `vehicles.csv`, `timings.csv`, `failures.csv`, and over scenarios `regions.csv` and
    /// `entries.csv`) and says how many there are.
    fn collect<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let collected =
            CampaignSpec::collect(self.settings.as_ref(), &self.out).map_err(campaign_error)?;
        let (collected, failed) = (collected.episodes, collected.failures);
        let d = PyDict::new(py);
        d.set_item("grid", self.settings.grid.len())?;
        d.set_item("collected", collected)?;
        d.set_item("failed", failed)?;
        d.set_item("episodes_csv", self.out.join("episodes.csv"))?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "Campaign(out='{}', episodes={}, shard='{}')",
            self.out.display(),
            self.settings.grid.len(),
            self.settings.shard
        )
    }
}

/// A file of an episode as Python sees it: its path in the cell directory and its bytes.
type PyFile<'py> = (String, Bound<'py, PyBytes>);

/// One unfinished episode of a campaign; picklable, so it can travel to another process.
#[pyclass(name = "CampaignTask", module = "bkpbs", frozen)]
pub struct PyCampaignTask {
    request: Request,
}

#[pymethods]
impl PyCampaignTask {
    /// The task from its `to_json()` text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        let request = serde_json::from_str(text)
            .map_err(|e| bad_input(format!("malformed campaign task: {e}")))?;
        Ok(PyCampaignTask { request })
    }

    /// The task as JSON (the request a `bkpbs worker` reads).
    fn to_json(&self) -> String {
        serde_json::to_string(&self.request).expect("request serialises")
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let ctor = py.get_type::<PyCampaignTask>().getattr("from_json")?;
        PyTuple::new(py, [ctor, PyTuple::new(py, [self.to_json()])?.into_any()])
    }

    /// The cell's position in grid order.
    #[getter]
    fn position(&self) -> usize {
        self.request.position
    }

    #[getter]
    fn planner(&self) -> &str {
        &self.request.planner
    }

    #[getter]
    fn alpha(&self) -> f64 {
        self.request.config.scenario.alpha
    }

    /// The arrival rate λ (veh/h).
    #[getter]
    fn lam(&self) -> f64 {
        self.request.config.scenario.lambda
    }

    #[getter]
    fn seed(&self) -> u64 {
        self.request.config.scenario.seed
    }

    /// The scenario of the user's own the episode runs (its `.sumocfg`), or `None` on the
    /// paper's demand.
    #[getter]
    fn scenario(&self) -> Option<PathBuf> {
        self.request.config.scenario.sumocfg.clone()
    }

    /// The cell directory the episode's files go to.
    #[getter]
    fn dir(&self) -> PathBuf {
        self.request.dir.clone()
    }

    /// Runs the episode in this process (GIL released) as a campaign worker does: its files
    /// in the cell directory, or `error.txt`. Returns `None` when done, else the error message.
    fn run(&self, py: Python<'_>) -> PyResult<Option<String>> {
        let _slot = Slot::claim()?;
        Ok(match py.detach(|| tasks::run_request(&self.request)) {
            Outcome::Done => None,
            Outcome::Failed { error } => Some(error),
        })
    }

    /// The files the episode reads, as absolute paths (relative ones resolved against `base`,
    /// default the working directory): its scenario's `.sumocfg` and the files that names, the
    /// model, calibration and policy files. A scheduler ships them to `run_portable`.
    #[pyo3(signature = (base = None))]
    fn inputs(&self, base: Option<PathBuf>) -> PyResult<Vec<PathBuf>> {
        let base = match base {
            Some(b) => b,
            None => std::env::current_dir()?,
        };
        Ok(portable::inputs(&self.request.config, &base))
    }

    /// Runs the episode in this process (GIL released) on a machine that need not see the
    /// campaign's files: `inputs` are `(path, bytes)` of the files `inputs(base)` listed where
    /// the campaign runs (working directory `base`), written below `scratch`, a private
    /// directory the caller removes. Returns `(None, files)`, the cell's files as
    /// `(relative path, bytes)` for `store`, or `(error, [])`.
    fn run_portable<'py>(
        &self,
        py: Python<'py>,
        scratch: PathBuf,
        base: PathBuf,
        inputs: Vec<(PathBuf, Bound<'py, PyBytes>)>,
    ) -> PyResult<(Option<String>, Vec<PyFile<'py>>)> {
        let _slot = Slot::claim()?;
        let inputs: Vec<portable::File> = inputs
            .into_iter()
            .map(|(p, b)| (p, b.as_bytes().to_vec()))
            .collect();
        let ran = py.detach(|| portable::run(&self.request, &base, &inputs, &scratch));
        Ok(match ran {
            Ok(files) => {
                let files = files
                    .into_iter()
                    .map(|(p, b)| (p.display().to_string(), PyBytes::new(py, &b)))
                    .collect();
                (None, files)
            }
            Err(error) => (Some(error), Vec::new()),
        })
    }

    /// Puts the episode's files, as `run_portable` returned them, into the cell directory:
    /// they replace its earlier files, `episode.csv` last, as a local run writes them.
    fn store(&self, py: Python<'_>, files: Vec<(PathBuf, Bound<'_, PyBytes>)>) -> PyResult<()> {
        let files: Vec<portable::File> = files
            .into_iter()
            .map(|(p, b)| (p, b.as_bytes().to_vec()))
            .collect();
        py.detach(|| portable::store(&self.request.dir, &files))
            .map_err(|e| match e {
                portable::PortableError::Name { .. } => bad_input(e),
                _ => pyo3::exceptions::PyOSError::new_err(e.to_string()),
            })
    }

    /// Records that the episode failed outside this process (e.g. its worker died): writes
    /// `error.txt` in the cell directory.
    fn record_failure(&self, message: &str) {
        worker::record_failure(&self.request.dir, message);
    }

    fn __repr__(&self) -> String {
        let s = &self.request.config.scenario;
        match &s.sumocfg {
            Some(cfg) => format!(
                "CampaignTask({} {} α={} seed={})",
                self.request.planner,
                cfg.display(),
                s.alpha,
                s.seed
            ),
            None => format!(
                "CampaignTask({} α={} λ={} seed={})",
                self.request.planner, s.alpha, s.lambda, s.seed
            ),
        }
    }
}

/// Tables and figures of one or more campaign directories (several are merged), as
/// `bkpbs report`; returns the Markdown tables. `out` defaults to the first directory.
#[pyfunction]
#[pyo3(signature = (dirs, out = None))]
pub fn report(dirs: Vec<PathBuf>, out: Option<PathBuf>) -> PyResult<String> {
    let r = core_report::run(&dirs, out.as_deref(), false).map_err(|e| match e {
        ReportError::Write(_) => pyo3::exceptions::PyOSError::new_err(e.to_string()),
        _ => bad_input(e),
    })?;
    Ok(r.markdown)
}
