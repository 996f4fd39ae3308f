//! The planner's motion primitives against what SUMO executes for the same commands.
//!
//! One CAV drives a script of primitives on an empty road; each step the probe compares the
//! state SUMO reports with the planner's rollout of the primitive it commanded. Tolerances: 0.3 m
//! in position after every single step, 1 m at the end of a lane change, 0.05 m/s in speed.

mod common;

use std::sync::{Arc, Mutex};

use bkpbs::config::Config;
use bkpbs::controller::{CavHandling, Command, Controller, LaneChange, Maneuver, Source};
use bkpbs::episode;
use bkpbs::episode::demand::PlannedVehicle;
use bkpbs::model::kinematics::BicycleState;
use bkpbs::model::math::Point;
use bkpbs::model::scene::{Kind, Origin, Scene};
use bkpbs::planner::primitives::{Library, Primitive};

#[derive(Debug, Default, Clone)]
struct Errors {
    /// (primitive, step within it, position error m, speed error m/s)
    samples: Vec<(Primitive, usize, f64, f64)>,
}

struct Probe {
    lib: Library,
    script: Vec<Primitive>,
    next: usize,
    /// Rollout of the primitive under way and how far into it we are.
    running: Option<(Primitive, Vec<BicycleState>, usize)>,
    errors: Arc<Mutex<Errors>>,
}

impl Controller for Probe {
    fn name(&self) -> &'static str {
        "probe"
    }
    fn handling(&self) -> CavHandling {
        CavHandling::Commanded
    }
    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>) {
        let Some(i) = scene.vehicles.iter().position(|v| v.kind == Kind::Cav) else {
            return;
        };
        let v = &scene.vehicles[i];
        let w = scene.road.lane_width;
        let observed = BicycleState {
            pos: Point::new(v.s, v.lane as f64 * w + v.lateral),
            heading: v.heading,
            speed: v.speed,
        };
        // Compare with what the rollout predicted for this step.
        if let Some((p, rollout, k)) = &mut self.running {
            let want = rollout[*k];
            let pos_err = (want.pos - observed.pos).norm();
            let speed_err = (want.speed * want.heading.cos() - observed.speed).abs();
            self.errors
                .lock()
                .unwrap()
                .samples
                .push((*p, *k, pos_err, speed_err));
            *k += 1;
            if *k == rollout.len() {
                self.running = None;
            }
        }
        // Start the next primitive when the previous one is done.
        let mut lane_change = None;
        if self.running.is_none() && self.next < self.script.len() {
            let p = self.script[self.next];
            self.next += 1;
            let lane_y = v.lane as f64 * w;
            self.running = Some((p, self.lib.rollout(p, &observed, lane_y), 0));
            lane_change = match p.lane_offset() {
                1 => Some(LaneChange::Left),
                -1 => Some(LaneChange::Right),
                _ => None,
            };
        }
        let speed = match &self.running {
            Some((_, rollout, k)) => {
                let s = rollout[*k];
                s.speed * s.heading.cos()
            }
            None => v.speed,
        };
        out.push(Command {
            vehicle: i,
            maneuver: Maneuver { speed, lane_change },
            source: Source::Rule,
        });
    }
}

#[test]
fn sumo_executes_every_primitive_as_the_planner_rolls_it_out() {
    agreement_on(Config::default(), 4.5);
}

/// The same script on a curved three-lane net (3.6 m lanes, netconvert's defaults): the frame
/// straightens the road, so the primitives hold there with the same tolerances.
#[test]
fn primitives_hold_on_a_curved_net() {
    let dir = tempfile::tempdir().unwrap();
    let net = common::netconvert_net(dir.path(), 3, &[700.0], true);
    let mut config = Config::default();
    config.scenario.net_file = Some(net);
    agreement_on(config, 3.6);
}

/// Runs the script of primitives with one CAV on `config`'s network of `lane_width` m lanes and
/// checks every step against the rollout.
fn agreement_on(mut config: Config, lane_width: f64) {
    use Primitive::*;
    config.scenario.steps = 60;
    let s = &config.scenario;
    let lib = Library::new(s.dt, lane_width, s.lane_change_duration, s.v_max);
    let script = vec![
        Accelerate,
        Accelerate,
        Accelerate,
        Idle,
        Idle,
        Decelerate,
        Decelerate,
        Decelerate,
        EmergencyBrake,
        EmergencyBrake,
        Idle,
        LaneChangeLeft,
        Idle,
        Idle,
        Accelerate,
        LaneChangeRight,
        Idle,
        Idle,
        Decelerate,
    ];
    let errors = Arc::new(Mutex::new(Errors::default()));
    let mut probe = Probe {
        lib,
        script: script.clone(),
        next: 0,
        running: None,
        errors: errors.clone(),
    };
    let demand = vec![PlannedVehicle {
        id: "main.0".into(),
        kind: Kind::Cav,
        origin: Origin::Main,
        entry: 0,
        exit: None,
        depart: 0.0,
        depart_lane: 0,
        depart_speed: 25.0,
        desired_speed: 35.0,
    }];
    let r = episode::run_with_demand(&config, &mut probe, &demand).unwrap();
    assert_eq!(r.summary.crashed, 0);
    let e = errors.lock().unwrap();
    // Every primitive of the script was executed and compared.
    for p in Primitive::ALL {
        assert!(e.samples.iter().any(|s| s.0 == p), "{p:?} never compared");
    }
    let mut worst_step: f64 = 0.0;
    let mut worst_lc_end: f64 = 0.0;
    let mut worst_speed: f64 = 0.0;
    for &(p, k, pos, speed) in &e.samples {
        assert!(
            pos <= if p.is_lane_change() { 1.0 } else { 0.3 },
            "{p:?} step {k}: {pos} m"
        );
        assert!(speed <= 0.05, "{p:?} step {k}: speed off by {speed}");
        if p.is_lane_change() && k == 4 {
            worst_lc_end = worst_lc_end.max(pos);
        } else if !p.is_lane_change() {
            worst_step = worst_step.max(pos);
        }
        worst_speed = worst_speed.max(speed);
    }
    let lc_max = e
        .samples
        .iter()
        .filter(|s| s.0.is_lane_change())
        .map(|s| s.2)
        .fold(0.0, f64::max);
    eprintln!(
        "primitive agreement with SUMO: single steps ≤ {worst_step:.3} m, lane change ≤ {lc_max:.3} m \
         during and ≤ {worst_lc_end:.3} m at its end, speed ≤ {worst_speed:.4} m/s ({} samples)",
        e.samples.len()
    );
    assert!(worst_lc_end <= 1.0);
}
