//! Closed forms of the undamped Hertz impact of an elastic sphere on a flat plate.
//!
//! With effective modulus `E*` (paper Eq. 6), sphere radius `R` (a flat plate: paper Eq. 5
//! gives `R`), density `rho` and impact speed `u`:
//!
//! - stiffness `k = 4/3 E* sqrt(R)` (Eq. 4), force `F = k delta^(3/2)` (Eq. 3);
//! - mass `m = 4/3 pi rho R^3`;
//! - maximum penetration `delta_max = (5 m u^2 / (4 k))^(2/5)` (Eq. 9);
//! - peak force `F_max = k delta_max^(3/2)`;
//! - contact duration `t_c = 2 tau delta_max / u`, `tau = (2/5) B(2/5, 1/2) = 1.4716376`;
//! - impulse `J = 2 m u` (elastic rebound).
//!
//! Everything is computed in the log-linear form of [`crate::envelope`]
//! (`F_max = c_F R^2 u^(6/5)`, `t_c = c_t R u^(-1/5)`) so that no intermediate leaves the
//! f32 range for any radius, speed and material the scene accepts.

use crate::error::{Error, positive, representable};
use crate::math::{Backend, DefaultBackend};

/// `2 tau = (4/5) B(2/5, 1/2) = 2.9432752` (physics notes, section 1).
pub const CONTACT_TIME_FACTOR: f32 = 2.943_275_2;

/// `pi`.
const PI: f32 = core::f32::consts::PI;

/// Contact stiffness `k = 4/3 E* sqrt(R)` in N/m^(3/2) (paper Eq. 4), default backend.
pub fn stiffness(effective_modulus_pa: f32, radius_m: f32) -> Result<f32, Error> {
    stiffness_in::<DefaultBackend>(effective_modulus_pa, radius_m)
}

/// [`stiffness`] with the math backend `M`.
pub fn stiffness_in<M: Backend>(effective_modulus_pa: f32, radius_m: f32) -> Result<f32, Error> {
    let e = positive(effective_modulus_pa, "effective_modulus_pa")?;
    let r = positive(radius_m, "radius_m")?;
    representable(4.0 / 3.0 * e * M::sqrt(r), "stiffness")
}

/// Sphere mass `m = 4/3 pi rho R^3` in kg.
pub fn sphere_mass_kg(density_kg_m3: f32, radius_m: f32) -> Result<f32, Error> {
    let rho = positive(density_kg_m3, "density_kg_m3")?;
    let r = positive(radius_m, "radius_m")?;
    representable(4.0 / 3.0 * PI * rho * r * r * r, "sphere mass")
}

/// The peak values of one undamped impact.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Impact {
    /// Maximum penetration `delta_max` in m.
    pub delta_max_m: f32,
    /// Peak contact force `F_max` in N.
    pub peak_force_n: f32,
    /// Contact duration `t_c` in s.
    pub duration_s: f32,
    /// Impulse of the pulse `2 m u` in N s.
    pub impulse_n_s: f32,
}

/// Material constant of the penetration: `delta_max = c_delta R u^(4/5)` with
/// `c_delta = (5 pi rho / (4 E*))^(2/5)` (from Eq. 9 with `m`, `k`
/// substituted), in s^(4/5) m^(-4/5).
pub fn penetration_coefficient(
    effective_modulus_pa: f32,
    density_kg_m3: f32,
) -> Result<f32, Error> {
    penetration_coefficient_in::<DefaultBackend>(effective_modulus_pa, density_kg_m3)
}

/// [`penetration_coefficient`] with the math backend `M`.
pub fn penetration_coefficient_in<M: Backend>(
    effective_modulus_pa: f32,
    density_kg_m3: f32,
) -> Result<f32, Error> {
    let e = positive(effective_modulus_pa, "effective_modulus_pa")?;
    let rho = positive(density_kg_m3, "density_kg_m3")?;
    // rho / E* can be as small as 1e-10: take the power of the ratio, never of a product.
    let ratio = representable(5.0 * PI / 4.0 * (rho / e), "density / modulus")?;
    let fifth = crate::math::fifth_root(ratio);
    representable(fifth * fifth, "penetration coefficient")
}

/// The undamped Hertz impact of a sphere of `radius_m` and `density_kg_m3` at `speed_m_s` on a
/// plate, with the pair's effective modulus (from [`crate::material::effective_modulus_pa`]).
///
/// `delta_max = c_delta R u^(4/5)`, `F_max = 4/3 E* sqrt(R) delta_max^(3/2)`,
/// `t_c = 2.9432752 delta_max / u`, `J = 2 m u`.
pub fn impact(
    effective_modulus_pa: f32,
    density_kg_m3: f32,
    radius_m: f32,
    speed_m_s: f32,
) -> Result<Impact, Error> {
    impact_in::<DefaultBackend>(effective_modulus_pa, density_kg_m3, radius_m, speed_m_s)
}

/// [`impact`] with the math backend `M`.
pub fn impact_in<M: Backend>(
    effective_modulus_pa: f32,
    density_kg_m3: f32,
    radius_m: f32,
    speed_m_s: f32,
) -> Result<Impact, Error> {
    let c_delta = penetration_coefficient_in::<M>(effective_modulus_pa, density_kg_m3)?;
    let r = positive(radius_m, "radius_m")?;
    let u = positive(speed_m_s, "speed_m_s")?;
    // `u^(4/5) = u / u^(1/5)`: one rounding beside the root's (its fourth power took four).
    let u_4_5 = u / crate::math::fifth_root(u);
    let delta = representable(c_delta * r * u_4_5, "delta_max")?;
    let k = stiffness_in::<M>(effective_modulus_pa, r)?;
    // delta^1.5 itself must be carried: a subnormal intermediate keeps only a few bits.
    let delta_3_2 = representable(M::pow_3_2(delta), "delta_max^1.5")?;
    let f = representable(k * delta_3_2, "peak force")?;
    let t = representable(CONTACT_TIME_FACTOR * delta / u, "contact duration")?;
    let m = sphere_mass_kg(density_kg_m3, r)?;
    let j = representable(2.0 * m * u, "impulse")?;
    Ok(Impact {
        delta_max_m: delta,
        peak_force_n: f,
        duration_s: t,
        impulse_n_s: j,
    })
}

/// Free-fall speed `u = sqrt(2 g h)` in m/s from a drop height in m (`g = 9.80665`).
pub fn drop_speed_m_s(height_m: f32) -> Result<f32, Error> {
    drop_speed_in::<DefaultBackend>(height_m)
}

/// [`drop_speed_m_s`] with the math backend `M`.
pub fn drop_speed_in<M: Backend>(height_m: f32) -> Result<f32, Error> {
    let h = positive(height_m, "height_m")?;
    representable(M::sqrt(2.0 * STANDARD_GRAVITY_M_S2 * h), "drop speed")
}

/// Standard gravity in m/s^2 (CGPM 1901).
pub const STANDARD_GRAVITY_M_S2: f32 = 9.806_65;
