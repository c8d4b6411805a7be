//! Radau13, the 7-stage Radau IIA collocation method of order 13 (Hairer & Wanner, *Solving
//! ODEs II*, IV.5 and IV.8, Hairer's `RADAU5` and `RADAU`): one step by simplified Newton on
//! the full 14 x 14 stage system, its embedded error estimate, and the collocation polynomial
//! as continuous output.
//!
//! The stage increments `Z = (z_1 .. z_7)`, `z_i = y(t + c_i h) - y0`, solve
//! `z_i = h sum_j a_ij f(y0 + z_j)`, `y1 = y0 + z_7` ([`super::radau_tableau`]). Newton's
//! matrix is `I - h [a_ij J_j]` with `J_j = J_a + c_j (J_b - J_a)`: the exact Jacobian
//! interpolated linearly between the step's start (`J_a`, the previous step's `J_b`) and its
//! end predicted by the previous step's collocation polynomial (`J_b`), one Jacobian per
//! step, one LU per step. The iteration starts from that polynomial extrapolated to the new
//! nodes and stops at `faccon |dZ| <= kappa = 0.1` (RADAU5's convergence control with the
//! rate `theta`, at most 7 iterations; a slow or diverging iteration shrinks the step as
//! RADAU5 does). The error is `err = (I - h gamma0 J_a)^-1 (gamma0 h f(y0) + sum_i e_i z_i)`
//! (RADAU5's, with `gamma0` the real eigenvalue of `A`; filtered once more through `f` at
//! `y0 + err` on a first or retried step whose error fails), and `f(y1)` comes free from the
//! collocation identity `f(y1) = (A^-1 Z)_7 / h`. The step-size factor is RADAU5's:
//! `err^(1/8) / fac` with `fac = 0.9 min(1, (2 NIT + 1) / (2 NIT + newt))`, `NIT = 7`, `newt`
//! the iterations taken, and Gustafsson's predictive factor (`control`).
//!
//! The stages see the force of [`Rhs::side`]: the unclamped force while it is on and no force
//! while the clamp holds it at zero, so that the stage equations stay smooth; the clamp's
//! switch is then an event that ends the step (`switching`), where the side flips.

use crate::physics::integrate::dense::Segment;
use crate::physics::integrate::error_scale::ErrorScale;
use crate::physics::integrate::lu::Lu;
use crate::physics::integrate::radau_tableau::{A, A_INV_LAST, C, DENSE, E, GAMMA0, S};
use crate::physics::integrate::rhs::{Rhs, Trial};

/// RADAU5's safety factor (its `SAFE`, 0.9 as in the other methods' controller), which
/// [`RadauState::safety`] lowers with the Newton iterations.
const SAFE: f64 = 0.9;
/// Newton iterations per step at most (RADAU5's `NIT`).
const NIT: usize = 7;
/// Newton's stopping constant (`faccon |dZ| <= KAPPA`, on the error scale).
const KAPPA: f64 = 0.1;
/// Unknowns of the stage system.
const N: usize = 2 * S;
/// Step factor after a diverging Newton iteration (RADAU5's).
const DIVERGED: f64 = 0.5;

type Jac = [[f64; 2]; 2];
type Stages = [[f64; 2]; S];

/// What an accepted step hands to the next: its end time, its continuous output (extrapolated
/// for the next step's starting values and Jacobian point) and the Jacobian at its predicted
/// end (`None` after a restart, whose one Jacobian was at its start).
#[derive(Debug, Clone, Copy)]
struct Carry {
    t1: f64,
    seg: Segment,
    j1: Option<Jac>,
}

/// The state Radau13 keeps between steps.
#[derive(Debug, Clone, Copy)]
pub(super) struct RadauState {
    /// The last accepted step's carry (`None` at a start or restart).
    carry: Option<Carry>,
    /// The last trial's carry, kept if it is accepted.
    pending: Option<Carry>,
    /// RADAU5's `faccon`: `theta / (1 - theta)` of the last Newton iteration.
    faccon: f64,
    /// The step-size controller's safety factor after the last trial:
    /// `0.9 min(1, (2 NIT + 1) / (2 NIT + newt))`.
    pub(super) safety: f64,
}

impl RadauState {
    pub(super) fn new() -> Self {
        Self {
            carry: None,
            pending: None,
            faccon: 1.0,
            safety: SAFE,
        }
    }

    /// The last trial was accepted: its carry serves the next step, unless the integration
    /// restarts there (an event: the law, or the side of the clamp, changes).
    pub(super) fn accepted(&mut self, restart: bool) {
        if restart || self.pending.is_none() {
            // Writes the two tags only: an explicit stepper's accepted step copies nothing.
            self.carry = None;
            self.pending = None;
        } else {
            self.carry = self.pending.take();
        }
    }

