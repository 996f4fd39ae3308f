//! Collecting the lane-change data set from SUMO episodes.
//!
//! [`Recorder`] is an episode [`Observer`]: it buffers the last `PREVIEW + 1` scenes and, once the
//! scene `PREVIEW` steps after step t has arrived, turns every HDV at a decision point in step t
//! into a [`Sample`]: its graph (a) at t, the CAVs near it at t with their actual states over
//! steps t+1 … t+15 (standing in for planned trajectories), where it is, and whether it started a
//! lane change at t+1. The last `PREVIEW` steps of an episode have no full preview and give no
//! samples. [`collect`] runs a mix of rollout policies over seeds.
//!
//! Lane changes on the main road are rare per step (a few per episode), so main-road samples
//! without a lane change are kept only with probability `main_negative_keep`; each kept sample
//! records the inverse as its weight, so the natural distribution can be restored.

use std::collections::{HashMap, VecDeque};
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::dataset::{Dataset, Sample};
use crate::config::{Config, PredictorKind};
use crate::controller;
use crate::episode::{self, Driver, EpisodeError, Observer, PerRegion};
use crate::model::scene::{Kind, Scene, VehicleState};
use crate::predict::features::{
    cav_node, ego_of, is_decision_point, lane_change_direction, lane_change_start, lane_class,
    neighbours, select_cavs, Agent, CavNode, Observation, Subset, CAV_NODES, PREVIEW,
};

/// Random stream of the collector's thinning of main-road negatives.
pub const THINNING_STREAM: u64 = 7;

/// Counts of what the recorder saw, for the collection log.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CollectStats {
    /// Episodes run.
    pub episodes: u64,
    /// HDV-steps seen (all of them).
    pub hdv_steps: u64,
    /// Samples kept, per subset and label: HDVs on the merge lane (ramp) that keep their lane at
    /// the next step.
    pub ramp_negative: u64,
    /// HDVs on the merge lane that start a lane change (the merge) at the next step.
    pub ramp_positive: u64,
    /// Main-road HDVs that keep their lane at the next step (kept after thinning).
    pub main_negative: u64,
    /// Main-road HDVs that start a lane change at the next step.
    pub main_positive: u64,
    /// Main-road negatives dropped by thinning.
    pub main_negative_dropped: u64,
    /// HDV-steps that are no decision points: on the ramp edge or mid-manoeuvre.
    pub not_decision_points: u64,
    /// HDVs gone at the next step (arrived or crashed): no label.
    pub vanished: u64,
    /// Lane changes in the unexpected direction (see `features::lane_change_direction`).
    pub unexpected_direction: u64,
}

impl std::ops::AddAssign for CollectStats {
    fn add_assign(&mut self, o: Self) {
        self.episodes += o.episodes;
        self.hdv_steps += o.hdv_steps;
        self.ramp_negative += o.ramp_negative;
        self.ramp_positive += o.ramp_positive;
        self.main_negative += o.main_negative;
        self.main_positive += o.main_positive;
        self.main_negative_dropped += o.main_negative_dropped;
        self.not_decision_points += o.not_decision_points;
        self.vanished += o.vanished;
        self.unexpected_direction += o.unexpected_direction;
    }
}

impl CollectStats {
    /// Counts a kept sample under its subset and label.
    fn count(&mut self, subset: Subset, label: bool) {
        match (subset, label) {
            (Subset::Ramp, false) => self.ramp_negative += 1,
            (Subset::Ramp, true) => self.ramp_positive += 1,
            (Subset::Main, false) => self.main_negative += 1,
            (Subset::Main, true) => self.main_positive += 1,
        }
    }
}

impl std::fmt::Display for CollectStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} episodes, {} HDV-steps: ramp {} + {} lane changes, main {} + {} lane changes \
             ({} main negatives thinned out), {} not at a decision point, {} vanished",
            self.episodes,
            self.hdv_steps,
            self.ramp_negative,
            self.ramp_positive,
            self.main_negative,
            self.main_positive,
            self.main_negative_dropped,
            self.not_decision_points,
            self.vanished
        )
    }
}

/// One scene with an id → index map.
struct Buffered {
    scene: Scene,
    index: HashMap<Arc<str>, usize>,
}

