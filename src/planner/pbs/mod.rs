//! BK-PBS: priority-based search over CAVs and HDVs with conditional re-prediction (paper
//! section IV.C, Algorithm 1).
//!
//! Agents are every vehicle of the scene. The root plans each CAV alone by M-A* (no obstacles)
//! and predicts each HDV unconditioned. A node is expanded depth-first: its first conflict that
//! involves a CAV (the earliest step at which a CAV is not clear of another vehicle by the
//! [`SafetyRule`], ties to the lowest pair; HDV–HDV pairs never count) gives two children,
//! `j ≺ i` and `i ≺ j`. In a child, `update_plan` walks the newly lowered agent and everything
//! below it in topological order and replans the lowered agent and each lower agent that is no
//! longer clear of a higher one: a CAV by M-A* against all its higher-priority agents, an HDV by
//! re-prediction conditioned on its higher-priority CAVs. A child whose CAV finds no plan, or
//! whose re-predicted HDV still conflicts, is pruned; the surviving children are pushed so the
//! cheaper is expanded first (cost = −Σ forward speeds over the horizon). A node without
//! conflicts is the solution.
//!
//! Nodes store only their new priority edge, the trajectories they replanned and their list of
//! conflicts (derived: a child recomputes only the pairs that involve a replanned agent); a
//! node's full state is rebuilt from its path when it is expanded. A node budget (and optionally
//! a wall-time budget) bounds a round; when it runs out, or every branch dies, the best node seen
//! (fewest conflicts, then cost) is returned as a fallback.
//!
//! At scale (`Problem::independent_groups`) a round is decomposed by independence detection:
//! the root's conflicts (and the carried commitments) link agents into groups; each group is
//! searched on its own, in parallel, with its own node budget; the groups' answers are put
//! together and checked against each other, and groups whose answers conflict are merged and
//! searched again, until no conflict crosses a group (or one group is left: the whole round).
//! Agents without any conflict keep their root plans. Pairs are only checked where their
//! stretches of road over the horizon come within reach of each other (a sweep over `s`).
//!
//! How the code maps to it:
//! - this file: the round's [`Problem`], [`Budget`], [`Solution`] and [`PbsStats`], and the
//!   search itself: `solve` (the round), `plan_root` (the root, with the carried commitments),
//!   `search` (the depth-first loop of Algorithm 1), `expand` and `child` (branching on a
//!   conflict), `update_plan` (Algorithm 1's UpdatePlan, with `merge_is_certain` guarding HDV
//!   re-predictions);
//! - `conflicts`: what a conflict is and finding them (`pair_conflict`, `all_conflicts`,
//!   `updated_conflicts`, the `within_reach` sweep);
//! - `tree`: the priority tree (`Tree`, `Node`) and a node's full `State`, rebuilt along its
//!   path (`State::at_node`);
//! - `track`: a trajectory as the checks read it (bodies per step, extent, progress);
//! - `groups`: independence detection, the round group by group.

use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;

use crate::model::scene::{Kind, Origin, Scene};
use crate::model::trajectory::Trajectory;
use crate::planner::mastar::{Mastar, NoPlan, Plan};
use crate::planner::priority::PriorityGraph;
use crate::planner::safety::SafetyRule;
use crate::predict::Predictor;

mod conflicts;
mod groups;
mod track;
mod tree;

use conflicts::Conflict;
use track::Track;
use tree::{Node, Replanned, State, Tree};

/// Bounds of one planning round.
#[derive(Debug, Clone, PartialEq)]
pub struct Budget {
    /// High-level nodes expanded at most (deterministic).
    pub nodes: usize,
    /// Wall time at most, if set (makes results depend on the machine's speed).
    pub time_ms: Option<f64>,
}

/// Builds the M-A* request of a CAV against given obstacles (supplied by the controller, which
/// knows the lane changes under way).
pub trait RequestFor: Sync {
    /// Plans `agent` (a scene vehicle index) with `planner` around `obstacles`, the trajectories
    /// of the agents it must yield to.
    fn plan(
        &self,
        planner: &Mastar,
        agent: usize,
        obstacles: &[&Trajectory],
    ) -> Result<Plan, NoPlan>;

    /// What `agent` executes without a plan ([`Mastar::fallback_trajectory`]).
    fn fallback(&self, planner: &Mastar, agent: usize, horizon: usize) -> Trajectory;
}

