//! How a scene file, the CLI or a study states a contact law (`LawSpec`, also the scene file's
//! `[contact]` table), and the force law it builds; the Adams law tuned to a restitution is
//! found by running the integrator ([`adams_for_restitution`]), so this sits above both
//! `laws` and `integrate`.

use serde::{Deserialize, Serialize};

use crate::physics::events::illinois_until;
use crate::physics::hertz64::{HERTZ_TC_FACTOR, HertzImpact64, positive};
use crate::physics::integrate::{ContactProblem, Limits, Method, Tolerance, integrate_contact};
use crate::physics::laws::{ForceLaw, RestitutionModel};
use crate::physics::sim_error::SimError;
use crate::physics::thornton::ThorntonContact;

/// An Adams IMPACT law whose `c_max` (N s/m) makes a gravity-free impact of a sphere of mass
/// `mass_kg` (kg) at `speed_m_s` (m/s) rebound with coefficient of restitution
/// `restitution` in (0, 1).
///
/// Adams has no closed form for this, so `c_max` is found numerically: the impact is
/// simulated with Dormand-Prince 5(4) at rtol = atol = 1e-10 (scaled state, stopping at
/// the kink) and the simulated restitution `e(c_max)`, which falls monotonically from 1 at
/// `c_max = 0`, is solved for the target by bracketed regula falsi (Illinois,
/// `events::illinois_until`) on `ln c_max`, starting from the linear-oscillator estimate
/// `c = 2 zeta m pi / t_c`, `zeta = -ln e / sqrt(pi^2 + ln^2 e)`, until
/// `|e(c_max) - e| <= 1e-9` or the bracket on `ln c_max` is 1e-13 wide. The restitution of
/// the result depends on the speed: it is the target only at `speed_m_s`.
pub fn adams_for_restitution(
    stiffness: f64,
    exponent: f64,
    d_m: f64,
    mass_kg: f64,
    speed_m_s: f64,
    restitution: f64,
) -> Result<ForceLaw, SimError> {
    if !(restitution > 0.0 && restitution < 1.0) {
        return Err(SimError::InvalidParameter {
            name: "restitution".to_string(),
            value: restitution,
            requirement: "in (0, 1) for a damped Adams law",
        });
    }
    let make = |c: f64| ForceLaw::AdamsImpact {
        stiffness,
        exponent,
        c_max_n_s_m: c,
        d_m,
    };
    make(1.0).validate()?;
    positive("mass_kg", mass_kg)?;
    positive("speed_m_s", speed_m_s)?;
    let tol = Tolerance::new(1e-10);
    let limits = Limits::default();
    // g(ln c) = e(c) - e_target, decreasing in ln c.
    let eval = |ln_c: f64| -> Result<f64, SimError> {
        let problem = ContactProblem {
            law: make(ln_c.exp()),
            mass_kg,
            speed_m_s,
            gravity_m_s2: 0.0,
        };
        let sol = integrate_contact(&problem, Method::Dopri5, tol, &limits)?;
        Ok(sol.restitution() - restitution)
    };
    // Linear-oscillator first guess with the Hertz contact time.
    let hz = HertzImpact64::from_stiffness_mass(stiffness, mass_kg, speed_m_s)?;
    let le = restitution.ln();
    let zeta = -le / (core::f64::consts::PI.powi(2) + le * le).sqrt();
    let t_c = HERTZ_TC_FACTOR * hz.delta_max_m / speed_m_s;
    let c0 = 2.0 * zeta * mass_kg * core::f64::consts::PI / t_c;
    let [(a, ga), (b, gb)] = bracket_decreasing(&eval, c0.ln(), 4.0_f64.ln(), restitution)?;
    // Illinois on [a, b] with ga > 0 >= gb.
    let ln_c = illinois_until(eval, a, ga, b, gb, 1e-9, 1e-13)?;
    Ok(make(ln_c.exp()))
}