    /// Forgets the previous steps (another stepper took over).
    pub(super) fn reset(&mut self) {
        self.carry = None;
        self.pending = None;
    }
}

/// One Radau13 step of size `h` from `(t, y)` with slope `f0` (of the side's force);
/// `retry` when the last trial from here was rejected.
pub(super) fn radau_step(
    rhs: &mut Rhs,
    state: &mut RadauState,
    (t, y, f0): (f64, [f64; 2], [f64; 2]),
    h: f64,
    scale: &ErrorScale,
    retry: bool,
) -> Trial {
    let carry = state.carry.filter(|c| c.t1 == t);
    let (mut z, ja, jb) = start(rhs, carry.as_ref(), t, y, h);
    let newt = match newton_matrix(h, ja, jb) {
        Some(lu) => newton(rhs, state, &lu, y, h, scale, &mut z),
        None => Err(DIVERGED),
    };
    let newt = match newt {
        Ok(n) => n,
        Err(shrink) => return failed(state, t, y, f0, shrink),
    };
    let y1 = [y[0] + z[S - 1][0], y[1] + z[S - 1][1]];
    let filter = carry.is_none() || retry;
    let err = estimate(rhs, (y, y1, f0), h, ja, &z, scale, filter);
    let ratio = (2 * NIT + 1) as f64 / (2 * NIT + newt) as f64;
    state.safety = SAFE * ratio.min(1.0);
    let f1 = [0, 1].map(|r| (0..S).map(|i| A_INV_LAST[i] * z[i][r]).sum::<f64>() / h);
    let seg = dense(t, h, y, &z);
    state.pending = Some(Carry {
        t1: t + h,
        seg,
        j1: Some(jb),
    });
    // Auto's choice reads the Jacobian at the step's start, as it reads Rodas4's.
    rhs.last_jac = Some(ja);
    Trial {
        y1,
        f1,
        force1_n: rhs.force_of_rate(f1),
        seg,
        err,
    }
}

/// Starting values and the Jacobians at the step's start and end: from the last accepted
/// step's collocation polynomial extrapolated to `t + c_i h`, else `Z = 0` and one Jacobian
/// at `y` for both.
fn start(rhs: &mut Rhs, carry: Option<&Carry>, t: f64, y: [f64; 2], h: f64) -> (Stages, Jac, Jac) {
    let Some(c) = carry else {
        let j = rhs.jac_side(y);
        return ([[0.0; 2]; S], j, j);
    };
    let z = C.map(|ci| {
        let p = c.seg.eval((t + ci * h - c.seg.t0) / c.seg.h);
        [p[0] - y[0], p[1] - y[1]]
    });
    let ja = match c.j1 {
        Some(j) => j,
        None => rhs.jac_side(y),
    };
    let jb = rhs.jac_side([y[0] + z[S - 1][0], y[1] + z[S - 1][1]]);
    (z, ja, jb)
}

/// The LU of Newton's matrix `I - h [a_ij J_j]`, `J_j = J_a + c_j (J_b - J_a)`, in 2 x 2
/// blocks (`None` when singular).
fn newton_matrix(h: f64, ja: Jac, jb: Jac) -> Option<Lu<N>> {
    let mut m = [[0.0; N]; N];
    for j in 0..S {
        let jj = [0, 1].map(|r| [0, 1].map(|c| ja[r][c] + C[j] * (jb[r][c] - ja[r][c])));
        for i in 0..S {
            let ha = h * A[i][j];
            for r in 0..2 {
                for c in 0..2 {
                    m[2 * i + r][2 * j + c] = -ha * jj[r][c];
                }
            }
        }
    }
    for (k, row) in m.iter_mut().enumerate() {
        row[k] += 1.0;
    }
    Lu::new(m)
}

