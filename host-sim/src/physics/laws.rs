//! Normal contact force laws for a sphere on a flat plate.
//!
//! Sign convention everywhere: `delta > 0` is penetration (m), `delta_dot` its rate (m/s),
//! positive while the sphere approaches the plate. The force `F` (N) is the plate's push on the
//! sphere, positive when repulsive; every law returns 0 for `delta <= 0` and, except undamped
//! Hertz (which cannot pull), is clamped at zero so that it never pulls.
//!
//! [`ForceLaw`] is the concrete law with numbers in SI units; the user's choice (for example
//! "Flores with e = 0.5") is a `LawSpec` of the `law_spec` module above this one, which builds
//! a [`ForceLaw`] for a given scene.

use serde::{Deserialize, Serialize};

use crate::physics::hertz64::{non_negative, positive};
use crate::physics::sim_error::SimError;
use crate::physics::thornton::ThorntonContact;

/// Adams' cubic STEP function (MSC Adams/Solver function reference, `STEP`):
/// `h0` for `x <= x0`, `h1` for `x >= x1`, else `h0 + (h1 - h0) s^2 (3 - 2 s)` with
/// `s = (x - x0)/(x1 - x0)`.
///
/// It is C1 (value and slope continuous); its second derivative jumps at `x0` and `x1`.
pub fn step_cubic(x: f64, x0: f64, h0: f64, x1: f64, h1: f64) -> f64 {
    if x <= x0 {
        h0
    } else if x >= x1 {
        h1
    } else {
        let s = (x - x0) / (x1 - x0);
        h0 + (h1 - h0) * s * s * (3.0 - 2.0 * s)
    }
}

/// Tsuji damping ratio `beta = ln e / sqrt(ln^2 e + pi^2)` (dimensionless, in [-1, 0] for
/// `e` in (0, 1]). Source: Tsuji, Tanaka & Ishida, Powder Technol. 71 (1992) 239-250, as
/// implemented in EDEM, LIGGGHTS and Chrono SMC (Hertz-Mindlin).
pub fn tsuji_beta(restitution: f64) -> f64 {
    let l = restitution.ln();
    l / (l * l + core::f64::consts::PI * core::f64::consts::PI).sqrt()
}

/// `delta^exponent`, written as `delta * sqrt(delta)` for the Hertz exponent 1.5.
fn pow_e(delta_m: f64, exponent: f64) -> f64 {
    if exponent == 1.5 {
        delta_m * delta_m.sqrt()
    } else {
        delta_m.powf(exponent)
    }
}

/// Restitution-based damping models `F = K delta^n (1 + chi delta_dot / u0)`, which differ in
/// how the hysteresis factor `chi` is derived from the target coefficient of restitution `e`.
///
/// With `n = 1.5` these laws (and Tsuji's) are scale-free: in the units of the Hertz closed
/// forms the equation of motion does not depend on size, speed or material, so the simulated
/// restitution is a function of the target alone. The figures quoted below are that function
/// (force clamped at zero, no gravity).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RestitutionModel {
    /// Hunt & Crossley, J. Appl. Mech. 42 (1975) 440-445: `chi = 3 (1 - e) / 2`.
    /// Derived for `e` near 1; with the force clamped at zero it overshoots the target `e` at
    /// low `e` (simulated e = 0.581, 0.663, 0.833, 0.952 for targets 0.3, 0.5, 0.8, 0.95).
    HuntCrossley,
    /// Lankarani & Nikravesh, J. Mech. Des. 112 (1990) 369-376: `chi = 3 (1 - e^2) / 4`.
    /// Derived for `e` near 1; overshoots the target `e` at low `e` (simulated 0.684, 0.725,
    /// 0.847, 0.954 for targets 0.3, 0.5, 0.8, 0.95).
    LankaraniNikravesh,
    /// Flores, Machado, Silva & Martins, Multibody Syst. Dyn. 25 (2011) 357-375:
    /// `chi = 8 (1 - e) / (5 e)`. Valid over the whole range of `e` (simulated 0.256, 0.470,
    /// 0.789, 0.947 for targets 0.3, 0.5, 0.8, 0.95).
    Flores,
    /// Gonthier, McPhee, Lange & Piedboeuf, Multibody Syst. Dyn. 11 (2004) 209-233:
    /// `chi = (1 - e^2) / e`. Valid over the whole range of `e` (simulated 0.304, 0.488,
    /// 0.768, 0.936 for targets 0.3, 0.5, 0.8, 0.95).
    Gonthier,
}

