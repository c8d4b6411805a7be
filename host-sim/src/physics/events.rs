//! Root location on a step's continuous output: the earliest sign change of a switching
//! function inside a step, found so that none is stepped over.
//!
//! A step's continuous output is a polynomial in `theta` in [0, 1] for each component of the
//! scaled state ([`Poly`], of the degree of the method's continuous output: 3 to 7). [`earliest_root`] halves `[a, b]` and drops a half only when an
//! enclosure proves that the function has no sign change there ([`Enclosure`]): for a
//! polynomial switching function (contact end `x`, Adams kink `x - x_d`) its Bernstein
//! coefficients on the half (the polynomial lies in their convex hull; with non-zero end
//! coefficients, at most one sign variation means at most one root inside, by Descartes' rule
//! for the Bernstein basis, so no further halving is needed), for the clamp a bound of the
//! law's switching function over the box of states that the polynomials take on the half. Left
//! halves are searched first, so the first root found is the earliest. A half narrower than
//! `2^-MAX_DEPTH` of the interval is not split further; its bracket, if any, is refined by
//! Illinois regula falsi.

/// Halvings of the searched interval before a bracket is refined as it is.
const MAX_DEPTH: u32 = 30;

/// Most coefficients of a [`Poly`]: degree 7 (Dop853's continuous output).
pub(crate) const MAX_COEFFS: usize = 8;

/// `$body` with `$n` bound to `$deg`, written out for the degrees of the methods' continuous
/// outputs (3: Rodas4; 4: Dopri5 and RK4; 7: Dop853 and Radau13), so that each copy sees its
/// degree as a constant and its loops unroll; the same arithmetic in the same order for any
/// degree.
macro_rules! by_degree {
    ($deg:expr, $n:ident => $body:expr) => {
        match $deg {
            3 => {
                let $n = 3;
                $body
            }
            4 => {
                let $n = 4;
                $body
            }
            7 => {
                let $n = 7;
                $body
            }
            $n => $body,
        }
    };
}
pub(crate) use by_degree;

/// A polynomial `c0 + c1 theta + ... + c_deg theta^deg` (power basis) of degree at most 7:
/// a component of a step's continuous output (cubic for Rodas4, quartic for Dopri5 and RK4's
/// Hermite interpolant padded with a zero, degree 7 for Dop853).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Poly {
    /// Coefficients `c_0 ..= c_deg`; the rest are 0.
    pub c: [f64; MAX_COEFFS],
    /// Degree (at most 7).
    pub deg: usize,
}

impl Poly {
    /// The quartic `c0 + ... + c4 theta^4`.
    pub fn quartic(c: [f64; 5]) -> Self {
        let mut out = [0.0; MAX_COEFFS];
        out[..5].copy_from_slice(&c);
        Self { c: out, deg: 4 }
    }

    /// Value at `theta` (Horner).
    #[inline]
    pub fn eval(&self, theta: f64) -> f64 {
        by_degree!(self.deg, n => self.eval_deg(n, theta))
    }

    /// [`Poly::eval`] for `n = deg` (a constant where inlined).
    #[inline(always)]
    fn eval_deg(&self, n: usize, theta: f64) -> f64 {
        let mut acc = self.c[n];
        for &ci in self.c[..n].iter().rev() {
            acc = ci + theta * acc;
        }
        acc
    }

    /// The polynomial minus the constant `x`.
    pub fn minus(&self, x: f64) -> Self {
        let mut p = *self;
        p.c[0] -= x;
        p
    }

    /// True when a cheap bound proves that the polynomial keeps the strict sign of `c_0` on
    /// [0, 1]: for `theta` there, `c_0 + sum_(k>=1) min(c_k, 0) <= p(theta) <= c_0 +
    /// sum_(k>=1) max(c_k, 0)` (as `theta^k <= 1`), less a rounding margin
    /// `4 (deg + 1) eps sum_k |c_k|` that also covers Horner's evaluation error. Settles most
    /// steps without the Bernstein coefficients.
    #[inline]
    pub fn keeps_sign_on_unit(&self) -> bool {
        by_degree!(self.deg, n => self.keeps_sign_deg(n))
    }

    /// [`Poly::keeps_sign_on_unit`] for `n = deg`.
    #[inline(always)]
    fn keeps_sign_deg(&self, n: usize) -> bool {
        let c = &self.c[..=n];
        let (mut neg, mut pos, mut abs) = (0.0_f64, 0.0_f64, c[0].abs());
        for &ck in &c[1..] {
            neg += ck.min(0.0);
            pos += ck.max(0.0);
            abs += ck.abs();
        }
        let margin = 4.0 * (n as f64 + 1.0) * f64::EPSILON * abs;
        (c[0] > 0.0 && c[0] + neg > margin) || (c[0] < 0.0 && c[0] + pos < -margin)
    }

