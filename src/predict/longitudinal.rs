//! How a predicted HDV moves along its lane: at constant speed (the default), or by an IDM
//! fitted to SUMO's drivers with `bkpbs calibrate` (`[predictor] calibration`), behind its
//! present leader, which keeps its speed.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::model_file::ModelError;
use crate::config::{Config, TrainingScenario};
use crate::model::scene::{Kind, Scene};
use crate::model::trajectory::Pose;
use crate::sumo::scenario_record::scenario_record;

/// IDM acceleration exponent δ (fixed, as SUMO's and the paper's).
pub const DELTA: f64 = 4.0;

/// IDM parameters; the desired speed is the vehicle's own times `v0_factor`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IdmParams {
    /// Desired speed v0 as a multiple of the vehicle's own desired speed (dimensionless), so
    /// one fit serves drivers of every desired speed.
    pub v0_factor: f64,
    /// Time headway T (s).
    pub time_headway: f64,
    /// Jam distance s0 (m).
    pub min_gap: f64,
    /// Maximum acceleration a (m/s²).
    pub accel: f64,
    /// Comfortable deceleration b (m/s²).
    pub decel: f64,
}

impl IdmParams {
    /// The parameters as one vector, in field order (v0_factor, T, s0, a, b): what the fit
    /// optimises.
    pub fn to_array(self) -> [f64; 5] {
        [
            self.v0_factor,
            self.time_headway,
            self.min_gap,
            self.accel,
            self.decel,
        ]
    }

    /// The parameters of a vector in [`IdmParams::to_array`]'s order.
    pub fn from_array(x: [f64; 5]) -> IdmParams {
        IdmParams {
            v0_factor: x[0],
            time_headway: x[1],
            min_gap: x[2],
            accel: x[3],
            decel: x[4],
        }
    }

    /// The IDM acceleration at speed `v`, desired speed `v0`, and (gap, closing speed) to the
    /// leader if there is one.
    pub fn acceleration(&self, v: f64, v0: f64, leader: Option<(f64, f64)>) -> f64 {
        let free = 1.0 - (v / v0.max(0.1)).powf(DELTA);
        let interaction = leader.map_or(0.0, |(gap, closing)| {
            let s_star = self.min_gap
                + (v * self.time_headway + v * closing / (2.0 * (self.accel * self.decel).sqrt()))
                    .max(0.0);
            (s_star / gap.max(0.1)).powi(2)
        });
        self.accel * (free - interaction)
    }
}

/// The longitudinal model of predicted HDVs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Longitudinal {
    /// The HDV keeps its present speed.
    ConstantSpeed,
    /// The HDV follows this IDM behind its present leader on its lane, which is taken to keep
    /// its speed.
    Idm(IdmParams),
}

/// What a predictor needs of `calibration.json` (written by `bkpbs calibrate`): the profile
/// it was made under, or the user's scenario it was made on, and the fitted IDM.
#[derive(Deserialize)]
struct CalibrationView {
    format: String,
    version: u32,
    #[serde(default)]
    profile: Option<String>,
    #[serde(default)]
    scenario: Option<ScenarioView>,
    idm: IdmParams,
}

/// The scenario a calibration was made on (`bkpbs calibrate --sumocfg`).
#[derive(Deserialize)]
struct ScenarioView {
    sumocfg: String,
    files: TrainingScenario,
}

/// What a calibration must have been made on for a run: the HDV profile SUMO runs under, and
/// the user's scenario the run is on, if any.
pub struct CalibrationFor<'a> {
    /// `hdv.profile`.
    pub profile: &'a str,
    /// The run's scenario of the user's, with its files' digests.
    pub scenario: Option<&'a TrainingScenario>,
}

/// Format tag of `calibration.json` (its `format` field).
pub const CALIBRATION_FORMAT: &str = "bkpbs-calibration";
/// Version of the `calibration.json` format this build reads (its `version` field).
pub const CALIBRATION_VERSION: u32 = 1;

impl Longitudinal {
    /// The configured model: the IDM of `predictor.calibration` if set, which must be a
    /// calibration for the profile SUMO runs.
    pub fn from_config(config: &Config) -> Result<Longitudinal, ModelError> {
        let p = &config.predictor;
        let profile = &config.hdv.profile;
        let Some(path) = calibration_path(config) else {
            return Ok(Longitudinal::ConstantSpeed);
        };
        let own = match &config.scenario.sumocfg {
            Some(_) => Some(
                scenario_record(&config.scenario).map_err(|e| ModelError::Shape {
                    path: path.clone(),
                    what: format!("the run's scenario cannot be read: {e}"),
                })?,
            ),
            None => None,
        };
        let expected = CalibrationFor {
            profile,
            scenario: own.as_ref(),
        };
        let expected = (!p.calibration_for_any_profile).then_some(expected);
        load(&path, expected).map(Longitudinal::Idm)
    }

