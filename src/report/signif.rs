//! Significance tests of the paired comparisons ([`super::paired`]): Wilcoxon's signed-rank
//! test of per-seed differences and Fisher's exact test of a 2×2 table of collision episodes.
//!
//! Both follow R's `wilcox.test(paired = TRUE)` and `fisher.test` so that a reader can check a
//! number with the tool they know: zero differences are dropped before ranking (Wilcoxon's
//! method, R's and SciPy's default), the exact null distribution is used below 50 pairs when no
//! two |differences| tie, and otherwise the normal approximation with the tie correction of the
//! variance and a continuity correction of ½. Campaigns run a handful of seeds, where the normal
//! approximation alone would be off by a factor of two.

use statrs::distribution::{ContinuousCDF, Discrete, Hypergeometric, Normal};

/// Below this many nonzero differences (and without ties) the exact distribution is used (R's
/// threshold).
pub const EXACT_BELOW: usize = 50;

/// How a p-value was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// The exact null distribution of the signed-rank statistic.
    Exact,
    /// The normal approximation with tie and continuity correction.
    Normal,
}

impl Method {
    /// The name written in tables (`exact`, `normal`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Exact => "exact",
            Method::Normal => "normal",
        }
    }
}

/// The outcome of a signed-rank test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignedRank {
    /// V: the sum of the ranks of the positive differences (R's statistic).
    pub v: f64,
    /// Nonzero differences ranked.
    pub n: usize,
    /// Zero differences dropped before ranking.
    pub zeros: usize,
    /// The two-sided p-value.
    pub p: f64,
    /// How `p` was computed.
    pub method: Method,
}

/// Ranks 1..n of `xs` (ascending), ties sharing the mean of their ranks; and whether any tied.
fn mid_ranks(xs: &[f64]) -> (Vec<f64>, bool) {
    let mut order: Vec<usize> = (0..xs.len()).collect();
    order.sort_by(|&a, &b| xs[a].total_cmp(&xs[b]));
    let mut ranks = vec![0.0; xs.len()];
    let mut ties = false;
    let mut i = 0;
    while i < order.len() {
        let mut j = i + 1;
        while j < order.len() && xs[order[j]] == xs[order[i]] {
            j += 1;
        }
        ties |= j - i > 1;
        let rank = (i + 1 + j) as f64 / 2.0;
        for &k in &order[i..j] {
            ranks[k] = rank;
        }
        i = j;
    }
    (ranks, ties)
}

/// Counts of V = 0..=n(n+1)/2 over the 2ⁿ sign patterns of ranks 1..n (no ties).
fn signed_rank_counts(n: usize) -> Vec<f64> {
    let max = n * (n + 1) / 2;
    let mut counts = vec![0.0; max + 1];
    counts[0] = 1.0;
    for r in 1..=n {
        for v in (r..=max).rev() {
            counts[v] += counts[v - r];
        }
    }
    counts
}

/// The exact two-sided p of V among n untied ranks: twice the smaller tail, at most 1.
fn exact_p(v: f64, n: usize) -> f64 {
    let counts = signed_rank_counts(n);
    let total: f64 = counts.iter().sum();
    let v = v.round() as usize;
    let lower: f64 = counts[..=v].iter().sum();
    let upper: f64 = counts[v..].iter().sum();
    (2.0 * lower.min(upper) / total).min(1.0)
}

/// The normal approximation's two-sided p of V among the n mid-`ranks` (tied values share a
/// rank, so equal ranks are one tie group).
fn normal_p(v: f64, n: usize, ranks: &[f64]) -> f64 {
    let nf = n as f64;
    let mut sorted = ranks.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mut tie_term = 0.0;
    let mut i = 0;
    while i < sorted.len() {
        let j = i + sorted[i..].iter().take_while(|r| **r == sorted[i]).count();
        let t = (j - i) as f64;
        tie_term += t * t * t - t;
        i = j;
    }
    let sigma = (nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0 - tie_term / 48.0).sqrt();
    let centred = v - nf * (nf + 1.0) / 4.0;
    let z = (centred - 0.5 * centred.signum()) / sigma;
    let standard = Normal::new(0.0, 1.0).expect("the standard normal");
    (2.0 * standard.cdf(z).min(standard.sf(z))).min(1.0)
}

