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

use crate::chain_residual::KINK_SAMPLES;
use crate::error::Error;
use crate::hertz::CONTACT_TIME_FACTOR;
use crate::shape_fit::{
    C_AREA, FlankChain, FlankFit, Flanks, amplitude_fit, descend, flank_gains, gauss_newton_of,
};

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
/// `u^(1/4)`), and outside the contact, where the force is 0; a flank sample in an interval
/// left out is not read. All zero
/// ([`PulseShape::NONE`]): no table, and a damped pulse that clips is `Saturated`.
/// `size_of` 544 B (65 points; `tests/sizes.rs`).
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
    /// table is made once per detector, and its error is stated); `g = z^(3/2)` and
    /// `dg/du = (3/2) z^(1/2) z' t_c`. Its area is [`C_AREA`], its peak at `u = 1/2`, its
    /// reach the whole contact (the force starts and ends like `u^(3/2)`), its error
    /// [`HERTZ_TABLE_ERROR`]. The detector measures a clipped Hertz pulse with it where the
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

/// Fits of a clipped pulse's flanks after the first, at most, each reading the flank samples
/// as the last left them (`ShapeFit::read_at`).
const READINGS: usize = 3;

/// Samples of a contact the flank fit sums at most ([`shape_flank_fit`]'s fifth row); a
/// longer one is not fitted.
const SUM_SAMPLES: usize = 8192;

/// Peak and duration of a pulse whose top is clipped, from its unclipped flanks ([`Flanks`]:
/// the two samples either side of the `run` clipped ones, the clipping `level`, and the sum
/// of the pulse's samples with their number) and the contact's own shape. The least-squares
/// fit of `F_peak g(r (k - k_peak) + u_peak)` (`u_peak` the table's `peak_at`), in `F_peak`,
/// the peak's time `k_peak` and the inverse duration `r = 1 / t_c` (per sample; about the
/// peak, a change of `r` leaves it in place), to the four flank samples and, as a fifth row,
/// to the sum of the pulse's other samples (the run's read as `Flanks::run_sum`), whose
/// noise is its samples' and the table's error summed over them (`ShapeFit::sum_sigma`):
/// where a flank sample sees no force, the sum still tests the fit. A flank sample that lies
/// in an end interval the table's reach leaves out is not read, and the fit is made again
/// (`READINGS` times at most) until the samples it reads stay the same. Where no flank
/// sample it reads sees an end of the contact, or one beyond it sees none, the flank samples
/// still bound that end (`ShapeFit::end_bounds`: the contact starts after a sample that sees
/// no force and before one that does), and the end joins the fit as a row within that
/// interval, its standard deviation the interval's over `sqrt 12`. Where the model falls
/// below the level at the run's first or last clipped sample, the descent takes a row that
/// lifts it there (`ShapeFit::level_rows`: the force was at the level or above); the sigmas
/// do not, an inequality stating no more. It starts from the best
/// of `SCAN` durations between the span of the flank samples that see force (`run + 3` when
/// all four do), and twice the sum over
/// `level x area`, each with its peak at `PLACES` places across the run (`scan_start`),
/// then takes up to 32 Gauss-Newton steps, each halved until it lowers the residual
/// (`F_peak` kept above half its value, the peak within the run, the clipped samples inside
/// the contact, `r` within the scan's range). The duration it reports is the
/// detector's, `area t_c / C_AREA` (the area over `C_AREA F_peak`). `None` when the fit does
/// not describe a clipped pulse of this shape (`accepted`). With the fit, the table's error
/// per sample at the flanks (counts: [`PulseShape::error`] times `F_peak`), which the fit's
/// sigmas take beside the noise.
///
/// ```
/// use coalshock::pulse_shape::{PulseShape, SHAPE_POINTS, SHAPE_STEP, shape_flank_fit};
/// use coalshock::shape_fit::{FlankChain, Flanks};
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
///     samples: clipped.len() as f32,
///     run_sum: run * 2000.0,
///     chain: FlankChain::RIGID,
/// };
/// let (fit, _) = shape_flank_fit(&flanks, 1.0, &s).unwrap();
/// assert!((fit.peak / 2400.0 - 1.0).abs() < 1e-3);
/// assert!((fit.duration / (40.0 * 9.0 / 16.0 / coalshock::shape_fit::C_AREA) - 1.0).abs() < 1e-3);
/// ```
#[inline(never)]
pub fn shape_flank_fit(flanks: &Flanks, noise: f32, shape: &PulseShape) -> Option<(FlankFit, f32)> {
    let (ks, ys) = flanks.samples()?;
    if !(shape.is_some() && noise.is_finite() && noise > 0.0) {
        return None;
    }
    let (run, level) = (flanks.run, flanks.level);
    // The contact spans the flank samples that see force, and the run between them. A
    // sample below four noise RMS may see none (`ShapeFit::end_bounds` asks the same of the
    // flank's whole sigma, known only once `F_peak` is: this bound is the looser).
    let unseen = ys.iter().filter(|&&y| y < 4.0 * noise).count() as f32;
    let range = (
        shape.area * level / (2.0 * flanks.sum),
        1.0 / (run + 3.0 - unseen),
    );
    if range.0.is_nan() || range.0 >= range.1 {
        return None;
    }
    let start = scan_start(&ks, &ys, run, range, shape)?;
    let fit = ShapeFit {
        ks,
        ys,
        read: 4,
        rest: flanks.sum - ys.iter().sum::<f32>() - flanks.run_sum,
        rest_samples: flanks.samples - 4.0 - run,
        run,
        chain: flanks.chain,
        shape,
        noise,
        sum_weight: 0.0,
        level,
        end_rows: [[0.0; 2]; 2],
    };
    let keep = |[peak, at, r]: [f32; 3], floor: f32| {
        let r = r.max(range.0).min(range.1);
        // The clipped samples lie inside the contact: it starts before the first and ends
        // after the last.
        let (rise, fall) = (shape.peak_at / r, (1.0 - shape.peak_at) / r);
        let (first, last) = fit.clipped();
        let at = at.max(-0.5).min(run - 0.5);
        [
            peak.max(floor),
            at.min(first + rise - 0.01).max(last - fall + 0.01),
            r,
        ]
    };
    let kept = keep(start, 0.0);
    let mut fit = fit.read_at(kept).weighted(kept)?;
    let mut p = descend_flanks(&fit, kept, &keep)?;
    // A flank sample that the fit moved into an end interval the reach leaves out: again,
    // without reading it (`accepted` takes the last fit only when the samples it reads stay
    // the same).
    for _ in 0..READINGS {
        let again = fit.read_at(p);
        if again.ks == fit.ks && again.read == fit.read {
            break;
        }
        fit = again.weighted(p)?;
        p = descend_flanks(&fit, p, &keep)?;
    }
    accepted(&fit, p, level, range)
}

