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
    /// Which force [`Rhs::f_side`] and [`Rhs::jac_side`] take (Radau13's stages).
    pub(super) side: Side,
    /// For the undamped Hertz law with `n = 1.5` ([`Rhs::hertz_scaled`]): `(k delta_max^1.5`
    /// in N, `p k delta_max^1.5)`, so that [`Rhs::f`] is `[cx v, g - p k delta_max^1.5
    /// x^1.5]` with one square root and no unit conversion; `None` for every other law.
    pub(super) hertz: Option<(f64, f64)>,
}

/// The force a step on one side of the clamp's switch sees: the law's own (clamped at zero),
/// or, while every switch is located, its smooth continuation on the current side: the
/// unclamped force `G` while the force is on, none while the clamp holds it at zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Side {
    /// [`ForceLaw::force`] (undamped Hertz, a method that never steps with Radau13, or once
    /// the clamp's switches are no longer located).
    Law,
    /// [`ForceLaw::unclamped_force`]: the force is on.
    On,
    /// No force: the clamp holds it at zero.
    Off,
}

impl Rhs {
    /// `[cx v, g - p F(x delta_max, v u)]` at the scaled state `y`: the law's force, or for
    /// undamped Hertz `F = k delta_max^1.5 x^1.5` (`x > 0`, else 0) with the constant hoisted
    /// ([`Rhs::hertz`]).
    pub(super) fn f(&mut self, y: [f64; 2]) -> [f64; 2] {
        if let Some((force_scale, rate_scale)) = self.hertz {
            let x = y[0];
            let q = if x > 0.0 { x * x.sqrt() } else { 0.0 };
            self.evals += 1;
            self.last_force_n = force_scale * q;
            return [self.cx * y[1], self.g - rate_scale * q];
        }
        let force = self.law.force(y[0] * self.d_m, y[1] * self.u_m_s);
        self.rates(y, force)
    }

    /// [`Rhs::hertz`] for `law`: `Some((k delta_max^1.5, p k delta_max^1.5))` (N, and per
    /// scaled time) for [`ForceLaw::Hertz`] with `n = 1.5`, else `None`.
    pub(super) fn hertz_scaled(law: &ForceLaw, d_m: f64, p: f64) -> Option<(f64, f64)> {
        match *law {
            ForceLaw::Hertz {
                stiffness,
                exponent: 1.5,
            } => {
                let force_scale = stiffness * d_m * d_m.sqrt();
                Some((force_scale, p * force_scale))
            }
            _ => None,
        }
    }

    /// Puts `law` in force (the law after a history-dependent law's turn).
    pub(super) fn set_law(&mut self, law: ForceLaw) {
        self.law = law;
        self.hertz = Self::hertz_scaled(&law, self.d_m, self.p);
    }

    /// `[cx v, g - p F]` at `y` for the force `F` (N), counted as one force evaluation.
    fn rates(&mut self, y: [f64; 2], force: f64) -> [f64; 2] {
        self.evals += 1;
        self.last_force_n = force;
        [self.cx * y[1], self.g - self.p * force]
    }

    /// [`Rhs::f`] with the force of [`Rhs::side`]: `[cx v, g - p F]` with `F` the law's force,
    /// the unclamped force `G`, or 0. Counted as a force evaluation.
    pub(super) fn f_side(&mut self, y: [f64; 2]) -> [f64; 2] {
        let (d, v) = (y[0] * self.d_m, y[1] * self.u_m_s);
        let force = match self.side {
            Side::Law => self.law.force(d, v),
            Side::On => self.law.unclamped_force(d, v),
            Side::Off => 0.0,
        };
        self.rates(y, force)
    }

    /// The side a state `y` on the clamp's switch (`G = 0`, so that both sides' forces are 0
    /// there) moves into: the sign of the switching function's rate
    /// `dG/dtau = dG/ddelta delta_max cx v + dG/ddelta_dot u g` (force 0, gradient of the
    /// [`ForceLaw::unclamped_force`]); [`Rhs::side`] unchanged where it is 0. Deciding by the
    /// rate, not by alternating, keeps a sign change that the continuous output shows but the
    /// solution does not (the creep of a heavily damped contact, where `G` stays within
    /// rounding of zero) from switching the force off. Part of the event's location, and
    /// like the event search not counted as an evaluation.
    pub(super) fn side_leaving_switch(&self, y: [f64; 2]) -> Side {
        let (dfd, dfv) = self
            .law
            .unclamped_force_gradient(y[0] * self.d_m, y[1] * self.u_m_s);
        let rate = dfd * self.d_m * self.cx * y[1] + dfv * self.u_m_s * self.g;
        if rate > 0.0 {
            Side::On
        } else if rate < 0.0 {
            Side::Off
        } else {
            self.side
        }
    }

    /// The force (N) a rate `f` of [`Rhs::f_side`] implies, without an evaluation:
    /// `max(0, (g - f_v) / p)` (the clamped force), 0 on [`Side::Off`].
    pub(super) fn force_of_rate(&self, f: [f64; 2]) -> f64 {
        match self.side {
            Side::Off => 0.0,
            Side::Law | Side::On => ((self.g - f[1]) / self.p).max(0.0),
        }
    }

    /// [`Rhs::jac`] of [`Rhs::f_side`]: the force's gradient is the law's
    /// ([`ForceLaw::force_gradient`]), the unclamped force's
    /// ([`ForceLaw::unclamped_force_gradient`]) or 0. Counted as a Jacobian evaluation.
    pub(super) fn jac_side(&mut self, y: [f64; 2]) -> [[f64; 2]; 2] {
        let (d, v) = (y[0] * self.d_m, y[1] * self.u_m_s);
        let (dfd, dfv) = match self.side {
            Side::Law => self.law.force_gradient(d, v),
            Side::On => self.law.unclamped_force_gradient(d, v),
            Side::Off => (0.0, 0.0),
        };
        self.jacobian(dfd, dfv)
    }

    /// The exact Jacobian `d(dx/dtau, dv/dtau) / d(x, v)` at `y`:
    /// `[[0, cx], [-p delta_max dF/ddelta, -p u dF/ddelta_dot]]` from
    /// [`ForceLaw::force_gradient`] (rows: the two rates).
    pub(super) fn jac(&mut self, y: [f64; 2]) -> [[f64; 2]; 2] {
        let (dfd, dfv) = self.law.force_gradient(y[0] * self.d_m, y[1] * self.u_m_s);
        self.jacobian(dfd, dfv)
    }

    /// `[[0, cx], [-p delta_max dfd, -p u dfv]]` for the force's gradient `(dfd, dfv)` (N/m,
    /// N s/m), counted as one Jacobian evaluation.
    fn jacobian(&mut self, dfd: f64, dfv: f64) -> [[f64; 2]; 2] {
        self.jac_evals += 1;
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
