//! The bias a chain known only to a tolerance can leave in a measured pulse: the spread of the
//! shifts of `ln F_max` and `ln t_c` per pulse duration, which the classifier adds to the
//! pulse's noise so that a chain given a few per cent off costs confidence, not the class.
//!
//! The equaliser inverts the chain it is given, `H_k(s)`. When the true chain is `H(s)`, the
//! force comes back as `F + e` with `e` the force filtered by `E = H / H_k - 1`. To first order
//! the peak moves by `e` at the peak, and for a pulse symmetric about its peak
//!
//! `d ln F_max = (1 / pi) int_0^{w_N} Re E(jw) S(w) dw`, `S(w) = t_c S1(w t_c)`,
//!
//! with `S1(v) = int_{-1/2}^{1/2} cos^(3/2)(pi x) cos(v x) dx` the spectrum of the kernel's Hertz
//! shape (`F^(2/3)` a half sine, see [`crate::detector`]) and `w_N = pi f_s`: the sampled pulse
//! carries nothing above the Nyquist frequency. The duration is the pulse's sum over the
//! detector's window over `C_AREA F_max`, the window `[a, b] t_c` about the peak with
//! `a = -1/2 - before / (f_s t_c)` and `b = 1/2 + after / (f_s t_c)` ([`crate::pulse_window`]:
//! the pre-trigger samples and the hold), so `d ln t_c = d ln A - d ln F_max` with
//!
//! `d ln A = (1 / pi) int_0^{w_N t_c} Re[E(jv / t_c) S1(v) (e^(jvb) - e^(jva)) / (jv)] dv / S1(0)`.
//!
//! Every stage has unit gain at DC (`E(0) = 0`): the whole area does not move. An
//! accelerometer's error answers within the window, which keeps the area, and `d ln t_c` is
//! close to `-d ln F_max`. A beam mode's error answers at the mode, far slower than the pulse:
//! inside the window the pulse is rescaled (`d ln A` close to `d ln F_max`, `ln t_c` barely
//! moves), and the area it keeps returns in the mode's ringing after the window. (Read as the
//! area kept, `d ln t_c = -d ln F_max`, a beam mode's gain stated a spread of `ln u` three times
//! what it does, and posteriors behind a chain given right were under-confident by 12 pp.)
//!
//! A tolerance `tol` is the given value's relative error: the given value is the truth's times
//! `1 + e`, `e` uniform within `+-tol` and independent of the others (as `host-sim evaluate
//! --chain-drawn` draws it). The truth is then the given's times `1 + x`, `x = -e / (1 + e)`
//! from `-tol / (1 + tol)` to `tol / (1 - tol)`: a damping known to 30 % may truly be 43 % above
//! the value given, or 23 % below. Each parameter of each stage (frequency, damping, and a
//! beam mode's gain) is moved alone to either end (the accelerometer's own tolerance, when the
//! chain states one: [`ChainDynamics::accelerometer_tolerance`]), giving the shifts `b_+` and
//! `b_-` of `(ln F_max, ln t_c)`. The shift is taken as linear in `x` on either side, so the
//! second moments are `sum_i (w_+ b_+ b_+^T + w_- b_- b_-^T)` ([`ChainSpread`], the weights
//! [`side_weight`]; `1/6` each for a small tolerance): that is what the classifier adds to
//! the pulse's noise. (Moved by `+-tol` about the given value, the frame taken before, a
//! damping given 30 % low stated about two thirds of the shift it leaves in `ln F_max` at the
//! shortest pulses. The sum of the worst shifts, the worst corner, made posteriors on the
//! scene's own chain far less sure than they are: a 0.85 stated where 0.99 held.) It is
//! tabulated at [`POINTS`] durations spaced evenly in `ln t_c` over the scene's pulses, at
//! build, and interpolated per pulse. The integrals are trapezoid rules in `v = w t_c` with
//! step [`STEP_V`] up to [`MAX_V`] (`S1` falls as `v^(-5/2)`: the trapezoid of `S1` alone over
//! that range is within 1e-4 of the exact 1); a beam mode's `E` is taken a half step right of
//! the imaginary axis (`s = (0.5 STEP_V + j v) / t_c`), which smooths a resonance narrower
//! than the step into its integral instead of sampling its peak. An accelerometer whose
//! resonance is wider than the step (`2 pi zeta f t_c > STEP_V`) is taken on the axis: half a
//! step right of it, its error's low-frequency part `E = 2 (zeta_k - zeta) s / w` gains a real
//! part that overstated the MEMS damping's peak shift by 27 % at 0.5 ms.