/// The episode observer that produces samples (with a lag of `PREVIEW` steps).
pub struct Recorder {
    episode: u32,
    dt: f64,
    main_negative_keep: f64,
    rng: ChaCha8Rng,
    buffer: VecDeque<Buffered>,
    step: u32,
    agents: Vec<Agent>,
    chosen: Vec<usize>,
    /// Samples produced so far.
    pub samples: Vec<Sample>,
    /// Counts of what this recorder saw.
    pub stats: CollectStats,
}

impl Recorder {
    /// For episode number `episode` (its seed seeds the thinning).
    pub fn new(episode: u32, seed: u64, dt: f64, main_negative_keep: f64) -> Recorder {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(THINNING_STREAM);
        Recorder {
            episode,
            dt,
            main_negative_keep: main_negative_keep.clamp(1e-6, 1.0),
            rng,
            buffer: VecDeque::with_capacity(PREVIEW + 1),
            step: 0,
            agents: Vec::new(),
            chosen: Vec::new(),
            samples: Vec::new(),
            stats: CollectStats::default(),
        }
    }

    /// Turns every HDV at a decision point in the oldest buffered scene into a sample, labelled
    /// by the next scene; called once the buffer holds the preview after that scene.
    fn emit(&mut self) {
        let now = &self.buffer[0].scene;
        let next = &self.buffer[1];
        let w = now.road.lane_width;
        self.agents.clear();
        self.agents
            .extend(now.vehicles.iter().map(|v| Agent::of(v, w)));
        for (i, v) in now.vehicles.iter().enumerate() {
            if v.kind != Kind::Hdv {
                continue;
            }
            let Some(label) = label_of(v, next, w, &mut self.stats) else {
                continue;
            };
            let subset = Subset::of_lane(lane_class(&now.road, v.lane).into());
            let Some(weight) = thinning_weight(
                &mut self.rng,
                self.main_negative_keep,
                subset,
                label,
                &mut self.stats,
            ) else {
                continue;
            };
            let obs = observation(&self.buffer, &self.agents, &mut self.chosen, i, self.dt);
            self.stats.count(subset, label);
            self.samples.push(Sample {
                episode: self.episode,
                step: self.step - PREVIEW as u32,
                subset,
                label,
                weight,
                obs,
            });
        }
    }
}

/// Whether HDV `v` starts a lane change at the `next` step, or `None` when it gives no sample:
/// not at a decision point, or gone at the next step. Counts what it sees into `stats`.
fn label_of(v: &VehicleState, next: &Buffered, w: f64, stats: &mut CollectStats) -> Option<bool> {
    stats.hdv_steps += 1;
    if !is_decision_point(v) {
        stats.not_decision_points += 1;
        return None;
    }
    let Some(&j) = next.index.get(&v.id) else {
        stats.vanished += 1;
        return None;
    };
    let dir = lane_change_start(v, &next.scene.vehicles[j], w);
    if dir != 0 && dir as i32 != lane_change_direction(&next.scene.road, v.lane) {
        stats.unexpected_direction += 1;
    }
    Some(dir != 0)
}

/// The weight of a sample, or `None` when thinning drops it: main-road negatives are kept with
/// probability `keep` (one draw from `rng` each) and weighted by its inverse, all others kept
/// with weight 1.
fn thinning_weight(
    rng: &mut ChaCha8Rng,
    keep: f64,
    subset: Subset,
    label: bool,
    stats: &mut CollectStats,
) -> Option<f32> {
    if subset == Subset::Main && !label && keep < 1.0 {
        if rng.gen::<f64>() >= keep {
            stats.main_negative_dropped += 1;
            return None;
        }
        return Some((1.0 / keep) as f32);
    }
    Some(1.0)
}

