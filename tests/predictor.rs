//! The learned lane-change predictor b_θ: gradients, model and data files, training, the
//! predictor on hand-built scenes and on real SUMO episodes.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod common;

use bkpbs::predict::features::Observation;
use bkpbs::predict::gcn::{sigmoid, Architecture};
use bkpbs::predict::infer::{Network, Workspace};
use bkpbs::train::gcn::{backward, forward, Cache, Inputs};
use bkpbs::train::training_loop::bce_with_logit;
use common::random_obs;

/// Σ BCE over the batch, in f64.
fn loss(arch: &Architecture, p: &[f64], x: &Inputs<f64>, labels: &[bool]) -> f64 {
    let mut c = Cache::default();
    forward(arch, p, x, &mut c);
    c.logits
        .iter()
        .zip(labels)
        .map(|(&z, &y)| bce_with_logit(z, y))
        .sum()
}

/// Central finite differences against the backward pass, for parameters sampled from every
/// layer (weights and biases).
fn gradient_check(conditioned: bool) {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let arch = Architecture::new(conditioned);
    let mut p: Vec<f64> = arch.init(&mut rng);
    // Non-zero biases: with zero biases an absent node (all-zero input) sits exactly on the
    // ReLU's kink, where finite differences see half a slope.
    for layer in arch.layers() {
        for i in layer.biases() {
            p[i] = rng.gen_range(-0.1..0.1);
        }
    }
    let obs: Vec<Observation> = (0..4).map(|_| random_obs(&mut rng)).collect();
    let labels = [true, false, false, true];
    let mut x = Inputs::<f64>::default();
    x.encode(obs.iter(), conditioned);
    let mut c = Cache::default();
    forward(&arch, &p, &x, &mut c);
    let dlogits: Vec<f64> = c
        .logits
        .iter()
        .zip(&labels)
        .map(|(&z, &y)| sigmoid(z) - y as u8 as f64)
        .collect();
    let mut grad = vec![0.0; arch.n_params];
    backward(&arch, &p, &x, &mut c, &dlogits, &mut grad);
    let h = 1e-5;
    let mut checked = 0;
    let mut worst: f64 = 0.0;
    for layer in arch.layers() {
        let w = layer.weights();
        let b = layer.biases();
        let mut picks: Vec<usize> = (0..40).map(|_| rng.gen_range(w.clone())).collect();
        picks.extend((0..12).map(|_| rng.gen_range(b.clone())));
        for i in picks {
            let mut q = p.clone();
            q[i] = p[i] + h;
            let up = loss(&arch, &q, &x, &labels);
            q[i] = p[i] - h;
            let down = loss(&arch, &q, &x, &labels);
            let numeric = (up - down) / (2.0 * h);
            let scale = numeric.abs().max(grad[i].abs());
            let err = (numeric - grad[i]).abs();
            // Relative error where the gradient is large enough for it to mean something
            // (the loss is O(1); f64 differences carry ~1e-11 of noise).
            if scale > 1e-5 {
                worst = worst.max(err / scale);
                assert!(
                    err <= 1e-4 * scale,
                    "param {i} of layer {layer:?}: numeric {numeric}, backward {}",
                    grad[i]
                );
                checked += 1;
            } else {
                assert!(err < 1e-9, "param {i}: {numeric} vs {}", grad[i]);
            }
        }
    }
    assert!(
        checked > 100,
        "only {checked} gradients were large enough to check"
    );
    eprintln!("gradient check (conditioned = {conditioned}): {checked} parameters, worst relative error {worst:.2e}");
}

#[test]
fn gradient_check_conditioned() {
    gradient_check(true);
}

#[test]
fn gradient_check_unconditioned() {
    gradient_check(false);
}

// ---------------------------------------------------------------------------------------------
// Model files.

use std::path::Path;