    /// Bernstein coefficients `b_0 ..= b_n` of the polynomial of degree `n = deg` restricted
    /// to `[a, b]` (the rest 0): Taylor shift to `a` (`q_j = p^(j)(a) (b - a)^j / j!`), then
    /// `b_i = sum_(j <= i) C(i, j) / C(n, j) q_j`. `n` is a constant where inlined (see
    /// `by_degree!`), so that the loops unroll.
    #[inline(always)]
    fn bernstein_deg(&self, n: usize, a: f64, b: f64) -> [f64; MAX_COEFFS] {
        let mut q = self.c;
        for i in 0..n {
            for j in (i..n).rev() {
                q[j] += a * q[j + 1];
            }
        }
        let w = b - a;
        let mut wj = w;
        for qj in q.iter_mut().take(n + 1).skip(1) {
            *qj *= wj;
            wj *= w;
        }
        let mut out = [0.0; MAX_COEFFS];
        if n == 4 {
            // The quartic's weights written out (Dopri5's and RK4's events depend on these
            // roundings bit for bit).
            out[..5].copy_from_slice(&[
                q[0],
                q[0] + 0.25 * q[1],
                q[0] + 0.5 * q[1] + q[2] / 6.0,
                q[0] + 0.75 * q[1] + 0.5 * q[2] + 0.25 * q[3],
                q[0] + q[1] + q[2] + q[3] + q[4],
            ]);
            return out;
        }
        let weights = &BERNSTEIN_WEIGHTS[n];
        for (bi, wi) in out.iter_mut().zip(weights).take(n + 1) {
            *bi = wi[..=n].iter().zip(&q).map(|(w, qj)| w * qj).sum();
        }
        out
    }

    /// Bounds `(lo, hi)` of the polynomial on `[a, b]` (the hull of its Bernstein
    /// coefficients).
    #[inline]
    pub fn range(&self, a: f64, b: f64) -> (f64, f64) {
        by_degree!(self.deg, n => self.range_deg(n, a, b))
    }

    /// [`Poly::range`] for `n = deg`.
    #[inline(always)]
    fn range_deg(&self, n: usize, a: f64, b: f64) -> (f64, f64) {
        let bs = self.bernstein_deg(n, a, b);
        bs[..=n]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            })
    }

    /// What the Bernstein coefficients on `[a, b]` say about the roots there.
    #[inline]
    pub fn enclosure(&self, a: f64, b: f64) -> Enclosure {
        by_degree!(self.deg, n => self.enclosure_deg(n, a, b))
    }

    /// [`Poly::enclosure`] for `n = deg`.
    #[inline(always)]
    fn enclosure_deg(&self, n: usize, a: f64, b: f64) -> Enclosure {
        let all = self.bernstein_deg(n, a, b);
        let bs = &all[..=n];
        if bs.iter().all(|&x| x > 0.0) || bs.iter().all(|&x| x < 0.0) {
            return Enclosure::NoRoot;
        }
        if bs[0] == 0.0 || bs[n] == 0.0 {
            // A root at an end: the count below is for the open interval only.
            return Enclosure::Unknown;
        }
        let mut last = 0.0_f64;
        let mut variations = 0;
        for &x in bs.iter().filter(|&&x| x != 0.0) {
            variations += usize::from(last * x < 0.0);
            last = x;
        }
        if variations <= 1 {
            Enclosure::AtMostOne
        } else {
            Enclosure::Unknown
        }
    }
}

/// The binomial coefficient `C(n, k)` as f64 (exact for `n <= 7`; 0 for `k > n`).
const fn binomial(n: usize, k: usize) -> f64 {
    if k > n {
        return 0.0;
    }
    let mut acc = 1.0;
    let mut i = 0;
    while i < k {
        acc = acc * (n - i) as f64 / (i + 1) as f64;
        i += 1;
    }
    acc
}

/// `BERNSTEIN_WEIGHTS[n][i][j] = C(i, j) / C(n, j)` (0 for `j > i`): the weights that turn
/// the scaled Taylor coefficients of a degree-`n` polynomial into its Bernstein coefficients.
const BERNSTEIN_WEIGHTS: [[[f64; MAX_COEFFS]; MAX_COEFFS]; MAX_COEFFS] = {
    let mut w = [[[0.0; MAX_COEFFS]; MAX_COEFFS]; MAX_COEFFS];
    let mut n = 0;
    while n < MAX_COEFFS {
        let mut i = 0;
        while i <= n {
            let mut j = 0;
            while j <= i {
                w[n][i][j] = binomial(i, j) / binomial(n, j);
                j += 1;
            }
            i += 1;
        }
        n += 1;
    }
    w
};