    /// The poses of vehicle `i` at steps 0..=`horizon`: along its lane by this model if it is
    /// an HDV (CAVs keep their speed), sideways at `lateral(k)`.
    pub fn poses(
        &self,
        scene: &Scene,
        i: usize,
        horizon: usize,
        dt: f64,
        lateral: impl Fn(usize) -> f64,
    ) -> Vec<Pose> {
        let model = match scene.vehicles[i].kind {
            Kind::Hdv => *self,
            Kind::Cav => Longitudinal::ConstantSpeed,
        };
        model
            .course(scene, i, horizon, dt)
            .into_iter()
            .enumerate()
            .map(|(k, (s, speed))| Pose {
                s,
                y: lateral(k),
                heading: 0.0,
                speed,
            })
            .collect()
    }

    /// (s, speed) of vehicle `i` at steps 0..=`horizon` along its lane.
    pub fn course(&self, scene: &Scene, i: usize, horizon: usize, dt: f64) -> Vec<(f64, f64)> {
        let v = &scene.vehicles[i];
        let Longitudinal::Idm(p) = self else {
            return (0..=horizon)
                .map(|k| (v.s + v.speed * dt * k as f64, v.speed))
                .collect();
        };
        let leader = scene
            .vehicles
            .iter()
            .filter(|u| u.lane == v.lane && u.s > v.s)
            .min_by(|a, b| a.s.total_cmp(&b.s));
        let v0 = p.v0_factor * v.desired_speed;
        let (mut s, mut speed) = (v.s, v.speed);
        let mut out = Vec::with_capacity(horizon + 1);
        out.push((s, speed));
        for k in 0..horizon {
            let ahead = leader.map(|l| {
                let rear = l.rear() + l.speed * dt * k as f64;
                (rear - (s + 0.5 * v.length), speed - l.speed)
            });
            speed = (speed + p.acceleration(speed, v0, ahead) * dt).max(0.0);
            s += speed * dt;
            out.push((s, speed));
        }
        out
    }
}

/// The calibration file `config` names: `predictor.calibration`, or the profile's in
/// `predictor.calibrations`; `None` for none (constant speed along the lane).
pub fn calibration_path(config: &Config) -> Option<PathBuf> {
    let p = &config.predictor;
    p.calibration.clone().or_else(|| {
        (p.calibrations.as_ref()).map(|dir| dir.join(&config.hdv.profile).join("calibration.json"))
    })
}

/// The fitted IDM of a calibration file, checked: the format, its version, and that it was
/// made for the run `expected` describes (unless `None`: any profile or scenario): under its
/// profile, or, for a calibration on a user's scenario, on the same scenario (the same files).
pub fn load(path: &Path, expected: Option<CalibrationFor>) -> Result<IdmParams, ModelError> {
    let p = || PathBuf::from(path);
    let text = crate::io::bounded::read_text(path, crate::io::bounded::FileKind::Model)
        .map_err(|cause| ModelError::Read { path: p(), cause })?;
    let c: CalibrationView = serde_json::from_str(&text).map_err(|e| ModelError::Json {
        path: p(),
        message: e.to_string(),
    })?;
    if c.format != CALIBRATION_FORMAT {
        return Err(ModelError::Format {
            path: p(),
            found: c.format,
        });
    }
    if c.version != CALIBRATION_VERSION {
        return Err(ModelError::Version {
            path: p(),
            found: c.version,
            expected: CALIBRATION_VERSION,
        });
    }
    if let Some(why) = expected.and_then(|e| mismatch(&c, &e)) {
        return Err(ModelError::Shape {
            path: p(),
            what: format!("{why} (predictor.calibration_for_any_profile allows it)"),
        });
    }
    let ok = c
        .idm
        .to_array()
        .iter()
        .all(|v| v.is_finite() && *v > 0.0 && *v < 1e3);
    if !ok {
        return Err(ModelError::Shape {
            path: p(),
            what: format!("IDM parameters out of range: {:?}", c.idm),
        });
    }
    Ok(c.idm)
}

