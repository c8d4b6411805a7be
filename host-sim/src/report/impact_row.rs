//! One row of `host-sim impact`: its input cells read and checked in the user's terms (the
//! column names, SI units) into an [`ImpactSpec`], the inputs the chosen law or method does
//! not use refused, and warnings where the impact lies far outside Hertz theory.
//!
//! Hertz validity, checked on the undamped closed forms (gravity-free):
//!
//! - **Penetration**: Hertz replaces the sphere's profile `R - sqrt(R^2 - r^2)` by the
//!   paraboloid `r^2 / (2 R)`; at the contact edge `r = a = sqrt(R delta)` they differ by
//!   `a^4 / (8 R^3)`, that is `delta / (8 R)` of the penetration. Above
//!   `delta_max / R = `[`MAX_PENETRATION_RATIO`]` = 0.08` the error passes 1 %.
//! - **Speed**: Hertz's impact theory is quasi-static: the sphere must be slow against the
//!   elastic waves that carry the load through it. Above [`MAX_WAVE_SPEED_SHARE`]` = 1 %` of
//!   the sphere's bar-wave speed `c0 = sqrt(E / rho)` (coal of the paper: 1960 m/s, so
//!   19.6 m/s) the warning says so.

use crate::physics::hertz64::{
    HertzImpact64, Material64, effective_modulus_pa, hertz_stiffness, sphere_mass_kg,
};
use crate::physics::impact::ImpactSpec;
use crate::physics::integrate::{Method, SimError, Tolerance};
use crate::physics::law_spec::LawSpec;
use crate::scene::MaterialName;

/// Input columns of a batch file, in the order they are echoed (see `impact_cli`).
pub const INPUT_COLUMNS: [&str; 18] = [
    "material",
    "density",
    "modulus",
    "poisson",
    "plate",
    "plate_density",
    "plate_modulus",
    "plate_poisson",
    "radius",
    "speed",
    "law",
    "restitution",
    "c_max",
    "depth",
    "method",
    "tol",
    "steps_per_tc",
    "gravity",
];

/// Index of `restitution` in [`INPUT_COLUMNS`].
pub const RESTITUTION_COLUMN: usize = 11;

/// Names of the echoed inputs in the answer: [`INPUT_COLUMNS`] with `restitution` written as
/// `target_restitution`, since `restitution` is also a result column (the simulated one).
/// A batch file may use either name.
pub const ECHO_COLUMNS: [&str; 18] = {
    let mut names = INPUT_COLUMNS;
    names[RESTITUTION_COLUMN] = "target_restitution";
    names
};

/// Adams penetration `d` in m when `depth` is not given (Adams' own suggestion).
pub const DEFAULT_DEPTH_M: f64 = 1e-5;

/// Dormand-Prince tolerance when `tol` is not given.
pub const DEFAULT_TOL: f64 = 1e-9;

/// Smallest accepted `tol`: below it the scaled state's rounding (2.2e-16 per step) is no
/// longer small against the tolerance.
pub const MIN_TOL: f64 = 1e-14;

/// RK4 steps per Hertz contact time when `steps_per_tc` is not given.
pub const DEFAULT_STEPS_PER_TC: u32 = 200;

/// Most RK4 steps per contact time (the run is then about a second long).
pub const MAX_STEPS_PER_TC: u32 = 10_000_000;

/// `delta_max / R` above which the paraboloid of Hertz errs by more than 1 % of the
/// penetration at the contact edge (`delta / (8 R)`, see the module docs).
pub const MAX_PENETRATION_RATIO: f64 = 0.08;

/// Share of the sphere's bar-wave speed `sqrt(E / rho)` above which the quasi-static Hertz
/// impact is warned about (see the module docs).
pub const MAX_WAVE_SPEED_SHARE: f64 = 0.01;

