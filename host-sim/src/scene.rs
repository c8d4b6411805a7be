//! The TOML scene format of host-sim (`f64`, SI units): the plate, the particle classes with
//! their priors, the contact force law the simulation integrates, the sensor chain that turns
//! contact force into ADC counts, and optional overrides of the kernel's settings.
//!
//! ```toml
//! name = "paper"
//! plate = "carbon_steel"              # a name, or { density_kg_m3 = .., modulus_pa = .., poisson = .. }
//!
//! [[classes]]
//! name = "coal"                       # at most 16 bytes (the kernel's NAME_LEN)
//! material = "coal"
//! radius_m = [0.015, 0.04]            # log-uniform prior on [min, max] (exactly two numbers)
//! speed_m_s = [1.0, 5.0]              # uniform prior; or drop_height_m = [h0, h1] (uniform height)
//! prior = 1.0                         # relative share of impacts (default 1)
//! # yield_pressure_pa = 40e6           # optional: the material's limiting contact pressure
//!                                     # (Thornton); the class's contact then yields
//!
//! [contact]
//! law = "hertz"                       # or hunt_crossley / lankarani_nikravesh / flores /
//!                                     # gonthier / tsuji { restitution }, adams { c_max_n_s_m, d_m },
//!                                     # adams_restitution { restitution, d_m }
//!
//! [sensor]
//! sample_rate_hz = 100000.0
//! effective_mass_kg = 50.0
//! counts_per_m_s2 = 30.0
//! noise_rms_counts = 4.0
//! adc_bits = 16
//! # dc_offset_counts = 0.0, dc_drift_counts_per_s = 0.0, oversample = 32
//! # accelerometer = { frequency_hz = 40000.0, damping_ratio = 0.05 }
//! # [[sensor.beam_modes]]  frequency_hz = 180.0, damping_ratio = 0.02, gain = 0.1
//!
//! [settings]                          # optional, any subset of the kernel's Settings
//! confident_error_rate = 0.01       # share of class verdicts allowed to be wrong
//! ```
//!
//! `[contact]` is the integrator's own `LawSpec` (`physics::law_spec`) and `[settings]` the
//! kernel's own `Settings` (`coalshock::settings_serde`, its `serde` feature): each is written
//! once.
//!
//! [`load`] reads, parses and checks a file; every error names the file, and the field or the
//! line and column that is wrong, and in a class the class's name. Values the kernel holds in
//! `f32` must lie within its bounds ([`KERNEL_RANGE`]: a non-zero size from 1e-30 to 1e30),
//! and so must each class's Hertz closed forms at the corners of its ranges. [`SceneFile::paper`] and [`SceneFile::paper_narrow`] are the
//! built-in scenes, equal to `scenes/paper.toml` and `scenes/paper_narrow.toml` and, once
//! converted (`bridge::convert`), to the kernel's `Scene::paper()` and `Scene::paper_narrow()`.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use coalshock::Settings;

use crate::physics::hertz64::Material64;
use crate::physics::law_spec::LawSpec;
use crate::physics::laws::restitution_in_range;
use crate::physics::sim_error::SimError;

/// Longest class name in bytes (the kernel's `coalshock::scene::NAME_LEN`).
pub const MAX_CLASS_NAME_BYTES: usize = coalshock::scene::NAME_LEN;

/// Most classes a scene file may hold (the kernel's `coalshock::scene::MAX_CLASSES`).
pub const MAX_CLASSES: usize = coalshock::scene::MAX_CLASSES;

/// Widest ADC in bits: samples are stored as `i16` (see `FORMATS.md`).
pub const MAX_ADC_BITS: u8 = 16;

/// Narrowest ADC in bits.
pub const MIN_ADC_BITS: u8 = 2;

/// Largest accepted oversampling factor of the sensor's fine time grid.
pub const MAX_OVERSAMPLE: u32 = 1024;

/// Default oversampling factor of the sensor's fine time grid (fine step `1 / (32 f_s)`).
pub const DEFAULT_OVERSAMPLE: u32 = 32;

/// What is wrong with a scene file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene file {}: {error}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        error: std::io::Error,
    },
    /// The file is not valid TOML or does not have the scene's shape (the message carries the
    /// line, column and key).
    #[error("scene file {}: {message}", path.display())]
    Parse {
        /// The file (`<string>` when parsed from a string).
        path: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// A value is out of its range.
    #[error("scene{}: {field} {problem}", path.as_ref().map(|p| format!(" file {}", p.display())).unwrap_or_default())]
    Invalid {
        /// The file, if the scene came from one.
        path: Option<PathBuf>,
        /// Where in the scene, e.g. `classes[1].radius_m`.
        field: String,
        /// What is wrong, e.g. `must be finite and > 0 (got -1)`.
        problem: String,
    },
}

impl SceneError {
    fn invalid(field: impl Into<String>, problem: impl Into<String>) -> Self {
        SceneError::Invalid {
            path: None,
            field: field.into(),
            problem: problem.into(),
        }
    }

    /// The same error with the class named after its field (`classes[1].prior (class
    /// "gangue")`).
    fn of_class(self, class: &str) -> Self {
        match self {
            SceneError::Invalid {
                path,
                field,
                problem,
            } => SceneError::Invalid {
                path,
                field: format!("{field} (class {class:?})"),
                problem,
            },
            other => other,
        }
    }