impl RestitutionModel {
    /// The hysteresis factor `chi(e)` (dimensionless) of the model for restitution `e`.
    pub fn chi(self, restitution: f64) -> f64 {
        let e = restitution;
        match self {
            Self::HuntCrossley => 1.5 * (1.0 - e),
            Self::LankaraniNikravesh => 0.75 * (1.0 - e * e),
            Self::Flores => 8.0 * (1.0 - e) / (5.0 * e),
            Self::Gonthier => (1.0 - e * e) / e,
        }
    }
}

/// A concrete normal force law `F(delta, delta_dot)` in SI units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ForceLaw {
    /// Undamped Hertz: `F = k delta^n` for `delta > 0`, else 0 (`n = 1.5` for a sphere).
    /// Source: Hertz (1882); the paper's eq. (3).
    Hertz {
        /// `k` in N/m^n.
        stiffness: f64,
        /// `n` (dimensionless).
        exponent: f64,
    },
    /// MSC Adams IMPACT in penetration form (the paper's eq. (12), physics notes section 2):
    /// `F = max(0, k delta^e + STEP(delta, 0, 0, d, c_max) delta_dot)` for `delta > 0`, else 0.
    /// Source: MSC Adams/Solver function reference, `IMPACT` and `STEP`.
    ///
    /// Continuous in `delta`; its damping coefficient has a jump in the second derivative at
    /// `delta = d` (see [`ForceLaw::kink_m`]), so the integrator stops and restarts there.
    AdamsImpact {
        /// `k` in N/m^e.
        stiffness: f64,
        /// `e` (dimensionless; 1.5 for sphere on flat).
        exponent: f64,
        /// Full damping coefficient `c_max` in N s/m, reached at `delta >= d`.
        c_max_n_s_m: f64,
        /// Penetration `d` in m over which the damping ramps from 0 to `c_max`.
        d_m: f64,
    },
    /// Restitution-based hysteresis damping `F = max(0, K delta^n (1 + chi delta_dot / u0))`
    /// for `delta > 0`, else 0, with `chi` from [`RestitutionModel::chi`].
    Restitution {
        /// Which `chi(e)`.
        model: RestitutionModel,
        /// `K` in N/m^n.
        stiffness: f64,
        /// `n` (dimensionless).
        exponent: f64,
        /// Target coefficient of restitution `e` the `chi` was made for.
        restitution: f64,
        /// `chi` (dimensionless).
        chi: f64,
        /// Initial approach speed `u0` in m/s (the impact speed).
        impact_speed_m_s: f64,
    },
    /// DEM (Tsuji / Hertz-Mindlin) damping:
    /// `F = max(0, k delta^1.5 - 2 sqrt(5/6) beta sqrt(S_n m) delta_dot)` for `delta > 0`,
    /// else 0, with `S_n = 2 E* sqrt(R delta) = (3/2) k sqrt(delta)` (N/m) and
    /// `beta = ln e / sqrt(ln^2 e + pi^2) <= 0`, so the damping term opposes the motion.
    /// Source: Tsuji et al. (1992); EDEM / LIGGGHTS / Chrono SMC Hertz-Mindlin.
    /// `beta(e)` is the linear spring-dashpot's; on the Hertz spring it rebounds faster than the
    /// target at low `e` (simulated 0.397, 0.550, 0.808, 0.9505 for 0.3, 0.5, 0.8, 0.95).
    Tsuji {
        /// `k = 4/3 E* sqrt(R)` in N/m^1.5.
        stiffness: f64,
        /// Sphere mass `m` in kg (the effective mass against a fixed plate).
        mass_kg: f64,
        /// Target coefficient of restitution `e`.
        restitution: f64,
        /// `beta = ln e / sqrt(ln^2 e + pi^2)` (dimensionless).
        beta: f64,
    },
    /// Thornton's elastic-perfectly-plastic contact (see [`crate::physics::thornton`]): Hertz up
    /// to the limiting contact pressure, then linear plastic loading, elastic unloading from the
    /// enlarged radius `R_p`; times `(1 + chi delta_dot / u)` and clamped at zero. History
    /// dependent: the integrator replaces the law by [`ForceLaw::turned_at`] where the
    /// penetration turns, and ends the contact at the residual penetration
    /// ([`ForceLaw::contact_end_m`]).
    Thornton(ThorntonContact),
}

