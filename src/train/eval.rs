//! `bkpbs eval-predictor`: the paper's tables I–II for b_θ, next to two baselines.
//!
//! As in the paper, 4000 samples from the ramp (acceleration lane) and 4000 from the main road
//! are classified, each as "lane change at the next step" or not. Two draws are reported:
//!
//! * **natural**: 4000 decision points drawn at random, so lane changes are as rare as they
//!   are in SUMO (≈ 2 % of ramp steps, ≈ 0.1 % of main-road steps; thinned-out main-road
//!   negatives count with their weight). Decisions at the thresholds tuned on the training
//!   data's validation split (best F1).
//! * **paper mix**: 4000 samples with the paper's share of lane changes (ramp 1443 of 4000,
//!   main 706 of 4000; all lane changes of the data if there are fewer, with negatives in
//!   proportion), so that accuracy means what it means in the paper. Only the class prior
//!   differs from the natural draw, so the calibrated probabilities are shifted to the paper's
//!   prior (Bayes' rule: logit + logit(prior_paper) − logit(prior_training)) and each sample is
//!   given its more likely class — the accuracy-optimal decision for that mix, fixed before
//!   looking at any evaluation sample.
//!
//! Baselines on the same samples: "never changes lane", and the logistic regression stored in
//! the model file (same features, same training data, same calibration and decision rules).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::dataset::{Dataset, Sample};
use super::training_loop::Confusion;
use crate::predict::features::Subset;
use crate::predict::infer::Workspace;
use crate::predict::model_file::LaneChangeModel;

/// The paper's number of lane changes among the [`PER_SUBSET`] samples of each evaluation
/// subset (tables I and II).
pub const PAPER_POSITIVES: [(Subset, usize); 2] = [(Subset::Ramp, 1443), (Subset::Main, 706)];

/// Samples per subset (the paper's 4000).
pub const PER_SUBSET: usize = 4000;

/// One subset's confusion matrices.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubsetEval {
    /// The subset evaluated (ramp or main road).
    pub subset: Subset,
    /// Samples classified.
    pub samples: usize,
    /// Lane changes among them.
    pub positives: usize,
    /// b_θ's decisions.
    pub model: Confusion,
    /// The "never changes lane" baseline's decisions.
    pub never: Confusion,
    /// The logistic-regression baseline's decisions.
    pub logistic: Confusion,
}

/// Both draws of both subsets.
#[derive(Debug, Clone, PartialEq)]
pub struct EvalReport {
    /// Where the model came from (a path, or `embedded:<name>`).
    pub model: String,
    /// Whether the model is conditioned on the CAVs' trajectories.
    pub conditioned: bool,
    /// The natural draw: [`PER_SUBSET`] decision points per subset, drawn by weight.
    pub natural: Vec<SubsetEval>,
    /// The paper mix: the paper's share of lane changes ([`PAPER_POSITIVES`]), per subset.
    pub paper_mix: Vec<SubsetEval>,
    /// Every decision point of the data, weighted (the natural distribution without the
    /// 4000-sample draw's noise: on the main road that draw holds only a handful of lane
    /// changes).
    pub all: Vec<SubsetEval>,
}

/// Efraimidis–Spirakis: `n` of `items` drawn without replacement with probability proportional
/// to their weights, in a deterministic order.
fn weighted_draw<'a>(items: &[&'a Sample], n: usize, rng: &mut ChaCha8Rng) -> Vec<&'a Sample> {
    let mut keyed: Vec<(f64, usize)> = items
        .iter()
        .enumerate()
        .map(|(i, s)| (rng.gen::<f64>().max(1e-300).ln() / s.weight as f64, i))
        .collect();
    keyed.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    keyed.iter().take(n).map(|&(_, i)| items[i]).collect()
}