/// The descent of `fit` from `p` ([`descend`]), over the flank samples it reads and its
/// extra rows ([`ShapeFit::residual`]), kept in range by `keep`: the point it reaches.
fn descend_flanks(
    fit: &ShapeFit,
    p: [f32; 3],
    keep: &impl Fn([f32; 3], f32) -> [f32; 3],
) -> Option<[f32; 3]> {
    let residual = |q| fit.residual(q);
    descend(fit.read(), p, fit.g(), residual, keep).map(|(p, ..)| p)
}

/// The fit at `p = [F_peak, k_peak, r]` when it describes a clipped pulse of the table's
/// shape, with its sigmas from the normal equations at `p` ([`ShapeFit::weighted`]): `None`
/// for flank samples read otherwise than the fit read them ([`ShapeFit::read_at`]), an unread
/// one beyond the force its end interval spans (4 noise RMS outside 0 to the force at the
/// reach's end or the model's), `r` at the end of its `range`, the fitted pulse below the
/// `level` where the first and the last clipped sample saw it (`ShapeFit::clipped`; less four
/// times the noise RMS of a flank sample, the sensor's with the table's, the samples' own
/// error and the sections' state error (`FlankChain::state_error`), and the chain's `FlankChain::level_error` times `F_peak`), their residual `rss`
/// with the sum row's above `8 x` that RMS, or fewer than four rows that see
/// the pulse (a flank sample whose force is below its noise RMS does not: at the contact's
/// start the fit sits on the kink between no force and the steep flank; the sum row and the
/// rows of the contact's ends that flank samples bound do, so a pulse that rises from no
/// force past the level within one sample is tested by its start's row).
fn accepted(
    fit: &ShapeFit,
    p: [f32; 3],
    level: f32,
    (r_lo, r_hi): (f32, f32),
) -> Option<(FlankFit, f32)> {
    let [peak, at, r] = p;
    // The rows weighted at `p` (the descent kept the weights of where it started).
    let weighted = fit.weighted(p)?;
    let (rss, _) = weighted.residual(p)?;
    let shape = fit.shape;
    let table = fit.flank_table(p);
    let sigma2 = fit.flank_variance(p);
    // The flank samples read and unread as the fit read them, each unread one within the
    // force its end interval spans (0 to the force at the reach's end) or the model's.
    let again = fit.read_at(p);
    let inside = again.read == fit.read && again.ks == fit.ks && {
        let [lo, hi] = shape.reach;
        let edge = shape.at(lo).0.max(shape.at(hi).0);
        let slack = 4.0 * libm::sqrtf(sigma2);
        let start = fit.start(p);
        let unread = fit.ks.iter().zip(&fit.ys).skip(fit.read);
        unread.into_iter().all(|(&k, &y)| {
            let u = r * (k - start);
            let g = if u > 0.0 && u < 1.0 {
                shape.at(u).0
            } else {
                0.0
            };
            y >= -slack && y <= peak * edge.max(g) + slack
        })
    };
    let (first, last) = fit.clipped();
    let edge = fit.model(p, first).0.min(fit.model(p, last).0);
    let level = level - fit.chain.level_error * peak;
    let free = r > 1.001 * r_lo && r < 0.999 * r_hi;
    if !(inside && free && edge >= level - 4.0 * libm::sqrtf(sigma2) && rss <= 64.0 * sigma2) {
        return None;
    }
    // The sigmas from the normal equations at `p`, without a flank sample whose force is
    // below its noise (the sensor's with the table's error): where the pulse starts (or
    // ends) at it, the fit sits on the kink between no force and the pulse's steep flank,
    // whose one-sided slope would claim a start time that sample does not pin.
    let g = fit.g();
    let sigma = libm::sqrtf(sigma2);
    let felt = |x: f32| match g(x) {
        (g, _) if peak * g < sigma => (0.0, 0.0),
        read => read,
    };
    // The sum row and the end rows; not the level rows.
    let (rows, count) = weighted.rows(p)?;
    let [row, ..] = rows;
    // Three unknowns: at least four rows that see the pulse, or the residual tests nothing.
    let (ks, ys) = fit.read();
    let seen = ks.iter().filter(|&&k| felt(r * (k - at)).0 > 0.0).count();
    if seen + usize::from(row[0] != 0.0) + count < 4 {
        return None;
    }
    let (_, inv, _) = gauss_newton_of(ks, ys, p, felt, &rows)?;
    let fit = FlankFit {
        peak,
        peak_at: at,
        duration: shape.area / (C_AREA * r),
        gains: flank_gains(&inv, peak, r),
    };
    Some((fit, table))
}