use bkpbs::config::{Config, PredictorKind};
use bkpbs::model::scene::{Kind, Origin, Scene, VehicleState};
use bkpbs::model::trajectory::{Pose, Trajectory};
use bkpbs::predict::features::Subset;
use bkpbs::predict::model_file::{LaneChangeModel, ModelError, ModelFile};
use bkpbs::predict::{Learned, Predictor};
use bkpbs::train::dataset::{DataError, Dataset, Sample};
use bkpbs::train::fit::fit;
use bkpbs::train::training_loop::{TrainOptions, Trained};

/// A synthetic data set with a learnable rule: ramp HDVs change lanes when little acceleration
/// lane is left and the right-of-way gap (left follower) is large; main-road HDVs when their
/// leader is close and the left lane is free.
fn synthetic(n: usize, seed: u64) -> Vec<Sample> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            let mut obs = random_obs(&mut rng);
            obs.ego.lateral = 0.0;
            let lane = obs.ego.lane as i32;
            let label = if lane == 0 {
                obs.ego.to_merge_end < 60.0 && obs.neighbours[3].ds < -20.0
            } else {
                obs.neighbours[0].present
                    && obs.neighbours[0].ds < 30.0
                    && !obs.neighbours[2].present
            };
            Sample {
                episode: (i / 50) as u32,
                step: (i % 50) as u32,
                subset: Subset::of_lane(lane),
                label,
                weight: 1.0,
                obs,
            }
        })
        .collect()
}

fn tiny_options(threads: usize) -> TrainOptions {
    TrainOptions {
        epochs: 6,
        threads,
        patience: 6,
        ..TrainOptions::default()
    }
}

fn tiny_model(conditioned: bool) -> ModelFile {
    let data = Dataset {
        meta: String::new(),
        samples: synthetic(1500, 5),
    };
    fit(
        &data,
        "synthetic.bin",
        conditioned,
        &tiny_options(2),
        |_, _| {},
    )
    .unwrap()
}

#[test]
fn training_loop_learns_and_is_deterministic_for_any_thread_count() {
    let samples = synthetic(3000, 9);
    let learner = bkpbs::train::gcn::GcnLearner {
        arch: Architecture::new(true),
    };
    let opts = |threads| TrainOptions {
        epochs: 3,
        threads,
        ..TrainOptions::default()
    };
    let run = |threads| -> Trained {
        bkpbs::train::training_loop::train(&learner, &samples, &opts(threads), |_| {}).unwrap()
    };
    let a = run(1);
    let b = run(2);
    assert_eq!(a.params, b.params, "1 and 2 threads give the same model");
    let losses = |t: &Trained| -> Vec<(f64, f64)> {
        t.log.iter().map(|e| (e.train_loss, e.val_loss)).collect()
    };
    assert_eq!(losses(&a), losses(&b));
    // The unconditioned network learns the rule.
    let learner = bkpbs::train::gcn::GcnLearner {
        arch: Architecture::new(false),
    };
    let opts = TrainOptions {
        epochs: 25,
        patience: 25,
        ..TrainOptions::default()
    };
    let t = bkpbs::train::training_loop::train(&learner, &samples, &opts, |_| {}).unwrap();
    let first = t.log.first().unwrap();
    let best = &t.log[t.best_epoch - 1];
    assert!(
        best.val_loss < 0.6 * first.val_loss,
        "validation loss {} → {}",
        first.val_loss,
        best.val_loss
    );
    assert!(
        best.val_main.recall() > 0.8 && best.val_ramp.f1() > 0.5,
        "{best}"
    );
}

