//! Controllers: a scene in, one maneuver per CAV out.
//!
//! Every planner of the project implements [`Controller`]; the episode runner applies what it
//! returns through SUMO's speed and lane-change calls. New planners are added to
//! [`PlannerKind`], the one list of them.

pub mod bk_mastar;
pub mod bk_pbs;
pub mod execute;
pub mod idm;
pub mod idm_mobil;
pub mod lane_claims;
pub mod merging;
pub mod mobil;
pub mod planner_kind;
pub mod rl_ppo;
pub mod search_planner;
pub mod shield;
pub mod sumo_native;

use crate::config::Config;
use crate::model::road::Road;
use crate::model::scene::Scene;
use crate::model::trajectory::Trajectory;
use crate::predict::PredictorError;

pub use planner_kind::{PlannerKind, UnknownPlanner, PLANNERS};

/// A lateral move to the neighbouring lane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LaneChange {
    /// To the lane on the left (lane index + 1).
    Left,
    /// To the lane on the right (lane index − 1).
    Right,
}

impl LaneChange {
    /// Road-frame lane offset of the move.
    pub fn offset(self) -> i32 {
        match self {
            LaneChange::Left => 1,
            LaneChange::Right => -1,
        }
    }

    /// The move from lane `from` to the next lane `to`, if they are neighbours.
    pub fn between(from: i32, to: i32) -> Option<LaneChange> {
        match to - from {
            1 => Some(LaneChange::Left),
            -1 => Some(LaneChange::Right),
            _ => None,
        }
    }
}

/// What one CAV does during the next step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Maneuver {
    /// Speed at the end of the next step (m/s).
    pub speed: f64,
    /// Start a lane change now.
    pub lane_change: Option<LaneChange>,
}

/// A maneuver for the vehicle at `vehicle` in the scene's vehicle list.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    /// Index of the CAV in the scene's vehicle list ([`Scene::vehicles`]).
    pub vehicle: usize,
    /// What the CAV does during the next step.
    pub maneuver: Maneuver,
    /// Where the maneuver came from (traces and collision forensics).
    pub source: Source,
}

/// Where a CAV's maneuver came from, so a trace can say why a CAV did what it did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Source {
    /// BK-PBS: the plan of the conflict-free node.
    PbsSolution,
    /// BK-PBS: the plan of the best node of a round that found no conflict-free one.
    PbsBestNode,
    /// BK-PBS: planned alone against every other trajectory after the round left it without
    /// a plan or in conflict.
    Repair,
    /// BK-M-A*: the CAV's own M-A* plan.
    Plan,
    /// No plan at all: braking at the emergency deceleration.
    Brake,
    /// The safety shield replaced the planned first move.
    Shield,
    /// A lane change under way, continued.
    Continuation,
    /// A rule-based controller (idm-mobil, test controllers).
    Rule,
    /// The RL-PPO policy's choice.
    Policy,
}

impl Source {
    /// The name used in traces.
    pub fn as_str(self) -> &'static str {
        match self {
            Source::PbsSolution => "pbs-solution",
            Source::PbsBestNode => "pbs-best-node",
            Source::Repair => "repair",
            Source::Plan => "plan",
            Source::Brake => "brake",
            Source::Shield => "shield",
            Source::Continuation => "continuation",
            Source::Rule => "rule",
            Source::Policy => "policy",
        }
    }
}

/// What a planner believed about one CAV in its last round: the trajectory it planned for it
/// and the trajectories it predicted (or planned) for the vehicles it checked it against.
/// Collected only while tracing ([`Controller::set_tracing`]).
#[derive(Debug, Clone)]
pub struct CavBelief {
    /// Scene index of the CAV.
    pub vehicle: usize,
    /// The trajectory planned for the CAV; `None` when it had no plan (it braked).
    pub planned: Option<Trajectory>,
    /// (scene index, trajectory) of the other vehicles.
    pub others: Vec<(usize, Trajectory)>,
}

/// Who drives the CAVs in SUMO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CavHandling {
    /// SUMO's own models with all of SUMO's safety checks (the `sumo` reference controller).
    Sumo,
    /// The controller's commands alone: SUMO's speed and lane-change checks are off for CAVs,
    /// so the controller's quality decides collisions.
    Commanded,
}

