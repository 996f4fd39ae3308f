//! From the network's raw logit to a decision: the prior shift per subset and the tuned
//! thresholds, fitted at training time and stored in the model file.

use serde::{Deserialize, Serialize};

use super::features::Subset;
use super::gcn::sigmoid;

/// From raw logits to decisions: the prior shift per subset and the tuned thresholds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Added to the logit of a ramp sample.
    pub logit_offset_ramp: f64,
    /// Added to the logit of a main-road sample: ln of the rate at which the training data kept
    /// main-road negatives.
    pub logit_offset_main: f64,
    /// A ramp sample is classified "lane change" when its calibrated probability reaches this
    /// (tuned for the best F1 on the validation episodes).
    pub threshold_ramp: f64,
    /// The same for a main-road sample.
    pub threshold_main: f64,
    /// Share of lane changes among the ramp training decision points (natural distribution).
    pub positive_rate_ramp: f64,
    /// The same among the main-road training decision points.
    pub positive_rate_main: f64,
}

impl Calibration {
    /// Calibrated probability of a raw logit.
    pub fn probability(&self, logit: f64, subset: Subset) -> f64 {
        sigmoid(logit + self.offset(subset))
    }

    /// Logit shift of `subset` (undoes the training data's down-sampling of negatives).
    pub fn offset(&self, subset: Subset) -> f64 {
        match subset {
            Subset::Ramp => self.logit_offset_ramp,
            Subset::Main => self.logit_offset_main,
        }
    }

    /// Decision threshold on the calibrated probability for `subset`.
    pub fn threshold(&self, subset: Subset) -> f64 {
        match subset {
            Subset::Ramp => self.threshold_ramp,
            Subset::Main => self.threshold_main,
        }
    }

    /// The natural share of lane changes the model was trained on.
    pub fn positive_rate(&self, subset: Subset) -> f64 {
        match subset {
            Subset::Ramp => self.positive_rate_ramp,
            Subset::Main => self.positive_rate_main,
        }
    }

    /// Logit shift that turns a calibrated probability into the probability under a different
    /// share `rate` of lane changes (label shift: only the class prior changes).
    pub fn shift_to(&self, subset: Subset, rate: f64) -> f64 {
        let logit = |p: f64| (p / (1.0 - p)).ln();
        logit(rate) - logit(self.positive_rate(subset).clamp(1e-9, 1.0 - 1e-9))
    }
}
