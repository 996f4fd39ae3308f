//! What a BK-PBS round counts as a conflict, and finding them: the first step at which a CAV
//! is not clear of another agent by the safety rule (HDV–HDV pairs never count), pair by pair,
//! only for pairs whose stretches of road come within reach of each other.
//!
//! A node's conflicts decide where the search branches (the first, by step then pair) and when
//! it stops (none left); a child recomputes only the pairs that touch an agent it replanned.

use std::sync::Arc;

use rayon::prelude::*;

use crate::model::trajectory::Trajectory;
use crate::planner::pbs::track::Track;
use crate::planner::pbs::Problem;
use crate::planner::safety::REACH;

/// (step, i, j) with i < j.
pub(super) type Conflict = (usize, usize, usize);

/// Pairs of `agents` (ascending, each pair `(a, b)` with a < b) whose stretches of road
/// (their tracks' extents) come within `safety::REACH` of each other: a sweep in order of the
/// stretches' starts.
fn within_reach(tracks: &[Arc<Track>], agents: &[usize]) -> Vec<(usize, usize)> {
    let extent = |a: usize| tracks[a].extent;
    let mut order: Vec<usize> = agents.to_vec();
    order.sort_by(|&a, &b| extent(a).0.total_cmp(&extent(b).0).then(a.cmp(&b)));
    let mut pairs = Vec::new();
    for (k, &a) in order.iter().enumerate() {
        for &b in &order[k + 1..] {
            if extent(b).0 > extent(a).1 + REACH {
                break;
            }
            pairs.push((a.min(b), a.max(b)));
        }
    }
    pairs
}

impl Problem<'_> {
    /// The first step at which pair (a, b) conflicts, if any.
    pub(super) fn pair_conflict(&self, a: usize, b: usize, tracks: &[Arc<Track>]) -> Option<usize> {
        let (ca, cb) = (self.is_cav(a), self.is_cav(b));
        if !ca && !cb {
            return None;
        }
        let (ta, tb) = (&tracks[a].bodies, &tracks[b].bodies);
        let (a0, b0) = (&ta[0], &tb[0]);
        (1..=self.horizon).find(|&k| {
            let (ba, bb) = (&ta[k], &tb[k]);
            let (pa, pb) = (&ba.pose, &bb.pose);
            if (pa.s - pb.s).abs() > REACH || (pa.y - pb.y).abs() > 6.0 {
                return false;
            }
            (ca && !self.rule.clear(ba, a0, bb, b0, k as f64 * self.dt))
                || (cb && !self.rule.clear(bb, b0, ba, a0, k as f64 * self.dt))
        })
    }

    /// Which agents are in a conflict under trajectories `ts`.
    pub fn conflicted_agents(&self, ts: &[Arc<Trajectory>]) -> Vec<bool> {
        let everyone: Vec<usize> = (0..ts.len()).collect();
        let mut out = vec![false; ts.len()];
        for (_, a, b) in self.all_conflicts(&self.tracks(ts), &everyone) {
            out[a] = true;
            out[b] = true;
        }
        out
    }

    /// Whether agents `a` and `b` conflict at any step under trajectories `ts`.
    pub fn conflict_between(&self, a: usize, b: usize, ts: &[Arc<Trajectory>]) -> bool {
        self.conflicts(a, b, &self.tracks(ts))
    }

    /// Whether agents `a` and `b` conflict at any step.
    pub(super) fn conflicts(&self, a: usize, b: usize, tracks: &[Arc<Track>]) -> bool {
        self.pair_conflict(a.min(b), a.max(b), tracks).is_some()
    }

    /// All conflicting pairs among `agents`, each at its first step, sorted (checked in
    /// parallel: on a full corridor there are thousands of pairs within reach).
    pub(super) fn all_conflicts(&self, tracks: &[Arc<Track>], agents: &[usize]) -> Vec<Conflict> {
        let mut out: Vec<Conflict> = within_reach(tracks, agents)
            .into_par_iter()
            .filter_map(|(a, b)| self.pair_conflict(a, b, tracks).map(|k| (k, a, b)))
            .collect();
        out.sort_unstable();
        out
    }

    /// The parent's conflicts with every pair touching a `changed` agent recomputed (pairs
    /// among `agents`).
    pub(super) fn updated_conflicts(
        &self,
        parent: &[Conflict],
        changed: &[usize],
        tracks: &[Arc<Track>],
        agents: &[usize],
    ) -> Vec<Conflict> {
        let touched = |a: usize| changed.contains(&a);
        let mut out: Vec<Conflict> = parent
            .iter()
            .copied()
            .filter(|&(_, a, b)| !touched(a) && !touched(b))
            .collect();
        let near = |a: usize, b: usize| {
            let ((lo_a, hi_a), (lo_b, hi_b)) = (tracks[a].extent, tracks[b].extent);
            lo_b <= hi_a + REACH && lo_a <= hi_b + REACH
        };
        for &c in changed {
            for &o in agents {
                if o == c || (touched(o) && o < c) || !near(c, o) {
                    continue; // each changed pair once; far pairs never conflict
                }
                let (a, b) = (c.min(o), c.max(o));
                if let Some(k) = self.pair_conflict(a, b, tracks) {
                    out.push((k, a, b));
                }
            }
        }
        out.sort_unstable();
        out
    }
}
