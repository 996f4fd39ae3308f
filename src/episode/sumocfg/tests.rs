//! The scenario episode's loop ([`ScenarioRun`]) on a scripted SUMO ([`FakeSumo`]): what it
//! books of departures, collisions, arrivals and region passages, and the commands it sends
//! when a planner takes a CAV over and hands it back.
//!
//! The region is the paper's merge built by hand ([`Road::paper_default`]): `main_in` (frame
//! `s` 0–150, SUMO lanes 0–1 = frame lanes 1–2), `acc` (150–330, lanes 0–2 = frame 0–2, the
//! acceleration lane 0), `main_out` (330–460, lanes 0–1 = frame 1–2) and `ramp` (−16.79–150,
//! frame lane 0). Its planner drives CAVs from `acc`'s start (150) to `main_out`'s (330).

use std::sync::Arc;

use super::run::ScenarioRun;
use super::{is_cav, regions, ScenarioResult};
use crate::config::Config;
use crate::episode::metrics::Outcome;
use crate::model::road::Road;
use crate::model::scene::Kind;
use crate::sumo::fake::{FakeSumo, FakeVehicle, Reading, Sent, Step};
use crate::sumo::SumoClient;

/// SUMO's step length in these tests (the configuration's default).
pub(super) const DT: f64 = 0.2;

/// The time the `k`-th scripted step (from 1) began: the time the loop books it at.
pub(super) fn began(k: u32) -> f64 {
    f64::from(k - 1) * DT
}

/// The episode's configuration: CAVs drawn with `alpha` on `seed`.
pub(super) fn config(alpha: f64, seed: u64) -> Config {
    let mut c = Config::default();
    c.scenario.dt = DT;
    c.scenario.alpha = alpha;
    c.scenario.seed = seed;
    c
}

/// The loop over the paper merge's one region, planned by `planner`.
pub(super) fn paper_run(config: &Config, planner: &str) -> ScenarioRun<'static> {
    let regions = regions(config, vec![Road::paper_default()], planner).unwrap();
    ScenarioRun::of_regions(config, regions)
}

/// SUMO playing `script`, the loop's edges registered, as the loop's caller does first.
pub(super) fn sumo_for(run: &ScenarioRun, script: Vec<Step>) -> FakeSumo {
    let mut sim = FakeSumo::new(DT, script);
    let names = run.planning.edge_names();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    sim.set_edge_codes(&names).unwrap();
    sim
}

/// Steps SUMO `steps` times, the loop booking and planning after each, as `ScenarioRun::run`.
pub(super) fn play(run: &mut ScenarioRun, sim: &mut FakeSumo, steps: u32) {
    for _ in 0..steps {
        let now = sim.time().unwrap();
        sim.step();
        run.after_step(sim, now, true).unwrap();
    }
}

/// The episode's result, SUMO's tripinfo output being `trips` (`<tripinfo>` elements).
pub(super) fn finish(mut run: ScenarioRun, trips: &str) -> ScenarioResult {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tripinfo.xml");
    std::fs::write(&path, format!("<tripinfos>\n{trips}\n</tripinfos>\n")).unwrap();
    run.close_timing(0.0);
    let options = super::SumoOptions {
        args: Vec::new(),
        notes: Vec::new(),
        tripinfo: path,
    };
    run.finish("test", &options).unwrap()
}

/// The record of vehicle `id`.
pub(super) fn record<'a>(result: &'a ScenarioResult, id: &str) -> &'a super::ScenarioVehicle {
    result.vehicles.iter().find(|v| v.id == id).unwrap()
}

/// The commands that switch SUMO's checks or hand speed back: every command but the planner's
/// speeds and lane changes.
fn hand_overs(sent: &[Sent]) -> Vec<Sent> {
    sent.iter()
        .filter(|s| !matches!(s, Sent::Speed(_, v) if *v >= 0.0))
        .filter(|s| !matches!(s, Sent::ChangeLane(..)))
        .cloned()
        .collect()
}

