//! BK-PBS on real SUMO: full episodes at both densities and both ends of the penetration range.

mod common;

use bkpbs::episode;

fn run(alpha: f64, lambda: f64, seed: u64) -> episode::EpisodeResult {
    common::episode_of("bk-pbs", alpha, lambda, seed)
}

#[test]
fn full_episodes_at_both_densities_and_penetrations() {
    for (alpha, lambda) in [(0.4, 2500.0), (0.8, 2500.0), (0.4, 3000.0), (0.8, 3000.0)] {
        let r = run(alpha, lambda, 4);
        let s = &r.summary;
        let p = &s.plan_stats;
        assert_eq!((s.steps, s.planner.as_str()), (400, "bk-pbs"));
        assert_eq!(s.inserted, s.arrived + s.crashed + s.present, "{s:?}");
        assert!(s.arrived > 25, "{s:?}");
        assert!(p.searches > 0 && p.predictions > 0, "{p:?}");
        // Most rounds end conflict-free; the budget is never what stops them by default.
        assert!(p.pbs_fallbacks * 3 < 399, "{p:?}");
        assert_eq!(p.time_budget_hits, 0);
        assert!(
            s.controllable_collision_rate < 0.1,
            "α={alpha} λ={lambda}: {s:?}"
        );
        eprintln!(
            "bk-pbs α={alpha} λ={lambda}: delay {:.2} s, crashed {}, PBS nodes {}, fallback rounds {}, M-A* calls {}, predictions {}",
            s.mean_delay_s.unwrap_or(f64::NAN),
            s.crashed,
            p.pbs_nodes,
            p.pbs_fallbacks,
            p.searches,
            p.predictions
        );
    }
}

#[test]
fn same_seed_same_csv_despite_parallel_search() {
    let a = run(0.8, 3000.0, 3);
    let b = run(0.8, 3000.0, 3);
    assert_eq!(a.episode_csv(), b.episode_csv());
    assert_eq!(a.vehicles_csv(), b.vehicles_csv());
}