use crate::complex::{C, cis};
use crate::equaliser::{Accelerometer, BeamMode, ChainDynamics, ChainTolerance};
use crate::math::{self, Backend};

/// Durations the spread is tabulated at.
pub const POINTS: usize = 6;

/// Step of the integral in `v = w t_c`.
pub const STEP_V: f32 = 0.5;

/// Upper end of the integral in `v = w t_c` (below it when the Nyquist frequency is lower).
pub const MAX_V: f32 = 64.0;

/// `S1(k STEP_V)`, `k = 0..=128`: the spectrum of `cos^(3/2)(pi x)` on `|x| < 1/2`, in closed
/// form `S1(v) = Gamma(5/2) / (2^(3/2) Gamma(7/4 + v / (2 pi)) Gamma(7/4 - v / (2 pi)))`,
/// rounded to f32 (`tests/chain_bias.rs` recomputes it by quadrature).
pub const HERTZ_SPECTRUM: [f32; 129] = [
    0.5564179,
    0.55373055,
    0.54572856,
    0.5325901,
    0.5146062,
    0.49217188,
    0.4657747,
    0.43597978,
    0.4034137,
    0.3687461,
    0.3326706,
    0.29588565,
    0.25907528,
    0.2228912,
    0.18793637,
    0.15475051,
    0.12379831,
    0.09546024,
    0.07002654,
    0.047694214,
    0.02856719,
    0.012659381,
    -9.949564e-05,
    -0.0098557295,
    -0.016821427,
    -0.021262793,
    -0.023487382,
    -0.02383082,
    -0.022643525,
    -0.020277893,
    -0.017076384,
    -0.013360926,
    -0.009423892,
    -0.0055209463,
    -0.0018658462,
    0.0013727059,
    0.0040721977,
    0.0061555402,
    0.0075885705,
    0.008376063,
    0.008556537,
    0.008196165,
    0.0073821195,
    0.0062156967,
    0.004805512,
    0.0032610863,
    0.0016870571,
    0.00017822636,
    -0.0011843992,
    -0.0023364818,
    -0.0032321003,
    -0.0038443871,
    -0.0041651228,
    -0.0042033964,
    -0.0039834864,
    -0.003542125,
    -0.002925347,
    -0.002185116,
    -0.0013759179,
    -0.00055150775,
    0.0002380373,
    0.0009488226,
    0.0015451034,
    0.0020006483,
    0.0022994736,
    0.002435953,
    0.002414346,
    0.0022478094,
    0.0019569853,
    0.0015682712,
    0.0011118904,
    0.00061988307,
    0.00012413271,
    -0.0003454621,
    -0.00076258084,
    -0.0011057645,
    -0.0013593372,
    -0.0015139385,
    -0.0015666595,
    -0.0015208011,
    -0.0013852905,
    -0.0011738109,
    -0.00090370857,
    -0.00059475633,
    -0.00026784933,
    5.628735e-05,
    0.00035830555,
    0.0006212919,
    0.0008316239,
    0.0009795864,
    0.001059726,
    0.0010709374,
    0.0010162911,
    0.0009026262,
    0.00073994434,
    0.0005406501,
    0.00031869012,
    8.864648e-05,
    -0.00013516161,
    -0.0003395146,
    -0.00051302306,
    -0.00064671395,
    -0.00073444564,
    -0.0007731355,
    -0.000762796,
    -0.00070638576,
    -0.0006094937,
    -0.0004798819,
    -0.0003269212,
    -0.00016095694,
    7.353772e-06,
    0.00016769383,
    0.0003106882,
    0.00042842352,
    0.00051485776,
    0.0005661007,
    0.00058055413,
    0.00055890944,
    0.00050400884,
    0.0004205839,
    0.00031489256,
    0.00019427962,
    6.669068e-05,
    -5.9830276e-05,
    -0.00017762874,
    -0.00027988476,
    -0.00036099032,
    -0.0004168392,
    -0.00044501564,
];