#[test]
fn every_departure_is_booked_with_its_type_time_and_drawn_kind() {
    let (alpha, seed) = (0.5, 11);
    let ids: Vec<String> = (0..12).map(|k| format!("flow.{k}")).collect();
    let type_of = |k: usize| if k % 3 == 0 { "truck" } else { "car" };
    // Four departures in each of three steps; nobody is read in the region.
    let fleet: Vec<FakeVehicle> = (ids.iter().enumerate())
        .map(|(k, id)| FakeVehicle::new(id, type_of(k)))
        .collect();
    let script = (fleet.chunks(4))
        .map(|four| Step {
            departed: four.to_vec(),
            ..Step::default()
        })
        .collect();
    let c = config(alpha, seed);
    let mut run = paper_run(&c, "idm-mobil");
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, 4);
    let result = finish(run, "");
    let booked: Vec<&str> = result.vehicles.iter().map(|v| v.id.as_str()).collect();
    assert_eq!(
        booked, ids,
        "one record per departure, in order of departure"
    );
    for (k, v) in result.vehicles.iter().enumerate() {
        assert_eq!(v.sumo_type, type_of(k), "{}", v.id);
        assert_eq!(v.depart_s, Some(began(k as u32 / 4 + 1)), "{}", v.id);
        let drawn = if is_cav(seed, &v.id, alpha) {
            Kind::Cav
        } else {
            Kind::Hdv
        };
        assert_eq!(v.kind, drawn, "{}", v.id);
        assert_eq!(v.outcome, Outcome::Present);
        assert_eq!((v.region.as_str(), v.region_enter_s), ("", None));
    }
    // The draw made both kinds here, so the kinds above are the draw's and no constant.
    let cavs = result.summary.inserted_cav;
    assert!(0 < cavs && cavs < ids.len(), "{cavs} CAVs");
    assert_eq!(result.summary.inserted, ids.len());
}

#[test]
fn cav_types_decide_the_kind_in_place_of_the_draw() {
    let mut c = config(0.0, 3);
    c.scenario.cav_types = vec!["cav".into()];
    let script = vec![Step::default()
        .depart(FakeVehicle::new("a", "cav"))
        .depart(FakeVehicle::new("b", "car"))];
    let mut run = paper_run(&c, "idm-mobil");
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, 1);
    let result = finish(run, "");
    assert_eq!(record(&result, "a").kind, Kind::Cav);
    assert_eq!(record(&result, "b").kind, Kind::Hdv);
}

/// Three vehicles departing together and driving along `acc`'s main lanes (frame lanes 1
/// and 2), inside the part the planner drives, for four steps.
fn three_through_the_region() -> Vec<Step> {
    (0..4)
        .map(|k| {
            let mut step = Step::default();
            for (j, id) in ["a", "b", "c"].into_iter().enumerate() {
                if k == 0 {
                    step = step.depart(FakeVehicle::new(id, "car"));
                }
                let pos = 20.0 + 40.0 * j as f64 + 6.0 * f64::from(k);
                step = step.read(Reading::on(id, "acc", 1 + (j % 2) as i32, pos, 30.0));
            }
            step
        })
        .collect()
}

#[test]
fn with_alpha_zero_no_vehicle_is_a_cav_and_sumo_is_sent_nothing() {
    let c = config(0.0, 5);
    let mut run = paper_run(&c, "idm-mobil");
    let mut sim = sumo_for(&run, three_through_the_region());
    play(&mut run, &mut sim, 4);
    assert!(sim.sent.is_empty(), "{:?}", sim.sent);
    let result = finish(run, "");
    assert!(result.vehicles.iter().all(|v| v.kind == Kind::Hdv));
    assert_eq!(result.summary.inserted, 3);
    // The same traffic all CAVs is planned: the silence above is α's.
    let c = config(1.0, 5);
    let mut run = paper_run(&c, "idm-mobil");
    let mut sim = sumo_for(&run, three_through_the_region());
    play(&mut run, &mut sim, 4);
    assert!(sim.sent.contains(&Sent::SpeedMode("a".into(), 0)));
}

/// CAV `c` driving into HDV `h` and `h` into `h2` in the second of four steps, `o` beside them.
fn chain_collision() -> Vec<Step> {
    let read = |pos: f64| {
        Step::default()
            .read(Reading::on("c", "acc", 1, pos, 30.0))
            .read(Reading::on("h", "acc", 1, pos + 6.0, 20.0))
            .read(Reading::on("h2", "acc", 1, pos + 12.0, 10.0))
            .read(Reading::on("o", "acc", 2, pos, 30.0))
    };
    vec![
        read(20.0)
            .depart(FakeVehicle::new("c", "cav"))
            .depart(FakeVehicle::new("h", "car"))
            .depart(FakeVehicle::new("h2", "car"))
            .depart(FakeVehicle::new("o", "car")),
        read(26.0).collide("c", "h").collide("h", "h2"),
        read(32.0).arrive("c").arrive("h").arrive("h2"),
        read(38.0),
    ]
}