/// Contact force law (see [`crate::physics::laws`]); its force in [`LawName::about`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LawName {
    /// Undamped Hertz.
    Hertz,
    /// MSC Adams IMPACT.
    Adams,
    /// Hunt-Crossley.
    HuntCrossley,
    /// Lankarani-Nikravesh.
    LankaraniNikravesh,
    /// Flores et al.
    Flores,
    /// Gonthier et al.
    Gonthier,
    /// Tsuji / Hertz-Mindlin DEM damping.
    Tsuji,
}

impl LawName {
    /// Every law, in the order the help lists them.
    pub const ALL: [Self; 7] = [
        Self::Hertz,
        Self::Adams,
        Self::HuntCrossley,
        Self::LankaraniNikravesh,
        Self::Flores,
        Self::Gonthier,
        Self::Tsuji,
    ];

    /// The name as written on the command line and in CSV.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Hertz => "hertz",
            Self::Adams => "adams",
            Self::HuntCrossley => "hunt-crossley",
            Self::LankaraniNikravesh => "lankarani-nikravesh",
            Self::Flores => "flores",
            Self::Gonthier => "gonthier",
            Self::Tsuji => "tsuji",
        }
    }

    /// The law's force, as the help shows it.
    pub fn about(self) -> &'static str {
        match self {
            Self::Hertz => "Undamped Hertz `F = k delta^1.5`",
            Self::Adams => {
                "MSC Adams IMPACT `F = max(0, k delta^1.5 + STEP(delta, 0, 0, d, c_max) delta')`, \
                 with `c_max` given or found for `restitution`"
            }
            Self::HuntCrossley => {
                "Hunt-Crossley `F = k delta^1.5 (1 + chi delta'/u)`, `chi = 3 (1 - e)/2`"
            }
            Self::LankaraniNikravesh => "Lankarani-Nikravesh, `chi = 3 (1 - e^2)/4`",
            Self::Flores => "Flores et al., `chi = 8 (1 - e)/(5 e)`",
            Self::Gonthier => "Gonthier et al., `chi = (1 - e^2)/e`",
            Self::Tsuji => "Tsuji / Hertz-Mindlin DEM damping with `beta(e)`",
        }
    }

    /// Parses a name (case-insensitive, `_` for `-` allowed).
    pub fn parse(s: &str) -> Result<Self, String> {
        let norm = s.trim().to_ascii_lowercase().replace('_', "-");
        Self::ALL
            .into_iter()
            .find(|l| l.as_str() == norm)
            .ok_or_else(|| {
                format!(
                    "unknown law {s:?}: expected hertz, adams, hunt-crossley, \
                     lankarani-nikravesh, flores, gonthier or tsuji"
                )
            })
    }
}

/// Integration method (see [`crate::physics::integrate::Method`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MethodName {
    /// Adaptive Dormand-Prince 5(4) with tolerance `tol` (the default).
    Dopri5,
    /// Adaptive Dormand-Prince 8(5,3) with tolerance `tol`: fewer force evaluations at tight
    /// tolerances (1e-9 and below).
    Dop853,
    /// Rodas4, a Rosenbrock method on the exact Jacobian, with tolerance `tol`: for heavily
    /// damped (stiff) contacts.
    Rodas4,
    /// Radau13, the 7-stage Radau IIA method of order 13 on the exact Jacobian, with
    /// tolerance `tol`: for heavily damped (stiff) contacts at tight tolerances.
    Radau13,
    /// Dop853 where the contact is not stiff, Radau13 where it is (chosen step by step from
    /// the Jacobian), with tolerance `tol`.
    Auto,
    /// Fixed-step RK4 with `steps_per_tc` steps per Hertz contact time.
    Rk4,
}

impl MethodName {
    /// Every method, in the order the help lists them.
    pub const ALL: [Self; 6] = [
        Self::Dopri5,
        Self::Dop853,
        Self::Rodas4,
        Self::Radau13,
        Self::Auto,
        Self::Rk4,
    ];

