//! A CAV's first moves, kept between the searches of one planning round.
//!
//! BK-PBS replans a CAV against one set of obstacles after another within a round; the moves
//! from its start (the primitives rolled out exactly from its state, the guard asked about each
//! lane change) do not depend on the obstacles, and working them out again each time was a sixth
//! of a round's time. So they are worked out once per phase and shared.

use std::sync::OnceLock;

use crate::model::kinematics::BicycleState;
use crate::planner::mastar::{FirstMove, Phase};

/// A move from a node: how it starts, the lane it ends in and its states at each step.
pub(super) type Move = (FirstMove, i32, Vec<BicycleState>);

/// The moves from one CAV's start, per phase, worked out once and shared by every search from
/// that start. It must belong to that start, its guard and its lane change under way.
#[derive(Debug, Default)]
pub struct FirstMoves {
    by_phase: [OnceLock<Vec<Move>>; 2],
}

impl FirstMoves {
    /// The moves of `phase` from this start: the kept ones, or those `work_out` gives, kept.
    pub(super) fn of_phase(&self, phase: Phase, work_out: impl FnOnce() -> Vec<Move>) -> Vec<Move> {
        self.by_phase[phase as usize].get_or_init(work_out).clone()
    }
}
