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
/// where [`peak_shape`]'s series holds to 2e-7. Above it three samples are used.
pub const FIVE_POINT_STEP: f32 = 0.42;

/// Taylor coefficients of [`peak_shape`]'s `g` in `x^2`.
const PEAK_SERIES: [f32; 10] = [
    1.0,
    -0.75,
    0.1875,
    -0.025,
    3.013_393e-3,
    -2.176_339_3e-4,
    2.967_735_4e-5,
    7.066_037e-7,
    6.807_855e-7,
    1.501e-7,
];

/// The Hertz pulse about its top, `g(x) = F / F_max` with `x = PEAK_OMEGA (t - t_peak) / t_c`:
/// `g = h^(3/2)` where `h = z / z_max` (`z = F^(2/3)`, the indentation) solves `m delta'' = -k
/// delta^(3/2)`, in these units `h'' = -h^(3/2)`, `h(0) = 1`, `h'(0) = 0`. Its Taylor series in
/// `x^2`, from that equation's recursion, is `g = 1 - (3/4) x^2 + (3/16) x^4 - x^6/40 +
/// 3.0134e-3 x^8 - 2.1763e-4 x^10 + ...`, taken to `x^18` (within 2e-7 of the series to `x^40`
/// for `|x| <= 1.05`; the pulse ends at `x = PEAK_OMEGA / 2 = 1.645`, the series' radius).
/// Returns `(g, dg/dx)`.
#[inline]
pub fn peak_shape(x: f32) -> (f32, f32) {
    let s = x * x;
    let (mut g, mut slope) = (0.0f32, 0.0f32);
    for (j, &a) in PEAK_SERIES.iter().enumerate().rev() {
        g = g * s + a;
        // dg/dx = x sum_j 2 j a_j s^(j-1): the terms from j = 1 on, one power lower.
        if j > 0 {
            slope = slope * s + 2.0 * j as f32 * a;
        }
    }
    (g, slope * x)
}

/// A pulse's peak and duration as the fit reads them, with what the noise does to the peak.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakFit {
    /// Peak `F_max` (counts).
    pub peak: f32,
    /// Duration `t_c = sum / (C_AREA F_max)` (samples).
    pub duration: f32,
    /// Variance of the peak over that of one sample's white noise: `var F_max = gain2
    /// sigma^2` (the least-squares `[(J^T J)^-1]_AA` for five samples; for three, from the
    /// derivatives of their closed form, see [`peak_fit`]).
    pub gain2: f32,
    /// Sum of the peak's weights over the samples, `sum_k dF_max / dy_k`: the peak shares
    /// `sigma^2 weight_sum` of covariance with the pulse's sum.
    pub weight_sum: f32,
    /// What the vertex's second-order bias takes, `[(3/4) d^2, [N^-1]_kk]` (`[0, 0]` but for
    /// the five samples' fit): where the fit places the top between the samples is noisy,
    /// with variance `var k_peak = noise^2 [N^-1]_kk` (samples^2), and the fitted top `F_max
    /// g(x)`, `g = 1 - (3/4) x^2 + ..` at `x = d (k - k_peak)`, lies above the samples by
    /// `(3/4) d^2 var k_peak` of `F_max` on average, the least-squares vertex's bias (Box
    /// 1971). The fit keeps `k_peak` within one sample of the largest, and the top lies within
    /// half a sample of it, so `|k_peak - k_top| <= 1.5` and `var k_peak` is taken at most
    /// `2.25` (the detector's `unbiased_vertex`).
    pub vertex_bias: [f32; 2],
    /// What [`PeakFit::weights`] computes the peak's weights from.
    #[cfg(feature = "noise_colour")]
    pub(crate) basis: WeightBasis,
}

/// What a [`PeakFit`]'s weights `dF_max / dy_k` come from ([`PeakFit::weights`]): the three
/// samples' weights themselves (their white-noise gains are taken from them), or the point of
/// the five samples' last step, from which only a detector behind a chain computes them.
#[cfg(feature = "noise_colour")]
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum WeightBasis {
    /// The largest sample alone carries the peak.
    Largest,
    /// The three samples' closed form ([`peak_fit`]): the weights its white-noise gains took.
    Three(ThreeWeights),
    /// The five samples' fit, whose last step was taken from `p = [F_max, k_peak, d]`.
    Five([f32; 3]),
}