#[test]
fn model_file_round_trips_and_bad_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let m = tiny_model(false);
    let path = dir.path().join("tiny.json");
    m.write(&path).unwrap();
    let back = ModelFile::read(&path).unwrap();
    assert_eq!(back, m);
    let text = std::fs::read_to_string(&path).unwrap();
    let named = |e: &ModelError, file: &str| {
        let s = e.to_string();
        assert!(s.contains(file), "{s}");
        assert!(!s.contains('\n'), "one line: {s}");
        s
    };
    // Truncated.
    let p = dir.path().join("truncated.json");
    std::fs::write(&p, &text[..text.len() / 2]).unwrap();
    let e = ModelFile::read(&p).unwrap_err();
    assert!(matches!(e, ModelError::Json { .. }), "{e}");
    assert!(named(&e, "truncated.json").contains("truncated or corrupt"));
    // Another version.
    let p = dir.path().join("v2.json");
    std::fs::write(&p, text.replacen("\"version\":1", "\"version\":2", 1)).unwrap();
    let e = ModelFile::read(&p).unwrap_err();
    assert!(matches!(e, ModelError::Version { found: 2, .. }), "{e}");
    named(&e, "v2.json");
    // Wrong shapes: one parameter missing, and a conditioned architecture claimed.
    let mut short = m.clone();
    short.params.pop();
    let p = dir.path().join("short.json");
    short.write(&p).unwrap_or_else(|_| unreachable!());
    let e = ModelFile::read(&p).unwrap_err();
    assert!(matches!(e, ModelError::Shape { .. }), "{e}");
    assert!(named(&e, "short.json").contains("parameters"));
    let mut claimed = m.clone();
    claimed.conditioned = true;
    let p = dir.path().join("claimed.json");
    claimed.write(&p).unwrap();
    let e = ModelFile::read(&p).unwrap_err();
    assert!(matches!(e, ModelError::Shape { .. }), "{e}");
    // Absurd weights (1e30 was once accepted, and saturated every probability).
    let mut huge = m.clone();
    huge.params[0] = 1e30;
    let p = dir.path().join("huge.json");
    huge.write(&p).unwrap();
    let e = ModelFile::read(&p).unwrap_err();
    assert!(matches!(e, ModelError::Shape { .. }), "{e}");
    assert!(named(&e, "huge.json").contains("magnitude"));
    // Another feature layout.
    let mut layout = m.clone();
    layout.layout.features_a += 1;
    let p = dir.path().join("layout.json");
    layout.write(&p).unwrap();
    let e = ModelFile::read(&p).unwrap_err();
    assert!(matches!(e, ModelError::Layout { .. }), "{e}");
    // Not a model at all, and missing.
    let p = dir.path().join("other.json");
    std::fs::write(&p, "{\"format\":\"something-else\",\"version\":1}").unwrap();
    assert!(matches!(
        ModelFile::read(&p).unwrap_err(),
        ModelError::Format { .. }
    ));
    let e = ModelFile::read(Path::new("no/such/model.json")).unwrap_err();
    named(&e, "no/such/model.json");
}

#[test]
fn data_file_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = Dataset {
        meta: "{}".into(),
        samples: synthetic(30, 1),
    };
    let path = dir.path().join("d.bin");
    d.write(&path).unwrap();
    assert_eq!(Dataset::read(&path).unwrap().samples, d.samples);
    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.path().join("cut.bin");
    std::fs::write(&cut, &bytes[..bytes.len() - 100]).unwrap();
    let e = Dataset::read(&cut).unwrap_err();
    assert!(matches!(e, DataError::Truncated { .. }), "{e}");
    assert!(e.to_string().contains("cut.bin"), "{e}");
    let junk = dir.path().join("junk.bin");
    std::fs::write(&junk, b"this is not data at all").unwrap();
    let e = Dataset::read(&junk).unwrap_err();
    assert!(matches!(e, DataError::Magic { .. }), "{e}");
    assert!(e.to_string().contains("junk.bin"), "{e}");
}

