//! The colour of the equalised noise: how a chain's equaliser correlates the ADC's white noise
//! between samples, and the variance that gives a weighted sum of samples.
//!
//! Behind a chain the detector fits samples `y_n = sum_m h_m e_(n-m)` of white noise `e`
//! through the equaliser's impulse response `h`. One sample's variance is `sigma^2 sum h^2`
//! (the noise gain); samples `k` apart are correlated by `rho_k = sum_m h_m h_(m+k) / sum h^2`.
//! A weighted sum `sum_n w_n y_n` then has variance `sigma^2 sum h^2 w^T P w` with `P_ij =
//! rho_|i-j|`, not `sum w^2`: behind an accelerometer's inverse (`rho_1` near +0.6) a
//! pulse's sum varies about three times as much as sixteen independent samples would, behind
//! a MEMS sensor's (`rho_1` near -0.4) about half as much.
//!
//! [`NoiseColour`] keeps what the detector's fits need of `P`: the variance `V(w)` of the sum
//! of `w` consecutive samples (in units of one sample's) at `w = 2, 3, 4, 5` (which give
//! `rho_1..4` exactly, since `V(m+1) - 2 V(m) + V(m-1) = 2 rho_m`) and at `w = 8, 16, 32, 64,
//! 128`, and its slope for long sums, `V(w+1) - V(w) -> (sum h)^2 / sum h^2`. Between the
//! tabled widths `V` is taken as linear. A rigid chain's noise is white: [`NoiseColour::WHITE`]
//! (`V(w) = w`).

/// Widths of the sums whose variance is tabled (samples).
pub const WIDTHS: [u32; 9] = [2, 3, 4, 5, 8, 16, 32, 64, 128];

/// Lags whose correlation the fits through the top's five samples take.
pub const LAGS: usize = 4;

/// The equalised noise's correlation between samples (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoiseColour {
    /// `V(w)` at [`WIDTHS`]: the variance of the sum of `w` consecutive samples over one
    /// sample's (`w` for white noise).
    sum_variance: [f32; 9],
    /// `lim V(w+1) - V(w) = (sum h)^2 / sum h^2`, the slope past the last width (1 for white
    /// noise).
    dc: f32,
    /// `rho_0..4`: `rho_0 = 1`, then `(V(k+1) - 2 V(k) + V(k-1)) / 2`.
    rho: [f32; LAGS + 1],
}

impl NoiseColour {
    /// White noise: samples uncorrelated, `V(w) = w`.
    pub const WHITE: NoiseColour = NoiseColour {
        sum_variance: [2.0, 3.0, 4.0, 5.0, 8.0, 16.0, 32.0, 64.0, 128.0],
        dc: 1.0,
        rho: [1.0, 0.0, 0.0, 0.0, 0.0],
    };

    /// The colour of noise whose one sample has variance `energy` (`sum h^2`), whose sums of
    /// [`WIDTHS`] consecutive samples have variances `sums` (`sum_n (sum_(j<w) h_(n-j))^2`)
    /// and whose impulse response sums to `dc_sum` (`sum h`), all for unit white noise in;
    /// white where `energy` is not positive or any of them is not finite.
    ///
    /// ```
    /// use coalshock::noise_colour::{NoiseColour, WIDTHS};
    /// // y_n = e_n + e_(n-1) / 2: one sample varies by 1.25, a sum of w by 1.25 + 2.25 (w - 1).
    /// let sums = WIDTHS.map(|w| 1.25 + 2.25 * (w as f32 - 1.0));
    /// let ma = NoiseColour::from_sums(1.25, sums, 1.5);
    /// assert!((ma.rho(1) - 0.4).abs() < 1e-6); // 0.5 / 1.25
    /// assert_eq!(NoiseColour::from_sums(0.0, sums, 1.5), NoiseColour::WHITE);
    /// ```
    pub fn from_sums(energy: f32, sums: [f32; 9], dc_sum: f32) -> Self {
        let valid = energy > 0.0 && dc_sum.is_finite() && sums.iter().all(|s| s.is_finite());
        if !valid {
            return Self::WHITE;
        }
        let mut colour = Self {
            sum_variance: sums.map(|s| (s / energy).max(0.0)),
            dc: dc_sum * dc_sum / energy,
            rho: Self::WHITE.rho,
        };
        let v = |w: usize| colour.sum_variance(w as f32);
        let rho = core::array::from_fn(|k| match k {
            0 => 1.0,
            _ => 0.5 * (v(k + 1) - 2.0 * v(k) + v(k - 1)),
        });
        colour.rho = rho;
        colour
    }