#[cfg(feature = "noise_colour")]
impl PeakFit {
    /// The peak's weights `dF_max / dy_k`: on the five samples about the largest
    /// (`[y_-2, .., y_2]`), and on every sample of the pulse's sum (through the duration the
    /// three samples' fit takes from it; 0 for the five samples' fit, whose weights are
    /// `[N^-1 J^T]_(0 k)` of its last step's normal equations). What coloured noise needs
    /// ([`crate::noise_colour::NoiseColour::weighted`]); white noise needs only `gain2` and
    /// `weight_sum` (`sum_k w_k^2` and `sum_k w_k`).
    pub fn weights(&self) -> ([f32; 5], f32) {
        match self.basis {
            WeightBasis::Largest => ([0.0, 0.0, 1.0, 0.0, 0.0], 0.0),
            WeightBasis::Three(w) => w.on_five(),
            WeightBasis::Five(p) => (five_point_weights(p), 0.0),
        }
    }
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
pub fn shape_fit<M: Backend>(top: [f32; 5], sum: f32, five: bool) -> Option<(f32, f32)> {
    // The noise gains, which take the number of samples in `sum`, are not returned.
    peak_fit::<M>(top, sum, 0.0, five).map(|f| (f.peak, f.duration))
}

/// The fit behind [`shape_fit`], with its noise gains. `F_max` and `t_c = sum / (C_AREA
/// F_max)` are iterated three times; with the phase step `d = PEAK_OMEGA / t_c` per sample:
///
/// - `five` (every pulse of the scene has one shape: the Hertz law's, whose shape the fit
///   takes, or a restitution-parametrised damped law's, whose difference from it the scene's
///   sampling correction measures with this same fit; a yielding top, or a damped law whose
///   shape changes with size and speed, is read as below) and
///   `d <= FIVE_POINT_STEP` (7.8 samples per pulse or more): Gauss-Newton steps of the
///   least-squares fit of `F_max g(d (k - k_peak))` ([`peak_shape`]) to the five samples, in
///   `F_max`, the offset `k_peak` and the phase step `d` (two Gauss-Newton steps from the
///   three samples' peak). The largest
///   of single noisy samples, which three samples lean on, is biased high by the noise;
///   the five samples' fit is not, to first order, and its noise is smaller.
/// - Otherwise `z = F^(2/3) = F_max^(2/3) sin(pi t / t_c)` is taken as a sinusoid of known
///   frequency, so `z_0` and its larger neighbour `z_1` give the offset `theta` of the true
///   peak, `tan theta = (z_1/z_0 - cos d) / sin d`, and `F_max = (z_0 / cos theta)^(3/2)` with
///   `|theta| <= d/2`. Its noise gains come from the derivatives of this closed form in the
///   two samples and, through `d = PEAK_OMEGA C_AREA F_max / sum`, in the `samples` samples
///   of the sum, carried through the three iterations.
pub fn peak_fit<M: Backend>(top: [f32; 5], sum: f32, samples: f32, five: bool) -> Option<PeakFit> {
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
        vertex_bias: [0.0; 2],
        #[cfg(feature = "noise_colour")]
        basis: WeightBasis::Largest,
    };
    // The larger neighbour, its index among the five, and its sample (no larger than `y0`).
    let (at1, y1, z1) = if zb > za {
        (3, after, zb)
    } else {
        (1, before, za)
    };
    let y1 = y1.min(y0);
    // `dln F_max / d(ln y_0, ln y_1, ln sum)` of the iterate, from `F_max = y_0`; each step's
    // `d = PEAK_OMEGA C_AREA F_max / sum` (until it is held at pi) carries the last one's.
    let mut a = [1.0, 0.0, 0.0];
    for _ in 0..3 {
        let d = step(fit.duration);
        let top3 = three_point::<M>(z0, z1, d);
        let kappa = if d < core::f32::consts::PI {
            top3.kappa
        } else {
            0.0
        };
        a = [
            top3.e0 + kappa * a[0],
            top3.e1 + kappa * a[1],
            kappa * (a[2] - 1.0),
        ];
        fit.peak = top3.peak;
        fit.duration = sum / (C_AREA * fit.peak);
    }
    let weights = ThreeWeights::new(a, fit.peak, y0, y1, at1, sum);
    (fit.gain2, fit.weight_sum) = weights.white_gains(samples);
    #[cfg(feature = "noise_colour")]
    {
        fit.basis = WeightBasis::Three(weights);
    }
    let d = step(fit.duration);
    if five && d <= FIVE_POINT_STEP {
        let mut p = [fit.peak, 0.0, d];
        for _ in 0..2 {
            #[cfg(feature = "noise_colour")]
            let from = p;
            let Some(gains) = five_point(&top, &mut p, d) else {
                break;
            };
            (fit.peak, fit.gain2, fit.weight_sum) = (p[0], gains.0, gains.1);
            fit.vertex_bias = [0.75 * p[2] * p[2], gains.2];
            #[cfg(feature = "noise_colour")]
            {
                fit.basis = WeightBasis::Five(from);
            }
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

/// The three samples' peak `F = (z_0 sqrt(1 + t^2))^(3/2)` (`t = tan theta`, see
/// [`peak_fit`]) and how it moves: `e_0 = dln F / dln y_0 = 1 - q`, `e_1 = dln F / dln y_1 =
/// q` with `q = t r / ((1 + t^2) sin d)` and `r = z_1 / z_0`, and `kappa = dln F / dln d =
/// (3/2) d t dt/dd / (1 + t^2)` with `dt/dd = (1 - r cos d) / sin^2 d`. Where `t` is held at
/// 0 (the top sample on the peak) all three derivatives of `t` are 0; at its upper bound
/// (`z_1 = z_0`, the peak midway) they are the free formulas' limit, since noise takes `z_1`
/// below `z_0` either way, except past `d = pi/2`, where the bound no longer moves with `d`.
#[derive(Debug, Clone, Copy)]
struct ThreePoint {
    peak: f32,
    e0: f32,
    e1: f32,
    kappa: f32,
}

/// The peak through the largest `z` sample `z0` and its larger neighbour `z1` with the phase
/// step `d` (see [`peak_fit`]).
fn three_point<M: Backend>(z0: f32, z1: f32, d: f32) -> ThreePoint {
    let (sh, ch) = math::sin_cos(0.5 * d.min(core::f32::consts::FRAC_PI_2));
    let (s, c) = math::sin_cos(d);
    let r = z1 / z0;
    let free = (r - c) / s;
    let t = free.max(0.0).min(sh / ch);
    let b = z0 * M::sqrt(1.0 + t * t);
    let moves = free > 0.0 && (free < sh / ch || d < core::f32::consts::FRAC_PI_2);
    let (q, kappa) = if moves {
        let one_t2 = 1.0 + t * t;
        (
            t * r / (one_t2 * s),
            1.5 * d * t * (1.0 - r * c) / (one_t2 * s * s),
        )
    } else {
        (0.0, 0.0)
    };
    ThreePoint {
        peak: M::pow_3_2(b.max(z0).min(z0 / ch)),
        e0: 1.0 - q,
        e1: q,
        kappa,
    }
}

/// The three samples' peak's weights `dF_max / dy_k` ([`peak_fit`]), from `a`, the
/// derivatives of `ln F_max` in `(ln y_0, ln y_1, ln sum)` carried through the fit's
/// iterations: `F_max a_0 / y_0` on the largest sample, `F_max a_1 / y_1` on its larger
/// neighbour (index `at1` of the five about the largest; 0 where that sample is not
/// positive), and `F_max a_s / sum` on every sample of the sum, those two included.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ThreeWeights {
    largest: f32,
    neighbour: f32,
    /// Only the noise's colour places the weights on the five samples ([`Self::on_five`]).
    #[cfg(feature = "noise_colour")]
    at1: usize,
    per_sample: f32,
}

impl ThreeWeights {
    /// The weights of the peak `f` from `a`, the largest sample `y0`, its larger neighbour
    /// `y1` at index `at1` and the pulse's `sum`; the largest sample's alone where they are
    /// not finite.
    fn new(a: [f32; 3], f: f32, y0: f32, y1: f32, at1: usize, sum: f32) -> Self {
        #[cfg(not(feature = "noise_colour"))]
        let _ = at1;
        let w = Self {
            largest: f * a[0] / y0,
            neighbour: if y1 > 0.0 { f * a[1] / y1 } else { 0.0 },
            #[cfg(feature = "noise_colour")]
            at1,
            per_sample: f * a[2] / sum,
        };
        if w.largest.is_finite() && w.neighbour.is_finite() && w.per_sample.is_finite() {
            w
        } else {
            Self {
                largest: 1.0,
                neighbour: 0.0,
                #[cfg(feature = "noise_colour")]
                at1,
                per_sample: 0.0,
            }
        }
    }

    /// `(gain2, weight_sum)` in white noise (see [`PeakFit`]) over the pulse's `samples`,
    /// each weighed `w_s` through the sum and the two at the top by their own `w_0`, `w_1`
    /// besides: `gain2 = sum_k w_k^2 = w_0^2 + w_1^2 + 2 w_s (w_0 + w_1) + samples w_s^2`,
    /// `weight_sum = sum_k w_k = w_0 + w_1 + samples w_s`.
    fn white_gains(&self, samples: f32) -> (f32, f32) {
        let (w0, w1, s) = (self.largest, self.neighbour, self.per_sample);
        let own = w0 + w1;
        (
            w0 * w0 + w1 * w1 + s * (2.0 * own + samples * s),
            own + samples * s,
        )
    }

    /// The weights as [`PeakFit::weights`] gives them: on the five samples about the largest,
    /// and on every sample of the sum.
    #[cfg(feature = "noise_colour")]
    fn on_five(&self) -> ([f32; 5], f32) {
        let mut top = [0.0, 0.0, self.largest, 0.0, 0.0];
        if let Some(w) = top.get_mut(self.at1) {
            *w = self.neighbour;
        }
        (top, self.per_sample)
    }
}

/// One Gauss-Newton step of the five-sample fit of `F_max g(d (k - k_peak))` in
/// `p = [F_max, k_peak, d]` (updated in place; `k_peak` kept within one sample of the largest,
/// `d` within a factor 1.25 of `d_area`, the area's): `(gain2, weight_sum, [N^-1]_kk)` of the
/// step's normal equations, `None` when they are singular or the peak leaves the positive.
fn five_point(top: &[f32; 5], p: &mut [f32; 3], d_area: f32) -> Option<(f32, f32, f32)> {
    let ([peak, offset, d], inv, c) = gauss_newton(&FIVE_KS, top, *p, &mut [])?;
    if peak.is_nan() || peak <= 0.0 {
        return None;
    }
    *p = [
        peak,
        offset.max(-1.0).min(1.0),
        d.max(0.8 * d_area).min(1.25 * d_area),
    ];
    let [w0, w1, w2] = inv[0];
    Some((w0, w0 * c[0] + w1 * c[1] + w2 * c[2], inv[1][1]))
}

/// The five samples' offsets from the largest.
const FIVE_KS: [f32; 5] = [-2.0, -1.0, 0.0, 1.0, 2.0];

/// The weights `dF_max / dy_k = [N^-1 J^T]_(0 k)` of the five samples' Gauss-Newton step
/// from `p = [F_max, k_peak, d]` ([`five_point`]; the rows `J_k` and `N = J^T J` do not
/// depend on the samples); zeros where `N` is singular. Their squares sum to `[N^-1]_00`, the
/// step's `gain2`.
#[cfg(feature = "noise_colour")]
fn five_point_weights(p: [f32; 3]) -> [f32; 5] {
    let mut rows = [[0.0f32; 3]; 5];
    let Some((_, inv, _)) = gauss_newton(&FIVE_KS, &[0.0; 5], p, &mut rows) else {
        return [0.0; 5];
    };
    let [w0, w1, w2] = inv[0];
    rows.map(|[j1, j2, j3]| w0 * j1 + w1 * j2 + w2 * j3)
}

/// One Gauss-Newton step of the least-squares fit of `F_max g(d (k - k_peak))`
/// ([`peak_shape`]) to the samples `ys` at `ks` (samples), from `p = [F_max, k_peak, d]`, as
/// [`five_point`] and [`flank_step`] take it: the new parameters `p + N^-1 b` (not yet kept
/// in their ranges), the inverse `N^-1` of the normal equations and the column sums `c` (see
/// [`normal_equations`]), the model's gradient at each sample written to `rows` (as many as
/// it holds); `None` when `N` is singular.
#[inline(never)]
fn gauss_newton(
    ks: &[f32],
    ys: &[f32],
    p: [f32; 3],
    rows: &mut [[f32; 3]],
) -> Option<([f32; 3], Matrix3, [f32; 3])> {
    damped_step(p, &normal_equations(ks, ys, p, peak_shape, rows), 0.0)
}

/// [`gauss_newton`] with the template `shape(x) = (g, dg/dx)` in place of [`peak_shape`], and
/// rows beside the samples', each `[dm/dF_max, dm/dk_peak, dm/dd, y - m]` (weighted against
/// one sample as the caller needs; zeros add nothing).
#[cfg(feature = "pulse_shape")]
pub(crate) fn gauss_newton_of(
    ks: &[f32],
    ys: &[f32],
    p: [f32; 3],
    shape: impl Fn(f32) -> (f32, f32),
    extra: &[[f32; 4]],
) -> Option<([f32; 3], Matrix3, [f32; 3])> {
    damped_step(p, &all_normal_equations(ks, ys, p, shape, extra), 0.0)
}

/// The relative damping `lambda` of a Levenberg-Marquardt step ([`damped_step`]),
/// which [`descend`] takes where the plain Gauss-Newton equations are singular. With it
/// `N + lambda diag(N)` is never singular to [`inverse3`]'s test while `diag(N)` has no zero:
/// for positive semi-definite `N`, `det(N + lambda D) >= lambda^3 det D` (Minkowski's
/// determinant inequality), and `(lambda / (1 + lambda))^3 = 2.5e-5` is above that test's
/// `1e-6`.
#[cfg(feature = "pulse_shape")]
const MARQUARDT_DAMPING: f32 = 0.03;

/// The normal equations `(N, b, c)` of [`normal_equations`] over the samples `ys` at `ks`,
/// with the `extra` rows ([`gauss_newton_of`]) added to `N` and `b`.
#[cfg(feature = "pulse_shape")]
fn all_normal_equations(
    ks: &[f32],
    ys: &[f32],
    p: [f32; 3],
    shape: impl Fn(f32) -> (f32, f32),
    extra: &[[f32; 4]],
) -> ([f32; 6], [f32; 3], [f32; 3]) {
    let (mut n, mut b, c) = normal_equations(ks, ys, p, shape, &mut []);
    for &[e1, e2, e3, r] in extra {
        add_row(&mut n, &mut b, [e1, e2, e3], r);
    }
    (n, b, c)
}

/// The step from `p` by the normal equations `(N, b, c)` ([`all_normal_equations`]) with
/// `N`'s diagonal scaled by `1 + damping` (Marquardt's step, which turns from
/// Gauss-Newton's towards the gradient's, scaled per parameter, as `damping` grows;
/// `damping = 0` is the plain step): the new parameters `p + (N + damping diag N)^-1 b`, that
/// inverse and `c`; `None` when the scaled `N` is singular.
fn damped_step(
    p: [f32; 3],
    &(n, b, c): &([f32; 6], [f32; 3], [f32; 3]),
    damping: f32,
) -> Option<([f32; 3], Matrix3, [f32; 3])> {
    let scale = 1.0 + damping;
    let [n11, n12, n13, n22, n23, n33] = n;
    let n = [n11 * scale, n12, n13, n22 * scale, n23, n33 * scale];
    let inv = inverse3(&n)?;
    let step = inv.map(|row| row[0] * b[0] + row[1] * b[1] + row[2] * b[2]);
    Some(([p[0] + step[0], p[1] + step[1], p[2] + step[2]], inv, c))
}

/// The least-squares amplitude of the template's values `gs` to the samples `ys`,
/// `F = sum y g / sum g^2` (counts), and the residual sum of squares `sum (y - F g)^2` it
/// leaves; `None` where the template is 0 at every sample.
#[cfg(feature = "pulse_shape")]
pub(crate) fn amplitude_fit(gs: &[f32], ys: &[f32]) -> Option<(f32, f32)> {
    let (yg, gg) = gs
        .iter()
        .zip(ys)
        .fold((0.0f32, 0.0f32), |(a, b), (&g, &y)| (a + y * g, b + g * g));
    if gg <= 0.0 {
        return None;
    }
    let peak = yg / gg;
    let rss = gs
        .iter()
        .zip(ys)
        .fold(0.0f32, |a, (&g, &y)| a + (y - peak * g) * (y - peak * g));
    Some((peak, rss))
}

/// Gauss-Newton steps of [`descend`], at most.
#[cfg(feature = "pulse_shape")]
pub(crate) const STEPS: usize = 32;

/// Halvings of a Gauss-Newton step that does not lower the residual, at most.
#[cfg(feature = "pulse_shape")]
pub(crate) const HALVINGS: usize = 6;

/// Up to [`STEPS`] Gauss-Newton steps ([`gauss_newton_of`]) from `p = [F_max, k_peak, d]`
/// over the samples `ys` at `ks` and the weighted extra rows that `residual(p)` builds with
/// the residual sum of squares at `p`, each halved until it lowers that residual (the steep
/// flank of a damped pulse can throw a full step off the pulse) and kept in range by
/// `keep(step, floor)` (`floor`: half the current `F_max`); none that does: converged. Where
/// the normal equations are singular (a clipped pulse's flank samples that lie before the
/// contact's start at `p` add nothing to them, and the rest may not pin three unknowns) the
/// step is Marquardt's ([`MARQUARDT_DAMPING`]). The point reached, its residual and the
/// extra rows `residual` built there; `None` for normal equations singular even so (a
/// parameter that no row moves), or a residual not taken at `p`.
#[cfg(feature = "pulse_shape")]
pub(crate) fn descend<const R: usize>(
    (ks, ys): (&[f32], &[f32]),
    mut p: [f32; 3],
    shape: impl Fn(f32) -> (f32, f32),
    residual: impl Fn([f32; 3]) -> Option<(f32, [[f32; 4]; R])>,
    keep: impl Fn([f32; 3], f32) -> [f32; 3],
) -> Option<([f32; 3], f32, [[f32; 4]; R])> {
    let (mut best, mut rows) = residual(p)?;
    for _ in 0..STEPS {
        let equations = all_normal_equations(ks, ys, p, &shape, &rows);
        let (next, _, _) = damped_step(p, &equations, 0.0)
            .or_else(|| damped_step(p, &equations, MARQUARDT_DAMPING))?;
        let mut scale = 1.0;
        let mut moved = false;
        for _ in 0..HALVINGS {
            let ([a, b, c], [na, nb, nc]) = (p, next);
            let step = [
                a + scale * (na - a),
                b + scale * (nb - b),
                c + scale * (nc - c),
            ];
            let q = keep(step, 0.5 * a);
            if let Some((e, at_q)) = residual(q).filter(|&(e, _)| e < best) {
                (p, best, rows, moved) = (q, e, at_q, true);
                break;
            }
            scale *= 0.5;
        }
        if !moved {
            break;
        }
    }
    Some((p, best, rows))
}

/// The Gauss-Newton normal equations of `F_max g(d (k - k_peak))` (the template `shape(x) =
/// (g, dg/dx)`: [`peak_shape`], or a contact's tabulated pulse about its peak,
/// `crate::pulse_shape::shape_flank_fit`) at
/// `p = [F_max, k_peak, d]` over the samples `ys` at `ks` (samples; `t = k - k_peak`):
/// `[n11, n12, n13, n22, n23, n33]`, the right side `b` and the column sums `c` of the
/// columns `dm/dF_max = g`, `dm/dk_peak = -F_max d g'` and `dm/dd = F_max t g'`. The first
/// rows `[g, -F_max d g', F_max t g']` are also written to `rows`, as many as it holds.
fn normal_equations(
    ks: &[f32],
    ys: &[f32],
    [peak, at, d]: [f32; 3],
    shape: impl Fn(f32) -> (f32, f32),
    rows: &mut [[f32; 3]],
) -> ([f32; 6], [f32; 3], [f32; 3]) {
    let (mut n, mut b, mut c) = ([0.0f32; 6], [0.0f32; 3], [0.0f32; 3]);
    for (i, (&k, &y)) in ks.iter().zip(ys).enumerate() {
        let t = k - at;
        let (g, slope) = shape(d * t);
        let (j1, j2, j3) = (g, -peak * d * slope, peak * t * slope);
        add_row(&mut n, &mut b, [j1, j2, j3], y - peak * g);
        c = [c[0] + j1, c[1] + j2, c[2] + j3];
        if let Some(row) = rows.get_mut(i) {
            *row = [j1, j2, j3];
        }
    }
    (n, b, c)
}

/// Adds one row, the model's gradient `j = [dm/dF_max, dm/dk_peak, dm/dd]` with the residual
/// `r = y - m`, to the normal equations `n = [n11, n12, n13, n22, n23, n33]` and their right
/// side `b`: `n += j j^T`, `b += j r`.
#[inline(always)]
fn add_row(n: &mut [f32; 6], b: &mut [f32; 3], [j1, j2, j3]: [f32; 3], r: f32) {
    *n = [
        n[0] + j1 * j1,
        n[1] + j1 * j2,
        n[2] + j1 * j3,
        n[3] + j2 * j2,
        n[4] + j2 * j3,
        n[5] + j3 * j3,
    ];
    *b = [b[0] + j1 * r, b[1] + j2 * r, b[2] + j3 * r];
}

/// A 3 x 3 matrix, by rows.
pub(crate) type Matrix3 = [[f32; 3]; 3];

/// The inverse of the symmetric 3 x 3 matrix `[[a, b, c], [b, e, f], [c, f, i]]`, given as
/// `[a, b, c, e, f, i]`, by its cofactors; `None` when it is singular to within f32
/// (determinant below `1e-6` of its diagonal's product).
fn inverse3(&[a, b, c, e, f, i]: &[f32; 6]) -> Option<Matrix3> {
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

/// Largest `|x|` of [`peak_shape`] at which [`flank_fit`] takes a flank sample: the series is
/// within 2e-5 of `g` there (`g(1.3) = 0.170`).
pub const FLANK_REACH: f32 = 1.3;

/// A pulse clipped at the ADC's full scale as the flank fits read it ([`flank_fit`],
/// `crate::pulse_shape::shape_flank_fit`): the two samples before the run (at `k = -2, -1`),
/// the two after it (`k = run, run + 1`), the run (the clipped samples, and behind an
/// accelerometer the [`FlankChain::guard`] samples either side of them that its equaliser's
/// FIR took from a clipped one), the clipping level and the sum of all the pulse's samples (counts above
/// the baseline) with their number and the run's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Flanks {
    /// The samples at `k = -2, -1` (counts).
    pub before: [f32; 2],
    /// The run's samples, `k = 0 .. run - 1`: clipped from `k = guard` to `run - 1 - guard`
    /// ([`FlankChain::guard`], at least 1).
    pub run: f32,
    /// The samples at `k = run, run + 1` (counts).
    pub after: [f32; 2],
    /// The clipping level (counts).
    pub level: f32,
    /// Sum of all the pulse's samples (counts).
    pub sum: f32,
    /// Samples in `sum` (the pulse's, with those before its trigger).
    pub samples: f32,
    /// Sum of the run's samples as read (counts): `run x level` on a rigid chain.
    pub run_sum: f32,
    /// What the chain did to the samples ([`FlankChain::RIGID`] on a rigid chain).
    pub chain: FlankChain,
}

/// What a chain between the plate and the ADC does to a clipped pulse's samples as the flank
/// fit reads them ([`Flanks::chain`]); nothing on a rigid chain ([`FlankChain::RIGID`]).
/// Behind an accelerometer alone the equaliser is a FIR, whose output is wrong only where
/// it read a clipped sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlankChain {
    /// Samples at each end of the run that are not clipped but read a clipped one (the
    /// equaliser's delay).
    pub guard: f32,
    /// How far the raw samples lag the force (samples): the accelerometer's group delay at
    /// low frequency, `2 zeta_a / w_a` times the rate, so that a clipped sample `k` saw the
    /// force at about `k - lag` at or above the level.
    pub lag: f32,
    /// The error each sample carries beside the noise, as a fraction of the pulse's peak,
    /// `[in the body, within crate::chain_residual::KINK_SAMPLES of an end of the contact]`:
    /// the equaliser's ([`crate::chain_residual::sample_error`]).
    pub sample_error: [f32; 2],
    /// How far below the level the force `lag` before a clipped sample may lie, as a
    /// fraction of the pulse's peak: the raw samples' own error against the force
    /// ([`crate::chain_residual::raw_error`]; an accelerometer with a resonant peak raises
    /// the pulse's top past the force's).
    pub level_error: f32,
    /// Behind beam modes, the RMS of what the sections' state, left off by the run, puts
    /// into a flank sample after it and into the pulse's sum, once taken off them
    /// (`[sample, sum]`, counts: the sigmas of `settle_clip::ClipError`); zeros
    /// elsewhere. The flank fit counts the first at every flank sample.
    pub state_error: [f32; 2],
}

impl FlankChain {
    /// A rigid chain: the samples are the force's.
    pub const RIGID: FlankChain = FlankChain {
        guard: 0.0,
        lag: 0.0,
        sample_error: [0.0; 2],
        level_error: 0.0,
        state_error: [0.0; 2],
    };