#[test]
fn configured_model_files_that_cannot_be_used_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = Config::default();
    c.predictor.kind = PredictorKind::Learned;
    c.predictor.conditioned_model = Some(dir.path().join("missing.json"));
    let e = c.validate().unwrap_err().to_string();
    assert!(
        e.contains("predictor.conditioned_model") && e.contains("missing.json"),
        "{e}"
    );
    // A corrupt file passes validation (it exists) but not the controller's construction.
    let bad = dir.path().join("corrupt.json");
    std::fs::write(&bad, "{\"format\":\"bkpbs-lane-change-model\",\"vers").unwrap();
    c.predictor.conditioned_model = Some(bad);
    c.validate().unwrap();
    let e = bkpbs::controller::check("bk-mastar", &c)
        .expect_err("corrupt model refused")
        .to_string();
    assert!(
        e.contains("predictor.conditioned_model") && e.contains("corrupt.json"),
        "{e}"
    );
    assert!(!e.contains('\n'), "{e}");
    // The models swapped.
    let dir2 = tempfile::tempdir().unwrap();
    let (cp, up) = (dir2.path().join("c.json"), dir2.path().join("u.json"));
    tiny_model(true).write(&cp).unwrap();
    tiny_model(false).write(&up).unwrap();
    c.predictor.conditioned_model = Some(up.clone());
    c.predictor.unconditioned_model = Some(cp.clone());
    assert!(matches!(
        bkpbs::predict::configured(&c),
        Err(bkpbs::predict::PredictorError { .. })
    ));
    c.predictor.conditioned_model = Some(cp);
    c.predictor.unconditioned_model = Some(up);
    assert_eq!(bkpbs::predict::configured(&c).unwrap().name(), "learned");
}

// ---------------------------------------------------------------------------------------------
// The predictor on hand-built scenes (with the committed models).

fn learned() -> Learned {
    let c = Config::default();
    Learned::with_models(
        &c,
        LaneChangeModel::embedded(true),
        LaneChangeModel::embedded(false),
    )
}

#[test]
fn ramp_hdv_near_the_lane_end_with_a_free_gap_is_predicted_to_merge_like_sumo() {
    let mut v = VehicleState::on_lane("ramp.1", Kind::Hdv, Origin::Ramp, 300.0, 0, 15.0);
    v.accel = 0.0;
    let s = Scene::on_paper_road(0.0, vec![v]);
    let p = learned();
    let r = p.rollout(&s, 0, &[], 20);
    let start = r.start.expect("predicted to merge within the horizon");
    assert_eq!(r.direction, 1);
    let t = p.predict(&s, 0, &[], 20);
    assert_eq!(t.poses.len(), 21);
    // SUMO's lane change: 0.9 m per step for 5 steps, from the step after the decision.
    for k in 0..=20 {
        let expect = (0.9 * (k as f64 - start as f64).clamp(0.0, 5.0)).min(4.5);
        assert!(
            (t.poses[k].y - expect).abs() < 1e-9,
            "step {k}: {:?}",
            t.poses[k]
        );
        assert!((t.poses[k].s - (300.0 + 15.0 * 0.2 * k as f64)).abs() < 1e-9);
    }
}

#[test]
fn vehicles_that_cannot_or_need_not_change_lanes_keep_their_lane() {
    let p = learned();
    // A ramp HDV far back on the ramp edge: no lane change while on the single-lane ramp.
    let mut on_ramp = VehicleState::on_lane("ramp.2", Kind::Hdv, Origin::Ramp, 20.0, 0, 20.0);
    on_ramp.on_ramp = true;
    // A ramp vehicle already merged (ramp HDVs never change lanes on the main road), and a CAV.
    let merged = VehicleState::on_lane("ramp.3", Kind::Hdv, Origin::Ramp, 380.0, 1, 30.0);
    let cav = VehicleState::on_lane("main.9", Kind::Cav, Origin::Main, 250.0, 1, 30.0);
    let s = Scene::on_paper_road(0.0, vec![on_ramp, merged, cav]);
    for i in 0..3 {
        let t = p.predict(&s, i, &[], 20);
        let y0 = s.vehicles[i].lane as f64 * 4.5;
        assert!(t.poses.iter().all(|q| q.y == y0), "vehicle {i}: {t:?}");
    }
    let r = p.rollout(&s, 0, &[], 20);
    assert_eq!(r.probabilities[0], 0.0, "on the ramp edge");
    assert!(r.start.is_none());
}

