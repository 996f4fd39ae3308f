//! Statistics of the report: the mean over seeds and its 95 % confidence interval.
//!
//! The interval is Student's: mean ± t(0.975, n − 1) · s / √n with s the sample standard
//! deviation (n − 1 in the denominator). Campaigns run few seeds (5 by default), where the normal
//! approximation (1.96) would understate the interval by a third, hence t.

use crate::episode::metrics::mean;

/// Fewer values than this get no 95 % interval in the report: t(0.975, n − 1) is 12.7, 4.3 and
/// 3.2 for 2, 3 and 4 values, so the interval would say more about how few seeds there are than
/// about the planners (a 2-seed collision rate read "13.62 ± 46.01" %). The tables list each
/// seed's value instead ([`super::tables`]), the figures draw each as a dot
/// ([`super::BAND_MIN_SEEDS`]). Paired differences keep their interval: a seed is the same
/// traffic for both planners, so their spread is not the traffic's.
pub const INTERVAL_MIN_SEEDS: usize = 5;

/// Two-sided 95 % quantiles t(0.975, df) for df = 1..=30.
const T_975: [f64; 30] = [
    12.706_205, 4.302_653, 3.182_446, 2.776_445, 2.570_582, 2.446_912, 2.364_624, 2.306_004,
    2.262_157, 2.228_139, 2.200_985, 2.178_813, 2.160_369, 2.144_787, 2.131_450, 2.119_905,
    2.109_816, 2.100_922, 2.093_024, 2.085_963, 2.079_614, 2.073_873, 2.068_658, 2.063_899,
    2.059_539, 2.055_529, 2.051_831, 2.048_407, 2.045_230, 2.042_272,
];

/// The 0.975 quantile of Student's t with `df` degrees of freedom (df ≥ 1).
///
/// Tabulated up to 30; beyond, the Cornish–Fisher expansion around the normal quantile, exact
/// to 1e-6 there.
pub fn t_975(df: usize) -> f64 {
    assert!(df >= 1, "Student t needs at least one degree of freedom");
    if df <= T_975.len() {
        return T_975[df - 1];
    }
    let z: f64 = 1.959_963_984_540_054;
    let v = df as f64;
    let g1 = (z.powi(3) + z) / 4.0;
    let g2 = (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / 96.0;
    let g3 = (3.0 * z.powi(7) + 19.0 * z.powi(5) + 17.0 * z.powi(3) - 15.0 * z) / 384.0;
    let g4 = (79.0 * z.powi(9) + 776.0 * z.powi(7) + 1482.0 * z.powi(5)
        - 1920.0 * z.powi(3)
        - 945.0 * z)
        / 92160.0;
    z + g1 / v + g2 / (v * v) + g3 / v.powi(3) + g4 / v.powi(4)
}

/// Sample standard deviation (n − 1); `None` below two values.
pub fn sample_std(xs: &[f64]) -> Option<f64> {
    let m = mean(xs.iter().copied())?;
    (xs.len() >= 2).then(|| {
        let ss: f64 = xs.iter().map(|x| (x - m) * (x - m)).sum();
        (ss / (xs.len() - 1) as f64).sqrt()
    })
}

/// A mean over seeds with its 95 % confidence half-width.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Number of values averaged.
    pub n: usize,
    /// The sample mean (in the unit of the values).
    pub mean: f64,
    /// t(0.975, n − 1) · s / √n; `None` for a single value.
    pub ci95: Option<f64>,
}

impl Estimate {
    /// The estimate of a sample; `None` for no values.
    pub fn of(xs: &[f64]) -> Option<Estimate> {
        let mean = mean(xs.iter().copied())?;
        let ci95 = sample_std(xs).map(|s| t_975(xs.len() - 1) * s / (xs.len() as f64).sqrt());
        Some(Estimate {
            n: xs.len(),
            mean,
            ci95,
        })
    }
}
