//! The equation of motion in scaled units, and what one trial step of it returns.

use crate::physics::integrate::dense::Segment;
use crate::physics::laws::ForceLaw;

/// Right-hand side in scaled units, counting evaluations.
pub(super) struct Rhs {
    pub(super) law: ForceLaw,
    pub(super) d_m: f64,
    pub(super) u_m_s: f64,
    /// dx/dtau = cx v
    pub(super) cx: f64,
    /// gravity term of dv/dtau
    pub(super) g: f64,
    /// T / (u m)
    pub(super) p: f64,
    pub(super) evals: usize,
    /// Evaluations of the Jacobian.
    pub(super) jac_evals: usize,
    /// The last Jacobian evaluated.
    pub(super) last_jac: Option<[[f64; 2]; 2]>,
    /// The force (N) of the last evaluation.
    pub(super) last_force_n: f64,
}

impl Rhs {
    pub(super) fn f(&mut self, y: [f64; 2]) -> [f64; 2] {
        self.evals += 1;
        let force = self.law.force(y[0] * self.d_m, y[1] * self.u_m_s);
        self.last_force_n = force;
        [self.cx * y[1], self.g - self.p * force]
    }

    /// The exact Jacobian `d(dx/dtau, dv/dtau) / d(x, v)` at `y`:
    /// `[[0, cx], [-p delta_max dF/ddelta, -p u dF/ddelta_dot]]` from
    /// [`ForceLaw::force_gradient`] (rows: the two rates).
    pub(super) fn jac(&mut self, y: [f64; 2]) -> [[f64; 2]; 2] {
        self.jac_evals += 1;
        let (dfd, dfv) = self.law.force_gradient(y[0] * self.d_m, y[1] * self.u_m_s);
        let j = [
            [0.0, self.cx],
            [-self.p * self.d_m * dfd, -self.p * self.u_m_s * dfv],
        ];
        self.last_jac = Some(j);
        j
    }
}

/// The largest modulus of the eigenvalues of a 2 x 2 matrix `j` (its spectral radius).
pub(super) fn spectral_radius(j: [[f64; 2]; 2]) -> f64 {
    let half_tr = 0.5 * (j[0][0] + j[1][1]);
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    let disc = half_tr * half_tr - det;
    if disc >= 0.0 {
        let r = disc.sqrt();
        (half_tr + r).abs().max((half_tr - r).abs())
    } else {
        det.abs().sqrt()
    }
}

pub(super) fn lin(y: [f64; 2], h: f64, terms: &[(f64, [f64; 2])]) -> [f64; 2] {
    let mut out = y;
    for i in 0..2 {
        let mut acc = 0.0;
        for (c, k) in terms {
            acc += c * k[i];
        }
        out[i] += h * acc;
    }
    out
}

/// Result of one trial step.
pub(super) struct Trial {
    pub(super) y1: [f64; 2],
    pub(super) f1: [f64; 2],
    /// The force (N) at `y1`.
    pub(super) force1_n: f64,
    pub(super) seg: Segment,
    /// Scaled error norm (adaptive methods), 0 for RK4.
    pub(super) err: f64,
}
