//! The learned files an episode uses — b_θ's model files, the HDV calibration its predictors
//! follow, the RL-PPO policy — with what each
//! was trained on: `bkpbs episode` warns once, after its run, where a file was trained on
//! another scenario than the one it runs (a campaign once at its start), and `bkpbs episode` lists them in `models.toml` beside its
//! CSV files (which keep their columns: committed results stay as they are).
//!
//! A file trained under another step length never gets here: loading it is refused
//! (`predict::configured_models`, `policy::model_file::load_file`).

use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::config::{Config, PredictorKind, TrainedOn, TrainingScenario};
use crate::controller::{BuildError, PlannerKind};
use crate::policy::model_file::{load_file, EMBEDDED_POLICY, EMBEDDED_POLICY_SOURCE};
use crate::predict::longitudinal::calibration_path;
use crate::predict::model_file::{LaneChangeModel, EMBEDDED_CONDITIONED, EMBEDDED_UNCONDITIONED};

/// The file `bkpbs episode` lists the models in, in its output directory.
pub const MODELS_RECORD: &str = "models.toml";

/// One learned file an episode uses.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UsedModel {
    /// The setting that selects it (`predictor.conditioned_model`, `rl.policy`), whether the
    /// configuration names a file or the embedded one is used.
    pub setting: String,
    /// Its path as given, or `embedded:<name>` for the one built into the binary.
    pub source: String,
    /// SHA-256 (hex) of its bytes.
    pub sha256: String,
    /// What it was trained on; absent for a file written before bkpbs kept it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trained_on: Option<TrainedOn>,
}

/// The learned files the planner `planner` uses under `config`: b_θ's two models for
/// `bk-pbs` (the unconditioned one for `bk-mastar`) with the learned predictor, then the HDV
/// calibration of either predictor if one is configured, the policy for `rl-ppo`, none
/// otherwise.
///
/// # Errors
/// An unknown planner, or a file that cannot be used (as building the planner would say).
pub fn models_used(config: &Config, planner: &str) -> Result<Vec<UsedModel>, BuildError> {
    let kind: PlannerKind = planner.parse()?;
    let learned = config.predictor.kind == PredictorKind::Learned;
    Ok(match kind {
        PlannerKind::BkPbs | PlannerKind::BkMastar => {
            let mut used = Vec::new();
            if learned {
                let (c, u) = crate::predict::learned::configured_models(config)?;
                if kind == PlannerKind::BkPbs {
                    used.push(of_model("predictor.conditioned_model", &c));
                }
                used.push(of_model("predictor.unconditioned_model", &u));
            }
            used.extend(of_calibration(config));
            used
        }
        PlannerKind::RlPpo => vec![of_policy(config)?],
        _ => Vec::new(),
    })
}

/// The record of a loaded b_θ.
fn of_model(setting: &str, model: &LaneChangeModel) -> UsedModel {
    let embedded = match model.source.as_str() {
        "embedded:gcn-conditioned.json" => Some(EMBEDDED_CONDITIONED),
        "embedded:gcn-unconditioned.json" => Some(EMBEDDED_UNCONDITIONED),
        _ => None,
    };
    UsedModel {
        setting: setting.into(),
        source: model.source.clone(),
        sha256: digest(embedded, &model.source),
        trained_on: model.file.trained_on.clone(),
    }
}

/// The record of the HDV calibration `config` names, if any (`bkpbs calibrate`'s file says
/// itself what it was made on: a profile or a scenario's files).
fn of_calibration(config: &Config) -> Option<UsedModel> {
    let source = calibration_path(config)?.display().to_string();
    Some(UsedModel {
        setting: "predictor.calibration".into(),
        sha256: digest(None, &source),
        source,
        trained_on: None,
    })
}

/// The record of the configured (or embedded) policy.
fn of_policy(config: &Config) -> Result<UsedModel, BuildError> {
    let path = config.rl.policy.as_deref();
    let file = load_file(path, config.scenario.dt)?;
    let source = path.map_or(EMBEDDED_POLICY_SOURCE.into(), |p| p.display().to_string());
    Ok(UsedModel {
        setting: "rl.policy".into(),
        sha256: digest(path.is_none().then_some(EMBEDDED_POLICY), &source),
        source,
        trained_on: file.trained_on,
    })
}