impl ForceLaw {
    /// Contact force `F` in N at penetration `delta_m` (m) and penetration rate
    /// `delta_dot_m_s` (m/s, positive while approaching). Zero for `delta_m <= 0`; for the
    /// damped laws `max(0, G)` with `G` the [`ForceLaw::unclamped_force`].
    pub fn force(&self, delta_m: f64, delta_dot_m_s: f64) -> f64 {
        if delta_m <= 0.0 {
            return 0.0;
        }
        match *self {
            Self::Hertz {
                stiffness,
                exponent,
            } => stiffness * pow_e(delta_m, exponent),
            _ => self.unclamped_force(delta_m, delta_dot_m_s).max(0.0),
        }
    }

    /// The force before the clamp at zero, `G` in N, for `delta_m > 0` (m) (0 for
    /// `delta_m <= 0`):
    /// `k delta^n` (Hertz), `k delta^e + STEP(delta, 0, 0, d, c_max) delta_dot` (Adams),
    /// `K delta^n (1 + chi delta_dot / u0)` (restitution laws),
    /// `k delta^1.5 - 2 sqrt(5/6) beta sqrt(S_n m) delta_dot` (Tsuji).
    /// Where `G` changes sign the clamped force has a kink; an integrator may stop there.
    pub fn unclamped_force(&self, delta_m: f64, delta_dot_m_s: f64) -> f64 {
        if delta_m <= 0.0 {
            return 0.0;
        }
        match *self {
            Self::Hertz {
                stiffness,
                exponent,
            } => stiffness * pow_e(delta_m, exponent),
            Self::AdamsImpact {
                stiffness,
                exponent,
                c_max_n_s_m,
                d_m,
            } => {
                let c = step_cubic(delta_m, 0.0, 0.0, d_m, c_max_n_s_m);
                stiffness * pow_e(delta_m, exponent) + c * delta_dot_m_s
            }
            Self::Restitution {
                stiffness,
                exponent,
                chi,
                impact_speed_m_s,
                ..
            } => {
                stiffness
                    * pow_e(delta_m, exponent)
                    * (1.0 + chi * delta_dot_m_s / impact_speed_m_s)
            }
            Self::Tsuji {
                stiffness,
                mass_kg,
                beta,
                ..
            } => {
                let sqrt_d = delta_m.sqrt();
                let s_n = 1.5 * stiffness * sqrt_d;
                let c = -2.0 * (5.0_f64 / 6.0).sqrt() * beta * (s_n * mass_kg).sqrt();
                stiffness * delta_m * sqrt_d + c * delta_dot_m_s
            }
            Self::Thornton(t) => t.unclamped_force_n(delta_m, delta_dot_m_s),
        }
    }

