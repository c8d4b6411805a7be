//! Change detectors of a coal/gangue flow computed on the host in `f64`, independently of the
//! kernel: the exact mixture likelihood ratio of a scene's noiseless class densities, Page's
//! CUSUM on it or on the true labels, and the naive rule "k confident gangue verdicts among
//! the last n".

use std::collections::VecDeque;

use crate::score::bayes::ClassModel;

/// The scene's classes split into coal and gangue, each group mixed by its priors.
#[derive(Debug, Clone, PartialEq)]
pub struct MixtureModel {
    /// The class models ([`crate::score::evaluate::class_models`]).
    pub models: Vec<ClassModel>,
    /// `gangue[c]`: class `c` is gangue.
    pub gangue: Vec<bool>,
}

impl MixtureModel {
    /// Prior weight of class `c` within its group.
    fn weight(&self, c: usize) -> f64 {
        let g = self.gangue[c];
        let total: f64 = self
            .models
            .iter()
            .zip(&self.gangue)
            .filter(|(_, gg)| **gg == g)
            .map(|(m, _)| m.prior)
            .sum();
        self.models[c].prior / total
    }

    /// `ln(p_G / p_C)` at `(ln F_max, ln t_c)` from the noiseless class densities,
    /// `p_G = sum_{c in G} w_c p_c` (`w_c` the prior within the group), likewise `p_C`;
    /// `+-inf` where one group has no density, `None` where neither has.
    pub fn ln_ratio(&self, ln_force: f64, ln_duration: f64) -> Option<f64> {
        let (mut pg, mut pc) = (0.0, 0.0);
        for (c, m) in self.models.iter().enumerate() {
            let p = self.weight(c) * m.density(ln_force, ln_duration);
            if self.gangue[c] {
                pg += p;
            } else {
                pc += p;
            }
        }
        match (pg > 0.0, pc > 0.0) {
            (false, false) => None,
            (true, false) => Some(f64::INFINITY),
            (false, true) => Some(f64::NEG_INFINITY),
            (true, true) => Some(pg.ln() - pc.ln()),
        }
    }
}

/// The CUSUM increment `ln[(pi1 r + 1 - pi1) / (pi0 r + 1 - pi0)]` of a pulse with
/// `ln r = ln_ratio` (in nats; exact at `ln r = +-inf`).
pub fn increment(pi0: f64, pi1: f64, ln_ratio: f64) -> f64 {
    if ln_ratio == f64::INFINITY {
        return (pi1 / pi0).ln();
    }
    if ln_ratio == f64::NEG_INFINITY {
        return ((1.0 - pi1) / (1.0 - pi0)).ln();
    }
    if ln_ratio > 0.0 {
        // Divide through by r so that e^ln_ratio cannot overflow.
        let q = (-ln_ratio).exp();
        ((pi1 + (1.0 - pi1) * q) / (pi0 + (1.0 - pi0) * q)).ln()
    } else {
        let r = ln_ratio.exp();
        ((pi1 * r + 1.0 - pi1) / (pi0 * r + 1.0 - pi0)).ln()
    }
}

/// The increment of a pulse whose class is known: `ln(pi1 / pi0)` for gangue,
/// `ln((1 - pi1) / (1 - pi0))` for coal (the label oracle).
pub fn label_increment(pi0: f64, pi1: f64, gangue: bool) -> f64 {
    if gangue {
        (pi1 / pi0).ln()
    } else {
        ((1.0 - pi1) / (1.0 - pi0)).ln()
    }
}

/// Page's CUSUM `S <- max(0, S + increment)`, alarm at `S >= h`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cusum {
    /// Threshold `h` in nats.
    pub threshold: f64,
    /// The statistic `S`.
    pub statistic: f64,
}

impl Cusum {
    /// A CUSUM with `h = ln(1 / false_alarm_rate)` (alarms per impact).
    pub fn for_rate(false_alarm_rate: f64) -> Self {
        Self {
            threshold: -false_alarm_rate.ln(),
            statistic: 0.0,
        }
    }

