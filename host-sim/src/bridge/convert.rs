//! The one place where host values (`f64`, [`crate::scene`], and the calibration already
//! computed) become the kernel's `f32` types and back: pure mappings, no integrator run (a
//! scene file's whole kernel scene, calibration first, is [`crate::bridge::kernel_scene`]).
//! Every `f64 -> f32` cast rounds to nearest; the kernel then checks the values (a value
//! beyond the f32 range becomes infinite and the kernel refuses it by name).

use coalshock::PulseShape;
use coalshock::math::Backend;
use coalshock::ratio_map::RatioMap;
use coalshock::sampled_phase::SampledPhase;
use coalshock::scene::SAMPLED_POINTS;

use crate::bridge::calibrate::{Calibration64, Sampled64};
use crate::bridge::ratio_table::RatioTable64;
use coalshock::{
    Accelerometer, BeamMode, ChainDynamics, ChainTolerance, ContactCalibration, Material,
    Measurement, ParticleClass, Range, SampledCalibration, Scene, SensorChain, Settings, Speed,
};

use crate::physics::hertz64::Material64;
use crate::scene::{ClassSpec, Range64, SensorSpec, SpeedSpec};

/// Why a scene file could not become a kernel scene.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConvertError {
    /// The kernel refused the scene (its message names the parameter).
    #[error("the kernel refused the scene: {0}")]
    Kernel(coalshock::Error),
    /// The damped contact could not be integrated for its calibration.
    #[error("calibrating the contact law: {0}")]
    Calibration(crate::physics::integrate::SimError),
    /// More classes than the kernel scene's capacity `N`.
    #[error("the scene has {classes} classes; this kernel scene holds at most {capacity}")]
    TooManyClasses {
        /// Classes in the file.
        classes: usize,
        /// Capacity of the kernel scene type.
        capacity: usize,
    },
}

/// `Material64` (f64) -> kernel `Material` (f32): density kg/m^3, modulus Pa, Poisson's ratio.
pub fn material_to_kernel(m: &Material64) -> Material {
    Material::new(
        m.density_kg_m3 as f32,
        m.modulus_pa as f32,
        m.poisson as f32,
    )
}

/// Kernel `Material` (f32) -> `Material64` (f64), exact.
pub fn material_from_kernel(m: &Material) -> Material64 {
    Material64 {
        density_kg_m3: m.density_kg_m3 as f64,
        modulus_pa: m.modulus_pa as f64,
        poisson: m.poisson as f64,
    }
}

/// `[min, max]` (f64) -> kernel `Range` (f32), same unit.
pub fn range_to_kernel(r: &Range64) -> Range {
    Range::new(r.min as f32, r.max as f32)
}

/// Kernel `Range` (f32) -> [`Range64`], exact.
pub fn range_from_kernel(r: &Range) -> Range64 {
    Range64::new(r.min as f64, r.max as f64)
}

/// A class of a scene file -> kernel `ParticleClass` (name, material, radius range in m,
/// speed in m/s or drop height in m, prior weight).
pub fn class_to_kernel(c: &ClassSpec) -> ParticleClass {
    let speed = match c.speed {
        SpeedSpec::Uniform(s) => Speed::Uniform(range_to_kernel(&s)),
        SpeedSpec::DropHeight(h) => Speed::DropHeight(range_to_kernel(&h)),
    };
    let mut k = ParticleClass::new(
        &c.name,
        material_to_kernel(&c.material.material()),
        range_to_kernel(&c.radius_m),
        speed,
    );
    k.prior = c.prior as f32;
    k.yield_pressure_pa = c.yield_pressure_pa.map(|p| p as f32);
    k
}

/// The kernel ratio map of each class (`Scene::with_ratio_maps`) from its f64 ratio table
/// ([`crate::bridge::ratio_table`]), `None` for none (an empty list: no class has a table); a
/// table the kernel refuses is [`ConvertError::Kernel`].
pub fn ratio_maps_to_kernel(
    tables: &[RatioTable64],
) -> Result<Vec<Option<RatioMap>>, ConvertError> {
    tables
        .iter()
        .map(|t| Ok(Some(t.to_kernel().map_err(ConvertError::Kernel)?)))
        .collect()
}

