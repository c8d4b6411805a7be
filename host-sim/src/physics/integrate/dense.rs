//! A step's continuous output (dense output) and the lookup of the step that holds a time.

use crate::physics::events::{MAX_COEFFS, Poly, by_degree};

/// A step's continuous output in Hairer's nested form
/// `y(theta) = r0 + theta (r1 + (1 - theta) (r2 + theta (r3 + (1 - theta) (r4 + ...))))`
/// for `theta` in [0, 1], in scaled units, with `n` coefficients per component: 5 for
/// Dopri5 (`CONTD5`) and RK4 (the cubic Hermite interpolant, `r4 = 0`), 8 for Dop853
/// (`CONTD8`), 4 for Rodas4 (`(1 - theta) y0 + theta (y1 + (1 - theta) (d2 + theta d3))`), 8
/// for Radau13 (its collocation polynomial through the step's start and its seven stages).
#[derive(Debug, Clone, Copy)]
pub(super) struct Segment {
    /// Scaled time of the step's start.
    pub(super) t0: f64,
    /// Scaled step size.
    pub(super) h: f64,
    /// Coefficients `r_0 .. r_(n-1)` of `x` and `v`; the rest are 0.
    pub(super) r: [[f64; MAX_COEFFS]; 2],
    /// Coefficients in use (at most [`MAX_COEFFS`]).
    pub(super) n: usize,
}

impl Segment {
    /// A segment from the coefficients of `x` and `v` (`r[i].len()` of each used).
    pub(super) fn nested<const N: usize>(t0: f64, h: f64, r: [[f64; N]; 2]) -> Self {
        let mut out = [[0.0; MAX_COEFFS]; 2];
        for (o, ri) in out.iter_mut().zip(&r) {
            o[..N].copy_from_slice(ri);
        }
        Self {
            t0,
            h,
            r: out,
            n: N,
        }
    }

    /// The state at step fraction `theta` (nested evaluation from the innermost term).
    #[inline]
    pub(super) fn eval(&self, theta: f64) -> [f64; 2] {
        by_degree!(self.n - 1, deg => self.eval_n(deg + 1, theta))
    }

    /// [`Segment::eval`] for `n` coefficients (a constant where inlined).
    #[inline(always)]
    fn eval_n(&self, n: usize, theta: f64) -> [f64; 2] {
        let th1 = 1.0 - theta;
        let c = |r: &[f64; MAX_COEFFS]| {
            let mut acc = r[n - 1];
            for i in (0..n - 1).rev() {
                acc = r[i] + if i % 2 == 0 { theta } else { th1 } * acc;
            }
            acc
        };
        [c(&self.r[0]), c(&self.r[1])]
    }

    /// True when a cheap interval bound on the nested form proves that component `i` minus
    /// `level` keeps one strict sign on [0, 1]: from the innermost term out, `acc = r_k + w acc`
    /// with `w` (`theta` or `1 - theta`) in [0, 1] lies in `[r_k + min(lo, 0), r_k + max(hi, 0)]`.
    /// The margin `1e-11 sum |r_k|` dwarfs the rounding of this bound, of the power-basis
    /// conversion ([`Segment::poly`]) and of its evaluation, so a root search on the
    /// polynomial would find no sign change either.
    #[inline]
    pub(super) fn keeps_sign(&self, i: usize, level: f64) -> bool {
        by_degree!(self.n - 1, deg => self.keeps_sign_n(deg + 1, i, level))
    }

    /// [`Segment::keeps_sign`] for `n` coefficients.
    #[inline(always)]
    fn keeps_sign_n(&self, n: usize, i: usize, level: f64) -> bool {
        let r = &self.r[i][..n];
        let (mut lo, mut hi) = (0.0_f64, 0.0_f64);
        let mut abs = level.abs();
        for (k, &rk) in r.iter().enumerate().rev() {
            let rk = if k == 0 { rk - level } else { rk };
            (lo, hi) = (rk + lo.min(0.0), rk + hi.max(0.0));
            abs += rk.abs();
        }
        let margin = 1e-11 * abs;
        lo > margin || hi < -margin
    }

