//! The episode thread's side of the stepped environment: each planning round, every CAV of
//! every region becomes an agent; their observations go to the caller, the actions come back,
//! and each region's executor turns them into the commands SUMO executes.
//!
//! [`Remote`] is the episode loop's [`Round`]: on the paper's merge its one region's scene, on
//! a user's scenario every merge region's scene at once, so that one decision covers every
//! agent, wherever it drives.

use std::sync::mpsc::{Receiver, Sender};
use std::sync::Arc;

use super::{Agent, Decision, Event};
use crate::config::Config;
use crate::controller::rl_ppo::{merge_progress, Executor};
use crate::controller::Command;
use crate::episode::round::Round;
use crate::model::scene::Scene;
use crate::policy::actions::IDLE;
use crate::policy::observation::{observe, OBS_DIM};

/// Sends the agents of each round, waits for their actions, commands them.
pub(super) struct Remote {
    /// One per region, made with the region's configuration at its first round.
    executors: Vec<Executor>,
    events: Sender<Event>,
    actions: Receiver<Vec<usize>>,
    /// The environment is gone: idle to the end.
    detached: bool,
}

impl Remote {
    pub(super) fn new(events: Sender<Event>, actions: Receiver<Vec<usize>>) -> Remote {
        Remote {
            executors: Vec::new(),
            events,
            actions,
            detached: false,
        }
    }

    /// One round over `regions` (configuration and scene each), `crashed` the vehicles removed
    /// in collisions since the last: each region's commands into its list of `out`.
    fn decide(
        &mut self,
        regions: &[(&Config, &Scene)],
        crashed: Vec<Arc<str>>,
        out: &mut [Vec<Command>],
    ) {
        for (config, _) in regions.iter().skip(self.executors.len()) {
            self.executors.push(Executor::new(config));
        }
        let mut seats = Vec::new();
        let mut agents = Vec::new();
        for (k, (_, scene)) in regions.iter().enumerate() {
            self.executors[k].forget_finished(scene.time);
            for i in scene.cav_indices() {
                agents.push(agent(&self.executors[k], scene, i));
                seats.push((k, i));
            }
        }
        if agents.is_empty() && crashed.is_empty() {
            return;
        }
        let forced: Vec<bool> = agents.iter().map(|a| a.forced).collect();
        // The region of the first agent is the one rendered.
        let shown = seats.first().map_or(0, |&(k, _)| k);
        let chosen = match (self.detached, regions.get(shown)) {
            (false, Some((_, scene))) => {
                let event = Event::Decide(Box::new(Decision {
                    scene: (*scene).clone(),
                    agents,
                    crashed,
                }));
                self.events
                    .send(event)
                    .ok()
                    .and_then(|()| self.actions.recv().ok())
            }
            _ => None,
        };
        self.detached |= chosen.is_none();
        let chosen = chosen.unwrap_or_else(|| vec![IDLE; seats.len()]);
        for ((&(k, i), a), f) in seats.iter().zip(chosen).zip(forced) {
            out[k].push(self.executors[k].command(regions[k].1, i, a, f));
        }
    }
}

impl Round for Remote {
    fn plan(
        &mut self,
        regions: &[(&Config, &Scene)],
        crashed: &[Arc<str>],
        out: &mut [Vec<Command>],
    ) {
        self.decide(regions, crashed.to_vec(), out);
    }
}

/// Scene vehicle `i`, a CAV, as the agent the caller decides for.
fn agent(executor: &Executor, scene: &Scene, i: usize) -> Agent {
    let v = &scene.vehicles[i];
    let forced = executor.changing(scene, i);
    let mut obs = vec![0.0; OBS_DIM];
    observe(scene, i, forced, executor.rules.v_max, &mut obs);
    Agent {
        id: v.id.clone(),
        obs,
        mask: executor.rules.mask(scene, i),
        forced,
        speed: v.speed,
        merge_progress: merge_progress(scene, i),
    }
}