/// Simplified Newton on `z_i - h sum_j a_ij f(y0 + z_j) = 0` (RADAU5's iteration and
/// convergence control): the iterations taken, or the factor to shrink the step by when the
/// iteration diverges or would not converge within [`NIT`].
fn newton(
    rhs: &mut Rhs,
    state: &mut RadauState,
    lu: &Lu<N>,
    y: [f64; 2],
    h: f64,
    scale: &ErrorScale,
    z: &mut Stages,
) -> Result<usize, f64> {
    state.faccon = state.faccon.max(f64::EPSILON).powf(0.8);
    let (mut dynold, mut thqold) = (0.0, 1.0);
    for newt in 1..=NIT {
        let fz = z.map(|zi| rhs.f_side([y[0] + zi[0], y[1] + zi[1]]));
        let mut g = [0.0; N];
        for i in 0..S {
            for r in 0..2 {
                let hf: f64 = (0..S).map(|j| A[i][j] * fz[j][r]).sum();
                g[2 * i + r] = h * hf - z[i][r];
            }
        }
        let dz = lu.solve(g);
        // The error scale over the step as this iterate has it (at first contact `x` starts
        // at 0, where a scale of `y0` alone would vanish).
        let end = [0, 1].map(|r| y[r] + z[S - 1][r] + dz[2 * S - 2 + r]);
        let sk = [scale.sk(0, y[0], end[0]), scale.sk(1, y[1], end[1])];
        let sum2: f64 = (0..N).map(|k| (dz[k] / sk[k % 2]).powi(2)).sum();
        let dyno = (sum2 / N as f64).sqrt();
        if !dyno.is_finite() {
            return Err(DIVERGED);
        }
        if newt > 1 {
            let thq = dyno / dynold;
            let theta = if newt == 2 {
                thq
            } else {
                (thq * thqold).sqrt()
            };
            thqold = thq;
            if theta >= 0.99 {
                return Err(DIVERGED);
            }
            state.faccon = theta / (1.0 - theta);
            let left = NIT as i32 - 1 - newt as i32;
            let dyth = state.faccon * dyno * theta.powi(left) / KAPPA;
            if dyth >= 1.0 {
                let q = dyth.clamp(1e-4, 20.0);
                return Err(0.8 * q.powf(-1.0 / (4.0 + f64::from(left))));
            }
        }
        dynold = dyno.max(f64::EPSILON);
        for (i, zi) in z.iter_mut().enumerate() {
            zi[0] += dz[2 * i];
            zi[1] += dz[2 * i + 1];
        }
        if state.faccon * dyno <= KAPPA {
            return Ok(newt);
        }
    }
    Err(DIVERGED)
}

/// The scaled error norm of `(I - h gamma0 J_a)^-1 (gamma0 h f(y0) + sum_i e_i z_i)`; with
/// `filter`, an error above 1 is recomputed with `f` at `y0 + err` in place of `f(y0)`
/// (RADAU5's second filtering on a first or rejected step). Infinite when the filter matrix
/// is singular.
fn estimate(
    rhs: &mut Rhs,
    (y, y1, f0): ([f64; 2], [f64; 2], [f64; 2]),
    h: f64,
    ja: Jac,
    z: &Stages,
    scale: &ErrorScale,
    filter: bool,
) -> f64 {
    let hg = h * GAMMA0;
    let ez = [0, 1].map(|r| (0..S).map(|i| E[i] * z[i][r]).sum::<f64>());
    let m = [
        [1.0 - hg * ja[0][0], -hg * ja[0][1]],
        [-hg * ja[1][0], 1.0 - hg * ja[1][1]],
    ];
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    if det == 0.0 || !det.is_finite() {
        return f64::INFINITY;
    }
    let err_of = |f: [f64; 2]| {
        let b = [hg * f[0] + ez[0], hg * f[1] + ez[1]];
        let e = [
            (m[1][1] * b[0] - m[0][1] * b[1]) / det,
            (m[0][0] * b[1] - m[1][0] * b[0]) / det,
        ];
        (scale.norm(e, y, y1), e)
    };
    let (err, e) = err_of(f0);
    if err >= 1.0 && filter {
        let fx = rhs.f_side([y[0] + e[0], y[1] + e[1]]);
        return err_of(fx).0;
    }
    err
}

/// The collocation polynomial `y0 + p(theta)`, `p(c_i) = z_i`, as a nested segment of
/// degree 7 ([`DENSE`]).
fn dense(t: f64, h: f64, y: [f64; 2], z: &Stages) -> Segment {
    let r = [0, 1].map(|comp| {
        let mut r = [0.0; S + 1];
        r[0] = y[comp];
        for (k, row) in DENSE.iter().enumerate() {
            r[k + 1] = (0..S).map(|i| row[i] * z[i][comp]).sum();
        }
        r
    });
    Segment::nested(t, h, r)
}

/// A step whose Newton iteration failed: rejected with the error that shrinks it by `shrink`
/// (`(SAFE / shrink)^8`, as the controller's factor is `err^(1/8) / SAFE`).
fn failed(state: &mut RadauState, t: f64, y: [f64; 2], f0: [f64; 2], shrink: f64) -> Trial {
    state.pending = None;
    state.safety = SAFE;
    Trial {
        y1: y,
        f1: f0,
        force1_n: f64::NAN,
        seg: Segment::hermite(t, 0.0, y, f0, y, f0),
        err: (SAFE / shrink).powi(8),
    }
}