/// Why calibration `c` does not fit the run `e`, if it does not.
fn mismatch(c: &CalibrationView, e: &CalibrationFor) -> Option<String> {
    match (&c.scenario, &c.profile) {
        (Some(s), _) => match e.scenario {
            Some(run) if run.same_as(&s.files) => None,
            Some(_) => Some(format!(
                "it calibrates the scenario '{}', but this run is on another (its files differ)",
                s.sumocfg
            )),
            None => Some(format!(
                "it calibrates the scenario '{}', but this run is on the paper's demand",
                s.sumocfg
            )),
        },
        (None, Some(profile)) if profile != e.profile => Some(format!(
            "it calibrates HDV profile '{profile}', but SUMO runs '{}' (hdv.profile)",
            e.profile
        )),
        (None, Some(_)) => None,
        (None, None) => Some("it names neither an HDV profile nor a scenario".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::road::Road;
    use crate::model::scene::{Origin, VehicleState};

    fn scene() -> Scene {
        Scene {
            time: 0.0,
            road: Road::paper_default(),
            vehicles: vec![
                VehicleState::on_lane("h", Kind::Hdv, Origin::Main, 100.0, 1, 30.0),
                VehicleState::on_lane("slow", Kind::Hdv, Origin::Main, 130.0, 1, 10.0),
            ],
        }
    }

    const IDM: IdmParams = IdmParams {
        v0_factor: 1.0,
        time_headway: 1.5,
        min_gap: 5.0,
        accel: 3.0,
        decel: 5.0,
    };

    #[test]
    fn the_idm_course_brakes_behind_a_slow_leader_and_constant_speed_does_not() {
        let s = scene();
        let constant = Longitudinal::ConstantSpeed.course(&s, 0, 15, 0.2);
        assert_eq!(constant[15], (100.0 + 30.0 * 0.2 * 15.0, 30.0));
        let idm = Longitudinal::Idm(IDM).course(&s, 0, 15, 0.2);
        assert!(idm[15].1 < 15.0, "{:?}", idm[15]);
        // It stays behind the leader, which keeps its 10 m/s.
        for (k, (pos, _)) in idm.iter().enumerate() {
            let leader_rear = 130.0 - 2.5 + 10.0 * 0.2 * k as f64;
            assert!(pos + 2.5 < leader_rear, "step {k}: {pos}");
        }
    }

    #[test]
    fn a_calibration_file_must_be_one_and_for_the_profile_sumo_runs() {
        let d = tempfile::tempdir().unwrap();
        let path = d.path().join("calibration.json");
        let write = |format: &str, profile: &str| {
            let text = serde_json::json!({
                "format": format, "version": 1, "profile": profile, "idm": IDM
            });
            std::fs::write(&path, text.to_string()).unwrap();
        };
        write(CALIBRATION_FORMAT, "paper");
        let under = |profile| {
            Some(CalibrationFor {
                profile,
                scenario: None,
            })
        };
        assert_eq!(load(&path, under("paper")).unwrap(), IDM);
        let e = load(&path, under("sumo-safe")).unwrap_err().to_string();
        assert!(e.contains("'paper'") && e.contains("'sumo-safe'"), "{e}");
        assert_eq!(load(&path, None).unwrap(), IDM, "any profile");
        write("something-else", "paper");
        assert!(load(&path, under("paper")).is_err());
        assert!(load(&d.path().join("missing.json"), under("paper")).is_err());
    }

    /// A calibration made on a user's scenario is used on that scenario (the same files) and
    /// refused, in one line naming it, on another or on the paper's demand.
    #[test]
    fn a_scenario_calibration_is_for_its_own_scenario() {
        let d = tempfile::tempdir().unwrap();
        let path = d.path().join("calibration.json");
        let world = |sha: &str| TrainingScenario::Sumocfg {
            file: "ramp.sumocfg".into(),
            sha256: [("ramp.sumocfg".to_string(), sha.to_string())].into(),
        };
        let text = serde_json::json!({
            "format": CALIBRATION_FORMAT, "version": 1, "idm": IDM,
            "scenario": {"sumocfg": "game/ramp.sumocfg", "files": world("ab")},
        });
        std::fs::write(&path, text.to_string()).unwrap();
        let on = |w: Option<&TrainingScenario>| {
            load(
                &path,
                Some(CalibrationFor {
                    profile: "sumo-safe",
                    scenario: w,
                }),
            )
        };
        assert_eq!(on(Some(&world("ab"))).unwrap(), IDM);
        let other = on(Some(&world("cd"))).unwrap_err().to_string();
        assert!(
            other.contains("'game/ramp.sumocfg'") && other.contains("another"),
            "{other}"
        );
        let paper = on(None).unwrap_err().to_string();
        assert!(paper.contains("paper's demand"), "{paper}");
        assert_eq!(load(&path, None).unwrap(), IDM, "any scenario");
    }
}
