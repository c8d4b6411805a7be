//! The one place where host values (`f64`, [`crate::scene`]) become the kernel's `f32` types
//! and back. Every `f64 -> f32` cast rounds to nearest; the kernel then checks the values
//! (a value beyond the f32 range becomes infinite and the kernel refuses it by name).

use coalshock::math::Backend;
use coalshock::ratio_map::RatioMap;
use coalshock::scene::{DEFAULT_CLASSES, SAMPLED_POINTS};

use crate::bridge::calibrate::Sampled64;
use coalshock::{
    Accelerometer, BeamMode, ChainDynamics, ChainTolerance, ContactCalibration, Material,
    Measurement, ParticleClass, Range, SampledCalibration, Scene, SensorChain, Settings, Speed,
};

use crate::physics::hertz64::Material64;
use crate::scene::{ClassSpec, Range64, SceneFile, SensorSpec, SettingsOverrides, SpeedSpec};

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

/// The kernel ratio map of each class of a scene file (`Scene::with_ratio_maps`): its table
/// when the scene's law needs one ([`crate::bridge::ratio_table`]: a fixed-coefficient Adams
/// law), else none (an empty list); a table that cannot be integrated or that the kernel
/// refuses is an error.
pub fn ratio_maps_to_kernel(scene: &SceneFile) -> Result<Vec<Option<RatioMap>>, ConvertError> {
    if !crate::bridge::ratio_table::needs_tables(scene) {
        return Ok(Vec::new());
    }
    (0..scene.classes.len())
        .map(|i| {
            let table = crate::bridge::ratio_table::class_table(scene, i)
                .map_err(ConvertError::Calibration)?;
            Ok(Some(table.to_kernel().map_err(ConvertError::Kernel)?))
        })
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
    Ok(dynamics)
}