/// Defines [`PlanStats`] from one list of (field, `episode.csv` column): the struct, its serde
/// names (the episode summary's columns) and its field-by-field sum, so a new count is written
/// once and can be neither left out of the sum nor out of the CSV.
macro_rules! plan_stats {
    ($($(#[doc = $doc:literal])* $field:ident => $column:literal,)*) => {
        /// Search effort of one planning round (deterministic counts, reported in
        /// `episode.csv` under their serde names).
        #[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
        pub struct PlanStats {
            $($(#[doc = $doc])* #[serde(rename = $column)] pub $field: u64,)*
        }

        impl std::ops::AddAssign for PlanStats {
            fn add_assign(&mut self, o: Self) {
                $(self.$field += o.$field;)*
            }
        }
    };
}

plan_stats! {
    /// Single-CAV searches (M-A* calls).
    searches => "plan_searches",
    /// Nodes expanded over all searches.
    nodes_expanded => "plan_nodes_expanded",
    /// Plans that needed phase 2.
    phase2_plans => "plan_phase2",
    /// CAVs with no plan at all, which braked at the emergency deceleration.
    fallbacks => "plan_fallbacks",
    /// BK-PBS: high-level nodes expanded.
    pbs_nodes => "pbs_nodes",
    /// BK-PBS: depth of the chosen node (summed over steps in episode totals).
    pbs_depth => "pbs_depth_sum",
    /// HDV predictions made (BK-PBS: root and conditioned re-predictions).
    predictions => "predictions",
    /// BK-PBS rounds that ended without a conflict-free node (best node used).
    pbs_fallbacks => "pbs_fallbacks",
    /// BK-PBS rounds stopped by the optional wall-time budget.
    time_budget_hits => "time_budget_hits",
    /// CAV maneuvers the safety shield replaced ([`shield::Shielded`]).
    shield_overrides => "shield_overrides",
}

/// A CAV controller, called once per step.
pub trait Controller: Send {
    /// The name used on the command line and in CSV files.
    fn name(&self) -> &'static str;

    /// How SUMO must treat CAVs for this controller.
    fn handling(&self) -> CavHandling;

    /// Appends one command per CAV it controls to `out` (which arrives empty).
    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>);

    /// Wall time the safety shield took within the last `plan` call (ms; 0 unshielded): its
    /// cost, measured apart from the planner's.
    fn last_shield_ms(&self) -> f64 {
        0.0
    }

    /// The effort of the last `plan` call (none for rule-based controllers).
    fn last_stats(&self) -> PlanStats {
        PlanStats::default()
    }

    /// Asks the controller to keep what it believed in each round, for [`Controller::beliefs`].
    fn set_tracing(&mut self, _on: bool) {}

    /// What the last `plan` call believed about each CAV (empty unless tracing, and for
    /// controllers that do not plan trajectories).
    fn beliefs(&self) -> Vec<CavBelief> {
        Vec::new()
    }

    /// Tells the controller that the lane change it started for vehicle `id` in its last `plan`
    /// call was withdrawn (by the safety shield) and will not happen: the vehicle keeps its lane.
    fn lane_change_cancelled(&mut self, _id: &str) {}
}

/// A controller the caller keeps, lent to an episode: it is the controller it borrows.
impl<C: Controller + ?Sized> Controller for &mut C {
    fn name(&self) -> &'static str {
        (**self).name()
    }
    fn handling(&self) -> CavHandling {
        (**self).handling()
    }
    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>) {
        (**self).plan(scene, out);
    }
    fn last_shield_ms(&self) -> f64 {
        (**self).last_shield_ms()
    }
    fn last_stats(&self) -> PlanStats {
        (**self).last_stats()
    }
    fn set_tracing(&mut self, on: bool) {
        (**self).set_tracing(on);
    }
    fn beliefs(&self) -> Vec<CavBelief> {
        (**self).beliefs()
    }
    fn lane_change_cancelled(&mut self, id: &str) {
        (**self).lane_change_cancelled(id);
    }
}

/// Why a controller could not be built: an unknown name, or a predictor model or policy file
/// the configuration names that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The planner name is not one of [`PLANNERS`].
    #[error(transparent)]
    Unknown(#[from] UnknownPlanner),
    /// The predictor model the configuration names cannot be loaded or used.
    #[error(transparent)]
    Predictor(#[from] PredictorError),
    /// The RL policy file (`rl.policy`) cannot be loaded or used.
    #[error("rl.policy: {0}")]
    Policy(#[from] crate::policy::model_file::PolicyError),
}

/// Builds the controller called `name` ([`PlannerKind::build`] for names from outside:
/// settings files, Python).
///
/// # Errors
/// An unknown name, or a predictor model or policy file that cannot be used.
pub fn by_name(
    name: &str,
    config: &Config,
    road: &Road,
) -> Result<Box<dyn Controller>, BuildError> {
    name.parse::<PlannerKind>()?.build(config, road)
}

/// Checks, before any SUMO starts, that [`by_name`] will build `name` under `config`
/// ([`PlannerKind::check`]).
///
/// # Errors
/// As [`by_name`].
pub fn check(name: &str, config: &Config) -> Result<(), BuildError> {
    name.parse::<PlannerKind>()?.check(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_planner_builds_and_unknown_is_refused() {
        let c = Config::default();
        let road = Road::paper_default();
        for p in PLANNERS {
            check(p, &c).unwrap();
            assert_eq!(by_name(p, &c, &road).unwrap().name(), p);
        }
        assert!(check("bk-pbz", &c).is_err());
        let e = by_name("bk-pbz", &c, &road).err().unwrap().to_string();
        assert!(e.contains("bk-pbz") && e.contains("idm-mobil"), "{e}");
    }
}
