//! Undamped Hertz impact of an elastic sphere on a flat plate, closed forms in `f64`.
//!
//! This is host-sim's own, independent implementation of the physics (it does not call the
//! kernel crate), used to scale the integrator and to check it.
//!
//! With `delta > 0` the penetration (m) and `u` the approach speed (m/s):
//!
//! * `1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2` (Pa), `R` the sphere radius (m, a flat plate has
//!   infinite radius, so `R = R1 R2/(R1 + R2)` reduces to the sphere's),
//! * `k = 4/3 E* sqrt(R)` (N/m^1.5), `m = 4/3 pi rho R^3` (kg), `F = k delta^(3/2)` (N),
//! * `delta_max = (5 m u^2 / (4 k))^(2/5)`, `F_max = k delta_max^(3/2)`,
//! * `t_c = 2 tau delta_max / u` with `tau = (2/5) B(2/5, 1/2) = 1.4716375921623524`,
//! * impulse `2 m u` (N s), coefficient of restitution 1.
//!
//! Sources: H. Hertz (1882); K. L. Johnson, *Contact Mechanics* (1985), section 11.4; the
//! project's paper, eqs. (3)-(9) and Tables 1-3.

use serde::{Deserialize, Serialize};

use crate::physics::sim_error::SimError;

/// `tau = integral_0^1 (1 - x^(5/2))^(-1/2) dx = (2/5) B(2/5, 1/2)` (dimensionless).
pub const HERTZ_TAU: f64 = 1.471_637_592_162_352_4;

/// `t_c u / delta_max = 2 tau = (4/5) B(2/5, 1/2) = 2.9432751843247` (dimensionless): the
/// contact duration of the undamped Hertz impact in units of `delta_max / u`.
pub const HERTZ_TC_FACTOR: f64 = 2.943_275_184_324_704_8;

/// Area of the Hertz pulse over `F_max t_c`: `1.6 / 2.9432752` (the impulse `2 m u`,
/// dimensionless).
pub const C_AREA: f64 = 1.6 / HERTZ_TC_FACTOR;

/// Standard gravity `g_n = 9.80665` m/s^2 (CGPM 1901), used when gravity is switched on.
pub const STANDARD_GRAVITY_M_S2: f64 = 9.806_65;

/// An isotropic, linear-elastic material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Material64 {
    /// Density `rho` in kg/m^3.
    pub density_kg_m3: f64,
    /// Young's modulus `E` in Pa.
    pub modulus_pa: f64,
    /// Poisson's ratio `nu` (dimensionless, in (-1, 0.5]).
    pub poisson: f64,
}

impl Material64 {
    /// Coal of the paper's Table 1: 1380 kg/m^3, 5.3 GPa, nu = 0.32.
    pub const COAL: Self = Self {
        density_kg_m3: 1380.0,
        modulus_pa: 5.3e9,
        poisson: 0.32,
    };
    /// Sandstone (gangue) of the paper's Table 2: 2487 kg/m^3, 13.5 GPa, nu = 0.123.
    pub const SANDSTONE: Self = Self {
        density_kg_m3: 2487.0,
        modulus_pa: 13.5e9,
        poisson: 0.123,
    };
    /// Carbon-steel plate of the paper's Table 1: 7850 kg/m^3, 206 GPa, nu = 0.28.
    pub const CARBON_STEEL: Self = Self {
        density_kg_m3: 7850.0,
        modulus_pa: 2.06e11,
        poisson: 0.28,
    };

    /// Checks that density and modulus are finite and positive and `-1 < nu <= 0.5`.
    ///
    /// `what` names the material in the error (for example `"sphere"`).
    pub fn validate(&self, what: &str) -> Result<(), SimError> {
        positive(&format!("{what}.density_kg_m3"), self.density_kg_m3)?;
        self.validate_elastic(what)
    }

    /// Checks the elastic constants alone: modulus finite and positive, `-1 < nu <= 0.5`
    /// (a plate's density does not enter the contact).
    pub fn validate_elastic(&self, what: &str) -> Result<(), SimError> {
        positive(&format!("{what}.modulus_pa"), self.modulus_pa)?;
        if !(self.poisson > -1.0 && self.poisson <= 0.5) {
            return Err(SimError::InvalidParameter {
                name: format!("{what}.poisson"),
                value: self.poisson,
                requirement: "Poisson's ratio in (-1, 0.5]",
            });
        }
        Ok(())
    }
}

/// `Ok` if `value` is finite and > 0, else an [`SimError::InvalidParameter`] naming `name`.
pub(crate) fn positive(name: &str, value: f64) -> Result<(), SimError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SimError::InvalidParameter {
            name: name.to_string(),
            value,
            requirement: "finite and > 0",
        })
    }
}