/// One planning problem: a scene and how to plan and predict in it.
pub struct Problem<'a> {
    /// The scene planned in; agents are its vehicles, by index.
    pub scene: &'a Scene,
    /// The M-A* planner of every CAV.
    pub planner: &'a Mastar,
    /// Predicts the HDVs, at the root and again given the CAVs' plans.
    pub predictor: &'a dyn Predictor,
    /// How each agent's M-A* request is built.
    pub requests: &'a dyn RequestFor,
    /// Priority edges `(hi, lo)` carried over from earlier rounds (commitments: `lo` yields to a
    /// cut-in of `hi` that relied on it). The root starts from them where they are still
    /// feasible.
    pub committed: &'a [(usize, usize)],
    /// Decides which pairs of trajectories conflict.
    pub rule: &'a SafetyRule,
    /// Steps checked for conflicts (and predicted).
    pub horizon: usize,
    /// Planning step (s).
    pub dt: f64,
    /// The round's node and time budget.
    pub budget: Budget,
    /// Decompose the round into independent groups (see the module documentation).
    pub independent_groups: bool,
}

/// Effort and outcome of a round.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PbsStats {
    /// High-level nodes expanded.
    pub nodes: u64,
    /// M-A* calls (root and replanning).
    pub mastar_calls: u64,
    /// Nodes expanded inside those M-A* calls.
    pub mastar_nodes: u64,
    /// HDV predictions (root and conditioned re-predictions).
    pub predictions: u64,
    /// Depth of the returned node.
    pub depth: u64,
    /// The budget ran out or every branch died: the best node seen was returned.
    pub fallback: bool,
    /// The wall-time budget was what ran out.
    pub timed_out: bool,
    /// CAV-involved conflicts left in the returned node.
    pub conflicts_left: u64,
}

/// What a round returns: per agent (scene vehicle) its trajectory, and for CAVs the plan
/// (`None` if even the root could not plan it: it must brake).
#[derive(Debug, Clone)]
pub struct Solution {
    /// Per agent the trajectory of the chosen node: planned for a CAV, predicted for an HDV.
    pub trajectories: Vec<Arc<Trajectory>>,
    /// Per agent the M-A* plan; `None` for an HDV or a CAV the root could not plan.
    pub plans: Vec<Option<Arc<Plan>>>,
    /// The priority edges `(hi, lo)` of the chosen node, the commitments included.
    pub edges: Vec<(usize, usize)>,
    /// The round's effort and outcome.
    pub stats: PbsStats,
}

/// An agent at the root: track, plan (CAVs), M-A* calls and nodes spent.
type RootPlan = (Arc<Track>, Option<Arc<Plan>>, u64, u64);

/// Counts kept while planning a child.
#[derive(Default)]
struct Effort {
    mastar_calls: u64,
    mastar_nodes: u64,
    predictions: u64,
}

impl Effort {
    /// Adds these counts to a round's `stats`.
    fn add_to(&self, stats: &mut PbsStats) {
        stats.mastar_calls += self.mastar_calls;
        stats.mastar_nodes += self.mastar_nodes;
        stats.predictions += self.predictions;
    }
}

