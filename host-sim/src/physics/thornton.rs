//! Thornton's elastic-perfectly-plastic contact of a sphere on a flat plate: the
//! force-displacement law ([`ThorntonContact`]) and the closed forms of one impact
//! ([`ThorntonImpact64`]), in `f64`.
//!
//! Sources: C. Thornton, "Coefficient of restitution for collinear collisions of
//! elastic-perfectly plastic spheres", J. Appl. Mech. 64 (1997) 383-386; K. L. Johnson,
//! *Contact Mechanics* (1985), ch. 6 and 11. With `E*` the effective modulus (Pa), `R` the
//! sphere radius (m), `p_y` the limiting contact pressure (Pa) and `delta` the penetration (m):
//!
//! * elastic (Hertz) loading `F = k delta^(3/2)`, `k = 4/3 E* sqrt(R)`, until the peak Hertz
//!   pressure `p0 = (2 E*/pi) sqrt(delta/R)` reaches `p_y`: at
//!   `delta_y = R (pi p_y / (2 E*))^2`, `F_y = k delta_y^(3/2) = pi^3 R^2 p_y^3 / (6 E*^2)`;
//! * plastic loading (the Hertz pressure truncated at `p_y`): `F = F_y + pi p_y R (delta -
//!   delta_y)`, with contact radius `a^2 = R delta = (2 F + F_y) / (2 pi p_y)`; the slope
//!   `pi p_y R` equals the Hertz slope at `delta_y`, so `F` is C1 there;
//! * elastic unloading from `delta*` (force `F*`, contact radius `a*`) as a Hertz contact of the
//!   plastically enlarged radius `R_p = 4 E* a*^3 / (3 F*)`:
//!   `F = 4/3 E* sqrt(R_p) (delta - delta_p)^(3/2)`, `delta* - delta_p = a*^2 / R_p`; the
//!   force is zero below the residual penetration `delta_p` (the dent), where the contact ends.
//!   Reloading follows the same elastic curve up to `delta*`.
//!
//! An optional hysteresis damping multiplies the elastic-plastic force by
//! `(1 + chi delta_dot / u)` (the form of the restitution laws, with `chi` from one of their
//! models), so that yield and viscous loss combine; the force is then clamped at zero.

use serde::{Deserialize, Serialize};

use crate::physics::hertz64::{HERTZ_TAU, HERTZ_TC_FACTOR, HertzImpact64, non_negative, positive};
use crate::physics::sim_error::SimError;

/// The elastic unloading branch fixed at the turnaround of the penetration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Unloading {
    /// Largest penetration `delta*` in m.
    pub delta_max_m: f64,
    /// Residual penetration `delta_p = delta* - a*^2 / R_p` in m.
    pub residual_m: f64,
    /// Unloading stiffness `4/3 E* sqrt(R_p)` in N/m^1.5.
    pub stiffness: f64,
}

/// Thornton's law for one impact (see the module docs), with an optional hysteresis damping.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ThorntonContact {
    /// Elastic stiffness `k = 4/3 E* sqrt(R)` in N/m^1.5.
    pub stiffness: f64,
    /// Sphere radius `R` in m.
    pub radius_m: f64,
    /// Limiting contact pressure `p_y` in Pa.
    pub yield_pressure_pa: f64,
    /// Hysteresis factor `chi` of the damping `(1 + chi delta_dot / u)` (0: none).
    pub chi: f64,
    /// Impact speed `u` in m/s (the damping's reference speed).
    pub impact_speed_m_s: f64,
    /// The unloading branch once the penetration has turned (`None` while loading).
    pub unloading: Option<Unloading>,
}

impl ThorntonContact {
    /// Effective modulus `E* = 3 k / (4 sqrt(R))` in Pa.
    pub fn effective_modulus_pa(&self) -> f64 {
        0.75 * self.stiffness / self.radius_m.sqrt()
    }

    /// Penetration at first yield `delta_y = R (pi p_y / (2 E*))^2` in m.
    pub fn yield_penetration_m(&self) -> f64 {
        let r =
            core::f64::consts::PI * self.yield_pressure_pa / (2.0 * self.effective_modulus_pa());
        self.radius_m * r * r
    }