/// Vehicle `v` crashed at `crash` with `with` (ids), a CAV involved when `controllable`.
fn assert_crashed(v: &super::ScenarioVehicle, crash: f64, with: &str, controllable: bool) {
    let id = &v.id;
    assert_eq!(v.outcome, Outcome::Crashed, "{id}");
    assert_eq!(v.crash_time_s, Some(crash), "{id}");
    assert_eq!(v.arrival_s, None, "{id}");
    assert_eq!(v.crashed_with, with, "{id}");
    assert_eq!(v.controllable_crash, controllable, "{id}");
    assert_eq!(v.region_delay_s, None, "{id}: no delay for a crash");
}

#[test]
fn a_collision_removes_both_vehicles_once_and_books_it() {
    // `c` is a CAV (by its type), `h`, `h2` HDVs; `c` drives into `h`, and `h` into `h2`, in the
    // second step. SUMO reports the vehicles removed as arrived in the step after.
    let mut c = config(0.0, 1);
    c.scenario.cav_types = vec!["cav".into()];
    let mut run = paper_run(&c, "idm-mobil");
    let mut sim = sumo_for(&run, chain_collision());
    play(&mut run, &mut sim, 4);
    let removed: Vec<&str> = sim
        .sent
        .iter()
        .filter(|s| matches!(s, Sent::Remove(_)))
        .map(Sent::vehicle)
        .collect();
    assert_eq!(removed, ["c", "h", "h2"], "each removed once");
    // The CAV was taken over in the first step; removed, it is handed back to nobody.
    assert_eq!(
        hand_overs(&sim.sent_to("c")),
        [
            Sent::SpeedMode("c".into(), 0),
            Sent::LaneChangeMode("c".into(), 0),
            Sent::Remove("c".into()),
        ]
    );
    let result = finish(run, "");
    let crash = began(2);
    let expect = [("c", "h", true), ("h", "c h2", true), ("h2", "h", false)];
    for (id, with, controllable) in expect {
        assert_crashed(record(&result, id), crash, with, controllable);
    }
    let o = record(&result, "o");
    assert_eq!((o.outcome, o.crash_time_s), (Outcome::Present, None));
    let events: Vec<(&str, &str, f64, bool)> = (result.collisions.iter())
        .map(|e| (&*e.collider, &*e.victim, e.time, e.controllable()))
        .collect();
    assert_eq!(events, [("c", "h", crash, true), ("h", "h2", crash, false)]);
    assert_eq!(result.collisions[0].collider_kind, Some(Kind::Cav));
    assert_eq!(result.collisions[0].victim_kind, Some(Kind::Hdv));
    let s = &result.summary;
    assert_eq!(
        (s.crashed, s.controllable_crashed, s.hdv_collisions),
        (3, 2, 1)
    );
}

#[test]
fn an_arrival_is_booked_and_joined_to_sumos_trip_figures() {
    let c = config(0.0, 2);
    let script = vec![
        Step::default()
            .depart(FakeVehicle::new("a", "car"))
            .depart(FakeVehicle::new("b", "car"))
            .read(Reading::on("a", "main_out", 0, 100.0, 30.0))
            .read(Reading::on("b", "acc", 1, 40.0, 30.0)),
        Step::default()
            .read(Reading::on("a", "main_out", 0, 106.0, 30.0))
            .read(Reading::on("b", "acc", 1, 46.0, 30.0)),
        Step::default()
            .arrive("a")
            .read(Reading::on("b", "acc", 1, 52.0, 30.0)),
        Step::default().read(Reading::on("b", "acc", 1, 58.0, 30.0)),
    ];
    let mut run = paper_run(&c, "idm-mobil");
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, 4);
    let trips = r#"<tripinfo id="a" depart="0.00" arrival="0.40" timeLoss="1.25" routeLength="480.50" departDelay="2.50"/>
