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

use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;

use crate::model::road::MERGE_LANE;
use crate::model::scene::{Kind, Origin, Scene};
use crate::model::trajectory::Trajectory;
use crate::planner::mastar::{Mastar, NoPlan, Plan};
use crate::planner::priority::PriorityGraph;
use crate::planner::safety::{SafetyRule, REACH};

mod groups;
mod track;
use crate::predict::Predictor;
use track::Track;

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
    fn plan(
        &self,
        planner: &Mastar,
        agent: usize,
        obstacles: &[&Trajectory],
    ) -> Result<Plan, NoPlan>;

    /// What `agent` executes without a plan ([`Mastar::fallback_trajectory`]).
    fn fallback(&self, planner: &Mastar, agent: usize, horizon: usize) -> Trajectory;
}

/// Lateral offset (m) toward the main road from which a ramp HDV's merge is under way.
const MERGE_UNDER_WAY: f64 = 0.1;

/// One planning problem: a scene and how to plan and predict in it.
pub struct Problem<'a> {
    pub scene: &'a Scene,
    pub planner: &'a Mastar,
    pub predictor: &'a dyn Predictor,
    pub requests: &'a dyn RequestFor,
    /// Priority edges `(hi, lo)` carried over from earlier rounds (commitments: `lo` yields to a
    /// cut-in of `hi` that relied on it). The root starts from them where they are still
    /// feasible.
    pub committed: &'a [(usize, usize)],
    pub rule: &'a SafetyRule,
    /// Steps checked for conflicts (and predicted).
    pub horizon: usize,
    pub dt: f64,
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
    pub trajectories: Vec<Arc<Trajectory>>,
    pub plans: Vec<Option<Arc<Plan>>>,
    /// The priority edges `(hi, lo)` of the chosen node, the commitments included.
    pub edges: Vec<(usize, usize)>,
    pub stats: PbsStats,
}

/// (step, i, j) with i < j.
type Conflict = (usize, usize, usize);

/// An agent at the root: track, plan (CAVs), M-A* calls and nodes spent.
type RootPlan = (Arc<Track>, Option<Arc<Plan>>, u64, u64);

/// An agent replanned in a node: its new track and plan (CAVs).
struct Replanned {
    agent: usize,
    track: Arc<Track>,
    plan: Option<Arc<Plan>>,
}

struct Node {
    parent: Option<usize>,
    edge: Option<(usize, usize)>,
    changed: Vec<Replanned>,
    conflicts: Vec<Conflict>,
    cost: f64,
    depth: usize,
}

/// The high-level search tree: every node generated (ids are indices), the depth-first stack
/// of nodes still to expand, and the best node seen, the fallback answer.
struct Tree {
    nodes: Vec<Node>,
    stack: Vec<usize>,
    best: usize,
}

impl Tree {
    /// A tree of `root` alone, which is also the best node so far and the first to expand.
    fn new(root: Node) -> Self {
        Tree {
            nodes: vec![root],
            stack: vec![0],
            best: 0,
        }
    }

