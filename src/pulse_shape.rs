//! A contact's own pulse shape `g(u) = F(u t_c) / F_peak` over its contact (`u` from 0 at
//! first touch to 1 where the force first returns to 0), tabulated for a law whose pulse is
//! self-similar, and the fit of a pulse clipped at the ADC's full scale to its unclipped
//! flanks with it ([`shape_flank_fit`]).
//!
//! The undamped Hertz pulse's table is made here ([`PulseShape::hertz`]). For the
//! restitution-parametrised laws (Hunt-Crossley, Lankarani-Nikravesh, Flores, Gonthier,
//! Tsuji) the force over the Hertz scales, `F / F_max` against `t / t_c`, depends on the
//! restitution alone, so one table, which the host takes from its integrator, holds for every
//! impact of a scene; Adams IMPACT with a fixed `c_max` is not self-similar and carries none.

use crate::error::Error;
use crate::hertz::CONTACT_TIME_FACTOR;
use crate::shape_fit::{C_AREA, FlankFit, Flanks, Matrix3, flank_gains, gauss_newton_of};

/// Points of a [`PulseShape`] over `u = 0..=1`, `u_j = j / (SHAPE_POINTS - 1)`.
pub const SHAPE_POINTS: usize = 65;

/// Runge-Kutta steps of [`PulseShape::hertz`] over the contact: 16 per point.
pub const HERTZ_STEPS: usize = 16 * (SHAPE_POINTS - 1);

/// Spacing of a [`PulseShape`]'s points in `u`: `1 / (SHAPE_POINTS - 1)`.
pub const SHAPE_STEP: f32 = 1.0 / (SHAPE_POINTS - 1) as f32;

/// The contact's pulse over its duration, `g(u) = F / F_peak` and `dg/du` at the points
/// `u_j = j SHAPE_STEP`, read between them by cubic Hermite interpolation ([`PulseShape::at`]).
/// The flank fit reads it only within its `reach`, which leaves out the first or the last
/// interval where the law's force starts or ends with an unbounded slope (Tsuji's rises like
/// `u^(1/4)`), and outside the contact, where the force is 0. All zero
/// ([`PulseShape::NONE`]): no table, and a damped pulse that clips is `Saturated`.
/// `size_of` 544 B (65 points).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PulseShape {
    /// `g(u_j) = F / F_peak` (dimensionless; largest 1).
    pub values: [f32; SHAPE_POINTS],
    /// `dg/du` at `u_j` (per contact time).
    pub slopes: [f32; SHAPE_POINTS],
    /// The pulse's area over `F_peak t_c`, `integral_0^1 g du` (dimensionless; the Hertz
    /// pulse's is [`crate::shape_fit::C_AREA`]).
    pub area: f32,
    /// Where the pulse peaks, `u` at `g = 1` (dimensionless; 0.5 for the Hertz pulse, less
    /// for a damped one, which rises faster than it falls).
    pub peak_at: f32,
    /// The range of `u` over which the table holds to [`SHAPE_ERROR`] (the whole contact,
    /// `[0, 1]`, or less its first or last interval): a flank sample inside the contact but
    /// outside it is not read.
    pub reach: [f32; 2],
    /// The table's own error per sample as a share of `F_peak`, `[between the end
    /// intervals, in an end interval within the reach]` (each at most [`SHAPE_ERROR`]): the
    /// flank fit counts the largest at its four samples as noise beside the sensor's.
    pub error: [f32; 2],
}

impl PulseShape {
    /// No table.
    pub const NONE: PulseShape = PulseShape {
        values: [0.0; SHAPE_POINTS],
        slopes: [0.0; SHAPE_POINTS],
        area: 0.0,
        peak_at: 0.0,
        reach: [0.0; 2],
        error: [0.0; 2],
    };