    fn in_file(self, file: &Path) -> Self {
        match self {
            SceneError::Invalid {
                path: None,
                field,
                problem,
            } => SceneError::Invalid {
                path: Some(file.to_path_buf()),
                field,
                problem,
            },
            other => other,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Materials
// ---------------------------------------------------------------------------------------------

/// The materials a scene can name (physics notes, section 4; the paper's Tables 1-2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaterialName {
    /// Coal (paper): 1380 kg/m^3, 5.3 GPa, nu 0.32.
    Coal,
    /// Sandstone gangue (paper): 2487 kg/m^3, 13.5 GPa, nu 0.123.
    Sandstone,
    /// Carbon-steel plate (paper): 7850 kg/m^3, 206 GPa, nu 0.28.
    CarbonSteel,
    /// Roof sandstone (literature): 2525 kg/m^3, 35 GPa, nu 0.25.
    RoofSandstone,
    /// Sandy mudstone (literature): 2500 kg/m^3, 5.4 GPa, nu 0.15.
    SandyMudstone,
}

impl MaterialName {
    /// Every named material, in the order of [`MaterialName::name`].
    pub const ALL: [MaterialName; 5] = [
        MaterialName::Coal,
        MaterialName::Sandstone,
        MaterialName::CarbonSteel,
        MaterialName::RoofSandstone,
        MaterialName::SandyMudstone,
    ];

    /// The name used in scene files (`snake_case`).
    pub fn name(self) -> &'static str {
        match self {
            MaterialName::Coal => "coal",
            MaterialName::Sandstone => "sandstone",
            MaterialName::CarbonSteel => "carbon_steel",
            MaterialName::RoofSandstone => "roof_sandstone",
            MaterialName::SandyMudstone => "sandy_mudstone",
        }
    }

    /// The material by name, or `None`: the names of [`MaterialName::name`], in any case,
    /// with `-` for `_`, and the short forms `steel` (carbon steel) and `mudstone` (sandy
    /// mudstone). Scene files and `host-sim impact` read materials through this one list.
    pub fn from_name(name: &str) -> Option<Self> {
        let norm = name.trim().to_ascii_lowercase().replace('-', "_");
        match norm.as_str() {
            "steel" => Some(MaterialName::CarbonSteel),
            "mudstone" => Some(MaterialName::SandyMudstone),
            n => Self::ALL.into_iter().find(|m| m.name() == n),
        }
    }

    /// Every name of [`MaterialName::ALL`], joined by `", "`.
    pub fn names() -> String {
        let names: Vec<&str> = Self::ALL.iter().map(|m| m.name()).collect();
        names.join(", ")
    }

    /// Density (kg/m^3), Young's modulus (Pa) and Poisson's ratio of the material.
    pub fn material(self) -> Material64 {
        let m = |density_kg_m3, modulus_pa, poisson| Material64 {
            density_kg_m3,
            modulus_pa,
            poisson,
        };
        match self {
            MaterialName::Coal => Material64::COAL,
            MaterialName::Sandstone => Material64::SANDSTONE,
            MaterialName::CarbonSteel => Material64::CARBON_STEEL,
            MaterialName::RoofSandstone => m(2525.0, 35.0e9, 0.25),
            MaterialName::SandyMudstone => m(2500.0, 5.4e9, 0.15),
        }
    }
}

/// A material in a scene file: a name from [`MaterialName`] (`"coal"`) or explicit properties
/// (`{ density_kg_m3 = 1380.0, modulus_pa = 5.3e9, poisson = 0.32 }`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MaterialSpec {
    /// A material from the built-in table.
    Named(MaterialName),
    /// Explicit density (kg/m^3), modulus (Pa) and Poisson's ratio.
    Custom(Material64),
}

impl MaterialSpec {
    /// The material's properties (SI units).
    pub fn material(&self) -> Material64 {
        match *self {
            MaterialSpec::Named(n) => n.material(),
            MaterialSpec::Custom(m) => m,
        }
    }

    /// Checks density and modulus finite and `> 0`, `0 <= nu < 0.5` (the kernel's range).
    fn validate(&self, field: &str) -> Result<(), SceneError> {
        let m = self.material();
        positive(&format!("{field}.density_kg_m3"), m.density_kg_m3)?;
        positive(&format!("{field}.modulus_pa"), m.modulus_pa)?;
        if !(m.poisson.is_finite() && (0.0..0.5).contains(&m.poisson)) {
            return Err(SceneError::invalid(
                format!("{field}.poisson"),
                format!("must be in [0, 0.5) (got {})", m.poisson),
            ));
        }
        Ok(())
    }
}

/// The explicit form of a material in a file.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CustomMaterial {
    density_kg_m3: f64,
    modulus_pa: f64,
    poisson: f64,
}

impl Serialize for MaterialSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match *self {
            MaterialSpec::Named(n) => s.serialize_str(n.name()),
            MaterialSpec::Custom(m) => CustomMaterial {
                density_kg_m3: m.density_kg_m3,
                modulus_pa: m.modulus_pa,
                poisson: m.poisson,
            }
            .serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for MaterialSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = MaterialSpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(
                    f,
                    "a material name ({}) or a table {{ density_kg_m3, modulus_pa, poisson }}",
                    MaterialName::names()
                )
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<MaterialSpec, E> {
                MaterialName::from_name(v)
                    .map(MaterialSpec::Named)
                    .ok_or_else(|| {
                        E::custom(format!(
                            "unknown material {v:?}; known: {}, or give {{ density_kg_m3, \
                         modulus_pa, poisson }}",
                            MaterialName::names()
                        ))
                    })
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<MaterialSpec, A::Error> {
                let c = CustomMaterial::deserialize(de::value::MapAccessDeserializer::new(map))?;
                Ok(MaterialSpec::Custom(Material64 {
                    density_kg_m3: c.density_kg_m3,
                    modulus_pa: c.modulus_pa,
                    poisson: c.poisson,
                }))
            }
        }
        d.deserialize_any(V)
    }
}

// ---------------------------------------------------------------------------------------------
// Ranges and classes
// ---------------------------------------------------------------------------------------------

/// A closed interval `[min, max]`, written `[min, max]` in a file (exactly two numbers); unit
/// given by the field name.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(into = "[f64; 2]")]
pub struct Range64 {
    /// Lower end.
    pub min: f64,
    /// Upper end.
    pub max: f64,
}

impl Range64 {
    /// `[min, max]` (checked by the scene's validation).
    pub const fn new(min: f64, max: f64) -> Self {
        Self { min, max }
    }

    fn validate(&self, field: &str) -> Result<(), SceneError> {
        positive(&format!("{field}[0]"), self.min)?;
        positive(&format!("{field}[1]"), self.max)?;
        if self.min >= self.max {
            return Err(SceneError::invalid(
                field,
                format!("must have min < max (got [{}, {}])", self.min, self.max),
            ));
        }
        Ok(())
    }
}