/// SHA-256 of `embedded` text, or of the file at `path` (`unreadable` if it went since).
fn digest(embedded: Option<&str>, path: &str) -> String {
    match embedded {
        Some(text) => format!("{:x}", Sha256::digest(text.as_bytes())),
        None => crate::sumo::scenario_files::digest_of(std::path::Path::new(path))
            .unwrap_or_else(|_| "unreadable".into()),
    }
}

/// The warnings of files trained on another scenario than `run`: one line per set of
/// training scenarios, naming its files, those scenarios and `run`; none for a file that does
/// not record its scenarios.
pub fn scenario_warnings(used: &[UsedModel], run: &TrainingScenario) -> Vec<String> {
    let mut by_scenarios: Vec<(String, Vec<String>)> = Vec::new();
    for m in used {
        let Some(t) = m.trained_on.as_ref() else {
            continue;
        };
        if t.scenarios.is_empty() || t.covers(run) {
            continue;
        }
        let (trained, file) = (t.scenarios_text(), format!("{} {}", m.setting, m.source));
        match by_scenarios.iter_mut().find(|(s, _)| *s == trained) {
            Some((_, files)) => files.push(file),
            None => by_scenarios.push((trained, vec![file])),
        }
    }
    by_scenarios
        .into_iter()
        .map(|(trained, files)| {
            format!(
                "warning: {} {} trained on {trained}, this episode runs {run}: its decisions \
                 may not fit here (see the guide, \"Your own scenario\", learned parts)",
                files.join(" and "),
                if files.len() == 1 { "was" } else { "were" },
            )
        })
        .collect()
}

/// The warnings, one line each, of the `used` files that were trained on another scenario than
/// `config` runs: what `bkpbs episode` prints after its run and a campaign once at its start
/// (the library prints nothing: an episode that fails says one `error:` line). None where the
/// scenario cannot be read (the episode reports that).
pub fn other_scenario_warnings(config: &Config, used: &[UsedModel]) -> Vec<String> {
    if used.is_empty() {
        return Vec::new();
    }
    match crate::sumo::scenario_record::scenario_record(&config.scenario) {
        Ok(run) => scenario_warnings(used, &run),
        Err(_) => Vec::new(),
    }
}

/// `models.toml`: one `[[model]]` table per used file (none: a comment saying so).
pub fn models_toml(used: &[UsedModel]) -> String {
    #[derive(Serialize)]
    struct Record<'a> {
        model: &'a [UsedModel],
    }
    let head = "# The learned files this episode used, with what each was trained on \
                (bkpbs episode; the guide's chapter on training).\n";
    if used.is_empty() {
        return format!("{head}# none: this planner uses no learned model\n");
    }
    let body = toml::to_string(&Record { model: used }).expect("the record serialises");
    format!("{head}{body}")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped models were trained on the paper's merge: quiet there, one warning naming
    /// both on another scenario.
    #[test]
    fn shipped_models_warn_only_off_the_paper_s_merge() {
        let used = models_used(&Config::default(), "bk-pbs").unwrap();
        assert_eq!(used.len(), 2);
        assert!(scenario_warnings(&used, &TrainingScenario::PaperMerge).is_empty());
        let other = TrainingScenario::Sumocfg {
            file: "mine.sumocfg".into(),
            sha256: [("mine.sumocfg".to_string(), "00".to_string())].into(),
        };
        let w = scenario_warnings(&used, &other);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("the paper's merge") && w[0].contains("mine.sumocfg"));
        assert!(w[0].contains("gcn-conditioned") && w[0].contains("gcn-unconditioned"));
    }

    /// `models.toml` lists the embedded policy with its record; a planner without models says so.
    #[test]
    fn the_record_lists_the_models_used() {
        let text = models_toml(&models_used(&Config::default(), "rl-ppo").unwrap());
        assert!(text.contains("source = \"embedded:rl-ppo.json\""), "{text}");
        assert!(text.contains("step_length_s = 0.2"), "{text}");
        toml::from_str::<toml::Value>(&text).unwrap();
        assert!(models_toml(&models_used(&Config::default(), "sumo").unwrap()).contains("none"));
    }
}
