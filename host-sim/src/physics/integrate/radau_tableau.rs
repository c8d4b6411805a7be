//! The tableau of the 7-stage Radau IIA method (order 13, stage order 7): nodes, collocation
//! coefficients, the error estimate's `gamma0` and weights, and the matrix that writes the
//! collocation polynomial in the nested form of a step's continuous output.
//!
//! Derived at 60 digits (the nodes as roots of `P_7(2c - 1) - P_6(2c - 1)`, `A` by integrating
//! the Lagrange polynomials of the nodes, `gamma0` and `e` from their definitions) and rounded
//! to 21 digits; the tests below check every constant against its definition in f64. Hairer &
//! Wanner, *Solving ODEs II*, IV.5 (Radau IIA) and IV.8 (the error estimate of `RADAU5` and
//! `RADAU`).

/// Stages.
pub(super) const S: usize = 7;

/// `gamma0`, the real eigenvalue of `A` (the real root of `det(A - gamma0 I) = 0`; `1 / gamma0`
/// is the real root of the denominator of the (s-1, s) Pade approximant to `exp`). It weighs
/// `h f(y0)` in the embedded formula and sets the error filter `(I - h gamma0 J)^-1`.
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
pub(super) const GAMMA0: f64 = 0.111896465300035075936;

/// The nodes `c_i`: the roots of `P_s(2c - 1) - P_(s-1)(2c - 1)` (`P_k` Legendre), `c_s = 1`.
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
pub(super) const C: [f64; S] = [
    0.0293164271597848919721,
    0.148078599668484291850,
    0.336984690281154299097,
    0.558671518771550132081,
    0.769233862030054500917,
    0.926945671319741114852,
    1.00000000000000000000,
];

/// The collocation coefficients `a_ij = integral_0^c_i l_j(t) dt` (`l_j` the Lagrange polynomial
/// of the nodes with `l_j(c_k) = delta_jk`); the last row is the weights `b_j`.
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
pub(super) const A: [[f64; S]; S] = [
    [
        0.0375462649939213313337,
        -0.0140393345564604015376,
        0.0103527896007423009368,
        -0.00815832254027501190920,
        0.00638841387953468494376,
        -0.00460232677914865549935,
        0.00182894256147064370404,
    ],
    [
        0.0801475965156189677952,
        0.0810620639858915366796,
        -0.0212379921207110349371,
        0.0140002912388171189837,
        -0.0102341857300901638292,
        0.00715346515136459049806,
        -0.00281263937240672334034,
    ],
    [
        0.0720638469418819021134,
        0.171068354983886619424,
        0.109614564040072109233,
        -0.0246198717289840538623,
        0.0147603770439508170732,
        -0.00957525939679140055633,
        0.00367267839713830567157,
    ],
    [
        0.0757051258198244204246,
        0.154090155142171144646,
        0.227107736673202386411,
        0.117478187037024781988,
        -0.0238108271530441735820,
        0.0127099855336612056336,
        -0.00460884428128963344034,
    ],
    [
        0.0739123421631918465408,
        0.161355607615942432186,
        0.206867241552104197820,
        0.237007115342694234762,
        0.103086793533813446624,
        -0.0188541391525804488401,
        0.00585890097488879182398,
    ],
    [
        0.0747055620597962301723,
        0.158307223872468700658,
        0.214153423267200031109,
        0.219877847031860039987,
        0.198752121680635269802,
        0.0692655016055091332310,
        -0.00811600819772829010788,
    ],
    [
        0.0744942355560103179332,
        0.159102115733650740872,
        0.212351889502977804199,
        0.223554914507283234750,
        0.190474936822115576903,
        0.119613744612656202894,
        0.0204081632653061224490,
    ],
];

/// The error weights `e = (bhat - b) A^-1`, with `bhat` the embedded weights of order `s`:
/// `gamma0 [q = 1] + sum_i bhat_i c_i^(q-1) = 1/q` for `q = 1 .. s`.
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
pub(super) const E: [f64; S] = [
    -6.08430729113280952203,
    0.783277943092000648144,
    -0.263590149638228428413,
    0.126699144195154188582,
    -0.0723848528985174055938,
    0.0433636160092582378720,
    -0.0159852093285764394194,
];

