//! One sphere-on-plate impact from a scene description: materials, size, speed, law and
//! numerics in, peak force, duration, restitution and the work done out.

use serde::{Deserialize, Serialize};

use crate::physics::hertz64::{HertzImpact64, Material64};
use crate::physics::integrate::{
    ContactProblem, Limits, Method, SimError, Tolerance, integrate_contact,
};
use crate::physics::law_spec::LawSpec;

/// What to simulate (SI units).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ImpactSpec {
    /// Material of the falling sphere (lump).
    pub sphere: Material64,
    /// Material of the plate (tail beam).
    pub plate: Material64,
    /// Sphere radius `R` in m.
    pub radius_m: f64,
    /// Approach speed `u` at first contact in m/s.
    pub speed_m_s: f64,
    /// Contact force law.
    pub law: LawSpec,
    /// Integration method.
    pub method: Method,
    /// Tolerance on the scaled state (used by [`Method::Dopri5`]).
    pub tolerance: Tolerance,
    /// Gravitational acceleration in m/s^2 pushing the sphere into the plate during the
    /// contact (`>= 0`; 0: none, [`crate::physics::hertz64::STANDARD_GRAVITY_M_S2`] = 9.80665 for
    /// standard gravity).
    /// Standard gravity changes `F_max` by up to about 2e-3 relative on the paper's grid.
    pub gravity_m_s2: f64,
    /// Sample interval in s of the recorded force-time series, or `None` for no series.
    pub record: Option<f64>,
    /// Guards against runaway integrations.
    pub limits: Limits,
}

impl ImpactSpec {
    /// A sphere of `sphere` material and radius `radius_m` (m) hitting a `plate` at
    /// `speed_m_s` (m/s): undamped Hertz, Dormand-Prince 5(4) at rtol = atol = 1e-9, no
    /// gravity, no recording, default limits.
    pub fn new(sphere: Material64, plate: Material64, radius_m: f64, speed_m_s: f64) -> Self {
        Self {
            sphere,
            plate,
            radius_m,
            speed_m_s,
            law: LawSpec::Hertz,
            method: Method::Dopri5,
            tolerance: Tolerance::default(),
            gravity_m_s2: 0.0,
            record: None,
            limits: Limits::default(),
        }
    }

    /// The paper's scene: coal (1380 kg/m^3, 5.3 GPa, nu 0.32), R = 0.03 m, on carbon steel
    /// at u = 1 m/s, with the defaults of [`ImpactSpec::new`].
    pub fn paper_scene() -> Self {
        Self::new(Material64::COAL, Material64::CARBON_STEEL, 0.03, 1.0)
    }

    /// The undamped Hertz closed forms of this scene.
    pub fn hertz(&self) -> Result<HertzImpact64, SimError> {
        HertzImpact64::new(&self.sphere, &self.plate, self.radius_m, self.speed_m_s)
    }
}

/// Outcome of one simulated impact (SI units).
#[derive(Debug, Clone, Serialize)]
pub struct ImpactReport {
    /// Maximum penetration in m.
    pub delta_max_m: f64,
    /// Peak contact force in N.
    pub peak_force_n: f64,
    /// Contact duration in s (first contact until `delta` is back to 0).
    pub duration_s: f64,
    /// Duration of the main force pulse in s (first contact to the first zero of the force
    /// after its peak); shorter than `duration_s` when a damped law's clamp at zero engages
    /// before separation.
    pub pulse_duration_s: f64,
    /// Rebound speed at separation in m/s.
    pub rebound_speed_m_s: f64,
    /// Coefficient of restitution `rebound_speed / speed` (dimensionless).
    pub restitution: f64,
    /// Contact impulse `integral F dt` in N s.
    pub impulse_n_s: f64,
    /// Accepted integration steps.
    pub steps: usize,
    /// Rejected integration steps.
    pub rejected_steps: usize,
    /// Force-law evaluations by the integrator (for an Adams law built from a restitution,
    /// the search for `c_max` is not included).
    pub force_evals: usize,
    /// Jacobian evaluations by an implicit method (Rodas4, Radau13; 0 for the explicit ones):
    /// each costs about one force evaluation (the exact 2 x 2 Jacobian of the force law).
    pub jacobian_evals: usize,
    /// Force-time series `(t_s, force_n)` every `record` seconds from first contact, if
    /// requested.
    pub force_series: Option<Vec<(f64, f64)>>,
}

/// Simulates one impact.
///
/// Errors on invalid input (non-positive radius, speed, modulus, ...), when the integration
/// exceeds its [`Limits`], or when an explicit method goes unstable.
pub fn simulate(spec: &ImpactSpec) -> Result<ImpactReport, SimError> {
    let hertz = spec.hertz()?;
    let law = spec.law.build(&hertz)?;
    let problem = ContactProblem {
        law,
        mass_kg: hertz.mass_kg,
        speed_m_s: hertz.speed_m_s,
        gravity_m_s2: spec.gravity_m_s2,
    };
    let sol = integrate_contact(&problem, spec.method, spec.tolerance, &spec.limits)?;
    let force_series = match spec.record {
        Some(dt) => Some(sol.sample_force(dt)?),
        None => None,
    };
    Ok(ImpactReport {
        delta_max_m: sol.delta_max_m,
        peak_force_n: sol.peak_force_n,
        duration_s: sol.duration_s,
        pulse_duration_s: sol.pulse_duration_s,
        rebound_speed_m_s: sol.rebound_speed_m_s,
        restitution: sol.restitution(),
        impulse_n_s: sol.impulse_n_s,
        steps: sol.work.steps,
        rejected_steps: sol.work.rejected_steps,
        force_evals: sol.work.force_evals,
        jacobian_evals: sol.work.jacobian_evals,
        force_series,
    })
}