<tripinfo id="b" depart="0.00" arrival="-1" timeLoss="0.75" routeLength="212.00"/>
<tripinfo id="never" depart="0.00" timeLoss="9.00" routeLength="1.00"/>"#;
    let result = finish(run, trips);
    let a = record(&result, "a");
    assert_eq!((a.outcome, a.arrival_s), (Outcome::Arrived, Some(began(3))));
    assert_eq!((a.time_loss_s, a.route_length_m), (Some(1.25), Some(480.5)));
    assert_eq!(a.crash_time_s, None);
    let b = record(&result, "b");
    assert_eq!((b.outcome, b.arrival_s), (Outcome::Present, None));
    assert_eq!((b.time_loss_s, b.route_length_m), (Some(0.75), Some(212.0)));
    assert_eq!(
        result.vehicles.len(),
        2,
        "a trip of no departure is no record"
    );
    let s = &result.summary;
    assert_eq!((s.arrived, s.present, s.crashed), (1, 1, 0));
    assert_eq!(s.time_loss().mean_time_loss_s, Some(1.0));
    // a waited 2.5 s to enter; b's trip names no wait.
    assert_eq!((a.depart_delay_s, b.depart_delay_s), (Some(2.5), Some(0.0)));
    assert_eq!(s.time_loss().mean_time_loss_with_wait_s, Some(2.25));
}

/// The vehicles never inserted are those SUMO still holds back after the last step, not
/// those it held back earlier and then inserted: each a row with SUMO's wait to the end (its
/// undeparted trip), and in the mean with the wait, which charges that whole wait.
#[test]
fn vehicles_still_waiting_after_the_last_step_are_never_inserted() {
    let c = config(0.0, 2);
    let script = vec![
        Step::default()
            .depart(FakeVehicle::new("a", "car"))
            .read(Reading::on("a", "main_in", 0, 10.0, 30.0))
            .wait("b")
            .wait_on("c", &["ramp", "acc", "main_out"]),
        Step::default()
            .depart(FakeVehicle::new("b", "car"))
            .read(Reading::on("a", "main_in", 0, 16.0, 30.0))
            .read(Reading::on("b", "main_in", 0, 1.0, 30.0))
            .wait_on("c", &["ramp", "acc", "main_out"])
            .wait_on("d", &["main_in", "acc", "main_out"])
            .wait("e"),
    ];
    let mut run = paper_run(&c, "sumo");
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, 2);
    let trips = r#"<tripinfo id="a" depart="0.00" arrival="-1" timeLoss="1.00" routeLength="9.00" departDelay="0.00"/>
<tripinfo id="b" depart="0.20" arrival="-1" timeLoss="0.00" routeLength="1.00" departDelay="0.20"/>
<tripinfo id="c" depart="-1" arrival="-1.00" timeLoss="0.00" routeLength="5.10" departDelay="0.30" vType="truck"/>
<tripinfo id="d" depart="-1" arrival="-1.00" timeLoss="0.00" routeLength="5.10" departDelay="0.10" vType="car"/>"#;
    let result = finish(run, trips);
    let s = &result.summary;
    assert_eq!((s.inserted, s.never_inserted), (2, 3));
    let ids: Vec<&str> = result.vehicles.iter().map(|v| v.id.as_str()).collect();
    assert_eq!(ids, ["a", "b", "c", "d", "e"]);
    let c = record(&result, "c");
    assert_eq!(
        (c.outcome, c.sumo_type.as_str()),
        (Outcome::NeverInserted, "truck")
    );
    // Two steps end at 0.4 s: c wanted to depart at 0.1 s and waited 0.3 s.
    assert_eq!(
        (c.scheduled_depart_s, c.depart_delay_s),
        (Some(0.1), Some(0.3))
    );
    assert_eq!((c.depart_s, c.time_loss_s), (None, None));
    assert_eq!(record(&result, "b").scheduled_depart_s, Some(0.0));
    // e has no trip: a row, without figures. The mean with the wait: a 1.0, b 0.2, c 0.3, d 0.1.
    assert_eq!(record(&result, "e").depart_delay_s, None);
    let with_wait = s.time_loss().mean_time_loss_with_wait_s.unwrap();
    assert!((with_wait - 0.4).abs() < 1e-12, "{with_wait}");
    assert_eq!(s.time_loss().mean_time_loss_s, Some(0.5));
    // Each by where its route enters the region; `e`'s route passes none.
    let r = &result.regions[0];
    assert_eq!((r.never_inserted_main, r.never_inserted_ramp), (1, 1));
}

