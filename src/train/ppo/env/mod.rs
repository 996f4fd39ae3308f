//! The merge scenario as a stepped RL environment, for Gymnasium and PettingZoo (the Python
//! package's `bkpbs.gym`): the caller picks every agent's primitive, one step at a time.
//!
//! The episode runs on its own thread, exactly as any episode (the runner, SUMO, metrics), with
//! a controller that hands each step's observations to the caller and waits for the actions.
//! Observations, action masks, lane-change execution and rewards are the Rust trainer's
//! ([`crate::policy`], [`RewardSettings`]), so an agent trained here faces the same task.
//!
//! Two agent sets: every CAV (PettingZoo), or one CAV among HDVs (Gymnasium; the paper trains
//! its RL-PPO "in a single CAV environment"): the first CAV of the demand inserted after the
//! warm-up, every other vehicle an HDV.
//!
//! On a user's scenario (`scenario.sumocfg`) the episode is `bkpbs episode --sumocfg`'s, every
//! merge region's CAVs the agents of one decision per step (each observed and executed in its
//! own region's frame); outside the regions SUMO drives them. The single agent is the first
//! CAV of the scenario's draw that departs after the warm-up with a route through a region.

use std::collections::{HashMap, HashSet};
use std::sync::mpsc::{self, Receiver, Sender, SyncSender};
use std::sync::Arc;
use std::thread::JoinHandle;

mod remote;

use super::reward::RewardSettings;
use crate::config::Config;
use crate::episode::demand::PlannedVehicle;
use crate::episode::sumocfg::{self, Fleet};
use crate::episode::{self, Driver, EpisodeError, NoObserver, Ran};
use crate::model::scene::{Kind, Scene};
use crate::planner::primitives::Primitive;
use crate::policy::actions::{Mask, IDLE};
use remote::Remote;

/// Which vehicles are agents.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Agents {
    /// One CAV among HDVs.
    Single,
    /// Every CAV.
    AllCavs,
}

/// One agent awaiting its action.
#[derive(Debug, Clone, PartialEq)]
pub struct Agent {
    /// The CAV's SUMO id.
    pub id: Arc<str>,
    /// Its observation vector (`OBS_DIM` values, the policy's input).
    pub obs: Vec<f32>,
    /// Which of the primitives it may choose now.
    pub mask: Mask,
    /// A lane change under way: its action is ignored (continued at constant speed).
    pub forced: bool,
    /// Its speed (m/s), for the reward.
    pub speed: f64,
    /// On the merge lane, the share of the merge zone its front has driven (the reward's
    /// deadline term); elsewhere `None`.
    pub merge_progress: Option<f64>,
}

/// What one step did to the agents that acted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepResult {
    /// (agent, reward) for every agent that acted.
    pub rewards: Vec<(Arc<str>, f64)>,
    /// Agents removed in a collision: their episode ended.
    pub terminated: Vec<Arc<str>>,
    /// Agents that left (arrived) or were still driving when the episode ended.
    pub truncated: Vec<Arc<str>>,
    /// The environment is over: no agent will act again.
    pub done: bool,
}

/// Why the environment cannot go on.
#[derive(Debug, thiserror::Error)]
pub enum EnvError {
    /// The episode itself failed (SUMO, configuration, demand).
    #[error(transparent)]
    Episode(#[from] EpisodeError),
    /// `step` got another number of actions than there are agents.
    #[error("expected {expected} actions, one per agent, got {got}")]
    Actions {
        /// Agents awaiting an action.
        expected: usize,
        /// Actions given.
        got: usize,
    },
    /// An action index outside the primitives.
    #[error("action {0} is not one of the 6 primitives (0–5)")]
    UnknownAction(usize),
    /// The episode thread stopped without reporting its end.
    #[error("the episode thread ended unexpectedly")]
    Lost,
    /// `step` called after the environment was done.
    #[error("the environment is done: reset it")]
    Done,
}

/// A step in which agents must decide: the scene, the agents, and the vehicles crashed since
/// the last one.
struct Decision {
    scene: Scene,
    agents: Vec<Agent>,
    crashed: Vec<Arc<str>>,
}

/// A step of the episode thread: agents to decide, or the end.
enum Event {
    Decide(Box<Decision>),
    Finished(Box<Result<Ran, EpisodeError>>),
}

/// A running episode stepped from outside.
pub struct MergeEnv {
    events: Receiver<Event>,
    /// Dropped when the environment closes: the episode thread then idles its agents.
    actions: Option<SyncSender<Vec<usize>>>,
    thread: Option<JoinHandle<()>>,
    agents: Vec<Agent>,
    scene: Option<Scene>,
    possible: Vec<Arc<str>>,
    /// The same ids, to tell a new one at once.
    known: HashSet<Arc<str>>,
    reward: RewardSettings,
    single: bool,
    done: bool,
    result: Option<Ran>,
}

impl MergeEnv {
    /// Starts the episode `config` describes and runs it to the first step with an agent.
    pub fn start(
        config: &Config,
        agents: Agents,
        reward: RewardSettings,
    ) -> Result<Self, EnvError> {
        config.validate().map_err(EpisodeError::from)?;
        let (event_tx, events) = mpsc::channel();
        let (actions, action_rx) = mpsc::sync_channel(1);
        let (thread, possible) = if config.scenario.sumocfg.is_some() {
            let config = config.clone();
            let run = move || scenario_thread(config, agents, event_tx, action_rx);
            // A scenario's flows decide their vehicles as it runs: its agents are known as
            // they come.
            (std::thread::spawn(run), Vec::new())
        } else {
            let demand = agent_demand(config, agents)?;
            let possible = demand
                .iter()
                .filter(|v| v.kind == Kind::Cav)
                .map(|v| Arc::from(v.id.as_str()))
                .collect();
            let config = config.clone();
            let run = move || episode_thread(config, demand, event_tx, action_rx);
            (std::thread::spawn(run), possible)
        };
        let mut env = MergeEnv {
            events,
            actions: Some(actions),
            thread: Some(thread),
            agents: Vec::new(),
            scene: None,
            known: possible.iter().cloned().collect(),
            possible,
            reward,
            single: agents == Agents::Single,
            done: false,
            result: None,
        };
        env.advance(&[])?;
        Ok(env)
    }