    /// The name as written on the command line and in CSV.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Dopri5 => "dopri5",
            Self::Dop853 => "dop853",
            Self::Rodas4 => "rodas4",
            Self::Radau13 => "radau13",
            Self::Auto => "auto",
            Self::Rk4 => "rk4",
        }
    }

    /// The method and its input, as the help shows it.
    pub fn about(self) -> &'static str {
        match self {
            Self::Dopri5 => "Adaptive Dormand-Prince 5(4) with tolerance `tol` (the default)",
            Self::Dop853 => {
                "Adaptive Dormand-Prince 8(5,3) with tolerance `tol`: fewer force evaluations at 1e-9 and below"
            }
            Self::Rodas4 => {
                "Rodas4, a Rosenbrock method on the exact Jacobian, with tolerance `tol`: for heavily damped (stiff) contacts"
            }
            Self::Radau13 => {
                "Radau IIA of order 13 on the exact Jacobian, with tolerance `tol`: for heavily damped (stiff) contacts at tight tolerances"
            }
            Self::Auto => {
                "Dop853 where the contact is not stiff, Radau13 where it is (chosen step by step), with tolerance `tol`"
            }
            Self::Rk4 => "Fixed-step RK4 with `steps_per_tc` steps per Hertz contact time",
        }
    }

    /// Parses a name (case-insensitive).
    pub fn parse(s: &str) -> Result<Self, String> {
        let norm = s.trim().to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|m| m.as_str() == norm)
            .ok_or_else(|| {
                format!(
                    "unknown method {s:?}: expected dopri5, dop853, rodas4, radau13, auto or rk4"
                )
            })
    }
}

/// A number in shortest round-trip form: plain for `1e-3 <= |x| < 1e7` (and 0), else
/// scientific (`1.0680041269757393e-4`).
pub fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-3..1e7).contains(&a) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Gravity from its text: an acceleration in m/s^2 pushing the sphere into the plate during
/// the contact, finite and `>= 0` (the flag `--gravity` and the batch column alike).
pub fn parse_gravity(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(g) if g.is_finite() && g >= 0.0 => Ok(g),
        _ => Err(format!(
            "gravity = {text:?}: give the acceleration in m/s^2 that pushes the sphere into \
             the plate, >= 0 (9.80665 for standard gravity, 0 for none)"
        )),
    }
}

/// One impact's inputs as text cells, in [`INPUT_COLUMNS`] order (empty = not given).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct InputRow {
    /// The cells.
    pub cells: [String; 18],
}

/// A row read: the simulation it asks for, its closed forms, the inputs as echoed (the
/// defaults that apply filled in) and its warnings.
#[derive(Debug, Clone)]
pub struct Reading {
    /// What to simulate.
    pub spec: ImpactSpec,
    /// The undamped, gravity-free Hertz closed forms of the impact.
    pub hertz: HertzImpact64,
    /// The inputs with the defaults that apply written in (`plate`, `law`, `method`,
    /// `depth` for adams, `tol` for dopri5, `steps_per_tc` for rk4, `gravity`).
    pub echo: InputRow,
    /// Where the impact lies far outside Hertz theory (see the module docs).
    pub warnings: Vec<String>,
}

impl InputRow {
    fn index(name: &str) -> Option<usize> {
        INPUT_COLUMNS.iter().position(|c| *c == name)
    }

    /// The cell of input column `name`, or `""` for an unknown name.
    pub fn get(&self, name: &str) -> &str {
        Self::index(name)
            .map(|i| self.cells[i].trim())
            .unwrap_or("")
    }

    fn set_default(&mut self, name: &str, value: &str) {
        if let Some(i) = Self::index(name)
            && self.cells[i].trim().is_empty()
        {
            self.cells[i] = value.to_string();
        }
    }

    fn num(&self, name: &str) -> Result<Option<f64>, String> {
        let s = self.get(name);
        if s.is_empty() {
            return Ok(None);
        }
        s.parse::<f64>()
            .map(Some)
            .map_err(|_| format!("{name}: {s:?} is not a number"))
    }

    /// Column `name` if given: a finite number `> 0` (in `unit`).
    fn positive(&self, name: &str, unit: &str) -> Result<Option<f64>, String> {
        match self.num(name)? {
            Some(v) if !(v.is_finite() && v > 0.0) => Err(format!(
                "{name} = {}: must be finite and > 0 ({unit})",
                fmt_f64(v)
            )),
            v => Ok(v),
        }
    }

