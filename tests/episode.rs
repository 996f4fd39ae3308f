//! Whole episodes on real SUMO, per controller.

mod common;

use bkpbs::config::Config;
use bkpbs::controller::{CavHandling, Command, Controller, Maneuver, Source};
use bkpbs::episode::demand::PlannedVehicle;
use bkpbs::episode::metrics::Outcome;
use bkpbs::episode::{self, EpisodeResult};
use bkpbs::model::scene::{Kind, Origin, Scene};
use common::episode_of as episode;

fn check_accounting(r: &EpisodeResult) {
    let s = &r.summary;
    assert_eq!(s.steps, 400);
    assert!(s.inserted > 30, "{s:?}");
    assert_eq!(s.inserted, s.arrived + s.crashed + s.present, "{s:?}");
    assert_eq!(Some(s.inserted + s.never_inserted), s.scheduled);
    assert_eq!(
        Some(r.vehicles.len()),
        s.scheduled,
        "a row for every vehicle planned"
    );
    for v in &r.vehicles {
        match v.outcome {
            Outcome::Arrived => {
                let t = v.arrival_time.unwrap();
                assert!(t > v.insert_time && v.crash_time.is_none(), "{v:?}");
                // Nobody beats the free-flow time (up to the 0.2 s step of insertion).
                assert!(v.delay().unwrap() > -0.25, "{v:?}");
            }
            Outcome::Crashed => assert!(v.crash_time.is_some() && v.arrival_time.is_none()),
            Outcome::Present => assert!(v.arrival_time.is_none() && v.crash_time.is_none()),
            Outcome::NeverInserted => {
                assert!(v.insert_time.is_nan() && v.covered == 0.0, "{v:?}");
                continue;
            }
        }
        assert!(v.insert_lane >= 0 && v.insert_speed.is_finite(), "{v:?}");
    }
    // Every crashed vehicle is accounted for by a collision event.
    for v in r.vehicles.iter().filter(|v| v.outcome == Outcome::Crashed) {
        assert!(r
            .collisions
            .iter()
            .any(|c| c.collider == v.id || c.victim == v.id));
    }
}

#[test]
fn full_episode_with_sumo_driving_the_cavs() {
    let r = episode("sumo", 0.5, 3000.0, 11);
    check_accounting(&r);
    assert!(r.summary.arrived > 20);
}

#[test]
fn full_episode_with_idm_mobil() {
    let r = episode("idm-mobil", 0.5, 3000.0, 11);
    check_accounting(&r);
    assert!(r.summary.arrived > 20);
    // Every vehicle's delay is finite and the mean lies in a plausible band for this density.
    let d = r.summary.travel().mean_delay_s.unwrap();
    assert!((0.0..30.0).contains(&d), "{d}");
    // Ramp CAVs do merge (the acceleration lane does not jam for good).
    assert!(r
        .vehicles
        .iter()
        .any(|v| v.origin == Origin::Ramp && v.kind == Kind::Cav && v.outcome == Outcome::Arrived));
}

#[test]
fn same_seed_gives_identical_csv_and_other_seed_differs() {
    let a = episode("idm-mobil", 0.8, 2500.0, 5);
    let b = episode("idm-mobil", 0.8, 2500.0, 5);
    assert_eq!(a.episode_csv(), b.episode_csv());
    assert_eq!(a.vehicles_csv(), b.vehicles_csv());
    assert_eq!(a.collisions_csv(), b.collisions_csv());
    let c = episode("idm-mobil", 0.8, 2500.0, 6);
    assert_ne!(a.vehicles_csv(), c.vehicles_csv());
}

/// Stages a rear-end crash: CAV `main.0` brakes to a stand, every other CAV holds its speed.
struct StopFirstKeepOthers;

impl Controller for StopFirstKeepOthers {
    fn name(&self) -> &'static str {
        "staged"
    }
    fn handling(&self) -> CavHandling {
        CavHandling::Commanded
    }
    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>) {
        for (i, v) in scene.vehicles.iter().enumerate() {
            if v.kind == Kind::Cav {
                let speed = if &*v.id == "main.0" {
                    (v.speed - 1.0).max(0.0)
                } else {
                    v.speed
                };
                out.push(Command {
                    vehicle: i,
                    maneuver: Maneuver {
                        speed,
                        lane_change: None,
                    },
                    source: Source::Rule,
                });
            }
        }
    }
}