    /// The variance a flank sample carries from [`FlankChain::state_error`] (counts^2).
    pub fn state_variance(&self) -> f32 {
        self.state_error[0] * self.state_error[0]
    }
}

impl Flanks {
    /// The four samples' positions `k` and values, `None` unless the level and the sum are
    /// finite and positive, at least one sample is clipped and the guard is at least 0.
    ///
    /// ```
    /// use coalshock::shape_fit::{FlankChain, Flanks};
    /// let f = Flanks {
    ///     before: [1.0, 2.0],
    ///     run: 3.0,
    ///     after: [2.5, 1.5],
    ///     level: 3.0,
    ///     sum: 16.0,
    ///     samples: 7.0,
    ///     run_sum: 9.0,
    ///     chain: FlankChain::RIGID,
    /// };
    /// assert_eq!(f.samples(), Some(([-2.0, -1.0, 3.0, 4.0], [1.0, 2.0, 2.5, 1.5])));
    /// assert_eq!(Flanks { run: 0.0, ..f }.samples(), None);
    /// let guard = FlankChain { guard: 1.5, ..FlankChain::RIGID };
    /// assert_eq!(Flanks { chain: guard, ..f }.samples(), None);
    /// ```
    pub fn samples(&self) -> Option<([f32; 4], [f32; 4])> {
        let (level, sum, run) = (self.level, self.sum, self.run);
        let guard = self.chain.guard;
        let guarded = guard >= 0.0 && run - 2.0 * guard >= 1.0;
        if !(level > 0.0 && sum > 0.0 && guarded && level.is_finite() && sum.is_finite()) {
            return None;
        }
        let ([b0, b1], [a0, a1]) = (self.before, self.after);
        Some(([-2.0, -1.0, run, run + 1.0], [b0, b1, a0, a1]))
    }
}

/// What [`flank_fit`] reads from a clipped pulse: peak (counts), its time and the duration
/// (samples), and the covariance of `(ln F_max, ln t_c)` over one sample's noise variance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlankFit {
    /// Peak `F_max` (counts).
    pub peak: f32,
    /// The peak's time `k_peak`, in samples after the run's first (within the run).
    pub peak_at: f32,
    /// Duration `t_c = PEAK_OMEGA / d` (samples).
    pub duration: f32,
    /// `[var ln F_max, var ln t_c, cov]` over the noise variance of one sample (counts^-2).
    pub gains: [f32; 3],
}