    /// The undamped Hertz pulse's table, from its equation of motion in the units
    /// `delta_max` and `delta_max / u`: `z'' = -(5/4) z^(3/2)`, `z(0) = 0`, `z'(0) = 1`, over
    /// the contact time `2.9432752` ([`CONTACT_TIME_FACTOR`]), by classical Runge-Kutta with
    /// [`HERTZ_STEPS`] steps in libm's correctly rounded `sqrtf` whatever the backend (the
    /// table is made once per detector, and its error is stated); `g = z^(3/2)` and `dg/du = (3/2) z^(1/2) z' t_c`. Its area is
    /// [`C_AREA`], its peak at `u = 1/2`, its reach the whole contact (the force starts and
    /// ends like `u^(3/2)`), its error [`HERTZ_TABLE_ERROR`]. The detector measures a clipped Hertz pulse with it where the
    /// series about the top ([`crate::shape_fit::flank_fit`]) does not reach the flanks.
    ///
    /// ```
    /// use coalshock::pulse_shape::PulseShape;
    /// let h = PulseShape::hertz();
    /// assert!(h.check().is_ok());
    /// assert_eq!(core::mem::size_of::<PulseShape>(), 544);
    /// // Near its top the pulse is 1 - (3/4) x^2 with x = 3.290681 (u - 1/2).
    /// let x = 3.290_681f32 * 0.05;
    /// assert!((h.at(0.55).0 - (1.0 - 0.75 * x * x + 0.1875 * x.powi(4))).abs() < 1e-5);
    /// ```
    pub fn hertz() -> PulseShape {
        let mut shape = PulseShape {
            area: C_AREA,
            peak_at: 0.5,
            reach: [0.0, 1.0],
            error: HERTZ_TABLE_ERROR,
            ..PulseShape::NONE
        };
        let h = CONTACT_TIME_FACTOR / HERTZ_STEPS as f32;
        let accel = |z: f32| -1.25 * z.max(0.0) * libm::sqrtf(z.max(0.0));
        let (mut z, mut v) = (0.0f32, 1.0f32);
        let per_point = HERTZ_STEPS / (SHAPE_POINTS - 1);
        for step in 0..=HERTZ_STEPS {
            if step % per_point == 0 {
                let j = step / per_point;
                let root = libm::sqrtf(z.max(0.0));
                if let (Some(g), Some(slope)) = (shape.values.get_mut(j), shape.slopes.get_mut(j)) {
                    *g = z.max(0.0) * root;
                    *slope = 1.5 * root * v * CONTACT_TIME_FACTOR;
                }
            }
            let (k1z, k1v) = (v, accel(z));
            let (k2z, k2v) = (v + 0.5 * h * k1v, accel(z + 0.5 * h * k1z));
            let (k3z, k3v) = (v + 0.5 * h * k2v, accel(z + 0.5 * h * k2z));
            let (k4z, k4v) = (v + h * k3v, accel(z + h * k3z));
            z += h / 6.0 * (k1z + 2.0 * k2z + 2.0 * k3z + k4z);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        shape
    }

    /// Whether the shape is tabulated (not [`PulseShape::NONE`]).
    ///
    /// ```
    /// use coalshock::pulse_shape::PulseShape;
    /// assert!(!PulseShape::NONE.is_some());
    /// ```
    #[inline]
    pub fn is_some(&self) -> bool {
        self.area > 0.0
    }

    /// `(g, dg/du)` at `u` by cubic Hermite interpolation between the two nearest points
    /// (value and slope at each); `(0, 0)` outside `0..=1` or for a non-finite `u`.
    ///
    /// ```
    /// use coalshock::pulse_shape::{PulseShape, SHAPE_POINTS, SHAPE_STEP};
    /// // g = 4 u (1 - u): the Hermite cubic is exact for it.
    /// let mut s = PulseShape::NONE;
    /// for j in 0..SHAPE_POINTS {
    ///     let u = j as f32 * SHAPE_STEP;
    ///     s.values[j] = 4.0 * u * (1.0 - u);
    ///     s.slopes[j] = 4.0 - 8.0 * u;
    /// }
    /// let (g, slope) = s.at(0.3);
    /// assert!((g - 0.84).abs() < 1e-6 && (slope - 1.6).abs() < 1e-5);
    /// assert_eq!(s.at(1.5), (0.0, 0.0));
    /// ```
    pub fn at(&self, u: f32) -> (f32, f32) {
        if !(0.0..=1.0).contains(&u) {
            return (0.0, 0.0);
        }
        let x = u / SHAPE_STEP;
        let i = (x as usize).min(SHAPE_POINTS - 2);
        let t = x - i as f32;
        let get = |v: &[f32; SHAPE_POINTS], k: usize| v.get(k).copied().unwrap_or(0.0);
        let (y0, y1) = (get(&self.values, i), get(&self.values, i + 1));
        let (m0, m1) = (
            get(&self.slopes, i) * SHAPE_STEP,
            get(&self.slopes, i + 1) * SHAPE_STEP,
        );
        // The Hermite basis in t: h00 = 2t^3 - 3t^2 + 1, h10 = t^3 - 2t^2 + t,
        // h01 = -2t^3 + 3t^2, h11 = t^3 - t^2, and their derivatives.
        let (t2, t3) = (t * t, t * t * t);
        let g = (2.0 * t3 - 3.0 * t2 + 1.0) * y0
            + (t3 - 2.0 * t2 + t) * m0
            + (3.0 * t2 - 2.0 * t3) * y1
            + (t3 - t2) * m1;
        let dg_dt = (6.0 * t2 - 6.0 * t) * (y0 - y1)
            + (3.0 * t2 - 4.0 * t + 1.0) * m0
            + (3.0 * t2 - 2.0 * t) * m1;
        (g, dg_dt / SHAPE_STEP)
    }

    /// `Err` unless the table is [`PulseShape::NONE`] or a pulse: every value finite within
    /// `-1..=1.001`, every slope finite within `|dg/du| <= 1e3`, the area within `0..=1`, the
    /// peak inside the contact (`0 < peak_at < 1`), the reach around it and each error within
    /// `0..=SHAPE_ERROR`.
    ///
    /// ```
    /// use coalshock::pulse_shape::PulseShape;
    /// assert!(PulseShape::NONE.check().is_ok());
    /// let bad = PulseShape {
    ///     area: 2.0,
    ///     peak_at: 0.5,
    ///     reach: [0.0, 1.0],
    ///     error: [1e-4, 1e-4],
    ///     ..PulseShape::NONE
    /// };
    /// assert!(bad.check().is_err());
    /// ```
    pub fn check(&self) -> Result<(), Error> {
        if *self == Self::NONE {
            return Ok(());
        }
        let values = self
            .values
            .iter()
            .all(|v| v.is_finite() && (-1.0..=1.001).contains(v));
        let slopes = self.slopes.iter().all(|v| v.is_finite() && v.abs() <= 1e3);
        let area = self.area > 0.0 && self.area <= 1.0;
        let peak = self.peak_at > 0.0 && self.peak_at < 1.0;
        let [lo, hi] = self.reach;
        let reach = 0.0 <= lo && lo < self.peak_at && self.peak_at < hi && hi <= 1.0;
        let error = self.error.iter().all(|e| (0.0..=SHAPE_ERROR).contains(e));
        if values && slopes && area && peak && reach && error {
            Ok(())
        } else {
            Err(Error::OutOfRange("contact.pulse_shape"))
        }
    }
}

/// The largest error per sample, as a share of `F_peak`, of a table the kernel takes
/// ([`PulseShape::error`]): the Hermite interpolation between the [`SHAPE_POINTS`] points and
/// the law's own spread from one impact to the next (host-sim measures both against its
/// integrator for each scene, and carries no table beyond it).
pub const SHAPE_ERROR: f32 = 1e-3;

/// [`PulseShape::hertz`]'s error, `[between the end intervals, in them]`: twice what
/// host-sim's integrator measures, 5.9e-6 and 4.4e-4 (`cargo test -p host-sim --test
/// pulse_shape`), to a floor of 1e-5.
pub const HERTZ_TABLE_ERROR: [f32; 2] = [1.2e-5, 9e-4];

/// Durations the flank fit tries before its Gauss-Newton steps (evenly in `1 / t_c`).
const SCAN: usize = 16;

/// Positions of the peak across the clipped run the flank fit tries with each duration.
const PLACES: usize = 8;

/// Gauss-Newton steps of the flank fit, at most.
const STEPS: usize = 32;

/// Halvings of a Gauss-Newton step that does not lower the residual, at most.
const HALVINGS: usize = 6;

/// Peak and duration of a damped pulse whose top is clipped, from its unclipped flanks
/// ([`Flanks`]: the two samples either side of the `run` clipped ones, the clipping `level`
/// and the sum of all samples) and the contact's own shape. The least-squares fit of `F_peak g(r (k - k_peak) + u_peak)` to the
/// four (`u_peak` the table's `peak_at`), in `F_peak`, the peak's time `k_peak` and the inverse
/// duration `r = 1 / t_c` (per sample; about the peak, a change of `r` leaves it in place):
/// the best of `SCAN` durations between the four samples' span, `run + 3`, and twice the
/// sum over `level x area`, each with its peak at `PLACES` places across the run and its
/// least-squares `F_peak` (`scan_start`), then up to `STEPS` Gauss-Newton steps, each
/// halved until it lowers the residual (`F_peak` kept above half its value, the peak within
/// the run, `r` within the scan's range). The duration it reports is the detector's,
/// `area t_c / C_AREA` (the area over `C_AREA F_peak`). `None` when the fit does not describe
/// a clipped pulse of this shape: a flank sample inside the contact but outside the table's
/// `reach`, `r` at the end of its range, the fitted pulse below the level (less
/// four `noise` RMS) at the run's ends, or the four samples' residual above `8 x` their noise
/// RMS (the sensor's `noise` with the table's error at them). With the fit, that error per
/// sample (counts: [`PulseShape::error`] times `F_peak`), which the fit's sigmas take beside
/// the noise.
///
/// ```
/// use coalshock::pulse_shape::{PulseShape, SHAPE_POINTS, SHAPE_STEP, shape_flank_fit};
/// use coalshock::shape_fit::Flanks;
/// // A skewed pulse, g = (27/4) u (1 - u)^2 (peak 1 at u = 1/3, area 9/16), 40 samples long
/// // from k_0 = -9.3, with a peak of 2 400 counts clipped at 2 000.
/// let mut s = PulseShape {
///     area: 9.0 / 16.0,
///     peak_at: 1.0 / 3.0,
///     reach: [0.0, 1.0],
///     error: [1e-6, 1e-6],
///     ..PulseShape::NONE
/// };
/// for j in 0..SHAPE_POINTS {
///     let u = j as f32 * SHAPE_STEP;
///     s.values[j] = 6.75 * u * (1.0 - u) * (1.0 - u);
///     s.slopes[j] = 6.75 * (1.0 - u) * (1.0 - 3.0 * u);
/// }
/// let y = |k: f32| 2400.0 * s.at((k + 9.3) / 40.0).0;
/// let clipped: Vec<f32> = (-12..32).map(|k| y(k as f32).min(2000.0)).collect();
/// let run = clipped.iter().filter(|&&v| v >= 2000.0).count() as f32;
/// let first = (-12..32).find(|&k| y(k as f32) >= 2000.0).unwrap() as f32;
/// let at = |k: f32| y(first + k);
/// let flanks = Flanks {
///     before: [at(-2.0), at(-1.0)],
///     run,
///     after: [at(run), at(run + 1.0)],
///     level: 2000.0,
///     sum: clipped.iter().sum(),
/// };
/// let (fit, _) = shape_flank_fit(&flanks, 1.0, &s).unwrap();
/// assert!((fit.peak / 2400.0 - 1.0).abs() < 1e-3);
/// assert!((fit.duration / (40.0 * 9.0 / 16.0 / coalshock::shape_fit::C_AREA) - 1.0).abs() < 1e-3);
/// ```
#[inline(never)]
pub fn shape_flank_fit(flanks: &Flanks, noise: f32, shape: &PulseShape) -> Option<(FlankFit, f32)> {
    let (ks, ys) = flanks.samples()?;
    if !(shape.is_some() && noise.is_finite()) {
        return None;
    }
    let Flanks {
        run, level, sum, ..
    } = *flanks;
    let (r_lo, r_hi) = (shape.area * level / (2.0 * sum), 1.0 / (run + 3.0));
    if r_lo.is_nan() || r_lo >= r_hi {
        return None;
    }
    // The pulse about its peak, `x = r (k - k_peak)`.
    let g = |x: f32| shape.at(x + shape.peak_at);
    let rss = |p: [f32; 3]| {
        ks.iter().zip(&ys).fold(0.0f32, |a, (&k, &y)| {
            let e = y - p[0] * g(p[2] * (k - p[1])).0;
            a + e * e
        })
    };
    let keep = |[peak, at, r]: [f32; 3], floor: f32| {
        [
            peak.max(floor),
            at.max(-0.5).min(run - 0.5),
            r.max(r_lo).min(r_hi),
        ]
    };
    let mut p = scan_start(&ks, &ys, run, (r_lo, r_hi), shape)?;
    let mut inv: Matrix3 = [[0.0; 3]; 3];
    let mut best = rss(p);
    for _ in 0..STEPS {
        let (next, next_inv, _) = gauss_newton_of(&ks, &ys, p, g)?;
        inv = next_inv;
        // The Gauss-Newton step, halved until it lowers the residual (the steep rise of a
        // damped pulse can throw a full step off the pulse); none that does: converged.
        let mut scale = 1.0;
        let mut moved = false;
        for _ in 0..HALVINGS {
            let [a, b, c] = p;
            let [na, nb, nc] = next;
            let step = [
                a + scale * (na - a),
                b + scale * (nb - b),
                c + scale * (nc - c),
            ];
            let q = keep(step, 0.5 * a);
            let e = rss(q);
            if e < best {
                (p, best, moved) = (q, e, true);
                break;
            }
            scale *= 0.5;
        }
        if !moved {
            break;
        }
    }
    let [peak, at, r] = p;
    let start = at - shape.peak_at / r;
    let model = |k: f32| peak * g(r * (k - at)).0;
    let rss = best;
    // Each flank sample outside the contact (the force 0) or within the table's reach; the
    // table's error at them, the larger where one lies in an end interval.
    let [reach_lo, reach_hi] = shape.reach;
    let us = ks.map(|k| r * (k - start));
    let inside = us
        .iter()
        .all(|&u| u <= 0.0 || u >= 1.0 || (reach_lo..=reach_hi).contains(&u));
    let at_end = us
        .iter()
        .any(|&u| u > 0.0 && u < 1.0 && !(SHAPE_STEP..=1.0 - SHAPE_STEP).contains(&u));
    let [inner, ends] = shape.error;
    let table = if at_end { ends } else { inner } * peak;
    let sigma2 = noise * noise + table * table;
    let edge = model(0.0).min(model(run - 1.0));
    let free = r > 1.001 * r_lo && r < 0.999 * r_hi;
    if !(inside && free && edge >= level - 4.0 * noise && rss <= 64.0 * sigma2) {
        return None;
    }
    let fit = FlankFit {
        peak,
        duration: shape.area / (C_AREA * r),
        gains: flank_gains(&inv, peak, r),
    };
    Some((fit, table))
}

/// The flank fit's start `[F_peak, k_peak, r]`: of [`SCAN`] inverse durations `r` evenly over
/// `r_lo..=r_hi`, each with the pulse's peak at [`PLACES`] places evenly across the clipped
/// run and `F_peak = sum y g / sum g^2` over the four samples, the one with the least
/// residual; `None` when none puts a flank sample inside the pulse.
fn scan_start(
    ks: &[f32; 4],
    ys: &[f32; 4],
    run: f32,
    (r_lo, r_hi): (f32, f32),
    shape: &PulseShape,
) -> Option<[f32; 3]> {
    let mut best: Option<([f32; 3], f32)> = None;
    for j in 0..SCAN * PLACES {
        let (jr, jp) = ((j / PLACES) as f32, (j % PLACES) as f32);
        let r = r_lo + (r_hi - r_lo) * jr / (SCAN - 1) as f32;
        let at = -0.5 + run * (jp + 0.5) / PLACES as f32;
        let gs = ks.map(|k| shape.at(r * (k - at) + shape.peak_at).0);
        let (yg, gg) = gs
            .iter()
            .zip(ys)
            .fold((0.0f32, 0.0f32), |(a, b), (&g, &y)| (a + y * g, b + g * g));
        if gg <= 0.0 {
            continue;
        }
        let peak = yg / gg;
        let rss = gs
            .iter()
            .zip(ys)
            .fold(0.0f32, |a, (&g, &y)| a + (y - peak * g) * (y - peak * g));
        if best.is_none_or(|(_, b)| rss < b) {
            best = Some(([peak, at, r], rss));
        }
    }
    best.map(|(p, _)| p)
}