/// The sensor chain the kernel inverts: `SensorChain::from_plate(f_s, M, S, noise, bits)`,
/// i.e. `force_per_count_n = M / S` (N per count) and the ADC range of `bits`, with the beam
/// modes and the accelerometer resonance as the kernel's `ChainDynamics` (offset and drift are
/// the baseline's to follow), its equaliser designed with the default backend. More modes
/// than the kernel carries is [`ConvertError::Kernel`].
pub fn sensor_to_kernel(s: &SensorSpec) -> Result<SensorChain, ConvertError> {
    sensor_to_kernel_in::<coalshock::math::DefaultBackend>(s)
}

/// [`sensor_to_kernel`] with math backend `M` for the equaliser's design. A rigid chain (no
/// mode, no accelerometer) is left as `SensorChain::from_plate` makes it, undesigned, as the
/// kernel's presets have it (a firmware with a rigid chain links no design code).
pub fn sensor_to_kernel_in<M: Backend>(s: &SensorSpec) -> Result<SensorChain, ConvertError> {
    let chain = SensorChain::from_plate(
        s.sample_rate_hz as f32,
        s.effective_mass_kg as f32,
        s.counts_per_m_s2 as f32,
        s.noise_rms_counts as f32,
        s.adc_bits,
    );
    let dynamics = dynamics_to_kernel(s)?;
    if dynamics.is_rigid() {
        return Ok(chain);
    }
    chain
        .with_dynamics_in::<M>(dynamics)
        .map_err(ConvertError::Kernel)
}

/// The beam modes and accelerometer resonance of a sensor as the kernel's `ChainDynamics`
/// (not designed). More modes than the kernel carries is [`ConvertError::Kernel`].
pub fn dynamics_to_kernel(s: &SensorSpec) -> Result<ChainDynamics, ConvertError> {
    let mut dynamics = ChainDynamics::RIGID;
    for m in &s.beam_modes {
        dynamics = dynamics
            .with_mode(BeamMode {
                frequency_hz: m.frequency_hz as f32,
                damping_ratio: m.damping_ratio as f32,
                gain: m.gain as f32,
            })
            .map_err(ConvertError::Kernel)?;
    }
    if let Some(a) = &s.accelerometer {
        dynamics = dynamics.with_accelerometer(Accelerometer {
            frequency_hz: a.frequency_hz as f32,
            damping_ratio: a.damping_ratio as f32,
        });
    }
    if let Some(t) = &s.chain_tolerance {
        dynamics = dynamics
            .with_tolerance(ChainTolerance {
                frequency: t.frequency as f32,
                damping: t.damping as f32,
                gain: t.gain as f32,
            })
            .map_err(ConvertError::Kernel)?;
    }
    if let Some(t) = &s.accelerometer_tolerance {
        dynamics = dynamics
            .with_accelerometer_tolerance(ChainTolerance {
                frequency: t.frequency as f32,
                damping: t.damping as f32,
                gain: 0.0,
            })
            .map_err(ConvertError::Kernel)?;
    }
    Ok(dynamics)
}

/// The sampling correction in the kernel's f32.
pub fn sampled_to_kernel(t: &Sampled64) -> SampledCalibration {
    let f = |v: &[f64; SAMPLED_POINTS]| v.map(|x| x as f32);
    SampledCalibration {
        ln_force: f(&t.ln_force),
        ln_duration: f(&t.ln_duration),
        sigma_ln_force: f(&t.sigma_ln_force),
        sigma_ln_duration: f(&t.sigma_ln_duration),
    }
}

