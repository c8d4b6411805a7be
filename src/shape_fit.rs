//! The Hertz pulse's shape as the detector reads it: its area and energy over `F_max t_c`,
//! its shape about the peak, and the fit of a sampled pulse's peak and duration from its
//! largest sample, the two samples either side of it and the sum of its samples.

use crate::math::{self, Backend};

/// Area of the Hertz pulse over `F_max t_c`: `C_AREA = 1.6 / 2.9432752 = 0.5436104` (the
/// impulse `2 m u` over `F_max t_c`).
pub const C_AREA: f32 = 0.543_612_1;

/// Energy `integral F^2 dt` of the Hertz pulse over `F_max^2 t_c`:
/// `C_ENERGY = 2 B(8/5, 1/2) / (2.5 * 2.9432752) = 0.4113417`.
pub const C_ENERGY: f32 = 0.411_341_7;

/// Phase rate of `z = F^(2/3)` at the peak, in rad per `t_c`: the Hertz pulse bends there like
/// `cos(PEAK_OMEGA t / t_c)`, with `PEAK_OMEGA = sqrt(5/4) 2.9432752` (from `z'' = -(5/4) z`
/// at the peak, in the units `delta_max / u` where `t_c = 2.9432752`): 4.7 % faster than the
/// `pi` of a sine.
pub const PEAK_OMEGA: f32 = 3.290_681;

/// Largest phase step per sample, `PEAK_OMEGA / n` rad for `n` samples per pulse, at which the
/// peak is fitted through five samples (from `n = 7.8`): the window's ends then lie within
/// `|x| <= 2.5 * 0.42 = 1.05` of the top, inside the pulse (`|x| < PEAK_OMEGA / 2 = 1.645`)
/// where [`peak_shape`]'s series holds to 3e-7. Above it three samples are used.
pub const FIVE_POINT_STEP: f32 = 0.42;

/// Taylor coefficients of [`peak_shape`]'s `h` in `x^2`.
const PEAK_SERIES: [f32; 7] = [
    1.0,
    -0.5,
    0.0625,
    -0.00625,
    4.464_285_7e-4,
    -3.348_214e-5,
    1.648_741_9e-6,
];

/// The Hertz pulse about its top: `z = F^(2/3)` over its largest value is `h(x)`, with
/// `x = PEAK_OMEGA (t - t_peak) / t_c` (`m delta'' = -k delta^(3/2)` in these units is
/// `h'' = -h^(3/2)`, `h(0) = 1`, `h'(0) = 0`), whose Taylor series is
/// `h = 1 - x^2/2 + x^4/16 - x^6/160 + x^8/2240 - 3 x^10/89600 + 1.648742e-6 x^12`
/// (the next term, `-1.6e-7 x^14`, is below 3e-7 for `|x| <= 1.05`; the series' own zero is
/// the pulse's end `PEAK_OMEGA / 2`). Returns the force's shape `g = F / F_max = h^(3/2)`
/// and its slope `dg/dx = (3/2) h^(1/2) dh/dx`, both 0 where `h <= 0`.
#[inline]
pub fn peak_shape<M: Backend>(x: f32) -> (f32, f32) {
    let s = x * x;
    let (mut h, mut slope) = (0.0f32, 0.0f32);
    for (j, &a) in PEAK_SERIES.iter().enumerate().rev() {
        h = h * s + a;
        // dh/dx = x sum_j 2 j a_j s^(j-1): the terms from j = 1 on, one power lower.
        if j > 0 {
            slope = slope * s + 2.0 * j as f32 * a;
        }
    }
    if h <= 0.0 {
        return (0.0, 0.0);
    }
    let root = M::sqrt(h);
    (h * root, 1.5 * root * slope * x)
}

