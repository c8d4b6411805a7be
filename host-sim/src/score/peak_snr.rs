//! The kernel's verdicts and feature errors by the impact's peak over the noise: each impact's
//! simulated peak force `F_max` (N) over the noise RMS of the force the detector sees,
//! `noise_force_n = noise_rms_counts * equaliser noise gain * effective_mass_kg /
//! counts_per_m_s2` (N), binned at [`EDGES`].
//!
//! Per bin: the impacts, the share the kernel detected (any report paired with the impact),
//! its `Class` verdicts and the share of those that are wrong, and the mean error of its
//! measured `(ln F_max, ln t_c)` against the closed-form Hertz features of the drawn size and
//! speed, and the root mean square of its error in its true class's `(ln R, ln u)` over the
//! sigmas the classifier weighed it on (`z`, [`crate::score::noise_check`]: 1 where the stated
//! noise holds). A pulse a few noise RMS above the detector's trigger (`trigger_sigmas`, 6 by
//! default) is found only when the noise lifts it, so its measured peak is biased up; the
//! table shows at what peak over noise the features, and the confident verdicts, hold.

use serde::Serialize;

/// Bin edges of `F_max / noise_force_n`; the last bin is open above.
pub const EDGES: [f64; 8] = [0.0, 6.0, 8.0, 10.0, 12.0, 16.0, 24.0, 48.0];

/// One impact as the table counts it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakRow {
    /// `F_max / noise_force_n` of the simulated pulse (dimensionless).
    pub peak_over_noise: f64,
    /// Whether a kernel report was paired with the impact.
    pub detected: bool,
    /// `Some(right)` for a `Class` verdict, `None` otherwise.
    pub confident: Option<bool>,
    /// Measured minus closed-form Hertz `(ln F_max, ln t_c)`, when the kernel measured it.
    pub error_ln: Option<(f64, f64)>,
    /// The measurement's `(z_x, z_y)` in its true class's `(ln R, ln u)`, when located.
    pub z: Option<(f64, f64)>,
}

/// One bin of [`PeakSnrTable`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct PeakSnrBin {
    /// Lower edge of `F_max / noise_force_n`.
    pub from: f64,
    /// Upper edge (`None`: open above).
    pub to: Option<f64>,
    /// Impacts in the bin.
    pub impacts: u64,
    /// Share of them the kernel detected.
    pub detected_share: f64,
    /// `Class` verdicts among them.
    pub confident: u64,
    /// Share of those verdicts that are wrong (0 without any).
    pub confident_wrong_share: f64,
    /// Mean measured minus Hertz `ln F_max` over the measured pulses (0 without any).
    pub bias_ln_force: f64,
    /// Mean measured minus Hertz `ln t_c` over the measured pulses (0 without any).
    pub bias_ln_duration: f64,
    /// Root mean square of `z` in `ln R` over the located pulses (0 without any).
    pub rms_z_ln_radius: f64,
    /// Root mean square of `z` in `ln u` over the located pulses (0 without any).
    pub rms_z_ln_speed: f64,
}

/// The table of [`PeakSnrBin`]s (see the module docs).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct PeakSnrTable {
    /// Noise RMS of the force the detector sees, in N.
    pub noise_force_n: f64,
    /// The bins that hold at least one impact, in order.
    pub bins: Vec<PeakSnrBin>,
}

/// What one bin of [`PeakSnrTable::of`] sums over its impacts.
#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    impacts: u64,
    confident: u64,
    detected: u64,
    wrong: u64,
    measured: u64,
    error_ln: (f64, f64),
    located: u64,
    z2: (f64, f64),
}

impl Sums {
    /// Adds impact `r`.
    fn add(&mut self, r: PeakRow) {
        self.impacts += 1;
        self.detected += u64::from(r.detected);
        if let Some(right) = r.confident {
            self.confident += 1;
            self.wrong += u64::from(!right);
        }
        if let Some((f, t)) = r.error_ln.filter(|(f, t)| f.is_finite() && t.is_finite()) {
            self.measured += 1;
            self.error_ln = (self.error_ln.0 + f, self.error_ln.1 + t);
        }
        if let Some((x, y)) = r.z.filter(|(x, y)| x.is_finite() && y.is_finite()) {
            self.located += 1;
            self.z2 = (self.z2.0 + x * x, self.z2.1 + y * y);
        }
    }