/// What is known about the roots of a switching function on an interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Enclosure {
    /// No root (the function keeps one strict sign).
    NoRoot,
    /// At most one root inside (a sign change between the ends is that root).
    AtMostOne,
    /// Nothing proven.
    Unknown,
}

/// The earliest `theta` in `(a, b]` where `g` changes sign, from `g(a) != 0` to 0 or the
/// opposite sign; `None` if `g` keeps its sign (or `g(a) == 0`). `enclose(lo, hi)` must tell
/// the truth about `g` on `[lo, hi]` (see [`Enclosure`]).
pub(crate) fn earliest_root(
    g: &dyn Fn(f64) -> f64,
    enclose: &dyn Fn(f64, f64) -> Enclosure,
    a: f64,
    b: f64,
) -> Option<f64> {
    earliest_root_within(g, enclose, a, b, usize::MAX)
}

/// [`earliest_root`] with at most `max_splits` halvings in all: once they are spent, a part
/// that no enclosure has settled is searched only for a sign change between its ends (as at
/// the depth limit). A function that hovers at zero over the whole interval (a law sliding
/// along its clamp) would otherwise cost up to `2^MAX_DEPTH` halvings.
pub(crate) fn earliest_root_within(
    g: &dyn Fn(f64) -> f64,
    enclose: &dyn Fn(f64, f64) -> Enclosure,
    a: f64,
    b: f64,
    max_splits: usize,
) -> Option<f64> {
    if b <= a || b.is_nan() {
        return None;
    }
    let splits = core::cell::Cell::new(max_splits);
    search(g, enclose, (a, g(a)), (b, g(b)), MAX_DEPTH, &splits)
}

fn search(
    g: &dyn Fn(f64) -> f64,
    enclose: &dyn Fn(f64, f64) -> Enclosure,
    (a, ga): (f64, f64),
    (b, gb): (f64, f64),
    depth: u32,
    splits: &core::cell::Cell<usize>,
) -> Option<f64> {
    let crossing = ga != 0.0 && ga * gb <= 0.0;
    match enclose(a, b) {
        Enclosure::NoRoot => None,
        Enclosure::AtMostOne => crossing.then(|| illinois(g, a, ga, b, gb)),
        Enclosure::Unknown if depth == 0 || splits.get() == 0 => {
            crossing.then(|| illinois(g, a, ga, b, gb))
        }
        Enclosure::Unknown => {
            splits.set(splits.get() - 1);
            let m = 0.5 * (a + b);
            let gm = g(m);
            search(g, enclose, (a, ga), (m, gm), depth - 1, splits)
                .or_else(|| search(g, enclose, (m, gm), (b, gb), depth - 1, splits))
        }
    }
}

/// Root of `g` on `[a, b]` with `ga`, `gb` of opposite signs (Illinois regula falsi, with a
/// bisection fallback), to `|b - a| <= 4 eps` ([`illinois_until`] with no tolerances).
pub(crate) fn illinois(g: impl Fn(f64) -> f64, a: f64, ga: f64, b: f64, gb: f64) -> f64 {
    let exact = |x: f64| Ok::<f64, core::convert::Infallible>(g(x));
    match illinois_until(exact, a, ga, b, gb, 0.0, 0.0) {
        Ok(x) => x,
        Err(never) => match never {},
    }
}