    fn required_positive(&self, name: &str, unit: &str) -> Result<f64, String> {
        self.positive(name, unit)?
            .ok_or_else(|| format!("{name} is missing ({unit})"))
    }

    /// Column `name` if given: Poisson's ratio in `(-1, 0.5]`.
    fn poisson(&self, name: &str) -> Result<Option<f64>, String> {
        match self.num(name)? {
            Some(nu) if !(nu > -1.0 && nu <= 0.5) => Err(format!(
                "{name} = {}: Poisson's ratio must be in (-1, 0.5]",
                fmt_f64(nu)
            )),
            v => Ok(v),
        }
    }

    /// The simulation this row asks for, or a message saying what is wrong with it.
    pub fn to_spec(&self) -> Result<ImpactSpec, String> {
        self.read().map(|r| r.spec)
    }

    /// Reads and checks the row (see [`Reading`]); every message names the column.
    pub fn read(&self) -> Result<Reading, String> {
        let mut echo = self.clone();
        let sphere = self.sphere()?;
        let plate = self.plate(&mut echo)?;
        let radius = self.required_positive("radius", "m")?;
        let speed = self.required_positive("speed", "m/s")?;
        let law_name = match self.get("law") {
            "" => LawName::Hertz,
            s => LawName::parse(s)?,
        };
        let method = match self.get("method") {
            "" => MethodName::Dopri5,
            s => MethodName::parse(s)?,
        };
        echo.set_default("law", law_name.as_str());
        echo.set_default("method", method.as_str());
        self.check_applies(law_name, method)?;
        let law = self.law(law_name, &mut echo)?;
        let gravity = match self.get("gravity") {
            "" => 0.0,
            s => parse_gravity(s)?,
        };
        echo.set_default("gravity", "0");
        let hertz = closed_forms(&sphere, &plate, radius, speed)?;
        let mut spec = ImpactSpec::new(sphere, plate, radius, speed);
        spec.law = law;
        spec.gravity_m_s2 = gravity;
        self.numerics(method, &mut spec, &mut echo)?;
        let warnings = hertz_warnings(&hertz, &sphere);
        Ok(Reading {
            spec,
            hertz,
            echo,
            warnings,
        })
    }

    /// The sphere: `material` by name, each of `density`, `modulus`, `poisson` replacing its
    /// value; all three without a name.
    fn sphere(&self) -> Result<Material64, String> {
        let props = [
            self.positive("density", "kg/m^3")?,
            self.positive("modulus", "Pa")?,
            self.poisson("poisson")?,
        ];
        let base = named("material", self.get("material"))?;
        let m = match (base, props) {
            (Some(m), _) => m,
            (None, [Some(d), Some(e), Some(nu)]) => Material64 {
                density_kg_m3: d,
                modulus_pa: e,
                poisson: nu,
            },
            (None, _) => {
                return Err("give material, or all of density, modulus and poisson".into());
            }
        };
        Ok(Material64 {
            density_kg_m3: props[0].unwrap_or(m.density_kg_m3),
            modulus_pa: props[1].unwrap_or(m.modulus_pa),
            poisson: props[2].unwrap_or(m.poisson),
        })
    }