impl Range64 {
    /// The range written as `values` in a file: exactly two numbers (integers are taken as
    /// numbers), else a message saying what was found.
    pub fn from_values(values: &[toml::Value]) -> Result<Self, String> {
        let shown = || {
            let cells: Vec<String> = values.iter().map(|v| v.to_string()).collect();
            format!("[{}]", cells.join(", "))
        };
        let number = |v: &toml::Value| match v {
            toml::Value::Float(x) => Some(*x),
            toml::Value::Integer(i) => Some(*i as f64),
            _ => None,
        };
        if values.len() != 2 {
            return Err(format!(
                "must be exactly two numbers [min, max] (got {} values: {})",
                values.len(),
                shown()
            ));
        }
        match (number(&values[0]), number(&values[1])) {
            (Some(min), Some(max)) => Ok(Self::new(min, max)),
            _ => Err(format!(
                "must be exactly two numbers [min, max] (got {})",
                shown()
            )),
        }
    }
}

impl<'de> Deserialize<'de> for Range64 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let values = Vec::<toml::Value>::deserialize(d)?;
        Range64::from_values(&values).map_err(de::Error::custom)
    }
}

impl From<[f64; 2]> for Range64 {
    fn from(v: [f64; 2]) -> Self {
        Self::new(v[0], v[1])
    }
}

impl From<Range64> for [f64; 2] {
    fn from(r: Range64) -> Self {
        [r.min, r.max]
    }
}

/// How the impact speed of a class is given, and so its prior.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpeedSpec {
    /// Impact speed `u` in m/s, uniform on the range (file key `speed_m_s`).
    Uniform(Range64),
    /// Drop height `h` in m, uniform on the range; `u = sqrt(2 g h)`, `g = 9.80665 m/s^2`
    /// (file key `drop_height_m`).
    DropHeight(Range64),
}

/// One particle class of a scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ClassRaw", into = "ClassRaw")]
pub struct ClassSpec {
    /// Name shown in reports, at most [`MAX_CLASS_NAME_BYTES`] bytes.
    pub name: String,
    /// The particle's material.
    pub material: MaterialSpec,
    /// Sphere radius `R` in m, log-uniform on the range.
    pub radius_m: Range64,
    /// Impact speed prior.
    pub speed: SpeedSpec,
    /// Prior weight (relative share of impacts), finite and `> 0`; 1 when not given.
    pub prior: f64,
    /// Limiting contact pressure `p_y` in Pa of the class's material against the plate
    /// (Thornton 1997), if it yields: its contacts then follow [`LawSpec::Thornton`] with the
    /// scene's restitution-law damping, if any. `None` (the default): elastic, as before.
    pub yield_pressure_pa: Option<f64>,
}

/// A class as written in a file: exactly one of `speed_m_s` and `drop_height_m`.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ClassRaw {
    name: String,
    material: MaterialSpec,
    radius_m: Vec<toml::Value>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    speed_m_s: Option<Vec<toml::Value>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    drop_height_m: Option<Vec<toml::Value>>,
    #[serde(default = "one")]
    prior: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    yield_pressure_pa: Option<f64>,
}

fn one() -> f64 {
    1.0
}

impl TryFrom<ClassRaw> for ClassSpec {
    type Error = String;
    fn try_from(r: ClassRaw) -> Result<Self, String> {
        let range = |field: &str, values: &[toml::Value]| {
            Range64::from_values(values).map_err(|e| format!("class {:?}: {field} {e}", r.name))
        };
        let radius_m = range("radius_m", &r.radius_m)?;
        let speed = match (&r.speed_m_s, &r.drop_height_m) {
            (Some(s), None) => SpeedSpec::Uniform(range("speed_m_s", s)?),
            (None, Some(h)) => SpeedSpec::DropHeight(range("drop_height_m", h)?),
            (Some(_), Some(_)) => {
                return Err(format!(
                    "class {:?}: give either speed_m_s or drop_height_m, not both",
                    r.name
                ));
            }
            (None, None) => {
                return Err(format!(
                    "class {:?}: missing speed_m_s = [min, max] (m/s) or drop_height_m = \
                     [min, max] (m)",
                    r.name
                ));
            }
        };
        Ok(ClassSpec {
            name: r.name,
            material: r.material,
            radius_m,
            speed,
            prior: r.prior,
            yield_pressure_pa: r.yield_pressure_pa,
        })
    }
}

impl From<ClassSpec> for ClassRaw {
    fn from(c: ClassSpec) -> Self {
        let (speed_m_s, drop_height_m) = match c.speed {
            SpeedSpec::Uniform(s) => (Some(s), None),
            SpeedSpec::DropHeight(h) => (None, Some(h)),
        };
        let values = |r: Range64| vec![toml::Value::Float(r.min), toml::Value::Float(r.max)];
        ClassRaw {
            name: c.name,
            material: c.material,
            radius_m: values(c.radius_m),
            speed_m_s: speed_m_s.map(values),
            drop_height_m: drop_height_m.map(values),
            prior: c.prior,
            yield_pressure_pa: c.yield_pressure_pa,
        }
    }
}

impl ClassSpec {
    /// A class with prior weight 1 and a uniform speed prior.
    pub fn new(name: &str, material: MaterialSpec, radius_m: Range64, speed_m_s: Range64) -> Self {
        Self {
            name: name.to_string(),
            material,
            radius_m,
            speed: SpeedSpec::Uniform(speed_m_s),
            prior: 1.0,
            yield_pressure_pa: None,
        }
    }

    /// The radius (m) and speed (m/s) at the quantiles `radius_q` and `speed_q` (in `[0, 1]`)
    /// of the class's priors: `R = exp(ln R_min + radius_q (ln R_max - ln R_min))`, and
    /// `u = u_min + speed_q (u_max - u_min)` or `u = sqrt(2 g (h_min + speed_q (h_max - h_min)))`.
    pub fn at_quantiles(&self, radius_q: f64, speed_q: f64) -> (f64, f64) {
        let (r0, r1) = (self.radius_m.min.ln(), self.radius_m.max.ln());
        let radius_m = (r0 + radius_q * (r1 - r0)).exp();
        let speed_m_s = match self.speed {
            SpeedSpec::Uniform(s) => s.min + speed_q * (s.max - s.min),
            SpeedSpec::DropHeight(h) => drop_speed_m_s(h.min + speed_q * (h.max - h.min)),
        };
        (radius_m, speed_m_s)
    }

