//! Experience from one SUMO episode: every CAV driven by the policy (shared weights, as at test
//! time), each CAV's decisions a [`Segment`] with the rewards of [`RewardSettings`].
//!
//! A CAV's segment ends with its collision (terminal, the penalty paid), or, when it arrives or
//! the episode ends, at its last decision, whose value bootstraps what follows: the road goes on
//! past the section, so arriving is not an end of the task (else the policy would learn that
//! lingering collects more reward).
//!
//! On a user's scenario (`scenario.sumocfg`) each merge region's CAVs are driven by a controller
//! of the region's own, as the `rl-ppo` planner drives them there, and each region's CAVs give
//! their segments apart (a CAV driving through two regions gives one in each).

use std::collections::HashSet;
use std::sync::{Arc, Mutex, PoisonError};

use serde::{Deserialize, Serialize};

use super::env::{agent_demand, agent_fleet, Agents};
use super::reward::RewardSettings;
use super::{Segment, Step};
use crate::config::Config;
use crate::controller::rl_ppo::{Choice, Decision, RlPpo};
use crate::controller::{Command, Controller};
use crate::episode::metrics::Outcome;
use crate::episode::round::Round;
use crate::episode::{self, sumocfg, Driver, EpisodeError, NoObserver};
use crate::model::scene::Scene;
use crate::planner::primitives::Primitive;
use crate::policy::network::ActorCritic;

/// Totals of one or more episodes, for the learning curve and evaluations.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct RolloutStats {
    /// Episodes run.
    pub episodes: u64,
    /// CAVs that made at least one decision.
    pub agents: u64,
    /// Agent steps (decisions): the environment steps PPO counts.
    pub steps: u64,
    /// Sum over CAVs of their undiscounted return.
    pub return_sum: f64,
    /// CAVs removed in a collision.
    pub crashed: u64,
    /// Sum of the CAVs' speeds over their decisions (m/s).
    pub speed_sum: f64,
    /// Wall time of the episodes (s).
    pub wall_s: f64,
}

impl RolloutStats {
    /// Adds `o`'s totals to these.
    pub fn add(&mut self, o: &RolloutStats) {
        self.episodes += o.episodes;
        self.agents += o.agents;
        self.steps += o.steps;
        self.return_sum += o.return_sum;
        self.crashed += o.crashed;
        self.speed_sum += o.speed_sum;
        self.wall_s += o.wall_s;
    }

    /// Mean return per CAV.
    pub fn mean_return(&self) -> f64 {
        self.return_sum / self.agents.max(1) as f64
    }

    /// Share of CAVs that crashed.
    pub fn collision_rate(&self) -> f64 {
        self.crashed as f64 / self.agents.max(1) as f64
    }

    /// Mean CAV speed over decisions (m/s).
    pub fn mean_speed(&self) -> f64 {
        self.speed_sum / self.steps.max(1) as f64
    }
}

/// One episode's experience.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Rollout {
    /// Each CAV's decisions (empty unless the policy was sampled).
    pub segments: Vec<Segment>,
    /// The episode's totals.
    pub stats: RolloutStats,
}

/// Runs the episode `config` describes with its CAVs (every one, or the one of
/// [`Agents::Single`] among HDVs) choosing by `choice` from `net`, and returns its experience
/// (segments only when sampling: PPO trains on-policy).
///
/// # Errors
/// SUMO failing, or an invalid configuration.
pub fn run(
    config: &Config,
    net: Arc<ActorCritic>,
    choice: Choice,
    reward: &RewardSettings,
    agents: Agents,
) -> Result<Rollout, EpisodeError> {
    config.validate()?;
    let keep_segments = matches!(choice, Choice::Sample(_));
    let ran = match config.scenario.sumocfg.is_some() {
        true => scenario_episode(config, net, choice, agents)?,
        false => paper_episode(config, net, choice, agents)?,
    };
    let mut out = Rollout::default();
    out.stats.episodes = 1;
    out.stats.wall_s = ran.wall_s;
    for (id, decisions) in ran.decisions {
        let crashed = ran.crashed.contains(&*id);
        let seg = segment(&decisions, crashed, reward);
        out.stats.agents += 1;
        out.stats.steps += decisions.len() as u64;
        out.stats.crashed += u64::from(crashed);
        out.stats.speed_sum += decisions.iter().map(|d| d.speed).sum::<f64>();
        out.stats.return_sum += seg.steps.iter().map(|s| f64::from(s.reward)).sum::<f64>();
        if keep_segments && !seg.steps.is_empty() {
            out.segments.push(seg);
        }
    }
    Ok(out)
}

/// What the CAVs of one episode decided, and which of them crashed.
struct Decided {
    /// (vehicle, its decisions), as the controllers recorded them.
    decisions: Vec<(Arc<str>, Vec<Decision>)>,
    /// The vehicles removed in a collision.
    crashed: HashSet<String>,
    /// The episode's wall time (s).
    wall_s: f64,
}

