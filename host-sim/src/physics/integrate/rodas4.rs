//! Rodas4, the L-stable, stiffly accurate Rosenbrock method of order 4(3) (Hairer & Wanner,
//! *Solving ODEs II*, IV.7; coefficients of Hairer's `RODAS`, `METH = 1`), one step on the
//! exact 2 x 2 Jacobian, with its 3rd-order continuous output.
//!
//! The stages solve `(I / (h gamma) - J) k_i = f(y + sum_j a_ij k_j) + sum_j c_ij k_j / h`
//! (`k_i` are increments); the 6th stage is the solution, the 5th the embedded one, and
//! their difference `k_6` the error estimate. The continuous output is
//! `y(theta) = (1 - theta) y0 + theta (y1 + (1 - theta) (d2 + theta d3))` with
//! `d2 = sum_j d2j k_j`, `d3 = sum_j d3j k_j` over the first five stages.

use crate::physics::integrate::dense::Segment;
use crate::physics::integrate::error_scale::ErrorScale;
use crate::physics::integrate::rhs::{Rhs, Trial};

const GAMMA: f64 = 0.25;
/// `a_ij` (`y_i = y0 + sum_j a_ij k_j`) of stages 2 to 5 (the 6th is the 5th plus `k_5`).
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
const A: [[f64; 4]; 4] = [
    [1.544, 0.0, 0.0, 0.0],
    [0.9466785280815826, 0.2557011698983284, 0.0, 0.0],
    [
        3.314825187068521,
        2.896124015972201,
        0.9986419139977817,
        0.0,
    ],
    [
        1.221224509226641,
        6.019134481288629,
        12.53708332932087,
        -0.687886036105895,
    ],
];
/// `c_ij` of stages 2 to 6.
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
const C: [[f64; 5]; 5] = [
    [-5.6688, 0.0, 0.0, 0.0, 0.0],
    [-2.430093356833875, -0.2063599157091915, 0.0, 0.0, 0.0],
    [
        -0.1073529058151375,
        -9.594562251023355,
        -20.47028614809616,
        0.0,
        0.0,
    ],
    [
        7.496443313967647,
        -10.24680431464352,
        -33.99990352819905,
        11.7089089320616,
        0.0,
    ],
    [
        8.083246795921522,
        -7.981132988064893,
        -31.52159432874371,
        16.31930543123136,
        -6.058818238834054,
    ],
];
/// The continuous output's `d2j` and `d3j`.
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
const D: [[f64; 5]; 2] = [
    [
        10.12623508344586,
        -7.487995877610167,
        -34.80091861555747,
        -7.992771707568823,
        1.025137723295662,
    ],
    [
        -0.6762803392801253,
        6.087714651680015,
        16.43084320892478,
        24.76722511418386,
        -6.594389125716872,
    ],
];

/// `sum_j w_j k_j` over the stages given.
fn dot(w: &[f64], ks: &[[f64; 2]]) -> [f64; 2] {
    let mut out = [0.0; 2];
    for (wj, k) in w.iter().zip(ks) {
        out[0] += wj * k[0];
        out[1] += wj * k[1];
    }
    out
}

/// One Rodas4 step of size `h` from `(t, y)` with slope `f0`: 5 evaluations of the
/// right-hand side and one of the Jacobian, and one more at the step's end when it passes its
/// error test (the next step's slope). A singular `I / (h gamma) - J` gives a non-finite
/// trial.
pub(super) fn rodas4_step(
    rhs: &mut Rhs,
    t: f64,
    y: [f64; 2],
    f0: [f64; 2],
    h: f64,
    scale: &ErrorScale,
) -> Trial {
    let j = rhs.jac(y);
    let fac = 1.0 / (h * GAMMA);
    let m = [[fac - j[0][0], -j[0][1]], [-j[1][0], fac - j[1][1]]];
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let solve = |b: [f64; 2]| {
        [
            (m[1][1] * b[0] - m[0][1] * b[1]) / det,
            (m[0][0] * b[1] - m[1][0] * b[0]) / det,
        ]
    };
    let mut ks = [[0.0; 2]; 6];
    ks[0] = solve(f0);
    let mut ynew = y;
    for s in 1..6 {
        let base = if s < 5 { y } else { ynew };
        let incr = if s < 5 {
            dot(&A[s - 1], &ks[..s])
        } else {
            ks[4]
        };
        ynew = [base[0] + incr[0], base[1] + incr[1]];
        let dy = rhs.f(ynew);
        let c = dot(&C[s - 1], &ks[..s]);
        ks[s] = solve([dy[0] + c[0] / h, dy[1] + c[1] / h]);
    }
    let y1 = [ynew[0] + ks[5][0], ynew[1] + ks[5][1]];
    let err = scale.norm(ks[5], y, y1);
    let (f1, force1_n) = if err <= 1.0 {
        (rhs.f(y1), rhs.last_force_n)
    } else {
        ([f64::NAN; 2], f64::NAN)
    };
    let d2 = dot(&D[0], &ks[..5]);
    let d3 = dot(&D[1], &ks[..5]);
    let r = [0, 1].map(|i| [y[i], y1[i] - y[i], d2[i], d3[i]]);
    Trial {
        y1,
        f1,
        force1_n,
        seg: Segment::nested(t, h, r),
        err,
    }
}