/// The second moments a chain's bias adds to a pulse's `(ln F_max, ln t_c)`: variances (log
/// units squared) and covariance. Added to the measurement's own, they widen its noise
/// (the envelope's `NoiseXy::with_chain`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChainSpread {
    /// Variance of `d ln F_max`.
    pub var_ln_force: f32,
    /// Variance of `d ln t_c`.
    pub var_ln_duration: f32,
    /// Covariance of the two.
    pub cov_ln: f32,
}

impl ChainSpread {
    /// No spread.
    pub const ZERO: ChainSpread = ChainSpread {
        var_ln_force: 0.0,
        var_ln_duration: 0.0,
        cov_ln: 0.0,
    };

    /// The standard deviation of `d ln F_max`, `sqrt(var_ln_force)`, by libm's exact square
    /// root whatever the kernel's backend: tests and reports read it, not the node's path, and
    /// micromath's square root is 3e-4 off.
    ///
    /// ```
    /// use coalshock::chain_bias::ChainSpread;
    /// let s = ChainSpread { var_ln_force: 4e-4, var_ln_duration: 0.0, cov_ln: 0.0 };
    /// assert!((s.sigma_ln_force() - 0.02).abs() < 1e-7);
    /// ```
    pub fn sigma_ln_force(&self) -> f32 {
        libm::sqrtf(self.var_ln_force.max(0.0))
    }
}

/// The tabulated [`ChainSpread`] against `ln t_c`; [`ChainBias::NONE`] for a rigid chain or
/// one known exactly.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChainBias {
    /// `ln t_c` (t_c in s) of the first point.
    ln_duration0: f32,
    /// Points per unit of `ln t_c`.
    points_per_ln: f32,
    /// The spread's moments at each point (0 everywhere for [`ChainBias::NONE`]):
    /// `var_ln_force`, `var_ln_duration`, `cov_ln`.
    moments: [[f32; POINTS]; 3],
}

impl ChainBias {
    /// No bias: what a rigid chain or a chain known exactly gets.
    pub const NONE: ChainBias = ChainBias {
        ln_duration0: 0.0,
        points_per_ln: 0.0,
        moments: [[0.0; POINTS]; 3],
    };

    /// The spread for `dynamics` known to its [`ChainTolerance`], sampled at
    /// `sample_rate_hz`, for pulses from `shortest_s` to `longest_s` (s) whose sums take
    /// `window_samples = (before, after)` samples beyond the contact
    /// ([`crate::pulse_window`]).
    pub fn new<M: Backend>(
        dynamics: &ChainDynamics,
        sample_rate_hz: f32,
        (shortest_s, longest_s): (f32, f32),
        window_samples: (f32, f32),
    ) -> Self {
        let exact = dynamics.tolerance() == ChainTolerance::EXACT
            && (dynamics.accelerometer().is_none()
                || dynamics.accelerometer_tolerance() == ChainTolerance::EXACT);
        if dynamics.is_rigid() || exact {
            return Self::NONE;
        }
        let (l0, l1) = (M::ln(shortest_s), M::ln(longest_s.max(shortest_s)));
        let span = (l1 - l0) / (POINTS - 1) as f32;
        let mut moments = [[0.0; POINTS]; 3];
        let [f, t, c] = &mut moments;
        for (i, ((f, t), c)) in f.iter_mut().zip(t.iter_mut()).zip(c.iter_mut()).enumerate() {
            let t_c = M::exp(l0 + span * i as f32);
            let p = spread_at(dynamics, sample_rate_hz, t_c, window_samples);
            (*f, *t, *c) = (p.var_ln_force, p.var_ln_duration, p.cov_ln);
        }
        Self {
            ln_duration0: l0,
            points_per_ln: if span > 0.0 { 1.0 / span } else { 0.0 },
            moments,
        }
    }

