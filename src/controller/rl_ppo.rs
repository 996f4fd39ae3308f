//! The `rl-ppo` baseline (paper, "Planning Algorithms"): one policy, shared by every CAV,
//! picks a motion primitive for each CAV every step from what it observes
//! ([`crate::policy::observation`]); the primitive's first step is executed. A lane change,
//! once started, is continued at constant speed for its duration, as the planners do.
//!
//! At test time the policy acts greedily (its most probable primitive). In training it samples,
//! and the controller records every CAV's decisions for PPO ([`Decision`]). Two reference
//! policies share the machinery: uniformly random over the allowed primitives, and always idle.

use std::collections::HashMap;
use std::sync::Arc;

use nalgebra::DMatrix;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::{CavHandling, Command, Controller, LaneChange, Maneuver, Source};
use crate::config::Config;

use crate::model::scene::Scene;
use crate::planner::lane_changes::LaneChanges;
use crate::planner::primitives::Primitive;
use crate::policy::actions::{Mask, Rules, IDLE};
use crate::policy::mlp::Activations;
use crate::policy::network::{greedy, masked_log_softmax, sample, ActorCritic};
use crate::policy::observation::{observe, OBS_DIM};

/// How the controller picks a CAV's primitive.
#[derive(Debug, Clone)]
pub enum Choice {
    /// The policy's most probable primitive (evaluation: the `rl-ppo` planner).
    Greedy,
    /// A draw from the policy's distribution (training), from this random stream.
    Sample(ChaCha8Rng),
    /// Uniform over the allowed primitives (a reference policy).
    Random(ChaCha8Rng),
    /// Always idle: keep lane and speed (a reference policy).
    Idle,
}

/// One CAV's decision at one step, for PPO.
#[derive(Debug, Clone, PartialEq)]
pub struct Decision {
    /// Simulation time of the decision (s).
    pub time: f64,
    /// The observation the policy saw ([`OBS_DIM`] features).
    pub obs: Vec<f32>,
    /// The primitives allowed at the decision.
    pub mask: Mask,
    /// Index of the chosen primitive in [`Primitive::ALL`] ([`IDLE`] when forced).
    pub action: u8,
    /// Log-probability of `action` under the policy that chose it (0 when forced).
    pub log_prob: f32,
    /// The value network's estimate of the observation.
    pub value: f32,
    /// No choice was made: a lane change under way was continued.
    pub forced: bool,
    /// The CAV's state at the decision, for the reward of the previous step.
    pub speed: f64,
    /// On the merge lane, the share of the merge zone its front has driven; else `None`.
    pub merge_progress: Option<f64>,
}

/// Every CAV's decisions in order, CAVs in order of their first decision.
#[derive(Debug, Clone, Default)]
pub struct Record {
    /// (vehicle id, its decisions in time order), CAVs in order of their first decision.
    pub vehicles: Vec<(Arc<str>, Vec<Decision>)>,
    index: HashMap<Arc<str>, usize>,
}

impl Record {
    fn push(&mut self, id: &Arc<str>, d: Decision) {
        let k = *self.index.entry(id.clone()).or_insert_with(|| {
            self.vehicles.push((id.clone(), Vec::new()));
            self.vehicles.len() - 1
        });
        self.vehicles[k].1.push(d);
    }
}

/// On the merge lane (past the ramp edge), the share of the merge zone scene vehicle `i`'s front
/// has driven; elsewhere `None`. The reward's merge-deadline term reads it.
pub fn merge_progress(scene: &Scene, i: usize) -> Option<f64> {
    let v = &scene.vehicles[i];
    let merge = scene.road.zone_for(v.lane, v.front());
    let zone = merge.end - merge.start;
    (scene.road.is_auxiliary(v.lane) && !v.on_ramp).then(|| (v.front() - merge.start) / zone)
}

/// Turns a chosen primitive into the command SUMO executes, and keeps the lane changes under
/// way (which must be continued, at constant speed, for their duration): shared by the
/// controller and the stepped environment ([`crate::controller`]'s callers in `train::ppo`).
#[derive(Debug, Clone)]
pub struct Executor {
    /// The motion rules: allowed primitives and the speeds they lead to.
    pub rules: Rules,
    /// The lane changes under way, continued until they end.
    pub lane_changes: LaneChanges,
    lane_change_s: f64,
}

impl Executor {
    /// The executor for `config`'s rules, with no lane change under way.
    pub fn new(config: &Config) -> Executor {
        Executor {
            rules: Rules::from_config(config),
            lane_changes: LaneChanges::default(),
            lane_change_s: config.scenario.lane_change_steps() as f64 * config.scenario.dt,
        }
    }

    /// Forgets the lane changes that have ended (call once per step, first).
    pub fn forget_finished(&mut self, now: f64) {
        self.lane_changes.forget_finished(now);
    }

    /// Whether scene vehicle `i` is executing a lane change it was told to make.
    pub fn changing(&self, scene: &Scene, i: usize) -> bool {
        let id = &scene.vehicles[i].id;
        self.lane_changes
            .ongoing(id, scene.time, self.rules.dt)
            .is_some()
    }