/// `Ok` if `value` is finite and >= 0, else an [`SimError::InvalidParameter`] naming `name`.
pub(crate) fn non_negative(name: &str, value: f64) -> Result<(), SimError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SimError::InvalidParameter {
            name: name.to_string(),
            value,
            requirement: "finite and >= 0",
        })
    }
}

/// Effective modulus `E* = 1 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2)` in Pa.
pub fn effective_modulus_pa(a: &Material64, b: &Material64) -> f64 {
    1.0 / ((1.0 - a.poisson * a.poisson) / a.modulus_pa
        + (1.0 - b.poisson * b.poisson) / b.modulus_pa)
}

/// Hertz stiffness `k = 4/3 E* sqrt(R)` in N/m^1.5 (`E*` in Pa, `R` in m).
pub fn hertz_stiffness(effective_modulus_pa: f64, radius_m: f64) -> f64 {
    4.0 / 3.0 * effective_modulus_pa * radius_m.sqrt()
}

/// Mass of a solid sphere `m = 4/3 pi rho R^3` in kg.
pub fn sphere_mass_kg(density_kg_m3: f64, radius_m: f64) -> f64 {
    4.0 / 3.0 * core::f64::consts::PI * density_kg_m3 * radius_m.powi(3)
}

/// Maximum penetration of the undamped impact `delta_max = (5 m u^2 / (4 k))^(2/5)` in m
/// (`m` in kg, `u` in m/s, `k` in N/m^1.5).
pub fn delta_max_m(mass_kg: f64, speed_m_s: f64, stiffness: f64) -> f64 {
    (5.0 * mass_kg * speed_m_s * speed_m_s / (4.0 * stiffness)).powf(0.4)
}

/// Closed-form undamped Hertz impact of a sphere on a flat plate (all SI units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HertzImpact64 {
    /// Effective modulus `E*` in Pa.
    pub effective_modulus_pa: f64,
    /// Sphere radius `R` in m.
    pub radius_m: f64,
    /// Sphere mass `m = 4/3 pi rho R^3` in kg.
    pub mass_kg: f64,
    /// Hertz stiffness `k = 4/3 E* sqrt(R)` in N/m^1.5.
    pub stiffness: f64,
    /// Approach speed `u` in m/s.
    pub speed_m_s: f64,
    /// `delta_max = (5 m u^2/(4 k))^(2/5)` in m.
    pub delta_max_m: f64,
    /// `F_max = k delta_max^(3/2)` in N.
    pub peak_force_n: f64,
    /// `t_c = 2.9432751843247 delta_max / u` in s.
    pub duration_s: f64,
    /// Impulse of the elastic pulse `2 m u` in N s.
    pub impulse_n_s: f64,
}

impl HertzImpact64 {
    /// Closed forms for a sphere of `sphere` material and radius `radius_m` (m) hitting a flat
    /// plate of `plate` material at `speed_m_s` (m/s).
    ///
    /// Errors if a material, the radius or the speed is not finite and positive (the plate's
    /// density is not used: the plate is a half-space, so it may be NaN).
    pub fn new(
        sphere: &Material64,
        plate: &Material64,
        radius_m: f64,
        speed_m_s: f64,
    ) -> Result<Self, SimError> {
        sphere.validate("sphere")?;
        plate.validate_elastic("plate")?;
        positive("radius_m", radius_m)?;
        let e_star = effective_modulus_pa(sphere, plate);
        let k = hertz_stiffness(e_star, radius_m);
        let m = sphere_mass_kg(sphere.density_kg_m3, radius_m);
        let mut out = Self::from_stiffness_mass(k, m, speed_m_s)?;
        out.effective_modulus_pa = e_star;
        out.radius_m = radius_m;
        Ok(out)
    }

    /// Closed forms from the stiffness `k` (N/m^1.5), mass `m` (kg) and speed `u` (m/s) alone;
    /// `effective_modulus_pa` and `radius_m` are then left as NaN (unknown).
    pub fn from_stiffness_mass(
        stiffness: f64,
        mass_kg: f64,
        speed_m_s: f64,
    ) -> Result<Self, SimError> {
        positive("stiffness", stiffness)?;
        positive("mass_kg", mass_kg)?;
        positive("speed_m_s", speed_m_s)?;
        let d = delta_max_m(mass_kg, speed_m_s, stiffness);
        Ok(Self {
            effective_modulus_pa: f64::NAN,
            radius_m: f64::NAN,
            mass_kg,
            stiffness,
            speed_m_s,
            delta_max_m: d,
            peak_force_n: stiffness * d * d.sqrt(),
            duration_s: HERTZ_TC_FACTOR * d / speed_m_s,
            impulse_n_s: 2.0 * mass_kg * speed_m_s,
        })
    }
}