/// Wilcoxon's signed-rank test of the differences `d` (two-sided); `None` when no difference is
/// nonzero: the test then has nothing to rank, and a p-value of 1 would claim it had looked.
pub fn signed_rank(d: &[f64]) -> Option<SignedRank> {
    let nonzero: Vec<f64> = d.iter().copied().filter(|x| *x != 0.0).collect();
    let n = nonzero.len();
    if n == 0 {
        return None;
    }
    let abs: Vec<f64> = nonzero.iter().map(|x| x.abs()).collect();
    let (ranks, ties) = mid_ranks(&abs);
    let v: f64 = nonzero
        .iter()
        .zip(&ranks)
        .filter(|(x, _)| **x > 0.0)
        .fold(0.0, |v, (_, r)| v + r);
    let (p, method) = if n < EXACT_BELOW && !ties {
        (exact_p(v, n), Method::Exact)
    } else {
        (normal_p(v, n, &ranks), Method::Normal)
    };
    Some(SignedRank {
        v,
        n,
        zeros: d.len() - n,
        p,
        method,
    })
}

/// Fisher's exact two-sided p of the 2×2 table [[a, b], [c, d]]: the probability, with the
/// margins fixed, of every table no more likely than the one observed (R's rule, with its
/// relative tolerance of 1e-7 for tables of equal probability).
pub fn fisher_exact(a: u64, b: u64, c: u64, d: u64) -> f64 {
    let population = a + b + c + d;
    let (successes, draws) = (a + c, a + b);
    let h = Hypergeometric::new(population, successes, draws).expect("margins within the total");
    let lo = draws.saturating_sub(population - successes);
    let hi = draws.min(successes);
    let observed = h.ln_pmf(a);
    let unlikely: Vec<f64> = (lo..=hi)
        .map(|k| h.ln_pmf(k))
        .filter(|&l| l <= observed + 1e-7_f64.ln_1p())
        .collect();
    if unlikely.len() as u64 == hi - lo + 1 {
        // Every table counts: exactly 1, not a sum rounded below it.
        return 1.0;
    }
    unlikely.into_iter().map(f64::exp).sum::<f64>().min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    #[allow(clippy::approx_constant)] // 3.14 is R's data, not π
    fn signed_rank_exact_matches_a_hand_count_and_r() {
        // n = 3, all positive: V = 6 is 1 of the 8 sign patterns, so each tail is 1/8 and the
        // two-sided p is 2/8.
        let t = signed_rank(&[1.0, 2.0, 3.0]).unwrap();
        assert_eq!((t.v, t.n, t.method), (6.0, 3, Method::Exact));
        assert!(close(t.p, 0.25, 1e-12), "{t:?}");
        // -1, 2, 3, 4: V = 9 of max 10; P(V >= 9) = #{10, 9} = 2 of 16, p = 4/16.
        let t = signed_rank(&[-1.0, 2.0, 3.0, 4.0]).unwrap();
        assert_eq!(t.v, 9.0);
        assert!(close(t.p, 0.25, 1e-12), "{t:?}");
        // R: wilcox.test(x, y, paired = TRUE): V = 40, p-value = 0.03906 (= 20/512).
        let x = [1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30];
        let y = [0.878, 0.647, 0.598, 2.05, 1.06, 1.29, 1.06, 3.14, 1.29];
        let d: Vec<f64> = x.iter().zip(&y).map(|(a, b)| a - b).collect();
        let t = signed_rank(&d).unwrap();
        assert_eq!((t.v, t.n, t.zeros, t.method), (40.0, 9, 0, Method::Exact));
        assert!(close(t.p, 20.0 / 512.0, 1e-12), "{t:?}");
        // The reverse difference mirrors V and keeps p.
        let minus: Vec<f64> = d.iter().map(|x| -x).collect();
        let t = signed_rank(&minus).unwrap();
        assert_eq!(t.v, 5.0);
        assert!(close(t.p, 20.0 / 512.0, 1e-12));
    }

    #[test]
    fn signed_rank_drops_zeros_and_corrects_ties_like_r_and_scipy() {
        // Zeros dropped (Wilcoxon), ties (1 1, 2 2 2 and 3 3 3): normal approximation. By hand:
        // |d| of the 9 nonzero = 1 2 2 1 3 3 3 2 4, mid-ranks 1.5 4 4 1.5 7 7 7 4 9,
        // V = 1.5 + 4 + 4 + 7·3 + 9 = 39.5, mean 22.5, var = 9·10·19/24 - (6 + 24 + 24)/48 =
        // 70.125, z = (17 - 0.5)/√70.125 = 1.970369, p = 0.048796 (SciPy's wilcoxon with
        // correction=True, method="approx": 0.048796126392).
        let t = signed_rank(&[1.0, 2.0, 2.0, 0.0, -1.0, 3.0, 3.0, 3.0, -2.0, 4.0, 0.0]).unwrap();
        assert_eq!((t.n, t.zeros, t.method), (9, 2, Method::Normal));
        assert_eq!(t.v, 39.5);
        assert!(close(t.p, 0.048_796_126_392, 1e-9), "{t:?}");
        // No nonzero difference: nothing to test.
        assert_eq!(signed_rank(&[0.0, 0.0]), None);
        assert_eq!(signed_rank(&[]), None);
        // A single nonzero difference: both tails are ½, p = 1.
        assert_eq!(signed_rank(&[0.0, 3.0]).unwrap().p, 1.0);
        // All negative: V is a plain zero (no "-0" in the CSV).
        let t = signed_rank(&[-1.0, -2.0]).unwrap();
        assert_eq!((t.v.to_string().as_str(), t.p), ("0", 0.5));
    }

    #[test]
    fn signed_rank_normal_approximation_for_many_pairs_matches_scipy() {
        // 60 differences with ties; scipy.stats.wilcoxon(d, correction=True, method="approx")
        // gives p = 0.0151240525.
        let d = [
            0.65, 1.12, 0.63, -1.0, 1.21, 0.75, -0.24, 0.88, 0.66, 0.59, 0.33, 0.85, -0.44, 0.14,
            -0.18, 0.9, 0.34, 0.01, -0.48, 0.04, 0.31, 0.02, 1.59, 1.31, -2.41, -1.59, 0.13, -0.12,
            0.51, 0.52, 2.42, -0.81, -0.08, 2.34, 0.95, 0.96, -0.21, -1.35, 0.47, 0.41, -0.93,
            -0.38, 0.23, -0.64, 0.2, 0.4, 0.34, -0.21, 0.89, 1.19, 0.62, -0.52, 1.03, -0.2, 1.18,
            -0.77, 1.21, 0.28, -0.95, -0.01,
        ];
        let t = signed_rank(&d).unwrap();
        assert_eq!((t.n, t.method), (60, Method::Normal));
        assert!(close(t.p, 0.015_124_052_5, 1e-9), "{t:?}");
    }

    #[test]
    fn fisher_exact_matches_a_hand_sum_and_r() {
        // [[3, 1], [1, 3]]: margins 4/4 of 8, P(k) = C(4,k)C(4,4-k)/70 = 1 16 36 16 1 (/70);
        // tables no likelier than k = 3 (16/70): k = 0, 1, 3, 4, p = 34/70 = 0.4857 (R).
        assert!(close(fisher_exact(3, 1, 1, 3), 34.0 / 70.0, 1e-12));
        assert!(close(fisher_exact(1, 3, 3, 1), 34.0 / 70.0, 1e-12));
        // R's fisher.test(matrix(c(2, 418, 8, 412), 2)); SciPy: 0.10727991399107317.
        assert!(close(fisher_exact(2, 8, 418, 412), 0.107_279_913_991, 1e-9));
        assert!(close(fisher_exact(2, 418, 8, 412), 0.107_279_913_991, 1e-9));
        // No collision anywhere: every table is the observed one, p = 1.
        assert_eq!(fisher_exact(0, 5, 0, 5), 1.0);
        assert_eq!(fisher_exact(1, 1, 0, 2), 1.0);
        assert!(close(fisher_exact(5, 0, 0, 5), 2.0 / 252.0, 1e-12));
    }
}