    /// `true` for white noise (a rigid chain): the fits' own gains then hold as they are.
    ///
    /// ```
    /// use coalshock::noise_colour::{NoiseColour, WIDTHS};
    /// assert!(NoiseColour::WHITE.is_white());
    /// let white = NoiseColour::from_sums(2.0, WIDTHS.map(|w| 2.0 * w as f32), 2.0_f32.sqrt());
    /// assert!((white.sum_variance(100.0) - 100.0).abs() < 1e-3);
    /// ```
    pub fn is_white(&self) -> bool {
        *self == Self::WHITE
    }

    /// `V(w)`, the variance of the sum of `w` consecutive samples over one sample's: linear
    /// between `V(0) = 0`, `V(1) = 1` and the tabled widths, and past the last one rising by
    /// `dc` per sample.
    ///
    /// ```
    /// use coalshock::noise_colour::{NoiseColour, WIDTHS};
    /// // y_n = e_n + e_(n-1) / 2: one sample varies by 1.25, a sum of w by 1.25 + 2.25 (w - 1).
    /// let sums = WIDTHS.map(|w| 1.25 + 2.25 * (w as f32 - 1.0));
    /// let ma = NoiseColour::from_sums(1.25, sums, 1.5);
    /// // `w + 2 (w - 1) rho_1` for every w, tabled or not, and past the table.
    /// for w in [1.0f32, 2.0, 6.0, 100.0, 300.0] {
    ///     let exact = w + 0.8 * (w - 1.0);
    ///     assert!((ma.sum_variance(w) - exact).abs() < 1e-3 * exact, "{w}");
    /// }
    /// ```
    #[inline(never)]
    pub fn sum_variance(&self, w: f32) -> f32 {
        if w <= 1.0 {
            return w.max(0.0);
        }
        let (mut w0, mut v0) = (1.0f32, 1.0f32);
        for (&wk, &vk) in WIDTHS.iter().zip(&self.sum_variance) {
            let wk = wk as f32;
            if w <= wk {
                return v0 + (vk - v0) * (w - w0) / (wk - w0);
            }
            (w0, v0) = (wk, vk);
        }
        v0 + (w - w0) * self.dc
    }

    /// `rho_k`, the correlation of samples `k` apart, for `k = 1..=4` (0 past them, and
    /// `rho_0 = 1`): `(V(k+1) - 2 V(k) + V(k-1)) / 2`.
    ///
    /// ```
    /// use coalshock::noise_colour::{NoiseColour, WIDTHS};
    /// // y_n = e_n + e_(n-1) / 2: one sample varies by 1.25, a sum of w by 1.25 + 2.25 (w - 1).
    /// let sums = WIDTHS.map(|w| 1.25 + 2.25 * (w as f32 - 1.0));
    /// let ma = NoiseColour::from_sums(1.25, sums, 1.5);
    /// assert_eq!(ma.rho(0), 1.0);
    /// assert!((ma.rho(1) - 0.4).abs() < 1e-6);
    /// assert!(ma.rho(2).abs() < 1e-6 && ma.rho(4).abs() < 1e-6 && ma.rho(5) == 0.0);
    /// ```
    pub fn rho(&self, k: usize) -> f32 {
        self.rho.get(k).copied().unwrap_or(0.0)
    }

    /// The covariance of a sample in the middle of `w` consecutive samples with their sum, over
    /// one sample's variance: `1 + 2 sum_(1 <= k <= h) rho_k = V(h+1) - V(h)` with
    /// `h = (w - 1) / 2`.
    ///
    /// ```
    /// use coalshock::noise_colour::{NoiseColour, WIDTHS};
    /// // y_n = e_n + e_(n-1) / 2: one sample varies by 1.25, a sum of w by 1.25 + 2.25 (w - 1).
    /// let sums = WIDTHS.map(|w| 1.25 + 2.25 * (w as f32 - 1.0));
    /// let ma = NoiseColour::from_sums(1.25, sums, 1.5);
    /// // 1 + 2 rho_1 from three samples on.
    /// assert!((ma.middle_row(9.0) - 1.8).abs() < 1e-5);
    /// assert_eq!(NoiseColour::WHITE.middle_row(9.0), 1.0);
    /// ```
    pub fn middle_row(&self, w: f32) -> f32 {
        let h = (0.5 * (w - 1.0)).max(0.0);
        self.sum_variance(h + 1.0) - self.sum_variance(h)
    }

