//! The noise the kernel states for each measured pulse, checked against the truth: the pulse's
//! error in its true class's `(x, y) = (ln R, ln u)` (R in m, u in m/s) over the standard
//! deviation the classifier weighed it on (`coalshock::Scene::located`),
//! `z_x = (x - ln R) / sigma_x` and `z_y = (y - ln u) / sigma_y`, which a stated noise that
//! holds makes standard normal.
//!
//! Per coordinate it reports the root mean square of `z` (1 when the stated sigmas hold on
//! average) and the shares of `|z|` beyond 1, 2 and 3 ([`NORMAL_BEYOND`]: 31.73 %, 4.55 % and
//! 0.27 % for a standard normal). Both matter: a noise stated too wide for most pulses and too
//! narrow for a few can have a root mean square of 1, and the shares show it; the first
//! leaves posteriors under-confident, the second over-confident.

use serde::Serialize;

/// `P(|z| > k)` of a standard normal for `k = 1, 2, 3`: `erfc(k / sqrt 2)`.
pub const NORMAL_BEYOND: [f64; 3] = [0.317_310_5, 0.045_500_26, 0.002_699_8];

/// `z` of one coordinate over the checked pulses.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ZStats {
    /// Root mean square of `z` (dimensionless; 1 for a stated noise that holds).
    pub rms: f64,
    /// Shares of the pulses with `|z|` beyond 1, 2 and 3 (compare [`NORMAL_BEYOND`]).
    pub beyond: [f64; 3],
}

impl ZStats {
    fn of(z: &[f64]) -> Self {
        let n = z.len().max(1) as f64;
        let share = |k: f64| z.iter().filter(|v| v.abs() > k).count() as f64 / n;
        Self {
            rms: (z.iter().map(|v| v * v).sum::<f64>() / n).sqrt(),
            beyond: [share(1.0), share(2.0), share(3.0)],
        }
    }
}

/// The stated noise checked over a set of measured pulses (see the module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StatedNoiseCheck {
    /// Pulses checked (measured, not rejected, with a finite `z`).
    pub pulses: u64,
    /// `z` of `ln R`.
    pub ln_radius: ZStats,
    /// `z` of `ln u`.
    pub ln_speed: ZStats,
}

impl StatedNoiseCheck {
    /// The check over `(z_x, z_y)` pairs (non-finite pairs left out).
    ///
    /// ```
    /// use host_sim::score::noise_check::StatedNoiseCheck;
    /// let c = StatedNoiseCheck::of([(0.5, -2.5), (-1.5, 0.5), (f64::NAN, 0.0)]);
    /// assert_eq!(c.pulses, 2);
    /// assert!((c.ln_radius.rms - 1.25f64.sqrt()).abs() < 1e-12);
    /// assert_eq!(c.ln_speed.beyond, [0.5, 0.5, 0.0]);
    /// ```
    pub fn of(z: impl IntoIterator<Item = (f64, f64)>) -> Self {
        let (zx, zy): (Vec<f64>, Vec<f64>) = z
            .into_iter()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .unzip();
        Self {
            pulses: zx.len() as u64,
            ln_radius: ZStats::of(&zx),
            ln_speed: ZStats::of(&zy),
        }
    }

    /// Three lines of text: a header, then `ln R` and `ln u` with the normal's shares beside.
    pub fn text(&self) -> String {
        let pct = |v: f64| format!("{:6.2} %", 100.0 * v);
        let row = |name: &str, s: &ZStats| {
            format!(
                "  {name:<28}{:>8.3}  {}  {}  {}\n",
                s.rms,
                pct(s.beyond[0]),
                pct(s.beyond[1]),
                pct(s.beyond[2])
            )
        };
        let normal = NORMAL_BEYOND;
        format!(
            "stated noise against the truth, z = (located - true) / stated sigma, {} pulses\n  \
             {:<28}{:>8}  {:>8}  {:>8}  {:>8}\n{}{}  {:<28}{:>8.3}  {}  {}  {}\n",
            self.pulses,
            "",
            "rms z",
            "|z|>1",
            "|z|>2",
            "|z|>3",
            row("ln R", &self.ln_radius),
            row("ln u", &self.ln_speed),
            "standard normal",
            1.0,
            pct(normal[0]),
            pct(normal[1]),
            pct(normal[2]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// `n` standard normal draws by Box-Muller.
    fn normals(n: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let u1: f64 = 1.0 - rng.random::<f64>();
                let u2: f64 = rng.random();
                (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
            })
            .collect()
    }

    #[test]
    fn the_normal_s_shares_are_erfc() {
        // erfc(k / sqrt 2) by the series of the normal's tail from its density, to 1e-7.
        let tail = |k: f64| {
            let (mut sum, mut x, step) = (0.0, k, 1e-4);
            while x < 12.0 {
                let mid = x + 0.5 * step;
                sum += (-0.5 * mid * mid).exp() * step;
                x += step;
            }
            2.0 * sum / std::f64::consts::TAU.sqrt()
        };
        for (k, &share) in NORMAL_BEYOND.iter().enumerate() {
            let exact = tail(k as f64 + 1.0);
            assert!((share / exact - 1.0).abs() < 1e-5, "{share} {exact}");
        }
    }

    #[test]
    fn standard_normal_errors_pass_and_doubled_ones_show() {
        let (x, y) = (normals(200_000, 1), normals(200_000, 2));
        let right = StatedNoiseCheck::of(x.iter().copied().zip(y.iter().copied()));
        for s in [right.ln_radius, right.ln_speed] {
            assert!((s.rms - 1.0).abs() < 0.01, "{s:?}");
            for (got, want) in s.beyond.iter().zip(NORMAL_BEYOND) {
                // Binomial standard error of a share over 200 000 draws: at most 0.11 pp.
                assert!((got - want).abs() < 4.0 * (want * (1.0 - want) / 2e5).sqrt());
            }
        }
        // Sigmas stated half what holds: z doubles, 61.7 % beyond 1, 31.7 % beyond 2.
        let wide = StatedNoiseCheck::of(x.iter().zip(&y).map(|(a, b)| (2.0 * a, 2.0 * b)));
        assert!((wide.ln_radius.rms - 2.0).abs() < 0.02);
        assert!((wide.ln_speed.beyond[0] - 0.6171).abs() < 0.005);
        assert!((wide.ln_speed.beyond[1] - NORMAL_BEYOND[0]).abs() < 0.005);
    }
}