    /// Component `i` of the output as a power-basis polynomial in `theta` of degree `n - 1`.
    pub(super) fn poly(&self, i: usize) -> Poly {
        let r = &self.r[i];
        if self.n == 5 {
            // Dopri5's and RK4's quartic as it always was written (bit for bit).
            let [r0, r1, r2, r3, r4] = [r[0], r[1], r[2], r[3], r[4]];
            return Poly::quartic([r0, r1 + r2, r3 + r4 - r2, -(r3 + 2.0 * r4), r4]);
        }
        // Expand from the innermost term: times theta shifts, times (1 - theta) subtracts the
        // shift.
        let mut c = [0.0; MAX_COEFFS];
        c[0] = r[self.n - 1];
        for k in (0..self.n - 1).rev() {
            let mut shifted = [0.0; MAX_COEFFS];
            shifted[1..].copy_from_slice(&c[..MAX_COEFFS - 1]);
            if k % 2 == 1 {
                for (s, ci) in shifted.iter_mut().zip(&c) {
                    *s = ci - *s;
                }
            }
            c = shifted;
            c[0] += r[k];
        }
        Poly { c, deg: self.n - 1 }
    }

    pub(super) fn hermite(
        t0: f64,
        h: f64,
        y0: [f64; 2],
        f0: [f64; 2],
        y1: [f64; 2],
        f1: [f64; 2],
    ) -> Self {
        let mut r = [[0.0; 5]; 2];
        for i in 0..2 {
            let ydiff = y1[i] - y0[i];
            let bspl = h * f0[i] - ydiff;
            r[i] = [y0[i], ydiff, bspl, ydiff - h * f1[i] - bspl, 0.0];
        }
        Self::nested(t0, h, r)
    }
}

/// The segment holding `tau` (the last one starting at or before it, or the first) and the
/// step fraction there, or `None` outside `[0, end of the last segment]`; binary search.
pub(super) fn find_segment(segments: &[Segment], tau: f64) -> Option<(usize, f64)> {
    let last = segments.last()?;
    if !(tau >= 0.0 && tau <= last.t0 + last.h) {
        return None;
    }
    let i = segments.partition_point(|s| s.t0 <= tau).saturating_sub(1);
    Some((i, step_fraction(&segments[i], tau)))
}

/// [`find_segment`] for increasing `tau`: walks forward from `cursor` (the index found by the
/// previous call, 0 at first) instead of searching; the same result for any `tau` (a step
/// back in time searches afresh).
pub(super) fn find_segment_walk(
    segments: &[Segment],
    tau: f64,
    cursor: &mut usize,
) -> Option<(usize, f64)> {
    let last = segments.last()?;
    if !(tau >= 0.0 && tau <= last.t0 + last.h) {
        return None;
    }
    let mut i = (*cursor).min(segments.len() - 1);
    if segments[i].t0 > tau {
        i = segments.partition_point(|s| s.t0 <= tau).saturating_sub(1);
    }
    while i + 1 < segments.len() && segments[i + 1].t0 <= tau {
        i += 1;
    }
    *cursor = i;
    Some((i, step_fraction(&segments[i], tau)))
}

/// `theta = (tau - t0) / h` clamped to [0, 1] (0 for an empty segment).
pub(super) fn step_fraction(s: &Segment, tau: f64) -> f64 {
    if s.h > 0.0 {
        ((tau - s.t0) / s.h).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

pub(super) fn eval_segments(segments: &[Segment], tau: f64) -> Option<[f64; 2]> {
    let (i, theta) = find_segment(segments, tau)?;
    Some(segments[i].eval(theta))
}

/// The segments that hold `[lo, hi]` (scaled times inside the output): evaluating there gives
/// the whole output's values without searching all of it.
pub(super) fn covering(segments: &[Segment], lo: f64, hi: f64) -> &[Segment] {
    let last = segments.len().saturating_sub(1);
    let i_lo = find_segment(segments, lo).map_or(0, |(i, _)| i);
    let i_hi = find_segment(segments, hi).map_or(last, |(i, _)| i);
    &segments[i_lo.min(i_hi)..=i_hi]
}
