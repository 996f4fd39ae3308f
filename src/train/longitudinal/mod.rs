//! Longitudinal calibration (`bkpbs calibrate`): how well the planner's HDV model predicts the
//! HDVs SUMO drives under a driver profile, or on a user's scenario (`scenario.sumocfg`: its
//! routes the demand, its vehicle types the drivers). Follow samples come from SUMO episodes
//! ([`samples`], each merge region's apart), an IDM is fitted to them by nonlinear least
//! squares ([`fit`]), and on held-out episodes its open-loop predictions ([`model`]) are
//! compared with constant speed, the planner's present assumption; on the paper's demand,
//! per-vehicle fits say how well heterogeneous drivers' drawn parameters are recovered.

pub mod fit;
pub mod model;
pub mod samples;

use std::collections::{BTreeMap, HashMap};

use serde::{Deserialize, Serialize};

use crate::config::{Config, TrainingScenario};
use crate::episode::{self, Driver, EpisodeError, PerRegion};
use crate::sumo::files::driver_type_draws;
use crate::sumo::scenario_record::scenario_record;
use fit::fit_idm;
use model::{predict_constant_speed, predict_idm, rmse, FollowSample, IdmParams};
use samples::FollowRecorder;

/// Format tag and version of `calibration.json`.
pub const FORMAT: &str = "bkpbs-calibration";
/// Version of the `calibration.json` layout this build writes.
pub const VERSION: u32 = 1;
/// Most samples the global fit uses (evenly thinned beyond): enough for five parameters.
pub const MAX_FIT_SAMPLES: usize = 4000;
/// Fewest samples of one vehicle for a per-vehicle fit.
pub const MIN_VEHICLE_SAMPLES: usize = 10;
/// Why a calibration on a user's scenario recovers no drawn parameters.
pub const RECOVERY_NOT_APPLICABLE: &str = "not applicable on a scenario of your own: its \
    vehicle types are its drivers, and per-vehicle recovery compares fits with a driver \
    profile's drawn parameters";

/// What to calibrate on: the episodes (the profile's, or the user's scenario's) of seeds
/// `seed_base ..` for fitting, the next `held_out` seeds for evaluation.
#[derive(Debug, Clone)]
pub struct CalibrateSpec {
    /// Episodes to fit on (seeds `seed_base ..`).
    pub episodes: u64,
    /// Held-out episodes to evaluate on (the seeds after the fitting ones).
    pub held_out: u64,
    /// Seed of the first episode.
    pub seed_base: u64,
}

/// Prediction errors on held-out samples: speed after 1 s and 3 s (m/s), gap after 3 s (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Errors {
    /// Root mean square error of the speed after 1 s (m/s).
    pub rmse_speed_1s: f64,
    /// Root mean square error of the speed after 3 s (m/s).
    pub rmse_speed_3s: f64,
    /// Root mean square error of the gap after 3 s (m; samples with a leader only).
    pub rmse_gap_3s: f64,
}

impl From<[f64; 3]> for Errors {
    fn from(e: [f64; 3]) -> Self {
        Errors {
            rmse_speed_1s: e[0],
            rmse_speed_3s: e[1],
            rmse_gap_3s: e[2],
        }
    }
}

/// How well per-vehicle fits recover one drawn parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Recovery {
    /// SUMO's attribute name (`tau`, `minGap`, `accel`, `decel`).
    pub parameter: String,
    /// Vehicles compared.
    pub vehicles: usize,
    /// Median |fitted − drawn| / drawn.
    pub median_relative_error: f64,
}

