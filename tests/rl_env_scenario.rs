//! The stepped RL environment (Gymnasium, PettingZoo) on a scenario of the user's own, SUMO's
//! shipped `ramp` game: driven by the committed policy, greedily, every CAV of every region an
//! agent, it is the `rl-ppo` planner's episode vehicle for vehicle — an agent trained there
//! faces the task the planner is evaluated on; with one agent among HDVs, exactly one vehicle
//! is a CAV, and it departed after the warm-up.

mod common;

use bkpbs::config::Config;
use bkpbs::episode::sumocfg::{self, ScenarioResult};
use bkpbs::episode::Ran;
use bkpbs::policy::model_file;
use bkpbs::policy::network::{greedy, masked_log_softmax, ActorCritic};
use bkpbs::policy::observation::OBS_DIM;
use bkpbs::train::ppo::env::{Agents, MergeEnv};
use bkpbs::train::ppo::reward::RewardSettings;
use common::{bkpbs, game_copy};
use nalgebra::DMatrix;

const STEPS: &str = "250";
const SEED: &str = "4";

fn ramp_config(cfg: &std::path::Path) -> Config {
    let mut c = Config::default();
    c.scenario.sumocfg = Some(cfg.to_path_buf());
    c.scenario.alpha = 0.5;
    c.scenario.seed = SEED.parse().unwrap();
    c.scenario.steps = STEPS.parse().unwrap();
    c
}

/// Runs the environment to its end, every agent acting as `net` greedily would; the result.
fn drive(env: &mut MergeEnv, net: &ActorCritic) -> (ScenarioResult, usize) {
    let mut decisions = 0;
    let mut act = Default::default();
    while env.result().is_none() {
        let agents = env.agents();
        let mut obs = DMatrix::zeros(OBS_DIM, agents.len());
        for (col, a) in agents.iter().enumerate() {
            obs.column_mut(col).copy_from_slice(&a.obs);
        }
        let logits = net.logits(&obs, &mut act);
        let actions: Vec<usize> = agents
            .iter()
            .enumerate()
            .map(|(col, a)| greedy(&masked_log_softmax(logits.column(col).as_slice(), &a.mask)))
            .collect();
        decisions += agents.len();
        let step = env.step(&actions).unwrap();
        if step.done && env.result().is_none() {
            env.close();
        }
    }
    match env.result() {
        Some(Ran::Scenario(r)) => ((**r).clone(), decisions),
        other => panic!("a scenario's result expected, got {other:?}"),
    }
}

fn file(dir: &std::path::Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap()
}

#[test]
fn the_environment_on_a_scenario_is_the_rl_ppo_planners_episode() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = game_copy(tmp.path()).join("ramp.sumocfg");
    let net = model_file::load(None, 0.2).unwrap();

    let mut env = MergeEnv::start(
        &ramp_config(&cfg),
        Agents::AllCavs,
        RewardSettings::default(),
    )
    .unwrap();
    let (all, decisions) = drive(&mut env, &net);
    assert!(decisions > 200, "{decisions} decisions");
    assert!(
        env.possible_agents().len() > 5,
        "{:?}",
        env.possible_agents()
    );
    drop(env);
    let env_dir = tmp.path().join("env");
    sumocfg::write(&all, &env_dir).unwrap();

    let cli_dir = tmp.path().join("cli");
    let o = bkpbs(&[
        "episode",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--planner",
        "rl-ppo",
        "--alpha",
        "0.5",
        "--seed",
        SEED,
        "--steps",
        STEPS,
        "--out",
        cli_dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    for f in ["vehicles.csv", "collisions.csv"] {
        assert_eq!(file(&env_dir, f), file(&cli_dir, f), "{f}");
    }
    let s = &all.summary;
    assert_eq!(s.planner, "rl-env");
    assert!(s.inserted_cav > 5 && s.inserted > 40, "{s:?}");

    let mut env = MergeEnv::start(
        &ramp_config(&cfg),
        Agents::Single,
        RewardSettings::default(),
    )
    .unwrap();
    let ego = env.agents()[0].id.clone();
    let (single, _) = drive(&mut env, &net);
    let cavs: Vec<_> = single
        .vehicles
        .iter()
        .filter(|v| v.kind == bkpbs::model::scene::Kind::Cav)
        .collect();
    assert_eq!(cavs.len(), 1, "one CAV among HDVs");
    assert_eq!(cavs[0].id.as_str(), &*ego);
    assert!(
        cavs[0].depart_s >= Some(10.0),
        "departed at {:?}",
        cavs[0].depart_s
    );
    assert_eq!(env.possible_agents(), [ego]);
}
