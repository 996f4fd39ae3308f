//! Planning every region of an episode in one round from outside the regions' own planners:
//! the stepped RL environment on a user's scenario (`train::ppo::env`), whose one decision per
//! step covers the agents of every region, as on the paper's merge it covers every CAV.

use std::sync::Arc;

use crate::config::Config;
use crate::controller::Command;
use crate::episode::region::Region;
use crate::model::scene::Scene;

/// One planning round over every region at once.
pub trait Round: Send {
    /// Each region's configuration and scene, in region order, and the vehicles removed in
    /// collisions since the last round; each region's commands go into its list of `out`
    /// (one per region, empty on entry).
    fn plan(
        &mut self,
        regions: &[(&Config, &Scene)],
        crashed: &[Arc<str>],
        out: &mut [Vec<Command>],
    );
}

/// One round of `round` over every region, each region's commands replaced by the round's.
pub(crate) fn plan_together(round: &mut dyn Round, regions: &mut [Region], crashed: &[Arc<str>]) {
    let mut commands: Vec<Vec<Command>> = regions
        .iter_mut()
        .map(|r| {
            let mut c = std::mem::take(&mut r.commands);
            c.clear();
            c
        })
        .collect();
    let views: Vec<(&Config, &Scene)> = regions
        .iter()
        .map(|r| (&r.config, &r.scene.scene))
        .collect();
    round.plan(&views, crashed, &mut commands);
    for (r, c) in regions.iter_mut().zip(commands) {
        r.commands = c;
    }
}