    /// Force at first yield `F_y = k delta_y^(3/2)` in N.
    pub fn yield_force_n(&self) -> f64 {
        let d = self.yield_penetration_m();
        self.stiffness * d * d.sqrt()
    }

    /// Plastic loading slope `pi p_y R` in N/m.
    pub fn plastic_slope_n_m(&self) -> f64 {
        core::f64::consts::PI * self.yield_pressure_pa * self.radius_m
    }

    /// The loading curve in N at penetration `delta_m` (m): `k delta^(3/2)` up to `delta_y`,
    /// `F_y + pi p_y R (delta - delta_y)` beyond; 0 for `delta_m <= 0`.
    pub fn loading_force_n(&self, delta_m: f64) -> f64 {
        if delta_m <= 0.0 {
            return 0.0;
        }
        let dy = self.yield_penetration_m();
        if delta_m <= dy {
            self.stiffness * delta_m * delta_m.sqrt()
        } else {
            self.stiffness * dy * dy.sqrt() + self.plastic_slope_n_m() * (delta_m - dy)
        }
    }

    /// The elastic-plastic force in N at `delta_m` (m), without damping: the loading curve, or
    /// after the turnaround `4/3 E* sqrt(R_p) (delta - delta_p)^(3/2)` up to `delta*` (0 below
    /// `delta_p`) and the loading curve beyond `delta*`.
    pub fn elastic_plastic_force_n(&self, delta_m: f64) -> f64 {
        match self.unloading {
            Some(u) if delta_m <= u.delta_max_m => {
                let s = delta_m - u.residual_m;
                if s > 0.0 {
                    u.stiffness * s * s.sqrt()
                } else {
                    0.0
                }
            }
            _ => self.loading_force_n(delta_m),
        }
    }

    /// The slope `dF/ddelta` in N/m of [`ThorntonContact::elastic_plastic_force_n`] at
    /// `delta_m` (m): `1.5 k delta^(1/2)` on the Hertz part of the loading curve,
    /// `pi p_y R` on its plastic part, `1.5 k_u (delta - delta_p)^(1/2)` on the unloading branch
    /// (0 below `delta_p`); the slope from below at the curve's kinks.
    pub fn elastic_plastic_slope_n_m(&self, delta_m: f64) -> f64 {
        match self.unloading {
            Some(u) if delta_m <= u.delta_max_m => {
                let s = delta_m - u.residual_m;
                if s > 0.0 {
                    1.5 * u.stiffness * s.sqrt()
                } else {
                    0.0
                }
            }
            _ if delta_m <= 0.0 => 0.0,
            _ if delta_m <= self.yield_penetration_m() => 1.5 * self.stiffness * delta_m.sqrt(),
            _ => self.plastic_slope_n_m(),
        }
    }

    /// The damping factor's switching function `1 + chi delta_dot / u` (dimensionless).
    pub fn damping_factor(&self, delta_dot_m_s: f64) -> f64 {
        1.0 + self.chi * delta_dot_m_s / self.impact_speed_m_s
    }

    /// The force in N before the clamp at zero: elastic-plastic force times the damping factor.
    pub fn unclamped_force_n(&self, delta_m: f64, delta_dot_m_s: f64) -> f64 {
        self.elastic_plastic_force_n(delta_m) * self.damping_factor(delta_dot_m_s)
    }

    /// The law after the penetration turned at `delta_max_m` (m): unloading from
    /// `F* = F(delta*)`, `a*^2 = R delta*`, `R_p = 4 E* a*^3 / (3 F*)` (`R_p = R` if the contact
    /// never yielded), `delta_p = delta* - a*^2 / R_p`.
    pub fn unloaded_from(&self, delta_max_m: f64) -> Self {
        let e_star = self.effective_modulus_pa();
        let f_star = self.loading_force_n(delta_max_m);
        let a2 = self.radius_m * delta_max_m;
        let (r_p, residual_m) = if f_star > 0.0 && delta_max_m > self.yield_penetration_m() {
            let r_p = 4.0 * e_star * a2 * a2.sqrt() / (3.0 * f_star);
            (r_p, (delta_max_m - a2 / r_p).max(0.0))
        } else {
            (self.radius_m, 0.0)
        };
        Self {
            unloading: Some(Unloading {
                delta_max_m,
                residual_m,
                stiffness: 4.0 / 3.0 * e_star * r_p.sqrt(),
            }),
            ..*self
        }
    }