/// A bracket `[(a, g(a)), (b, g(b))]` with `g(a) > 0 >= g(b)` of the decreasing
/// `g = e - restitution`, stepping `step` from `x0` up (while `g > 0`) or down (while
/// `g <= 0`), at most 40 steps; else [`SimError::RestitutionNotBracketed`] with the
/// restitution reached.
fn bracket_decreasing(
    g: &dyn Fn(f64) -> Result<f64, SimError>,
    x0: f64,
    step: f64,
    restitution: f64,
) -> Result<[(f64, f64); 2], SimError> {
    let (mut a, mut ga) = (x0, g(x0)?);
    let (mut b, mut gb) = (a, ga);
    let mut n = 0;
    // Not damped enough: raise c until e falls below the target; else lower it until it
    // rises above.
    let raise = ga > 0.0;
    while if raise { gb > 0.0 } else { ga <= 0.0 } {
        if raise {
            (a, ga) = (b, gb);
            b += step;
            gb = g(b)?;
        } else {
            (b, gb) = (a, ga);
            a -= step;
            ga = g(a)?;
        }
        n += 1;
        if n > 40 {
            return Err(SimError::RestitutionNotBracketed {
                target: restitution,
                reached: if raise { gb } else { ga } + restitution,
            });
        }
    }
    Ok([(a, ga), (b, gb)])
}

/// The user's choice of contact law, independent of the scene: the scene file's `[contact]`
/// table (tag `law`, `snake_case` names, e.g. `law = "flores"`, `restitution = 0.5`), the
/// command line's and the integrator's. [`LawSpec::build`] makes the concrete [`ForceLaw`]
/// with the scene's Hertz stiffness `k = 4/3 E* sqrt(R)`, exponent 1.5, mass and impact speed;
/// the contact is gravity-free (as the kernel's envelopes are).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "snake_case", deny_unknown_fields)]
pub enum LawSpec {
    /// Undamped Hertz `F = k delta^(3/2)` (restitution 1); the kernel's model.
    #[default]
    Hertz,
    /// Hunt-Crossley `F = k delta^1.5 (1 + chi delta_dot / u)`, `chi = 3 (1 - e) / 2`.
    HuntCrossley {
        /// Target coefficient of restitution `e` in (0, 1].
        restitution: f64,
    },
    /// Lankarani-Nikravesh, `chi = 3 (1 - e^2) / 4`.
    LankaraniNikravesh {
        /// Target coefficient of restitution `e` in (0, 1].
        restitution: f64,
    },
    /// Flores et al., `chi = 8 (1 - e) / (5 e)`.
    Flores {
        /// Target coefficient of restitution `e` in (0, 1].
        restitution: f64,
    },
    /// Gonthier et al., `chi = (1 - e^2) / e`.
    Gonthier {
        /// Target coefficient of restitution `e` in (0, 1].
        restitution: f64,
    },
    /// DEM (Tsuji / Hertz-Mindlin) damping with `beta(e)`.
    Tsuji {
        /// Target coefficient of restitution `e` in (0, 1].
        restitution: f64,
    },
    /// MSC Adams IMPACT `F = max(0, k delta^1.5 + STEP(delta, 0, 0, d, c_max) delta_dot)` with
    /// an explicit full damping.
    Adams {
        /// Full damping `c_max` in N s/m (`>= 0`).
        c_max_n_s_m: f64,
        /// Penetration `d` in m over which the damping ramps up (`> 0`; Adams: about 1e-5).
        d_m: f64,
    },
    /// Adams IMPACT with `c_max` solved per impact so that it rebounds with `restitution`
    /// (see [`adams_for_restitution`]; one root search per impact: slow).
    AdamsRestitution {
        /// Target coefficient of restitution in (0, 1).
        restitution: f64,
        /// Penetration `d` in m (`> 0`).
        d_m: f64,
    },
    /// Thornton's elastic-perfectly-plastic contact with limiting contact pressure
    /// `yield_pressure_pa` (Pa), optionally times the hysteresis damping
    /// `(1 + chi delta_dot / u)` of a restitution model (see [`crate::physics::thornton`]). Needs
    /// the scene's `E*` and `R` (a [`HertzImpact64::new`]). Not a `[contact]` law of a scene
    /// file: a class that states `yield_pressure_pa` gets it ([`LawSpec::restitution_damping`]
    /// of the scene's law).
    #[serde(skip)]
    Thornton {
        /// Limiting contact pressure `p_y` in Pa.
        yield_pressure_pa: f64,
        /// The viscous part: `chi = model.chi(restitution)`, or none.
        damping: Option<(RestitutionModel, f64)>,
    },
}

impl LawSpec {
    /// The restitution-parametrised law named `name` as a scene file names it
    /// (`hunt_crossley`, `lankarani_nikravesh`, `flores`, `gonthier`, `tsuji`) at restitution
    /// `restitution`; `None` for any other name.
    ///
    /// ```
    /// use host_sim::law_spec::LawSpec;
    /// let law = LawSpec::restitution_law("gonthier", 0.3);
    /// assert_eq!(law, Some(LawSpec::Gonthier { restitution: 0.3 }));
    /// assert_eq!(LawSpec::restitution_law("hertz", 0.3), None);
    /// ```
    pub fn restitution_law(name: &str, restitution: f64) -> Option<Self> {
        Some(match name {
            "hunt_crossley" => Self::HuntCrossley { restitution },
            "lankarani_nikravesh" => Self::LankaraniNikravesh { restitution },
            "flores" => Self::Flores { restitution },
            "gonthier" => Self::Gonthier { restitution },
            "tsuji" => Self::Tsuji { restitution },
            _ => return None,
        })
    }