#[test]
fn a_lane_change_under_way_is_finished_at_sumos_lateral_speed() {
    let p = learned();
    // 2 steps into a change from lane 1 to lane 2 (SUMO: lateral +1.8, heading positive).
    let mut v = VehicleState::on_lane("main.1", Kind::Hdv, Origin::Main, 200.0, 1, 30.0);
    v.lateral = 1.8;
    v.heading = 0.2;
    // After the midpoint of a change from lane 2 to lane 1 (lane 1, lateral +1.8, heading < 0).
    let mut w = VehicleState::on_lane("main.2", Kind::Hdv, Origin::Main, 100.0, 1, 30.0);
    w.lateral = 1.8;
    w.heading = -0.2;
    let s = Scene::on_paper_road(0.0, vec![v, w]);
    let a = p.predict(&s, 0, &[], 10);
    let ys: Vec<f64> = a.poses.iter().map(|q| (q.y * 1e6).round() / 1e6).collect();
    assert_eq!(&ys[..5], &[6.3, 7.2, 8.1, 9.0, 9.0]);
    let b = p.predict(&s, 1, &[], 10);
    let ys: Vec<f64> = b.poses.iter().map(|q| (q.y * 1e6).round() / 1e6).collect();
    assert_eq!(&ys[..4], &[6.3, 5.4, 4.5, 4.5]);
}

#[test]
fn conditioning_on_a_cav_plan_uses_the_conditioned_model() {
    let p = learned();
    let hdv = VehicleState::on_lane("ramp.1", Kind::Hdv, Origin::Ramp, 270.0, 0, 20.0);
    let cav = VehicleState::on_lane("main.1", Kind::Cav, Origin::Main, 262.0, 1, 22.0);
    let s = Scene::on_paper_road(0.0, vec![hdv, cav]);
    // The CAV's plan: speed up past the HDV.
    let plan = Trajectory {
        poses: (0..=40)
            .map(|k| Pose {
                s: 262.0 + 22.0 * 0.2 * k as f64 + 0.2 * (k * k) as f64,
                y: 4.5,
                heading: 0.0,
                speed: 22.0 + 2.0 * 0.2 * k as f64,
            })
            .collect(),
        length: 5.0,
        width: 2.0,
        brake: None,
        committed: true,
    };
    let u = p.rollout(&s, 0, &[], 20);
    let c = p.rollout(&s, 0, &[&plan], 20);
    assert!(!u.probabilities.is_empty() && !c.probabilities.is_empty());
    assert_ne!(u.probabilities, c.probabilities, "the plan is an input");
    assert!(c.probabilities.iter().all(|q| (0.0..=1.0).contains(q)));
}

// ---------------------------------------------------------------------------------------------
// Real SUMO.

