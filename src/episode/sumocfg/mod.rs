//! An episode on a user's own SUMO scenario (`scenario.sumocfg`): SUMO loads the user's
//! configuration — net, routes, flows, vehicle types, additional files, their options — and
//! bkpbs adds only what it must ([`sumo_options`]). A seeded share α of the vehicles SUMO
//! inserts are CAVs, each decided when it departs on a random stream of its own (flows decide
//! their vehicles at run time, so the share is realised, not exact; `episode.csv` reports it).
//! Inside each merge region (all of the network's, or those `scenario.regions` selects) the
//! chosen planner drives the CAVs, one planner per region (or one [`Round`] over every region:
//! the stepped RL environment's); outside, SUMO drives every vehicle
//! on its type's own model, and the HDVs everywhere (no merge rule: the user's drivers are the
//! user's).
//!
//! Each vehicle is seen with its own type's length and width. A CAV whose route leaves the
//! region by an off-ramp, or that drives on a deceleration lane, is left to SUMO (the planners
//! keep CAVs on the carriageway and plan only its lanes and the merge lanes).
//!
//! Each CAV is planned below its own type's `maxSpeed`, the region's entry limit and the limit
//! of the lane it drives on, and within its type's `accel`, `decel` and `emergencyDecel` (the
//! search planners' primitives and IDM+MOBIL's accelerations; the `rl-ppo` policy's primitives
//! are its trained action space). Campaigns over scenarios run these episodes in worker
//! processes (`campaign`, over the grid's scenario axis).

mod entry_rows;
#[cfg(test)]
mod entry_tests;
mod fleet;
mod never_inserted;
mod options;
mod own_loop;
mod passage;
mod records;
mod region_books;
mod region_rows;
mod run;
#[cfg(test)]
mod tests;

use std::path::PathBuf;

use rand::{Rng, SeedableRng};

use crate::config::Config;
use crate::controller;
use crate::episode::error::EpisodeError;
use crate::episode::metrics::{CollisionEvent, Timing};
use crate::episode::region::Region;
use crate::episode::summary::{Summary, Traffic};
use crate::model::road::Road;
use crate::sumo::frame;
use crate::sumo::route_files::distributions;
use crate::sumo::sumocfg::{SumoConfig, SumoConfigError};
use crate::sumo::{Simulation, StderrCapture};

pub use crate::episode::round::Round;
pub use entry_rows::RegionEntryRow;
pub use fleet::Fleet;
pub use options::{has_cavs, sumo_options, SumoOptions};
pub use own_loop::OwnLoop;
pub use records::{csv_of, ScenarioVehicle};
pub use region_rows::{RegionKey, RegionRow};

/// What an episode on a user's scenario produced.
#[derive(Debug, Clone)]
pub struct ScenarioResult {
    /// The `episode.csv` row.
    pub summary: Summary,
    /// One row per vehicle SUMO inserted, in order of departure, then one per vehicle never
    /// inserted.
    pub vehicles: Vec<ScenarioVehicle>,
    /// One row per merge region (`regions.csv`), in the order of `summary.regions`.
    pub regions: Vec<RegionRow>,
    /// One row per merge region and entry (`entries.csv`): the regions in the order of
    /// `regions`, each one's main carriageway first, then its on-ramps along the road.
    pub entries: Vec<RegionEntryRow>,
    /// Every collision SUMO reported.
    pub collisions: Vec<CollisionEvent>,
    /// The options bkpbs gave SUMO beside the user's configuration.
    pub sumo_options: Vec<String>,
    /// One line per setting of the user's configuration bkpbs changed, saying why.
    pub sumo_notes: Vec<String>,
    /// What SUMO printed to stderr.
    pub sumo_log: String,
    /// Its wall-clock figures (`timing.csv`): planning per step is every region's together.
    pub timing: Timing,
    /// Vehicles in the regions' scenes per planning step, on average.
    pub vehicles_per_step: f64,
    /// CAVs the planners drove per planning step, on average.
    pub cavs_per_step: f64,
    /// Each region's trajectories in its own road frame (region name, file), when
    /// `output.trajectories` is `csv`.
    pub trajectories: Vec<(String, crate::episode::trajectories::TrajectoryFile)>,
    /// Each region's planners' trace (region name, `trace.jsonl` text), when `output.trace`
    /// asks (`bkpbs episode --trace`).
    pub traces: Vec<(String, String)>,
}