    /// The bin of edges `from` and `to` (`None`: open above) from these sums: its counts,
    /// shares, means and root mean squares.
    fn bin(self, from: f64, to: Option<f64>) -> PeakSnrBin {
        let ratio = |a: f64, b: u64| if b == 0 { 0.0 } else { a / b as f64 };
        PeakSnrBin {
            from,
            to,
            impacts: self.impacts,
            detected_share: ratio(self.detected as f64, self.impacts),
            confident: self.confident,
            confident_wrong_share: ratio(self.wrong as f64, self.confident),
            bias_ln_force: ratio(self.error_ln.0, self.measured),
            bias_ln_duration: ratio(self.error_ln.1, self.measured),
            rms_z_ln_radius: ratio(self.z2.0, self.located).sqrt(),
            rms_z_ln_speed: ratio(self.z2.1, self.located).sqrt(),
        }
    }
}

impl PeakSnrTable {
    /// The table over `rows`, for a force noise of `noise_force_n` N.
    ///
    /// ```
    /// use host_sim::score::peak_snr::{PeakRow, PeakSnrTable};
    /// let row = |snr, confident, e| PeakRow {
    ///     peak_over_noise: snr, detected: true, confident, error_ln: Some((e, -e)),
    ///     z: Some((3.0 * e, 4.0 * e)),
    /// };
    /// let t = PeakSnrTable::of(10.0, [row(7.0, Some(false), 0.2), row(7.5, None, 0.0),
    ///                                 row(30.0, Some(true), 0.01)]);
    /// assert_eq!(t.bins.len(), 2);
    /// assert_eq!((t.bins[0].from, t.bins[0].to), (6.0, Some(8.0)));
    /// assert_eq!((t.bins[0].impacts, t.bins[0].confident), (2, 1));
    /// assert_eq!(t.bins[0].confident_wrong_share, 1.0);
    /// assert!((t.bins[0].bias_ln_force - 0.1).abs() < 1e-12);
    /// // z in ln R: 0.6 and 0, root mean square 0.6 / sqrt(2).
    /// assert!((t.bins[0].rms_z_ln_radius - 0.6 / 2f64.sqrt()).abs() < 1e-12);
    /// assert!((t.bins[0].rms_z_ln_speed - 0.8 / 2f64.sqrt()).abs() < 1e-12);
    /// assert_eq!(t.bins[1].to, Some(48.0));
    /// ```
    pub fn of(noise_force_n: f64, rows: impl IntoIterator<Item = PeakRow>) -> Self {
        let mut sums = [Sums::default(); EDGES.len()];
        for r in rows {
            if !r.peak_over_noise.is_finite() {
                continue;
            }
            let i = EDGES.partition_point(|&e| e <= r.peak_over_noise).max(1) - 1;
            sums[i].add(r);
        }
        let bins = sums
            .iter()
            .enumerate()
            .filter(|(_, s)| s.impacts > 0)
            .map(|(i, s)| s.bin(EDGES[i], EDGES.get(i + 1).copied()))
            .collect();
        Self {
            noise_force_n,
            bins,
        }
    }

    /// The table as text: one line per bin.
    pub fn text(&self) -> String {
        use std::fmt::Write;
        let mut s = format!(
            "\nby peak over noise (F_max over the detector's force noise, {:.4} N RMS)\n",
            self.noise_force_n
        );
        let _ = writeln!(
            s,
            "  {:<14}{:>9}{:>10}{:>11}{:>9}{:>11}{:>13}{:>20}",
            "F_max / noise",
            "impacts",
            "detected",
            "confident",
            "wrong",
            "bias ln F",
            "bias ln t_c",
            "rms z ln R / ln u"
        );
        for b in &self.bins {
            let range = match b.to {
                Some(to) => format!("[{}, {})", b.from, to),
                None => format!("[{}, inf)", b.from),
            };
            let _ = writeln!(
                s,
                "  {range:<14}{:>9}{:>9.2}%{:>11}{:>8.2}%{:>+11.4}{:>+13.4}{:>13.2} / {:.2}",
                b.impacts,
                100.0 * b.detected_share,
                b.confident,
                100.0 * b.confident_wrong_share,
                b.bias_ln_force,
                b.bias_ln_duration,
                b.rms_z_ln_radius,
                b.rms_z_ln_speed
            );
        }
        s
    }
}
