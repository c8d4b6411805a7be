//! A short pulse of a damped contact measured by the contact's own shape: the table
//! ([`PulseShape`]) fitted to the five samples about the pulse's largest, where a fit through
//! the top's samples needs a sampling correction whose place in its table the measured
//! duration does not pin (`docs/few_samples.md`).
//!
//! The model of sample `k` (samples from the largest) is `F_peak g(r (k - k_peak) + u_peak)`
//! with `g` the table, `u_peak` where it peaks and `r` the inverse of the contact time in
//! samples; each sample is weighted by its noise, the sensor's with the table's error times
//! `F_peak`. Its peak and duration are the continuous pulse's, as the flank fit of a clipped
//! pulse gives them ([`crate::pulse_shape::shape_flank_fit`]).

use crate::pulse_shape::{PulseShape, in_end_interval};
use crate::shape_fit::{
    C_AREA, FIVE_POINT_STEP, FlankFit, PEAK_OMEGA, amplitude_fit, descend, flank_gains,
    gauss_newton_of,
};

/// Samples per pulse (the duration a fit through the top measures, `t_c` from the area) below
/// which the detector measures a damped pulse on a rigid chain by [`short_shape_fit`]:
/// `PEAK_OMEGA / FIVE_POINT_STEP = 7.8`, below which that fit reads only the three samples at
/// the top (and the sum), and needs the sampling correction.
pub const SHORT_SAMPLES: f32 = PEAK_OMEGA / FIVE_POINT_STEP;

/// The samples' places, from the pulse's largest (samples).
const KS: [f32; 5] = [-2.0, -1.0, 0.0, 1.0, 2.0];

/// Inverse durations the start scans, evenly over `r0 / 2..=2 r0` (`r0` from the measured
/// duration).
const SCAN: usize = 16;

/// Peak places the start scans per inverse duration, evenly over `-1..=1` samples.
const PLACES: usize = 9;

/// How far the descent may take `r` from `r0` (a factor either way), and the peak from the
/// largest sample (samples).
const R_SPAN: f32 = 4.0;
const AT_SPAN: f32 = 1.5;

/// Descents, each from the best start of its band of inverse durations.
const STARTS: usize = 4;

/// The force, in sigmas of its sample, at which a sample sees the pulse: below it, at a
/// contact's end, the fit sits on the kink between no force and the flank, and the sample's
/// slope there would claim a start or end that it does not pin.
const SEEN: f32 = 4.0;

/// The weighted residual sum of squares the fit may leave over its five samples (two degrees
/// of freedom: exceeded with probability 3e-4 by noise alone).
const RSS_MAX: f32 = 16.0;

/// The peak and duration of a short pulse from its five samples `ys` about its largest
/// (counts over the baseline, the largest in the middle), the sensor's noise RMS (counts), the
/// contact's table and the duration a fit through the top measured (samples, from the area):
/// the weighted least-squares fit of the model in the module's docs, the least residual of
/// four descents by Gauss-Newton steps, each from the best start of a scan in its band
/// of durations (more fits hold than from the best start alone). Its sigmas come from the
/// normal equations of the samples that see the pulse (a force of `SEEN` of their sigmas or
/// more), their gains over a noise variance of 1 ([`FlankFit::gains`]: the rows are
/// weighted). The samples beyond the five
/// are not read (a damped contact's long tail may reach them, with little force). `None`
/// (the caller keeps its own measurement) without a table, for a fit held at the bounds its
/// steps keep it in (`r` within `r0 / 4..4 r0`, `r0` from the measured duration; the peak
/// within 1.5 samples of the largest), a weighted residual above `RSS_MAX`, fewer than three
/// samples that see the pulse, or singular equations.
///
/// ```
/// use coalshock::pulse_shape::PulseShape;
/// use coalshock::short_pulse::short_shape_fit;
/// use coalshock::shape_fit::C_AREA;
/// // The Hertz pulse at 3 samples per contact, its peak 0.3 samples after the largest sample.
/// let s = PulseShape::hertz();
/// let (peak, r, at) = (1000.0, 1.0 / 3.0, 0.3);
/// let ys = [-2.0f32, -1.0, 0.0, 1.0, 2.0].map(|k| peak * s.at(r * (k - at) + 0.5).0);
/// let fit = short_shape_fit(&ys, 1.0, &s, 3.0).unwrap();
/// assert!((fit.peak / peak - 1.0).abs() < 1e-3);
/// assert!((fit.duration / (s.area / (C_AREA * r)) - 1.0).abs() < 1e-3);
/// assert!(fit.gains[0] > 0.0 && fit.gains[1] > 0.0);
/// ```
#[inline(never)]
pub fn short_shape_fit(
    ys: &[f32; 5],
    noise: f32,
    shape: &PulseShape,
    duration: f32,
) -> Option<FlankFit> {
    let r0 = shape.area / (C_AREA * duration);
    if !(shape.is_some() && noise.is_finite() && noise > 0.0 && r0.is_finite() && r0 > 0.0) {
        return None;
    }
    let fit = Short { ys, noise, shape };
    // The descent from the best start of each band of durations: the contact's end may
    // cross a sample, whose kink can hold a descent short of the least residual.
    let found = fit.scan(r0).map(|start| fit.descend(start?, r0));
    let (p, rss, rows) = found
        .into_iter()
        .flatten()
        .reduce(|a, b| if b.1 < a.1 { b } else { a })?;
    fit.accepted(p, rss, &rows, r0)
}

/// What [`short_shape_fit`] fits.
struct Short<'a> {
    ys: &'a [f32; 5],
    noise: f32,
    shape: &'a PulseShape,
}