    /// The speed range in m/s: the given one, or `sqrt(2 g h)` at both ends of the drop
    /// height range (`g = 9.80665 m/s^2`).
    pub fn speed_range_m_s(&self) -> Range64 {
        match self.speed {
            SpeedSpec::Uniform(s) => s,
            SpeedSpec::DropHeight(h) => Range64::new(drop_speed_m_s(h.min), drop_speed_m_s(h.max)),
        }
    }

    fn validate(&self, field: &str) -> Result<(), SceneError> {
        if self.name.is_empty() || self.name.len() > MAX_CLASS_NAME_BYTES {
            return Err(SceneError::invalid(
                format!("{field}.name"),
                format!(
                    "must be 1 to {MAX_CLASS_NAME_BYTES} bytes long (got {:?}, {} bytes)",
                    self.name,
                    self.name.len()
                ),
            ));
        }
        self.material.validate(&format!("{field}.material"))?;
        self.radius_m.validate(&format!("{field}.radius_m"))?;
        match self.speed {
            SpeedSpec::Uniform(s) => s.validate(&format!("{field}.speed_m_s"))?,
            SpeedSpec::DropHeight(h) => h.validate(&format!("{field}.drop_height_m"))?,
        }
        if let Some(p) = self.yield_pressure_pa {
            positive(&format!("{field}.yield_pressure_pa"), p)?;
        }
        positive(&format!("{field}.prior"), self.prior)
    }
}

/// Free-fall speed `u = sqrt(2 g h)` in m/s after a drop of `height_m` (m),
/// `g = 9.80665 m/s^2`.
pub fn drop_speed_m_s(height_m: f64) -> f64 {
    (2.0 * crate::physics::hertz64::STANDARD_GRAVITY_M_S2 * height_m).sqrt()
}

// ---------------------------------------------------------------------------------------------
// Contact law
// ---------------------------------------------------------------------------------------------

/// Checks the parameters of the scene's `[contact]` law, naming the field (`contact.d_m`).
fn validate_contact(law: &LawSpec) -> Result<(), SceneError> {
    let e_in = |e: f64, hi_open: bool| {
        if restitution_in_range(e, hi_open) {
            Ok(())
        } else {
            Err(SceneError::invalid(
                "contact.restitution",
                format!(
                    "must be in (0, 1{} (got {e})",
                    if hi_open { ")" } else { "]" }
                ),
            ))
        }
    };
    match *law {
        LawSpec::Hertz => Ok(()),
        LawSpec::HuntCrossley { restitution }
        | LawSpec::LankaraniNikravesh { restitution }
        | LawSpec::Flores { restitution }
        | LawSpec::Gonthier { restitution }
        | LawSpec::Tsuji { restitution } => e_in(restitution, false),
        LawSpec::Adams { c_max_n_s_m, d_m } => {
            if !(c_max_n_s_m.is_finite() && c_max_n_s_m >= 0.0) {
                return Err(SceneError::invalid(
                    "contact.c_max_n_s_m",
                    format!("must be finite and >= 0 (got {c_max_n_s_m})"),
                ));
            }
            positive("contact.d_m", d_m)
        }
        LawSpec::AdamsRestitution { restitution, d_m } => {
            e_in(restitution, true)?;
            positive("contact.d_m", d_m)
        }
        LawSpec::Thornton { .. } => Err(SceneError::invalid(
            "contact.law",
            "thornton is not a [contact] law: a class that states yield_pressure_pa yields",
        )),
    }
}

// ---------------------------------------------------------------------------------------------
// Sensor chain
// ---------------------------------------------------------------------------------------------

/// The accelerometer's own resonance: a second-order low-pass
/// `H(s) = w^2 / (s^2 + 2 zeta w s + w^2)`, `w = 2 pi f_n`, unit gain at DC, `|H| = 1/(2 zeta)`
/// at `f_n`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Resonance {
    /// Natural frequency `f_n` in Hz.
    pub frequency_hz: f64,
    /// Damping ratio `zeta` (dimensionless, `> 0`).
    pub damping_ratio: f64,
}

/// One beam mode: a base-excited mass-spring-damper riding on the rigid beam. With `a` the
/// rigid acceleration `F / M`, its coordinate obeys `q'' + 2 zeta w q' + w^2 q = a`
/// (`w = 2 pi f_n`) and it adds `gain q''` to the beam's acceleration: the modal term
/// `gain s^2 / (s^2 + 2 zeta w s + w^2)` of a free-free structure's accelerance
/// (`gain = M phi^2 / m_mode`). It carries no net impulse (zero at DC) and, for a pulse much
/// shorter than its period, adds `gain F / M` to the peak.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamMode {
    /// Natural frequency `f_n` in Hz.
    pub frequency_hz: f64,
    /// Damping ratio `zeta` (dimensionless, `> 0`).
    pub damping_ratio: f64,
    /// Dimensionless weight of the mode's acceleration in the sensor's signal.
    pub gain: f64,
}

/// How well the kernel knows the chain (`[sensor] chain_tolerance`): the largest relative error
/// of every stage's frequency, damping ratio and beam mode gain, each in `[0, 0.5)`. The kernel
/// widens a pulse's noise by the bias this can leave; unset: the kernel's
/// `ChainTolerance::IDENTIFIED` (2 %, 30 %, 20 %).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChainToleranceSpec {
    /// Relative error of every frequency.
    pub frequency: f64,
    /// Relative error of every damping ratio.
    pub damping: f64,
    /// Relative error of every beam mode's gain.
    pub gain: f64,
}

/// How well the kernel knows the accelerometer's band apart from the beam
/// (`[sensor] accelerometer_tolerance`): the largest relative error of its frequency and
/// damping ratio, each in `[0, 0.5)`. Unset: the chain's `chain_tolerance` holds for it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AccelerometerToleranceSpec {
    /// Relative error of its frequency.
    pub frequency: f64,
    /// Relative error of its damping ratio.
    pub damping: f64,
}