impl ScenarioResult {
    /// One `warning:` line per region no vehicle entered from an on-ramp (`regions.csv`'s
    /// `ramp_traffic` false), naming its ramps: its rows measure traffic past a merge nobody
    /// used, not merging.
    pub fn no_ramp_traffic_warnings(&self) -> Vec<String> {
        let ramp = crate::model::scene::Origin::Ramp.as_str();
        (self.regions.iter())
            .filter(|row| !row.ramp_traffic)
            .filter_map(|row| {
                let ramps: Vec<&str> = (self.entries.iter())
                    .filter(|e| e.key.region == row.key.region && e.origin == ramp)
                    .map(|e| e.entry.as_str())
                    .collect();
                // A region of lane drops alone has no on-ramp to receive anyone.
                if ramps.is_empty() {
                    return None;
                }
                let plural = if ramps.len() == 1 { "" } else { "s" };
                Some(format!(
                    "warning: region {} received no vehicle from its on-ramp{plural} ({}) in this \
                     episode ({} never inserted were bound for it): its rows measure traffic \
                     past a merge nobody used",
                    row.key.region,
                    ramps.join(", "),
                    row.never_inserted_ramp
                ))
            })
            .collect()
    }
}

/// The directory below an episode's where each region's trajectories go
/// (`trajectories/<region>/`, the region's edges joined by `+`), each with the episode's
/// `collisions.csv` beside them, so that `bkpbs plot` draws the region's time–space diagram.
pub const TRAJECTORIES_DIR: &str = "trajectories";

/// The region directories of an episode on a scenario of the user's own
/// (`<dir>/trajectories/<region>/`), in name order; none for any other directory.
pub fn region_dirs(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(dir.join(TRAJECTORIES_DIR))
        .map(|d| {
            d.flatten()
                .map(|e| e.path())
                .filter(|p| p.is_dir())
                .collect()
        })
        .unwrap_or_default();
    found.sort();
    found
}

/// A region's trajectory directory below an episode's `dir`.
pub fn region_dir(dir: &std::path::Path, region: &str) -> PathBuf {
    dir.join(TRAJECTORIES_DIR).join(region.replace(' ', "+"))
}

/// Whether vehicle `id` is a CAV: a draw of probability α on a stream seeded by the
/// episode's seed and the id alone, so the answer does not depend on who departed before.
pub fn is_cav(seed: u64, id: &str, alpha: f64) -> bool {
    // FNV-1a of the id, mixed with the seed: a stable, platform-independent stream key.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325 ^ seed.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    for b in id.bytes() {
        h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
    }
    rand_chacha::ChaCha8Rng::seed_from_u64(h).gen_bool(alpha.clamp(0.0, 1.0))
}

/// Whether vehicle `id` of SUMO type `sumo_type` is a CAV: one of `scenario.cav_types` when
/// it names any, else the draw of [`is_cav`].
pub fn becomes_cav(s: &crate::config::Scenario, id: &str, sumo_type: &str) -> bool {
    if s.cav_types.is_empty() {
        is_cav(s.seed, id, s.alpha)
    } else {
        s.cav_types.iter().any(|t| t == sumo_type)
    }
}

/// Each of `scenario.cav_types` must be a vehicle type SUMO loaded: a misspelt one would make
/// no CAV at all, and the episode would run as if nothing were wrong.
fn check_cav_types(
    sim: &impl crate::sumo::SumoClient,
    config: &Config,
    path: &std::path::Path,
) -> Result<(), EpisodeError> {
    let wanted = &config.scenario.cav_types;
    if wanted.is_empty() {
        return Ok(());
    }
    let loaded = sim.vehicle_type_ids().map_err(|cause| EpisodeError::Step {
        step: 0,
        time: 0.0,
        cause,
    })?;
    let distributions = SumoConfig::read(path).and_then(|c| distributions(&c))?;
    if let Some((t, d)) = wanted
        .iter()
        .find_map(|t| distributions.get(t).map(|d| (t, d)))
    {
        return Err(SumoConfigError::Content {
            path: path.to_path_buf(),
            what: format!(
                "cav_types names '{t}', a vTypeDistribution of {}: each of its vehicles gets \
                 the type drawn from it, so none would be a CAV; name its types instead ({})",
                d.file,
                d.members.join(", ")
            ),
        }
        .into());
    }
    match wanted.iter().find(|t| !loaded.contains(t)) {
        None => Ok(()),
        Some(t) => Err(SumoConfigError::Content {
            path: path.to_path_buf(),
            what: format!(
                "cav_types names vehicle type '{t}', which it does not load (its types: {})",
                loaded.join(", ")
            ),
        }
        .into()),
    }
}

/// Runs the scenario of `config.scenario.sumocfg` with `planner` driving the CAVs in each of
/// its merge regions (those `scenario.regions` selects).
///
/// # Errors
/// An unreadable configuration, a step length other than the planners', a network without a
/// region to plan, an unknown planner, or SUMO failing.
pub fn run(config: &Config, planner: &str) -> Result<ScenarioResult, EpisodeError> {
    run_observed(config, planner, &mut crate::episode::NoObserver)
}

