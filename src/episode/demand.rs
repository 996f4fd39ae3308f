//! Per-episode traffic demand, generated deterministically from (λ, α, seed).
//!
//! Arrivals form Poisson processes: the main road at rate (1 − r)·λ, each vehicle on any main
//! lane with equal probability, and the on-ramps at rate r·λ together, shared equally or by
//! `demand.ramp_weights`, where r is `demand.ramp_share`.
//! α is the share of CAVs among the episode's vehicles (`demand.cav_share = "exact"`, the
//! paper's definition: round(α·n) CAVs placed at random) or, optionally, each vehicle's
//! probability of being a CAV (`"probability"`). Insertion speeds and HDV desired speeds are uniform
//! over their configured ranges; CAVs want v_max. Depart times are rounded up to the step grid.
//! The vehicles enter SUMO through [`crate::episode::entry`], which waits for room at the entry.

use std::fmt::Write as _;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::config::ConfigError;
use crate::config::{CavShare, Config};
use crate::episode::EpisodeError;
use crate::model::road::Road;
use crate::model::scene::{Kind, Origin};
use crate::sumo::files::routes_xml;
use crate::sumo::frame::scenario_road;

/// Random stream of the demand (other streams of the same seed drive other random choices).
pub const DEMAND_STREAM: u64 = 1;

/// One vehicle the episode will try to insert.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedVehicle {
    /// SUMO vehicle id: `<entry name>.<n>`, n its place in the episode's arrival order.
    pub id: String,
    /// CAV or HDV.
    pub kind: Kind,
    /// Main road or on-ramp.
    pub origin: Origin,
    /// Where it enters: an index into the road's entries (0 the main road, then the ramps), whose
    /// name is also its SUMO route.
    pub entry: usize,
    /// The off-ramp it leaves by (an index into the road's exits), if any.
    pub exit: Option<usize>,
    /// Scheduled insertion time (s).
    pub depart: f64,
    /// SUMO lane index on the first edge of the route.
    pub depart_lane: u32,
    /// Insertion speed (m/s, rounded to 0.01).
    pub depart_speed: f64,
    /// Desired speed (m/s, rounded to 0.01): v_max for a CAV, drawn for an HDV.
    pub desired_speed: f64,
}

/// The vehicles arriving on the scenario's network (see [`generate`]).
///
/// # Errors
/// A network file that cannot be read or is not a merge, or ramp weights that do not fit it.
pub fn generate_for(config: &Config) -> Result<Vec<PlannedVehicle>, EpisodeError> {
    let road = scenario_road(&config.scenario)?;
    check_entries(config, &road)?;
    Ok(generate(config, &road))
}

/// Whether the demand's settings fit `road`: one ramp weight per on-ramp, if any are given.
///
/// # Errors
/// [`ConfigError::Invalid`] naming `demand.ramp_weights`.
pub fn check_entries(config: &Config, road: &Road) -> Result<(), ConfigError> {
    let (given, ramps) = (config.demand.ramp_weights.len(), road.ramp_zones().count());
    if given == 0 || given == ramps {
        return Ok(());
    }
    Err(ConfigError::Invalid {
        field: "demand.ramp_weights",
        value: format!("{given} weights for a network of {ramps} on-ramps"),
        reason: "give one weight per on-ramp, in order along the road",
    })
}

/// Random stream that sends HDVs off by the off-ramps (`demand.exit_share`).
pub const EXIT_STREAM: u64 = 4;