/// Classifies `drawn`: at the tuned thresholds, or — given a share of lane changes `prior` —
/// by the most likely class once the calibrated probabilities are shifted to that share.
fn classify(
    model: &LaneChangeModel,
    subset: Subset,
    drawn: &[&Sample],
    prior: Option<f64>,
    weighted: bool,
) -> SubsetEval {
    let mut ws = Workspace::default();
    let mut x = Vec::new();
    let mut e = SubsetEval {
        subset,
        samples: drawn.len(),
        positives: drawn.iter().filter(|s| s.label).count(),
        model: Confusion::default(),
        never: Confusion::default(),
        logistic: Confusion::default(),
    };
    let cal = &model.file.calibration;
    let bcal = &model.file.baseline.calibration;
    let rule = |c: &crate::predict::calibration::Calibration, logit: f64| match prior {
        Some(rate) => c.probability(logit + c.shift_to(subset, rate), subset) >= 0.5,
        None => c.probability(logit, subset) >= c.threshold(subset),
    };
    for s in drawn {
        let w = if weighted { s.weight as f64 } else { 1.0 };
        let z = model.logit(&s.obs, &mut ws) as f64;
        e.model.add(rule(cal, z), s.label, w);
        e.never.add(false, s.label, w);
        let zb = model.baseline_logit(&s.obs, &mut x) as f64;
        e.logistic.add(rule(bcal, zb), s.label, w);
    }
    e
}

/// Evaluates `model` on `data` (`seed` drives the draws).
pub fn evaluate(model: &LaneChangeModel, data: &Dataset, seed: u64) -> EvalReport {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut natural = Vec::new();
    let mut paper_mix = Vec::new();
    let mut everything = Vec::new();
    for (subset, paper_pos) in PAPER_POSITIVES {
        let all: Vec<&Sample> = data.samples.iter().filter(|s| s.subset == subset).collect();
        let drawn = weighted_draw(&all, PER_SUBSET, &mut rng);
        natural.push(classify(model, subset, &drawn, None, false));
        everything.push(classify(model, subset, &all, None, true));
        let pos: Vec<&Sample> = all.iter().copied().filter(|s| s.label).collect();
        let neg: Vec<&Sample> = all.iter().copied().filter(|s| !s.label).collect();
        let share = paper_pos as f64 / PER_SUBSET as f64;
        let n_pos = paper_pos.min(pos.len());
        let n_neg = if n_pos == paper_pos {
            PER_SUBSET - paper_pos
        } else {
            (n_pos as f64 * (1.0 - share) / share).round() as usize
        };
        let mut mix = weighted_draw(&pos, n_pos, &mut rng);
        mix.extend(weighted_draw(&neg, n_neg, &mut rng));
        paper_mix.push(classify(model, subset, &mix, Some(share), false));
    }
    EvalReport {
        model: model.source.clone(),
        conditioned: model.conditioned(),
        natural,
        paper_mix,
        all: everything,
    }
}

fn pct(x: f64) -> String {
    format!("{:.1}%", 100.0 * x)
}

fn line(lead: &str, what: &str, c: &Confusion) -> String {
    format!(
        "{lead}{what:<23} accuracy {:>6}  precision {:>6}  recall {:>6}  F1 {:.3}  | actual no: {:>4.0} predicted no, {:>4.0} yes; actual yes: {:>4.0} no, {:>4.0} yes\n",
        pct(c.accuracy()),
        pct(c.precision()),
        pct(c.recall()),
        c.f1(),
        c.tn,
        c.fp,
        c.fn_,
        c.tp
    )
}

impl EvalReport {
    /// The report as text: per draw and subset, a summary line for b_θ (starting with the
    /// subset's name in the natural draw) and one for each baseline.
    pub fn to_text(&self) -> String {
        let mut out = format!(
            "b_θ model: {} ({})\n",
            self.model,
            if self.conditioned {
                "conditioned on CAV trajectories"
            } else {
                "unconditioned"
            }
        );
        for (title, lead, rows) in [
            (
                "natural draw: decision points at random, lane changes as frequent as in SUMO",
                "",
                &self.natural,
            ),
            (
                "all decision points of the data, main-road negatives counted with their weight",
                "all-data ",
                &self.all,
            ),
            (
                "paper mix: the paper's share of lane changes (ramp 1443, main 706 of 4000); \
                 decisions for that share (calibrated probabilities shifted to it, most likely class)",
                "paper-mix ",
                &self.paper_mix,
            ),
        ] {
            out += &format!("\n{title}\n");
            for r in rows {
                let name = r.subset.as_str();
                let pad = " ".repeat(lead.len() + name.len());
                out += &line(&format!("{lead}{name} "), "b_θ (GCN)", &r.model);
                out += &line(&format!("{pad} "), "baseline never-changes", &r.never);
                out += &line(&format!("{pad} "), "baseline logistic", &r.logistic);
                out += &format!(
                    "{pad}  ({} samples, {} lane changes)\n",
                    r.samples, r.positives
                );
            }
        }
        out
    }
}