/// Peak and duration of a Hertz pulse whose top is clipped on a rigid chain (its
/// [`Flanks::chain`] is not read: the samples are taken for the force's),
/// from its unclipped flanks ([`Flanks`]: the two samples either side of the `run` clipped
/// ones, the clipping `level` and the sum of all samples). The
/// least-squares fit of `F_max g(d (k - k_peak))` ([`peak_shape`]) to the four, in `F_max`,
/// `k_peak` and the phase step `d` (six Gauss-Newton steps from `k_peak` at the clipped run's
/// middle, `d` from the area over the level, `F_max` through the nearer flank samples), gives
/// `t_c = PEAK_OMEGA / d`. `None` when the fit fails or does not describe a clipped pulse: a
/// flank sample beyond [`FLANK_REACH`], `d` at the end of its range, the peak outside the
/// clipped run, the fitted pulse below the level (less four `noise` RMS) at the run's ends,
/// or the four samples' residual above `4 noise` RMS (with `1e-4 F_max` for the template).
#[inline(never)]
pub fn flank_fit(flanks: &Flanks, noise: f32) -> Option<FlankFit> {
    let (ks, ys) = flanks.samples()?;
    let Flanks {
        before,
        run,
        after,
        level,
        sum,
        ..
    } = *flanks;
    let d0 = step(sum / (C_AREA * level));
    let half = 0.5 * (run + 1.0);
    let near = 0.5 * (before[1] + after[0]);
    let mut p = [
        near / peak_shape(d0 * half).0.max(0.1),
        0.5 * (run - 1.0),
        d0,
    ];
    let mut inv = [[0.0f32; 3]; 3];
    for _ in 0..6 {
        inv = flank_step(&ks, &ys, &mut p, (0.5 * d0, 2.0 * d0), 0.5 * (run - 1.0))?;
    }
    let [peak, at, d] = p;
    let reach = ks.iter().fold(0.0f32, |m, &k| m.max((d * (k - at)).abs()));
    let model = |k: f32| peak * peak_shape(d * (k - at)).0;
    let rss = ks
        .iter()
        .zip(&ys)
        .fold(0.0f32, |a, (&k, &y)| a + (y - model(k)) * (y - model(k)));
    let tolerance = 16.0 * noise * noise + 4e-8 * peak * peak;
    let edge = model(0.0).min(model(run - 1.0));
    let inside = at >= -0.5 && at <= run - 0.5 && d > 0.501 * d0 && d < 1.99 * d0;
    if !(inside && reach <= FLANK_REACH && edge >= level - 4.0 * noise && rss <= 4.0 * tolerance) {
        return None;
    }
    Some(FlankFit {
        peak,
        peak_at: at,
        duration: PEAK_OMEGA / d,
        gains: flank_gains(&inv, peak, d),
    })
}