/// The kernel settings of a scene file from its `[settings]` (`file`) and the f64 values its
/// calibration computed ([`crate::bridge::kernel_scene::SceneCalibration`]): `contact`, the
/// contact calibration of a damped law or a yielding class (`None`: the Hertz law, no yield),
/// `yields` whether a class yields, and `table_residual` the residual of the classes' ratio
/// tables (`None`: no tables). Each ratio of the contact calibration is taken unless the file
/// states one other than the kernel's default; a scene that yields also takes
/// `flat_top_ratio`. A law whose ratios vary between impacts widens the tolerances to cover
/// them: `shape_tolerance >= 1.5 x` the spread of `ln q` (between impacts, plus that of
/// sampling at the scene's rate), `model_sigma >= ` the larger spread of `ln F` and `ln t`,
/// `spike_fraction >= 1.25 x` the sharpest sampled bend, `skew_tolerance >= 1.5 x` the spread
/// of the skewness between impacts, and at least what the scene's pulses sampled at its rate
/// need ([`crate::bridge::skew_tolerance`]) (unless the file states them other than the
/// default: a file value equal to the kernel's default is not told from a missing one). A
/// scene whose classes carry ratio tables leaves the force and duration ratios to them (1
/// here), and its `model_sigma` is at least what the tables leave against direct integration
/// (`table_residual`). Every value is rounded to `f32` here.
pub fn settings_to_kernel(
    file: &Settings,
    contact: Option<&Calibration64>,
    yields: bool,
    table_residual: Option<f64>,
) -> Settings {
    let mut s = *file;
    let d = Settings::default();
    let cal = contact.copied();
    // The file's value where it states one (other than the default), else the computed one.
    let pick = |file: f32, default: f32, computed: Option<f64>| match computed {
        Some(c) if file == default => c as f32,
        _ => file,
    };
    // A scene that yields allows its broader tops a longer run of equal samples before
    // calling one clipped.
    if let Some(c) = cal.filter(|_| yields) {
        s.flat_top_ratio = c.flat_top_ratio.max(1.0) as f32;
    }
    let unless_tables = |v: f64| if table_residual.is_some() { 1.0 } else { v };
    let (o, dc) = (file.contact, d.contact);
    s.contact = ContactCalibration {
        force_ratio: pick(
            o.force_ratio,
            dc.force_ratio,
            cal.map(|c| unless_tables(c.ratios.force)),
        ),
        duration_ratio: pick(
            o.duration_ratio,
            dc.duration_ratio,
            cal.map(|c| unless_tables(c.ratios.duration)),
        ),
        shape_ratio: pick(o.shape_ratio, dc.shape_ratio, cal.map(|c| c.ratios.shape)),
        skewness: pick(o.skewness, dc.skewness, cal.map(|c| c.skewness)),
        sampled: cal
            .and_then(|c| c.sampled)
            .map_or(SampledCalibration::NONE, |t| sampled_to_kernel(&t)),
    };
    s.sampled_phase = cal
        .and_then(|c| c.phase)
        .map_or(SampledPhase::NONE, |t| t.to_kernel());
    s.pulse_shape = cal
        .and_then(|c| c.pulse_shape)
        .map_or(PulseShape::NONE, |(shape, _)| shape);
    if let Some(c) = cal {
        if s.shape_tolerance == d.shape_tolerance {
            let spread = c.spread_ln.shape + c.sampled_shape_spread;
            s.shape_tolerance = s.shape_tolerance.max((1.5 * spread) as f32);
        }
        if s.model_sigma == d.model_sigma {
            let spread = table_residual.unwrap_or(c.spread_ln.force.max(c.spread_ln.duration));
            s.model_sigma = s.model_sigma.max(spread as f32);
        }
        if s.skew_tolerance == d.skew_tolerance {
            let needed = (1.5 * c.skewness_spread).max(c.skewness_sampled_tolerance);
            s.skew_tolerance = s.skew_tolerance.max(needed as f32);
        }
        if s.spike_fraction == d.spike_fraction {
            s.spike_fraction = s.spike_fraction.max((1.25 * c.sharpest_bend) as f32);
        }
    }
    s
}