    /// Adds one increment; `true` when the alarm is raised (the statistic is then reset to 0,
    /// so a run of pulses gives one alarm per crossing).
    pub fn step(&mut self, increment: f64) -> bool {
        self.statistic = (self.statistic + increment).max(0.0);
        if self.statistic >= self.threshold {
            self.statistic = 0.0;
            return true;
        }
        false
    }
}

/// The naive rule: alarm once `k` of the last `n` pulses got a confident gangue verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct NaiveRule {
    /// Confident gangue verdicts needed.
    pub k: usize,
    /// Pulses looked back on.
    pub n: usize,
    window: VecDeque<bool>,
    count: usize,
}

impl NaiveRule {
    /// `k` of the last `n`.
    pub fn new(k: usize, n: usize) -> Self {
        Self {
            k,
            n,
            window: VecDeque::with_capacity(n + 1),
            count: 0,
        }
    }

    /// One pulse; `true` on alarm (the window is then emptied).
    pub fn step(&mut self, confident_gangue: bool) -> bool {
        self.window.push_back(confident_gangue);
        self.count += confident_gangue as usize;
        if self.window.len() > self.n {
            self.count -= self.window.pop_front().unwrap_or(false) as usize;
        }
        if self.count >= self.k {
            self.window.clear();
            self.count = 0;
            return true;
        }
        false
    }

    /// The smallest `k` whose alarm rate per pulse on background flow is at most `alpha`,
    /// by the bound `q P(Bin(n - 1, q) >= k - 1)` (an alarm needs a confident gangue verdict
    /// now and `k - 1` more among the `n - 1` before), `q` the rate of confident gangue
    /// verdicts in background flow; `n` when none is small enough.
    pub fn k_for(q: f64, n: usize, alpha: f64) -> usize {
        (1..=n)
            .find(|&k| q * binomial_tail(n - 1, q, k - 1) <= alpha)
            .unwrap_or(n)
    }
}

/// `P(Bin(n, p) >= k)`.
pub fn binomial_tail(n: usize, p: f64, k: usize) -> f64 {
    let mut term = (1.0 - p).powi(n as i32); // P(X = 0)
    let mut below = 0.0;
    for j in 0..k.min(n + 1) {
        below += term;
        term *= (n - j) as f64 / (j + 1) as f64 * p / (1.0 - p);
    }
    (1.0 - below).max(0.0)
}

/// Median and 90th percentile (nearest rank) of `v`; `(NaN, NaN)` when empty.
pub fn median_p90(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let rank = |q: f64| s[((q * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1];
    (rank(0.5), rank(0.9))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn increment_is_exact_at_the_extremes_and_zero_for_no_information() {
        assert!((increment(0.05, 0.5, f64::INFINITY) - 10f64.ln()).abs() < 1e-12);
        assert!((increment(0.05, 0.5, 800.0) - 10f64.ln()).abs() < 1e-12);
        assert!((increment(0.05, 0.5, -800.0) - (0.5f64 / 0.95).ln()).abs() < 1e-12);
        assert_eq!(increment(0.05, 0.5, 0.0), 0.0);
    }

    #[test]
    fn binomial_tail_and_naive_k() {
        assert!((binomial_tail(2, 0.5, 1) - 0.75).abs() < 1e-12);
        assert!((binomial_tail(3, 0.5, 3) - 0.125).abs() < 1e-12);
        assert_eq!(binomial_tail(3, 0.5, 0), 1.0);
        let k = NaiveRule::k_for(0.02, 20, 1e-5);
        assert!(0.02 * binomial_tail(19, 0.02, k - 1) <= 1e-5);
        assert!(0.02 * binomial_tail(19, 0.02, k - 2) > 1e-5);
        let mut r = NaiveRule::new(2, 3);
        assert!(!r.step(true));
        assert!(!r.step(false));
        assert!(!r.step(false));
        assert!(!r.step(true)); // the first true left the window
        assert!(r.step(true));
    }

    #[test]
    fn median_and_p90_by_nearest_rank() {
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(median_p90(&v), (5.0, 9.0));
    }
}