    /// The gradient `(dF/ddelta in N/m, dF/ddelta_dot in N s/m)` of [`ForceLaw::force`] at
    /// `delta_m` (m) and `delta_dot_m_s` (m/s), exact: `(0, 0)` for `delta_m <= 0` and where
    /// the clamp holds the force at zero (unclamped force `G < 0`); else the gradient of `G`:
    /// * Hertz: `(n k delta^(n-1), 0)`;
    /// * Adams: `(e k delta^(e-1) + STEP'(delta) delta_dot, STEP(delta))` with
    ///   `STEP'(delta) = 6 c_max s (1 - s) / d`, `s = delta / d`, below `d` (0 above);
    /// * restitution laws: `(n K delta^(n-1) (1 + chi delta_dot / u0), K delta^n chi / u0)`;
    /// * Tsuji: `(1.5 k delta^(1/2) + c0 delta_dot / (4 delta^(3/4)), c0 delta^(1/4))` with
    ///   `c0 = -2 sqrt(5/6) beta sqrt(1.5 k m)`;
    /// * Thornton: `(F_ep' (1 + chi delta_dot / u), F_ep chi / u)`.
    pub fn force_gradient(&self, delta_m: f64, delta_dot_m_s: f64) -> (f64, f64) {
        if delta_m <= 0.0
            || (self.is_clamped() && self.unclamped_force(delta_m, delta_dot_m_s) < 0.0)
        {
            return (0.0, 0.0);
        }
        self.unclamped_force_gradient(delta_m, delta_dot_m_s)
    }

    /// The gradient `(dG/ddelta in N/m, dG/ddelta_dot in N s/m)` of the
    /// [`ForceLaw::unclamped_force`] `G` at `delta_m` (m) and `delta_dot_m_s` (m/s), exact:
    /// `(0, 0)` for `delta_m <= 0`, else the formulas of [`ForceLaw::force_gradient`] whatever
    /// the sign of `G` (the smooth continuation of the force through the clamp's switch).
    pub fn unclamped_force_gradient(&self, delta_m: f64, delta_dot_m_s: f64) -> (f64, f64) {
        if delta_m <= 0.0 {
            return (0.0, 0.0);
        }
        let pow_slope = |k: f64, n: f64| {
            if n == 1.5 {
                1.5 * k * delta_m.sqrt()
            } else {
                n * k * delta_m.powf(n - 1.0)
            }
        };
        match *self {
            Self::Hertz {
                stiffness,
                exponent,
            } => (pow_slope(stiffness, exponent), 0.0),
            Self::AdamsImpact {
                stiffness,
                exponent,
                c_max_n_s_m,
                d_m,
            } => {
                let c = step_cubic(delta_m, 0.0, 0.0, d_m, c_max_n_s_m);
                let dc = if delta_m < d_m {
                    let s = delta_m / d_m;
                    6.0 * c_max_n_s_m * s * (1.0 - s) / d_m
                } else {
                    0.0
                };
                (pow_slope(stiffness, exponent) + dc * delta_dot_m_s, c)
            }
            Self::Restitution {
                stiffness,
                exponent,
                chi,
                impact_speed_m_s,
                ..
            } => {
                let factor = 1.0 + chi * delta_dot_m_s / impact_speed_m_s;
                (
                    pow_slope(stiffness, exponent) * factor,
                    stiffness * pow_e(delta_m, exponent) * chi / impact_speed_m_s,
                )
            }
            Self::Tsuji {
                stiffness,
                mass_kg,
                beta,
                ..
            } => {
                let c0 = -2.0 * (5.0_f64 / 6.0).sqrt() * beta * (1.5 * stiffness * mass_kg).sqrt();
                let q = delta_m.sqrt().sqrt();
                (
                    1.5 * stiffness * delta_m.sqrt() + 0.25 * c0 * delta_dot_m_s / (q * q * q),
                    c0 * q,
                )
            }
            Self::Thornton(t) => (
                t.elastic_plastic_slope_n_m(delta_m) * t.damping_factor(delta_dot_m_s),
                t.elastic_plastic_force_n(delta_m) * t.chi / t.impact_speed_m_s,
            ),
        }
    }