impl Short<'_> {
    /// The table about its peak, `x = r (k - k_peak)`: `(g, dg/dx)`.
    fn g(&self) -> impl Fn(f32) -> (f32, f32) + '_ {
        |x| self.shape.at(x + self.shape.peak_at)
    }

    /// The model at sample `k` and its gradient in `p = [F_peak, k_peak, r]` (counts), and
    /// the table's error there over `F_peak`: `PulseShape::error` within the reach (the
    /// larger in an end interval), the force at the reach's edge beyond it (the table does
    /// not bound its error there), 0 outside the contact.
    fn model(&self, [peak, at, r]: [f32; 3], k: f32) -> (f32, [f32; 3], f32) {
        let t = k - at;
        let (g, slope) = (self.g())(r * t);
        let u = r * t + self.shape.peak_at;
        let [lo, hi] = self.shape.reach;
        let [inner, ends] = self.shape.error;
        let error = match u {
            u if u <= 0.0 || u >= 1.0 => 0.0,
            u if u < lo => self.shape.at(lo).0,
            u if u > hi => self.shape.at(hi).0,
            u if in_end_interval(u) => ends,
            _ => inner,
        };
        (peak * g, [g, -peak * r * slope, peak * t * slope], error)
    }

    /// The five weighted rows at `p`, `[dm/dp, y - m] / sigma` with `sigma^2 = noise^2 +
    /// (error F_peak)^2`, and their residual sum of squares.
    fn rows(&self, p: [f32; 3]) -> (f32, [[f32; 4]; 5]) {
        let (mut rss, mut rows) = (0.0, [[0.0; 4]; 5]);
        for ((row, &k), &y) in rows.iter_mut().zip(&KS).zip(self.ys) {
            let (m, [g0, g1, g2], error) = self.model(p, k);
            let e = error * p[0];
            let w = 1.0 / libm::sqrtf(self.noise * self.noise + e * e);
            let res = w * (y - m);
            rss += res * res;
            *row = [w * g0, w * g1, w * g2, res];
        }
        (rss, rows)
    }

    /// The descent ([`descend`]) from `start` over the five weighted rows ([`Self::rows`]),
    /// kept within `r0 / R_SPAN..R_SPAN r0` and [`AT_SPAN`] samples of the largest, `F_peak`
    /// above half its value: the point reached, its residual and its rows.
    fn descend(&self, start: [f32; 3], r0: f32) -> Option<([f32; 3], f32, [[f32; 4]; 5])> {
        let keep = |[peak, at, r]: [f32; 3], floor: f32| {
            [
                peak.max(floor),
                at.clamp(-AT_SPAN, AT_SPAN),
                r.clamp(r0 / R_SPAN, R_SPAN * r0),
            ]
        };
        let residual = |p| Some(self.rows(p));
        descend((&[], &[]), start, self.g(), residual, keep)
    }

    /// The starts, one per band of [`SCAN`] / [`STARTS`] inverse durations: of [`SCAN`]
    /// inverse durations over `r0 / 2..=2 r0` and [`PLACES`] peak places over `-1..=1`, with
    /// `F_peak = sum y g / sum g^2`, the one of least residual in its band.
    fn scan(&self, r0: f32) -> [Option<[f32; 3]>; STARTS] {
        let mut best: [Option<([f32; 3], f32)>; STARTS] = [None; STARTS];
        for j in 0..SCAN * PLACES {
            let (jr, jp) = (j / PLACES, (j % PLACES) as f32);
            let r = r0 * libm::exp2f(2.0 * jr as f32 / (SCAN - 1) as f32 - 1.0);
            let at = 2.0 * jp / (PLACES - 1) as f32 - 1.0;
            let gs = KS.map(|k| (self.g())(r * (k - at)).0);
            let (Some(band), Some((peak, rss))) = (
                best.get_mut(jr * STARTS / SCAN),
                amplitude_fit(&gs, self.ys),
            ) else {
                continue;
            };
            if peak > 0.0 && band.is_none_or(|(_, b)| rss < b) {
                *band = Some(([peak, at, r], rss));
            }
        }
        best.map(|b| b.map(|(p, _)| p))
    }

    /// The fit at `p` with residual `rss` and weighted `rows` ([`Self::rows`]) when it holds
    /// (see [`short_shape_fit`]).
    fn accepted(&self, p: [f32; 3], rss: f32, rows: &[[f32; 4]; 5], r0: f32) -> Option<FlankFit> {
        let [peak, at, r] = p;
        // Not held at the bounds the descent keeps it in.
        let free =
            r > 1.0004 * r0 / R_SPAN && r < 0.99975 * R_SPAN * r0 && at.abs() < AT_SPAN - 0.001;
        if !(free && rss <= RSS_MAX) {
            return None;
        }
        // The rows that see the pulse: the model's force four sigma or more.
        let mut felt = [[0.0f32; 4]; 5];
        let mut seen = 0;
        for (row, out) in rows.iter().zip(felt.iter_mut()) {
            let [g0, ..] = *row;
            // `g0 = g / sigma`: the force over the sigma is `F_peak g0`.
            if peak * g0 >= SEEN {
                *out = *row;
                seen += 1;
            }
        }
        if seen < 3 {
            return None;
        }
        let (_, inv, _) = gauss_newton_of(&[], &[], p, self.g(), &felt)?;
        Some(FlankFit {
            peak,
            peak_at: at,
            duration: self.shape.area / (C_AREA * r),
            gains: flank_gains(&inv, peak, r),
        })
    }
}