/// A CAV `c` from `main_in` through the planned part (`acc`, frame 150–330) onto `main_out`:
/// before it, in it for three steps, then past it.
fn cav_through_the_planned_part() -> Vec<Step> {
    let on = |edge: &str, pos: f64| Step::default().read(Reading::on("c", edge, 0, pos, 30.0));
    vec![
        on("main_in", 140.0).depart(FakeVehicle::new("c", "car")),
        Step::default().read(Reading::on("c", "acc", 1, 10.0, 30.0)),
        Step::default().read(Reading::on("c", "acc", 1, 16.0, 30.0)),
        Step::default().read(Reading::on("c", "acc", 1, 22.0, 30.0)),
        on("main_out", 5.0),
        on("main_out", 11.0),
    ]
}

#[test]
fn a_cav_is_taken_over_in_the_planned_part_and_handed_back_after_it_once_each() {
    let c = config(1.0, 4);
    let mut run = paper_run(&c, "idm-mobil");
    let mut sim = sumo_for(&run, cav_through_the_planned_part());
    // Before the planned part: SUMO drives it.
    play(&mut run, &mut sim, 1);
    assert!(sim.sent.is_empty(), "{:?}", sim.sent);
    // In it: SUMO's checks off first, then the planner's speed.
    play(&mut run, &mut sim, 1);
    let off = [
        Sent::SpeedMode("c".into(), 0),
        Sent::LaneChangeMode("c".into(), 0),
    ];
    assert_eq!(sim.sent[..2], off);
    assert!(
        matches!(&sim.sent[2], Sent::Speed(id, v) if id == "c" && *v >= 0.0),
        "{:?}",
        sim.sent
    );
    // Still in it: only the planner's commands, every step.
    play(&mut run, &mut sim, 2);
    assert_eq!(hand_overs(&sim.sent).len(), 2, "{:?}", sim.sent);
    let speeds = |sent: &[Sent]| {
        sent.iter()
            .filter(|s| matches!(s, Sent::Speed(_, v) if *v >= 0.0))
            .count()
    };
    assert_eq!(speeds(&sim.sent), 3);
    // Past it: back to SUMO, once.
    play(&mut run, &mut sim, 2);
    assert_eq!(
        hand_overs(&sim.sent),
        [
            Sent::SpeedMode("c".into(), 0),
            Sent::LaneChangeMode("c".into(), 0),
            Sent::Speed("c".into(), -1.0),
            Sent::SpeedMode("c".into(), 31),
            Sent::LaneChangeMode("c".into(), 1621),
        ]
    );
    assert_eq!(speeds(&sim.sent), 3, "no planned speed after the hand-back");
}

#[test]
fn sumos_own_planner_takes_no_cav_over() {
    let c = config(1.0, 4);
    let mut run = paper_run(&c, "sumo");
    let mut sim = sumo_for(&run, cav_through_the_planned_part());
    play(&mut run, &mut sim, 6);
    assert!(sim.sent.is_empty(), "{:?}", sim.sent);
    assert_eq!(finish(run, "").vehicles[0].kind, Kind::Cav);
}

#[test]
fn a_cav_whose_route_leaves_the_region_early_stays_sumos() {
    let c = config(1.0, 4);
    let mut script = cav_through_the_planned_part();
    script[0].departed[0] = FakeVehicle::new("c", "car").distance(-1.0);
    let mut run = paper_run(&c, "idm-mobil");
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, 6);
    assert!(sim.sent.is_empty(), "{:?}", sim.sent);
}

#[test]
fn a_cav_on_a_lane_the_planner_has_none_of_stays_sumos() {
    // The merge zone ends at 250 here, so `acc`'s lane 0 past it is a deceleration lane: no
    // lane of the planners'. The CAV drives on it at s = 260 and on lane 1 beside it.
    let mut road = Road::paper_default();
    road.zones[0].end = 250.0;
    let c = config(1.0, 9);
    let mut run = ScenarioRun::of_regions(&c, regions(&c, vec![road], "idm-mobil").unwrap());
    let script = vec![
        Step::default()
            .depart(FakeVehicle::new("d", "car"))
            .read(Reading::on("d", "acc", 0, 110.0, 20.0)),
        Step::default().read(Reading::on("d", "acc", 0, 114.0, 20.0)),
        Step::default().read(Reading::on("d", "acc", 1, 118.0, 20.0)),
    ];
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, 2);
    assert!(sim.sent.is_empty(), "{:?}", sim.sent);
    play(&mut run, &mut sim, 1);
    assert_eq!(sim.sent[0], Sent::SpeedMode("d".into(), 0));
}

