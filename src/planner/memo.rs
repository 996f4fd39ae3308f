//! The searches of one planning round, remembered: a CAV planned again against exactly the same
//! obstacles gets the answer it got the first time.
//!
//! BK-PBS asks for the same search many times in a round: sibling branches replan an agent
//! under the same higher-priority agents, and at scale, when two groups' answers conflict, the
//! merged group is searched again from the root and repeats most of what its parts did. M-A* is
//! deterministic, so an answer looked up is the answer the search would give: plans do not
//! change, and neither do the effort counts (an answer carries the nodes its search expanded).
//!
//! A lookup compares the obstacles exactly (every pose, bit for bit), not just their hash.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Mutex, MutexGuard};

use rustc_hash::FxHasher;

use crate::model::trajectory::Trajectory;
use crate::planner::mastar::{NoPlan, Plan};

/// A search's answer.
pub type Answer = Result<Plan, NoPlan>;

/// Per agent and hash of its obstacles: the obstacles searched against (in order) and the
/// answer, for each search with that hash.
type Entries = HashMap<(usize, u64), Vec<(Vec<Trajectory>, Answer)>>;

/// The searches of one round.
#[derive(Default)]
pub struct SearchMemo {
    entries: Mutex<Entries>,
}

impl SearchMemo {
    /// The answer for `agent` against `obstacles`: remembered, or found by `search` and kept.
    /// (Two threads asking at once may both search; both get the same answer.)
    pub fn answer(
        &self,
        agent: usize,
        obstacles: &[&Trajectory],
        search: impl FnOnce() -> Answer,
    ) -> Answer {
        let key = (agent, fingerprint(obstacles));
        if let Some(found) = self.lookup(key, obstacles) {
            return found;
        }
        let answer = search();
        let kept = obstacles.iter().map(|t| (*t).clone()).collect();
        self.lock()
            .entry(key)
            .or_default()
            .push((kept, answer.clone()));
        answer
    }

    fn lookup(&self, key: (usize, u64), obstacles: &[&Trajectory]) -> Option<Answer> {
        let entries = self.lock();
        let same = |kept: &[Trajectory]| {
            kept.len() == obstacles.len()
                && kept.iter().zip(obstacles).all(|(a, b)| same_bits(a, b))
        };
        entries
            .get(&key)?
            .iter()
            .find(|(kept, _)| same(kept))
            .map(|(_, answer)| answer.clone())
    }

    fn lock(&self) -> MutexGuard<'_, Entries> {
        // A panic elsewhere while holding the lock leaves only complete entries behind.
        self.entries.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Every number of a trajectory, as bits: its poses, then its body.
fn bits(t: &Trajectory) -> impl Iterator<Item = u64> + '_ {
    let poses = t.poses.iter().flat_map(|p| [p.s, p.y, p.heading, p.speed]);
    let body = [t.length, t.width, t.brake.unwrap_or(f64::NAN)];
    poses
        .chain(body)
        .map(f64::to_bits)
        .chain([t.brake.is_some() as u64])
}

/// Whether two trajectories are the same bit for bit.
fn same_bits(a: &Trajectory, b: &Trajectory) -> bool {
    a.poses.len() == b.poses.len() && bits(a).eq(bits(b))
}

/// A hash of the obstacles, in order, over every bit of their poses and bodies.
fn fingerprint(obstacles: &[&Trajectory]) -> u64 {
    let mut h = FxHasher::default();
    for t in obstacles {
        t.poses.len().hash(&mut h);
        bits(t).for_each(|x| x.hash(&mut h));
    }
    h.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn the_same_obstacles_are_searched_once_and_others_again() {
        let memo = SearchMemo::default();
        let a = Trajectory::straight(0.0, 4.5, 20.0, 5, 0.2);
        let mut b = a.clone();
        b.poses[3].speed += 1e-12;
        let searches = Cell::new(0);
        let search = || {
            searches.set(searches.get() + 1);
            Err(NoPlan {
                expanded: searches.get(),
            })
        };
        let first = memo.answer(0, &[&a], search).unwrap_err();
        let again = memo.answer(0, &[&a], search).unwrap_err();
        assert_eq!((first.expanded, again.expanded, searches.get()), (1, 1, 1));
        // A pose differing in the last bit, another agent, another order: searched.
        memo.answer(0, &[&b], search).unwrap_err();
        memo.answer(1, &[&a], search).unwrap_err();
        memo.answer(0, &[&a, &b], search).unwrap_err();
        memo.answer(0, &[&b, &a], search).unwrap_err();
        assert_eq!(searches.get(), 5);
    }
}
