//! The bias a chain known only to a tolerance can leave in a measured pulse: the spread of the
//! shift of `ln F_max` (and, opposite, of `ln t_c`) per pulse duration, which the classifier
//! adds to the pulse's noise so that a chain given a few per cent off costs confidence, not
//! the class.
//!
//! The equaliser inverts the chain it is given, `H_k(s)`. When the true chain is `H(s)`, the
//! force comes back as `F + e` with `e` the force filtered by `E = H / H_k - 1`. To first order
//! the peak moves by `e` at the peak, and for a pulse symmetric about its peak
//!
//! `d ln F_max = (1 / pi) int_0^{w_N} Re E(jw) S(w) dw`, `S(w) = t_c S1(w t_c)`,
//!
//! with `S1(v) = int_{-1/2}^{1/2} cos^(3/2)(pi x) cos(v x) dx` the spectrum of the kernel's Hertz
//! shape (`F^(2/3)` a half sine, see [`crate::detector`]) and `w_N = pi f_s`: the sampled pulse
//! carries nothing above the Nyquist frequency. Every stage has unit gain at DC (`E(0) = 0`),
//! so the pulse's area `C_AREA F_max t_c` does not move and `d ln t_c = -d ln F_max`.
//!
//! Each parameter of each stage (frequency, damping, and a beam mode's gain) is moved by
//! `+-` its relative tolerance alone (the accelerometer's own, when the chain states one:
//! [`ChainDynamics::accelerometer_tolerance`]), giving the larger `|d ln F_max|` of the two
//! signs, `b_i`.
//! Each parameter's error is taken as uniform within its tolerance and independent of the
//! others, so the bias has the standard deviation `sqrt(sum_i b_i^2 / 3)` to first order: that
//! is the figure the classifier adds to the pulse's noise. (The sum of the `b_i`, the worst
//! corner, made posteriors on the scene's own chain far less sure than they are: a 0.85 stated
//! where 0.99 held.) It is tabulated at
//! [`POINTS`] durations spaced evenly in `ln t_c` over the scene's pulses, at build, and
//! interpolated per pulse. The integral is a trapezoid rule in `v = w t_c` with step
//! [`STEP_V`] up to [`MAX_V`] (`S1` falls as `v^(-5/2)`: the trapezoid of `S1` alone over that
//! range is within 1e-4 of the exact 1); `E` is taken a half step right of the imaginary axis
//! (`s = (0.5 STEP_V + j v) / t_c`), which smooths a mode's resonance narrower than the step
//! into its integral instead of sampling its peak.

use crate::complex::C;
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

/// The tabulated spread of `d ln F_max` against `ln t_c`; [`ChainBias::NONE`] for a rigid
/// chain or one known exactly.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChainBias {
    /// `ln t_c` (t_c in s) of the first point.
    ln_duration0: f32,
    /// Points per unit of `ln t_c`.
    points_per_ln: f32,
    /// The spread at each point (0 everywhere for [`ChainBias::NONE`]).
    bias_ln_force: [f32; POINTS],
}

impl ChainBias {
    /// No bias: what a rigid chain or a chain known exactly gets.
    pub const NONE: ChainBias = ChainBias {
        ln_duration0: 0.0,
        points_per_ln: 0.0,
        bias_ln_force: [0.0; POINTS],
    };

    /// The spread for `dynamics` known to its [`ChainTolerance`], sampled at
    /// `sample_rate_hz`, for pulses from `shortest_s` to `longest_s` (s).
    pub fn new<M: Backend>(
        dynamics: &ChainDynamics,
        sample_rate_hz: f32,
        shortest_s: f32,
        longest_s: f32,
    ) -> Self {
        let exact = dynamics.tolerance() == ChainTolerance::EXACT
            && (dynamics.accelerometer().is_none()
                || dynamics.accelerometer_tolerance() == ChainTolerance::EXACT);
        if dynamics.is_rigid() || exact {
            return Self::NONE;
        }
        let (l0, l1) = (M::ln(shortest_s), M::ln(longest_s.max(shortest_s)));
        let span = (l1 - l0) / (POINTS - 1) as f32;
        let mut bias_ln_force = [0.0; POINTS];
        for (i, b) in bias_ln_force.iter_mut().enumerate() {
            let t_c = M::exp(l0 + span * i as f32);
            *b = bound_at(dynamics, sample_rate_hz, t_c);
        }
        Self {
            ln_duration0: l0,
            points_per_ln: if span > 0.0 { 1.0 / span } else { 0.0 },
            bias_ln_force,
        }
    }