/// Root of `g` on `[a, b]` with `ga`, `gb` of opposite signs: Illinois regula falsi (the
/// secant of the bracket, the kept end's value halved when the same end is kept twice), with
/// a bisection whenever the secant leaves the bracket and at every 8th step; at most 200
/// evaluations. It stops at the first `x` with `|g(x)| <= g_tol` (`g(x) == 0` for 0), or when
/// the bracket is at most `max(x_tol, 4 eps |b|)` wide, and returns the last `x` evaluated;
/// the first error of `g` ends it.
pub(crate) fn illinois_until<E>(
    mut g: impl FnMut(f64) -> Result<f64, E>,
    mut a: f64,
    mut ga: f64,
    mut b: f64,
    mut gb: f64,
    g_tol: f64,
    x_tol: f64,
) -> Result<f64, E> {
    if ga == 0.0 {
        return Ok(a);
    }
    if gb == 0.0 {
        return Ok(b);
    }
    for it in 0..200 {
        let mut x = b - gb * (b - a) / (gb - ga);
        let (lo, hi) = (a.min(b), a.max(b));
        if !(x > lo && x < hi) || it % 8 == 7 {
            x = 0.5 * (a + b);
        }
        let gx = g(x)?;
        if gx.abs() <= g_tol {
            return Ok(x);
        }
        if gx * gb < 0.0 {
            a = b;
            ga = gb;
        } else {
            ga *= 0.5;
        }
        b = x;
        gb = gx;
        if (b - a).abs() <= x_tol.max(4.0 * f64::EPSILON * b.abs().max(1e-300)) {
            break;
        }
    }
    Ok(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(theta - 0.2)(theta - 0.25)(theta - 0.3)(theta - 2)`: three roots close together, one
    /// of them on a halving point; the earliest is found, also when the ends of the searched
    /// interval have the same sign.
    #[test]
    fn finds_the_earliest_of_close_roots() {
        let roots = [0.2, 0.25, 0.3, 2.0];
        let mut c = [1.0, 0.0, 0.0, 0.0, 0.0];
        for r in roots {
            let mut n = [0.0; 5];
            for i in 0..5 {
                n[i] = -r * c[i] + if i > 0 { c[i - 1] } else { 0.0 };
            }
            c = n;
        }
        let p = Poly::quartic(c);
        let th = earliest_root(&|t| p.eval(t), &|a, b| p.enclosure(a, b), 0.0, 1.0);
        assert!((th.expect("a root") - 0.2).abs() < 1e-14);
        // A pair of roots inside with no sign change between the ends is not stepped over.
        let th = earliest_root(&|t| p.eval(t), &|a, b| p.enclosure(a, b), 0.22, 1.0);
        assert!((th.expect("a root") - 0.25).abs() < 1e-14);
        let (lo, hi) = p.range(0.0, 1.0);
        for i in 0..=100 {
            let v = p.eval(f64::from(i) / 100.0);
            assert!(lo <= v && v <= hi);
        }
    }

    /// `x^3 - 2` on `[0, 2]`: the exact search ends within 4 eps of `cbrt 2`; with a tolerance
    /// on `g` it stops as soon as `|g(x)| <= g_tol`, with fewer evaluations; an error of `g`
    /// ends the search with that error.
    #[test]
    fn illinois_until_stops_at_its_tolerances_and_errors() {
        let root = 2f64.cbrt();
        let g = |x: f64| x * x * x - 2.0;
        let x = illinois(g, 0.0, -2.0, 2.0, 6.0);
        assert!((x - root).abs() <= 4.0 * f64::EPSILON * root, "{x}");
        // The root with tolerance `g_tol` on `g`, and the evaluations it took.
        let counted = |g_tol: f64| {
            let mut calls = 0;
            let counting = |x: f64| {
                calls += 1;
                Ok::<f64, ()>(g(x))
            };
            let x = illinois_until(counting, 0.0, -2.0, 2.0, 6.0, g_tol, 0.0);
            (x.expect("no error"), calls)
        };
        let (exact, exact_calls) = counted(0.0);
        assert_eq!(exact, x, "illinois is the search with no tolerance");
        let (loose, loose_calls) = counted(1e-6);
        assert!(
            g(loose).abs() <= 1e-6 && loose_calls < exact_calls,
            "{loose}"
        );
        let failed = illinois_until(
            |x| if x > 1.0 { Err(x) } else { Ok(g(x)) },
            0.0,
            -2.0,
            2.0,
            6.0,
            0.0,
            0.0,
        );
        assert!(failed.is_err());
    }

    /// A degree-7 polynomial (Dop853's output degree) with roots 0.3, 0.31, 0.32 and four
    /// outside [0, 1]: the earliest root is found from either end's sign, and the Bernstein
    /// hull encloses every value.
    #[test]
    fn degree_seven_roots_and_hull() {
        let roots = [0.3, 0.31, 0.32, -1.0, 1.5, 2.0, 3.0];
        let mut c = [0.0; MAX_COEFFS];
        c[0] = 1.0;
        for (deg, r) in roots.iter().enumerate() {
            let mut n = [0.0; MAX_COEFFS];
            for i in 0..=deg + 1 {
                n[i] = -r * c[i] + if i > 0 { c[i - 1] } else { 0.0 };
            }
            c = n;
        }
        let p = Poly { c, deg: 7 };
        let th = earliest_root(&|t| p.eval(t), &|a, b| p.enclosure(a, b), 0.0, 1.0);
        assert!((th.expect("a root") - 0.3).abs() < 1e-11, "{th:?}");
        let th = earliest_root(&|t| p.eval(t), &|a, b| p.enclosure(a, b), 0.305, 1.0);
        assert!((th.expect("a root") - 0.31).abs() < 1e-11);
        for (a, b) in [(0.0, 1.0), (0.25, 0.5)] {
            let (lo, hi) = p.range(a, b);
            for i in 0..=100 {
                let v = p.eval(a + (b - a) * f64::from(i) / 100.0);
                assert!(
                    lo - 1e-15 <= v && v <= hi + 1e-15,
                    "{v} outside [{lo}, {hi}]"
                );
            }
        }
    }
}
