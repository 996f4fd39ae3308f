//! Tests of the BK-PBS round: conflicts resolved, both branches explored, fallbacks, budgets,
//! determinism, commitments and independent groups.

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
    fn predict(&self, scene: &Scene, i: usize, on: &[&Trajectory], horizon: usize) -> Trajectory {
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

/// Solves the round of `vehicles` and checks that it was resolved: a node without conflicts
/// found (no fallback, none left) whose trajectories are indeed conflict-free.
fn solve_resolved(vehicles: Vec<VehicleState>, spy: &Spy) -> (Solution, Scene) {
    let (sol, scene) = solve(vehicles, spy);
    assert!(
        !sol.stats.fallback && sol.stats.conflicts_left == 0,
        "{:?}",
        sol.stats
    );
    assert!(conflict_free(&sol, &scene), "{:?}", sol.stats);
    (sol, scene)
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
    let (sol, scene) = solve_resolved(
        vec![
            vehicle("ramp.1", Kind::Cav, Origin::Ramp, 250.0, 0, 25.0),
            vehicle("main.2", Kind::Cav, Origin::Main, 247.0, 1, 25.0),
        ],
        &spy(),
    );
    assert!(sol.stats.nodes >= 1, "the root conflicts: {:?}", sol.stats);
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
    let (sol, _) = solve_resolved(
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
    fn predict(&self, scene: &Scene, i: usize, on: &[&Trajectory], horizon: usize) -> Trajectory {
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