    /// Checks the parameters finite and in range.
    pub fn validate(&self) -> Result<(), SimError> {
        positive("law.stiffness", self.stiffness)?;
        positive("law.radius_m", self.radius_m)?;
        positive("law.yield_pressure_pa", self.yield_pressure_pa)?;
        positive("law.impact_speed_m_s", self.impact_speed_m_s)?;
        non_negative("law.chi", self.chi)
    }
}

/// Closed forms of the undamped, gravity-free impact under Thornton's law (all SI units).
///
/// Energy gives the yield speed, the peak force and the restitution; the contact time is the
/// sum of three phases (Hertz loading to `delta_y`, a harmonic arc under the linear plastic
/// law, half a Hertz contact of radius `R_p`). Below the yield speed it is the Hertz impact.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ThorntonImpact64 {
    /// Impact speed at which the contact just reaches yield,
    /// `V_y = sqrt(4 k delta_y^(5/2) / (5 m))` in m/s; for a solid sphere of density `rho`
    /// `V_y = (pi^4 / 40)^(1/2) (p_y^5 / (E*^4 rho))^(1/2) = 1.5605 (p_y^5 / (E*^4 rho))^(1/2)`.
    pub yield_speed_m_s: f64,
    /// `delta_y` in m.
    pub yield_penetration_m: f64,
    /// `F_y` in N.
    pub yield_force_n: f64,
    /// Largest penetration `delta*` in m.
    pub delta_max_m: f64,
    /// Peak force `F* = F_y sqrt(6/5 (u/V_y)^2 - 1/5)` in N above yield (Hertz below).
    pub peak_force_n: f64,
    /// Plastically enlarged radius `R_p` in m.
    pub plastic_radius_m: f64,
    /// Residual penetration `delta_p` in m.
    pub residual_m: f64,
    /// Coefficient of restitution `e = sqrt(W_unload / (m u^2 / 2))`,
    /// `W_unload = (2/5) F* (delta* - delta_p)`.
    pub restitution: f64,
    /// Time of the elastic loading phase in s: `(delta_H / u) (2/5) B(w_y; 2/5, 1/2)`,
    /// `w_y = (V_y / u)^2`, `delta_H` the Hertz `delta_max` at `u`.
    pub elastic_time_s: f64,
    /// Time of the plastic phase in s: `atan(v_y / (c w)) / w` with `w = sqrt(pi p_y R / m)`,
    /// `c = F_y / (pi p_y R)`, `v_y = sqrt(u^2 - V_y^2)`.
    pub plastic_time_s: f64,
    /// Time of the elastic unloading in s: `tau (delta* - delta_p) / (e u)`,
    /// `tau = (2/5) B(2/5, 1/2)`.
    pub unloading_time_s: f64,
    /// Contact duration (first contact to `delta = delta_p`) in s: the sum of the three phases.
    pub duration_s: f64,
    /// The duration the area gives a Hertz-shaped pulse of the same peak,
    /// `t_A = J / (C_AREA F*)` in s, with the impulse `J = m u (1 + e)` and
    /// `C_AREA = 1.6 / 2.9432752` ([`crate::physics::hertz64::C_AREA`], written out so that
    /// the calibration's ratios round as they did; the Hertz contact time `t_c` below yield).
    pub area_duration_s: f64,
}