    /// The clamp's switching function `S(delta, delta_dot)`: the
    /// [`ForceLaw::unclamped_force`] `G` divided by a factor that is positive for `delta > 0`,
    /// chosen so that `S` stays finite as `delta -> 0+` (its limit is returned for
    /// `delta_m <= 0`). `S` and `G` change sign together; `S` is what the integrator's event
    /// location root-finds:
    /// * Hertz: `S = k` (N/m^n; never switches);
    /// * Adams: `S = G / delta^e = k + STEP(delta, 0, 0, d, c_max) delta_dot / delta^e`
    ///   (N/m^e), the STEP term `c_max delta^(2 - e) (3 - 2 delta/d) / d^2` for `delta < d`;
    /// * restitution laws: `S = G / (K delta^n) = 1 + chi delta_dot / u0` (dimensionless);
    /// * Tsuji: `S = G / delta^(1/4) = k delta^1.25 + c0 delta_dot` (N/m^1.25) with
    ///   `c0 = -2 sqrt(5/6) beta sqrt(1.5 k m)` (N s/m^1.25);
    /// * Thornton: `S = 1 + chi delta_dot / u` (dimensionless; the elastic-plastic force's own
    ///   zero, at the residual penetration, is the contact end).
    pub fn clamp_switch(&self, delta_m: f64, delta_dot_m_s: f64) -> f64 {
        self.clamp_switch_bounds((delta_m, delta_m), (delta_dot_m_s, delta_dot_m_s))
            .0
    }

    /// Bounds `(lo, hi)` of [`ForceLaw::clamp_switch`] over the box `delta_m` in
    /// `[delta.0, delta.1]` (m, negative ends taken as 0) and `delta_dot_m_s` in
    /// `[delta_dot.0, delta_dot.1]` (m/s), by interval arithmetic: every value of `S` on the
    /// box lies in `[lo, hi]` (up to rounding), so `lo > 0` or `hi < 0` proves that the force
    /// does not switch there. Units as [`ForceLaw::clamp_switch`].
    pub fn clamp_switch_bounds(&self, delta: (f64, f64), delta_dot: (f64, f64)) -> (f64, f64) {
        let (d_lo, d_hi) = (delta.0.max(0.0), delta.1.max(delta.0).max(0.0));
        match *self {
            Self::Hertz { stiffness, .. } => (stiffness, stiffness),
            Self::AdamsImpact {
                stiffness,
                exponent,
                c_max_n_s_m,
                d_m,
            } => {
                let w = adams_weight_bounds(d_lo, d_hi, exponent, c_max_n_s_m, d_m);
                let p = mul_bounds(w, delta_dot);
                (stiffness + p.0, stiffness + p.1)
            }
            Self::Restitution {
                chi,
                impact_speed_m_s,
                ..
            } => (
                1.0 + chi * delta_dot.0 / impact_speed_m_s,
                1.0 + chi * delta_dot.1 / impact_speed_m_s,
            ),
            Self::Tsuji {
                stiffness,
                mass_kg,
                beta,
                ..
            } => {
                let c0 = -2.0 * (5.0_f64 / 6.0).sqrt() * beta * (1.5 * stiffness * mass_kg).sqrt();
                (
                    stiffness * d_lo.powf(1.25) + c0 * delta_dot.0,
                    stiffness * d_hi.powf(1.25) + c0 * delta_dot.1,
                )
            }
            Self::Thornton(t) => (t.damping_factor(delta_dot.0), t.damping_factor(delta_dot.1)),
        }
    }

    /// Whether the law is clamped at zero, i.e. can switch its force off while `delta > 0`
    /// (every law but undamped Hertz).
    pub fn is_clamped(&self) -> bool {
        !matches!(self, Self::Hertz { .. })
    }

