//! A scene file's kernel scene: its calibration computed first (the f64 integrator runs of
//! [`crate::bridge::calibrate`] and [`crate::bridge::ratio_table`], [`SceneCalibration`]),
//! then converted to the kernel's f32 types ([`crate::bridge::convert`]).

use coalshock::math::Backend;
use coalshock::ratio_map::RatioMap;
use coalshock::scene::DEFAULT_CLASSES;
use coalshock::{Material, ParticleClass, Scene, Settings};

use crate::bridge::calibrate::{Calibration64, calibrate};
use crate::bridge::convert::{
    ConvertError, class_to_kernel, dynamics_to_kernel, material_to_kernel, ratio_maps_to_kernel,
    sensor_to_kernel_in, settings_to_kernel,
};
use crate::bridge::equalised_fit::EqualisedChain;
use crate::bridge::ratio_table::{RatioTable64, class_residual, class_table, needs_tables};
use crate::bridge::sampled_phase::TABLE_PHASES;
use crate::physics::integrate::SimError;
use crate::physics::law_spec::LawSpec;
use crate::scene::{SceneFile, SensorSpec};

/// What a scene's kernel takes from the integrator (f64): the contact calibration, and the
/// classes' ratio tables with what they leave against direct integration.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneCalibration {
    /// The contact calibration ([`calibrate`]; `None`: the Hertz law, no yielding class).
    pub contact: Option<Calibration64>,
    /// Each class's ratio table when the law needs them ([`needs_tables`]), else empty.
    pub tables: Vec<RatioTable64>,
    /// With tables, the largest root-mean-square residual of a class's table against direct
    /// integration, of the peak force or the duration, in log units ([`class_residual`]).
    pub table_residual: Option<f64>,
}

impl SceneCalibration {
    /// Integrates `scene`'s classes for their calibration (nothing for the Hertz law with no
    /// yielding class).
    pub fn of(scene: &SceneFile) -> Result<Self, SimError> {
        let tables = if needs_tables(scene) {
            (0..scene.classes.len())
                .map(|i| class_table(scene, i))
                .collect::<Result<Vec<_>, _>>()?
        } else {
            Vec::new()
        };
        // Only a damped contact's phase table is fitted through the chain.
        let chain = (scene.contact != LawSpec::Hertz)
            .then(|| equalised_chain(&scene.sensor))
            .flatten();
        let contact = calibrate(scene, chain.as_ref())?;
        let table_residual = if tables.is_empty() {
            None
        } else {
            let mut worst = 0.0f64;
            for (i, table) in tables.iter().enumerate() {
                let (f, t) = class_residual(scene, i, table)?;
                worst = worst.max(f).max(t);
            }
            Some(worst)
        };
        Ok(Self {
            contact,
            tables,
            table_residual,
        })
    }

    /// The kernel settings of `scene` with this calibration ([`settings_to_kernel`]).
    pub fn settings(&self, scene: &SceneFile) -> Settings {
        settings_to_kernel(
            &scene.settings,
            self.contact.as_ref(),
            scene.yields(),
            self.table_residual,
        )
    }
}

/// The chain of `sensor` as the kernel equalises it, for the phase table of a damped contact
/// ([`EqualisedChain`] at [`TABLE_PHASES`]); `None` for a rigid chain, and for one the kernel
/// refuses (the scene's build then names the stage).
fn equalised_chain(sensor: &SensorSpec) -> Option<EqualisedChain> {
    let dynamics = dynamics_to_kernel(sensor).ok()?;
    EqualisedChain::new(sensor, &dynamics, TABLE_PHASES)
}

/// The kernel settings of a scene file: its `[settings]` with its calibration
/// ([`SceneCalibration::of`], then [`settings_to_kernel`]).
pub fn calibrated_settings(scene: &SceneFile) -> Result<Settings, ConvertError> {
    let cal = SceneCalibration::of(scene).map_err(ConvertError::Calibration)?;
    Ok(cal.settings(scene))
}

/// A scene file -> the kernel scene with the default capacity and backend, via
/// `Scene::with_ratio_maps`.
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
/// classes, their ratio maps and the calibrated settings. Building them runs the integrator
/// ([`SceneCalibration::of`]); a study that gives the kernel several chains for one scene
/// builds them once.
#[derive(Debug, Clone)]
pub struct KernelParts {
    plate: Material,
    classes: Vec<ParticleClass>,
    ratio_maps: Vec<Option<RatioMap>>,
    settings: Settings,
}

impl KernelParts {
    /// The parts of `scene`: its calibration, converted.
    pub fn of(scene: &SceneFile) -> Result<Self, ConvertError> {
        let cal = SceneCalibration::of(scene).map_err(ConvertError::Calibration)?;
        Ok(Self {
            plate: material_to_kernel(&scene.plate.material()),
            classes: scene.classes.iter().map(class_to_kernel).collect(),
            ratio_maps: ratio_maps_to_kernel(&cal.tables)?,
            settings: cal.settings(scene),
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
    fn kernel_refusals_are_typed() {
        let mut s = SceneFile::paper();
        s.settings.confident_error_rate = 0.6;
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