    /// The spread of `d ln F_max` for a pulse of `ln t_c` (t_c in s), linear in `ln t_c`
    /// between the points and held beyond them; 0 for [`ChainBias::NONE`].
    pub fn bias_ln_force(&self, ln_duration: f32) -> f32 {
        let at = (ln_duration - self.ln_duration0) * self.points_per_ln;
        math::interpolate(&self.bias_ln_force, math::table_position(at, POINTS))
    }

    /// The spread at each tabulated point, from the shortest pulse to the longest.
    pub fn points(&self) -> &[f32; POINTS] {
        &self.bias_ln_force
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

/// The three relative moves of a stage's parameters, each alone, with both signs.
const MOVES: usize = 6;

/// `(d frequency, d damping, d gain)` relative, of move `k`.
fn mv(k: usize, tol: ChainTolerance) -> (f32, f32, f32) {
    let sign = if k.is_multiple_of(2) { 1.0 } else { -1.0 };
    match k / 2 {
        0 => (sign * tol.frequency, 0.0, 0.0),
        1 => (0.0, sign * tol.damping, 0.0),
        _ => (0.0, 0.0, sign * tol.gain),
    }
}

/// The standard deviation of `d ln F_max` for one pulse duration `t_c` (s): the module's
/// integral for every stage and move, `sqrt(sum_i b_i^2 / 3)` over parameters.
// Not inlined: a rigid scene's build never calls it and must not carry its frame.
#[inline(never)]
fn bound_at(d: &ChainDynamics, sample_rate_hz: f32, t_c: f32) -> f32 {
    let (tol, acc_tol) = (d.tolerance(), d.accelerometer_tolerance());
    let v_top = (core::f32::consts::PI * sample_rate_hz * t_c).min(MAX_V);
    // [stage][move]: modes, then the accelerometer.
    let mut sums = [[0.0f32; MOVES]; crate::equaliser::MAX_MODES + 1];
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
        let s = C::new(0.5 * STEP_V / t_c, v / t_c);
        let mut beam = C::new(1.0, 0.0);
        for m in d.modes() {
            let t = mode_term(s, m);
            beam = C::new(beam.re + t.re, beam.im + t.im);
        }
        for (m, row) in d.modes().iter().zip(sums.iter_mut()) {
            let t = mode_term(s, m);
            for (j, sum) in row.iter_mut().enumerate() {
                let (df, dz, dg) = mv(j, tol);
                let moved = BeamMode {
                    frequency_hz: m.frequency_hz * (1.0 + df),
                    damping_ratio: m.damping_ratio * (1.0 + dz),
                    gain: m.gain * (1.0 + dg),
                };
                *sum += mode_term(s, &moved).sub(t).div(beam).re * w;
            }
        }
        if let (Some(a), Some(row)) = (d.accelerometer(), sums.last_mut()) {
            let t = accelerometer_term(s, &a);
            for (j, sum) in row.iter_mut().enumerate().take(4) {
                let (df, dz, _) = mv(j, acc_tol);
                let moved = Accelerometer {
                    frequency_hz: a.frequency_hz * (1.0 + df),
                    damping_ratio: a.damping_ratio * (1.0 + dz),
                };
                *sum += accelerometer_term(s, &moved).div(t).re * w - w;
            }
        }
    }
    // Sum over parameters of `b_i^2`, `b_i` the larger move of the two signs.
    let squares = |row: &[f32; MOVES]| {
        row.chunks_exact(2)
            .map(|pair| pair.iter().fold(0.0f32, |a, v| a.max(v.abs())))
            .map(|b| b * b)
            .sum::<f32>()
    };
    let total = libm::sqrtf(sums.iter().map(squares).sum::<f32>() / 3.0);
    if total.is_finite() { total } else { 0.0 }
}