/// A kernel measurement in `f64`: peak force (N), duration (s) and their log-unit standard
/// deviations.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Measurement64 {
    /// Peak contact force in N.
    pub peak_force_n: f64,
    /// Contact duration in s.
    pub duration_s: f64,
    /// Standard deviation of `ln F_max` (dimensionless).
    pub sigma_ln_force: f64,
    /// Standard deviation of `ln t_c` (dimensionless).
    pub sigma_ln_duration: f64,
}

/// Kernel `Measurement` (f32) -> [`Measurement64`], exact.
pub fn measurement_from_kernel(m: &Measurement) -> Measurement64 {
    Measurement64 {
        peak_force_n: m.peak_force_n as f64,
        duration_s: m.duration_s as f64,
        sigma_ln_force: m.sigma_ln_force as f64,
        sigma_ln_duration: m.sigma_ln_duration as f64,
    }
}

/// The kernel's closed-form impact (backend `M`, f32 arithmetic) in `f64`: maximum
/// penetration (m), peak force (N), contact duration (s) and impulse (N s).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct KernelImpact64 {
    /// `delta_max` in m.
    pub delta_max_m: f64,
    /// `F_max` in N.
    pub peak_force_n: f64,
    /// `t_c` in s.
    pub duration_s: f64,
    /// `2 m u` in N s.
    pub impulse_n_s: f64,
}

/// The kernel's `hertz::impact_in::<M>` for a sphere of `sphere` material, radius `radius_m`
/// (m) and speed `speed_m_s` (m/s) on a `plate`: every input rounded to f32 here, the
/// effective modulus from the kernel's `material::effective_modulus_pa`, the result widened
/// exactly to f64. Errors when the kernel refuses a value.
pub fn kernel_impact_in<M: Backend>(
    sphere: &Material64,
    plate: &Material64,
    radius_m: f64,
    speed_m_s: f64,
) -> Result<KernelImpact64, ConvertError> {
    let s = material_to_kernel(sphere);
    let e = coalshock::material::effective_modulus_pa(&s, &material_to_kernel(plate))
        .map_err(ConvertError::Kernel)?;
    let i = coalshock::hertz::impact_in::<M>(e, s.density_kg_m3, radius_m as f32, speed_m_s as f32)
        .map_err(ConvertError::Kernel)?;
    Ok(KernelImpact64 {
        delta_max_m: i.delta_max_m as f64,
        peak_force_n: i.peak_force_n as f64,
        duration_s: i.duration_s as f64,
        impulse_n_s: i.impulse_n_s as f64,
    })
}

/// The kernel's build-time separability of a scene in `f64`: `(overlap_share, bayes_error)`,
/// both prior-weighted shares in `[0, 1]` (see `coalshock::scene::Separability`), exact.
pub fn separability_from_kernel(s: &coalshock::scene::Separability) -> (f64, f64) {
    (s.overlap_share as f64, s.bayes_error as f64)
}

/// The shortest and longest Hertz contact duration of a kernel scene's classes, in s, exact.
pub fn duration_bounds_from_kernel<const N: usize, M: Backend>(scene: &Scene<N, M>) -> (f64, f64) {
    let (a, b) = scene.duration_bounds_s();
    (a as f64, b as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn materials_round_trip_and_named_table_matches_kernel() {
        use crate::scene::MaterialName;
        let pairs = [
            (MaterialName::Coal, Material::COAL),
            (MaterialName::Sandstone, Material::SANDSTONE),
            (MaterialName::CarbonSteel, Material::CARBON_STEEL),
            (MaterialName::RoofSandstone, Material::ROOF_SANDSTONE),
            (MaterialName::SandyMudstone, Material::SANDY_MUDSTONE),
        ];
        for (name, kernel) in pairs {
            assert_eq!(material_to_kernel(&name.material()), kernel, "{name:?}");
            assert_eq!(
                material_to_kernel(&material_from_kernel(&kernel)),
                kernel,
                "{name:?}"
            );
        }
    }
}