    /// Every vehicle that may become an agent (the demand's CAVs), in order of insertion; on a
    /// user's scenario, whose flows decide their vehicles as it runs, those that have been
    /// agents so far.
    pub fn possible_agents(&self) -> &[Arc<str>] {
        &self.possible
    }

    /// The agents of the current step.
    pub fn agents(&self) -> &[Agent] {
        &self.agents
    }

    /// The current step's scene (for rendering).
    pub fn scene(&self) -> Option<&Scene> {
        self.scene.as_ref()
    }

    /// The finished episode's results (metrics, vehicles), once done.
    pub fn result(&self) -> Option<&Ran> {
        self.result.as_ref()
    }

    /// Applies one primitive per agent (in [`MergeEnv::agents`]'s order; a masked-out one is
    /// replaced by idle, a forced agent's is ignored) and runs to the next step with an agent.
    pub fn step(&mut self, actions: &[usize]) -> Result<StepResult, EnvError> {
        if self.done {
            return Err(EnvError::Done);
        }
        if actions.len() != self.agents.len() {
            return Err(EnvError::Actions {
                expected: self.agents.len(),
                got: actions.len(),
            });
        }
        if let Some(&a) = actions.iter().find(|&&a| a >= Primitive::ALL.len()) {
            return Err(EnvError::UnknownAction(a));
        }
        let chosen: Vec<usize> = actions
            .iter()
            .zip(&self.agents)
            .map(|(&a, ag)| if ag.forced || !ag.mask[a] { IDLE } else { a })
            .collect();
        self.send(chosen.clone())?;
        self.advance(&chosen)
    }

    /// Waits for the next step with agents (or the end) and scores the previous agents' moves.
    fn advance(&mut self, chosen: &[usize]) -> Result<StepResult, EnvError> {
        let mut before = std::mem::take(&mut self.agents);
        let mut out = StepResult::default();
        loop {
            match self.events.recv().map_err(|_| EnvError::Lost)? {
                Event::Decide(d) => {
                    let Decision {
                        scene,
                        agents,
                        crashed,
                    } = *d;
                    self.score(&before, chosen, Some((&agents, &crashed)), &mut out);
                    before.clear();
                    self.scene = Some(scene);
                    if agents.is_empty() {
                        // Only news of a collision: nobody to ask, the episode goes on.
                        self.send(Vec::new())?;
                        continue;
                    }
                    self.learn_agents(&agents);
                    self.agents = agents;
                }
                Event::Finished(result) => {
                    self.score(&before, chosen, None, &mut out);
                    self.done = true;
                    self.join();
                    self.result = Some((*result)?);
                }
            }
            break;
        }
        // One agent among HDVs: its leaving ends the environment.
        if self.single && (!out.terminated.is_empty() || !out.truncated.is_empty()) {
            self.done = true;
            self.agents.clear();
        }
        out.done = self.done;
        Ok(out)
    }

    /// Adds the agents not seen before to the possible ones (a scenario's, as they come).
    fn learn_agents(&mut self, agents: &[Agent]) {
        for a in agents {
            if self.known.insert(a.id.clone()) {
                self.possible.push(a.id.clone());
            }
        }
    }