#[test]
fn a_region_passage_runs_from_the_first_reading_there_to_the_last() {
    let c = config(0.0, 6);
    // `r` comes up the ramp (frame s = 150 − 166.79 + position) onto the acceleration lane,
    // then leaves the frame (SUMO's internal edge past it); `m` drives the main road; `x`
    // never comes near.
    let script = vec![
        Step::default()
            .depart(FakeVehicle::new("r", "car"))
            .depart(FakeVehicle::new("m", "car"))
            .depart(FakeVehicle::new("x", "car"))
            .read(Reading::on("r", "ramp", 0, 100.0, 20.0))
            .read(Reading::on("m", "main_in", 1, 50.0, 30.0))
            .read(Reading::on("x", "elsewhere", 0, 50.0, 30.0)),
        Step::default()
            .read(Reading::on("r", "ramp", 0, 104.0, 20.0))
            .read(Reading::on("m", "main_in", 1, 56.0, 30.0)),
        Step::default()
            .read(Reading::on("r", "acc", 0, 10.0, 20.0))
            .read(Reading::on("m", "main_in", 1, 62.0, 30.0)),
        Step::default()
            .read(Reading::on("r", ":junction_0", 0, 1.0, 20.0))
            .read(Reading::on("m", ":junction_1", 0, 1.0, 30.0))
            .read(Reading::on("x", "elsewhere", 0, 62.0, 30.0)),
    ];
    let mut run = paper_run(&c, "idm-mobil");
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, 4);
    let result = finish(run, "");
    let r = record(&result, "r");
    assert_eq!(
        (r.region.as_str(), r.region_origin.as_str()),
        ("acc", "ramp")
    );
    assert_eq!(
        (r.region_enter_s, r.region_leave_s),
        (Some(began(1)), Some(began(3)))
    );
    let ramp_start = 150.0 - 166.79;
    let distance = 160.0 - (ramp_start + 100.0);
    assert!((r.region_distance_m.unwrap() - distance).abs() < 1e-9);
    assert!(r.region_delay_s.is_some());
    let m = record(&result, "m");
    assert_eq!(
        (m.region.as_str(), m.region_origin.as_str()),
        ("acc", "main")
    );
    assert_eq!(
        (m.region_enter_s, m.region_leave_s),
        (Some(began(1)), Some(began(3)))
    );
    assert_eq!(m.region_distance_m, Some(12.0));
    let x = record(&result, "x");
    assert_eq!((x.region.as_str(), x.region_origin.as_str()), ("", ""));
    assert_eq!((x.region_enter_s, x.region_distance_m), (None, None));
    assert_eq!(result.summary.share.clone().unwrap().in_region, 2);
}

/// The paper road with every edge's name prefixed by `prefix`: a second region of a network.
fn renamed(mut road: Road, prefix: &str) -> Road {
    let name = |n: &str| -> Arc<str> { format!("{prefix}{n}").into() };
    for e in &mut road.edges {
        e.name = name(&e.name);
    }
    road.end_edge.0 = name(&road.end_edge.0);
    for entry in &mut road.entries {
        entry.route = entry.route.iter().map(|e| name(e)).collect();
    }
    road
}

#[test]
fn each_region_reads_its_own_edges_after_the_codes_of_those_before() {
    let c = config(0.0, 8);
    let roads = vec![Road::paper_default(), renamed(Road::paper_default(), "b_")];
    let mut run = ScenarioRun::of_regions(&c, regions(&c, roads, "idm-mobil").unwrap());
    let script = vec![Step::default()
        .depart(FakeVehicle::new("one", "car"))
        .depart(FakeVehicle::new("two", "car"))
        .read(Reading::on("one", "ramp", 0, 100.0, 20.0))
        .read(Reading::on("two", "b_ramp", 0, 100.0, 20.0))];
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, 1);
    let result = finish(run, "");
    let one = record(&result, "one");
    assert_eq!(
        (one.region.as_str(), one.region_origin.as_str()),
        ("acc", "ramp")
    );
    let two = record(&result, "two");
    assert_eq!(
        (two.region.as_str(), two.region_origin.as_str()),
        ("b_acc", "ramp")
    );
    assert_eq!(result.summary.regions.as_deref(), Some("acc; b_acc"));
}