/// Runs the scenario as [`run`] does, showing each merge region's scene of every step to
/// `observer` ([`Observer::observe_region`](crate::episode::Observer::observe_region)).
///
/// # Errors
/// As [`run`]'s.
pub fn run_observed(
    config: &Config,
    planner: &str,
    observer: &mut dyn crate::episode::Observer,
) -> Result<ScenarioResult, EpisodeError> {
    run_planned(config, planner, |roads| {
        let regions = regions(config, roads, planner)?;
        Ok(run::ScenarioRun::observed(
            config,
            regions,
            Box::new(observer),
        ))
    })
}

/// Runs the scenario of `config.scenario.sumocfg` with `round` planning every merge region
/// at once and `fleet` choosing the CAVs; `name` is the planner column of its rows.
///
/// # Errors
/// As [`run`]'s.
pub fn run_together(
    config: &Config,
    name: &str,
    round: Box<dyn Round>,
    fleet: Fleet,
) -> Result<ScenarioResult, EpisodeError> {
    run_planned(config, name, |roads| {
        let regions = roads
            .into_iter()
            .map(|road| Region::new(region_config(config, &road), road, None))
            .collect();
        Ok(run::ScenarioRun::planned_together(
            config, regions, round, fleet,
        ))
    })
}

/// The episode of `config`, its loop made by `make` from the regions' roads; `planner` names
/// it in the rows.
fn run_planned<'a>(
    config: &Config,
    planner: &str,
    make: impl FnOnce(Vec<Road>) -> Result<run::ScenarioRun<'a>, EpisodeError>,
) -> Result<ScenarioResult, EpisodeError> {
    config.validate()?;
    let (path, cfg) = checked(config)?;
    let roads = frame::scenario_roads(&config.scenario)?;
    let dir = scratch_dir()?;
    let options = sumo_options(config, &cfg, dir.path());
    let args = command_line(config, &path, &options.args);
    let wall = std::time::Instant::now();
    let capture = (!config.sumo.verbose).then(StderrCapture::start).flatten();
    let outcome = (|| {
        let sim = Simulation::start(&args, config.sumo.stall_limit()).map_err(|cause| {
            EpisodeError::Start {
                net: cfg.net.clone(),
                cause,
            }
        })?;
        check_cav_types(&sim, config, &path)?;
        let mut run = make(roads)?;
        run.run(sim, config)?;
        Ok::<_, EpisodeError>(run.finish(planner, &options))
    })();
    let sumo_log = capture.map(StderrCapture::finish).unwrap_or_default();
    let mut result = outcome
        .map_err(|e| e.with_sumo_log(sumo_log.clone()))?
        .map_err(EpisodeError::Output)?;
    result.sumo_log = sumo_log;
    result.timing.wall_s = wall.elapsed().as_secs_f64();
    Ok(result)
}

/// One region per road of `roads`, each with its own `planner`.
fn regions(
    config: &Config,
    roads: Vec<Road>,
    planner: &str,
) -> Result<Vec<Region<'static>>, EpisodeError> {
    roads
        .into_iter()
        .map(|road| {
            let c = region_config(config, &road);
            let controller = controller::by_name(planner, &c, &road)?;
            Ok(Region::new(c, road, Some(controller)))
        })
        .collect()
}

/// The configuration of `road`'s region: the episode's, CAVs driving no faster than the
/// carriageway allows where they enter it.
fn region_config(config: &Config, road: &Road) -> Config {
    let mut c = config.clone();
    c.scenario.v_max = c.scenario.v_max.min(road.entries[0].speed_limit);
    c
}

/// The path of the episode's SUMO configuration and the configuration, read and checked to run
/// at the planners' step.
fn checked(config: &Config) -> Result<(PathBuf, SumoConfig), EpisodeError> {
    let path = config
        .scenario
        .sumocfg
        .clone()
        .expect("a scenario episode has a configuration");
    let cfg = SumoConfig::read(&path)?;
    cfg.check_step(config.scenario.dt)?;
    crate::sumo::route_files::check_demand(&cfg)?;
    Ok((path, cfg))
}

/// SUMO's command line: the user's configuration at `path`, then bkpbs's `options`, then
/// sumo-gui's when `sumo.gui` shows the episode there.
fn command_line(config: &Config, path: &std::path::Path, options: &[String]) -> Vec<String> {
    let program = crate::sumo::files::program(config.sumo.gui);
    let mut args = vec![program, "-c".into(), path.display().to_string()];
    args.extend(options.iter().cloned());
    args.extend(crate::sumo::files::gui_options(config));
    args
}

