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
            s.controllable_collision_rate.unwrap() < 0.1,
            "α={alpha} λ={lambda}: {s:?}"
        );
        eprintln!(
            "bk-pbs α={alpha} λ={lambda}: delay {:.2} s, crashed {}, PBS nodes {}, fallback rounds {}, M-A* calls {}, predictions {}",
            s.travel().mean_delay_s.unwrap_or(f64::NAN),
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

/// The `episode.csv` value of `column`.
fn csv_value(r: &episode::EpisodeResult, column: &str) -> String {
    let text = String::from_utf8(r.episode_csv()).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = header.iter().position(|h| *h == column).unwrap();
    row[at].to_string()
}

#[test]
fn the_shield_counts_its_overrides_and_is_silent_when_off() {
    // An episode of the paper grid in which the shield acts (7 overrides on SUMO 1.15, 8 on 1.28).
    let mut c = bkpbs::config::Config::default();
    c.scenario.alpha = 0.5;
    c.scenario.lambda = 3000.0;
    c.scenario.seed = 1;
    let on = episode::run(&c, "bk-pbs").unwrap();
    let text = String::from_utf8(on.episode_csv()).unwrap();
    assert!(
        text.starts_with("planner,") && text.contains(",time_budget_hits,shield_overrides\n"),
        "{text}"
    );
    let overrides = on.summary.plan_stats.shield_overrides;
    assert!(overrides > 0, "{:?}", on.summary);
    assert_eq!(csv_value(&on, "shield_overrides"), overrides.to_string());
    c.safety.shield = false;
    let off = episode::run(&c, "bk-pbs").unwrap();
    assert_eq!(csv_value(&off, "shield_overrides"), "0");
    eprintln!(
        "bk-pbs α=0.5 λ=3000 seed 1: shield on: {overrides} overrides, {} controllable crashes, delay {:?}; off: {} controllable crashes, delay {:?}",
        on.summary.controllable_crashed,
        on.summary.travel().mean_delay_s,
        off.summary.controllable_crashed,
        off.summary.travel().mean_delay_s
    );
}

#[test]
fn the_grid_cell_that_crashed_no_longer_does() {
    // Regression: bk-pbs at α 0.8, λ 3000, seed 0 (the first reference grid's demand, α drawn
    // per vehicle) crashed two CAVs in a merge: a merging CAV had no plan while its lane change
    // was under way. The planner alone (shield off) and with the shield must avoid it.
    for shield in [false, true] {
        let mut c = bkpbs::config::Config::default();
        c.scenario.alpha = 0.8;
        c.scenario.lambda = 3000.0;
        c.scenario.seed = 0;
        c.demand.cav_share = bkpbs::config::CavShare::Probability;
        c.safety.shield = shield;
        let s = episode::run(&c, "bk-pbs").unwrap().summary;
        assert_eq!(s.controllable_crashed, 0, "shield {shield}: {s:?}");
    }
}