/// The result of a calibration, as written to `calibration.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Always [`FORMAT`].
    pub format: String,
    /// Always [`VERSION`].
    pub version: u32,
    /// The HDV driver profile calibrated on (`[hdv] profile`); none on a user's scenario.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile: Option<String>,
    /// The user's scenario calibrated on, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenario: Option<CalibratedScenario>,
    /// Episodes fitted on.
    pub episodes: u64,
    /// Held-out episodes evaluated on.
    pub held_out: u64,
    /// Seed of the first episode.
    pub seed_base: u64,
    /// Samples the global fit used (at most [`MAX_FIT_SAMPLES`]).
    pub fit_samples: usize,
    /// Samples of the held-out episodes.
    pub held_out_samples: usize,
    /// The fitted IDM (desired speed: the vehicle's own times `v0_factor`).
    pub idm: IdmParams,
    /// Constant speed's errors on the held-out samples.
    pub constant_speed: Errors,
    /// The fitted IDM's errors on the held-out samples.
    pub idm_fitted: Errors,
    /// Heterogeneous profiles: recovery of the drawn parameters by per-vehicle fits.
    pub recovery: Vec<Recovery>,
    /// Why there is no recovery at all, on a user's scenario ([`RECOVERY_NOT_APPLICABLE`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recovery_not_applicable: Option<String>,
}

/// A user's scenario as a calibration records it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibratedScenario {
    /// The SUMO configuration as given (`--sumocfg`, `[scenario] sumocfg`).
    pub sumocfg: String,
    /// Its world: the configuration's file name and the SHA-256 of it and every file it names.
    pub files: TrainingScenario,
}

impl CalibratedScenario {
    /// The scenario `config` runs, if it runs one of the user's.
    ///
    /// # Errors
    /// A file of the scenario that cannot be read, naming it.
    pub fn of(config: &Config) -> Result<Option<CalibratedScenario>, EpisodeError> {
        let Some(cfg) = &config.scenario.sumocfg else {
            return Ok(None);
        };
        Ok(Some(CalibratedScenario {
            sumocfg: cfg.display().to_string(),
            files: scenario_record(&config.scenario)?,
        }))
    }
}

impl Calibration {
    /// The report: one line per model in a fixed form, then the fit and any recovery.
    pub fn to_text(&self) -> String {
        let line = |model: &str, e: &Errors| {
            format!(
                "longitudinal {model} rmse_speed_1s={:.3} rmse_speed_3s={:.3} rmse_gap_3s={:.3}\n",
                e.rmse_speed_1s, e.rmse_speed_3s, e.rmse_gap_3s
            )
        };
        let p = &self.idm;
        let mut out =
            line("constant-speed", &self.constant_speed) + &line("idm-fitted", &self.idm_fitted);
        out += &format!(
            "idm fitted on {} samples of {} episodes ({}): v0 = {:.3} × desired, T = {:.3} s, s0 = {:.3} m, a = {:.3} m/s², b = {:.3} m/s²; evaluated on {} samples of {} held-out episodes\n",
            self.fit_samples, self.episodes, self.world(), p.v0_factor, p.time_headway, p.min_gap, p.accel, p.decel, self.held_out_samples, self.held_out
        );
        for r in &self.recovery {
            out += &format!(
                "per-vehicle recovery {}: median relative error {:.1} % over {} vehicles\n",
                r.parameter,
                100.0 * r.median_relative_error,
                r.vehicles
            );
        }
        if let Some(why) = &self.recovery_not_applicable {
            out += &format!("per-vehicle recovery: {why}\n");
        }
        out
    }

    /// What was calibrated on, for the report: `profile NAME` or `scenario PATH`.
    fn world(&self) -> String {
        match (&self.scenario, &self.profile) {
            (Some(s), _) => format!("scenario {}", s.sumocfg),
            (None, Some(p)) => format!("profile {p}"),
            (None, None) => "no profile".into(),
        }
    }
}

/// Vehicle id → its SUMO type.
type VehicleTypes = HashMap<String, String>;

/// One episode's samples (each merge region's apart, in region order) and, on the paper's
/// demand, each vehicle's SUMO type (a user's scenario's drivers have no profile's draws).
fn episode_samples(
    config: &Config,
    seed: u64,
) -> Result<(Vec<FollowSample>, Option<VehicleTypes>), EpisodeError> {
    let mut c = config.clone();
    c.scenario.seed = seed;
    let mut recorders = PerRegion::new(|_| FollowRecorder::default());
    let types = if c.scenario.sumocfg.is_some() {
        episode::sumocfg::run_observed(&c, "sumo", &mut recorders)?;
        None
    } else {
        let planned = episode::demand::generate_for(&c)?;
        let result = episode::run_observed(&c, Driver::Named("sumo"), &planned, &mut recorders)?;
        let types = result.vehicles.iter();
        Some(types.map(|v| (v.id.clone(), v.sumo_type.clone())).collect())
    };
    Ok((samples::of_regions(&recorders.into_regions()), types))
}