impl Problem<'_> {
    fn is_cav(&self, a: usize) -> bool {
        self.scene.vehicles[a].kind == Kind::Cav
    }

    /// Whether HDV `a` will merge whatever the CAVs do: a ramp HDV whose lane change is under
    /// way (moving off the merge lane's centre toward the main road), or standing in the zone at
    /// the lane's end where the merge rule forces it in. A conditioned re-prediction may not
    /// argue such a merge away: its unconditioned prediction stands (no optimism about HDVs).
    fn merge_is_certain(&self, a: usize) -> bool {
        let v = &self.scene.vehicles[a];
        let road = &self.scene.road;
        let forced = road.forces_merge(v.lane, v.front(), v.speed);
        v.kind == Kind::Hdv
            && v.origin == Origin::Ramp
            && road.is_auxiliary(v.lane)
            && (v.other_lane().is_some_and(|to| road.is_merge(v.lane, to)) || forced)
    }

    /// The tracks of `ts` over this problem's horizon.
    fn tracks(&self, ts: &[Arc<Trajectory>]) -> Vec<Arc<Track>> {
        Track::all(ts, self.horizon, self.dt)
    }

    /// The track of a newly planned or predicted trajectory.
    fn track(&self, t: Arc<Trajectory>) -> Arc<Track> {
        Arc::new(Track::new(t, self.horizon, self.dt))
    }

    fn predict(&self, agent: usize, conditioned_on: &[&Trajectory]) -> Arc<Track> {
        let t = self
            .predictor
            .predict(self.scene, agent, conditioned_on, self.horizon);
        self.track(Arc::new(t))
    }

    /// Replans `lowered` and every agent below it that is no longer clear of a higher one.
    /// Returns the replanned agents, or `None` if the child must be pruned.
    fn update_plan(
        &self,
        state: &mut State,
        lowered: usize,
        effort: &mut Effort,
    ) -> Option<Vec<usize>> {
        let mut changed = Vec::new();
        for k in state.graph.topological_from(lowered) {
            let higher = state.graph.ancestors(k);
            let conflicted =
                |tracks: &[Arc<Track>]| higher.iter().any(|&h| self.conflicts(k, h, tracks));
            if k != lowered && !conflicted(&state.tracks) {
                continue;
            }
            if self.is_cav(k) {
                let obstacles: Vec<&Trajectory> = higher
                    .iter()
                    .map(|&h| &*state.tracks[h].trajectory)
                    .collect();
                effort.mastar_calls += 1;
                match self.requests.plan(self.planner, k, &obstacles) {
                    Ok(plan) => {
                        effort.mastar_nodes += plan.expanded as u64;
                        state.tracks[k] = self.track(Arc::new(plan.trajectory.clone()));
                        state.plans[k] = Some(Arc::new(plan));
                    }
                    Err(e) => {
                        effort.mastar_nodes += e.expanded as u64;
                        return None;
                    }
                }
            } else {
                let cavs: Vec<&Trajectory> = higher
                    .iter()
                    .filter(|&&h| self.is_cav(h))
                    .map(|&h| &*state.tracks[h].trajectory)
                    .collect();
                if !self.merge_is_certain(k) {
                    effort.predictions += 1;
                    state.tracks[k] = self.predict(k, &cavs);
                }
                if conflicted(&state.tracks) {
                    return None;
                }
            }
            changed.push(k);
        }
        Some(changed)
    }

    /// Runs one planning round: Algorithm 1, depth-first from the root until a node without
    /// conflicts or the end of the budget, then the best node seen as a fallback; over the
    /// whole scene, or group by group (`independent_groups`).
    pub fn solve(&self) -> Solution {
        let start = Instant::now();
        let mut stats = PbsStats::default();
        let root_state = self.plan_root(&mut stats);
        if self.independent_groups {
            return groups::solve(self, &root_state, start, stats);
        }
        let all: Vec<usize> = (0..self.scene.vehicles.len()).collect();
        let conflicts = self.all_conflicts(&root_state.tracks, &all);
        let (state, stats) = self.search(&root_state, &all, conflicts, start, stats);
        state.solution(stats)
    }

    /// Algorithm 1 over `agents` (the others keep their root trajectories and plans), whose
    /// conflicts at the root are `root_conflicts`: the chosen node's state, and the effort.
    fn search(
        &self,
        root_state: &State,
        agents: &[usize],
        root_conflicts: Vec<Conflict>,
        start: Instant,
        mut stats: PbsStats,
    ) -> (State, PbsStats) {
        let mut tree = Tree::new(Node::root(root_state, root_conflicts));
        let mut solution = None;
        while let Some(id) = tree.stack.pop() {
            if tree.nodes[id].conflicts.is_empty() {
                solution = Some(id);
                break;
            }
            if self.budget_spent(start, &mut stats) {
                break;
            }
            stats.nodes += 1;
            let children = self.expand(&tree.nodes, id, root_state, agents, &mut stats);
            tree.push_children(children);
        }
        let chosen = solution.unwrap_or(tree.best);
        stats.fallback = solution.is_none();
        self.answer(&tree.nodes, chosen, root_state, stats)
    }

    /// The root's state: each CAV planned alone (in parallel: they are independent), each HDV
    /// predicted unconditioned; the effort is added to `stats`.
    fn plan_root(&self, stats: &mut PbsStats) -> State {
        let n = self.scene.vehicles.len();
        let root: Vec<RootPlan> = (0..n).into_par_iter().map(|a| self.root_plan(a)).collect();
        let mut tracks = Vec::with_capacity(n);
        let mut plans = Vec::with_capacity(n);
        for (a, (t, p, calls, nodes)) in root.into_iter().enumerate() {
            stats.mastar_calls += calls;
            stats.mastar_nodes += nodes;
            stats.predictions += u64::from(!self.is_cav(a));
            tracks.push(t);
            plans.push(p);
        }
        let mut state = State {
            graph: PriorityGraph::new(n),
            tracks,
            plans,
        };
        self.keep_commitments(&mut state, stats);
        state
    }

    /// Adds each committed edge whose lower agent can still plan (or be predicted) around its
    /// higher ones, replanning it as a child would; a commitment that has become infeasible is
    /// dropped, and the state is left as it was.
    fn keep_commitments(&self, state: &mut State, stats: &mut PbsStats) {
        for &(hi, lo) in self.committed {
            let mut next = state.clone();
            if !next.graph.add(hi, lo) {
                continue;
            }
            let mut effort = Effort::default();
            let kept = self.update_plan(&mut next, lo, &mut effort).is_some();
            effort.add_to(stats);
            if kept {
                *state = next;
            }
        }
    }

    /// Agent `a` at the root: a CAV planned by M-A* without obstacles (its braking fallback,
    /// without a plan, if even that fails), an HDV predicted unconditioned.
    fn root_plan(&self, a: usize) -> RootPlan {
        if self.is_cav(a) {
            match self.requests.plan(self.planner, a, &[]) {
                Ok(p) => (
                    self.track(Arc::new(p.trajectory.clone())),
                    Some(Arc::new(p.clone())),
                    1,
                    p.expanded as u64,
                ),
                Err(e) => (
                    self.track(Arc::new(self.requests.fallback(
                        self.planner,
                        a,
                        self.horizon,
                    ))),
                    None,
                    1,
                    e.expanded as u64,
                ),
            }
        } else {
            (self.predict(a, &[]), None, 0, 0)
        }
    }

    /// Whether the round must stop expanding: the node budget is used up or, if set, the
    /// wall-time budget (which is then flagged in `stats`).
    fn budget_spent(&self, start: Instant, stats: &mut PbsStats) -> bool {
        if stats.nodes as usize >= self.budget.nodes {
            return true;
        }
        if self
            .budget
            .time_ms
            .is_some_and(|ms| start.elapsed().as_secs_f64() * 1e3 >= ms)
        {
            stats.timed_out = true;
            return true;
        }
        false
    }

    /// The surviving children of node `id`, branching on its first conflict (i, j) into
    /// `j ≺ i` and `i ≺ j`, costlier first; none if i and j are already ordered (a dead end).
    /// Their effort is added to `stats`.
    fn expand(
        &self,
        nodes: &[Node],
        id: usize,
        root_state: &State,
        agents: &[usize],
        stats: &mut PbsStats,
    ) -> Vec<Node> {
        let (_, i, j) = nodes[id].conflicts[0];
        let state = root_state.at_node(nodes, id);
        if state.graph.reaches(i, j) || state.graph.reaches(j, i) {
            return Vec::new(); // ordered agents still in conflict: a dead end
        }
        // Both children at once: they are independent.
        let (left, right) = rayon::join(
            || self.child(&nodes[id], &state, j, i, agents),
            || self.child(&nodes[id], &state, i, j, agents),
        );
        let mut children: Vec<(Node, Effort)> = [left, right]
            .into_iter()
            .flatten()
            .map(|(mut c, e)| {
                c.parent = Some(id);
                (c, e)
            })
            .collect();
        for (_, e) in &children {
            e.add_to(stats);
        }
        // Push the costlier first so the cheaper is expanded first.
        children.sort_by(|a, b| b.0.cost.total_cmp(&a.0.cost));
        children.into_iter().map(|(c, _)| c).collect()
    }

    /// The search's answer, node `chosen`: its full state, with its depth and conflicts left
    /// recorded in `stats`.
    fn answer(
        &self,
        nodes: &[Node],
        chosen: usize,
        root_state: &State,
        mut stats: PbsStats,
    ) -> (State, PbsStats) {
        stats.depth = nodes[chosen].depth as u64;
        stats.conflicts_left = nodes[chosen].conflicts.len() as u64;
        (root_state.at_node(nodes, chosen), stats)
    }

    /// The child of `parent` (whose state is `state`) that adds `hi ≺ lo`, unless pruned.
    fn child(
        &self,
        parent: &Node,
        state: &State,
        hi: usize,
        lo: usize,
        agents: &[usize],
    ) -> Option<(Node, Effort)> {
        let mut child = state.clone();
        if !child.graph.add(hi, lo) {
            return None;
        }
        let mut effort = Effort::default();
        let changed = self.update_plan(&mut child, lo, &mut effort)?;
        // Lowering `lo` must resolve the conflict that caused the branch; when the conflict is
        // only `hi`'s (e.g. `hi` follows `lo` too closely), only lowering `hi` can.
        if self.conflicts(hi, lo, &child.tracks) {
            return None;
        }
        let conflicts = self.updated_conflicts(&parent.conflicts, &changed, &child.tracks, agents);
        Some((
            Node {
                parent: None,
                edge: Some((hi, lo)),
                changed: changed
                    .iter()
                    .map(|&a| Replanned {
                        agent: a,
                        track: child.tracks[a].clone(),
                        plan: child.plans[a].clone(),
                    })
                    .collect(),
                cost: child.cost(),
                conflicts,
                depth: parent.depth + 1,
            },
            effort,
        ))
    }
}

#[cfg(test)]
mod tests;