impl ThorntonImpact64 {
    /// The closed forms for the Hertz impact `hertz` (which must carry `E*` and `R`, as
    /// [`HertzImpact64::new`] gives) with limiting contact pressure `yield_pressure_pa` (Pa).
    pub fn new(hertz: &HertzImpact64, yield_pressure_pa: f64) -> Result<Self, SimError> {
        positive("effective_modulus_pa", hertz.effective_modulus_pa)?;
        positive("radius_m", hertz.radius_m)?;
        positive("yield_pressure_pa", yield_pressure_pa)?;
        let law = ThorntonContact {
            stiffness: hertz.stiffness,
            radius_m: hertz.radius_m,
            yield_pressure_pa,
            chi: 0.0,
            impact_speed_m_s: hertz.speed_m_s,
            unloading: None,
        };
        let (k, m, u) = (hertz.stiffness, hertz.mass_kg, hertz.speed_m_s);
        let (dy, fy) = (law.yield_penetration_m(), law.yield_force_n());
        let vy = (0.8 * k * dy * dy * dy.sqrt() / m).sqrt();
        let slope = law.plastic_slope_n_m();
        let (delta_max_m, elastic_time_s, plastic_time_s) = if u > vy {
            let f_star = (fy * fy + slope * m * (u * u - vy * vy)).sqrt();
            let w_y = (vy / u) * (vy / u);
            let t1 = hertz.delta_max_m / u * 0.4 * incomplete_beta_2_5_1_2(w_y);
            let omega = (slope / m).sqrt();
            let t2 = ((u * u - vy * vy).sqrt() / (fy / slope * omega)).atan() / omega;
            (dy + (f_star - fy) / slope, t1, t2)
        } else {
            (hertz.delta_max_m, 0.5 * hertz.duration_s, 0.0)
        };
        let unl = law
            .unloaded_from(delta_max_m)
            .unloading
            .unwrap_or(Unloading {
                delta_max_m,
                residual_m: 0.0,
                stiffness: k,
            });
        let peak_force_n = law.loading_force_n(delta_max_m);
        let s = delta_max_m - unl.residual_m;
        let restitution = (0.4 * peak_force_n * s / (0.5 * m * u * u)).sqrt();
        let unloading_time_s = HERTZ_TAU * s / (restitution * u);
        let r_p = (0.75 * unl.stiffness / hertz.effective_modulus_pa).powi(2);
        Ok(Self {
            yield_speed_m_s: vy,
            yield_penetration_m: dy,
            yield_force_n: fy,
            delta_max_m,
            peak_force_n,
            plastic_radius_m: r_p,
            residual_m: unl.residual_m,
            restitution,
            elastic_time_s,
            plastic_time_s,
            unloading_time_s,
            duration_s: elastic_time_s + plastic_time_s + unloading_time_s,
            area_duration_s: m * u * (1.0 + restitution) * HERTZ_TC_FACTOR / (1.6 * peak_force_n),
        })
    }
}

/// `B(2/5, 1/2) = (5/2) tau` (dimensionless).
const BETA_2_5_1_2: f64 = 2.5 * HERTZ_TAU;

/// The incomplete beta function `B(w; 2/5, 1/2) = integral_0^w t^(-3/5) (1 - t)^(-1/2) dt`
/// for `w` in [0, 1]: the series `w^a sum_n (1 - b)_n w^n / (n! (a + n))` (Abramowitz &
/// Stegun 6.6.8 with 15.1.1) for `w <= 1/2`, else `B(a, b) - B(1 - w; b, a)` with the same
/// series, each to double precision (at most 60 terms, ratio `<= 1/2`).
pub fn incomplete_beta_2_5_1_2(w: f64) -> f64 {
    let w = w.clamp(0.0, 1.0);
    if w <= 0.5 {
        beta_series(w, 0.4, 0.5)
    } else {
        BETA_2_5_1_2 - beta_series(1.0 - w, 0.5, 0.4)
    }
}

/// `w^a sum_{n >= 0} (1 - b)_n w^n / (n! (a + n))` for `0 <= w <= 1/2`.
fn beta_series(w: f64, a: f64, b: f64) -> f64 {
    let (mut term, mut sum) = (1.0_f64, 1.0 / a);
    for n in 0..60 {
        let nf = f64::from(n);
        term *= (nf + 1.0 - b) * w / (nf + 1.0);
        let add = term / (a + nf + 1.0);
        sum += add;
        if add.abs() < 1e-18 * sum.abs() {
            break;
        }
    }
    w.powf(a) * sum
}