#[test]
fn collecting_on_sumo_gives_consistent_samples() {
    use bkpbs::train::collect::{collect, meta_of, CollectPlan};
    let plan = CollectPlan {
        episodes: 2,
        seed_base: 3,
        planners: vec!["idm-mobil".into()],
        alphas: vec![0.3],
        lambdas: vec![3000.0],
        steps: 250,
        main_negative_keep: 0.5,
    };
    let d = collect(&Config::default(), &plan, |_, _| {}).unwrap();
    let stats = meta_of(&d).unwrap().stats;
    assert_eq!(stats.episodes, 2);
    assert_eq!(stats.unexpected_direction, 0);
    assert!(stats.ramp_positive > 0, "{stats}");
    assert_eq!(
        d.samples.len() as u64,
        stats.ramp_negative + stats.ramp_positive + stats.main_negative + stats.main_positive
    );
    for s in &d.samples {
        assert!(s.step + 15 < 250, "no sample without a full preview");
        assert_eq!(s.subset, Subset::of_lane(s.obs.ego.lane as i32));
        assert_eq!(s.obs.ego.lateral, 0.0, "decision points only");
        match s.subset {
            Subset::Ramp => assert_eq!(s.weight, 1.0),
            Subset::Main => assert_eq!(s.weight, if s.label { 1.0 } else { 2.0 }),
        }
        // Ramp vehicles merge from the acceleration lane; neighbours are within range.
        assert!(s.obs.ego.lane != 0 || s.obs.ego.from_ramp);
        for n in &s.obs.neighbours {
            assert!(n.present || (n.ds, n.dy, n.speed) == (0.0, 0.0, 0.0));
            assert!(n.ds.abs() <= 100.0);
        }
        // A CAV seen at step k+1 was near the HDV at the start of the preview.
        for c in s.obs.cavs.iter().flatten().filter(|c| c.present) {
            assert!(c.ds.abs() < 60.0 + 15.0 * 0.2 * 40.0 && c.dy.abs() <= 2.0 * 4.5 + 1e-3);
        }
    }
    // Round trip through a file.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("c.bin");
    d.write(&p).unwrap();
    assert_eq!(Dataset::read(&p).unwrap().samples, d.samples);
}

#[test]
fn bk_mastar_with_the_learned_predictor_runs_a_sumo_episode() {
    let mut c = Config::default();
    c.scenario.steps = 150;
    c.scenario.seed = 5;
    c.scenario.alpha = 0.5;
    c.scenario.lambda = 3000.0;
    c.predictor.kind = PredictorKind::Learned;
    let r = bkpbs::episode::run(&c, "bk-mastar").unwrap();
    let s = &r.summary;
    assert_eq!(s.steps, 150);
    assert_eq!(s.inserted, s.arrived + s.crashed + s.present, "{s:?}");
    assert!(s.plan_stats.searches > 0 && s.arrived > 5, "{s:?}");
    eprintln!(
        "bk-mastar + b_θ, 150 steps: inserted {}, arrived {}, crashed {}, fallbacks {}",
        s.inserted, s.arrived, s.crashed, s.plan_stats.fallbacks
    );
}

#[test]
fn episode_cli_takes_the_predictor_flag_and_reports_bad_models_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = common::bkpbs(&[
        "episode",
        "--planner",
        "bk-mastar",
        "--predictor",
        "learned",
        "--steps",
        "40",
        "--out",
        dir.path().join("run").to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", common::stderr(&out));
    let cfg = dir.path().join("c.toml");
    std::fs::write(
        &cfg,
        "[predictor]\nkind = \"learned\"\nunconditioned_model = \"no/such/model.json\"\n",
    )
    .unwrap();
    let out = common::bkpbs(&[
        "episode",
        "--planner",
        "bk-mastar",
        "--steps",
        "5",
        "--config",
        cfg.to_str().unwrap(),
    ]);
    common::refused_naming(&out, &["no/such/model.json"]);
}

/// The allocation-free single-sample pass used for prediction gives the logits of the batched
/// training pass.
#[test]
fn single_sample_pass_matches_the_batched_one() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for conditioned in [false, true] {
        let arch = Architecture::new(conditioned);
        let p: Vec<f32> = arch.init(&mut rng);
        let net = Network::new(&arch, &p);
        let obs: Vec<Observation> = (0..20).map(|_| random_obs(&mut rng)).collect();
        let mut x = Inputs::<f32>::default();
        x.encode(obs.iter(), conditioned);
        let mut c = Cache::default();
        forward(&arch, &p, &x, &mut c);
        let mut ws = Workspace::default();
        for (o, &batched) in obs.iter().zip(c.logits.iter()) {
            bkpbs::predict::features::encode_a(o, ws.xa.as_mut_slice());
            bkpbs::predict::features::encode_b(o, ws.xb.as_mut_slice());
            let single = net.logit(&mut ws);
            assert!((single - batched).abs() < 1e-4, "{single} vs {batched}");
        }
    }
}
