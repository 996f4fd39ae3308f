//! The paper demand's loop on a scripted SUMO ([`crate::sumo::fake`]): what it sends when it
//! admits a vehicle, takes one over, books a collision or an arrival, and what it records of a
//! vehicle SUMO never inserts.

use super::*;
use crate::episode::observer::NoObserver;
use crate::model::scene::{Kind, Origin};
use crate::sumo::fake::{FakeSumo, FakeVehicle, Reading, Sent, Step};

/// A vehicle the demand scheduled at `depart` on entry `origin` (lane 0 of the main road, or
/// the ramp), at 25 m/s desiring 30 m/s.
fn planned(id: &str, kind: Kind, origin: Origin, depart: f64) -> PlannedVehicle {
    PlannedVehicle {
        id: id.into(),
        kind,
        origin,
        entry: usize::from(origin == Origin::Ramp),
        exit: None,
        depart,
        depart_lane: 0,
        depart_speed: 25.0,
        desired_speed: 30.0,
    }
}

/// The paper's loop on the embedded merge, for `planned` driven by IDM+MOBIL (which commands
/// its CAVs), stepped through `script`: each step the entry gate admits, the fake plays the
/// step, the loop books and plans after it (not after the last). The fake and the result.
fn run_script(planned: &[PlannedVehicle], script: Vec<Step>) -> (FakeSumo, EpisodeResult) {
    let config = Config {
        scenario: crate::config::Scenario {
            steps: script.len() as u32,
            ..Config::default().scenario
        },
        ..Config::default()
    };
    let road = frame::embedded_road();
    let controller = controller::by_name("idm-mobil", &config, &road).unwrap();
    let steps = script.len();
    let mut sim = FakeSumo::new(config.scenario.dt, script);
    sim.set_edge_codes(&frame::edge_names(&road)).unwrap();
    let planners = Planners::Own(controller);
    let mut episode = demand_episode(&config, planned, road, planners, Box::new(NoObserver));
    for k in 0..steps {
        let now = sim.time().unwrap();
        let regions = &episode.planning.regions;
        episode.traffic.admit(&mut sim, now, regions).unwrap();
        sim.step();
        episode.after_step(&mut sim, now, k + 1 < steps).unwrap();
    }
    episode.planning.close_timing(0.0, steps as u32);
    let result = finish(episode, "idm-mobil");
    (sim, result)
}

/// A CAV on the main road and an HDV on the ramp, both scheduled at 0.
fn a_cav_and_a_ramp_hdv() -> [PlannedVehicle; 2] {
    [
        planned("main.0", Kind::Cav, Origin::Main, 0.0),
        planned("ramp.0", Kind::Hdv, Origin::Ramp, 0.0),
    ]
}

/// Their first step: both inserted, 10 m into their first edges.
fn both_enter() -> Step {
    Step::default()
        .depart(FakeVehicle::new("main.0", "cav"))
        .depart(FakeVehicle::new("ramp.0", "hdv"))
        .read(Reading::on("main.0", "main_in", 0, 10.0, 25.0))
        .read(Reading::on("ramp.0", "ramp", 0, 10.0, 25.0))
}

/// Their second: 5 m further.
fn both_drive_on() -> Step {
    Step::default()
        .read(Reading::on("main.0", "main_in", 0, 15.0, 25.0))
        .read(Reading::on("ramp.0", "ramp", 0, 15.0, 25.0))
}

fn record<'a>(result: &'a EpisodeResult, id: &str) -> &'a VehicleRecord {
    let found = result.vehicles.iter().find(|v| v.id == id);
    found.unwrap_or_else(|| panic!("no record of {id}"))
}