/// The last row of `A^-1`: `f(y1) = (A^-1 Z)_s / h` for the stage increments `Z` of a
/// converged step (the collocation identity `Z = h A F`).
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
pub(super) const A_INV_LAST: [f64; S] = [
    11.4954552051166652807,
    -8.51707242305662462678,
    8.38103130196482460418,
    -10.0334416519504009909,
    15.0943939429911665406,
    -34.4203663750656308078,
    25.0000000000000000000,
];

/// The collocation polynomial `p(theta)` with `p(0) = 0`, `p(c_i) = z_i` in the nested form of
/// [`crate::physics::integrate::dense::Segment`]: `r_k = sum_i DENSE[k - 1][i] z_i` for
/// `k = 1 .. s` (`r_0 = y0`), the basis `theta^ceil(k/2) (1 - theta)^floor(k/2)`.
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
pub(super) const DENSE: [[f64; S]; S] = [
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.00000000000000000000],
    [
        54.3744368941286145146,
        -7.00002400425918651204,
        2.35566109198755719226,
        -1.13228906610613438638,
        0.646891326767358711867,
        -0.387533385375352377425,
        -0.857142857142857142857,
    ],
    [
        -65.8698920992452797953,
        15.5170964273158111388,
        -10.7366923939523817964,
        11.1657307180565353773,
        -15.7412852697585252525,
        34.8078997604409831852,
        -23.1428571428571428571,
    ],
    [
        -689.360118574533121417,
        273.211701635941239977,
        -95.3446301900061710690,
        41.1573916529693604692,
        -14.4685430714550379900,
        -16.6243728814876985411,
        15.4285714285714285714,
    ],
    [
        887.538512327271947251,
        -452.106857185745272798,
        273.111908085196959349,
        -248.059626224968399333,
        295.582795381629055284,
        -303.495303811955718324,
        141.428571428571428571,
    ],
    [
        2023.97219738226257475,
        -1104.85966226882262785,
        588.804777756487698125,
        -228.562750956537773210,
        -0.00264094126188600811347,
        97.2195075993005856284,
        -56.5714285714285714286,
    ],
    [
        -2735.41419905074769653,
        1778.72623876915360708,
        -1362.19807751020025178,
        1085.50325126088713055,
        -853.899984542750253867,
        616.425628216514607409,
        -245.142857142857142857,
    ],
];

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // the formulas' index notation
mod tests {
    use super::*;

    /// `P_s(u) - P_(s-1)(u)` by the Legendre recurrence `(k+1) P_(k+1) = (2k+1) u P_k - k P_(k-1)`.
    fn radau_poly(u: f64) -> f64 {
        let (mut p0, mut p1) = (1.0, u);
        for k in 1..S {
            let k = k as f64;
            (p0, p1) = (p1, ((2.0 * k + 1.0) * u * p1 - k * p0) / (k + 1.0));
        }
        p1 - p0
    }

    /// `n!` as f64.
    fn fact(n: usize) -> f64 {
        (1..=n).map(|k| k as f64).product()
    }

    #[test]
    fn nodes_are_the_radau_roots() {
        for (i, &c) in C.iter().enumerate() {
            assert!(radau_poly(2.0 * c - 1.0).abs() < 1e-13, "c_{i} = {c}");
            if i > 0 {
                assert!(c > C[i - 1]);
            }
        }
        assert_eq!(C[S - 1], 1.0);
    }

    /// Collocation: `sum_j a_ij c_j^(q-1) = c_i^q / q` for `q = 1 .. s` (stage order `s`).
    #[test]
    fn coefficients_satisfy_the_collocation_conditions() {
        for i in 0..S {
            for q in 1..=S {
                let lhs: f64 = (0..S).map(|j| A[i][j] * C[j].powi(q as i32 - 1)).sum();
                let rhs = C[i].powi(q as i32) / q as f64;
                assert!((lhs - rhs).abs() < 1e-14, "row {i}, q {q}: {lhs} vs {rhs}");
            }
        }
    }

