//! The bias the equaliser itself leaves in a short pulse: at a few samples per pulse the
//! regularised accelerometer inverse (and the modes' discretisation) reshape the Hertz pulse,
//! and the detector's fit then reads its peak low and its duration long. Computed at build per
//! point of the sampling correction, and added to the scene's [`SampledCalibration`]; and the
//! largest error it leaves in one sample ([`sample_error`]), which a clipped pulse's flank fit
//! counts.
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

/// Points `x` (in pulse lengths from its middle) at which [`sample_error`] takes the error,
/// in each of three sets: 49 in steps of 1/32 from a quarter of the pulse before it to a
/// quarter after, and 49 about each end (the kinks, where the error is largest and as
/// narrow as a sample) in steps of 1/8 sample over [`KINK_SAMPLES`] either side.
const ERROR_XS: usize = 49;

/// Samples either side of an end of the pulse in which [`sample_error`] takes the error
/// at the ends: the accelerometer's FIR spans two either side of a sample.
pub const KINK_SAMPLES: f32 = 3.0;

/// How far [`sample_error`] integrates, in `v = w t_c`: the kink at a Hertz pulse's start
/// puts a tail `S1 ~ v^(-5/2)` into its spectrum, which the equaliser cannot follow near
/// and past the Nyquist frequency (`v = pi n`); past this the rest is bounded (`far_tail`).
const ERROR_MAX_V: f32 = 2048.0;

/// The step in `v` past [`MAX_V`] (`S1` and `e^(j v x)` turn by at most 1/8 of a period).
const FAR_STEP_V: f32 = 1.0;

/// The largest error the equaliser leaves in one sample of the kernel's Hertz pulse at `n`
/// samples per pulse, as a fraction of its peak, `[in the body, at the ends]`: `max |y(x) -
/// P(x)|` (module docs) over points `x` (`ERROR_XS` per set) from a quarter of the pulse
/// before it to a quarter after, at the ends over those within [`KINK_SAMPLES`] of an end
/// (the kinks `t^(3/2)` at the contact's start and end, whose spectrum falls slowest), in
/// the body over the others. The integral is taken to `ERROR_MAX_V` (the table
/// [`HERTZ_SPECTRUM`] to [`MAX_V`], then the closed form, `far_spectrum`) and bounded past
/// it. 0 for a rigid chain. The flank fit of a clipped pulse counts it beside its table's
/// error.
///
/// ```
/// use coalshock::chain_residual::sample_error;
/// use coalshock::equaliser::{Accelerometer, ChainDynamics, EqualiserDesign};
/// use coalshock::math::Libm;
/// let rigid = ChainDynamics::RIGID;
/// let identity = EqualiserDesign::new::<Libm>(&rigid, 1e5).unwrap();
/// assert_eq!(sample_error(&rigid, &identity, 1e5, 8.0), [0.0; 2]);
/// // A 40 kHz piezo (zeta 0.05) at 100 kS/s: the error falls with the pulse's length,
/// // slowest at the kinks (host-sim's exact chain: 2.1e-2 and 1.5e-3 at the ends).
/// let piezo = rigid.with_accelerometer(Accelerometer {
///     frequency_hz: 40e3,
///     damping_ratio: 0.05,
/// });
/// let design = EqualiserDesign::new::<Libm>(&piezo, 1e5).unwrap();
/// let [body8, ends8] = sample_error(&piezo, &design, 1e5, 8.0);
/// let [body45, ends45] = sample_error(&piezo, &design, 1e5, 45.0);
/// assert!(body8 < ends8 && body45 < ends45 && ends45 < ends8);
/// assert!((ends8 / 2.1e-2 - 1.0).abs() < 0.05 && (ends45 / 1.5e-3 - 1.0).abs() < 0.05);
/// ```
#[inline(never)]
pub fn sample_error(
    dynamics: &ChainDynamics,
    design: &EqualiserDesign,
    sample_rate_hz: f32,
    n: f32,
) -> [f32; 2] {
    if design.is_identity() || n.is_nan() || n <= 0.0 {
        return [0.0; 2];
    }
    let t_c = n / sample_rate_hz;
    let r = |v: f32| chain_term(C::new(0.0, v / t_c), dynamics).mul(design.response(v / n));
    let kink = |end: f32| move |k: usize| end + (k as f32 - 24.0) / (8.0 * n);
    let grid = error_integral(r, |k| k as f32 / 32.0 - 0.75);
    let start = error_integral(r, kink(-0.5));
    let end = error_integral(r, kink(0.5));
    let tail = far_tail(ERROR_MAX_V);
    let largest = |a: &[f32]| a.iter().fold(0.0f32, |m, e| m.max(e.abs())) + tail;
    let within = KINK_SAMPLES / n;
    let body = grid.iter().enumerate().filter(|&(k, _)| {
        let x = k as f32 / 32.0 - 0.75;
        (libm::fabsf(x) - 0.5).abs() > within
    });
    // The body's largest error lies at its edge, [`KINK_SAMPLES`] from an end: the kinks'
    // outermost points.
    let edges = [start, end].map(|a| [a.first(), a.last()].map(|e| e.map_or(0.0, |e| e.abs())));
    let edge = edges.iter().flatten().fold(0.0f32, |m, &e| m.max(e));
    let body = body.fold(edge, |m, (_, e)| m.max(e.abs())) + tail;
    [body, largest(&start).max(largest(&end))]
}