/// A pulse's peak and duration as the fit reads them, with what the noise does to the peak.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakFit {
    /// Peak `F_max` (counts).
    pub peak: f32,
    /// Duration `t_c = sum / (C_AREA F_max)` (samples).
    pub duration: f32,
    /// Variance of the peak over that of one sample's white noise: `var F_max = gain2
    /// sigma^2` (the least-squares `[(J^T J)^-1]_AA`; 1 for three samples).
    pub gain2: f32,
    /// Sum of the peak's weights over the samples, `sum_k dF_max / dy_k`: the peak shares
    /// `sigma^2 weight_sum` of covariance with the pulse's sum (1 for three samples).
    pub weight_sum: f32,
}

/// The five samples of `y` about index `i`, `[y_(i-2), .., y_(i+2)]`, 0 where `y` has none:
/// what [`shape_fit`] takes about a pulse's largest sample.
pub fn five_about(y: &[f32], i: usize) -> [f32; 5] {
    core::array::from_fn(|k| {
        (i + k)
            .checked_sub(2)
            .and_then(|j| y.get(j))
            .copied()
            .unwrap_or(0.0)
    })
}

/// Peak (counts) and duration (samples) of a sampled Hertz pulse from its five samples about
/// the largest, `top = [y_-2, y_-1, y_0, y_1, y_2]` (`y_0` the largest), and the sum of all its
/// samples; `None` when they are not a positive pulse. See [`peak_fit`].
pub fn shape_fit<M: Backend>(top: [f32; 5], sum: f32) -> Option<(f32, f32)> {
    peak_fit::<M>(top, sum).map(|f| (f.peak, f.duration))
}

/// The fit behind [`shape_fit`], with its noise gains. `F_max` and `t_c = sum / (C_AREA
/// F_max)` are iterated three times; with the phase step `d = PEAK_OMEGA / t_c` per sample:
///
/// - `d <= FIVE_POINT_STEP` (7.8 samples per pulse or more): one Gauss-Newton step of the
///   least-squares fit of `F_max g(d (k - k_peak))` ([`peak_shape`]) to the five samples, in
///   `F_max` and the offset `k_peak` (samples, from 0, kept within one sample). The largest
///   of single noisy samples, which three samples lean on, is biased high by the noise;
///   the five samples' fit is not, to first order, and its noise is smaller.
/// - Otherwise `z = F^(2/3) = F_max^(2/3) sin(pi t / t_c)` is taken as a sinusoid of known
///   frequency, so `z_0` and its larger neighbour `z_1` give the offset `theta` of the true
///   peak, `tan theta = (z_1/z_0 - cos d) / sin d`, and `F_max = (z_0 / cos theta)^(3/2)` with
///   `|theta| <= d/2`.
pub fn peak_fit<M: Backend>(top: [f32; 5], sum: f32) -> Option<PeakFit> {
    let [_, before, y0, after, _] = top;
    if !(y0 > 0.0 && sum > 0.0 && y0.is_finite() && sum.is_finite()) {
        return None;
    }
    let z = |y: f32| if y > 0.0 { M::pow_2_3(y) } else { 0.0 };
    let (z0, za, zb) = (z(y0), z(before.min(y0)), z(after.min(y0)));
    let mut fit = PeakFit {
        peak: y0,
        duration: sum / (C_AREA * y0),
        gain2: 1.0,
        weight_sum: 1.0,
    };
    for _ in 0..3 {
        fit.peak = three_point::<M>(z0, za.max(zb), step(fit.duration));
        fit.duration = sum / (C_AREA * fit.peak);
    }
    let d = step(fit.duration);
    if d <= FIVE_POINT_STEP {
        let mut p = [fit.peak, 0.0, d];
        for _ in 0..3 {
            let Some(gains) = five_point::<M>(&top, &mut p, d) else {
                break;
            };
            (fit.peak, fit.gain2, fit.weight_sum) = (p[0], gains.0, gains.1);
        }
        fit.duration = sum / (C_AREA * fit.peak);
    }
    (fit.peak.is_finite() && fit.duration.is_finite() && fit.peak > 0.0 && fit.duration > 0.0)
        .then_some(fit)
}

