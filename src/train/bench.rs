//! `bkpbs bench-predictor`: what b_θ costs, measured side by side in one SUMO episode.
//!
//! At every step of a dense episode (the configured λ and α; CAVs driven by idm-mobil) the
//! observer times, on the same scene: one model evaluation (P(lane change) of one HDV, features
//! encoded; conditioned and unconditioned), and the prediction of every HDV's trajectory over the
//! planning horizon by the constant-speed predictor, by b_θ unconditioned and by b_θ conditioned
//! on the constant-speed trajectories of all CAVs (the most any HDV is conditioned on in
//! BK-PBS). Figures are medians (and 99th percentiles) over the steps after the warm-up.

use std::time::Instant;

use crate::config::Config;
use crate::episode::metrics::percentile;
use crate::episode::{self, Driver, EpisodeError, Observer};
use crate::model::road::Road;
use crate::model::scene::{Kind, Scene};
use crate::model::trajectory::Trajectory;
use crate::planner::mastar::Mastar;
use crate::predict::features::{
    cav_node, ego_of, is_decision_point, neighbours, select_cavs, Agent, Observation, PREVIEW,
};
use crate::predict::infer::Workspace;
use crate::predict::learned::Learned;
use crate::predict::{ConstantSpeed, Predictor};

/// Steps skipped at the start while the road fills.
const WARM_UP: usize = 50;
/// Model evaluations per timed batch (one clock read per batch).
const REPEATS: usize = 200;

/// Medians (and p99) of the timings.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PredictorBench {
    /// Steps timed (those after the warm-up with at least one HDV on the road).
    pub steps: usize,
    /// Median number of HDVs on the road per timed step.
    pub hdvs_per_step_median: f64,
    /// Median number of CAVs on the road per timed step.
    pub cavs_per_step_median: f64,
    /// One unconditioned model evaluation, median (µs).
    pub single_unconditioned_us: f64,
    /// One model evaluation conditioned on the nearest CAVs' plans, median (µs).
    pub single_conditioned_us: f64,
    /// Constant-speed trajectories of all HDVs of a step (ms): median and 99th percentile.
    pub constant_ms: (f64, f64),
    /// b_θ unconditioned, trajectories of all HDVs of a step (ms): median and 99th percentile.
    pub unconditioned_ms: (f64, f64),
    /// b_θ conditioned on every CAV's constant-speed trajectory, all HDVs of a step (ms): median
    /// and 99th percentile.
    pub conditioned_ms: (f64, f64),
}

struct Timer<'a> {
    learned: &'a Learned,
    constant: ConstantSpeed,
    horizon: usize,
    dt: f64,
    step: usize,
    ws: Workspace,
    hdvs: Vec<f64>,
    cavs: Vec<f64>,
    single: [Vec<f64>; 2],
    per_step: [Vec<f64>; 3],
}

impl Observer for Timer<'_> {
    fn observe(&mut self, scene: &Scene) {
        self.step += 1;
        if self.step <= WARM_UP {
            return;
        }
        let hdvs: Vec<usize> = (0..scene.vehicles.len())
            .filter(|&i| scene.vehicles[i].kind == Kind::Hdv)
            .collect();
        if hdvs.is_empty() {
            return;
        }
        let plans: Vec<Trajectory> = scene
            .vehicles
            .iter()
            .enumerate()
            .filter(|(_, v)| v.kind == Kind::Cav)
            .map(|(j, _)| self.constant.predict(scene, j, &[], self.horizon))
            .collect();
        let refs: Vec<&Trajectory> = plans.iter().collect();
        self.hdvs.push(hdvs.len() as f64);
        self.cavs.push(refs.len() as f64);
        // One model evaluation, on the first HDV at a decision point.
        if let Some(&i) = hdvs
            .iter()
            .find(|&&i| is_decision_point(&scene.vehicles[i]))
        {
            self.time_single(scene, i, &refs);
        }
        self.time_all(scene, &hdvs, &refs);
    }
}

impl Timer<'_> {
    /// Times one model evaluation for HDV `i`, unconditioned and conditioned on `plans`,
    /// repeated [`REPEATS`] times so the clock's resolution does not matter.
    fn time_single(&mut self, scene: &Scene, i: usize, plans: &[&Trajectory]) {
        let (plain, with_cavs) = observations(scene, i, plans, self.dt);
        for (k, conditioned) in [false, true].into_iter().enumerate() {
            let model = self.learned.model(conditioned);
            let obs = if conditioned { with_cavs } else { plain };
            let t = Instant::now();
            let mut acc = 0.0;
            for _ in 0..REPEATS {
                acc += model.probability(std::hint::black_box(&obs), &mut self.ws);
            }
            std::hint::black_box(acc);
            self.single[k].push(t.elapsed().as_secs_f64() * 1e6 / REPEATS as f64);
        }
    }

    /// Times the trajectories of all `hdvs` over the horizon by each predictor: constant speed,
    /// b_θ unconditioned, b_θ conditioned on `plans`.
    fn time_all(&mut self, scene: &Scene, hdvs: &[usize], plans: &[&Trajectory]) {
        let time = |f: &dyn Fn(usize) -> Trajectory| {
            let t = Instant::now();
            for &i in hdvs {
                std::hint::black_box(f(i));
            }
            t.elapsed().as_secs_f64() * 1e3
        };
        let c = time(&|i| self.constant.predict(scene, i, &[], self.horizon));
        let u = time(&|i| self.learned.predict(scene, i, &[], self.horizon));
        let k = time(&|i| self.learned.predict(scene, i, plans, self.horizon));
        self.per_step[0].push(c);
        self.per_step[1].push(u);
        self.per_step[2].push(k);
    }
}