/// The input of vehicle `i` (among `agents`) in the oldest buffered scene: its graph (a) then,
/// and the nearest CAVs' actual states over the following `PREVIEW` scenes, standing in for
/// their plans (a CAV gone by then leaves empty nodes).
fn observation(
    buffer: &VecDeque<Buffered>,
    agents: &[Agent],
    chosen: &mut Vec<usize>,
    i: usize,
    dt: f64,
) -> Observation {
    let now = &buffer[0].scene;
    let w = now.road.lane_width;
    let ego = agents[i];
    let others = agents
        .iter()
        .enumerate()
        .filter(|&(k, _)| k != i)
        .map(|(_, a)| a);
    let mut obs = Observation {
        ego: ego_of(&now.vehicles[i], &now.road),
        neighbours: neighbours(&ego, others),
        ..Observation::default()
    };
    let cavs = agents
        .iter()
        .copied()
        .enumerate()
        .filter(|&(k, a)| a.is_cav && k != i);
    select_cavs(&ego, cavs, chosen);
    for (n, &c) in chosen.iter().enumerate() {
        let id = &now.vehicles[c].id;
        for (k, later) in (1..=PREVIEW).zip(buffer.range(1..=PREVIEW)) {
            obs.cavs[k - 1][n] = match later.index.get(id) {
                Some(&m) => {
                    let a = Agent::of(&later.scene.vehicles[m], w);
                    cav_node(&ego, k, dt, a.s, a.y, a.speed)
                }
                None => CavNode::default(),
            };
        }
    }
    debug_assert!(chosen.len() <= CAV_NODES);
    obs
}

impl Observer for Recorder {
    fn observe(&mut self, scene: &Scene) {
        let index = scene
            .vehicles
            .iter()
            .enumerate()
            .map(|(i, v)| (v.id.clone(), i))
            .collect();
        self.buffer.push_back(Buffered {
            scene: scene.clone(),
            index,
        });
        if self.buffer.len() == PREVIEW + 1 {
            self.emit();
            self.buffer.pop_front();
        }
        self.step += 1;
    }
}

/// Which episodes to run: episode e uses seed `seed_base + e`, planner `planners[e mod P]`,
/// α `alphas[(e / P) mod A]` and λ `lambdas[(e / (P·A)) mod L]`, so every combination recurs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CollectPlan {
    /// Number of episodes.
    pub episodes: usize,
    /// Seed of episode 0; episode e uses `seed_base + e`.
    pub seed_base: u64,
    /// Planners driving the CAVs (names as on the command line), cycled fastest.
    pub planners: Vec<String>,
    /// CAV penetrations α (share of inserted vehicles that are CAVs) to cycle through.
    pub alphas: Vec<f64>,
    /// Total arrival rates λ (veh/h) to cycle through, slowest.
    pub lambdas: Vec<f64>,
    /// Episode length (steps).
    pub steps: u32,
    /// Probability of keeping a main-road sample without a lane change.
    pub main_negative_keep: f64,
}

/// Seeds the committed models were trained on start here.
pub const TRAIN_SEED_BASE: u64 = 10_000;
/// Evaluation data is collected from here on: never used for training.
pub const EVAL_SEED_BASE: u64 = 90_000;

impl Default for CollectPlan {
    fn default() -> Self {
        CollectPlan {
            episodes: 100,
            seed_base: TRAIN_SEED_BASE,
            planners: vec!["idm-mobil".into(), "bk-mastar".into()],
            alphas: vec![0.2, 0.4, 0.6, 0.8],
            lambdas: vec![2500.0, 3000.0],
            steps: 400,
            main_negative_keep: 0.1,
        }
    }
}

/// One episode of a plan.
#[derive(Debug, Clone, PartialEq)]
pub struct EpisodeSpec {
    /// Seed of the episode's demand and HDV behaviour.
    pub seed: u64,
    /// Planner driving the CAVs.
    pub planner: String,
    /// CAV penetration α.
    pub alpha: f64,
    /// Total arrival rate λ (veh/h); none on a user's scenario, whose routes are its demand.
    pub lambda: Option<f64>,
}

impl CollectPlan {
    /// The episode numbered `e`.
    pub fn episode(&self, e: usize) -> EpisodeSpec {
        let p = self.planners.len().max(1);
        let a = self.alphas.len().max(1);
        let l = self.lambdas.len().max(1);
        EpisodeSpec {
            seed: self.seed_base + e as u64,
            planner: self.planners[e % p].clone(),
            alpha: self.alphas[(e / p) % a],
            lambda: self.lambdas.get((e / (p * a)) % l).copied(),
        }
    }
}