/// A sample of a vehicle with drawn parameters, and those draws.
type DrawnSample = (FollowSample, Option<BTreeMap<String, f64>>);

/// The samples of one profile: to fit on, held out, and with each vehicle's draws.
struct ProfileData {
    fit: Vec<FollowSample>,
    held_out: Vec<FollowSample>,
    drawn: Vec<DrawnSample>,
}

/// The index of a heterogeneous driver type (`hdv.7`, `hdv.7@id`).
fn driver_index(sumo_type: &str) -> Option<usize> {
    sumo_type
        .split('@')
        .next()?
        .strip_prefix("hdv.")?
        .parse()
        .ok()
}

/// Runs the episodes (the profile's, or the user's scenario's) and gathers their samples.
fn gather(
    config: &Config,
    spec: &CalibrateSpec,
    progress: &mut impl FnMut(&str),
) -> Result<ProfileData, EpisodeError> {
    let mut data = ProfileData {
        fit: Vec::new(),
        held_out: Vec::new(),
        drawn: Vec::new(),
    };
    let world = match &config.scenario.sumocfg {
        Some(cfg) => cfg.display().to_string(),
        None => config.hdv.profile.clone(),
    };
    for k in 0..spec.episodes + spec.held_out {
        let seed = spec.seed_base + k;
        let (samples, types) = episode_samples(config, seed)?;
        progress(&format!("{world} seed {seed}: {} samples", samples.len()));
        if k >= spec.episodes {
            data.held_out.extend(samples);
            continue;
        }
        if let Some(types) = types {
            data.drawn
                .extend(with_draws(config, seed, &samples, &types));
        }
        data.fit.extend(samples);
    }
    Ok(data)
}

/// The samples of episode `seed` on the paper's demand, each with its vehicle's drawn
/// parameters if its driver type (`types`: vehicle → SUMO type) has any; vehicles named
/// `seed/id`, apart from other episodes'.
fn with_draws(
    config: &Config,
    seed: u64,
    samples: &[FollowSample],
    types: &VehicleTypes,
) -> Vec<DrawnSample> {
    let mut c = config.clone();
    c.scenario.seed = seed;
    let draws = driver_type_draws(&c);
    samples
        .iter()
        .map(|s| {
            let drawn = types
                .get(&s.vehicle)
                .and_then(|t| driver_index(t))
                .and_then(|i| draws.get(i).cloned());
            let vehicle = format!("{seed}/{}", s.vehicle);
            let sample = FollowSample {
                vehicle,
                ..s.clone()
            };
            (sample, drawn)
        })
        .collect()
}

/// The global IDM fit of a profile's samples (at most [`MAX_FIT_SAMPLES`], evenly thinned),
/// starting from `[idm]`; returns it and the number of samples used.
fn fit_global(config: &Config, samples: &[FollowSample]) -> (IdmParams, usize) {
    let start = IdmParams {
        v0_factor: 1.0,
        time_headway: config.idm.time_headway,
        min_gap: config.idm.min_gap,
        accel: config.idm.accel,
        decel: config.idm.decel,
    };
    let stride = samples.len().div_ceil(MAX_FIT_SAMPLES).max(1);
    let thinned: Vec<&FollowSample> = samples.iter().step_by(stride).collect();
    (
        fit_idm(&thinned, start, config.scenario.dt).params,
        thinned.len(),
    )
}