/// The model inputs of HDV `i` as it stands: unconditioned, and conditioned on the nearest
/// CAVs' `plans` over the preview.
fn observations(
    scene: &Scene,
    i: usize,
    plans: &[&Trajectory],
    dt: f64,
) -> (Observation, Observation) {
    let w = scene.road.lane_width;
    let ego = Agent::of(&scene.vehicles[i], w);
    let others: Vec<Agent> = scene
        .vehicles
        .iter()
        .enumerate()
        .filter(|&(j, _)| j != i)
        .map(|(_, v)| Agent::of(v, w))
        .collect();
    let plain = Observation {
        ego: ego_of(&scene.vehicles[i], &scene.road),
        neighbours: neighbours(&ego, others.iter()),
        ..Observation::default()
    };
    let mut with_cavs = plain;
    let cands = plans.iter().enumerate().map(|(n, t)| {
        let p = t.at(0, dt);
        let lane = scene.road.lane_at(p.y);
        (
            n,
            Agent {
                s: p.s,
                y: p.y,
                lane,
                speed: p.speed,
                is_cav: true,
            },
        )
    });
    let mut chosen = Vec::new();
    select_cavs(&ego, cands, &mut chosen);
    for (slot, &n) in chosen.iter().enumerate() {
        for k in 1..=PREVIEW {
            let p = plans[n].at(k, dt);
            with_cavs.cavs[k - 1][slot] = cav_node(&ego, k, dt, p.s, p.y, p.speed);
        }
    }
    (plain, with_cavs)
}

/// Runs the benchmark episode of `config` with `learned`.
pub fn run(config: &Config, learned: &Learned) -> Result<PredictorBench, EpisodeError> {
    let mut c = config.clone();
    c.predictor.kind = crate::config::PredictorKind::Constant;
    c.validate()?;
    // The horizon the planners predict over (the road does not enter it).
    let horizon = Mastar::from_config(&c, Road::paper_default()).check_horizon();
    let mut timer = Timer {
        learned,
        constant: ConstantSpeed::new(&c),
        horizon,
        dt: c.scenario.dt,
        step: 0,
        ws: Workspace::default(),
        hdvs: Vec::new(),
        cavs: Vec::new(),
        single: [Vec::new(), Vec::new()],
        per_step: [Vec::new(), Vec::new(), Vec::new()],
    };
    let demand = crate::episode::demand::generate_for(&c)?;
    episode::run_observed(&c, Driver::Named("idm-mobil"), &demand, &mut timer)?;
    let med = |v: &mut Vec<f64>| percentile(v, 50.0);
    let pair = |v: &mut Vec<f64>| (percentile(v, 50.0), percentile(v, 99.0));
    let [s0, s1] = &mut timer.single;
    let [p0, p1, p2] = &mut timer.per_step;
    Ok(PredictorBench {
        steps: p0.len(),
        hdvs_per_step_median: med(&mut timer.hdvs),
        cavs_per_step_median: med(&mut timer.cavs),
        single_unconditioned_us: med(s0),
        single_conditioned_us: med(s1),
        constant_ms: pair(p0),
        unconditioned_ms: pair(p1),
        conditioned_ms: pair(p2),
    })
}

impl PredictorBench {
    /// The figures as a small table.
    pub fn to_text(&self) -> String {
        format!(
            "{} steps timed, median {} HDVs and {} CAVs per step\n\
             one prediction (P(lane change) of one HDV, features encoded): unconditioned {:.2} µs, conditioned {:.2} µs (median)\n\
             {:<44} {:>12} {:>10}\n\
             {:<44} {:>12.3} {:>10.3}\n\
             {:<44} {:>12.3} {:>10.3}\n\
             {:<44} {:>12.3} {:>10.3}\n",
            self.steps,
            self.hdvs_per_step_median,
            self.cavs_per_step_median,
            self.single_unconditioned_us,
            self.single_conditioned_us,
            "all HDVs' trajectories per step (ms)",
            "median",
            "p99",
            "constant speed",
            self.constant_ms.0,
            self.constant_ms.1,
            "b_θ unconditioned",
            self.unconditioned_ms.0,
            self.unconditioned_ms.1,
            "b_θ conditioned on all CAVs' trajectories",
            self.conditioned_ms.0,
            self.conditioned_ms.1,
        )
    }
}