    /// The variance, over one sample's, of `sum_k top_k y_(k-2) + per_sample sum_n y_n` (the
    /// five samples about a pulse's largest and all `samples` of its sum), and its covariance
    /// with the sum alone: `(top^T P top + per^2 V(n) + 2 per (sum top) r, (sum top) r + per
    /// V(n))` with `r` the [`NoiseColour::middle_row`] of `n` samples (the top taken in the
    /// middle of the pulse). For white noise, `(sum top^2 + per^2 n + 2 per sum top, sum top +
    /// per n)`.
    ///
    /// ```
    /// use coalshock::noise_colour::{NoiseColour, WIDTHS};
    /// // y_n = e_n + e_(n-1) / 2: one sample varies by 1.25, a sum of w by 1.25 + 2.25 (w - 1).
    /// let sums = WIDTHS.map(|w| 1.25 + 2.25 * (w as f32 - 1.0));
    /// let ma = NoiseColour::from_sums(1.25, sums, 1.5);
    /// // y_0 + y_1: 2 + 2 rho_1; its covariance with a sum of 9 about it: 2 (1 + 2 rho_1).
    /// let (var, cov) = ma.weighted(&[0.0, 0.0, 1.0, 1.0, 0.0], 0.0, 9.0);
    /// assert!((var - 2.8).abs() < 1e-5 && (cov - 3.6).abs() < 1e-5);
    /// // White noise: the sum of squares, and the sum.
    /// let (var, cov) = NoiseColour::WHITE.weighted(&[0.5, 0.0, 1.0, 0.0, 0.0], 0.1, 9.0);
    /// assert!((var - (1.25 + 0.09 + 0.3)).abs() < 1e-5 && (cov - 2.4).abs() < 1e-5);
    /// ```
    #[inline(never)]
    pub fn weighted(&self, top: &[f32; 5], per_sample: f32, samples: f32) -> (f32, f32) {
        let mut quadratic = 0.0f32;
        for (i, &a) in top.iter().enumerate() {
            for (j, &b) in top.iter().enumerate() {
                quadratic += a * b * self.rho(i.abs_diff(j));
            }
        }
        let top_sum: f32 = top.iter().sum();
        let r = self.middle_row(samples);
        let v = self.sum_variance(samples);
        (
            quadratic + per_sample * per_sample * v + 2.0 * per_sample * top_sum * r,
            top_sum * r + per_sample * v,
        )
    }
}

/// The sums [`NoiseColour::from_sums`] takes, gathered from the step response `s` of a filter
/// to unit input, one sample at a time ([`ColourSums::push`]): the impulse response is `h_m =
/// s_m - s_(m-1)`, and the sum of `w` consecutive outputs for unit white noise in varies by
/// `sum_m (s_m - s_(m-w))^2`, kept for each of [`WIDTHS`] with the last 128 `s` in a ring.
#[derive(Debug, Clone)]
pub struct ColourSums {
    past: [f32; SPAN],
    sums: [f32; 9],
    pushed: usize,
}

/// The ring's length: the widest of [`WIDTHS`].
const SPAN: usize = 128;

impl Default for ColourSums {
    fn default() -> Self {
        Self::new()
    }
}

impl ColourSums {
    /// No sample yet: the step response before it is 0.
    pub const fn new() -> Self {
        Self {
            past: [0.0; SPAN],
            sums: [0.0; 9],
            pushed: 0,
        }
    }

    /// Takes the next sample `s` of the step response.
    ///
    /// ```
    /// use coalshock::noise_colour::ColourSums;
    /// // h = [1, 1/2]: step response 1, 1.5, 1.5, ...
    /// let mut sums = ColourSums::new();
    /// for s in [1.0, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5] {
    ///     sums.push(s);
    /// }
    /// // y_n = e_n + e_(n-1) / 2: rho_1 = 0.5 / 1.25.
    /// assert!((sums.colour(1.25, 1.5).rho(1) - 0.4).abs() < 1e-6);
    /// ```
    pub fn push(&mut self, s: f32) {
        let m = self.pushed;
        for (sum, &w) in self.sums.iter_mut().zip(&WIDTHS) {
            let before = match m.checked_sub(w as usize) {
                Some(j) => self.past.get(j % SPAN).copied().unwrap_or(0.0),
                None => 0.0,
            };
            *sum += (s - before) * (s - before);
        }
        if let Some(slot) = self.past.get_mut(m % SPAN) {
            *slot = s;
        }
        self.pushed = m.wrapping_add(1);
    }

    /// The colour of the pushed response, whose impulse response's squares sum to `energy` and
    /// which ended at `last = sum h` ([`NoiseColour::from_sums`]).
    pub fn colour(&self, energy: f32, last: f32) -> NoiseColour {
        NoiseColour::from_sums(energy, self.sums, last)
    }
}