    /// The plate: `plate` by name (carbon steel when neither it nor a property is given),
    /// each of `plate_modulus`, `plate_poisson`, `plate_density` replacing its value; without
    /// a name, `plate_modulus` and `plate_poisson` (the plate's density does not enter the
    /// contact of a sphere on a plate and may be left out).
    fn plate(&self, echo: &mut InputRow) -> Result<Material64, String> {
        let density = self.positive("plate_density", "kg/m^3")?;
        let modulus = self.positive("plate_modulus", "Pa")?;
        let poisson = self.poisson("plate_poisson")?;
        let name = self.get("plate");
        let any_prop = density.is_some() || modulus.is_some() || poisson.is_some();
        let base = match named("plate", name)? {
            Some(m) => m,
            None if !any_prop => {
                echo.set_default("plate", MaterialName::CarbonSteel.name());
                Material64::CARBON_STEEL
            }
            None => match (modulus, poisson) {
                (Some(e), Some(nu)) => Material64 {
                    density_kg_m3: f64::NAN,
                    modulus_pa: e,
                    poisson: nu,
                },
                _ => {
                    return Err("give plate, or both plate_modulus and plate_poisson \
                                (plate_density is optional)"
                        .into());
                }
            },
        };
        Ok(Material64 {
            density_kg_m3: density.unwrap_or(base.density_kg_m3),
            modulus_pa: modulus.unwrap_or(base.modulus_pa),
            poisson: poisson.unwrap_or(base.poisson),
        })
    }

    /// Refuses an input that the law or the method does not use.
    fn check_applies(&self, law: LawName, method: MethodName) -> Result<(), String> {
        let refuse = |col: &str, who: String, users: &str| {
            if self.get(col).is_empty() {
                Ok(())
            } else {
                Err(format!(
                    "{col} does not apply to {who} ({users}); remove it"
                ))
            }
        };
        let law_who = format!("law {}", law.as_str());
        match law {
            LawName::Hertz => {
                let users = "undamped: restitution 1";
                refuse("restitution", law_who.clone(), users)?;
                refuse("c_max", law_who.clone(), users)?;
                refuse("depth", law_who, users)?;
            }
            LawName::Adams => {}
            _ => {
                let users = "only adams takes c_max and depth";
                refuse("c_max", law_who.clone(), users)?;
                refuse("depth", law_who, users)?;
            }
        }
        let method_who = format!("method {}", method.as_str());
        match method {
            MethodName::Rk4 => refuse("tol", method_who, "only the adaptive methods take it"),
            _ => refuse("steps_per_tc", method_who, "only rk4 takes it"),
        }
    }

    /// The law's specification, its restitution, `c_max` and depth checked.
    fn law(&self, name: LawName, echo: &mut InputRow) -> Result<LawSpec, String> {
        let restitution = self.num("restitution")?;
        let need_e = || match restitution {
            Some(e) => restitution_in_range(e, false, name),
            None => Err(format!("law {} needs restitution", name.as_str())),
        };
        Ok(match name {
            LawName::Hertz => LawSpec::Hertz,
            LawName::Adams => self.adams(restitution, echo)?,
            LawName::HuntCrossley => LawSpec::HuntCrossley {
                restitution: need_e()?,
            },
            LawName::LankaraniNikravesh => LawSpec::LankaraniNikravesh {
                restitution: need_e()?,
            },
            LawName::Flores => LawSpec::Flores {
                restitution: need_e()?,
            },
            LawName::Gonthier => LawSpec::Gonthier {
                restitution: need_e()?,
            },
            LawName::Tsuji => LawSpec::Tsuji {
                restitution: need_e()?,
            },
        })
    }

    /// Adams's law from `c_max` (finite, >= 0, N s/m) or `restitution` (in (0, 1)), one of the
    /// two, and `depth` (m, default 1e-5, which `echo` then shows).
    fn adams(&self, restitution: Option<f64>, echo: &mut InputRow) -> Result<LawSpec, String> {
        let d_m = self.positive("depth", "m")?.unwrap_or(DEFAULT_DEPTH_M);
        echo.set_default("depth", "1e-5");
        Ok(match (self.num("c_max")?, restitution) {
            (Some(c), None) if c.is_finite() && c >= 0.0 => LawSpec::Adams {
                c_max_n_s_m: c,
                d_m,
            },
            (Some(c), None) => {
                return Err(format!(
                    "c_max = {}: must be finite and >= 0 (N s/m)",
                    fmt_f64(c)
                ));
            }
            (None, Some(e)) => LawSpec::AdamsRestitution {
                restitution: restitution_in_range(e, true, LawName::Adams)?,
                d_m,
            },
            (Some(_), Some(_)) => {
                return Err("law adams: give c_max or restitution, not both".into());
            }
            (None, None) => return Err("law adams needs c_max or restitution".into()),
        })
    }

