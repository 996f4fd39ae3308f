//! The priority tree of a BK-PBS round: its nodes, the depth-first stack and the best node
//! seen, and the full state of a node (its priority graph, every agent's track and plan).
//!
//! A node stores only what it changed (its new priority edge and the agents it replanned), so a
//! tree of thousands of nodes holds few trajectories; a node's [`State`] is rebuilt from the root
//! along its path when the search needs it ([`State::at_node`]).

use std::sync::Arc;

use crate::planner::mastar::Plan;
use crate::planner::pbs::conflicts::Conflict;
use crate::planner::pbs::track::Track;
use crate::planner::pbs::{PbsStats, Solution};
use crate::planner::priority::PriorityGraph;

/// An agent replanned in a node: its new track and plan (CAVs).
pub(super) struct Replanned {
    pub agent: usize,
    pub track: Arc<Track>,
    pub plan: Option<Arc<Plan>>,
}

/// A node of the priority tree: its parent, the priority edge it added, the agents it replanned,
/// its conflicts (sorted: the first is the one to branch on), its cost and its depth.
pub(super) struct Node {
    pub parent: Option<usize>,
    pub edge: Option<(usize, usize)>,
    pub changed: Vec<Replanned>,
    pub conflicts: Vec<Conflict>,
    pub cost: f64,
    pub depth: usize,
}

/// The high-level search tree: every node generated (ids are indices), the depth-first stack
/// of nodes still to expand, and the best node seen, the fallback answer.
pub(super) struct Tree {
    pub nodes: Vec<Node>,
    pub stack: Vec<usize>,
    pub best: usize,
}

impl Tree {
    /// A tree of `root` alone, which is also the best node so far and the first to expand.
    pub fn new(root: Node) -> Self {
        Tree {
            nodes: vec![root],
            stack: vec![0],
            best: 0,
        }
    }

    /// Adds `children` in order, each pushed on the stack (so the last is expanded first) and
    /// made the best node if it beats the best so far.
    pub fn push_children(&mut self, children: Vec<Node>) {
        for c in children {
            let cid = self.nodes.len();
            if c.better_than(&self.nodes[self.best]) {
                self.best = cid;
            }
            self.nodes.push(c);
            self.stack.push(cid);
        }
    }
}

impl Node {
    /// The tree's root node, whose state is `root_state`, with its conflicts.
    pub fn root(root_state: &State, conflicts: Vec<Conflict>) -> Node {
        Node {
            parent: None,
            edge: None,
            changed: Vec::new(),
            cost: root_state.cost(),
            conflicts,
            depth: 0,
        }
    }

    /// Whether this node is a better fallback than `other`: fewer conflicts, then cheaper.
    fn better_than(&self, other: &Node) -> bool {
        (self.conflicts.len(), self.cost) < (other.conflicts.len(), other.cost)
    }
}

/// The full state of a node.
#[derive(Clone)]
pub(super) struct State {
    pub graph: PriorityGraph,
    pub tracks: Vec<Arc<Track>>,
    pub plans: Vec<Option<Arc<Plan>>>,
}

impl State {
    /// A node's cost: −Σ forward speeds over steps 1..=horizon of all agents.
    pub fn cost(&self) -> f64 {
        -self.tracks.iter().map(|t| t.progress).sum::<f64>()
    }

    /// What the search answers from this state.
    pub fn solution(self, stats: PbsStats) -> Solution {
        Solution {
            edges: self.graph.edges(),
            trajectories: self.tracks.iter().map(|t| t.trajectory.clone()).collect(),
            plans: self.plans,
            stats,
        }
    }

    /// The state of node `id` of `nodes`, rebuilt from this, the root's state, along its path.
    pub fn at_node(&self, nodes: &[Node], id: usize) -> State {
        let mut path = Vec::new();
        let mut at = Some(id);
        while let Some(x) = at {
            path.push(x);
            at = nodes[x].parent;
        }
        let mut state = self.clone();
        for &x in path.iter().rev() {
            let node = &nodes[x];
            if let Some((hi, lo)) = node.edge {
                state.graph.add(hi, lo);
            }
            for r in &node.changed {
                state.tracks[r.agent] = r.track.clone();
                state.plans[r.agent] = r.plan.clone();
            }
        }
        state
    }
}