    /// The command executing primitive `action` for scene vehicle `i` (a continuation when
    /// `forced`), remembering a lane change it starts.
    pub fn command(&mut self, scene: &Scene, i: usize, action: usize, forced: bool) -> Command {
        let v = &scene.vehicles[i];
        let p = Primitive::ALL[action];
        let lane_change = match p.lane_offset() {
            1 => Some(LaneChange::Left),
            -1 => Some(LaneChange::Right),
            _ => None,
        };
        if lane_change.is_some() {
            let target = v.lane + p.lane_offset();
            self.lane_changes
                .start(&v.id, scene.time, self.lane_change_s, target);
        }
        Command {
            vehicle: i,
            maneuver: Maneuver {
                speed: self.rules.next_speed(action, v.speed),
                lane_change,
            },
            source: if forced {
                Source::Continuation
            } else {
                Source::Policy
            },
        }
    }
}

/// The RL-PPO controller.
pub struct RlPpo {
    net: Arc<ActorCritic>,
    choice: Choice,
    executor: Executor,
    record: Option<Record>,
    actor_act: Activations,
    critic_act: Activations,
}

impl RlPpo {
    /// The controller of `net`, choosing by `choice`; `record`: keep every decision.
    pub fn new(config: &Config, net: Arc<ActorCritic>, choice: Choice, record: bool) -> Self {
        RlPpo {
            net,
            choice,
            executor: Executor::new(config),
            record: record.then(Record::default),
            actor_act: Activations::default(),
            critic_act: Activations::default(),
        }
    }

    /// The `rl-ppo` planner: the configured (or embedded) policy, greedy.
    pub fn from_config(config: &Config) -> Result<Self, crate::policy::model_file::PolicyError> {
        let net = crate::policy::model_file::load(config.rl.policy.as_deref(), config.scenario.dt)?;
        Ok(RlPpo::new(config, Arc::new(net), Choice::Greedy, false))
    }

    /// The decisions recorded so far (empty unless recording).
    pub fn take_record(&mut self) -> Record {
        self.record.take().unwrap_or_default()
    }

    /// The primitive for a CAV with `mask` and the policy's `log_probs`, and its log-probability
    /// under the policy.
    fn choose(&mut self, mask: &Mask, log_probs: &[f32]) -> usize {
        match &mut self.choice {
            Choice::Greedy => greedy(log_probs),
            Choice::Sample(rng) => sample(log_probs, rng.gen::<f64>()),
            Choice::Random(rng) => {
                let allowed: Vec<usize> = (0..mask.len()).filter(|&k| mask[k]).collect();
                allowed[rng.gen_range(0..allowed.len())]
            }
            Choice::Idle => IDLE,
        }
    }

    /// Observations of the CAVs at `cavs` (one column each) and whether each is mid change.
    fn observations(&self, scene: &Scene, cavs: &[usize]) -> (DMatrix<f32>, Vec<bool>) {
        let mut obs = DMatrix::zeros(OBS_DIM, cavs.len());
        let mut changing = Vec::with_capacity(cavs.len());
        for (col, &i) in cavs.iter().enumerate() {
            let ongoing = self.executor.changing(scene, i);
            observe(
                scene,
                i,
                ongoing,
                self.executor.rules.v_max,
                obs.column_mut(col).as_mut_slice(),
            );
            changing.push(ongoing);
        }
        (obs, changing)
    }
}

impl Controller for RlPpo {
    fn name(&self) -> &'static str {
        "rl-ppo"
    }

    fn handling(&self) -> CavHandling {
        CavHandling::Commanded
    }

    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>) {
        self.executor.forget_finished(scene.time);
        let cavs = scene.cav_indices();
        if cavs.is_empty() {
            return;
        }
        let (obs, changing) = self.observations(scene, &cavs);
        let net = Arc::clone(&self.net);
        let logits = net.logits(&obs, &mut self.actor_act);
        let values = if self.record.is_some() {
            net.values(&obs, &mut self.critic_act)
        } else {
            vec![0.0; cavs.len()]
        };
        for (col, &i) in cavs.iter().enumerate() {
            let v = &scene.vehicles[i];
            let mask = self.executor.rules.mask(scene, i);
            let log_probs = masked_log_softmax(logits.column(col).as_slice(), &mask);
            let forced = changing[col];
            let action = if forced {
                IDLE
            } else {
                self.choose(&mask, &log_probs)
            };
            if let Some(record) = &mut self.record {
                record.push(
                    &v.id,
                    Decision {
                        time: scene.time,
                        obs: obs.column(col).iter().copied().collect(),
                        mask,
                        action: action as u8,
                        log_prob: if forced { 0.0 } else { log_probs[action] },
                        value: values[col],
                        forced,
                        speed: v.speed,
                        merge_progress: merge_progress(scene, i),
                    },
                );
            }
            out.push(self.executor.command(scene, i, action, forced));
        }
    }

    fn lane_change_cancelled(&mut self, id: &str) {
        self.executor.lane_changes.cancel(id);
    }
}
