//! `bk-mastar`: every CAV planned on its own by M-A* against the predicted trajectories of all
//! other vehicles (HDVs by the predictor, other CAVs at constant speed in their lane), with no
//! conflict resolution between CAVs (paper section V.C). The first primitive of each plan is
//! executed; a CAV without a plan in either phase brakes at the emergency deceleration, and the
//! step records a fallback. What it shares with `bk-pbs` lives in
//! [`crate::controller::search_planner`].

use crate::config::Config;
use crate::controller::search_planner::{Round, RoundPlanner, SearchCore, SearchPlanner};
use crate::controller::{Command, Source};
use crate::model::road::Road;
use crate::model::scene::{Kind, Scene};
use crate::model::trajectory::Trajectory;
use crate::planner::lane_end::{held_up_at_lane_end, merge_order, standing_in_target_lane};
use crate::predict::{ConstantSpeed, Predictor};

/// Decentralised M-A* planner.
pub type BkMastar = SearchPlanner<EachAlone>;

impl BkMastar {
    /// With `predictor` for HDVs, on `road`.
    pub fn new(config: &Config, predictor: Box<dyn Predictor>, road: &Road) -> Self {
        let rounds = EachAlone {
            others: ConstantSpeed::new(config),
        };
        SearchPlanner::with_rounds(config, predictor, road, rounds)
    }
}

/// BK-M-A*'s round: each CAV planned alone against everyone else's prediction.
pub struct EachAlone {
    /// How the other CAVs are predicted: at constant speed in their lane.
    others: ConstantSpeed,
}

impl EachAlone {
    /// Every vehicle's predicted trajectory over the check horizon.
    fn predictions(&self, core: &SearchCore, scene: &Scene) -> Vec<Trajectory> {
        let horizon = core.horizon();
        scene
            .vehicles
            .iter()
            .enumerate()
            .map(|(j, v)| match v.kind {
                Kind::Hdv => core.predictor.predict(scene, j, &[], horizon),
                Kind::Cav => self.others.predict(scene, j, &[], horizon),
            })
            .collect()
    }
}

impl RoundPlanner for EachAlone {
    const NAME: &'static str = "bk-mastar";

    fn plan_round(
        &mut self,
        core: &SearchCore,
        scene: &Scene,
        round: &mut Round,
        out: &mut Vec<Command>,
    ) {
        let predictions = self.predictions(core, scene);
        let idm = &core.config.idm;
        let lane_end = merge_order(scene, idm.min_gap, idm.decel);
        let waiting = |r: usize| standing_in_target_lane(scene, r, core.horizon(), core.dt());
        let yielded_to: Vec<(usize, Trajectory)> = lane_end
            .iter()
            .map(|&(hi, lo)| (lo, hi))
            .filter(|&(_, hi)| held_up_at_lane_end(scene, &scene.vehicles[hi]))
            .map(|(lo, r)| (lo, waiting(r)))
            .collect();
        for (i, v) in scene.vehicles.iter().enumerate() {
            if v.kind != Kind::Cav {
                continue;
            }
            // At a lane end (see `merge_order`): the ones that wait for this CAV are no
            // obstacle to it, and the merger it yields to stands in lane 1 already.
            let mut obstacles: Vec<&Trajectory> = predictions
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i && !lane_end.contains(&(i, j)))
                .map(|(_, t)| t)
                .collect();
            obstacles.extend(yielded_to.iter().filter(|(lo, _)| *lo == i).map(|(_, t)| t));
            let req = core
                .lane_changes
                .request(scene, i, core.dt(), &obstacles, core.guard());
            let result = core.planner.plan(&req);
            round.count_search(result.as_ref());
            let others = predictions.iter().enumerate();
            let plan = result.as_ref().ok();
            out.push(round.command(core, scene, i, plan, Source::Plan, others));
        }
    }
}