    /// `true` for a law whose force pulse, scaled to unit peak and contact time, is one shape
    /// for every size, speed and material: undamped Hertz and the restitution-parametrised
    /// laws at a given restitution (their damping is `chi(e) delta_dot / u`, dimensionless in
    /// the scaled time; Tsuji's `beta(e)` likewise). Not Adams' fixed `c_max` (its damping
    /// ratio changes with size and speed), nor a per-impact `c_max`, nor a yielding contact.
    ///
    /// ```
    /// use host_sim::law_spec::LawSpec;
    /// assert!(LawSpec::Hertz.self_similar());
    /// assert!(LawSpec::Tsuji { restitution: 0.4 }.self_similar());
    /// assert!(!LawSpec::Adams { c_max_n_s_m: 687.0, d_m: 1e-5 }.self_similar());
    /// ```
    pub fn self_similar(&self) -> bool {
        matches!(
            self,
            Self::Hertz
                | Self::HuntCrossley { .. }
                | Self::LankaraniNikravesh { .. }
                | Self::Flores { .. }
                | Self::Gonthier { .. }
                | Self::Tsuji { .. }
        )
    }

    /// The restitution model and target `e` of a law of the restitution form `(1 + chi
    /// delta_dot / u)` (Hunt-Crossley, Lankarani-Nikravesh, Flores, Gonthier), else `None`.
    pub fn restitution_damping(&self) -> Option<(RestitutionModel, f64)> {
        match *self {
            Self::HuntCrossley { restitution } => {
                Some((RestitutionModel::HuntCrossley, restitution))
            }
            Self::LankaraniNikravesh { restitution } => {
                Some((RestitutionModel::LankaraniNikravesh, restitution))
            }
            Self::Flores { restitution } => Some((RestitutionModel::Flores, restitution)),
            Self::Gonthier { restitution } => Some((RestitutionModel::Gonthier, restitution)),
            _ => None,
        }
    }

    /// The concrete law for the scene `hertz` (stiffness, mass and speed are taken from it).
    pub fn build(&self, hertz: &HertzImpact64) -> Result<ForceLaw, SimError> {
        let k = hertz.stiffness;
        let m = hertz.mass_kg;
        let u = hertz.speed_m_s;
        let restitution = |model, e| ForceLaw::restitution_law(model, k, 1.5, e, u);
        let law = match *self {
            Self::Hertz => ForceLaw::Hertz {
                stiffness: k,
                exponent: 1.5,
            },
            Self::Adams { c_max_n_s_m, d_m } => ForceLaw::AdamsImpact {
                stiffness: k,
                exponent: 1.5,
                c_max_n_s_m,
                d_m,
            },
            Self::AdamsRestitution { restitution, d_m } => {
                adams_for_restitution(k, 1.5, d_m, m, u, restitution)?
            }
            Self::HuntCrossley { restitution: e } => {
                restitution(RestitutionModel::HuntCrossley, e)?
            }
            Self::LankaraniNikravesh { restitution: e } => {
                restitution(RestitutionModel::LankaraniNikravesh, e)?
            }
            Self::Flores { restitution: e } => restitution(RestitutionModel::Flores, e)?,
            Self::Gonthier { restitution: e } => restitution(RestitutionModel::Gonthier, e)?,
            Self::Tsuji { restitution: e } => ForceLaw::tsuji(k, m, e)?,
            Self::Thornton {
                yield_pressure_pa,
                damping,
            } => {
                positive("radius_m", hertz.radius_m)?;
                let chi = match damping {
                    Some((model, e)) => {
                        ForceLaw::restitution_law(model, k, 1.5, e, u)?;
                        model.chi(e)
                    }
                    None => 0.0,
                };
                ForceLaw::Thornton(ThorntonContact {
                    stiffness: k,
                    radius_m: hertz.radius_m,
                    yield_pressure_pa,
                    chi,
                    impact_speed_m_s: u,
                    unloading: None,
                })
            }
        };
        law.validate()?;
        Ok(law)
    }
}