    /// The method with its `tol` (`[MIN_TOL, 1)`) or `steps_per_tc` (1 to
    /// [`MAX_STEPS_PER_TC`]).
    fn numerics(
        &self,
        method: MethodName,
        spec: &mut ImpactSpec,
        echo: &mut InputRow,
    ) -> Result<(), String> {
        let adaptive = match method {
            MethodName::Dopri5 => Some(Method::Dopri5),
            MethodName::Dop853 => Some(Method::Dop853),
            MethodName::Rodas4 => Some(Method::Rodas4),
            MethodName::Radau13 => Some(Method::Radau13),
            MethodName::Auto => Some(Method::Auto),
            MethodName::Rk4 => None,
        };
        match adaptive {
            Some(adaptive) => {
                let tol = self.num("tol")?.unwrap_or(DEFAULT_TOL);
                if !(MIN_TOL..1.0).contains(&tol) {
                    return Err(format!(
                        "tol = {}: must be in [{MIN_TOL:e}, 1) (relative and absolute \
                         tolerance on the state scaled by delta_max and u)",
                        fmt_f64(tol)
                    ));
                }
                echo.set_default("tol", "1e-9");
                spec.method = adaptive;
                spec.tolerance = Tolerance::new(tol);
            }
            None => {
                let steps = match self.get("steps_per_tc") {
                    "" => DEFAULT_STEPS_PER_TC,
                    s => s
                        .parse::<u32>()
                        .ok()
                        .filter(|n| (1..=MAX_STEPS_PER_TC).contains(n))
                        .ok_or_else(|| {
                            format!(
                                "steps_per_tc = {s}: must be a whole number from 1 to \
                                 {MAX_STEPS_PER_TC}"
                            )
                        })?,
                };
                echo.set_default("steps_per_tc", &steps.to_string());
                spec.method = Method::Rk4 {
                    steps_per_tc: steps,
                };
            }
        }
        Ok(())
    }
}

/// The material named in column `column`, `None` for an empty cell.
fn named(column: &str, name: &str) -> Result<Option<Material64>, String> {
    if name.is_empty() {
        return Ok(None);
    }
    MaterialName::from_name(name)
        .map(|m| Some(m.material()))
        .ok_or_else(|| {
            let props = if column == "plate" {
                "plate_modulus/plate_poisson"
            } else {
                "density/modulus/poisson"
            };
            format!(
                "unknown {column} {name:?}: expected one of {} or {props}",
                MaterialName::names()
            )
        })
}

/// The Hertz closed forms, each derived value checked to be a positive f64 (a radius of
/// 1e-200 m has no representable mass), named by the inputs it comes from.
fn closed_forms(
    sphere: &Material64,
    plate: &Material64,
    radius_m: f64,
    speed_m_s: f64,
) -> Result<HertzImpact64, String> {
    let usable = |v: f64| v.is_finite() && v > 0.0;
    let mass = sphere_mass_kg(sphere.density_kg_m3, radius_m);
    if !usable(mass) {
        return Err(format!(
            "radius = {} m and density = {} kg/m^3 give a sphere mass of {} kg, outside the \
             range of f64",
            fmt_f64(radius_m),
            fmt_f64(sphere.density_kg_m3),
            fmt_f64(mass)
        ));
    }
    let k = hertz_stiffness(effective_modulus_pa(sphere, plate), radius_m);
    if !usable(k) {
        return Err(format!(
            "the moduli, Poisson's ratios and radius = {} m give a Hertz stiffness \
             k = {} N/m^1.5, outside the range of f64",
            fmt_f64(radius_m),
            fmt_f64(k)
        ));
    }
    let hz = HertzImpact64::from_stiffness_mass(k, mass, speed_m_s).map_err(user_terms)?;
    if !(usable(hz.delta_max_m) && usable(hz.peak_force_n) && usable(hz.duration_s)) {
        return Err(format!(
            "speed = {} m/s with this sphere gives delta_max = {} m, F_max = {} N, \
             t_c = {} s: outside the range of f64",
            fmt_f64(speed_m_s),
            fmt_f64(hz.delta_max_m),
            fmt_f64(hz.peak_force_n),
            fmt_f64(hz.duration_s)
        ));
    }
    Ok(HertzImpact64 {
        effective_modulus_pa: effective_modulus_pa(sphere, plate),
        radius_m,
        ..hz
    })
}

