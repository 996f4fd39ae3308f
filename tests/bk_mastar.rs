//! BK-M-A* on real SUMO: full episodes at both densities and both ends of the penetration range.

mod common;

use bkpbs::episode;
use bkpbs::episode::metrics::Outcome;

fn run(alpha: f64, lambda: f64, seed: u64) -> episode::EpisodeResult {
    common::episode_of("bk-mastar", alpha, lambda, seed)
}

#[test]
fn full_episodes_at_both_densities_and_penetrations() {
    let (mut early_ramp_cavs, mut early_ramp_cavs_arrived) = (0, 0);
    for (alpha, lambda) in [(0.4, 2500.0), (0.8, 2500.0), (0.4, 3000.0), (0.8, 3000.0)] {
        let r = run(alpha, lambda, 4);
        let s = &r.summary;
        assert_eq!(s.steps, 400);
        assert_eq!(s.planner, "bk-mastar");
        assert_eq!(s.inserted, s.arrived + s.crashed + s.present, "{s:?}");
        assert!(s.arrived > 25, "{s:?}");
        // Every CAV was planned every step it was in the network.
        assert!(s.plan_stats.searches > 0 && s.plan_stats.nodes_expanded > 0);
        // The planner keeps safe gaps: collisions involving CAVs stay rare.
        assert!(
            s.controllable_collision_rate.unwrap() < 0.1,
            "α={alpha} λ={lambda}: {s:?}"
        );
        // Ramp CAVs that entered in the first 40 s, and how many of them reached the end.
        let early: Vec<_> = r
            .vehicles
            .iter()
            .filter(|v| {
                v.origin == bkpbs::model::scene::Origin::Ramp
                    && v.kind == bkpbs::model::scene::Kind::Cav
                    && v.insert_time < 40.0
            })
            .collect();
        early_ramp_cavs += early.len();
        early_ramp_cavs_arrived += early
            .iter()
            .filter(|v| v.outcome == Outcome::Arrived)
            .count();
        eprintln!(
            "bk-mastar α={alpha} λ={lambda}: delay {:?} s, crashed {}, fallbacks {}, phase-2 {} of {} searches, {:.1} nodes/search",
            s.travel().mean_delay_s,
            s.crashed,
            s.plan_stats.fallbacks,
            s.plan_stats.phase2_plans,
            s.plan_stats.searches,
            s.plan_stats.nodes_expanded as f64 / s.plan_stats.searches as f64
        );
    }
    // Most merge. (Known limitation: a ramp CAV that has slowed below the 10 m/s a lane
    // change needs, with no gap, can stay at the end of the acceleration lane.)
    assert!(
        early_ramp_cavs_arrived * 2 >= early_ramp_cavs,
        "{early_ramp_cavs_arrived} of {early_ramp_cavs} early ramp CAVs arrived"
    );
}

#[test]
fn same_seed_same_csv() {
    let a = run(0.6, 3000.0, 2);
    let b = run(0.6, 3000.0, 2);
    assert_eq!(a.episode_csv(), b.episode_csv());
    assert_eq!(a.vehicles_csv(), b.vehicles_csv());
}
