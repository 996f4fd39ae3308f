//! A* search, generic and small: the problem lives entirely in the closures.
//!
//! Costs are `f64` (non-negative, finite). Ties on f = g + h go to the larger g (the deeper
//! node, which dives toward the goal), then to the earlier-generated node, so the search is
//! deterministic. A closed set keyed by `key(node)` keeps the first expansion of each key.

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

use rustc_hash::FxHashSet;
use std::hash::Hash;

use ordered_float::OrderedFloat;

/// Why the search stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// A node satisfying the goal predicate was expanded.
    Found,
    /// Every reachable node was expanded without reaching the goal.
    Exhausted,
    /// The expansion budget ran out first.
    Budget,
}

/// Outcome of a search.
#[derive(Debug, Clone)]
pub struct Search<N> {
    /// Start to goal, both included; empty unless `stop == Found`.
    pub path: Vec<N>,
    /// Cost of `path` (g of the goal); infinite unless `stop == Found`.
    pub cost: f64,
    /// Nodes expanded.
    pub expanded: usize,
    /// Why the search stopped.
    pub stop: Stop,
}

/// An open-list entry: generated node `seq`, its cost `g` from the start and `f = g + h`.
struct Entry {
    f: OrderedFloat<f64>,
    g: OrderedFloat<f64>,
    seq: usize,
}

impl PartialEq for Entry {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Entry {
    /// Max-heap order: smaller f first, then larger g, then earlier seq.
    fn cmp(&self, o: &Self) -> Ordering {
        Reverse(self.f)
            .cmp(&Reverse(o.f))
            .then(self.g.cmp(&o.g))
            .then(Reverse(self.seq).cmp(&Reverse(o.seq)))
    }
}

/// A* from `start` with at most `budget` expansions.
///
/// - `successors(n)` yields `(next, edge_cost)` with `edge_cost ≥ 0`;
/// - `heuristic(n)` must never overestimate the remaining cost to a goal (admissible), or the
///   path found may not be the cheapest;
/// - `success(n)` is the goal test, applied when a node is expanded;
/// - `key(n)` identifies equivalent nodes: only the first expanded node of a key is expanded.
///
/// ```
/// use bkpbs::planner::search::{astar, Stop};
/// // Walk from 0 to 7 on the integers with steps of +1 (cost 1) or +3 (cost 2).
/// let r = astar(0i32, |&n| vec![(n + 1, 1.0), (n + 3, 2.0)], |&n| (7 - n).max(0) as f64 * 2.0 / 3.0,
///               |&n| n == 7, |&n| n, 100);
/// assert_eq!(r.stop, Stop::Found);
/// assert_eq!(r.cost, 5.0); // 0 -> 3 -> 6 -> 7
/// assert_eq!(r.path, vec![0, 3, 6, 7]);
/// ```
pub fn astar<N, K, I>(
    start: N,
    mut successors: impl FnMut(&N) -> I,
    mut heuristic: impl FnMut(&N) -> f64,
    mut success: impl FnMut(&N) -> bool,
    key: impl Fn(&N) -> K,
    budget: usize,
) -> Search<N>
where
    N: Clone,
    K: Eq + Hash,
    I: IntoIterator<Item = (N, f64)>,
{
    let mut tree = Tree::default();
    let h0 = heuristic(&start);
    tree.push(start, NO_PARENT, 0.0, h0);
    // Keys are small tuples of integers: a fast hash, not a DoS-resistant one.
    let mut closed: FxHashSet<K> = FxHashSet::default();
    let mut expanded = 0;
    while let Some(Entry { seq, g, .. }) = tree.open.pop() {
        if !closed.insert(key(tree.node(seq))) {
            continue;
        }
        if success(tree.node(seq)) {
            return Search::found(tree.path_to(seq), g.0, expanded);
        }
        if expanded >= budget {
            return Search::failed(Stop::Budget, expanded);
        }
        expanded += 1;
        let is_closed = |n: &N| closed.contains(&key(n));
        tree.expand(seq, g.0, &mut successors, &mut heuristic, is_closed);
    }
    Search::failed(Stop::Exhausted, expanded)
}

impl<N> Search<N> {
    /// The search that reached a goal along `path` at `cost`.
    fn found(path: Vec<N>, cost: f64, expanded: usize) -> Self {
        Search {
            path,
            cost,
            expanded,
            stop: Stop::Found,
        }
    }