/// The vehicles of `outcomes` (id, outcome) that crashed.
fn crashed<'a>(outcomes: impl Iterator<Item = (&'a String, Outcome)>) -> HashSet<String> {
    outcomes
        .filter(|(_, o)| *o == Outcome::Crashed)
        .map(|(id, _)| id.clone())
        .collect()
}

/// The episode on the paper's demand, one controller driving its CAVs.
fn paper_episode(
    config: &Config,
    net: Arc<ActorCritic>,
    choice: Choice,
    agents: Agents,
) -> Result<Decided, EpisodeError> {
    let mut ctl = RlPpo::new(config, net, choice, true);
    let demand = agent_demand(config, agents)?;
    let result = episode::run_observed(config, Driver::Given(&mut ctl), &demand, &mut NoObserver)?;
    Ok(Decided {
        decisions: ctl.take_record().vehicles,
        crashed: crashed(result.vehicles.iter().map(|v| (&v.id, v.outcome))),
        wall_s: result.timing.wall_s,
    })
}

/// The episode on the user's scenario of `config`, each region's CAVs driven by a controller
/// of its own; the regions' decisions in region order.
fn scenario_episode(
    config: &Config,
    net: Arc<ActorCritic>,
    choice: Choice,
    agents: Agents,
) -> Result<Decided, EpisodeError> {
    let controllers = Arc::new(Mutex::new(Vec::new()));
    let round = RegionControllers {
        controllers: Arc::clone(&controllers),
        net,
        choice,
    };
    let result = sumocfg::run_together(config, "rl-ppo", Box::new(round), agent_fleet(agents))?;
    let mut controllers = controllers.lock().unwrap_or_else(PoisonError::into_inner);
    Ok(Decided {
        decisions: (controllers.iter_mut())
            .flat_map(|c| c.take_record().vehicles)
            .collect(),
        crashed: crashed(result.vehicles.iter().map(|v| (&v.id, v.outcome))),
        wall_s: result.timing.wall_s,
    })
}

/// Plans every merge region of a scenario with a recording [`RlPpo`] of its own, made with the
/// region's configuration at the first round; the caller shares them, to read their records
/// once the episode is over.
struct RegionControllers {
    controllers: Arc<Mutex<Vec<RlPpo>>>,
    net: Arc<ActorCritic>,
    choice: Choice,
}

impl Round for RegionControllers {
    fn plan(
        &mut self,
        regions: &[(&Config, &Scene)],
        _crashed: &[Arc<str>],
        out: &mut [Vec<Command>],
    ) {
        let mut controllers = self
            .controllers
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        for (k, (config, _)) in regions.iter().enumerate().skip(controllers.len()) {
            let choice = region_choice(&self.choice, k);
            controllers.push(RlPpo::new(config, Arc::clone(&self.net), choice, true));
        }
        for ((c, (_, scene)), out) in controllers.iter_mut().zip(regions).zip(out) {
            c.plan(scene, out);
        }
    }
}

/// Region `k`'s way of choosing: `choice` itself for region 0, a random stream of its own
/// (`choice`'s stream + `k`) for each further region.
fn region_choice(choice: &Choice, k: usize) -> Choice {
    let own = |rng: &rand_chacha::ChaCha8Rng| {
        let mut r = rng.clone();
        r.set_stream(rng.get_stream().wrapping_add(k as u64));
        r
    };
    match choice {
        Choice::Sample(rng) => Choice::Sample(own(rng)),
        Choice::Random(rng) => Choice::Random(own(rng)),
        other => other.clone(),
    }
}

/// The segment of one CAV's `decisions`: each step's reward read off the next decision's state;
/// the last decision ends it (collision) or only bootstraps it (otherwise).
pub fn segment(decisions: &[Decision], crashed: bool, reward: &RewardSettings) -> Segment {
    let step = |d: &Decision, r: f64| Step {
        obs: d.obs.clone(),
        mask: d.mask.to_vec(),
        action: d.action,
        log_prob: d.log_prob,
        value: d.value,
        reward: r as f32,
        forced: d.forced,
    };
    let changed =
        |d: &Decision| !d.forced && Primitive::ALL[usize::from(d.action)].is_lane_change();
    let mut steps: Vec<Step> = decisions
        .windows(2)
        .map(|w| {
            step(
                &w[0],
                reward.step(w[1].speed, w[1].merge_progress, changed(&w[0])),
            )
        })
        .collect();
    match decisions.last() {
        Some(last) if crashed => {
            steps.push(step(last, -reward.collision_penalty));
            Segment {
                steps,
                terminal: true,
                bootstrap: 0.0,
            }
        }
        Some(last) => Segment {
            steps,
            terminal: false,
            bootstrap: last.value,
        },
        None => Segment {
            steps,
            terminal: false,
            bootstrap: 0.0,
        },
    }
}