    /// The weights `b` (the last row of `A`) integrate polynomials of degree `2s - 2` exactly:
    /// `sum_j b_j c_j^(q-1) = 1/q` for `q = 1 .. 2s - 1` (order 13).
    #[test]
    fn weights_have_order_thirteen() {
        for q in 1..2 * S {
            let lhs: f64 = (0..S).map(|j| A[S - 1][j] * C[j].powi(q as i32 - 1)).sum();
            assert!((lhs - 1.0 / q as f64).abs() < 1e-14, "q {q}: {lhs}");
        }
    }

    /// `1 / gamma0` is a root of the Pade denominator
    /// `Q(z) = sum_i (2s-1-i)! s! / ((2s-1)! i! (s-i)!) (-z)^i`, whose roots are the reciprocal
    /// eigenvalues of `A`; and `A - gamma0 I` is singular (`det` by elimination, against the
    /// product of the pivots' scale).
    #[test]
    fn gamma0_is_the_real_eigenvalue() {
        let z = 1.0 / GAMMA0;
        let terms: Vec<f64> = (0..=S)
            .map(|i| {
                fact(2 * S - 1 - i) * fact(S) / (fact(2 * S - 1) * fact(i) * fact(S - i))
                    * (-z).powi(i as i32)
            })
            .collect();
        let sum: f64 = terms.iter().sum();
        let scale: f64 = terms.iter().map(|t| t.abs()).sum();
        assert!(sum.abs() < 1e-14 * scale, "Q(1/gamma0) = {sum} of {scale}");
        let mut m = A;
        for (i, row) in m.iter_mut().enumerate() {
            row[i] -= GAMMA0;
        }
        let mut det = 1.0;
        for k in 0..S {
            let p = (k..S)
                .max_by(|&a, &b| m[a][k].abs().total_cmp(&m[b][k].abs()))
                .unwrap();
            m.swap(k, p);
            det *= m[k][k];
            for r in k + 1..S {
                let l = m[r][k] / m[k][k];
                for c in k..S {
                    m[r][c] -= l * m[k][c];
                }
            }
        }
        let mut unshifted = 1.0;
        for row in &A {
            unshifted *= row.iter().map(|a| a.abs()).sum::<f64>();
        }
        assert!(det.abs() < 1e-13 * unshifted, "det {det} of {unshifted}");
    }

    /// `bhat = b + e A` has order `s` with `gamma0` on `f(y0)`:
    /// `gamma0 [q = 1] + sum_i bhat_i c_i^(q-1) = 1/q` for `q = 1 .. s`.
    #[test]
    fn error_weights_give_the_embedded_formula() {
        let bhat: Vec<f64> = (0..S)
            .map(|j| A[S - 1][j] + (0..S).map(|i| E[i] * A[i][j]).sum::<f64>())
            .collect();
        for q in 1..=S {
            let lhs: f64 = (0..S)
                .map(|i| bhat[i] * C[i].powi(q as i32 - 1))
                .sum::<f64>()
                + if q == 1 { GAMMA0 } else { 0.0 };
            assert!((lhs - 1.0 / q as f64).abs() < 1e-13, "q {q}: {lhs}");
        }
        // bhat differs from b: the estimate is not zero.
        assert!((0..S).any(|j| (bhat[j] - A[S - 1][j]).abs() > 1e-3));
    }

    #[test]
    fn last_row_of_the_inverse() {
        for k in 0..S {
            let v: f64 = (0..S).map(|j| A_INV_LAST[j] * A[j][k]).sum();
            let want = if k == S - 1 { 1.0 } else { 0.0 };
            assert!((v - want).abs() < 1e-13, "column {k}: {v}");
        }
    }

    /// The nested form through `DENSE` interpolates: `p(c_i) = z_i` for each unit `z`.
    #[test]
    fn dense_matrix_interpolates_the_stages() {
        for m in 0..S {
            let r: Vec<f64> = (0..S).map(|k| DENSE[k][m]).collect();
            for (i, &th) in C.iter().enumerate() {
                let mut acc = r[S - 1];
                for k in (0..S - 1).rev() {
                    acc = r[k] + if k % 2 == 0 { 1.0 - th } else { th } * acc;
                }
                let p = th * acc;
                let want = if i == m { 1.0 } else { 0.0 };
                assert!((p - want).abs() < 1e-11, "z_{m} at c_{i}: {p}");
            }
        }
    }
}
