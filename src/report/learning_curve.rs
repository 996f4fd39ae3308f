//! The RL-PPO learning curve (`learning_curve.png` / `.svg` of `bkpbs train-rl`): mean return,
//! CAV collision rate and mean speed of each update's sampled episodes against environment
//! steps; each update thin, a moving average over `SMOOTHING` updates thick.

use super::plot::{Curve, LinePanel, LinePanels};
use crate::train::ppo::rollout::RolloutStats;
use crate::train::ppo::trainer::CurveRow;

/// Updates in the moving average.
const SMOOTHING: usize = 20;

/// One panel of the figure: a quantity of each update, and the same quantity of a reference
/// policy (none for quantities only training has, like the entropy).
struct Quantity {
    title: &'static str,
    y_label: &'static str,
    value: fn(&CurveRow) -> f64,
    level: Option<fn(&RolloutStats) -> f64>,
}

/// The panels, in reading order.
const QUANTITIES: [Quantity; 4] = [
    Quantity {
        title: "mean return per CAV",
        y_label: "return",
        value: |r| r.mean_return,
        level: Some(RolloutStats::mean_return),
    },
    Quantity {
        title: "CAV collision rate",
        y_label: "crashed CAVs (%)",
        value: |r| 100.0 * r.collision_rate,
        level: Some(|s| 100.0 * s.collision_rate()),
    },
    Quantity {
        title: "mean CAV speed",
        y_label: "m/s",
        value: |r| r.mean_speed,
        level: Some(RolloutStats::mean_speed),
    },
    Quantity {
        title: "policy entropy",
        y_label: "nats",
        value: |r| r.entropy,
        level: None,
    },
];

/// The figure of `rows`, with the levels of reference policies (name, totals on held-out
/// episodes) as flat lines.
pub fn figure(rows: &[CurveRow], references: &[(&str, RolloutStats)]) -> LinePanels {
    let x_end = rows.last().map_or(1.0, |r| r.env_steps as f64 / 1e6);
    let mut legend = vec![
        (0, "each update (sampled)".into(), false),
        (0, format!("mean of {SMOOTHING} updates"), true),
    ];
    for (k, (name, _)) in references.iter().enumerate() {
        legend.push((k + 1, format!("{name}, held-out"), true));
    }
    LinePanels {
        panels: QUANTITIES
            .iter()
            .map(|q| q.panel(rows, references, x_end))
            .collect(),
        legend,
    }
}

impl Quantity {
    /// Each update thin, their moving average thick (colour 0), then reference `k`'s level as a
    /// flat line from 0 to `x_end` in colour `k + 1`.
    fn panel(
        &self,
        rows: &[CurveRow],
        references: &[(&str, RolloutStats)],
        x_end: f64,
    ) -> LinePanel {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| (r.env_steps as f64 / 1e6, (self.value)(r)))
            .collect();
        let flat = references.iter().enumerate().filter_map(|(k, (_, st))| {
            self.level.map(|f| Curve {
                points: vec![(0.0, f(st)), (x_end, f(st))],
                colour: k + 1,
                thick: true,
            })
        });
        let updates = [
            Curve {
                points: points.clone(),
                colour: 0,
                thick: false,
            },
            Curve {
                points: moving_average(&points, SMOOTHING),
                colour: 0,
                thick: true,
            },
        ];
        LinePanel {
            title: self.title.into(),
            x_label: "environment steps (millions of CAV decisions)".into(),
            y_label: self.y_label.into(),
            curves: updates.into_iter().chain(flat).collect(),
            bands: Vec::new(),
            dots: Vec::new(),
            marks: Vec::new(),
            x_range: None,
        }
    }
}

/// Trailing moving average over up to `k` points.
fn moving_average(points: &[(f64, f64)], k: usize) -> Vec<(f64, f64)> {
    (0..points.len())
        .map(|i| {
            let from = (i + 1).saturating_sub(k);
            let w = &points[from..=i];
            (
                points[i].0,
                w.iter().map(|p| p.1).sum::<f64>() / w.len() as f64,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_average_trails() {
        let p = [(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)];
        assert_eq!(
            moving_average(&p, 2),
            vec![(0.0, 1.0), (1.0, 2.0), (2.0, 4.0)]
        );
    }
}