/// Warnings where the impact lies far outside Hertz theory (see the module docs).
pub fn hertz_warnings(hz: &HertzImpact64, sphere: &Material64) -> Vec<String> {
    let mut out = Vec::new();
    let ratio = hz.delta_max_m / hz.radius_m;
    if ratio > MAX_PENETRATION_RATIO {
        out.push(format!(
            "penetration delta_max = {:.3e} m is {ratio:.3} of the radius, above \
             {MAX_PENETRATION_RATIO}: Hertz's paraboloid errs by {:.1} % of it at the contact \
             edge (small-strain Hertz theory does not hold)",
            hz.delta_max_m,
            100.0 * ratio / 8.0
        ));
    }
    let c0 = (sphere.modulus_pa / sphere.density_kg_m3).sqrt();
    if hz.speed_m_s > MAX_WAVE_SPEED_SHARE * c0 {
        out.push(format!(
            "speed = {} m/s is {:.3} of the sphere's bar-wave speed sqrt(E/rho) = {c0:.0} m/s, \
             above {MAX_WAVE_SPEED_SHARE}: the quasi-static Hertz impact does not hold",
            fmt_f64(hz.speed_m_s),
            hz.speed_m_s / c0
        ));
    }
    out
}

/// An integration error in the user's terms: a parameter the integrator names internally
/// (`law.d_m`, `mass_kg`, ...) is named by its column.
pub fn user_terms(e: SimError) -> String {
    let SimError::InvalidParameter {
        name,
        value,
        requirement,
    } = &e
    else {
        return e.to_string();
    };
    let column = match name.as_str() {
        "law.d_m" => "depth",
        "law.c_max_n_s_m" => "c_max",
        "restitution" => "restitution",
        "tolerance.rtol" | "tolerance.atol" => "tol",
        "steps_per_tc" => "steps_per_tc",
        "gravity_m_s2" => "gravity",
        "radius_m" => "radius",
        "speed_m_s" | "law.impact_speed_m_s" => "speed",
        "sphere.density_kg_m3" => "density",
        "sphere.modulus_pa" => "modulus",
        "sphere.poisson" => "poisson",
        "plate.modulus_pa" => "plate_modulus",
        "plate.poisson" => "plate_poisson",
        "record interval_s" => "series_interval",
        "mass_kg" | "law.mass_kg" => "the sphere's mass (from density and radius)",
        "stiffness" | "law.stiffness" => {
            "the Hertz stiffness (from the moduli, Poisson's ratios and radius)"
        }
        _ => name.as_str(),
    };
    format!("{column} = {}: must be {requirement}", fmt_f64(*value))
}

/// The coefficient of restitution `e` for law `name`, when in `(0, 1]` (`(0, 1)` with
/// `top_open`); otherwise the message that says so.
fn restitution_in_range(e: f64, top_open: bool, name: LawName) -> Result<f64, String> {
    let ok = e > 0.0 && if top_open { e < 1.0 } else { e <= 1.0 };
    if ok {
        Ok(e)
    } else {
        let top = if top_open { "1)" } else { "1]" };
        Err(format!(
            "restitution = {}: must be in (0, {top} for law {}",
            fmt_f64(e),
            name.as_str()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn echo_columns_rename_restitution_alone() {
        assert_eq!(INPUT_COLUMNS[RESTITUTION_COLUMN], "restitution");
        for (i, (a, b)) in INPUT_COLUMNS.iter().zip(ECHO_COLUMNS).enumerate() {
            assert_eq!(*a == b, i != RESTITUTION_COLUMN, "{a} {b}");
        }
    }
}