/// The sensor chain (`[sensor]`): contact force -> beam -> accelerometer -> sampling -> noise
/// -> offset and drift -> ADC (see `sim::sensor`, the layer above).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// Sample rate `f_s` in Hz.
    pub sample_rate_hz: f64,
    /// Effective (rigid) mass `M` of the tail beam in kg: `a = F / M`.
    pub effective_mass_kg: f64,
    /// Accelerometer and ADC sensitivity `S` in counts per m/s^2.
    pub counts_per_m_s2: f64,
    /// RMS of the additive white Gaussian noise in counts (`>= 0`).
    pub noise_rms_counts: f64,
    /// ADC resolution in bits, 2 to 16: codes `-2^(b-1) ..= 2^(b-1) - 1`.
    pub adc_bits: u8,
    /// Constant offset added before quantisation, in counts.
    #[serde(default)]
    pub dc_offset_counts: f64,
    /// Linear drift added before quantisation, in counts per s (of stream time).
    #[serde(default)]
    pub dc_drift_counts_per_s: f64,
    /// Oversampling factor of the fine time grid the linear stages run on (1 to 1024).
    #[serde(default = "default_oversample")]
    pub oversample: u32,
    /// The accelerometer's resonance, if modelled.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accelerometer: Option<Resonance>,
    /// Beam modes, if modelled.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub beam_modes: Vec<BeamMode>,
    /// How well the kernel knows the accelerometer and the beam modes (unset: 2 %, 30 %, 20 %).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chain_tolerance: Option<ChainToleranceSpec>,
    /// How well the kernel knows the accelerometer apart from the modes (unset: as the chain).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accelerometer_tolerance: Option<AccelerometerToleranceSpec>,
}

fn default_oversample() -> u32 {
    DEFAULT_OVERSAMPLE
}

impl SensorSpec {
    /// A rigid chain (no accelerometer resonance, no modes, no offset or drift).
    pub fn rigid(
        sample_rate_hz: f64,
        effective_mass_kg: f64,
        counts_per_m_s2: f64,
        noise_rms_counts: f64,
        adc_bits: u8,
    ) -> Self {
        Self {
            sample_rate_hz,
            effective_mass_kg,
            counts_per_m_s2,
            noise_rms_counts,
            adc_bits,
            dc_offset_counts: 0.0,
            dc_drift_counts_per_s: 0.0,
            oversample: DEFAULT_OVERSAMPLE,
            accelerometer: None,
            beam_modes: Vec::new(),
            chain_tolerance: None,
            accelerometer_tolerance: None,
        }
    }

    /// `true` when the chain is the pure scale: no accelerometer resonance and no beam mode
    /// (nothing rings, nothing is integrated between samples).
    pub fn is_rigid(&self) -> bool {
        self.accelerometer.is_none() && self.beam_modes.is_empty()
    }

    /// Lowest and highest ADC code, `(-2^(b-1), 2^(b-1) - 1)`.
    pub fn adc_range(&self) -> (i32, i32) {
        let bits = self.adc_bits.clamp(MIN_ADC_BITS, MAX_ADC_BITS);
        let half = 1i32 << (bits - 1);
        (-half, half - 1)
    }

    /// Checks every field (see the field docs for the ranges).
    pub fn validate(&self) -> Result<(), SceneError> {
        positive("sensor.sample_rate_hz", self.sample_rate_hz)?;
        positive("sensor.effective_mass_kg", self.effective_mass_kg)?;
        positive("sensor.counts_per_m_s2", self.counts_per_m_s2)?;
        if !(self.noise_rms_counts.is_finite() && self.noise_rms_counts >= 0.0) {
            return Err(SceneError::invalid(
                "sensor.noise_rms_counts",
                format!("must be finite and >= 0 (got {})", self.noise_rms_counts),
            ));
        }
        if !(MIN_ADC_BITS..=MAX_ADC_BITS).contains(&self.adc_bits) {
            return Err(SceneError::invalid(
                "sensor.adc_bits",
                format!(
                    "must be {MIN_ADC_BITS} to {MAX_ADC_BITS} (got {})",
                    self.adc_bits
                ),
            ));
        }
        finite("sensor.dc_offset_counts", self.dc_offset_counts)?;
        finite("sensor.dc_drift_counts_per_s", self.dc_drift_counts_per_s)?;
        if !(1..=MAX_OVERSAMPLE).contains(&self.oversample) {
            return Err(SceneError::invalid(
                "sensor.oversample",
                format!("must be 1 to {MAX_OVERSAMPLE} (got {})", self.oversample),
            ));
        }
        if let Some(r) = &self.accelerometer {
            positive("sensor.accelerometer.frequency_hz", r.frequency_hz)?;
            positive("sensor.accelerometer.damping_ratio", r.damping_ratio)?;
        }
        for (i, m) in self.beam_modes.iter().enumerate() {
            positive(
                &format!("sensor.beam_modes[{i}].frequency_hz"),
                m.frequency_hz,
            )?;
            positive(
                &format!("sensor.beam_modes[{i}].damping_ratio"),
                m.damping_ratio,
            )?;
            finite(&format!("sensor.beam_modes[{i}].gain"), m.gain)?;
        }
        let mut tolerances = Vec::new();
        if let Some(t) = &self.chain_tolerance {
            tolerances.extend([
                ("sensor.chain_tolerance.frequency", t.frequency),
                ("sensor.chain_tolerance.damping", t.damping),
                ("sensor.chain_tolerance.gain", t.gain),
            ]);
        }
        if let Some(t) = &self.accelerometer_tolerance {
            if self.accelerometer.is_none() {
                return Err(SceneError::invalid(
                    "sensor.accelerometer_tolerance",
                    "is set but the chain has no accelerometer stage",
                ));
            }
            tolerances.extend([
                ("sensor.accelerometer_tolerance.frequency", t.frequency),
                ("sensor.accelerometer_tolerance.damping", t.damping),
            ]);
        }
        for (name, v) in tolerances {
            if !(v.is_finite() && (0.0..0.5).contains(&v)) {
                return Err(SceneError::invalid(
                    name,
                    format!("must be a relative error in [0, 0.5) (got {v})"),
                ));
            }
        }
        Ok(())
    }
}

/// Whether `s` is the kernel's default (a `[settings]` table with no key).
fn settings_are_default(s: &Settings) -> bool {
    *s == Settings::default()
}

// ---------------------------------------------------------------------------------------------
// The scene file
// ---------------------------------------------------------------------------------------------