/// Whether `u` lies in the table's first or last interval, inside the contact.
pub(crate) fn in_end_interval(u: f32) -> bool {
    u > 0.0 && u < 1.0 && !(SHAPE_STEP..=1.0 - SHAPE_STEP).contains(&u)
}

/// What [`shape_flank_fit`] fits: the four flank samples `ys` at `ks` (the first `read` of
/// them read, [`ShapeFit::read_at`]), the sum `rest` of the
/// pulse's other `rest_samples` samples (counts; the flank samples and the run's taken off),
/// the run's length, what the chain did to the samples ([`FlankChain`]), the contact's table, the sensor's noise
/// RMS (counts) and the weight of the sum's row against one flank sample.
#[derive(Clone, Copy)]
struct ShapeFit<'a> {
    ks: [f32; 4],
    ys: [f32; 4],
    read: usize,
    rest: f32,
    rest_samples: f32,
    run: f32,
    chain: FlankChain,
    shape: &'a PulseShape,
    noise: f32,
    /// The sum row's weight against one flank sample's: 0, no sum row, until
    /// [`Self::weighted`] sets it at a point; every residual is taken of a weighted fit.
    sum_weight: f32,
    /// The clipping level (counts).
    level: f32,
    /// The contact's start and end rows, each `[mid, weight]` ([`Self::end_bounds`]);
    /// weight 0: none.
    end_rows: [[f32; 2]; 2],
}