/// Why collection stopped.
#[derive(Debug, thiserror::Error)]
pub enum CollectError {
    /// The plan itself is unusable (empty lists, keep share outside (0, 1]).
    #[error("collection plan: {0}")]
    Plan(String),
    /// A planner name the controller does not know.
    #[error(transparent)]
    Planner(#[from] controller::UnknownPlanner),
    /// An episode of the plan failed to run.
    #[error(
        "episode {episode} ({planner}, α = {alpha}{}, seed {seed}) failed: {cause}",
        lambda.map(|l| format!(", λ = {l}")).unwrap_or_default()
    )]
    Episode {
        /// Episode number within the plan.
        episode: usize,
        /// Its planner.
        planner: String,
        /// Its CAV penetration α.
        alpha: f64,
        /// Its arrival rate λ (veh/h), on the paper's demand.
        lambda: Option<f64>,
        /// Its seed.
        seed: u64,
        /// What went wrong.
        cause: Box<EpisodeError>,
    },
    /// A file of the scenario could not be read for the data's record of it.
    #[error(transparent)]
    Scenario(#[from] crate::sumo::sumocfg::SumoConfigError),
}

/// What the collector writes into a data file's header.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CollectMeta {
    /// The plan the data was collected with.
    pub plan: CollectPlan,
    /// The predictor of the bk-mastar rollouts (always the constant-speed one, so the data never
    /// depends on a learned model).
    pub rollout_predictor: String,
    /// Totals over all episodes.
    pub stats: CollectStats,
    /// Version of bkpbs that collected the data.
    pub bkpbs_version: String,
    /// What the data was collected on (step length, scenario, seeds, command, versions), which
    /// `bkpbs train` carries into the model; absent in data files written before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trained_on: Option<crate::config::TrainedOn>,
}

/// Runs the plan's episodes one after another (libsumo: one simulation per process) on top of
/// `base` (scenario α, λ, seed and steps are set per episode), calling `progress` after each.
pub fn collect(
    base: &Config,
    plan: &CollectPlan,
    mut progress: impl FnMut(usize, &CollectStats),
) -> Result<Dataset, CollectError> {
    check_plan(plan, base.scenario.sumocfg.is_some())?;
    let seeds = super::provenance::seed_range(plan.seed_base, plan.episodes as u64);
    let trained_on = super::provenance::of_episodes(base, seeds, plan.episodes as u64)?;
    let mut samples = Vec::new();
    let mut stats = CollectStats::default();
    for e in 0..plan.episodes {
        let mut rec = collect_episode(base, plan, e)?;
        rec.stats.episodes = 1;
        stats += rec.stats;
        samples.append(&mut rec.samples);
        progress(e + 1, &stats);
    }
    let meta = CollectMeta {
        plan: plan.clone(),
        rollout_predictor: "constant".into(),
        stats,
        bkpbs_version: env!("CARGO_PKG_VERSION").into(),
        trained_on: Some(trained_on),
    };
    Ok(Dataset {
        meta: serde_json::to_string(&meta).expect("metadata serialises"),
        samples,
    })
}

/// A plan that names at least one planner, α and λ (no λ on a user's scenario, `scenario`),
/// known planners only, and a negative sampling share in (0, 1].
fn check_plan(plan: &CollectPlan, scenario: bool) -> Result<(), CollectError> {
    if plan.planners.is_empty() || plan.alphas.is_empty() {
        return Err(CollectError::Plan(
            "planners and alphas need at least one value each".into(),
        ));
    }
    match (scenario, plan.lambdas.is_empty()) {
        (false, true) => {
            return Err(CollectError::Plan("lambdas need at least one value".into()));
        }
        (true, false) => {
            return Err(CollectError::Plan(
                "lambdas do not apply to a scenario of your own (its routes are its demand)".into(),
            ));
        }
        _ => {}
    }
    if !(plan.main_negative_keep > 0.0 && plan.main_negative_keep <= 1.0) {
        return Err(CollectError::Plan(format!(
            "main_negative_keep = {} must lie in (0, 1]",
            plan.main_negative_keep
        )));
    }
    for p in &plan.planners {
        p.parse::<controller::PlannerKind>()?;
    }
    Ok(())
}