/// A whole scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Name of the scene (free text).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub name: String,
    /// The plate (tail beam) material.
    pub plate: MaterialSpec,
    /// The particle classes, in the order verdicts index them (2 to [`MAX_CLASSES`]).
    pub classes: Vec<ClassSpec>,
    /// The contact law of the simulation (`[contact]`, default undamped Hertz).
    #[serde(default)]
    pub contact: LawSpec,
    /// The sensor chain.
    pub sensor: SensorSpec,
    /// The kernel's settings (`[settings]`, read by the kernel's own serde form,
    /// `coalshock::settings_serde`): a key not given keeps the kernel's default. For a damped
    /// or yielding contact, `bridge::calibrate` fills in the calibration keys the file leaves
    /// at their defaults.
    #[serde(default, skip_serializing_if = "settings_are_default")]
    pub settings: Settings,
}

impl SceneFile {
    /// The paper's scene, as the kernel's `Scene::paper()`: coal (1380 kg/m^3, 5.3 GPa, 0.32)
    /// and sandstone gangue (2487 kg/m^3, 13.5 GPa, 0.123) on carbon steel, `R` in
    /// `[0.015, 0.04]` m (log-uniform), `u` in `[1, 5]` m/s (uniform), equal priors,
    /// undamped Hertz contact; sensor 100 kS/s, 50 kg, 30 counts per m/s^2, 4 counts RMS
    /// noise, 16-bit ADC, no resonance, modes, offset or drift.
    pub fn paper() -> Self {
        Self::paper_with_speed("paper", Range64::new(1.0, 5.0))
    }

    /// [`SceneFile::paper`] with `u` in `[2.5, 3.5]` m/s, as `Scene::paper_narrow()`.
    pub fn paper_narrow() -> Self {
        Self::paper_with_speed("paper_narrow", Range64::new(2.5, 3.5))
    }

    fn paper_with_speed(name: &str, speed: Range64) -> Self {
        let radius = Range64::new(0.015, 0.04);
        Self {
            name: name.to_string(),
            plate: MaterialSpec::Named(MaterialName::CarbonSteel),
            classes: vec![
                ClassSpec::new(
                    "coal",
                    MaterialSpec::Named(MaterialName::Coal),
                    radius,
                    speed,
                ),
                ClassSpec::new(
                    "gangue",
                    MaterialSpec::Named(MaterialName::Sandstone),
                    radius,
                    speed,
                ),
            ],
            contact: LawSpec::Hertz,
            sensor: SensorSpec::rigid(100_000.0, 50.0, 30.0, 4.0, 16),
            settings: Settings::default(),
        }
    }

    /// Parses and checks a scene from TOML text.
    pub fn from_toml_str(text: &str) -> Result<Self, SceneError> {
        let scene: SceneFile = toml::from_str(text).map_err(|e| SceneError::Parse {
            path: PathBuf::from("<string>"),
            message: e.to_string(),
        })?;
        scene.validate()?;
        Ok(scene)
    }

    /// The scene as TOML text (what [`load`] reads back to an equal scene).
    pub fn to_toml_string(&self) -> Result<String, SceneError> {
        toml::to_string(self).map_err(|e| SceneError::Parse {
            path: PathBuf::from("<string>"),
            message: e.to_string(),
        })
    }

    /// Checks every value: materials, ranges, priors, class names (unique, at most
    /// [`MAX_CLASS_NAME_BYTES`] bytes), 2 to [`MAX_CLASSES`] classes, the contact law's
    /// parameters and the sensor chain.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.plate.validate("plate")?;
        if self.classes.len() < 2 || self.classes.len() > MAX_CLASSES {
            return Err(SceneError::invalid(
                "classes",
                format!(
                    "must hold 2 to {MAX_CLASSES} classes (got {})",
                    self.classes.len()
                ),
            ));
        }
        for (i, c) in self.classes.iter().enumerate() {
            c.validate(&format!("classes[{i}]"))
                .and_then(|()| {
                    class_closed_forms_fit(c, &self.plate.material(), &format!("classes[{i}]"))
                })
                .map_err(|e| e.of_class(&c.name))?;
            if self.classes[..i].iter().any(|o| o.name == c.name) {
                return Err(SceneError::invalid(
                    format!("classes[{i}].name"),
                    format!("{:?} is used by an earlier class", c.name),
                ));
            }
        }
        validate_contact(&self.contact)?;
        for i in 0..self.classes.len() {
            self.class_law(i).map_err(|e| {
                SceneError::invalid(format!("classes[{i}].yield_pressure_pa"), e.to_string())
                    .of_class(&self.classes[i].name)
            })?;
        }
        self.sensor.validate()?;
        for (name, v) in [
            ("settings.trigger_sigmas", self.settings.trigger_sigmas),
            ("settings.release_sigmas", self.settings.release_sigmas),
            ("settings.baseline_tau_s", self.settings.baseline_tau_s),
            ("settings.model_sigma", self.settings.model_sigma),
            (
                "settings.confident_error_rate",
                self.settings.confident_error_rate,
            ),
            ("settings.out_sigmas", self.settings.out_sigmas),
        ] {
            finite_f32(name, v)?;
        }
        let v = self.settings.confident_error_rate;
        if !(v > 0.0 && v < 0.5) {
            return Err(SceneError::invalid(
                "settings.confident_error_rate",
                format!(
                    "must be in (0, 0.5), the share of class verdicts allowed to be wrong (got {v})"
                ),
            ));
        }
        Ok(())
    }

    /// The integrator's law for class `class`: the scene's `[contact]` law, or, when the class
    /// states `yield_pressure_pa`, [`LawSpec::Thornton`] with the scene's restitution-law
    /// damping (`None` for `law = "hertz"`). Errors, naming the field, for a yielding class
    /// under a law whose damping is not of the restitution form (Adams, Tsuji).
    pub fn class_law(&self, class: usize) -> Result<LawSpec, SimError> {
        let Some(p_y) = self.classes.get(class).and_then(|c| c.yield_pressure_pa) else {
            return Ok(self.contact);
        };
        let damping = self.contact.restitution_damping();
        if damping.is_none() && self.contact != LawSpec::Hertz {
            return Err(SimError::InvalidParameter {
                name: format!("classes[{class}].yield_pressure_pa"),
                value: p_y,
                requirement: "given with contact law hertz, hunt_crossley, \
                              lankarani_nikravesh, flores or gonthier (a yielding contact \
                              takes only their damping)",
            });
        }
        Ok(LawSpec::Thornton {
            yield_pressure_pa: p_y,
            damping,
        })
    }

    /// Whether any class yields (states `yield_pressure_pa`).
    pub fn yields(&self) -> bool {
        self.classes.iter().any(|c| c.yield_pressure_pa.is_some())
    }

    /// Prior weights normalised to sum 1, in class order.
    pub fn class_probabilities(&self) -> Vec<f64> {
        let total: f64 = self.classes.iter().map(|c| c.prior).sum();
        self.classes.iter().map(|c| c.prior / total).collect()
    }
}