    /// The spread for a pulse of `ln t_c` (t_c in s), each moment linear in `ln t_c` between
    /// the points and held beyond them; [`ChainSpread::ZERO`] for [`ChainBias::NONE`].
    pub fn spread(&self, ln_duration: f32) -> ChainSpread {
        let at = (ln_duration - self.ln_duration0) * self.points_per_ln;
        let at = math::table_position(at, POINTS);
        let [f, t, c] = &self.moments;
        ChainSpread {
            var_ln_force: math::interpolate(f, at),
            var_ln_duration: math::interpolate(t, at),
            cov_ln: math::interpolate(c, at),
        }
    }

    /// The spread at each tabulated point, from the shortest pulse to the longest.
    pub fn points(&self) -> [ChainSpread; POINTS] {
        let [f, t, c] = &self.moments;
        core::array::from_fn(|i| ChainSpread {
            var_ln_force: f.get(i).copied().unwrap_or(0.0),
            var_ln_duration: t.get(i).copied().unwrap_or(0.0),
            cov_ln: c.get(i).copied().unwrap_or(0.0),
        })
    }
}

/// `s^2 + 2 zeta w s + w^2` at `s`, with `w = 2 pi f`.
fn resonance(s: C, frequency_hz: f32, damping_ratio: f32) -> C {
    let w = 2.0 * core::f32::consts::PI * frequency_hz;
    let s2 = s.mul(s);
    C::new(
        s2.re + 2.0 * damping_ratio * w * s.re + w * w,
        s2.im + 2.0 * damping_ratio * w * s.im,
    )
}

/// A beam mode's term `g s^2 / (s^2 + 2 zeta w s + w^2)`.
pub(crate) fn mode_term(s: C, m: &BeamMode) -> C {
    let s2 = s.mul(s);
    C::new(m.gain * s2.re, m.gain * s2.im).div(resonance(s, m.frequency_hz, m.damping_ratio))
}

/// The accelerometer's `w^2 / (s^2 + 2 zeta w s + w^2)`.
pub(crate) fn accelerometer_term(s: C, a: &Accelerometer) -> C {
    let w = 2.0 * core::f32::consts::PI * a.frequency_hz;
    C::new(w * w, 0.0).div(resonance(s, a.frequency_hz, a.damping_ratio))
}

/// The whole chain `H(s) = (1 + sum_j g_j s^2 / d_j(s)) H_a(s)` at `s` (rad/s), unit gain at
/// DC ([`crate::equaliser`] writes it out).
pub(crate) fn chain_term(s: C, d: &ChainDynamics) -> C {
    let beam = d
        .modes()
        .iter()
        .fold(C::new(1.0, 0.0), |sum, m| sum.add(mode_term(s, m)));
    match d.accelerometer() {
        Some(a) => beam.mul(accelerometer_term(s, &a)),
        None => beam,
    }
}

/// The three relative moves of a stage's parameters, each alone, to both ends of its
/// tolerance.
const MOVES: usize = 6;

/// Move `k`'s parameter (0 frequency, 1 damping, 2 gain) and the signed end `t` of the given
/// value's error `e = -t`: `+tol` for the even moves, `-tol` for the odd.
fn signed_tolerance(k: usize, tol: ChainTolerance) -> (usize, f32) {
    let sign = if k.is_multiple_of(2) { 1.0 } else { -1.0 };
    let t = match k / 2 {
        0 => tol.frequency,
        1 => tol.damping,
        _ => tol.gain,
    };
    (k / 2, sign * t)
}

/// `(d frequency, d damping, d gain)` relative, of move `k`: the truth at the end of the
/// tolerance on the move's side. The given value is the truth's times `1 + e`, so the truth is
/// the given's times `1 + x`, `x = t / (1 - t)` for `e = -t`.
fn mv(k: usize, tol: ChainTolerance) -> (f32, f32, f32) {
    let (parameter, t) = signed_tolerance(k, tol);
    let x = t / (1.0 - t);
    match parameter {
        0 => (x, 0.0, 0.0),
        1 => (0.0, x, 0.0),
        _ => (0.0, 0.0, x),
    }
}

/// Gauss-Legendre nodes and weights on `[-1, 1]`, four points (exact for degree 7).
const GAUSS_4: [(f32, f32); 4] = [
    (-0.861_136_3, 0.347_854_85),
    (-0.339_981_04, 0.652_145_15),
    (0.339_981_04, 0.652_145_15),
    (0.861_136_3, 0.347_854_85),
];

