//! What produced a cell: the bkpbs build (version and commit) and the SUMO that ran it, and the
//! SHA-256 of every model, calibration, policy and network file its configuration names. The
//! worker records it in the cell (`provenance.toml`, beside `settings.toml`, which records the
//! settings and the scenario's file digests); a cell whose record differs from what this build
//! would run with is not finished, and the campaign says why when it runs it again (another
//! commit, a retrained model in place of the old one). Files embedded in the binary (the
//! default models and network) are the commit's.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::config::Config;
use crate::io::bounded::{read_text, FileKind};
use crate::io::build::Build;

/// Name of the cell's provenance record.
pub const PROVENANCE_RECORD: &str = "provenance.toml";

/// The files of a profile in `predictor.calibrations` (`DIR/<profile>/…`) an episode may read.
pub const PROFILE_FILES: [&str; 3] = [
    "calibration.json",
    "gcn-conditioned.json",
    "gcn-unconditioned.json",
];

/// What produced a cell.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Provenance {
    /// The SUMO version it ran on.
    pub sumo: String,
    /// The bkpbs build that ran it.
    pub bkpbs: Build,
    /// SHA-256 (hex) of each file the configuration names besides the scenario's, by its
    /// setting (`predictor.conditioned_model`, `sumo.additional_files.0`, …).
    pub inputs: BTreeMap<String, String>,
}

impl Provenance {
    /// The provenance of an episode of `config` run by this build, the files read where
    /// `config` names them.
    ///
    /// # Errors
    /// A named file that cannot be read, as a sentence naming its setting.
    pub fn of(config: &Config) -> Result<Provenance, String> {
        let mut inputs = BTreeMap::new();
        for (setting, path) in named_inputs(config) {
            if !path.is_file() {
                continue; // an optional profile file the directory lacks
            }
            let digest = crate::sumo::scenario_files::digest_of(&path)
                .map_err(|e| format!("cannot read {setting} '{}': {e}", path.display()))?;
            inputs.insert(setting, digest);
        }
        Ok(Provenance {
            sumo: crate::sumo::version::BUILT.into(),
            bkpbs: Build::this(),
            inputs,
        })
    }

    /// As TOML, the record's contents.
    pub fn to_toml(&self) -> String {
        let head = "# What produced this cell: the bkpbs build, SUMO, and the SHA-256 of each \
                    model, calibration, policy and network file it read.\n";
        format!(
            "{head}{}",
            toml::to_string_pretty(self).expect("provenance serialises")
        )
    }

    /// Why a cell recorded as `self` is not what `now` would run, as a sentence; `None` if it
    /// is.
    pub fn difference(&self, now: &Provenance) -> Option<String> {
        if self.bkpbs != now.bkpbs {
            return Some(format!("{} ran it, this is {}", self.bkpbs, now.bkpbs));
        }
        if self.sumo != now.sumo {
            return Some(format!(
                "SUMO {} ran it, this is SUMO {}",
                self.sumo, now.sumo
            ));
        }
        let settings = self.inputs.keys().chain(now.inputs.keys());
        settings
            .into_iter()
            .find_map(|k| match (self.inputs.get(k), now.inputs.get(k)) {
                (Some(a), Some(b)) if a == b => None,
                (Some(_), Some(_)) => Some(format!("its {k} file is not the one it ran with")),
                (Some(_), None) => Some(format!("it read a {k} file this run does not")),
                _ => Some(format!("it ran without the {k} file this run reads")),
            })
    }
}

/// Each file `config` names outside its scenario, by its setting: models, calibrations, the
/// RL policy, the network and SUMO's additional files.
pub fn named_inputs(config: &Config) -> Vec<(String, PathBuf)> {
    let (s, p) = (&config.scenario, &config.predictor);
    let single = [
        ("scenario.net_file", &s.net_file),
        ("predictor.conditioned_model", &p.conditioned_model),
        ("predictor.unconditioned_model", &p.unconditioned_model),
        ("predictor.calibration", &p.calibration),
        ("rl.policy", &config.rl.policy),
    ];
    let mut named: Vec<(String, PathBuf)> = single
        .into_iter()
        .filter_map(|(k, path)| Some((k.to_string(), path.clone()?)))
        .collect();
    if let Some(dir) = &p.calibrations {
        let profile = dir.join(&config.hdv.profile);
        named.extend(
            PROFILE_FILES
                .iter()
                .map(|f| (format!("predictor.calibrations.{f}"), profile.join(f))),
        );
    }
    let additional = config.sumo.additional_files.iter().enumerate();
    named.extend(additional.map(|(i, f)| (format!("sumo.additional_files.{i}"), f.clone())));
    named
}

/// Does the cell in `dir` record the provenance an episode of `config` would have now? A cell
/// of another build, or whose model file was replaced since, is not finished.
pub fn check_provenance(dir: &Path, config: &Config) -> Result<(), String> {
    let text = read_text(&dir.join(PROVENANCE_RECORD), FileKind::Config)
        .map_err(|_| format!("{PROVENANCE_RECORD} is missing or unreadable"))?;
    let recorded: Provenance = toml::from_str(&text)
        .map_err(|_| format!("{PROVENANCE_RECORD} is not a provenance record"))?;
    let now = Provenance::of(config)?;
    match recorded.difference(&now) {
        Some(why) => Err(why),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_model(dir: &Path, bytes: &[u8]) -> Config {
        let path = dir.join("gcn.json");
        std::fs::write(&path, bytes).expect("write model");
        let mut c = Config::default();
        c.predictor.conditioned_model = Some(path);
        c
    }

    #[test]
    fn a_replaced_model_is_named() {
        let dir = tempfile::tempdir().expect("tempdir");
        let old = Provenance::of(&with_model(dir.path(), b"old")).expect("provenance");
        let now = Provenance::of(&with_model(dir.path(), b"new")).expect("provenance");
        let why = old.difference(&now).expect("differs");
        assert!(why.contains("predictor.conditioned_model"), "{why}");
        assert_eq!(now.difference(&now), None);
    }

    #[test]
    fn another_build_is_named() {
        let now = Provenance::of(&Config::default()).expect("provenance");
        let mut old = now.clone();
        old.bkpbs.commit = "0123456789abcdef".into();
        let why = old.difference(&now).expect("differs");
        assert!(
            why.starts_with("bkpbs ") && why.contains("0123456789ab"),
            "{why}"
        );
    }

    #[test]
    fn the_record_reads_back() {
        let dir = tempfile::tempdir().expect("tempdir");
        let p = Provenance::of(&with_model(dir.path(), b"weights")).expect("provenance");
        std::fs::write(dir.path().join(PROVENANCE_RECORD), p.to_toml()).expect("write");
        let c = with_model(dir.path(), b"weights");
        assert_eq!(check_provenance(dir.path(), &c), Ok(()));
        let c = with_model(dir.path(), b"retrained");
        let why = check_provenance(dir.path(), &c).expect_err("stale");
        assert!(why.contains("conditioned_model"), "{why}");
    }
}