    /// The search that stopped for `stop` without reaching a goal.
    fn failed(stop: Stop, expanded: usize) -> Self {
        Search {
            path: Vec::new(),
            cost: f64::INFINITY,
            expanded,
            stop,
        }
    }
}

/// The parent of the start node.
const NO_PARENT: usize = usize::MAX;

/// A generated node and the node it was generated from.
struct Generated<N> {
    node: N,
    parent: usize,
}

/// The search tree: every node generated so far, in order of generation (its index is the
/// `seq` its open-list entry carries, so ties go to the earlier one), and the open list.
struct Tree<N> {
    arena: Vec<Generated<N>>,
    open: BinaryHeap<Entry>,
}

impl<N> Default for Tree<N> {
    fn default() -> Self {
        Tree {
            arena: Vec::new(),
            open: BinaryHeap::new(),
        }
    }
}

impl<N: Clone> Tree<N> {
    #[inline]
    fn node(&self, seq: usize) -> &N {
        &self.arena[seq].node
    }

    /// Stores `node`, generated from `parent` at cost `g` from the start with heuristic `h`,
    /// and opens it.
    #[inline]
    fn push(&mut self, node: N, parent: usize, g: f64, h: f64) {
        let seq = self.arena.len();
        self.arena.push(Generated { node, parent });
        self.open.push(Entry {
            f: OrderedFloat(g + h),
            g: OrderedFloat(g),
            seq,
        });
    }

    /// Generates the successors of node `seq` (at cost `g` from the start) and opens those
    /// whose key is not closed yet, in the order `successors` yields them.
    #[inline]
    fn expand<I>(
        &mut self,
        seq: usize,
        g: f64,
        successors: &mut impl FnMut(&N) -> I,
        heuristic: &mut impl FnMut(&N) -> f64,
        is_closed: impl Fn(&N) -> bool,
    ) where
        I: IntoIterator<Item = (N, f64)>,
    {
        // Gathered before any is stored: the arena may move as it grows.
        let generated: Vec<(N, f64)> = successors(self.node(seq)).into_iter().collect();
        for (next, cost) in generated {
            if is_closed(&next) {
                continue;
            }
            let g2 = g + cost;
            let h = heuristic(&next);
            self.push(next, seq, g2, h);
        }
    }

    /// The nodes from the start to node `seq`, both included.
    fn path_to(&self, seq: usize) -> Vec<N> {
        let mut path = Vec::new();
        let mut at = seq;
        while at != NO_PARENT {
            path.push(self.arena[at].node.clone());
            at = self.arena[at].parent;
        }
        path.reverse();
        path
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    type Cell = (i32, i32);

    /// Grid world 0..w × 0..h with walls, from (0, 0) to `goal`, 4-neighbour moves of cost 1;
    /// with the Manhattan heuristic (A*) or none (Dijkstra).
    fn grid(
        walls: &[Cell],
        w: i32,
        h: i32,
        goal: Cell,
        budget: usize,
        informed: bool,
    ) -> Search<Cell> {
        let walls: HashSet<Cell> = walls.iter().copied().collect();
        astar(
            (0, 0),
            |&(x, y)| {
                [(1, 0), (-1, 0), (0, 1), (0, -1)]
                    .into_iter()
                    .map(move |(dx, dy)| (x + dx, y + dy))
                    .filter(|&(a, b)| {
                        a >= 0 && b >= 0 && a < w && b < h && !walls.contains(&(a, b))
                    })
                    .map(|n| (n, 1.0))
                    .collect::<Vec<_>>()
            },
            |&(x, y)| {
                if informed {
                    ((goal.0 - x).abs() + (goal.1 - y).abs()) as f64
                } else {
                    0.0
                }
            },
            |&n| n == goal,
            |&n| n,
            budget,
        )
    }

    #[test]
    fn agrees_with_dijkstra_around_a_wall() {
        let walls: Vec<(i32, i32)> = (0..4).map(|y| (2, y)).collect();
        let r = grid(&walls, 6, 5, (5, 0), 1000, true);
        assert_eq!(r.stop, Stop::Found);
        assert_eq!(r.cost, grid(&walls, 6, 5, (5, 0), usize::MAX, false).cost);
        assert_eq!(r.cost, 13.0);
        assert_eq!(r.path.first(), Some(&(0, 0)));
        assert_eq!(r.path.last(), Some(&(5, 0)));
    }

    #[test]
    fn exhausted_when_unreachable_and_budget_respected() {
        let walls: Vec<(i32, i32)> = (0..5).map(|y| (2, y)).collect();
        assert_eq!(grid(&walls, 6, 5, (5, 0), 1000, true).stop, Stop::Exhausted);
        let r = grid(&[], 50, 50, (49, 49), 10, true);
        assert_eq!((r.stop, r.expanded), (Stop::Budget, 10));
    }

    #[test]
    fn deterministic_path_among_equal_costs() {
        let a = grid(&[], 5, 5, (3, 3), 1000, true).path;
        for _ in 0..5 {
            assert_eq!(grid(&[], 5, 5, (3, 3), 1000, true).path, a);
        }
    }
}
