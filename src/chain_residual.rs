//! The bias the equaliser itself leaves in a short pulse: at a few samples per pulse the
//! regularised accelerometer inverse (and the modes' discretisation) reshape the Hertz pulse,
//! and the detector's fit then reads its peak low and its duration long. Computed at build per
//! point of the sampling correction, and added to the scene's [`SampledCalibration`].
//!
//! The equalised chain passes the force through `R(w) = H(jw) Q(e^(j w T))`: `H` the chain
//! ([`crate::equaliser`]), `Q` its equaliser with the reported delay taken off; `R(0) = 1`,
//! and `R = 1` for a rigid chain. The kernel's pulse `F_max P(t / t_c)`, `P(x) = cos^(3/2)(pi
//! x)` on `|x| < 1/2`, has the spectrum `F_max t_c S1(w t_c)` ([`HERTZ_SPECTRUM`]). Every
//! equalised sample is a linear functional of the continuous signal, so with `v = w t_c`
//! and `x = t / t_c`, exactly,
//!
//! `y(x) = P(x) + (1 / pi) int_0^inf Re((R - 1) e^(j v x)) S1(v) dv`,
//!
//! and by Poisson's summation formula the sum of the samples `x_j = x_0 + j / n` (`n` samples
//! per pulse), whose aliases sit at `w = 2 pi m f_s` where `Q = 1`, is
//!
//! `sum_j y(x_j) = n S1(0) + 2 n sum_(m >= 1) Re(H(j 2 pi m f_s) e^(j 2 pi m n x_0)) S1(2 pi m n)`.
//!
//! The rigid pulse has the same with `R = 1` and `H = 1`. [`crate::shape_fit::shape_fit`] reads each
//! (the largest sample, two samples either side of it and the sum), at [`PHASES`] sample phases; the
//! mean over phases of `ln(fit of y / fit of P)` is the bias, and the spread over phases of
//! `ln(fit of y)` joins the measurement's noise (in place of the fit's generic bound). The integral is a trapezoid rule in `v`, step
//! [`crate::chain_bias::STEP_V`] up to [`crate::chain_bias::MAX_V`], as the chain's bound takes
//! it. Points at [`SMOOTH_FROM_SAMPLES`] samples per pulse or more are left at 0: the fit's
//! error there is below 1e-3 and a scene whose every pulse is that long is read by the
//! smoothed top, not by this fit.
//!
//! It runs once per scene, in f32 with libm whatever the scene's backend, and only behind a
//! chain: `SensorChain::with_dynamics` hands [`residual`] to the chain as a
//! [`crate::equaliser::ResidualFn`], so a firmware whose chain is rigid links none of it.
//! Its helpers are not inlined: this runs once per scene and is kept small in flash.

use crate::chain_bias::{HERTZ_SPECTRUM, MAX_V, STEP_V, chain_term};
use crate::complex::{C, cis};
use crate::equaliser::{ChainDynamics, EqualiserDesign};
use crate::math::{self, Backend, Libm as M};
use crate::sampled::{SAMPLED_FIRST_N, SAMPLED_POINTS, SAMPLED_STEP, SampledCalibration};
use crate::shape_fit::{five_about, shape_fit};

/// Sample phases averaged per point.
pub const PHASES: usize = 8;

/// Samples per pulse from which the residual is taken as 0 (see the module docs).
pub const SMOOTH_FROM_SAMPLES: f32 = 24.0;

/// Samples computed around the peak: offsets `-3..=3` from the sample nearest it (the
/// largest is within one of it, and the fit takes two either side of the largest).
const AROUND: usize = 7;

/// The equaliser's residual bias at each point `n_k` of a [`SampledCalibration`], for
/// `dynamics` equalised by `design` at `sample_rate_hz`; [`SampledCalibration::NONE`] for
/// a rigid chain.
pub fn residual(
    dynamics: &ChainDynamics,
    design: &EqualiserDesign,
    sample_rate_hz: f32,
) -> SampledCalibration {
    let mut out = SampledCalibration::NONE;
    if design.is_identity() {
        return out;
    }
    let mut n = SAMPLED_FIRST_N;
    for k in 0..SAMPLED_POINTS {
        if n < SMOOTH_FROM_SAMPLES {
            let [lf, lt, sf, st] = point(dynamics, design, sample_rate_hz, n);
            for (table, v) in [
                (&mut out.ln_force, lf),
                (&mut out.ln_duration, lt),
                (&mut out.sigma_ln_force, sf),
                (&mut out.sigma_ln_duration, st),
            ] {
                if let Some(slot) = table.get_mut(k) {
                    *slot = if v.is_finite() { v } else { 0.0 };
                }
            }
        }
        n *= SAMPLED_STEP;
    }
    out
}