    /// The penetration (m) at which the law has a kink that an integrator should stop at and
    /// restart from: `Some(d)` for [`ForceLaw::AdamsImpact`], `None` otherwise. (Every law is
    /// also non-smooth at `delta = 0`, and the damped ones where the clamp at zero engages,
    /// see [`ForceLaw::unclamped_force`].)
    /// For [`ForceLaw::Thornton`] while loading: `Some(delta_y)`, where the curvature of the
    /// loading curve jumps.
    pub fn kink_m(&self) -> Option<f64> {
        match *self {
            Self::AdamsImpact { d_m, .. } if d_m > 0.0 => Some(d_m),
            Self::Thornton(t) if t.unloading.is_none() => Some(t.yield_penetration_m()),
            _ => None,
        }
    }

    /// Whether the force depends on the penetration's history and has not turned yet: the
    /// integrator then stops where `delta_dot` falls to 0 and continues with
    /// [`ForceLaw::turned_at`] (only [`ForceLaw::Thornton`] while loading).
    pub fn awaits_turn(&self) -> bool {
        matches!(self, Self::Thornton(t) if t.unloading.is_none())
    }

    /// The law after the penetration turned at `delta_max_m` (m): Thornton's unloading branch;
    /// every other law is returned unchanged.
    pub fn turned_at(&self, delta_max_m: f64) -> Self {
        match *self {
            Self::Thornton(t) => Self::Thornton(t.unloaded_from(delta_max_m)),
            other => other,
        }
    }

    /// The penetration (m) at which the contact ends: the residual penetration `delta_p` of a
    /// turned Thornton law (the dent), 0 otherwise.
    pub fn contact_end_m(&self) -> f64 {
        match *self {
            Self::Thornton(t) => t.unloading.map_or(0.0, |u| u.residual_m),
            _ => 0.0,
        }
    }

    /// The elastic stiffness `k` (N/m^n) of the law.
    pub fn stiffness(&self) -> f64 {
        match *self {
            Self::Hertz { stiffness, .. }
            | Self::AdamsImpact { stiffness, .. }
            | Self::Restitution { stiffness, .. }
            | Self::Tsuji { stiffness, .. } => stiffness,
            Self::Thornton(t) => t.stiffness,
        }
    }

    /// The elastic exponent `n` (dimensionless; 1.5 for Tsuji).
    pub fn exponent(&self) -> f64 {
        match *self {
            Self::Hertz { exponent, .. }
            | Self::AdamsImpact { exponent, .. }
            | Self::Restitution { exponent, .. } => exponent,
            Self::Tsuji { .. } | Self::Thornton(_) => 1.5,
        }
    }

    /// Checks that the parameters are finite and in range.
    pub fn validate(&self) -> Result<(), SimError> {
        positive("law.stiffness", self.stiffness())?;
        positive("law.exponent", self.exponent())?;
        match *self {
            Self::Hertz { .. } => Ok(()),
            Self::Thornton(t) => t.validate(),
            Self::AdamsImpact {
                c_max_n_s_m, d_m, ..
            } => {
                non_negative("law.c_max_n_s_m", c_max_n_s_m)?;
                positive("law.d_m", d_m)
            }
            Self::Restitution {
                chi,
                impact_speed_m_s,
                ..
            } => {
                non_negative("law.chi", chi)?;
                positive("law.impact_speed_m_s", impact_speed_m_s)
            }
            Self::Tsuji { mass_kg, beta, .. } => {
                positive("law.mass_kg", mass_kg)?;
                if (-1.0..=0.0).contains(&beta) {
                    Ok(())
                } else {
                    Err(SimError::InvalidParameter {
                        name: "law.beta".to_string(),
                        value: beta,
                        requirement: "in [-1, 0]",
                    })
                }
            }
        }
    }