/// Episode `e` of the plan, run with the constant-speed predictor (so the data never depends
/// on a learned model) and recorded: on the paper's demand its one merge, on a user's scenario
/// (`scenario.sumocfg`, whose routes are the demand: the plan's λ does not apply) each merge
/// region's scenes apart, the regions' samples in region order.
fn collect_episode(base: &Config, plan: &CollectPlan, e: usize) -> Result<Recorder, CollectError> {
    let spec = plan.episode(e);
    let mut config = base.clone();
    config.scenario.alpha = spec.alpha;
    if let Some(lambda) = spec.lambda {
        config.scenario.lambda = lambda;
    }
    config.scenario.seed = spec.seed;
    config.scenario.steps = plan.steps;
    config.predictor.kind = PredictorKind::Constant;
    let fail = |cause: EpisodeError| CollectError::Episode {
        episode: e,
        planner: spec.planner.clone(),
        alpha: spec.alpha,
        lambda: spec.lambda,
        seed: spec.seed,
        cause: Box::new(cause),
    };
    config.validate().map_err(|c| fail(c.into()))?;
    let mut recorders = PerRegion::new(|region: usize| {
        // Each region thins on a stream of its own.
        let seed = spec.seed.wrapping_add((region as u64) << 32);
        Recorder::new(e as u32, seed, config.scenario.dt, plan.main_negative_keep)
    });
    if config.scenario.sumocfg.is_some() {
        episode::sumocfg::run_observed(&config, &spec.planner, &mut recorders).map_err(fail)?;
    } else {
        let demand = crate::episode::demand::generate_for(&config).map_err(fail)?;
        episode::run_observed(
            &config,
            Driver::Named(&spec.planner),
            &demand,
            &mut recorders,
        )
        .map_err(fail)?;
    }
    Ok(into_one(recorders.into_regions()))
}

/// Every region's samples, in region order, and their counts together.
fn into_one(regions: Vec<Recorder>) -> Recorder {
    let mut regions = regions.into_iter();
    let mut one = regions.next().expect("region 0's recorder at least");
    for mut r in regions {
        one.samples.append(&mut r.samples);
        one.stats += r.stats;
    }
    one
}

/// The collection metadata of a data file, if it has any.
pub fn meta_of(data: &Dataset) -> Option<CollectMeta> {
    serde_json::from_str(&data.meta).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scene::Origin;

    /// A scene holding one HDV called `id`.
    fn scene_of(id: &str, time: f64) -> Scene {
        let v = VehicleState::on_lane(id, Kind::Hdv, Origin::Main, 100.0, 1, 30.0);
        Scene::on_paper_road(time, vec![v])
    }

    #[test]
    fn each_region_is_recorded_apart_and_the_regions_samples_come_in_region_order() {
        let mut recorders =
            PerRegion::new(|region: usize| Recorder::new(7, 100 + region as u64, 0.2, 1.0));
        for k in 0..3 {
            let t = f64::from(k) * 0.2;
            recorders.observe_region(0, &scene_of("a", t));
            recorders.observe_region(1, &scene_of("b", t));
        }
        let mut regions = recorders.into_regions();
        assert_eq!(regions.len(), 2);
        for (r, id) in regions.iter().zip(["a", "b"]) {
            assert_eq!(r.step, 3, "each region's recorder saw its own three scenes");
            let ids: Vec<&str> = (r.buffer.iter())
                .flat_map(|b| b.scene.vehicles.iter().map(|v| &*v.id))
                .collect();
            assert!(ids.iter().all(|i| *i == id), "region of {id} saw {ids:?}");
        }
        regions[0].samples.push(Sample {
            episode: 7,
            step: 0,
            subset: Subset::Main,
            label: false,
            weight: 1.0,
            obs: Default::default(),
        });
        let mut second = regions[0].samples[0].clone();
        second.step = 1;
        regions[1].samples.push(second);
        let one = into_one(regions);
        let steps: Vec<u32> = one.samples.iter().map(|s| s.step).collect();
        assert_eq!(steps, [0, 1]);
    }

    #[test]
    fn a_plan_on_a_scenario_of_your_own_has_no_lambda_and_one_on_the_paper_demand_has_one() {
        let plan = CollectPlan::default();
        assert!(check_plan(&plan, false).is_ok());
        let refused = check_plan(&plan, true).unwrap_err().to_string();
        assert!(refused.contains("lambdas do not apply"), "{refused}");
        let own = CollectPlan {
            lambdas: Vec::new(),
            ..plan
        };
        assert!(check_plan(&own, true).is_ok());
        assert_eq!(own.episode(5).lambda, None);
        assert!(check_plan(&own, false).is_err());
    }
}