/// The kernel's default `Settings` with the file's overrides applied.
pub fn settings_to_kernel(o: &SettingsOverrides) -> Settings {
    let mut s = Settings::default();
    let set = |dst: &mut f32, v: Option<f64>| {
        if let Some(v) = v {
            *dst = v as f32;
        }
    };
    set(&mut s.trigger_sigmas, o.trigger_sigmas);
    set(&mut s.release_sigmas, o.release_sigmas);
    set(&mut s.baseline_tau_s, o.baseline_tau_s);
    set(&mut s.model_sigma, o.model_sigma);
    set(&mut s.confident_error_rate, o.confident_error_rate);
    set(&mut s.out_sigmas, o.out_sigmas);
    set(&mut s.shape_tolerance, o.shape_tolerance);
    set(&mut s.spike_fraction, o.spike_fraction);
    let ratio = |v: Option<f64>| v.unwrap_or(1.0) as f32;
    s.contact = ContactCalibration {
        force_ratio: ratio(o.force_ratio),
        duration_ratio: ratio(o.duration_ratio),
        shape_ratio: ratio(o.shape_ratio),
        skewness: o.skewness.unwrap_or(0.0) as f32,
        sampled: SampledCalibration::NONE,
    };
    set(&mut s.skew_tolerance, o.skew_tolerance);
    if let Some(v) = o.hold_samples {
        s.hold_samples = v;
    }
    if let Some(v) = o.stuck_samples {
        s.stuck_samples = v;
    }
    if let Some(v) = o.separability_grid {
        s.separability_grid = v;
    }
    s
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

/// A scene file -> the kernel scene with the default capacity and backend, via `Scene::new`.
pub fn scene_to_kernel(scene: &SceneFile) -> Result<Scene, ConvertError> {
    scene_to_kernel_in::<DEFAULT_CLASSES, coalshock::math::DefaultBackend>(scene)
}

/// [`scene_to_kernel`] with capacity `N` and math backend `M`.
pub fn scene_to_kernel_in<const N: usize, M: Backend>(
    scene: &SceneFile,
) -> Result<Scene<N, M>, ConvertError> {
    // Checked before the parts, whose calibration may run the integrator.
    within_capacity::<N>(scene.classes.len())?;
    KernelParts::of(scene)?.scene_in::<N, M>(&scene.sensor)
}

/// `Err(TooManyClasses)` unless `classes <= N`.
fn within_capacity<const N: usize>(classes: usize) -> Result<(), ConvertError> {
    if classes > N {
        return Err(ConvertError::TooManyClasses {
            classes,
            capacity: N,
        });
    }
    Ok(())
}

/// What a kernel scene takes from its scene file besides the sensor chain: the plate, the
/// classes, their ratio maps and the calibrated settings. Building them may run the
/// integrator ([`calibrated_settings`], [`ratio_maps_to_kernel`]); a study that gives the
/// kernel several chains for one scene builds them once.
#[derive(Debug, Clone)]
pub struct KernelParts {
    plate: Material,
    classes: Vec<ParticleClass>,
    ratio_maps: Vec<Option<RatioMap>>,
    settings: Settings,
}

impl KernelParts {
    /// The parts of `scene`.
    pub fn of(scene: &SceneFile) -> Result<Self, ConvertError> {
        Ok(Self {
            plate: material_to_kernel(&scene.plate.material()),
            classes: scene.classes.iter().map(class_to_kernel).collect(),
            ratio_maps: ratio_maps_to_kernel(scene)?,
            settings: calibrated_settings(scene)?,
        })
    }

    /// The kernel scene of these parts behind the chain `sensor`, with capacity `N` and math
    /// backend `M`, via `Scene::with_ratio_maps`.
    pub fn scene_in<const N: usize, M: Backend>(
        &self,
        sensor: &SensorSpec,
    ) -> Result<Scene<N, M>, ConvertError> {
        within_capacity::<N>(self.classes.len())?;
        Scene::with_ratio_maps(
            self.plate,
            &self.classes,
            &self.ratio_maps,
            sensor_to_kernel_in::<M>(sensor)?,
            self.settings,
        )
        .map_err(ConvertError::Kernel)
    }
}

/// The kernel settings of a scene file: [`settings_to_kernel`], and for a damped contact
/// law or a yielding class the calibration of [`crate::bridge::calibrate::calibrate`] (each ratio
/// unless the file gives it; a scene that yields also its `area_ratio`, by which the
/// duration ratio is then divided). A law whose ratios vary between impacts widens the tolerances to cover them:
/// `shape_tolerance >= 1.5 x` the spread of `ln q` (between impacts, plus that of sampling at
/// the scene's rate), `model_sigma >= ` the larger spread of
/// `ln F` and `ln t`, `spike_fraction >= 1.25 x` the sharpest sampled bend,
/// `skew_tolerance >= 1.5 x` the spread of the skewness, or what of it the detector's trigger
/// cut leaves outside its allowance if that is more (unless the file sets them). A scene
/// whose classes carry ratio tables ([`ratio_maps_to_kernel`]) leaves the force and duration
/// ratios to them (1 here), and its `model_sigma` is at least what the tables leave against
/// direct integration ([`crate::bridge::ratio_table::class_residual`]).
pub fn calibrated_settings(scene: &SceneFile) -> Result<Settings, ConvertError> {
    let mut s = settings_to_kernel(&scene.settings);
    let o = &scene.settings;
    let cal = crate::bridge::calibrate::calibrate(scene).map_err(ConvertError::Calibration)?;
    let pick = |given: Option<f64>, computed: Option<f64>| given.or(computed).unwrap_or(1.0) as f32;
    // A scene that yields reads its flatter pulses' duration with their own area
    // (`area_ratio`), and the classifier divides only by what remains of the ratio.
    let area = cal.filter(|_| scene.yields()).map_or(1.0, |c| c.area_ratio);
    s.area_ratio = area as f32;
    // ... and allows its broader tops a longer run of equal samples before calling one clipped.
    if let Some(c) = cal.filter(|_| scene.yields()) {
        s.flat_top_ratio = c.flat_top_ratio.max(1.0) as f32;
    }
    let tables = crate::bridge::ratio_table::needs_tables(scene);
    let unless_tables = |v: f64| if tables { 1.0 } else { v };
    s.contact = ContactCalibration {
        force_ratio: pick(o.force_ratio, cal.map(|c| unless_tables(c.ratios.force))),
        duration_ratio: pick(
            o.duration_ratio,
            cal.map(|c| unless_tables(c.ratios.duration / area)),
        ),
        shape_ratio: pick(o.shape_ratio, cal.map(|c| c.ratios.shape)),
        skewness: o.skewness.or(cal.map(|c| c.skewness)).unwrap_or(0.0) as f32,
        sampled: cal
            .and_then(|c| c.sampled)
            .map_or(SampledCalibration::NONE, |t| sampled_to_kernel(&t)),
    };
    if let Some(c) = cal {
        if o.shape_tolerance.is_none() {
            let spread = c.spread_ln.shape + c.sampled_shape_spread;
            s.shape_tolerance = s.shape_tolerance.max((1.5 * spread) as f32);
        }
        if o.model_sigma.is_none() {
            let spread = if tables {
                table_residual(scene)?
            } else {
                c.spread_ln.force.max(c.spread_ln.duration)
            };
            s.model_sigma = s.model_sigma.max(spread as f32);
        }
        if o.skew_tolerance.is_none() {
            let spread = c.skewness_spread.max(c.skewness_cut_excess);
            s.skew_tolerance = s.skew_tolerance.max((1.5 * spread) as f32);
        }
        if o.spike_fraction.is_none() {
            s.spike_fraction = s.spike_fraction.max((1.25 * c.sharpest_bend) as f32);
        }
    }
    Ok(s)
}

/// The largest of the classes' residual spreads (root mean square) of their ratio tables
/// against direct integration, of the peak force or the duration, in log units
/// ([`crate::bridge::ratio_table::class_residual`]).
fn table_residual(scene: &SceneFile) -> Result<f64, ConvertError> {
    let mut worst = 0.0f64;
    for i in 0..scene.classes.len() {
        let table =
            crate::bridge::ratio_table::class_table(scene, i).map_err(ConvertError::Calibration)?;
        let (f, t) = crate::bridge::ratio_table::class_residual(scene, i, &table)
            .map_err(ConvertError::Calibration)?;
        worst = worst.max(f).max(t);
    }
    Ok(worst)
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

    fn scene_file(name: &str) -> SceneFile {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join("scenes")
            .join(name);
        crate::scene::load(path).expect("shipped scene loads")
    }

    #[test]
    fn paper_toml_is_the_kernel_paper_scene() {
        let file = scene_file("paper.toml");
        assert_eq!(file, SceneFile::paper());
        let kernel = scene_to_kernel(&file).expect("converts");
        assert_eq!(kernel, Scene::paper().expect("kernel preset"));
    }

    #[test]
    fn paper_narrow_toml_is_the_kernel_narrow_scene() {
        let file = scene_file("paper_narrow.toml");
        assert_eq!(file, SceneFile::paper_narrow());
        let kernel = scene_to_kernel(&file).expect("converts");
        assert_eq!(kernel, Scene::paper_narrow().expect("kernel preset"));
    }

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

    #[test]
    fn kernel_refusals_are_typed() {
        let mut s = SceneFile::paper();
        s.settings.confident_error_rate = Some(0.6);
        assert_eq!(
            scene_to_kernel(&s),
            Err(ConvertError::Kernel(coalshock::Error::OutOfRange(
                "confident_error_rate"
            )))
        );
        let mut s = SceneFile::paper();
        for i in 0..3 {
            let mut c = s.classes[0].clone();
            c.name = format!("extra{i}");
            s.classes.push(c);
        }
        assert!(matches!(
            scene_to_kernel(&s),
            Err(ConvertError::TooManyClasses {
                classes: 5,
                capacity: 4
            })
        ));
    }
}