/// Runs the episodes, fits and evaluates; `progress` hears about each episode. On a user's
/// scenario (`scenario.sumocfg`) the calibration records it and no profile, and says why it
/// recovers no drawn parameters.
///
/// # Errors
/// A file of the scenario that cannot be read, or an episode that fails.
pub fn calibrate(
    config: &Config,
    spec: &CalibrateSpec,
    mut progress: impl FnMut(&str),
) -> Result<Calibration, EpisodeError> {
    let scenario = CalibratedScenario::of(config)?;
    let data = gather(config, spec, &mut progress)?;
    let dt = config.scenario.dt;
    let (global, fit_samples) = fit_global(config, &data.fit);
    let own = scenario.is_some();
    Ok(Calibration {
        format: FORMAT.into(),
        version: VERSION,
        profile: (!own).then(|| config.hdv.profile.clone()),
        scenario,
        episodes: spec.episodes,
        held_out: spec.held_out,
        seed_base: spec.seed_base,
        fit_samples,
        held_out_samples: data.held_out.len(),
        idm: global,
        constant_speed: rmse(&data.held_out, |s| predict_constant_speed(s, dt)).into(),
        idm_fitted: rmse(&data.held_out, |s| predict_idm(&global, s, dt)).into(),
        recovery: recover(&data.drawn, global, dt),
        recovery_not_applicable: own.then(|| RECOVERY_NOT_APPLICABLE.into()),
    })
}

/// The generalisation matrix: an IDM fitted on each profile, evaluated on every profile's
/// held-out samples, next to constant speed.
#[derive(Debug, Clone, PartialEq)]
pub struct Matrix {
    /// The driver profiles, in the order of the matrix's rows and columns.
    pub profiles: Vec<String>,
    /// `fitted[a][b]`: errors of the IDM fitted on profile a, on profile b's held-out samples.
    pub fitted: Vec<Vec<Errors>>,
    /// `constant[b]`: constant speed on profile b's held-out samples.
    pub constant: Vec<Errors>,
}

/// Fits on every profile and evaluates on every profile (the same seeds for each).
pub fn matrix(
    config: &Config,
    profiles: &[String],
    spec: &CalibrateSpec,
    mut progress: impl FnMut(&str),
) -> Result<Matrix, EpisodeError> {
    let dt = config.scenario.dt;
    let mut data = Vec::new();
    for p in profiles {
        let mut c = config.clone();
        c.hdv.profile = p.clone();
        data.push(gather(&c, spec, &mut progress)?);
    }
    let fits: Vec<IdmParams> = data.iter().map(|d| fit_global(config, &d.fit).0).collect();
    Ok(Matrix {
        profiles: profiles.to_vec(),
        fitted: fits
            .iter()
            .map(|f| {
                data.iter()
                    .map(|d| rmse(&d.held_out, |s| predict_idm(f, s, dt)).into())
                    .collect()
            })
            .collect(),
        constant: data
            .iter()
            .map(|d| rmse(&d.held_out, |s| predict_constant_speed(s, dt)).into())
            .collect(),
    })
}

/// SUMO attribute → index into [`IdmParams::to_array`].
const RECOVERED: [(&str, usize); 4] = [("tau", 1), ("minGap", 2), ("accel", 3), ("decel", 4)];

/// Per-vehicle fits of the vehicles with drawn parameters and enough samples, compared with
/// their draws.
fn recover(data: &[DrawnSample], start: IdmParams, dt: f64) -> Vec<Recovery> {
    let mut by_vehicle: BTreeMap<&str, (Vec<&FollowSample>, &BTreeMap<String, f64>)> =
        BTreeMap::new();
    for (s, drawn) in data {
        if let Some(d) = drawn {
            by_vehicle
                .entry(&s.vehicle)
                .or_insert((Vec::new(), d))
                .0
                .push(s);
        }
    }
    let mut errors: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for (samples, drawn) in by_vehicle.values() {
        if samples.len() < MIN_VEHICLE_SAMPLES || samples.iter().all(|s| s.leader.is_none()) {
            continue;
        }
        let fitted = fit_idm(samples, start, dt).params.to_array();
        for (name, i) in RECOVERED {
            if let Some(&want) = drawn.get(name) {
                errors
                    .entry(name)
                    .or_default()
                    .push((fitted[i] - want).abs() / want);
            }
        }
    }
    errors
        .into_iter()
        .map(|(name, mut e)| {
            e.sort_by(f64::total_cmp);
            Recovery {
                parameter: name.to_string(),
                vehicles: e.len(),
                median_relative_error: e[e.len() / 2],
            }
        })
        .collect()
}