/// The weight of a move's shift `b` at its end in the second moment, `E[b^2] = w b^2` over its
/// side: the given value is the truth's times `1 + e`, `e` uniform within `+-tol`, so the
/// truth is the given's times `1 + x` with `x = -e / (1 + e)`; the shift is taken linear in
/// `x`, and the side's end is `x(t) = t / (1 - t)` at `t = -e = +-tol`. Then `w = int_0^t
/// x(u)^2 du / (2 t x(t)^2)`, by four-point Gauss-Legendre (within 6e-5 of the closed form up
/// to `|t| = 0.49`): 1/6 as `t -> 0`, 0.1381 at `t = 0.3`, 0.1891 at `t = -0.3`.
///
/// ```
/// # use coalshock::chain_bias::side_weight;
/// assert!((side_weight(1e-4) - 1.0 / 6.0).abs() < 1e-4);
/// // int_0^0.3 (u / (1 - u))^2 du = 1 / 0.7 + 2 ln 0.7 - 0.7, over 2 (0.3) (0.3 / 0.7)^2.
/// let closed = (1.0 / 0.7 + 2.0 * 0.7f64.ln() - 0.7) / (0.6 * (0.3f64 / 0.7).powi(2));
/// assert!((side_weight(0.3) as f64 - closed).abs() < 1e-6);
/// // int_0^0.3 (u / (1 + u))^2 du = 1.3 - 2 ln 1.3 - 1 / 1.3, over 2 (0.3) (0.3 / 1.3)^2.
/// let closed = (1.3 - 2.0 * 1.3f64.ln() - 1.0 / 1.3) / (0.6 * (0.3f64 / 1.3).powi(2));
/// assert!((side_weight(-0.3) as f64 - closed).abs() < 1e-6);
/// ```
pub fn side_weight(t: f32) -> f32 {
    let end = t / (1.0 - t);
    if end == 0.0 {
        return 1.0 / 6.0;
    }
    let mut sum = 0.0;
    for &(node, weight) in &GAUSS_4 {
        let u = 0.5 * t * (1.0 + node);
        let x = u / (1.0 - u) / end;
        sum += weight * x * x;
    }
    0.25 * sum
}

/// A move's first-order shifts `(d ln F_max, d ln A)` (peak, and the sum over the window),
/// accumulated over the integral's points.
type Shifts = [[(f32, f32); MOVES]; crate::equaliser::MAX_MODES + 1];

/// The [`ChainSpread`] for one pulse duration `t_c` (s) whose sum spans `window_samples`
/// samples beyond the contact: the module's integrals for every stage and move, each move's
/// `(d ln F_max, d ln t_c = d ln A - d ln F_max)` taken as the shift at its side's end of the
/// tolerance, the error uniform within it (`E[b b^T] = w_+ b_+ b_+^T + w_- b_- b_-^T` of the
/// two sides' shifts, [`side_weight`]), summed over parameters.
// Not inlined: a rigid scene's build never calls it and must not carry its frame.
#[inline(never)]
fn spread_at(
    d: &ChainDynamics,
    sample_rate_hz: f32,
    t_c: f32,
    window_samples: (f32, f32),
) -> ChainSpread {
    let shifts = shifts_at(d, sample_rate_hz, t_c, window_samples);
    let (beam, acc) = (d.tolerance(), d.accelerometer_tolerance());
    let mut s = ChainSpread::ZERO;
    for (i, &(df, da)) in shifts.iter().flatten().enumerate() {
        let tol = if i < crate::equaliser::MAX_MODES * MOVES {
            beam
        } else {
            acc
        };
        let w = side_weight(signed_tolerance(i % MOVES, tol).1);
        let dt = da - df;
        s.var_ln_force += w * df * df;
        s.var_ln_duration += w * dt * dt;
        s.cov_ln += w * df * dt;
    }
    let finite =
        s.var_ln_force.is_finite() && s.var_ln_duration.is_finite() && s.cov_ln.is_finite();
    if finite { s } else { ChainSpread::ZERO }
}