/// The largest error of a raw sample of the kernel's Hertz pulse at `n` samples per pulse
/// against the force `lag` samples before it, as a fraction of its peak, over the middle
/// half of the pulse (where it clips): `max |y(x) - P(x - lag / n)|` with `y` the chain's
/// continuous output, the module docs' integral with `R(w) = H(jw) e^(j w lag T)` in place of
/// `H Q` (taken as [`sample_error`] takes it). 0 for a rigid chain. An accelerometer whose
/// resonance lies near the pulse's band raises the raw top above the force's; a clipped
/// pulse's flank fit allows the force this far below the level at a clipped sample.
///
/// ```
/// use coalshock::chain_residual::raw_error;
/// use coalshock::equaliser::{Accelerometer, ChainDynamics};
/// assert_eq!(raw_error(&ChainDynamics::RIGID, 1e5, 8.0, 0.0), 0.0);
/// // A 7.5 kHz MEMS band (zeta 0.43) at 26.7 kS/s: its top overshoots a short pulse's.
/// let mems = ChainDynamics::RIGID.with_accelerometer(Accelerometer {
///     frequency_hz: 7.5e3,
///     damping_ratio: 0.43,
/// });
/// let lag = 0.43 * 26.7e3 / (core::f32::consts::PI * 7.5e3);
/// let (short, long) = (raw_error(&mems, 26.7e3, 6.0, lag), raw_error(&mems, 26.7e3, 24.0, lag));
/// assert!(short > 0.01 && long < short);
/// ```
#[inline(never)]
pub fn raw_error(dynamics: &ChainDynamics, sample_rate_hz: f32, n: f32, lag: f32) -> f32 {
    if dynamics.is_rigid() || n.is_nan() || n <= 0.0 {
        return 0.0;
    }
    let t_c = n / sample_rate_hz;
    let r = |v: f32| chain_term(C::new(0.0, v / t_c), dynamics).mul(cis(v * lag / n));
    let middle = error_integral(r, |k| (k as f32 - 24.0) / 96.0);
    middle.iter().fold(0.0f32, |m, e| m.max(e.abs())) + far_tail(ERROR_MAX_V)
}

/// `y(x) - P(x)` at the points `x_at(k)`, `k < ERROR_XS`, for a response `r(v)` over
/// `v = w t_c`: the trapezoid rule of the module docs' integral of `(r - 1) S1` in steps of
/// [`STEP_V`] to [`MAX_V`], then of [`FAR_STEP_V`] to [`ERROR_MAX_V`], each `e^(j v x)`
/// turned by its step.
#[inline(never)]
fn error_integral(r: impl Fn(f32) -> C, x_at: impl Fn(usize) -> f32) -> [f32; ERROR_XS] {
    let mut acc = [0.0f32; ERROR_XS];
    let mut turn = [C::new(1.0, 0.0); ERROR_XS];
    let mut step: [C; ERROR_XS] = core::array::from_fn(|k| cis(STEP_V * x_at(k)));
    let near = (MAX_V / STEP_V) as usize;
    let far = ((ERROR_MAX_V - MAX_V) / FAR_STEP_V) as usize;
    for i in 0..=near + far {
        let (v, h, s1) = if i <= near {
            let h = match i {
                0 => 0.5 * STEP_V,
                i if i == near => 0.5 * (STEP_V + FAR_STEP_V),
                _ => STEP_V,
            };
            let v = i as f32 * STEP_V;
            (v, h, spectrum(v))
        } else {
            let v = MAX_V + (i - near) as f32 * FAR_STEP_V;
            let h = if i == near + far { 0.5 } else { 1.0 } * FAR_STEP_V;
            (v, h, far_spectrum(v))
        };
        if i == near {
            step = core::array::from_fn(|k| cis(FAR_STEP_V * x_at(k)));
        }
        let w = r(v)
            .sub(C::new(1.0, 0.0))
            .scale(s1 * h / core::f32::consts::PI);
        for ((a, t), s) in acc.iter_mut().zip(turn.iter_mut()).zip(&step) {
            *a += w.mul(*t).re;
            *t = t.mul(*s);
        }
    }
    acc
}

/// `S1(v)` past [`MAX_V`] in closed form, `Gamma(5/2) sin(pi (7/4 - a)) Gamma(a - 3/4) /
/// (2^(3/2) pi Gamma(a + 7/4))` with `a = v / (2 pi)` (the reflection of [`HERTZ_SPECTRUM`]'s
/// form), the ratio of Gammas through `lgamma`.
fn far_spectrum(v: f32) -> f32 {
    let a = v / core::f32::consts::TAU;
    let ratio = libm::expf(libm::lgammaf(a - 0.75) - libm::lgammaf(a + 1.75));
    let gamma_5_2 = 1.329_340_4;
    let sin = libm::sinf(core::f32::consts::PI * (1.75 - a));
    gamma_5_2 * sin * ratio / (2.0 * core::f32::consts::SQRT_2 * core::f32::consts::PI)
}

/// A bound of the error integral past `v`: `(1 / pi) int_v^inf |R - 1| |S1| dv` with
/// `|R - 1| <= 2` and `|S1| <= 14.8 v^(-5/2)` (`far_spectrum`'s envelope), `6.3 v^(-3/2)`.
fn far_tail(v: f32) -> f32 {
    2.0 * 14.8 * (2.0 / 3.0) / core::f32::consts::PI / (v * libm::sqrtf(v))
}