/// The scratch directories of scenario episodes in the temporary directory are
/// `bkpbs-scenario-<pid>-<random>`: the process id tells those of an episode that died (swept
/// by the next one) from those of one running now.
pub const SCRATCH_PREFIX: &str = "bkpbs-scenario-";

/// A directory of the episode's own for SUMO's tripinfo output, removed with it.
fn scratch_dir() -> Result<tempfile::TempDir, EpisodeError> {
    // Those of episodes killed, stalled or aborted before they could remove their own.
    crate::io::sweep_stale(&std::env::temp_dir(), SCRATCH_PREFIX);
    tempfile::Builder::new()
        .prefix(&format!("{SCRATCH_PREFIX}{}-", std::process::id()))
        .tempdir()
        .map_err(|cause| {
            crate::sumo::files::InputError::Write {
                path: std::env::temp_dir(),
                cause,
            }
            .into()
        })
}

/// SUMO stepping the user's scenario with bkpbs's options and nobody reading or commanding:
/// the floor `bkpbs bench --sumocfg` compares the planners with (ms per step).
///
/// # Errors
/// As [`run`]'s before the first step, or SUMO failing.
pub fn sumo_alone_ms_per_step(config: &Config) -> Result<f64, EpisodeError> {
    let (path, cfg) = checked(config)?;
    let dir = scratch_dir()?;
    let options = sumo_options(config, &cfg, dir.path()).args;
    let capture = (!config.sumo.verbose).then(StderrCapture::start).flatten();
    let timed = (|| {
        let mut sim = Simulation::start(
            &command_line(config, &path, &options),
            config.sumo.stall_limit(),
        )
        .map_err(|cause| EpisodeError::Start {
            net: cfg.net.clone(),
            cause,
        })?;
        let start = std::time::Instant::now();
        let steps = config.scenario.steps;
        for step in 0..steps {
            sim.step().map_err(|cause| EpisodeError::Step {
                step,
                time: step as f64 * config.scenario.dt,
                cause,
            })?;
        }
        let ms = start.elapsed().as_secs_f64() * 1e3 / f64::from(steps.max(1));
        let _ = sim.close();
        Ok(ms)
    })();
    let log = capture.map(StderrCapture::finish).unwrap_or_default();
    timed.map_err(|e: EpisodeError| e.with_sumo_log(log))
}

/// Writes the episode's files into `dir` as one set, `episode.csv` last.
pub fn write(
    result: &ScenarioResult,
    dir: &std::path::Path,
) -> Result<Vec<PathBuf>, crate::io::WriteError> {
    let episode = Summary::csv(Traffic::Scenario, std::slice::from_ref(&result.summary));
    let vehicles = records::vehicles_csv(&result.vehicles);
    let regions = csv_of(&result.regions);
    let entries = csv_of(&result.entries);
    let collisions = crate::episode::output::collisions_csv(&result.collisions);
    let timing = crate::episode::output::timing_csv(&result.timing);
    write_trajectories(result, dir, &collisions)?;
    let options = result.sumo_options.join(" ") + "\n";
    let log = (!result.sumo_log.is_empty()).then_some(result.sumo_log.as_bytes());
    crate::io::replace_together(
        dir,
        &[
            ("sumo.log", log),
            ("sumo_options.txt", Some(options.as_bytes())),
            ("vehicles.csv", Some(&vehicles[..])),
            ("regions.csv", Some(&regions[..])),
            ("entries.csv", Some(&entries[..])),
            ("collisions.csv", Some(&collisions[..])),
            ("timing.csv", Some(&timing[..])),
            ("episode.csv", Some(&episode[..])),
        ],
    )
}

/// Replaces the episode's region trajectories in `dir` with `result`'s (none: removed, so that
/// a directory never holds an earlier run's).
fn write_trajectories(
    result: &ScenarioResult,
    dir: &std::path::Path,
    collisions: &[u8],
) -> Result<(), crate::io::WriteError> {
    let root = dir.join(TRAJECTORIES_DIR);
    match std::fs::remove_dir_all(&root) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(cause) => return Err(crate::io::WriteError { path: root, cause }),
    }
    for (region, file) in &result.trajectories {
        let d = region_dir(dir, region);
        crate::io::write_atomic(&d.join(file.name), &file.bytes)?;
        crate::io::write_atomic(&d.join("collisions.csv"), collisions)?;
    }
    for (region, text) in &result.traces {
        let d = region_dir(dir, region);
        crate::io::write_atomic(&d.join(crate::episode::trace::TRACE_FILE), text.as_bytes())?;
        crate::io::write_atomic(&d.join("collisions.csv"), collisions)?;
    }
    Ok(())
}