fn planned(id: &str, kind: Kind, depart: f64, speed: f64) -> PlannedVehicle {
    PlannedVehicle {
        id: id.into(),
        kind,
        origin: Origin::Main,
        entry: 0,
        exit: None,
        depart,
        depart_lane: 0,
        depart_speed: speed,
        desired_speed: 35.0,
    }
}

#[test]
fn staged_collision_behind_a_stopped_vehicle_is_controllable() {
    let mut c = Config::default();
    c.scenario.steps = 150;
    // main.0 enters first and brakes to a stand at 5 m/s²; main.1 enters 2 s later and is told
    // to keep its speed: it runs into the stopped car.
    let demand = vec![
        planned("main.0", Kind::Cav, 0.0, 25.0),
        planned("main.1", Kind::Cav, 2.0, 25.0),
    ];
    let r = episode::run_with_demand(&c, &mut StopFirstKeepOthers, &demand).unwrap();
    let s = &r.summary;
    assert_eq!(
        (s.inserted, s.crashed, s.controllable_crashed),
        (2, 2, 2),
        "{s:?}"
    );
    assert!((s.controllable_collision_rate.unwrap() - 1.0).abs() < 1e-12);
    assert_eq!(s.hdv_collisions, 0);
    assert_eq!(r.collisions.len(), 1);
    let e = &r.collisions[0];
    assert_eq!(
        (e.collider.as_str(), e.victim.as_str()),
        ("main.1", "main.0")
    );
    assert!(e.controllable());
    let hit = r.vehicles.iter().find(|v| v.id == "main.1").unwrap();
    assert_eq!(hit.crashed_with, vec!["main.0".to_string()]);
    assert_eq!(hit.outcome, Outcome::Crashed);
}

#[test]
fn an_hdv_behind_the_stopped_cav_brakes_in_time() {
    // Same staging with an HDV behind: SUMO's HDV model brakes, nothing crashes.
    let mut c = Config::default();
    c.scenario.steps = 150;
    let demand = vec![
        planned("main.0", Kind::Cav, 0.0, 25.0),
        planned("main.1", Kind::Hdv, 2.0, 25.0),
    ];
    let r = episode::run_with_demand(&c, &mut StopFirstKeepOthers, &demand).unwrap();
    assert_eq!(
        (r.summary.inserted, r.summary.crashed),
        (2, 0),
        "{:?}",
        r.summary
    );
}

#[test]
fn t_star_from_the_inserted_speed_when_asked() {
    // Same episode twice: t* from the drawn speed (default) and from SUMO's insertion speed.
    let mut c = bkpbs::config::Config::default();
    c.scenario.steps = 150;
    c.scenario.lambda = 3000.0;
    let drawn = episode::run(&c, "idm-mobil").unwrap();
    c.metrics.t_star_speed = bkpbs::config::TStarSpeed::Inserted;
    let inserted = episode::run(&c, "idm-mobil").unwrap();
    let (accel, v_max) = (c.scenario.free_flow_accel, c.scenario.v_max);
    let mut slower = 0;
    let inserted_only = |r: &EpisodeResult| -> Vec<bkpbs::episode::metrics::VehicleRecord> {
        r.vehicles
            .iter()
            .filter(|v| v.inserted())
            .cloned()
            .collect()
    };
    for (d, i) in inserted_only(&drawn).iter().zip(&inserted_only(&inserted)) {
        assert_eq!((&d.id, d.insert_speed), (&i.id, i.insert_speed));
        let t = bkpbs::model::kinematics::free_flow_time;
        assert_eq!(d.t_star, t(d.distance, d.scheduled_speed, accel, v_max));
        assert_eq!(i.t_star, t(i.distance, i.insert_speed, accel, v_max));
        slower += usize::from(i.insert_speed < i.scheduled_speed - 0.01);
    }
    assert!(
        slower > 0,
        "some vehicle entered slower than drawn, so the variants differ"
    );
}