/// `[var ln F_max, var ln t_c, cov]` over one sample's noise variance of a flank fit in
/// `[F_max, k_peak, d]` whose duration is `t_c = const / d` (`ln t_c = const - ln d`), from
/// the inverse `inv` of its normal equations: `inv_FF / F^2`, `inv_dd / d^2`, `-inv_Fd / (F d)`.
pub(crate) fn flank_gains(inv: &Matrix3, peak: f32, d: f32) -> [f32; 3] {
    [
        inv[0][0] / (peak * peak),
        inv[2][2] / (d * d),
        -inv[0][2] / (peak * d),
    ]
}

/// One Gauss-Newton step of [`flank_fit`] over the samples `ys` at `ks` ([`gauss_newton`]),
/// `p = [F_max, k_peak, d]` updated in place (`F_max` kept above half its value, `d` within
/// `d_range`, `k_peak` within one sample of `middle`): the inverse of the normal equations,
/// `None` when they are singular.
fn flank_step(
    ks: &[f32; 4],
    ys: &[f32; 4],
    p: &mut [f32; 3],
    (d_lo, d_hi): (f32, f32),
    middle: f32,
) -> Option<Matrix3> {
    let ([peak, at, d], inv, _) = gauss_newton(ks, ys, *p, &mut [])?;
    *p = [
        peak.max(0.5 * p[0]),
        at.max(middle - 1.0).min(middle + 1.0),
        d.max(d_lo).min(d_hi),
    ];
    Some(inv)
}