    /// Rewards of the agents `before` for their `chosen` actions, given the next step's agents
    /// and the vehicles crashed since (`None`: the episode ended).
    fn score(
        &self,
        before: &[Agent],
        chosen: &[usize],
        next: Option<(&[Agent], &[Arc<str>])>,
        out: &mut StepResult,
    ) {
        let now: HashMap<&str, &Agent> = next
            .map(|(agents, _)| agents.iter().map(|a| (&*a.id, a)).collect())
            .unwrap_or_default();
        for (prev, &a) in before.iter().zip(chosen) {
            let changed = !prev.forced && Primitive::ALL[a].is_lane_change();
            let id = prev.id.clone();
            if next.is_some_and(|(_, crashed)| crashed.contains(&prev.id)) {
                out.rewards
                    .push((id.clone(), -self.reward.collision_penalty));
                out.terminated.push(id);
            } else if let Some(n) = now.get(&*prev.id) {
                let r = self.reward.step(n.speed, n.merge_progress, changed);
                out.rewards.push((id, r));
            } else {
                // It left (arrived) or the episode ended: the state after the step is unknown,
                // so the step is scored on the state before it. (The Rust trainer instead drops
                // such a last step and bootstraps from its value; a Gymnasium step needs a reward.)
                let r = self.reward.step(prev.speed, prev.merge_progress, changed);
                out.rewards.push((id.clone(), r));
                out.truncated.push(id);
            }
        }
    }

    fn send(&self, actions: Vec<usize>) -> Result<(), EnvError> {
        let to = self.actions.as_ref().ok_or(EnvError::Done)?;
        to.send(actions).map_err(|_| EnvError::Lost)
    }

    /// Ends the episode early: every agent idles to its end (the simulation must close before
    /// another can start in this process); the episode's result stays readable. Also after a
    /// single agent has left, when the thread may be waiting for the actions of an agent that
    /// came back (a scenario's next region) or for news of a collision to be taken.
    pub fn close(&mut self) {
        self.actions = None;
        self.join();
        while let Ok(event) = self.events.try_recv() {
            if let Event::Finished(result) = event {
                self.result = self.result.take().or_else(|| (*result).ok());
            }
        }
        self.done = true;
        self.agents.clear();
    }

    fn join(&mut self) {
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for MergeEnv {
    fn drop(&mut self) {
        self.close();
    }
}

/// How long a single agent's episode runs before its agent may depart (s).
const WARMUP_S: f64 = 10.0;

/// The demand of the episode: as drawn, or with one agent CAV among HDVs (the first CAV
/// inserted after a 10 s warm-up; every other vehicle an HDV).
pub fn agent_demand(config: &Config, agents: Agents) -> Result<Vec<PlannedVehicle>, EpisodeError> {
    let mut demand = episode::demand::generate_for(config)?;
    if agents == Agents::Single {
        let ego = demand
            .iter()
            .position(|v| v.kind == Kind::Cav && v.depart >= WARMUP_S)
            .or_else(|| demand.iter().position(|v| v.depart >= WARMUP_S))
            .unwrap_or(0);
        for (k, v) in demand.iter_mut().enumerate() {
            v.kind = if k == ego { Kind::Cav } else { Kind::Hdv };
        }
    }
    Ok(demand)
}

fn episode_thread(
    config: Config,
    demand: Vec<PlannedVehicle>,
    events: Sender<Event>,
    actions: Receiver<Vec<usize>>,
) {
    let round = Box::new(Remote::new(events.clone(), actions));
    let driver = Driver::Round("rl-env", round);
    let result = episode::run_observed(&config, driver, &demand, &mut NoObserver);
    let _ = events.send(Event::Finished(Box::new(
        result.map(|r| Ran::Demand(Box::new(r))),
    )));
}

/// The CAVs of an episode on a user's scenario: the scenario's draw, or one among HDVs (the
/// first of the draw departing after the warm-up with a route through a region).
pub fn agent_fleet(agents: Agents) -> Fleet {
    match agents {
        Agents::Single => Fleet::single(WARMUP_S),
        Agents::AllCavs => Fleet::Drawn,
    }
}

/// The episode on the user's scenario of `config`, every region's CAVs (or one among HDVs)
/// the agents of one round per step.
fn scenario_thread(
    config: Config,
    agents: Agents,
    events: Sender<Event>,
    actions: Receiver<Vec<usize>>,
) {
    let round = Box::new(Remote::new(events.clone(), actions));
    let result = sumocfg::run_together(&config, "rl-env", round, agent_fleet(agents));
    let _ = events.send(Event::Finished(Box::new(
        result.map(|r| Ran::Scenario(Box::new(r))),
    )));
}