/// Phase step per sample of a pulse of `duration` samples, `PEAK_OMEGA / duration`; a pulse
/// shorter than one sample is clamped to one.
fn step(duration: f32) -> f32 {
    (PEAK_OMEGA / duration).min(core::f32::consts::PI)
}

/// The peak through the largest `z` sample `z0` and its larger neighbour `z1` with the phase
/// step `d` (see [`peak_fit`]).
fn three_point<M: Backend>(z0: f32, z1: f32, d: f32) -> f32 {
    let (sh, ch) = math::sin_cos(0.5 * d.min(core::f32::consts::FRAC_PI_2));
    let (s, c) = math::sin_cos(d);
    let t = ((z1 / z0 - c) / s).max(0.0).min(sh / ch);
    let b = z0 * M::sqrt(1.0 + t * t);
    M::pow_3_2(b.max(z0).min(z0 / ch))
}

/// One Gauss-Newton step of the five-sample fit of `F_max g(d (k - k_peak))` in
/// `p = [F_max, k_peak, d]` (updated in place; `k_peak` kept within one sample of the largest,
/// `d` within a factor 1.25 of `d_area`, the area's): `(gain2, weight_sum)` of the step's
/// normal equations, `None` when they are singular or the peak leaves the positive.
fn five_point<M: Backend>(top: &[f32; 5], p: &mut [f32; 3], d_area: f32) -> Option<(f32, f32)> {
    let [peak, offset, d] = *p;
    // Normal equations `n`, right side `b` and column sums `c` of the columns
    // dm/dF_max = g, dm/dk_peak = -F_max d g', dm/dd = F_max (k - k_peak) g'.
    let (mut n, mut b, mut c) = ([[0.0f32; 3]; 3], [0.0f32; 3], [0.0f32; 3]);
    for (k, &y) in top.iter().enumerate() {
        let t = k as f32 - 2.0 - offset;
        let (g, slope) = peak_shape::<M>(d * t);
        let j = [g, -peak * d * slope, peak * t * slope];
        let r = y - peak * g;
        for (((&ja, ba), ca), row) in j.iter().zip(&mut b).zip(&mut c).zip(&mut n) {
            *ba += ja * r;
            *ca += ja;
            for (nab, &jb) in row.iter_mut().zip(&j) {
                *nab += ja * jb;
            }
        }
    }
    let inv = inverse3(&n)?;
    let dot = |row: &[f32; 3], v: &[f32; 3]| row[0] * v[0] + row[1] * v[1] + row[2] * v[2];
    let new_peak = peak + dot(&inv[0], &b);
    if new_peak.is_nan() || new_peak <= 0.0 {
        return None;
    }
    *p = [
        new_peak,
        (offset + dot(&inv[1], &b)).clamp(-1.0, 1.0),
        (d + dot(&inv[2], &b)).clamp(0.8 * d_area, 1.25 * d_area),
    ];
    Some((inv[0][0], dot(&inv[0], &c)))
}

/// The inverse of the symmetric 3 x 3 matrix `n` by its cofactors; `None` when it is
/// singular to within f32 (determinant below `1e-6` of its diagonal's product).
fn inverse3(n: &[[f32; 3]; 3]) -> Option<[[f32; 3]; 3]> {
    let [[a, b, c], [_, e, f], [_, _, i]] = *n;
    let cof = [
        [e * i - f * f, c * f - b * i, b * f - c * e],
        [c * f - b * i, a * i - c * c, b * c - a * f],
        [b * f - c * e, b * c - a * f, a * e - b * b],
    ];
    let det = a * cof[0][0] + b * cof[0][1] + c * cof[0][2];
    if det.is_nan() || det.abs() <= 1e-6 * (a * e * i).abs() {
        return None;
    }
    Some(cof.map(|row| row.map(|v| v / det)))
}
