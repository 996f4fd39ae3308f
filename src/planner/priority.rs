//! Priority orderings of PBS: a DAG over agents, where an edge `hi → lo` says `hi ≺ lo`
//! (`hi` has priority: `lo` plans around `hi`).
//!
//! A search node stores only the edge it added on top of its parent (see `pbs`); the graph of a
//! node is rebuilt from the edges along its path when the node is expanded, which costs a few
//! microseconds for the depths PBS reaches. Adding an edge that would close a cycle is refused,
//! so every graph is acyclic by construction; the topological order is deterministic (Kahn's
//! algorithm, smallest agent first).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A priority DAG over agents `0..n`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PriorityGraph {
    /// `lower[a]`: agents `a` has direct priority over.
    lower: Vec<Vec<usize>>,
    /// `higher[a]`: agents with direct priority over `a`.
    higher: Vec<Vec<usize>>,
}

impl PriorityGraph {
    /// No priorities among `n` agents.
    pub fn new(n: usize) -> Self {
        PriorityGraph {
            lower: vec![Vec::new(); n],
            higher: vec![Vec::new(); n],
        }
    }

    /// Number of agents.
    pub fn len(&self) -> usize {
        self.lower.len()
    }

    /// Whether there are no agents.
    pub fn is_empty(&self) -> bool {
        self.lower.is_empty()
    }

    /// Adds `hi ≺ lo`; refuses (returns false) if `lo` already has priority over `hi`, which
    /// would close a cycle. Adding an existing edge is a no-op.
    pub fn add(&mut self, hi: usize, lo: usize) -> bool {
        if hi == lo || self.reaches(lo, hi) {
            return false;
        }
        if !self.lower[hi].contains(&lo) {
            self.lower[hi].push(lo);
            self.higher[lo].push(hi);
        }
        true
    }

    /// Every direct edge `(hi, lo)`, in agent order.
    pub fn edges(&self) -> Vec<(usize, usize)> {
        (0..self.len())
            .flat_map(|hi| self.lower[hi].iter().map(move |&lo| (hi, lo)))
            .collect()
    }

    /// Whether `a` has priority over `b`, directly or through others.
    pub fn reaches(&self, a: usize, b: usize) -> bool {
        self.closure(a, &self.lower)[b]
    }

    fn closure(&self, start: usize, next: &[Vec<usize>]) -> Vec<bool> {
        let mut seen = vec![false; self.len()];
        let mut stack = vec![start];
        while let Some(x) = stack.pop() {
            for &y in &next[x] {
                if !seen[y] {
                    seen[y] = true;
                    stack.push(y);
                }
            }
        }
        seen
    }

    /// All agents with priority over `a` (transitively), ascending.
    pub fn ancestors(&self, a: usize) -> Vec<usize> {
        let seen = self.closure(a, &self.higher);
        (0..self.len()).filter(|&i| seen[i]).collect()
    }

    /// All agents `a` has priority over (transitively), ascending.
    pub fn descendants(&self, a: usize) -> Vec<usize> {
        let seen = self.closure(a, &self.lower);
        (0..self.len()).filter(|&i| seen[i]).collect()
    }

    /// `a` and its descendants in a topological order of the whole graph (every agent after
    /// all of its ancestors), ties broken by the smaller index.
    pub fn topological_from(&self, a: usize) -> Vec<usize> {
        let mut keep = self.closure(a, &self.lower);
        keep[a] = true;
        // In-degrees counted within the kept set only: edges from outside are already settled.
        let mut indegree = vec![0usize; self.len()];
        for x in (0..self.len()).filter(|&x| keep[x]) {
            for &y in &self.lower[x] {
                if keep[y] {
                    indegree[y] += 1;
                }
            }
        }
        let mut ready: BinaryHeap<Reverse<usize>> = (0..self.len())
            .filter(|&x| keep[x] && indegree[x] == 0)
            .map(Reverse)
            .collect();
        let mut order = Vec::new();
        while let Some(Reverse(x)) = ready.pop() {
            order.push(x);
            for &y in &self.lower[x] {
                if keep[y] {
                    indegree[y] -= 1;
                    if indegree[y] == 0 {
                        ready.push(Reverse(y));
                    }
                }
            }
        }
        order
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cycles_are_refused() {
        let mut g = PriorityGraph::new(4);
        assert!(g.add(0, 1) && g.add(1, 2));
        assert!(!g.add(2, 0), "0 ≺ 1 ≺ 2 forbids 2 ≺ 0");
        assert!(!g.add(1, 1));
        assert!(g.add(0, 2), "a redundant edge is fine");
        assert!(g.reaches(0, 2) && !g.reaches(2, 0));
    }

    #[test]
    fn ancestors_and_descendants() {
        let mut g = PriorityGraph::new(5);
        g.add(0, 2);
        g.add(1, 2);
        g.add(2, 3);
        assert_eq!(g.ancestors(3), vec![0, 1, 2]);
        assert_eq!(g.descendants(0), vec![2, 3]);
        assert!(g.ancestors(4).is_empty());
    }

    #[test]
    fn topological_order_respects_every_edge() {
        let mut g = PriorityGraph::new(7);
        for (a, b) in [(3, 1), (1, 0), (3, 5), (5, 0), (0, 6), (2, 6), (4, 2)] {
            assert!(g.add(a, b));
        }
        let order = g.topological_from(3);
        assert_eq!(order, vec![3, 1, 5, 0, 6]);
        let pos = |x: usize| order.iter().position(|&y| y == x).unwrap();
        for x in 0..7 {
            for &y in &g.lower[x] {
                if order.contains(&x) && order.contains(&y) {
                    assert!(pos(x) < pos(y), "{x} ≺ {y}");
                }
            }
        }
        // From an agent with no lower ones: just itself.
        assert_eq!(g.topological_from(6), vec![6]);
    }
}