    /// Adds `children` in order, each pushed on the stack (so the last is expanded first) and
    /// made the best node if it beats the best so far.
    fn push_children(&mut self, children: Vec<Node>) {
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
    fn root(root_state: &State, conflicts: Vec<Conflict>) -> Node {
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
struct State {
    graph: PriorityGraph,
    tracks: Vec<Arc<Track>>,
    plans: Vec<Option<Arc<Plan>>>,
}

impl State {
    /// A node's cost: −Σ forward speeds over steps 1..=horizon of all agents.
    fn cost(&self) -> f64 {
        -self.tracks.iter().map(|t| t.progress).sum::<f64>()
    }

    /// What the search answers from this state.
    fn solution(self, stats: PbsStats) -> Solution {
        Solution {
            edges: self.graph.edges(),
            trajectories: self.tracks.iter().map(|t| t.trajectory.clone()).collect(),
            plans: self.plans,
            stats,
        }
    }
}

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

/// Counts kept while planning a child.
#[derive(Default)]
struct Effort {
    mastar_calls: u64,
    mastar_nodes: u64,
    predictions: u64,
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
        let forced = self.scene.road.forces_merge(v.front(), v.speed);
        v.kind == Kind::Hdv
            && v.origin == Origin::Ramp
            && v.lane == MERGE_LANE
            && (v.lateral > MERGE_UNDER_WAY || forced)
    }

    /// The first step at which pair (a, b) conflicts, if any.
    fn pair_conflict(&self, a: usize, b: usize, tracks: &[Arc<Track>]) -> Option<usize> {
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

    /// The tracks of `ts` over this problem's horizon.
    fn tracks(&self, ts: &[Arc<Trajectory>]) -> Vec<Arc<Track>> {
        Track::all(ts, self.horizon, self.dt)
    }

    /// The track of a newly planned or predicted trajectory.
    fn track(&self, t: Arc<Trajectory>) -> Arc<Track> {
        Arc::new(Track::new(t, self.horizon, self.dt))
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
    fn conflicts(&self, a: usize, b: usize, tracks: &[Arc<Track>]) -> bool {
        self.pair_conflict(a.min(b), a.max(b), tracks).is_some()
    }

    /// All conflicting pairs among `agents`, each at its first step, sorted (checked in
    /// parallel: on a full corridor there are thousands of pairs within reach).
    fn all_conflicts(&self, tracks: &[Arc<Track>], agents: &[usize]) -> Vec<Conflict> {
        let mut out: Vec<Conflict> = within_reach(tracks, agents)
            .into_par_iter()
            .filter_map(|(a, b)| self.pair_conflict(a, b, tracks).map(|k| (k, a, b)))
            .collect();
        out.sort_unstable();
        out
    }

    /// The parent's conflicts with every pair touching a `changed` agent recomputed (pairs
    /// among `agents`).
    fn updated_conflicts(
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
            stats.mastar_calls += effort.mastar_calls;
            stats.mastar_nodes += effort.mastar_nodes;
            stats.predictions += effort.predictions;
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
        let state = self.materialize(nodes, id, root_state);
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
            stats.mastar_calls += e.mastar_calls;
            stats.mastar_nodes += e.mastar_nodes;
            stats.predictions += e.predictions;
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
        (self.materialize(nodes, chosen, root_state), stats)
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

    /// Rebuilds a node's state from the root along its path.
    fn materialize(&self, nodes: &[Node], id: usize, root: &State) -> State {
        let mut path = Vec::new();
        let mut at = Some(id);
        while let Some(x) = at {
            path.push(x);
            at = nodes[x].parent;
        }
        let mut state = root.clone();
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

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;
    use crate::config::Config;
    use crate::model::scene::{Origin, VehicleState};
    use crate::planner::lane_changes::{LaneChanges, SceneRequests};
    use crate::predict::ConstantSpeed;

    fn vehicle(id: &str, kind: Kind, origin: Origin, s: f64, lane: i32, v: f64) -> VehicleState {
        VehicleState::on_lane(id, kind, origin, s, lane, v)
    }

    /// The constant-speed predictor, counting the calls conditioned on CAV plans.
    struct Spy {
        inner: ConstantSpeed,
        conditioned: AtomicUsize,
    }

    impl Predictor for Spy {
        fn name(&self) -> &'static str {
            "spy"
        }
        fn predict(
            &self,
            scene: &Scene,
            i: usize,
            on: &[&Trajectory],
            horizon: usize,
        ) -> Trajectory {
            if !on.is_empty() {
                self.conditioned.fetch_add(1, Ordering::SeqCst);
            }
            self.inner.predict(scene, i, on, horizon)
        }
    }

    fn solve(vehicles: Vec<VehicleState>, spy: &Spy) -> (Solution, Scene) {
        solve_within(
            vehicles,
            spy,
            Budget {
                nodes: 200,
                time_ms: None,
            },
        )
    }

    fn solve_within(vehicles: Vec<VehicleState>, spy: &Spy, budget: Budget) -> (Solution, Scene) {
        solve_committed(vehicles, spy, budget, &[])
    }

    /// Runs `f` on the test problem of `scene`: the default planner and safety rule, no lane
    /// change under way, a 20-step horizon.
    fn with_problem<R>(
        scene: &Scene,
        predictor: &dyn Predictor,
        committed: &[(usize, usize)],
        budget: Budget,
        f: impl FnOnce(&Problem) -> R,
    ) -> R {
        with_grouping(scene, predictor, committed, budget, false, f)
    }

    fn with_grouping<R>(
        scene: &Scene,
        predictor: &dyn Predictor,
        committed: &[(usize, usize)],
        budget: Budget,
        independent_groups: bool,
        f: impl FnOnce(&Problem) -> R,
    ) -> R {
        let config = Config::default();
        let planner = Mastar::on_paper_road();
        let rule = SafetyRule::new(&config.planner, 4.5);
        let lane_changes = LaneChanges::default();
        let requests = SceneRequests::new(scene, &lane_changes, 0.2, None);
        f(&Problem {
            scene,
            planner: &planner,
            predictor,
            requests: &requests,
            committed,
            rule: &rule,
            horizon: 20,
            dt: 0.2,
            budget,
            independent_groups,
        })
    }

    fn solve_committed(
        vehicles: Vec<VehicleState>,
        spy: &Spy,
        budget: Budget,
        committed: &[(usize, usize)],
    ) -> (Solution, Scene) {
        let scene = Scene::on_paper_road(0.0, vehicles);
        let solution = with_problem(&scene, spy, committed, budget, |p| p.solve());
        (solution, scene)
    }

    fn spy() -> Spy {
        Spy {
            inner: ConstantSpeed::new(&Config::default()),
            conditioned: AtomicUsize::new(0),
        }
    }

    /// Whether no pair of the solution's trajectories conflicts under the safety rule: the one
    /// notion of a conflict, the same the search resolves.
    fn conflict_free(sol: &Solution, scene: &Scene) -> bool {
        let predictor = ConstantSpeed::new(&Config::default());
        let budget = Budget {
            nodes: 1,
            time_ms: None,
        };
        let ts = &sol.trajectories;
        with_problem(scene, &predictor, &[], budget, |problem| {
            (0..ts.len()).all(|a| (a + 1..ts.len()).all(|b| !problem.conflict_between(a, b, ts)))
        })
    }

    /// Two merges far apart along the road (one in the merge zone, one 1 km on): each is a
    /// group of its own; the answer is conflict-free, and the same on one thread as on four.
    #[test]
    fn far_apart_conflicts_are_searched_as_independent_groups() {
        let sp = spy();
        let vehicles = vec![
            vehicle("ramp.1", Kind::Cav, Origin::Ramp, 250.0, 0, 25.0),
            vehicle("main.2", Kind::Cav, Origin::Main, 248.0, 1, 25.0),
            vehicle("main.3", Kind::Cav, Origin::Main, 1250.0, 1, 28.0),
            vehicle("main.4", Kind::Hdv, Origin::Main, 1285.0, 1, 22.0),
            vehicle("main.5", Kind::Cav, Origin::Main, 600.0, 2, 30.0),
        ];
        let scene = Scene::on_paper_road(0.0, vehicles);
        let budget = Budget {
            nodes: 200,
            time_ms: None,
        };
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                with_grouping(&scene, &sp, &[], budget.clone(), true, |p| {
                    let everyone: Vec<usize> = (0..5).collect();
                    let root = p.plan_root(&mut PbsStats::default());
                    let linked = p.all_conflicts(&root.tracks, &everyone);
                    (p.solve(), linked)
                })
            })
        };
        let ((one, linked), (four, _)) = (on(1), on(4));
        // The root's conflicts link 0–1 and 2–3 only: two groups, and 4 alone.
        let pairs: Vec<(usize, usize)> = linked.iter().map(|&(_, a, b)| (a, b)).collect();
        assert!(
            pairs.contains(&(0, 1))
                && pairs
                    .iter()
                    .all(|&(a, b)| (a, b) == (0, 1) || (a, b) == (2, 3)),
            "{pairs:?}"
        );
        assert!(conflict_free(&one, &scene), "{:?}", one.stats);
        assert_eq!(one.trajectories, four.trajectories);
        assert_eq!(one.edges, four.edges);
        assert!(!one.stats.fallback && one.stats.nodes >= 1);
    }

    #[test]
    fn two_cavs_whose_plans_cross_one_yields() {
        // A ramp CAV merging from the acceleration lane right beside a main-road CAV: alone,
        // each would take the same space.
        let sp = spy();
        let (sol, scene) = solve(
            vec![
                vehicle("ramp.1", Kind::Cav, Origin::Ramp, 250.0, 0, 25.0),
                vehicle("main.2", Kind::Cav, Origin::Main, 247.0, 1, 25.0),
            ],
            &sp,
        );
        assert!(sol.stats.nodes >= 1, "the root conflicts: {:?}", sol.stats);
        assert!(
            !sol.stats.fallback && sol.stats.conflicts_left == 0,
            "{:?}",
            sol.stats
        );
        assert!(conflict_free(&sol, &scene));
        assert!(sol.plans.iter().all(Option::is_some));
        // The paper's claim: planned BK-M-A*'s way, each CAV alone against the other's
        // constant-speed prediction, the two plans conflict; BK-PBS (above) resolves it.
        let m = Mastar::on_paper_road();
        let lc = LaneChanges::default();
        let predicted: Vec<Trajectory> = (0..2)
            .map(|j| ConstantSpeed::new(&Config::default()).predict(&scene, j, &[], 20))
            .collect();
        let alone: Vec<Arc<Trajectory>> = (0..2)
            .map(|i| {
                let others = [&predicted[1 - i]];
                let req = lc.request(&scene, i, 0.2, &others, None);
                Arc::new(m.plan(&req).expect("a plan alone").trajectory)
            })
            .collect();
        let independent = Solution {
            trajectories: alone,
            plans: vec![None, None],
            edges: Vec::new(),
            stats: PbsStats::default(),
        };
        assert!(
            !conflict_free(&independent, &scene),
            "BK-M-A* leaves the conflict"
        );
    }

    #[test]
    fn cav_and_hdv_merging_into_one_gap_explore_both_branches() {
        // A ramp HDV deep in the merge zone (about to merge) and a CAV beside it on the main
        // road: the branch giving the CAV priority re-predicts the HDV conditioned on the CAV's
        // plan; the other replans the CAV around the HDV.
        let sp = spy();
        let (sol, scene) = solve(
            vec![
                vehicle("ramp.1", Kind::Hdv, Origin::Ramp, 280.0, 0, 24.0),
                vehicle("main.2", Kind::Cav, Origin::Main, 276.0, 1, 25.0),
            ],
            &sp,
        );
        assert!(
            sp.conditioned.load(Ordering::SeqCst) >= 1,
            "CAV ≺ HDV branch re-predicts the HDV"
        );
        assert!(
            sol.stats.mastar_calls >= 2,
            "HDV ≺ CAV branch replans the CAV: {:?}",
            sol.stats
        );
        assert!(
            !sol.stats.fallback && sol.stats.conflicts_left == 0,
            "{:?}",
            sol.stats
        );
        assert!(conflict_free(&sol, &scene));
    }

    #[test]
    fn unresolvable_scene_falls_back_to_the_best_node() {
        // A CAV at 35 m/s 1 m behind cars standing in both lanes: nothing avoids them.
        let sp = spy();
        let (sol, _) = solve(
            vec![
                vehicle("main.1", Kind::Cav, Origin::Main, 100.0, 1, 35.0),
                vehicle("main.2", Kind::Hdv, Origin::Main, 106.0, 1, 0.0),
                vehicle("main.3", Kind::Hdv, Origin::Main, 106.0, 2, 0.0),
            ],
            &sp,
        );
        assert!(sol.stats.fallback, "{:?}", sol.stats);
        assert!(sol.stats.conflicts_left >= 1);
        assert_eq!(sol.trajectories.len(), 3);
    }

    #[test]
    fn an_exhausted_budget_returns_the_best_node_and_says_why() {
        let cross = || {
            vec![
                vehicle("ramp.1", Kind::Cav, Origin::Ramp, 250.0, 0, 25.0),
                vehicle("main.2", Kind::Cav, Origin::Main, 247.0, 1, 25.0),
            ]
        };
        // No time at all: the root is all there is.
        let (sol, _) = solve_within(
            cross(),
            &spy(),
            Budget {
                nodes: 200,
                time_ms: Some(0.0),
            },
        );
        assert!(
            sol.stats.timed_out && sol.stats.fallback && sol.stats.nodes == 0,
            "{:?}",
            sol.stats
        );
        assert!(sol.plans.iter().all(Option::is_some), "root plans are kept");
        // No nodes at all: the same, without the time-out flag.
        let (sol, _) = solve_within(
            cross(),
            &spy(),
            Budget {
                nodes: 0,
                time_ms: None,
            },
        );
        assert!(!sol.stats.timed_out && sol.stats.fallback && sol.stats.nodes == 0);
    }

    #[test]
    fn same_input_same_plan() {
        let mk = || {
            vec![
                vehicle("ramp.1", Kind::Cav, Origin::Ramp, 250.0, 0, 25.0),
                vehicle("main.2", Kind::Cav, Origin::Main, 247.0, 1, 25.0),
                vehicle("main.3", Kind::Hdv, Origin::Main, 290.0, 1, 20.0),
                vehicle("main.4", Kind::Cav, Origin::Main, 200.0, 2, 33.0),
            ]
        };
        let (a, _) = solve(mk(), &spy());
        let (b, _) = solve(mk(), &spy());
        assert_eq!(a.stats, b.stats);
        for (x, y) in a.trajectories.iter().zip(&b.trajectories) {
            assert_eq!(x.poses, y.poses);
        }
    }

    #[test]
    fn a_committed_yield_carries_into_the_next_round() {
        // R2: a CAV that started a cut-in relying on another CAV yielding keeps that priority
        // next round (it once started afresh, and the follower could take the gap back).
        // Two main-road CAVs in one lane, the follower faster: committed "0 ≺ 1", the follower
        // plans around the leader from the root on, and the edge is in the answer.
        let sp = spy();
        let vehicles = vec![
            vehicle("main.1", Kind::Cav, Origin::Main, 130.0, 1, 25.0),
            vehicle("main.2", Kind::Cav, Origin::Main, 112.0, 1, 33.0),
        ];
        let budget = Budget {
            nodes: 200,
            time_ms: None,
        };
        let (sol, scene) = solve_committed(vehicles, &sp, budget, &[(0, 1)]);
        assert!(sol.edges.contains(&(0, 1)), "{:?}", sol.edges);
        assert!(conflict_free(&sol, &scene));
    }

    /// Predicts the standing ramp HDV merging into lane 1 — unless conditioned on CAV plans,
    /// when it (over-optimistically) stays put; CAVs at constant speed.
    struct Optimist;

    impl Predictor for Optimist {
        fn name(&self) -> &'static str {
            "optimist"
        }
        fn predict(
            &self,
            scene: &Scene,
            i: usize,
            on: &[&Trajectory],
            horizon: usize,
        ) -> Trajectory {
            let v = &scene.vehicles[i];
            let mut t = Trajectory::straight(v.s, v.lane as f64 * 4.5, v.speed, horizon, 0.2);
            if v.kind == Kind::Hdv && on.is_empty() {
                for (k, p) in t.poses.iter_mut().enumerate() {
                    p.y = (k as f64 * 0.9).min(4.5);
                }
            }
            t
        }
    }

    #[test]
    fn a_forced_ramp_merge_survives_conditioned_re_prediction() {
        // R4: a ramp HDV standing at the lane end will be forced in; a conditioned
        // re-prediction that has it stay put must not make the CAV beside it drive on.
        let scene = Scene::on_paper_road(
            0.0,
            vec![
                vehicle("ramp.1", Kind::Hdv, Origin::Ramp, 324.0, 0, 0.0),
                vehicle("main.2", Kind::Cav, Origin::Main, 300.0, 1, 20.0),
            ],
        );
        let budget = Budget {
            nodes: 200,
            time_ms: None,
        };
        with_problem(&scene, &Optimist, &[], budget, |problem| {
            assert!(problem.merge_is_certain(0));
            let sol = problem.solve();
            let hdv = &sol.trajectories[0];
            assert!(
                (hdv.poses[20].y - 4.5).abs() < 1e-9,
                "the merge stands: {:?}",
                hdv.poses[20]
            );
            assert!(
                !problem.conflict_between(0, 1, &sol.trajectories),
                "{:?}",
                sol.stats
            );
        });
    }
}