#[cfg(all(test, feature = "pulse_shape"))]
mod tests {
    use super::*;

    /// A pulse of compact support, `g(x) = 1 - x^2` on `|x| < 1` (0 outside), and its slope.
    fn parabola(x: f32) -> (f32, f32) {
        if x.abs() < 1.0 {
            (1.0 - x * x, -2.0 * x)
        } else {
            (0.0, 0.0)
        }
    }

    /// The parabola's area `F_max (4/3) / d` as an extra row at `p` (as the pulse's sum is one
    /// beside a clipped pulse's flank samples): its gradient and its residual against `area`.
    fn area_row([peak, _, d]: [f32; 3], area: f32) -> [f32; 4] {
        let a = 4.0 / (3.0 * d);
        [a, 0.0, -peak * a / d, area - peak * a]
    }

    /// Two samples before the pulse (0, as a clipped pulse's before its contact) and two on its
    /// falling flank, with the area. From a start whose pulse covers one of them, the
    /// Gauss-Newton equations are singular (that sample's row and the area's, three unknowns);
    /// Marquardt's steps widen the pulse until the other counts, and the descent reaches the
    /// exact `F_max 100`, `k_peak 0`, `d 0.5` that the samples and the area were made from.
    #[test]
    fn a_descent_from_singular_equations_reaches_the_pulse() {
        let truth = [100.0f32, 0.0, 0.5];
        let ks = [-3.0f32, -2.5, 1.0, 1.5];
        let ys = ks.map(|k| truth[0] * parabola(truth[2] * (k - truth[1])).0);
        let area = area_row(truth, 0.0)[3].abs();
        let start = [80.0, 0.5, 1.2];
        // Only k = 1 lies within |1.2 (k - 0.5)| < 1.
        assert!(gauss_newton_of(&ks, &ys, start, parabola, &[area_row(start, area)]).is_none());
        let residual = |p: [f32; 3]| {
            let row = area_row(p, area);
            let rss = ks.iter().zip(&ys).fold(row[3] * row[3], |a, (&k, &y)| {
                let e = y - p[0] * parabola(p[2] * (k - p[1])).0;
                a + e * e
            });
            Some((rss, [row]))
        };
        let keep = |p: [f32; 3], floor: f32| [p[0].max(floor), p[1], p[2].max(0.05)];
        let found = descend((&ks, &ys), start, parabola, residual, keep);
        assert!(found.is_some(), "the damped steps descend");
        let Some((p, rss, _)) = found else { return };
        assert!((p[0] - truth[0]).abs() < 1e-2, "F_max {}", p[0]);
        assert!((p[1] - truth[1]).abs() < 1e-3, "k_peak {}", p[1]);
        assert!((p[2] - truth[2]).abs() < 1e-4, "d {}", p[2]);
        assert!(rss < 1e-3, "rss {rss}");
    }
}