/// Every stage's and move's `(d ln F_max, d ln A)` for a pulse of `t_c` (s): the module's two
/// integrals, the window `[a, b] t_c` about the peak with `a = -1/2 - before / (f_s t_c)`,
/// `b = 1/2 + after / (f_s t_c)`.
fn shifts_at(
    d: &ChainDynamics,
    sample_rate_hz: f32,
    t_c: f32,
    (before, after): (f32, f32),
) -> Shifts {
    let (tol, acc_tol) = (d.tolerance(), d.accelerometer_tolerance());
    let beam_moves: [_; MOVES] = core::array::from_fn(|j| mv(j, tol));
    let acc_moves: [_; MOVES] = core::array::from_fn(|j| mv(j, acc_tol));
    let v_top = (core::f32::consts::PI * sample_rate_hz * t_c).min(MAX_V);
    let samples = sample_rate_hz * t_c;
    let (a, b) = (-0.5 - before / samples, 0.5 + after / samples);
    let area = HERTZ_SPECTRUM[0];
    let (turn_a, turn_b) = (cis(STEP_V * a), cis(STEP_V * b));
    let (mut at_a, mut at_b) = (C::new(1.0, 0.0), C::new(1.0, 0.0));
    // [stage][move]: modes, then the accelerometer.
    let mut sums: Shifts = [[(0.0, 0.0); MOVES]; crate::equaliser::MAX_MODES + 1];
    for (k, &weight) in HERTZ_SPECTRUM.iter().enumerate() {
        let v = k as f32 * STEP_V;
        if v > v_top {
            break;
        }
        let trapezoid = if k == 0 || v + STEP_V > v_top {
            0.5
        } else {
            1.0
        };
        let w = weight * trapezoid * STEP_V / core::f32::consts::PI;
        // `(e^(jvb) - e^(jva)) / (jv)`: the exponentials by one rotation per step.
        let window = if k == 0 {
            C::new(b - a, 0.0)
        } else {
            C::new(0.0, -1.0 / v).mul(at_b.sub(at_a))
        }
        .scale(w / area);
        (at_a, at_b) = (at_a.mul(turn_a), at_b.mul(turn_b));
        // The error's response `e = E - 1` weighed by the peak's `w` and the window's.
        let add = |sum: &mut (f32, f32), e: C| {
            sum.0 += e.re * w;
            sum.1 += e.mul(window).re;
        };
        let s = C::new(0.5 * STEP_V / t_c, v / t_c);
        let mut terms = [C::new(0.0, 0.0); crate::equaliser::MAX_MODES];
        let mut beam = C::new(1.0, 0.0);
        for (m, t) in d.modes().iter().zip(terms.iter_mut()) {
            *t = mode_term(s, m);
            beam = beam.add(*t);
        }
        let per_beam = C::new(1.0, 0.0).div(beam);
        for ((m, &t), row) in d.modes().iter().zip(terms.iter()).zip(sums.iter_mut()) {
            for (sum, &(df, dz, dg)) in row.iter_mut().zip(&beam_moves) {
                let moved = BeamMode {
                    frequency_hz: m.frequency_hz * (1.0 + df),
                    damping_ratio: m.damping_ratio * (1.0 + dz),
                    gain: m.gain * (1.0 + dg),
                };
                add(sum, mode_term(s, &moved).sub(t).mul(per_beam));
            }
        }
        if let (Some(acc), Some(row)) = (d.accelerometer(), sums.last_mut()) {
            // A resonance wider than the step is taken on the axis.
            let width = acc.damping_ratio * 2.0 * core::f32::consts::PI * acc.frequency_hz * t_c;
            let s = if width > STEP_V { C::new(0.0, s.im) } else { s };
            let per_t = C::new(1.0, 0.0).div(accelerometer_term(s, &acc));
            for (sum, &(df, dz, _)) in row.iter_mut().zip(&acc_moves).take(4) {
                let moved = Accelerometer {
                    frequency_hz: acc.frequency_hz * (1.0 + df),
                    damping_ratio: acc.damping_ratio * (1.0 + dz),
                };
                add(
                    sum,
                    accelerometer_term(s, &moved)
                        .mul(per_t)
                        .sub(C::new(1.0, 0.0)),
                );
            }
        }
    }
    sums
}