/// Admitted at its scheduled time on its route and lane, a CAV is taken over (no checks, no
/// own lane changes) and then commanded a speed; a ramp HDV drives at its own desired speed and
/// changes lanes only when the merge rule says.
#[test]
fn a_cav_is_taken_over_and_a_ramp_hdv_waits_for_the_merge_rule() {
    let demand = a_cav_and_a_ramp_hdv();
    let script = vec![both_enter(), both_drive_on()];
    let (sim, result) = run_script(&demand, script);
    let cav = sim.sent_to("main.0");
    assert_eq!(
        cav[..3],
        [
            Sent::Add("main.0".into(), "main".into(), "cav".into(), 0, 25.0),
            Sent::SpeedMode("main.0".into(), 0),
            Sent::LaneChangeMode("main.0".into(), 0),
        ]
    );
    assert!(
        matches!(cav.last(), Some(Sent::Speed(_, v)) if *v >= 0.0),
        "{cav:?}"
    );
    let hdv = sim.sent_to("ramp.0");
    assert_eq!(
        hdv,
        [
            Sent::Add("ramp.0".into(), "ramp".into(), "hdv".into(), 0, 25.0),
            Sent::MaxSpeed("ramp.0".into(), 30.0),
            Sent::LaneChangeMode("ramp.0".into(), 0b10_0000_0000),
        ]
    );
    assert_eq!(record(&result, "main.0").insert_time, 0.0);
    assert_eq!(record(&result, "main.0").outcome, Outcome::Present);
    assert_eq!(result.summary.inserted, 2);
}

/// A collision removes both vehicles from SUMO at once and books them crashed, each with the
/// other; with a CAV in it, it is controllable.
#[test]
fn a_collision_removes_both_and_is_controllable_with_a_cav_in_it() {
    let demand = a_cav_and_a_ramp_hdv();
    let script = vec![
        both_enter(),
        both_drive_on().collide("ramp.0", "main.0"),
        Step::default(),
    ];
    let (sim, result) = run_script(&demand, script);
    let removed: Vec<&Sent> = (sim.sent.iter())
        .filter(|s| matches!(s, Sent::Remove(_)))
        .collect();
    assert_eq!(
        removed,
        [
            &Sent::Remove("ramp.0".into()),
            &Sent::Remove("main.0".into())
        ]
    );
    for (id, other) in [("main.0", "ramp.0"), ("ramp.0", "main.0")] {
        let r = record(&result, id);
        assert_eq!(r.outcome, Outcome::Crashed, "{id}");
        assert_eq!(r.crashed_with, [other], "{id}");
        assert!(r.controllable_crash, "{id}");
        assert!((r.crash_time.unwrap() - 0.2).abs() < 1e-9, "{id}");
    }
    assert_eq!(result.collisions.len(), 1);
    assert!(result.collisions[0].controllable());
    assert_eq!(result.summary.controllable_crashed, 2);
}

/// A vehicle SUMO reports arrived is booked so; one the demand scheduled that SUMO never
/// inserted is a record of its own, never inserted, at the end.
#[test]
fn arrivals_are_booked_and_a_vehicle_never_inserted_is_recorded() {
    let demand = [
        planned("main.0", Kind::Hdv, Origin::Main, 0.0),
        planned("main.1", Kind::Hdv, Origin::Main, 0.2),
    ];
    let script = vec![
        Step::default()
            .depart(FakeVehicle::new("main.0", "hdv"))
            .read(Reading::on("main.0", "main_out", 0, 100.0, 25.0)),
        Step::default().arrive("main.0"),
        Step::default(),
    ];
    let (sim, result) = run_script(&demand, script);
    assert!(sim
        .sent
        .iter()
        .any(|s| matches!(s, Sent::Add(id, ..) if id == "main.1")));
    let arrived = record(&result, "main.0");
    assert_eq!(arrived.outcome, Outcome::Arrived);
    assert!(arrived.arrival_time.is_some());
    let never = record(&result, "main.1");
    assert_eq!(never.outcome, Outcome::NeverInserted);
    assert_eq!(
        (result.summary.arrived, result.summary.never_inserted),
        (1, 1)
    );
}
