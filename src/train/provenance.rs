//! The [`TrainedOn`] record of what `bkpbs collect`, `bkpbs train` and `bkpbs train-rl`
//! write: collect records the world and seeds of its episodes in the data file, train carries
//! that record into the model file with its own command and seed, train-rl writes its own
//! into the policy file.

use crate::config::trained_on::command_line;
use crate::config::{Config, TrainedOn};
use crate::io::build::Build;
use crate::sumo::scenario_record::scenario_record;
use crate::sumo::sumocfg::SumoConfigError;

/// Seeds `first`, `first + 1`, … of `episodes` episodes, as `first-last` (one seed alone).
pub fn seed_range(first: u64, episodes: u64) -> String {
    match episodes {
        0 => "none".into(),
        1 => first.to_string(),
        n => format!("{first}-{}", first + n - 1),
    }
}

/// The record of episodes of `base`'s world with `seeds` seeds (`episodes` of them), run by
/// this process under this build, before any training.
///
/// # Errors
/// A file of the scenario that cannot be read.
pub fn of_episodes(
    base: &Config,
    seeds: String,
    episodes: u64,
) -> Result<TrainedOn, SumoConfigError> {
    Ok(TrainedOn {
        step_length_s: base.scenario.dt,
        scenarios: vec![scenario_record(&base.scenario)?],
        episode_seeds: seeds,
        episodes: episodes.to_string(),
        training_seed: "-".into(),
        commands: vec![command_line()],
        sumo_version: crate::sumo::version::BUILT.into(),
        bkpbs_version: Build::this().version,
        bkpbs_commit: Build::this().commit,
    })
}

/// The model's record: the data's, with this process's command and the training `seed`; the
/// bkpbs version and commit become this build's when the data's were another's (both are
/// named then).
pub fn of_training(data: &TrainedOn, seed: u64) -> TrainedOn {
    let mut r = data.clone();
    r.training_seed = seed.to_string();
    r.commands.push(command_line());
    let Build { version, commit } = Build::this();
    if r.bkpbs_commit != commit || r.bkpbs_version != version {
        r.bkpbs_version = format!("{version} (data: {})", r.bkpbs_version);
        r.bkpbs_commit = format!("{commit} (data: {})", r.bkpbs_commit);
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_ranges_read_as_written_in_the_readmes() {
        assert_eq!(seed_range(10_000, 500), "10000-10499");
        assert_eq!(seed_range(7, 1), "7");
    }

    /// Training keeps the data's world and seeds and adds its own command and seed.
    #[test]
    fn training_carries_the_data_s_record() {
        let data = of_episodes(&Config::default(), seed_range(10, 5), 5).unwrap();
        let model = of_training(&data, 3);
        assert_eq!(model.scenarios, data.scenarios);
        assert_eq!(model.episode_seeds, "10-14");
        assert_eq!(model.training_seed, "3");
        assert_eq!(model.commands.len(), 2);
        assert_eq!(model.bkpbs_commit, data.bkpbs_commit);
    }
}
