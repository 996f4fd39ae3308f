//! Which world an episode of a configuration runs, as a [`TrainingScenario`]: the paper's
//! merge, the paper's demand on a network file, or a SUMO configuration, its files known by
//! their SHA-256. `bkpbs collect` and `bkpbs train-rl` record it in what they write; an
//! episode compares it with the record of each model it uses.

use std::path::Path;

use super::scenario_files::{digest_of, digests};
use super::sumocfg::SumoConfigError;
use crate::config::{Scenario, TrainingScenario};

/// The world `scenario` runs.
///
/// # Errors
/// A file of the scenario that cannot be read, naming it.
pub fn scenario_record(scenario: &Scenario) -> Result<TrainingScenario, SumoConfigError> {
    if let Some(cfg) = &scenario.sumocfg {
        return Ok(TrainingScenario::Sumocfg {
            file: file_name(cfg),
            sha256: digests(cfg)?,
        });
    }
    match &scenario.net_file {
        None => Ok(TrainingScenario::PaperMerge),
        Some(net) => Ok(TrainingScenario::Network {
            file: file_name(net),
            sha256: digest_of(net).map_err(|cause| SumoConfigError::Content {
                path: net.clone(),
                what: format!("cannot read the network file: {cause}"),
            })?,
        }),
    }
}

/// The file name of `path`, without its directory (the whole path when it has none).
fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The embedded merge is the paper's; a network file is known by its digest.
    #[test]
    fn the_record_names_the_scenario_s_files() {
        let mut s = Scenario::default();
        assert_eq!(scenario_record(&s).unwrap(), TrainingScenario::PaperMerge);
        let net = Path::new(env!("CARGO_MANIFEST_DIR")).join("sumo_net/three-lane.net.xml");
        s.net_file = Some(net.clone());
        match scenario_record(&s).unwrap() {
            TrainingScenario::Network { file, sha256 } => {
                assert_eq!(file, "three-lane.net.xml");
                assert_eq!(sha256, digest_of(&net).unwrap());
            }
            other => panic!("{other:?}"),
        }
    }
}