impl ShapeFit<'_> {
    /// Where the force was at the level at the first and the last clipped sample (`k`): the
    /// run less its guard at each end, `lag` earlier.
    fn clipped(&self) -> (f32, f32) {
        let FlankChain { guard, lag, .. } = self.chain;
        let first = guard - lag;
        (first, first + self.run - 1.0 - 2.0 * guard)
    }

    /// The flank samples the fit reads, `(ks, ys)`: the first `read` ([`Self::read_at`]).
    fn read(&self) -> (&[f32], &[f32]) {
        let n = self.read;
        (
            self.ks.get(..n).unwrap_or(&[]),
            self.ys.get(..n).unwrap_or(&[]),
        )
    }

    /// The fit with its flank samples ordered as read at `p`: first those outside the
    /// contact (the force 0) or within the table's reach, then those inside the contact in
    /// an end interval the reach leaves out (where the table's error is not bounded), which
    /// it does not read, nor any it did not read before (so that a sample on an interval's
    /// edge does not flip between readings).
    fn read_at(&self, p: [f32; 3]) -> Self {
        let (start, r) = (self.start(p), p[2]);
        let [lo, hi] = self.shape.reach;
        let was_read = self.read().0;
        let unread = |k: f32| {
            let u = r * (k - start);
            (u > 0.0 && u < lo) || (u > hi && u < 1.0) || !was_read.contains(&k)
        };
        let mut out = ShapeFit { read: 0, ..*self };
        let mut n = 0;
        for later in [false, true] {
            let pairs = self.ks.iter().zip(&self.ys);
            for (&k, &y) in pairs.filter(|&(&k, _)| unread(k) == later) {
                if let (Some(ko), Some(yo)) = (out.ks.get_mut(n), out.ys.get_mut(n)) {
                    (*ko, *yo) = (k, y);
                }
                n += 1;
            }
            if !later {
                out.read = n;
            }
        }
        out
    }

    /// The contact's start at `p = [F_peak, k_peak, r]` (samples): `k_peak - u_peak / r`.
    fn start(&self, [_, at, r]: [f32; 3]) -> f32 {
        at - self.shape.peak_at / r
    }

    /// The table about its peak, `x = r (k - k_peak)`: `(g, dg/dx)`.
    fn g(&self) -> impl Fn(f32) -> (f32, f32) + '_ {
        |x| self.shape.at(x + self.shape.peak_at)
    }

    /// The table's error per flank sample at `p` (counts, [`PulseShape::error`] times
    /// `F_peak`): the larger where one lies in an end interval; with the samples' own error
    /// (`FlankChain::sample_error` times `F_peak`).
    fn flank_table(&self, p: [f32; 3]) -> f32 {
        let [peak, _, r] = p;
        let start = self.start(p);
        let at_end = self
            .read()
            .0
            .iter()
            .any(|&k| in_end_interval(r * (k - start)));
        let [inner, ends] = self.shape.error;
        (if at_end { ends } else { inner } + self.own_error(p)) * peak
    }

    /// The samples' own error over the peak at `p` (`FlankChain::sample_error`): at the ends
    /// where a flank sample lies within [`KINK_SAMPLES`] of the contact's start or end.
    fn own_error(&self, p: [f32; 3]) -> f32 {
        let start = self.start(p);
        let end = start + 1.0 / p[2];
        let near = |k: f32| (k - start).abs() <= KINK_SAMPLES || (k - end).abs() <= KINK_SAMPLES;
        let [body, ends] = self.chain.sample_error;
        if self.read().0.iter().any(|&k| near(k)) {
            ends
        } else {
            body
        }
    }

    /// The variance of a flank sample at `p` (counts^2): the sensor's noise, the table's
    /// error ([`Self::flank_table`]) and the sections' state error
    /// (`FlankChain::state_variance`).
    fn flank_variance(&self, p: [f32; 3]) -> f32 {
        let table = self.flank_table(p);
        self.noise * self.noise + table * table + self.chain.state_variance()
    }

    /// The fit with its sum row weighted at `p` against one flank sample: the flank sample's
    /// sigma ([`Self::flank_variance`]) over the sum's ([`Self::sum_sigma`]).
    fn weighted(&self, p: [f32; 3]) -> Option<Self> {
        let flank = libm::sqrtf(self.flank_variance(p));
        let row = |b: Option<[f32; 2]>| match b {
            Some([lo, hi]) if hi > lo => [0.5 * (lo + hi), flank * libm::sqrtf(12.0) / (hi - lo)],
            _ => [0.0; 2],
        };
        // Force at a flank sample: four times its noise (the sensor's, the table's and the
        // chain's) or more; none: within that of 0.
        let seen = 4.0 * flank;
        Some(ShapeFit {
            sum_weight: flank / self.sum_sigma(p)?,
            end_rows: [
                row(self.end_bounds(p, seen, false)),
                row(self.end_bounds(p, seen, true)),
            ],
            ..*self
        })
    }

    /// Where the contact starts (`after` false) or ends at `p`, `[earliest, latest]`
    /// (samples), from the flank samples on that side that see force (at least `seen` counts)
    /// and those that do not: between the outermost that does (or the run's edge) and the
    /// nearest beyond it that does not; or, where none does not and the outermost that does
    /// lies in the end interval the table's reach leaves out (the fit does not read it),
    /// within that interval beyond it. `None` when nothing bounds it so.
    fn end_bounds(&self, p: [f32; 3], seen: f32, after: bool) -> Option<[f32; 2]> {
        // Distances outward from the run: `-k` before it, `k` after it.
        let out = if after { 1.0 } else { -1.0 };
        let (first, last) = self.clipped();
        let side = || {
            let pairs = self.ks.iter().zip(&self.ys);
            pairs
                .filter(move |&(&k, _)| out * k > 0.0)
                .map(move |(&k, &y)| (out * k, y))
        };
        let edge = if after { last } else { -first };
        let read = self.read().0;
        let read_sees = side().any(|(d, y)| y >= seen && read.contains(&(out * d)));
        let inner = side()
            .filter(|&(_, y)| y >= seen)
            .fold(edge, |m, (d, _)| m.max(d));
        let beyond = side().filter(|&(d, y)| y.abs() < seen && d > inner);
        let outer = match beyond.map(|(d, _)| d).reduce(f32::min) {
            Some(d) => d,
            None if !read_sees && inner > edge => inner + SHAPE_STEP / p[2],
            None => return None,
        };
        let [a, b] = [out * inner, out * outer];
        Some([a.min(b), a.max(b)])
    }

    /// The model `F_peak g(r (k - k_peak) + u_peak)` at sample `k` and its gradient in
    /// `p = [F_peak, k_peak, r]` (counts).
    fn model(&self, [peak, at, r]: [f32; 3], k: f32) -> (f32, [f32; 3]) {
        let t = k - at;
        let (g, slope) = (self.g())(r * t);
        (peak * g, [g, -peak * r * slope, peak * t * slope])
    }

    /// The samples `k` of the contact at `p` that the sum row takes: neither clipped nor a
    /// flank sample; `None` past [`SUM_SAMPLES`].
    fn rest_of(&self, p: [f32; 3]) -> Option<impl Iterator<Item = f32> + '_> {
        let (start, r) = (self.start(p), p[2]);
        let (first, last) = (libm::ceilf(start), libm::floorf(start + 1.0 / r));
        let count = last - first + 1.0;
        if count.is_nan() || count > SUM_SAMPLES as f32 {
            return None;
        }
        let run = self.run;
        Some(
            (0..count.max(0.0) as usize)
                .map(move |i| first + i as f32)
                .filter(move |&k| !(-2.0..run + 2.0).contains(&k)),
        )
    }

    /// The sum row at `p`, weighted: `sum_weight [dS/dF_peak, dS/dk_peak, dS/dr, rest - S]`
    /// with `S` the model's sum over [`Self::rest_of`].
    fn sum_row(&self, p: [f32; 3]) -> Option<[f32; 4]> {
        let (s, [j1, j2, j3]) = self.rest_of(p)?.fold((0.0, [0.0f32; 3]), |(s, j), k| {
            let (m, g) = self.model(p, k);
            (s + m, [j[0] + g[0], j[1] + g[1], j[2] + g[2]])
        });
        let w = self.sum_weight;
        Some([w * j1, w * j2, w * j3, w * (self.rest - s)])
    }

    /// The extra rows at `p` that the sigmas take, weighted: the sum row, and a row per end
    /// of the contact that flank samples bound ([`Self::end_bounds`]), `w [0, 1, d end / dr,
    /// mid - end]` with the start `k_peak - u_peak / r` and the end `k_peak + (1 - u_peak) /
    /// r`. Absent rows are zeros; with the number of end rows.
    fn rows(&self, p: [f32; 3]) -> Option<([[f32; 4]; 3], usize)> {
        let [_, at, r] = p;
        let u = self.shape.peak_at;
        let ends = [
            (at - u / r, u / (r * r)),
            (at + (1.0 - u) / r, -(1.0 - u) / (r * r)),
        ];
        let mut rows = [self.sum_row(p)?, [0.0; 4], [0.0; 4]];
        let mut count = 0;
        for ((&[mid, w], (end, slope)), row) in
            self.end_rows.iter().zip(ends).zip(rows.iter_mut().skip(1))
        {
            if w > 0.0 {
                *row = [0.0, w, w * slope, w * (mid - end)];
                count += 1;
            }
        }
        Some((rows, count))
    }

    /// At the first and the last clipped sample (`Self::clipped`), where the model lies
    /// below the level (less the chain's `level_error` times `F_peak`), the row that lifts it
    /// there, `[dm/dp, level - m]`; zeros where it does not. The descent takes them (the
    /// force was at the level or above there); the sigmas do not (an inequality).
    fn level_rows(&self, p: [f32; 3]) -> [[f32; 4]; 2] {
        let level = self.level - self.chain.level_error * p[0];
        let (first, last) = self.clipped();
        [first, last].map(|k| match self.model(p, k) {
            (m, [g0, g1, g2]) if m < level => [g0, g1, g2, level - m],
            _ => [0.0; 4],
        })
    }

    /// The sum's standard deviation at `p` (counts): the noise of its `rest_samples` and the
    /// table's error at each contact sample in it, summed (it may share one sign), with the
    /// force at the reach's ends where the reach leaves out an end interval (a sample may
    /// lie there, where the table's error is not bounded: the pulse rises to that force from
    /// 0, or falls from it to 0); and the samples' own error (`FlankChain::sample_error`) at
    /// the flank samples and the run's: the equaliser keeps the sum of all the pulse's
    /// samples, so what it moves into the others is what it takes from those.
    fn sum_sigma(&self, p: [f32; 3]) -> Option<f32> {
        let [peak, _, r] = p;
        let shape = self.shape;
        let start = self.start(p);
        let [inner, ends] = shape.error;
        let [lo, hi] = shape.reach;
        let unread = if lo > 0.0 { shape.at(lo).0 } else { 0.0 }
            + if hi < 1.0 { shape.at(hi).0 } else { 0.0 }
            + self.own_error(p) * (self.run + 4.0);
        let table = self.rest_of(p)?.fold(unread * peak, |a, k| {
            let end = in_end_interval(r * (k - start));
            a + if end { ends } else { inner } * peak
        });
        let n = self.rest_samples.max(0.0);
        let state = self.chain.state_error[1];
        let sigma = libm::sqrtf(n * self.noise * self.noise + table * table + state * state);
        (sigma > 0.0 && sigma.is_finite()).then_some(sigma)
    }

    /// The residual sum of squares at `p`, the samples' read and the extra rows' that the
    /// descent takes ([`Self::rows`] and [`Self::level_rows`]), and those rows.
    fn residual(&self, p: [f32; 3]) -> Option<(f32, [[f32; 4]; 5])> {
        let (ks, ys) = self.read();
        let flanks = ks.iter().zip(ys).fold(0.0, |a, (&k, &y)| {
            let e = y - self.model(p, k).0;
            a + e * e
        });
        let ([sum, start, end], _) = self.rows(p)?;
        let [l0, l1] = self.level_rows(p);
        let rows = [sum, start, end, l0, l1];
        let extra = rows.iter().fold(0.0, |a, [.., e]| a + e * e);
        Some((flanks + extra, rows))
    }
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
        let Some((peak, rss)) = amplitude_fit(&gs, ys) else {
            continue;
        };
        if best.is_none_or(|(_, b)| rss < b) {
            best = Some(([peak, at, r], rss));
        }
    }
    best.map(|(p, _)| p)
}