/// Reads, parses and checks a scene file. Errors name the file and the line and column (parse
/// errors) or the field (range errors) that is wrong.
pub fn load(path: impl AsRef<Path>) -> Result<SceneFile, SceneError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|error| SceneError::Read {
        path: path.to_path_buf(),
        error,
    })?;
    let scene: SceneFile = toml::from_str(&text).map_err(|e| SceneError::Parse {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    scene.validate().map_err(|e| e.in_file(path))?;
    Ok(scene)
}

/// `v` finite and `> 0`, and a normal `f32` (the kernel's type).
fn positive(field: &str, v: f64) -> Result<(), SceneError> {
    if !(v.is_finite() && v > 0.0) {
        return Err(SceneError::invalid(
            field,
            format!("must be finite and > 0 (got {v})"),
        ));
    }
    kernel_f32(field, v)
}

/// `v` finite and within the `f32` range (the kernel's type).
fn finite(field: &str, v: f64) -> Result<(), SceneError> {
    if !v.is_finite() {
        return Err(SceneError::invalid(
            field,
            format!("must be finite (got {v})"),
        ));
    }
    kernel_f32(field, v)
}

/// A kernel setting `v`, read as `f32` (a number beyond the `f32` range reads as infinite),
/// finite and within [`KERNEL_RANGE`].
fn finite_f32(field: &str, v: f32) -> Result<(), SceneError> {
    if v.is_infinite() {
        let hi = KERNEL_RANGE.1;
        return Err(SceneError::invalid(
            field,
            format!("must be finite and at most {hi:e} in size (read as the kernel's f32: {v})"),
        ));
    }
    finite(field, f64::from(v))
}

/// Smallest and largest magnitude the kernel carries in its `f32` closed forms, its own bounds
/// (`coalshock::error::REPRESENTABLE`): every positive input and derived quantity outside them
/// is refused there.
pub const KERNEL_RANGE: (f64, f64) = (1e-30, 1e30);

/// `v` (finite) survives the kernel's `f32` arithmetic: `|v| <= ` [`KERNEL_RANGE`]`.1`, and
/// `v` is 0 or `|v| >= ` [`KERNEL_RANGE`]`.0`.
fn kernel_f32(field: &str, v: f64) -> Result<(), SceneError> {
    let (lo, hi) = KERNEL_RANGE;
    if v.abs() > hi {
        return Err(SceneError::invalid(
            field,
            format!(
                "= {v:e} overflows the kernel's f32 arithmetic (it refuses values above {hi:e})"
            ),
        ));
    }
    if v != 0.0 && v.abs() < lo {
        return Err(SceneError::invalid(
            field,
            format!(
                "= {v:e} underflows the kernel's f32 arithmetic (it refuses values below {lo:e})"
            ),
        ));
    }
    Ok(())
}

/// The Hertz closed forms of class `c` on `plate` at the corners of its radius and speed
/// ranges, each within [`KERNEL_RANGE`] (the kernel computes them in `f32`): sphere mass,
/// stiffness, `5 pi rho / (4 E*)`, `delta_max`, `delta_max^1.5`, `F_max`, `t_c`, impulse.
fn class_closed_forms_fit(
    c: &ClassSpec,
    plate: &Material64,
    field: &str,
) -> Result<(), SceneError> {
    let m = c.material.material();
    let u = c.speed_range_m_s();
    let e_star = crate::physics::hertz64::effective_modulus_pa(&m, plate);
    for r in [c.radius_m.min, c.radius_m.max] {
        for u in [u.min, u.max] {
            let Ok(hz) = crate::physics::hertz64::HertzImpact64::new(&m, plate, r, u) else {
                continue;
            };
            let d = hz.delta_max_m;
            for (what, v) in [
                ("sphere mass (kg)", hz.mass_kg),
                ("Hertz stiffness (N/m^1.5)", hz.stiffness),
                (
                    "5 pi rho / (4 E*) (s^2/m^2)",
                    1.25 * std::f64::consts::PI * m.density_kg_m3 / e_star,
                ),
                ("delta_max (m)", d),
                ("delta_max^1.5", d * d.sqrt()),
                ("peak force (N)", hz.peak_force_n),
                ("contact duration (s)", hz.duration_s),
                ("impulse (N s)", hz.impulse_n_s),
            ] {
                if !(v.is_finite() && v >= KERNEL_RANGE.0 && v <= KERNEL_RANGE.1) {
                    return Err(SceneError::invalid(
                        format!("{field}.radius_m and speed"),
                        format!(
                            "give a {what} of {v:e} at R = {r:e} m, u = {u} m/s: outside \
                             [{:e}, {:e}], the range the kernel's f32 closed forms carry",
                            KERNEL_RANGE.0, KERNEL_RANGE.1
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::laws::RestitutionModel;

    #[test]
    fn paper_round_trips_through_toml() {
        let p = SceneFile::paper();
        let text = p.to_toml_string().expect("serialize");
        assert_eq!(SceneFile::from_toml_str(&text).expect("parse"), p);
    }

    #[test]
    fn errors_name_the_field() {
        let mut s = SceneFile::paper();
        s.classes[1].radius_m = Range64::new(0.04, 0.015);
        let e = s.validate().expect_err("inverted").to_string();
        assert!(e.contains("classes[1].radius_m"), "{e}");
        let text = SceneFile::paper()
            .to_toml_string()
            .expect("serialize")
            .replace("\"sandstone\"", "\"sandston\"");
        let e = SceneFile::from_toml_str(&text)
            .expect_err("unknown")
            .to_string();
        assert!(e.contains("unknown material") && e.contains("line"), "{e}");
    }

    /// A class may state its limiting contact pressure; without it the scene's law is used
    /// unchanged, with it Thornton's law with the scene's restitution-law damping. A law whose
    /// damping Thornton's law cannot take, or a bad value, is refused naming the field.
    #[test]
    fn yield_pressure_is_optional_and_names_its_field() {
        let paper = SceneFile::paper();
        assert!(!paper.yields());
        assert_eq!(paper.class_law(1).expect("law"), LawSpec::Hertz);
        let mut s = paper.clone();
        s.classes[0].yield_pressure_pa = Some(3e7);
        let text = s.to_toml_string().expect("serialize");
        assert!(text.contains("yield_pressure_pa"), "{text}");
        assert!(!paper.to_toml_string().expect("serialize").contains("yield"));
        assert_eq!(SceneFile::from_toml_str(&text).expect("parse"), s);
        s.contact = LawSpec::Flores { restitution: 0.5 };
        assert_eq!(
            s.class_law(0).expect("law"),
            LawSpec::Thornton {
                yield_pressure_pa: 3e7,
                damping: Some((RestitutionModel::Flores, 0.5)),
            }
        );
        assert_eq!(
            s.class_law(1).expect("law"),
            LawSpec::Flores { restitution: 0.5 }
        );
        s.contact = LawSpec::Tsuji { restitution: 0.5 };
        let e = s.validate().expect_err("tsuji").to_string();
        assert!(e.contains("classes[0].yield_pressure_pa"), "{e}");
        s.contact = LawSpec::Hertz;
        s.classes[0].yield_pressure_pa = Some(-1.0);
        let e = s.validate().expect_err("negative").to_string();
        assert!(e.contains("classes[0].yield_pressure_pa"), "{e}");
    }

    #[test]
    fn custom_material_and_drop_height_parse() {
        let text = r#"
plate = { density_kg_m3 = 7850.0, modulus_pa = 2.06e11, poisson = 0.28 }
[[classes]]
name = "coal"
material = "coal"
radius_m = [0.01, 0.02]
drop_height_m = [0.5, 1.0]
[[classes]]
name = "rock"
material = { density_kg_m3 = 2525.0, modulus_pa = 35e9, poisson = 0.25 }
radius_m = [0.01, 0.02]
speed_m_s = [1.0, 2.0]
prior = 0.25
[contact]
law = "flores"
restitution = 0.5
[sensor]
sample_rate_hz = 50000.0
effective_mass_kg = 20.0
counts_per_m_s2 = 10.0
noise_rms_counts = 2.0
adc_bits = 12
accelerometer = { frequency_hz = 30000.0, damping_ratio = 0.05 }
[[sensor.beam_modes]]
frequency_hz = 200.0
damping_ratio = 0.02
gain = 0.1
"#;
        let s = SceneFile::from_toml_str(text).expect("parse");
        assert_eq!(s.plate.material(), Material64::CARBON_STEEL);
        assert!(matches!(s.classes[0].speed, SpeedSpec::DropHeight(_)));
        assert_eq!(s.classes[1].prior, 0.25);
        assert_eq!(s.contact, LawSpec::Flores { restitution: 0.5 });
        assert_eq!(s.sensor.beam_modes.len(), 1);
        assert_eq!(s.sensor.adc_range(), (-2048, 2047));
        let u = s.classes[0].speed_range_m_s();
        assert!((u.min - (2.0f64 * 9.80665 * 0.5).sqrt()).abs() < 1e-12);
    }

    /// The `[settings]` table: every key lands in its kernel field (the values and fields
    /// written out here, not taken from the reader), a key not given keeps the kernel's
    /// default, a float is rounded as `f64 as f32`, and an unknown key is refused by name.
    #[test]
    fn settings_keys_land_in_the_kernel_fields() {
        let paper = SceneFile::paper().to_toml_string().expect("serialize");
        assert!(!paper.contains("[settings]"), "defaults are not written");
        let table = "[settings]\ntrigger_sigmas = 7\nrelease_sigmas = 2.5\nhold_samples = 3\n\
                     baseline_tau_s = 0.05\nstuck_samples = 0\nmodel_sigma = 0.1\n\
                     confident_error_rate = 0.1\nout_sigmas = 5.0\nseparability_grid = 16\n\
                     shape_tolerance = 0.2\nforce_ratio = 0.9\nduration_ratio = 1.1\n\
                     shape_ratio = 0.95\nspike_fraction = 0.6\nskewness = 0.3\n\
                     skew_tolerance = 0.07\n";
        let s = SceneFile::from_toml_str(&format!("{paper}{table}")).expect("parse");
        let k = s.settings;
        assert_eq!((k.trigger_sigmas, k.release_sigmas), (7.0, 2.5));
        assert_eq!(
            (k.hold_samples, k.stuck_samples, k.separability_grid),
            (3, 0, 16)
        );
        assert_eq!(k.baseline_tau_s, 0.05f64 as f32);
        assert_eq!(
            (k.model_sigma, k.confident_error_rate),
            (0.1f64 as f32, 0.1f64 as f32)
        );
        assert_eq!((k.out_sigmas, k.shape_tolerance), (5.0, 0.2f64 as f32));
        assert_eq!(k.contact.force_ratio, 0.9f64 as f32);
        assert_eq!(k.contact.duration_ratio, 1.1f64 as f32);
        assert_eq!(k.contact.shape_ratio, 0.95f64 as f32);
        assert_eq!(k.contact.skewness, 0.3f64 as f32);
        assert_eq!(
            (k.spike_fraction, k.skew_tolerance),
            (0.6f64 as f32, 0.07f64 as f32)
        );
        assert_eq!(
            SceneFile::from_toml_str(&s.to_toml_string().expect("write")).expect("read"),
            s
        );
        let one = SceneFile::from_toml_str(&format!("{paper}[settings]\nout_sigmas = 3.5\n"))
            .expect("parse");
        let expected = Settings {
            out_sigmas: 3.5,
            ..Settings::default()
        };
        assert_eq!(one.settings, expected);
        let e = SceneFile::from_toml_str(&format!("{paper}[settings]\ntrigger_sigma = 6.0\n"))
            .expect_err("unknown key")
            .to_string();
        assert!(
            e.contains("unknown field `trigger_sigma`") && e.contains("line"),
            "{e}"
        );
        let e = SceneFile::from_toml_str(&format!("{paper}[settings]\nout_sigmas = 1e300\n"))
            .expect_err("infinite")
            .to_string();
        assert!(e.contains("settings.out_sigmas"), "{e}");
    }
}