/// With `demand.exit_share` above 0 and off-ramps on `road`: which main-road HDVs leave, and
/// by which off-ramp, drawn from a stream of their own (one draw per vehicle, so the rest of the
/// demand is the same with or without exits).
fn draw_exits(config: &Config, road: &Road, vehicles: &mut [PlannedVehicle]) {
    let share = config.demand.exit_share;
    if share <= 0.0 || road.exits.is_empty() {
        return;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(config.scenario.seed);
    rng.set_stream(EXIT_STREAM);
    for v in vehicles {
        let (leaves, which) = (rng.gen_bool(share), rng.gen_range(0..road.exits.len()));
        if leaves && v.kind == Kind::Hdv && v.origin == Origin::Main {
            v.exit = road.exit_route(v.entry, which).map(|_| which);
        }
    }
}

/// The SUMO route of planned vehicle `v` on `road`: its entry's, or the one out by its exit.
pub fn route_name(road: &Road, v: &PlannedVehicle) -> String {
    match v.exit {
        Some(x) => road.exit_route_name(v.entry, x),
        None => road.entries[v.entry].name.clone(),
    }
}

/// Random stream that places the CAVs when `demand.cav_share` is exact.
pub const CAV_PLACEMENT_STREAM: u64 = 3;

/// Draws the vehicles arriving on `road` within the episode's horizon, sorted by depart time.
///
/// Departures are rounded up to the step grid, and only those at or before the last simulated
/// step are kept: a vehicle due later could never enter.
pub fn generate(config: &Config, road: &Road) -> Vec<PlannedVehicle> {
    let sc = &config.scenario;
    let mut rng = ChaCha8Rng::seed_from_u64(sc.seed);
    rng.set_stream(DEMAND_STREAM);
    let events = arrivals(config, road.entries.len() - 1, &mut rng);
    let cavs = exact_cavs(config, events.len());
    let [v_lo, v_hi] = config.demand.insertion_speed;
    let [d_lo, d_hi] = config.demand.hdv_desired_speed;
    let mut vehicles = events
        .into_iter()
        .enumerate()
        .map(|(n, (t, entry))| {
            let origin = if entry == 0 {
                Origin::Main
            } else {
                Origin::Ramp
            };
            // Drawn in either mode, so the exact mode changes who is a CAV and nothing else.
            let drawn_cav = rng.gen_bool(sc.alpha);
            let kind = match &cavs {
                Some(chosen) if chosen[n] => Kind::Cav,
                Some(_) => Kind::Hdv,
                None if drawn_cav => Kind::Cav,
                None => Kind::Hdv,
            };
            let depart_lane = match origin {
                Origin::Main => rng.gen_range(0..road.main_lanes as u32),
                Origin::Ramp => 0,
            };
            let depart_speed = rng.gen_range(v_lo..=v_hi);
            let hdv_desired = rng.gen_range(d_lo..=d_hi);
            let desired_speed = match kind {
                Kind::Cav => sc.v_max,
                Kind::Hdv => hdv_desired,
            };
            PlannedVehicle {
                id: format!("{}.{n}", road.entries[entry].name),
                kind,
                origin,
                entry,
                exit: None,
                depart: t,
                depart_lane,
                depart_speed: (depart_speed * 100.0).round() / 100.0,
                desired_speed: (desired_speed * 100.0).round() / 100.0,
            }
        })
        .collect::<Vec<_>>();
    draw_exits(config, road, &mut vehicles);
    vehicles
}

/// Arrival events (time on the step grid, entry: 0 the main road, k the k-th of `ramps`
/// on-ramps) of every entry, sorted, up to the last simulated step.
fn arrivals(config: &Config, ramps: usize, rng: &mut ChaCha8Rng) -> Vec<(f64, usize)> {
    let sc = &config.scenario;
    let horizon = sc.steps as f64 * sc.dt;
    let last_step = sc.steps.saturating_sub(1) as f64 * sc.dt;
    let rate_main = sc.lambda * (1.0 - config.demand.ramp_share) / 3600.0;
    let weights = &config.demand.ramp_weights;
    let rate_ramp = |k: usize| {
        let all = sc.lambda * config.demand.ramp_share / 3600.0;
        if weights.len() == ramps {
            all * weights[k - 1] / weights.iter().sum::<f64>()
        } else {
            all / ramps.max(1) as f64
        }
    };
    let mut events: Vec<(f64, usize)> = arrival_times(rng, rate_main, horizon)
        .into_iter()
        .map(|t| (t, 0))
        .collect();
    for k in 1..=ramps {
        let times = arrival_times(rng, rate_ramp(k), horizon);
        events.extend(times.into_iter().map(|t| (t, k)));
    }
    events.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let on_grid = |t: f64| ((t / sc.dt).ceil() * sc.dt * 1e6).round() / 1e6;
    events.retain_mut(|(t, _)| {
        *t = on_grid(*t);
        *t <= last_step + 1e-9
    });
    events
}

/// With `demand.cav_share = exact`, which of `n` vehicles are CAVs: round(α·n) of them, chosen
/// uniformly at random from a stream of their own; `None` in the probability mode.
fn exact_cavs(config: &Config, n: usize) -> Option<Vec<bool>> {
    if config.demand.cav_share != CavShare::Exact {
        return None;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(config.scenario.seed);
    rng.set_stream(CAV_PLACEMENT_STREAM);
    let k = (config.scenario.alpha * n as f64).round() as usize;
    let mut chosen = vec![false; n];
    for i in rand::seq::index::sample(&mut rng, n, k.min(n)) {
        chosen[i] = true;
    }
    Some(chosen)
}

/// Event times of a Poisson process of `rate` (1/s) on [0, horizon).
fn arrival_times(rng: &mut ChaCha8Rng, rate: f64, horizon: f64) -> Vec<f64> {
    let mut out = Vec::new();
    if rate <= 0.0 {
        return out;
    }
    let mut t = 0.0;
    loop {
        let u: f64 = rng.gen_range(f64::EPSILON..1.0);
        t += -u.ln() / rate;
        if t >= horizon {
            return out;
        }
        out.push(t);
    }
}

/// The demand on `road` as a SUMO route file, for inspection or for running it in SUMO alone.
pub fn route_file(road: &Road, vehicles: &[PlannedVehicle]) -> String {
    let routes = routes_xml(road);
    let mut xml = routes.trim_end().trim_end_matches("</routes>").to_string();
    for v in vehicles {
        let _ = writeln!(
            xml,
            "    <vehicle id=\"{}\" type=\"{}\" route=\"{}\" depart=\"{:.2}\" departLane=\"{}\" departPos=\"base\" departSpeed=\"{:.2}\"/>",
            v.id,
            v.kind.as_str(),
            route_name(road, v),
            v.depart,
            v.depart_lane,
            v.depart_speed
        );
    }
    xml.push_str("</routes>\n");
    xml
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gen(c: &Config) -> Vec<PlannedVehicle> {
        generate(c, &Road::paper_default())
    }

    #[test]
    fn shipped_demo_demand_matches_the_defaults() {
        let shipped = include_str!("../../sumo_net/demo.rou.xml");
        let generated = route_file(&Road::paper_default(), &gen(&Config::default()));
        assert_eq!(
            shipped, generated,
            "regenerate with `bkpbs demand --out sumo_net/demo.rou.xml`"
        );
    }

    fn config(alpha: f64, lambda: f64, seed: u64) -> Config {
        let mut c = Config::default();
        c.scenario.alpha = alpha;
        c.scenario.lambda = lambda;
        c.scenario.seed = seed;
        c
    }

    #[test]
    fn same_seed_same_demand_other_seed_other_demand() {
        assert_eq!(gen(&config(0.5, 3000.0, 7)), gen(&config(0.5, 3000.0, 7)));
        assert_ne!(gen(&config(0.5, 3000.0, 7)), gen(&config(0.5, 3000.0, 8)));
    }

    #[test]
    fn rates_and_penetration_match_over_many_seeds() {
        let c0 = Config::default();
        let horizon_h = c0.scenario.steps as f64 * c0.scenario.dt / 3600.0;
        for &(alpha, lambda) in &[(0.4, 2500.0), (0.8, 3000.0)] {
            let (mut n, mut cav, mut ramp) = (0usize, 0usize, 0usize);
            let seeds = 400;
            for seed in 0..seeds {
                for v in gen(&config(alpha, lambda, seed)) {
                    n += 1;
                    cav += (v.kind == Kind::Cav) as usize;
                    ramp += (v.origin == Origin::Ramp) as usize;
                }
            }
            let rate = n as f64 / (seeds as f64 * horizon_h);
            assert!(
                (rate - lambda).abs() / lambda < 0.02,
                "rate {rate} vs {lambda}"
            );
            let a = cav as f64 / n as f64;
            assert!((a - alpha).abs() < 0.02, "alpha {a} vs {alpha}");
            let r = ramp as f64 / n as f64;
            assert!((r - c0.demand.ramp_share).abs() < 0.02, "ramp share {r}");
        }
    }

    #[test]
    fn speeds_lie_in_their_ranges_and_departs_on_grid() {
        let c = config(0.5, 3000.0, 3);
        for v in gen(&c) {
            assert!((25.0..=35.0).contains(&v.depart_speed));
            if v.kind == Kind::Hdv {
                assert!((25.0..=35.0).contains(&v.desired_speed));
            } else {
                assert_eq!(v.desired_speed, 35.0);
            }
            let steps = v.depart / c.scenario.dt;
            assert!((steps - steps.round()).abs() < 1e-6);
            assert!(v.depart < 80.0 + 1e-9);
        }
    }

    #[test]
    fn departures_end_at_the_last_simulated_step() {
        // Regression: departures drawn in (79.8, 80) were rounded up to 80.0, a step the episode
        // never simulates, and counted as never inserted.
        let mut latest: f64 = 0.0;
        for seed in 0..200 {
            for v in gen(&config(0.5, 3000.0, seed)) {
                latest = latest.max(v.depart);
            }
        }
        assert!((latest - 79.8).abs() < 1e-9, "latest departure {latest}");
    }

    #[test]
    fn exact_share_makes_round_alpha_n_cavs() {
        for (alpha, seed) in [(0.5, 1), (0.4, 2), (0.8, 3), (0.6, 4)] {
            let d = gen(&config(alpha, 3000.0, seed));
            let cavs = d.iter().filter(|v| v.kind == Kind::Cav).count();
            assert_eq!(cavs, (alpha * d.len() as f64).round() as usize, "α {alpha}");
        }
    }

    #[test]
    fn probability_share_changes_only_who_is_a_cav() {
        let exact = config(0.5, 3000.0, 11);
        let mut prob = exact.clone();
        prob.demand.cav_share = CavShare::Probability;
        let (a, b) = (gen(&exact), gen(&prob));
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(
                (&x.id, x.depart, x.depart_lane, x.depart_speed),
                (&y.id, y.depart, y.depart_lane, y.depart_speed)
            );
        }
        let cavs = |d: &[PlannedVehicle]| d.iter().filter(|v| v.kind == Kind::Cav).count();
        assert_eq!(cavs(&a), (0.5 * a.len() as f64).round() as usize);
        // Over many seeds the probability mode averages α but single episodes vary.
        let shares: Vec<f64> = (0..50)
            .map(|seed| {
                let mut c = config(0.5, 3000.0, seed);
                c.demand.cav_share = CavShare::Probability;
                let d = gen(&c);
                cavs(&d) as f64 / d.len() as f64
            })
            .collect();
        assert!(shares.iter().any(|s| (s - 0.5).abs() > 0.05), "{shares:?}");
    }

    #[test]
    fn alpha_extremes_give_one_kind() {
        assert!(gen(&config(0.0, 3000.0, 1))
            .iter()
            .all(|v| v.kind == Kind::Hdv));
        assert!(gen(&config(1.0, 3000.0, 1))
            .iter()
            .all(|v| v.kind == Kind::Cav));
    }

    /// Off-ramps: only main-road HDVs leave, about the share asked for, by an exit their route
    /// passes; everything else about the demand is the same as without exits.
    #[test]
    fn main_road_hdvs_leave_by_the_off_ramps() {
        let mut road = Road::paper_default();
        road.exits.push(crate::model::road::Exit {
            name: "off1".into(),
            leaves: "acc".into(),
            edges: vec!["off".into()],
            end: ("off".into(), 100.0),
        });
        let mut c = config(0.5, 3000.0, 5);
        let plain = generate(&c, &road);
        c.demand.exit_share = 0.5;
        let leaving = generate(&c, &road);
        assert_eq!(plain.len(), leaving.len());
        let mut n = 0;
        for (a, b) in plain.iter().zip(&leaving) {
            assert_eq!(
                (&a.id, a.kind, a.depart, a.exit),
                (&b.id, b.kind, b.depart, None)
            );
            if let Some(x) = b.exit {
                n += 1;
                assert_eq!((b.kind, b.origin, x), (Kind::Hdv, Origin::Main, 0));
                assert_eq!(route_name(&road, b), "main-off1");
            }
        }
        let main_hdvs = leaving
            .iter()
            .filter(|v| v.kind == Kind::Hdv && v.origin == Origin::Main)
            .count();
        assert!(
            n > main_hdvs / 4 && n < 3 * main_hdvs / 4,
            "{n} of {main_hdvs}"
        );
        let xml = routes_xml(&road);
        assert!(
            xml.contains("<route id=\"main-off1\" edges=\"main_in acc off\"/>"),
            "{xml}"
        );
        assert!(
            xml.contains("<route id=\"ramp-off1\" edges=\"ramp acc off\"/>"),
            "{xml}"
        );
    }

    /// `demand.ramp_weights` splits the ramps' share; a list that does not fit the network is
    /// refused naming the setting.
    #[test]
    fn ramp_weights_split_the_ramp_demand() {
        let mut road = Road::paper_default();
        road.zones.push(crate::model::road::MergeZone {
            lane: crate::model::road::MERGE_LANE,
            ramp_start: 600.0,
            start: 800.0,
            end: 1000.0,
            weaving: false,
            ramp: true,
            nose: false,
        });
        road.entries[1].name = "ramp1".into();
        road.entries.push(crate::model::road::Entry::new(
            "ramp2",
            &["ramp2", "acc", "main_out"],
            40.0,
        ));
        let mut c = config(0.5, 6000.0, 1);
        c.scenario.steps = 4000;
        c.demand.ramp_share = 0.5;
        c.demand.ramp_weights = vec![3.0, 1.0];
        check_entries(&c, &road).unwrap();
        let d = generate(&c, &road);
        let count = |p: &str| d.iter().filter(|v| v.id.starts_with(p)).count() as f64;
        let ratio = count("ramp1.") / count("ramp2.");
        assert!((ratio - 3.0).abs() < 0.4, "{ratio}");
        c.demand.ramp_weights = vec![1.0];
        let e = check_entries(&c, &road).unwrap_err().to_string();
        assert!(
            e.contains("demand.ramp_weights") && e.contains("1 weights for a network of 2"),
            "{e}"
        );
        c.demand.ramp_weights = vec![0.0, 0.0];
        assert!(c.validate().is_err());
    }

    #[test]
    fn route_file_lists_every_vehicle() {
        let vs = gen(&config(0.5, 3000.0, 2));
        let xml = route_file(&Road::paper_default(), &vs);
        assert_eq!(xml.matches("<vehicle ").count(), vs.len());
        assert!(xml.contains("route=\"ramp\""));
    }
}
