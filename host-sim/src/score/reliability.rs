//! The reliability of stated posteriors: verdicts binned by the posterior a classifier states
//! for its best class, against the share of them that named the true class, and the
//! calibration error that follows.
//!
//! A verdict `v` with stated posterior `p_v`, outcome `r_v` (1 right, 0 wrong) and weight
//! `w_v` (the prior weight of its true class per impact drawn, so that classes count in the
//! proportions of their priors) falls in the bin `[lower, upper)` holding `p_v` (the last bin
//! includes 1). Per bin: `stated = sum w p / sum w`, `observed = sum w r / sum w`. The
//! calibration error is `|stated - observed|` over the bins holding at least
//! [`MIN_VERDICTS`] verdicts: its largest value and its mean weighted by the bins' verdict
//! counts. A bin's observed share has the standard error `sqrt(o (1 - o) / n)`, 0.7 pp at
//! `o = 0.9`, `n = 2000`.

use serde::Serialize;

/// Bin edges of the stated posterior (dimensionless; the last bin includes 1).
pub const BIN_EDGES: [f64; 10] = [0.0, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.99, 0.999, 1.0];

/// Fewest verdicts a bin needs to count in the calibration error.
pub const MIN_VERDICTS: u64 = 200;

/// One posterior bin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ReliabilityBin {
    /// Lowest stated posterior of the bin.
    pub lower: f64,
    /// Upper end (excluded, but 1 is in the last bin).
    pub upper: f64,
    /// Verdicts in the bin.
    pub verdicts: u64,
    /// Mean stated posterior (weighted; 0 when empty).
    pub stated: f64,
    /// Share of the bin's verdicts that named the true class (weighted; 0 when empty).
    pub observed: f64,
    /// Standard error of `observed` were the posteriors calibrated,
    /// `sqrt(stated (1 - stated) / verdicts)` (0 when empty): a bin's `|stated - observed|`
    /// within about twice it is what its count allows.
    pub std_error: f64,
}

/// The reliability table and its calibration error.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Reliability {
    /// The bins, in order of [`BIN_EDGES`].
    pub bins: Vec<ReliabilityBin>,
    /// Verdicts with a stated posterior, all bins.
    pub verdicts: u64,
    /// Largest `|stated - observed|` over bins with at least [`MIN_VERDICTS`] verdicts (0 when
    /// none has).
    pub calibration_error_max: f64,
    /// Mean `|stated - observed|` over the same bins, weighted by their verdict counts.
    pub calibration_error_mean: f64,
    /// [`MIN_VERDICTS`].
    pub min_verdicts: u64,
}

/// The table of `verdicts`: `(stated posterior, right, weight)` each (non-finite posteriors
/// and non-positive weights are left out).
pub fn reliability(verdicts: impl IntoIterator<Item = (f64, bool, f64)>) -> Reliability {
    let k = BIN_EDGES.len() - 1;
    let mut count = vec![0u64; k];
    let mut sums = vec![[0.0f64; 3]; k]; // weight, weight x stated, weight x right
    for (p, right, w) in verdicts {
        if !(p.is_finite() && w > 0.0) {
            continue;
        }
        let b = BIN_EDGES[1..k].iter().take_while(|&&e| p >= e).count();
        count[b] += 1;
        sums[b][0] += w;
        sums[b][1] += w * p;
        sums[b][2] += w * right as u8 as f64;
    }
    let bins: Vec<ReliabilityBin> = (0..k)
        .map(|b| {
            let w = sums[b][0];
            let mean = |v: f64| if w > 0.0 { v / w } else { 0.0 };
            let stated = mean(sums[b][1]);
            ReliabilityBin {
                lower: BIN_EDGES[b],
                upper: BIN_EDGES[b + 1],
                verdicts: count[b],
                stated,
                observed: mean(sums[b][2]),
                std_error: if count[b] > 0 {
                    (stated * (1.0 - stated) / count[b] as f64).sqrt()
                } else {
                    0.0
                },
            }
        })
        .collect();
    let full: Vec<&ReliabilityBin> = bins.iter().filter(|b| b.verdicts >= MIN_VERDICTS).collect();
    let gap = |b: &ReliabilityBin| (b.stated - b.observed).abs();
    let n_full: u64 = full.iter().map(|b| b.verdicts).sum();
    Reliability {
        verdicts: count.iter().sum(),
        calibration_error_max: full.iter().map(|b| gap(b)).fold(0.0, f64::max),
        calibration_error_mean: if n_full > 0 {
            full.iter().map(|b| gap(b) * b.verdicts as f64).sum::<f64>() / n_full as f64
        } else {
            0.0
        },
        min_verdicts: MIN_VERDICTS,
        bins,
    }
}

impl Reliability {
    /// The table as text, one line per non-empty bin.
    pub fn table(&self) -> String {
        let mut s = format!(
            "  {:<16}{:>9}{:>10}{:>10}{:>9}{:>9}\n",
            "posterior", "verdicts", "stated", "observed", "|diff|", "std err"
        );
        for b in self.bins.iter().filter(|b| b.verdicts > 0) {
            let close = if b.upper >= 1.0 { ']' } else { ')' };
            s += &format!(
                "  [{:.3}, {:.3}{close}  {:>9}{:>9.2} %{:>8.2} %{:>7.2} %{:>7.2} %{}\n",
                b.lower,
                b.upper,
                b.verdicts,
                100.0 * b.stated,
                100.0 * b.observed,
                100.0 * (b.stated - b.observed).abs(),
                100.0 * b.std_error,
                if b.verdicts < self.min_verdicts {
                    "  (few)"
                } else {
                    ""
                }
            );
        }
        s += &format!(
            "  calibration error over bins of >= {} verdicts: max {:.2} pp, mean {:.2} pp\n",
            self.min_verdicts,
            100.0 * self.calibration_error_max,
            100.0 * self.calibration_error_mean
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_weights_and_errors_follow_their_definitions() {
        // 300 verdicts stated 0.95 of which 270 right (observed 0.9), 100 stated 0.55 all
        // wrong (too few to count), 400 stated 1.0 all right.
        let mut v = Vec::new();
        v.extend((0..300).map(|i| (0.95, i < 270, 1.0)));
        v.extend((0..100).map(|_| (0.55, false, 1.0)));
        v.extend((0..400).map(|_| (1.0, true, 1.0)));
        v.push((f64::NAN, true, 1.0));
        let r = reliability(v);
        assert_eq!(r.verdicts, 800);
        let b = |lo: f64| r.bins.iter().find(|b| b.lower == lo).unwrap();
        assert_eq!(b(0.95).verdicts, 300);
        assert!((b(0.95).observed - 0.9).abs() < 1e-12);
        assert_eq!(b(0.5).verdicts, 100);
        assert_eq!(b(0.999).verdicts, 400);
        assert!((r.calibration_error_max - 0.05).abs() < 1e-12);
        assert!((r.calibration_error_mean - 0.05 * 300.0 / 700.0).abs() < 1e-12);
        // The binomial standard error at the stated share: sqrt(0.95 0.05 / 300) = 1.258 pp.
        assert!((b(0.95).std_error - 0.012_583).abs() < 1e-6);
        assert_eq!(b(0.999).std_error, 0.0);
        // Weights: a class weighted 3 times as much moves the observed share.
        let r = reliability([(0.7, true, 3.0), (0.7, false, 1.0)]);
        assert_eq!(r.bins[3].lower, 0.7);
        assert!((r.bins[3].observed - 0.75).abs() < 1e-12);
    }
}