/// `[mean ln F, mean ln t, spread ln F, spread ln t]` at `n` samples per pulse: the mean over
/// phases of the fit of the equalised pulse over the rigid one's, and the spread over phases
/// of the equalised pulse's fit itself. The spread is the whole error the fit leaves at that
/// phase, its own sampling error included: the detector states that error through this
/// correction in place of its generic bound, and the equaliser's reshaping partly cancels it
/// (behind the 6.3 kHz MEMS band the spread of the ratio to the rigid fit overstated it).
#[inline(never)]
fn point(
    dynamics: &ChainDynamics,
    design: &EqualiserDesign,
    sample_rate_hz: f32,
    n: f32,
) -> [f32; 4] {
    let t_c = n / sample_rate_hz;
    let weights = weights(dynamics, design, n, t_c);
    let aliases = aliases(dynamics, sample_rate_hz, n);
    let (mut sum, mut own, mut own2) = ([0.0f32; 2], [0.0f32; 2], [0.0f32; 2]);
    let mut count = 0.0f32;
    for p in 0..PHASES {
        let phase = (p as f32 + 0.5) / PHASES as f32 - 0.5;
        let (Some(rigid), Some(chain)) = (
            fit(n, phase, &aliases, None),
            fit(n, phase, &aliases, Some(&weights)),
        ) else {
            continue;
        };
        for i in 0..2 {
            let (c, r) = (chain.get(i).copied(), rigid.get(i).copied());
            let c = M::ln(c.unwrap_or(1.0));
            let d = c - M::ln(r.unwrap_or(1.0));
            if let (Some(s), Some(o), Some(o2)) = (sum.get_mut(i), own.get_mut(i), own2.get_mut(i))
            {
                *s += d;
                *o += c;
                *o2 += c * c;
            }
        }
        count += 1.0;
    }
    if count == 0.0 {
        return [0.0; 4];
    }
    let mean = sum.map(|s| s / count);
    let spread = |i: usize| {
        let m = own.get(i).copied().unwrap_or(0.0) / count;
        let s2 = own2.get(i).copied().unwrap_or(0.0);
        M::sqrt((s2 / count - m * m).max(0.0))
    };
    let [lf, lt] = mean;
    [lf, lt, spread(0), spread(1)]
}

/// Trapezoid weights `(R(v_i) - 1) S1(v_i) h_i / pi` at `v_i = i STEP_V`, for pulses of
/// `t_c` (s) at `n` samples per pulse.
#[inline(never)]
fn weights(d: &ChainDynamics, q: &EqualiserDesign, n: f32, t_c: f32) -> [C; HERTZ_SPECTRUM.len()] {
    let mut w = [C::default(); HERTZ_SPECTRUM.len()];
    let last = HERTZ_SPECTRUM.len() - 1;
    for (i, (slot, &s1)) in w.iter_mut().zip(HERTZ_SPECTRUM.iter()).enumerate() {
        let v = i as f32 * STEP_V;
        let r = chain_term(C::new(0.0, v / t_c), d).mul(q.response(v / n));
        let trapezoid = if i == 0 || i == last { 0.5 } else { 1.0 };
        *slot = r
            .sub(C::new(1.0, 0.0))
            .scale(s1 * trapezoid * STEP_V / core::f32::consts::PI);
    }
    w
}

/// Aliases `m = 1, 2` of the sum: `H(j 2 pi m f_s) - 1` and `S1(2 pi m n)`.
#[inline(never)]
fn aliases(d: &ChainDynamics, sample_rate_hz: f32, n: f32) -> [(C, f32); 2] {
    let tau = core::f32::consts::TAU;
    [1.0f32, 2.0].map(|m| {
        let h = chain_term(C::new(0.0, tau * m * sample_rate_hz), d);
        (h.sub(C::new(1.0, 0.0)), spectrum(tau * m * n))
    })
}

/// `S1(v)` interpolated in [`HERTZ_SPECTRUM`]; 0 past [`MAX_V`].
fn spectrum(v: f32) -> f32 {
    if v.is_nan() || v > MAX_V {
        return 0.0;
    }
    let at = math::table_position(v / STEP_V, HERTZ_SPECTRUM.len());
    math::interpolate(&HERTZ_SPECTRUM, at)
}

/// The kernel's pulse shape `P(x) = cos^(3/2)(pi x)` on `|x| < 1/2`, else 0.
#[inline(never)]
fn shape(x: f32) -> f32 {
    if x.abs() >= 0.5 {
        return 0.0;
    }
    // cos(pi x) = sin(pi (x + 1/2)), with the argument in [0, pi] as `sin_cos` takes it.
    let c = math::sin_cos(core::f32::consts::PI * (x + 0.5)).0;
    c * M::sqrt(c)
}

/// The detector's fit `[F, t]` of the pulse sampled at `x_j = (j + phase) / n`: rigid
/// (`weights` `None`), or equalised.
#[inline(never)]
fn fit(n: f32, phase: f32, aliases: &[(C, f32); 2], weights: Option<&[C]>) -> Option<[f32; 2]> {
    let mut y = [0.0f32; AROUND];
    for (j, slot) in y.iter_mut().enumerate() {
        let x = (j as f32 - 3.0 + phase) / n;
        *slot = shape(x) + weights.map_or(0.0, |w| residual_at(w, x));
    }
    let mut sum = n * HERTZ_SPECTRUM.first().copied().unwrap_or(0.0);
    for (m, &(h1, s1)) in aliases.iter().enumerate() {
        let turn = cis(core::f32::consts::TAU * (m + 1) as f32 * phase);
        let h = if weights.is_some() { h1 } else { C::default() };
        sum += 2.0 * n * s1 * turn.add(h.mul(turn)).re;
    }
    let (i, _) = (2..AROUND - 2)
        .filter_map(|i| y.get(i).map(|&v| (i, v)))
        .fold((3, f32::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
    // The detector's fit for the undamped Hertz pulse this models.
    let (f, t) = shape_fit::<M>(five_about(&y, i), sum, true)?;
    Some([f, t])
}

/// `(1 / pi) int_0^MAX_V Re((R - 1) e^(j v x)) S1(v) dv` from the trapezoid weights.
#[inline(never)]
fn residual_at(weights: &[C], x: f32) -> f32 {
    let step = cis(STEP_V * x);
    let mut rot = C::new(1.0, 0.0);
    let mut acc = 0.0f32;
    for w in weights {
        acc += w.mul(rot).re;
        rot = rot.mul(step);
    }
    acc
}