    /// A restitution-based law ([`ForceLaw::Restitution`]) with `chi = model.chi(e)`.
    ///
    /// `stiffness` in N/m^n, `impact_speed_m_s` the approach speed `u0` (m/s); `restitution`
    /// must be in (0, 1].
    pub fn restitution_law(
        model: RestitutionModel,
        stiffness: f64,
        exponent: f64,
        restitution: f64,
        impact_speed_m_s: f64,
    ) -> Result<Self, SimError> {
        check_restitution(restitution)?;
        let law = Self::Restitution {
            model,
            stiffness,
            exponent,
            restitution,
            chi: model.chi(restitution),
            impact_speed_m_s,
        };
        law.validate()?;
        Ok(law)
    }

    /// A Tsuji law ([`ForceLaw::Tsuji`]) for stiffness `k` (N/m^1.5), mass `m` (kg) and target
    /// restitution `e` in (0, 1].
    pub fn tsuji(stiffness: f64, mass_kg: f64, restitution: f64) -> Result<Self, SimError> {
        check_restitution(restitution)?;
        let law = Self::Tsuji {
            stiffness,
            mass_kg,
            restitution,
            beta: tsuji_beta(restitution),
        };
        law.validate()?;
        Ok(law)
    }
}

/// Bounds of the Adams STEP weight `w(delta) = STEP(delta, 0, 0, d, c) / delta^e`
/// (N s/m^(1+e)) over `delta` in `[lo, hi]` (m, `0 <= lo <= hi`): `c delta^(2 - e)
/// (3 - 2 delta/d) / d^2` below `d` (a product of two non-negative monotone factors),
/// `c delta^-e` above it (decreasing); the hull where the interval straddles `d`.
fn adams_weight_bounds(lo: f64, hi: f64, e: f64, c: f64, d: f64) -> (f64, f64) {
    let mut out = (f64::INFINITY, f64::NEG_INFINITY);
    let mut join = |b: (f64, f64)| out = (out.0.min(b.0), out.1.max(b.1));
    if lo < d {
        let top = hi.min(d);
        let pow = |x: f64| if e == 1.5 { x.sqrt() } else { x.powf(2.0 - e) };
        let (pa, pb) = (pow(lo), pow(top));
        let scale = c / (d * d);
        join((
            scale * pa.min(pb) * (3.0 - 2.0 * top / d),
            scale * pa.max(pb) * (3.0 - 2.0 * lo / d),
        ));
    }
    if hi >= d {
        let bottom = lo.max(d);
        join((c / pow_e(hi, e), c / pow_e(bottom, e)));
    }
    out
}

/// Interval product `[a.0, a.1] * [b.0, b.1]` (the whole line if a product is undefined).
fn mul_bounds(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    let p = [a.0 * b.0, a.0 * b.1, a.1 * b.0, a.1 * b.1];
    if p.iter().any(|x| x.is_nan()) {
        return (f64::NEG_INFINITY, f64::INFINITY);
    }
    let lo = p.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (lo, hi)
}

/// `true` when `e` is a target restitution the restitution laws take: finite, in `(0, 1]`,
/// or in `(0, 1)` when `open_at_one` (Adams' restitution form).
///
/// ```
/// use host_sim::laws::restitution_in_range;
/// assert!(restitution_in_range(1.0, false));
/// assert!(!restitution_in_range(1.0, true));
/// assert!(!restitution_in_range(0.0, false));
/// assert!(!restitution_in_range(f64::NAN, false));
/// ```
pub fn restitution_in_range(e: f64, open_at_one: bool) -> bool {
    e.is_finite() && e > 0.0 && if open_at_one { e < 1.0 } else { e <= 1.0 }
}

fn check_restitution(e: f64) -> Result<(), SimError> {
    if restitution_in_range(e, false) {
        Ok(())
    } else {
        Err(SimError::InvalidParameter {
            name: "restitution".to_string(),
            value: e,
            requirement: "in (0, 1]",
        })
    }
}
