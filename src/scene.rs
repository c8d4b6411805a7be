//! A scene: the plate, the particle classes and the sensor chain, with everything the stream
//! needs precomputed once (envelopes, separability, detector thresholds).

use heapless::{String, Vec};

use crate::chain_bias::ChainBias;
use crate::chain_residual::{self, SMOOTH_FROM_SAMPLES};
use crate::envelope::{Envelope, Range};
use crate::equaliser::{ChainDynamics, EqualiserDesign, ResidualFn};
use crate::error::{Error, positive, representable};
use crate::hertz;
use crate::material::{Material, effective_modulus_pa};
use crate::math::{Backend, DefaultBackend};
#[cfg(feature = "pulse_shape")]
pub use crate::pulse_shape::PulseShape;
use crate::pulse_window::{PRE_TRIGGER, hold_samples};
use crate::ratio_map::RatioMap;
pub use crate::sampled::{SAMPLED_FIRST_N, SAMPLED_POINTS, SAMPLED_STEP, SampledCalibration};
pub use crate::sampled_phase::SampledPhase;

/// Shortest duration, in samples, that is classified: a pulse measured shorter (by more than
/// three of its sigmas) is rejected as `TooShort`, and a scene whose shortest pulse is shorter
/// is refused. The fit's duration error is 3.9 % at 3 samples per pulse and grows as `n^-2.5`.
pub const MIN_DURATION_SAMPLES: f32 = 2.5;

/// Default number of classes a scene can hold.
pub const DEFAULT_CLASSES: usize = 4;

/// Most classes any scene can hold (the classifier's scratch space).
pub const MAX_CLASSES: usize = 32;

/// Longest class name, in bytes.
pub const NAME_LEN: usize = 16;

/// Largest separability grid (cells per side) a scene accepts.
pub const MAX_SEPARABILITY_GRID: u16 = 256;

/// How the impact speed of a class is given, and so its prior.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Speed {
    /// Speed in m/s, uniform on the range (the paper's `1 <= u <= 5`).
    Uniform(Range),
    /// Drop height in m, uniform on the range; `u = sqrt(2 g h)`, so `p(u) ~ u`.
    DropHeight(Range),
}

/// One particle class: a name, a material, and the radius and speed it comes with.
#[derive(Debug, Clone, PartialEq)]
pub struct ParticleClass {
    /// Name shown in reports (at most [`NAME_LEN`] bytes).
    pub name: String<NAME_LEN>,
    /// The particle's material.
    pub material: Material,
    /// Sphere radius in m, log-uniform on the range.
    pub radius_m: Range,
    /// Impact speed.
    pub speed: Speed,
    /// Prior weight of the class (relative share of impacts), `> 0`.
    pub prior: f32,
    /// Limiting contact pressure `p_y` in Pa of Thornton's elastic-perfectly-plastic contact
    /// (finite, `> 0`), if the class's contact yields: its envelope is then bent by
    /// [`crate::ratio_map`]; `None`: elastic Hertz contact.
    pub yield_pressure_pa: Option<f32>,
}

impl ParticleClass {
    /// A class with a prior weight of 1; a name longer than [`NAME_LEN`] bytes is cut.
    pub fn new(name: &str, material: Material, radius_m: Range, speed: Speed) -> Self {
        let mut s = String::new();
        for c in name.chars() {
            if s.push(c).is_err() {
                break;
            }
        }
        Self {
            name: s,
            material,
            radius_m,
            speed,
            prior: 1.0,
            yield_pressure_pa: None,
        }
    }
}

/// The sensor chain the kernel inverts: integer ADC counts to contact force.
///
/// A rigid plate of effective mass `M` (kg) under an accelerometer of `S` counts per m/s^2 gives
/// `F = counts * M / S`: `force_per_count_n = M / S`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorChain {
    /// Sample rate in Hz.
    pub sample_rate_hz: f32,
    /// Contact force per ADC count above the baseline, in N.
    pub force_per_count_n: f32,
    /// RMS noise of the quiet signal in counts (sets the thresholds).
    pub noise_rms_counts: f32,
    /// Lowest ADC code (a sample at or below it is saturated).
    pub adc_min: i32,
    /// Highest ADC code (a sample at or above it is saturated).
    pub adc_max: i32,
    /// The beam's modes and the accelerometer's resonance between the plate and the ADC,
    /// which the node inverts before it detects anything ([`ChainDynamics::RIGID`]: none).
    pub dynamics: ChainDynamics,
}

impl SensorChain {
    /// A chain from the plate's effective mass (kg) and the accelerometer's sensitivity
    /// (counts per m/s^2): `force_per_count_n = effective_mass_kg / counts_per_m_s2`.
    pub fn from_plate(
        sample_rate_hz: f32,
        effective_mass_kg: f32,
        counts_per_m_s2: f32,
        noise_rms_counts: f32,
        adc_bits: u8,
    ) -> Self {
        let bits = adc_bits.clamp(2, 31);
        let half = 1i64 << (bits - 1);
        Self {
            sample_rate_hz,
            force_per_count_n: effective_mass_kg / counts_per_m_s2,
            noise_rms_counts,
            adc_min: (-half) as i32,
            adc_max: (half - 1) as i32,
            dynamics: ChainDynamics::RIGID,
        }
    }

    /// The same chain with the beam modes and accelerometer resonance `dynamics`, whose
    /// equaliser is designed here at the chain's sample rate with the default backend;
    /// a stage that cannot be inverted is refused with [`Error::Chain`] naming it.
    pub fn with_dynamics(self, dynamics: ChainDynamics) -> Result<Self, Error> {
        self.with_dynamics_in::<DefaultBackend>(dynamics)
    }

    /// [`SensorChain::with_dynamics`] with the math backend `M`.
    pub fn with_dynamics_in<M: Backend>(mut self, dynamics: ChainDynamics) -> Result<Self, Error> {
        self.dynamics = dynamics
            .designed::<M>(self.sample_rate_hz)?
            .with_residual(ResidualFn(chain_residual::residual));
        Ok(self)
    }

    fn check(&self) -> Result<(), Error> {
        positive(self.sample_rate_hz, "sample_rate_hz")?;
        positive(self.force_per_count_n, "force_per_count_n")?;
        if !self.noise_rms_counts.is_finite() {
            return Err(Error::NonFinite("noise_rms_counts"));
        }
        if self.noise_rms_counts < 0.0 {
            return Err(Error::NonPositive("noise_rms_counts"));
        }
        if self.adc_min >= self.adc_max {
            return Err(Error::InvertedRange("adc_min..adc_max"));
        }
        Ok(())
    }
}

/// Detector and classifier settings; [`Settings::default`] is what the presets use.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// A pulse starts when a sample exceeds the baseline by this many noise RMS (and at least
    /// 2 counts).
    pub trigger_sigmas: f32,
    /// A pulse ends after [`Settings::hold_samples`] samples below baseline + this many RMS.
    pub release_sigmas: f32,
    /// Samples below the release level that end a pulse.
    pub hold_samples: u16,
    /// Baseline (DC) tracking time constant in s.
    pub baseline_tau_s: f32,
    /// Identical consecutive samples that flag a stuck sensor (0: off). Only active when
    /// the noise RMS is at least one count, so that a quiet sensor is never called stuck.
    pub stuck_samples: u16,
    /// Model tolerance in log units added (in quadrature) to the measurement noise of both
    /// `ln F_max` and `ln t_c`: what damping, the plate and the sensor do that the Hertz model
    /// does not. Default 0: a scene whose contact the kernel models exactly pays nothing for it
    /// (a posterior widened beyond the measurement's noise is under-confident, and loses
    /// coverage); host-sim sets it to the spread a calibrated law leaves.
    pub model_sigma: f32,
    /// The share of `Class` verdicts the user accepts to be wrong, in `(0, 0.5)` (default
    /// 0.01): a class is reported when its posterior reaches `1 - confident_error_rate`
    /// ([`Settings::confidence_threshold`]), below that the pulse is `Ambiguous`. With
    /// calibrated posteriors every `Class` verdict is then wrong with probability at most
    /// this rate, so the confident-error rate over any set of verdicts is at most this rate.
    pub confident_error_rate: f32,
    /// Standardised distance outside every envelope beyond which a pulse is `OutOfEnvelope`.
    pub out_sigmas: f32,
    /// Midpoint rows along `ln u` of the quadrature that integrates the separability at build
    /// time (2..=256): 8 rows are already within 1e-4 of the exact value.
    pub separability_grid: u16,
    /// Largest `|ln q|` of a pulse's shape ratio `q = t_energy / t_area` (1 for the Hertz
    /// pulse, see [`crate::detector`]) beyond the noise's share, above which the pulse is
    /// rejected as `Misshapen`. A damped contact skews the pulse (`ln q` down to -0.1 at
    /// restitution 0.5): its [`ContactCalibration::shape_ratio`] recentres the check, and a law
    /// whose shape varies from impact to impact needs a wider tolerance.
    pub shape_tolerance: f32,
    /// What the scene's contact does to a measured pulse against the undamped Hertz pulse of
    /// the same impact ([`ContactCalibration::HERTZ`] for an undamped contact).
    pub contact: ContactCalibration,
    /// A pulse with a second difference `v[i-1] - 2 v[i] + v[i+1]` below
    /// `-(2 b + spike_fraction F_max + 8 noise)` (`b` the sharpest bend of a Hertz pulse of its
    /// peak and duration) has a sample that jumped alone: `Spike`. 0.3 for a smooth contact; a
    /// law whose force steps (Adams IMPACT with a small penetration depth: -0.56 F_max at
    /// 100 kS/s) needs more, and then only larger spikes are seen.
    pub spike_fraction: f32,
    /// Largest distance of a pulse's skewness from its contact's
    /// ([`ContactCalibration::skewness`]) beyond the sampling and noise allowance, above which
    /// the pulse is `Misshapen` (two impacts with unequal peaks within one contact).
    pub skew_tolerance: f32,
    /// How much broader, as a share of its duration, the contact's pulse top is than the Hertz
    /// pulse's (the time within 2 % of the peak; 1 for Hertz, 2-3 for a yielding pulse):
    /// the run of identical samples at a pulse's maximum that makes it `Saturated` is this
    /// many times longer, so that a broad top is not taken for a clipped one (a top clipped
    /// by the same share of its peak is still caught). `>= 1`, at most `1e3`. With the
    /// `plasticity` feature only.
    #[cfg(feature = "plasticity")]
    pub flat_top_ratio: f32,
    /// A damped contact's sampling correction by samples per pulse and sampling phase, which
    /// takes the place of `contact.sampled` where it reaches ([`SampledPhase::NONE`]: no
    /// table). Behind a chain that is not rigid it is of the pulses as the detector sees them
    /// there, equalised (host-sim fits it through the chain and this kernel's equaliser), and
    /// the scene adds nothing to it. With the `sampled_phase` feature only.
    #[cfg(feature = "sampled_phase")]
    pub sampled_phase: SampledPhase,
    /// A damped contact's own pulse shape, from which the detector measures a pulse clipped
    /// at the ADC's full scale on a rigid chain ([`PulseShape::NONE`]: none, and such a pulse
    /// is `Saturated`; an undamped contact's is the Hertz shape, built in). With the
    /// `pulse_shape` feature only.
    #[cfg(feature = "pulse_shape")]
    pub pulse_shape: PulseShape,
}

/// A damped contact against the undamped Hertz model, as the detector measures it: the ratios
/// measured / Hertz of the peak force `F_max`, of the duration `area / (C_AREA F_max)` and of
/// the shape ratio `q` (see [`crate::detector`]). The classifier divides a measurement by
/// them before it compares it with the Hertz envelopes, and the shape check is centred on
/// `shape_ratio`. For the restitution-parametrised laws (Hunt-Crossley, Flores, ...) they
/// depend on the restitution alone, so one calibration holds for every impact of a scene;
/// host-sim computes them from its integrator. Dimensionless; each in `1e-3..1e3`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ContactCalibration {
    /// Measured peak force over the Hertz `F_max`.
    pub force_ratio: f32,
    /// Measured duration (from the area) over the Hertz `t_c`.
    pub duration_ratio: f32,
    /// Shape ratio `q` of the contact's pulse (1 for the Hertz pulse).
    pub shape_ratio: f32,
    /// Skewness of the contact's whole pulse, `E[(t - mu)^3] / E[(t - mu)^2]^(3/2)` with the
    /// force as the weight (0 for the symmetric Hertz pulse; a damped pulse rises faster than it
    /// falls: 0.82 for Flores at restitution 0.5, 0.15-0.2 for Adams with `d = 0.01 mm`).
    pub skewness: f32,
    /// What sampling adds to `force_ratio` and `duration_ratio` at few samples per pulse
    /// ([`SampledCalibration::NONE`] for the Hertz pulse, whose fit error the detector
    /// carries itself).
    pub sampled: SampledCalibration,
}

impl ContactCalibration {
    /// The undamped Hertz contact: every ratio 1 (the classifier's division is then exact).
    pub const HERTZ: ContactCalibration = ContactCalibration {
        force_ratio: 1.0,
        duration_ratio: 1.0,
        shape_ratio: 1.0,
        skewness: 0.0,
        sampled: SampledCalibration::NONE,
    };

    fn check(&self) -> Result<(), Error> {
        let ok = |v: f32| v.is_finite() && (1e-3..=1e3).contains(&v);
        if !ok(self.force_ratio) {
            return Err(Error::OutOfRange("contact.force_ratio"));
        }
        if !ok(self.duration_ratio) {
            return Err(Error::OutOfRange("contact.duration_ratio"));
        }
        if !ok(self.shape_ratio) {
            return Err(Error::OutOfRange("contact.shape_ratio"));
        }
        if !(self.skewness.is_finite() && self.skewness.abs() <= 10.0) {
            return Err(Error::OutOfRange("contact.skewness"));
        }
        self.sampled.check()
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            trigger_sigmas: 6.0,
            release_sigmas: 3.0,
            hold_samples: 2,
            baseline_tau_s: 0.02,
            stuck_samples: 64,
            model_sigma: 0.0,
            confident_error_rate: 0.01,
            out_sigmas: 4.0,
            separability_grid: 48,
            shape_tolerance: 0.02,
            contact: ContactCalibration::HERTZ,
            spike_fraction: 0.3,
            skew_tolerance: 0.05,
            #[cfg(feature = "plasticity")]
            flat_top_ratio: 1.0,
            #[cfg(feature = "sampled_phase")]
            sampled_phase: SampledPhase::NONE,
            #[cfg(feature = "pulse_shape")]
            pulse_shape: PulseShape::NONE,
        }
    }
}

impl Settings {
    /// Posterior a class needs for a `Class` verdict: `1 - confident_error_rate`
    /// (dimensionless, in `(0.5, 1)` for a valid rate).
    pub fn confidence_threshold(&self) -> f32 {
        1.0 - self.confident_error_rate
    }

    /// Whether the settings carry a sampling correction: by samples per pulse
    /// (`contact.sampled`) or, with the feature `sampled_phase`, by samples per pulse and
    /// phase (`sampled_phase`). Its spread then states the fit's error at few samples per
    /// pulse, and the classifier divides the measurement by it.
    ///
    /// ```
    /// use coalshock::Settings;
    /// assert!(!Settings::default().corrects_sampling());
    /// ```
    #[inline]
    pub fn corrects_sampling(&self) -> bool {
        #[cfg(feature = "sampled_phase")]
        if self.sampled_phase != SampledPhase::NONE {
            return true;
        }
        self.contact.sampled != SampledCalibration::NONE
    }

    fn check(&self) -> Result<(), Error> {
        positive(self.trigger_sigmas, "trigger_sigmas")?;
        positive(self.release_sigmas, "release_sigmas")?;
        positive(self.baseline_tau_s, "baseline_tau_s")?;
        positive(self.out_sigmas, "out_sigmas")?;
        if !self.model_sigma.is_finite() || self.model_sigma < 0.0 {
            return Err(Error::OutOfRange("model_sigma"));
        }
        if !(self.shape_tolerance.is_finite() && self.shape_tolerance > 0.0) {
            return Err(Error::OutOfRange("shape_tolerance"));
        }
        self.contact.check()?;
        #[cfg(feature = "sampled_phase")]
        self.sampled_phase.check()?;
        #[cfg(feature = "pulse_shape")]
        self.pulse_shape.check()?;
        if !(self.spike_fraction.is_finite() && self.spike_fraction > 0.0) {
            return Err(Error::OutOfRange("spike_fraction"));
        }
        if !(self.skew_tolerance.is_finite() && self.skew_tolerance > 0.0) {
            return Err(Error::OutOfRange("skew_tolerance"));
        }
        #[cfg(feature = "plasticity")]
        {
            if !(1.0..=1e3).contains(&self.flat_top_ratio) {
                return Err(Error::OutOfRange("flat_top_ratio"));
            }
        }
        if self.release_sigmas > self.trigger_sigmas {
            return Err(Error::InvertedRange("release_sigmas..trigger_sigmas"));
        }
        if !(self.confident_error_rate > 0.0 && self.confident_error_rate < 0.5) {
            return Err(Error::OutOfRange("confident_error_rate"));
        }
        if self.hold_samples == 0 {
            return Err(Error::NonPositive("hold_samples"));
        }
        if self.separability_grid < 2 || self.separability_grid > MAX_SEPARABILITY_GRID {
            return Err(Error::OutOfRange("separability_grid"));
        }
        Ok(())
    }
}

/// How well the scene's classes can be told apart at all, from the noiseless envelopes.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Separability {
    /// Prior-weighted share of impacts that land where another class is also possible.
    pub overlap_share: f32,
    /// Bayes error without noise: the share of impacts even the best classifier on exact
    /// `(F_max, t_c)` gets wrong (the forced-choice accuracy ceiling is `1 - bayes_error`).
    pub bayes_error: f32,
}

/// A built scene: classes with their envelopes, sensor chain, settings, separability, all
/// computed with the math backend `M`.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene<const N: usize = DEFAULT_CLASSES, M: Backend = DefaultBackend> {
    plate: Material,
    classes: Vec<ParticleClass, N>,
    envelopes: Vec<Envelope, N>,
    ln_priors: Vec<f32, N>,
    sensor: SensorChain,
    equaliser: EqualiserDesign,
    chain_bias: ChainBias,
    settings: Settings,
    separability: Separability,
    shortest_duration_s: f32,
    longest_duration_s: f32,
    backend: M,
}

impl<const N: usize, M: Backend> Scene<N, M> {
    /// Builds a scene and precomputes every class's envelope and the separability, and behind a
    /// chain that is not rigid the bias its equaliser leaves in short pulses
    /// ([`crate::chain_residual`], folded into `settings.contact.sampled`; a
    /// `settings.sampled_phase` table is already of the equalised pulses).
    ///
    /// Refuses, with a typed [`Error`]: invalid materials, ranges or sensor settings; fewer than
    /// two classes or more than `N`; any corner of any envelope whose peak force or duration
    /// f32 cannot carry; a scene whose shortest pulse is shorter than
    /// [`MIN_DURATION_SAMPLES`] (2.5 samples), or whose shortest measured pulse (times the
    /// contact's `duration_ratio`) is shorter than its sampling correction reaches (1.6
    /// samples with a phase table, else 2.5): its pulses cannot be measured.
    pub fn new(
        plate: Material,
        classes: &[ParticleClass],
        sensor: SensorChain,
        settings: Settings,
    ) -> Result<Self, Error> {
        Self::with_ratio_maps(plate, classes, &[], sensor, settings)
    }

    /// [`Scene::new`] with a ratio map per class (`maps[i]` for `classes[i]`; missing or `None`:
    /// none) that bends the class's envelope when its contact's measured/Hertz ratios vary with
    /// size and speed (a damped law with a fixed coefficient, tabulated by the host from its
    /// integrator; [`crate::ratio_map`]): the scene's [`ContactCalibration`] then holds only
    /// what the table leaves. Without the `ratio_map` feature a class with a map is refused.
    pub fn with_ratio_maps(
        plate: Material,
        classes: &[ParticleClass],
        maps: &[Option<RatioMap>],
        sensor: SensorChain,
        settings: Settings,
    ) -> Result<Self, Error> {
        plate.validate()?;
        sensor.check()?;
        settings.check()?;
        let equaliser = sensor.dynamics.equaliser_at(sensor.sample_rate_hz)?;
        class_count_fits(classes.len(), N)?;
        let mut envelopes = Vec::new();
        let mut ln_priors = Vec::new();
        let mut stored = Vec::new();
        let mut shortest = f32::INFINITY;
        let mut longest = 0.0f32;
        for (i, c) in classes.iter().enumerate() {
            let table = maps.get(i).copied().flatten();
            let (short, long) = Self::push_envelope(&plate, c, table, &mut envelopes)?;
            shortest = shortest.min(short);
            longest = longest.max(long);
            let prior = positive(c.prior, "prior")?;
            // Capacity was checked above: these pushes cannot fail.
            let _ = ln_priors.push(M::ln(prior));
            let _ = stored.push(c.clone());
        }
        relative_to_largest(&mut ln_priors);
        durations_measurable(shortest, longest, sensor.sample_rate_hz, &settings)?;
        let fs = sensor.sample_rate_hz;
        let window = (
            PRE_TRIGGER as f32,
            hold_samples(settings.hold_samples, shortest, fs) as f32,
        );
        let chain_bias = ChainBias::new::<M>(&sensor.dynamics, fs, (shortest, longest), window);
        let mut scene = Self {
            plate,
            classes: stored,
            envelopes,
            ln_priors,
            sensor,
            equaliser,
            chain_bias,
            settings,
            separability: Separability {
                overlap_share: 0.0,
                bayes_error: 0.0,
            },
            shortest_duration_s: shortest,
            longest_duration_s: longest,
            backend: M::default(),
        };
        if !scene.equaliser.is_identity()
            && shortest * scene.sensor.sample_rate_hz < SMOOTH_FROM_SAMPLES
        {
            add_residual(&mut scene.settings, &scene.sensor);
        }
        scene.separability = scene.integrate_separability();
        Ok(scene)
    }

    /// Pushes class `c`'s envelope on `plate` (bent by its yield or its ratio map `table`, if
    /// any) onto `envelopes` (which has room: the class count was checked), and returns its
    /// shortest and longest pulse (s): Hertz's corners (smallest radius and highest speed; the
    /// opposite), or for a bent envelope the extremes of its four corners.
    #[inline(never)]
    fn push_envelope(
        plate: &Material,
        c: &ParticleClass,
        table: Option<RatioMap>,
        envelopes: &mut Vec<Envelope, N>,
    ) -> Result<(f32, f32), Error> {
        let e_eff = effective_modulus_pa(&c.material, plate)?;
        let (speed, beta) = match c.speed {
            Speed::Uniform(r) => (r.checked("speed_m_s")?, 1.0),
            Speed::DropHeight(h) => {
                let h = h.checked("drop_height_m")?;
                (
                    Range::new(
                        hertz::drop_speed_in::<M>(h.min)?,
                        hertz::drop_speed_in::<M>(h.max)?,
                    ),
                    2.0,
                )
            }
        };
        let rho = c.material.density_kg_m3;
        let mut env = Envelope::new::<M>(e_eff, rho, c.radius_m, speed, beta)?;
        // Shortest pulse: smallest radius, highest speed; longest: the opposite.
        let mut short = hertz::impact_in::<M>(e_eff, rho, c.radius_m.min, speed.max)?.duration_s;
        let mut long = hertz::impact_in::<M>(e_eff, rho, c.radius_m.max, speed.min)?.duration_s;
        if c.yield_pressure_pa.is_some() || table.is_some() {
            env = bend::<M>(env, c, table, e_eff, rho)?;
            // A bent duration's extremes need not be Hertz's corners: all four are taken.
            let ln_t = env.corners().map(|(x, y)| env.forward(x, y).1);
            short = M::exp(ln_t.iter().fold(f32::INFINITY, |a, &b| a.min(b)));
            long = M::exp(ln_t.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b)));
        }
        let _ = envelopes.push(env);
        Ok((short, long))
    }

    /// The plate material.
    pub fn plate(&self) -> &Material {
        &self.plate
    }

    /// The classes, in the order verdicts index them.
    pub fn classes(&self) -> &[ParticleClass] {
        &self.classes
    }

    /// The envelope of each class, same order as [`Self::classes`].
    pub fn envelopes(&self) -> &[Envelope] {
        &self.envelopes
    }

    /// `ln` of each class's prior weight relative to the largest (so the largest is 0).
    pub fn ln_priors(&self) -> &[f32] {
        &self.ln_priors
    }

    /// The sensor chain.
    pub fn sensor(&self) -> &SensorChain {
        &self.sensor
    }

    /// The equaliser that inverts the sensor chain (the identity for a rigid chain).
    pub fn equaliser(&self) -> &EqualiserDesign {
        &self.equaliser
    }

    /// The bound of the bias the chain's tolerance can leave in `ln F_max`, per pulse duration
    /// ([`ChainBias::NONE`] for a rigid chain or one known exactly).
    pub fn chain_bias(&self) -> &ChainBias {
        &self.chain_bias
    }

    /// The settings as given, but for `contact.sampled` behind a chain that is not rigid: the
    /// bias the equaliser leaves in short pulses ([`crate::chain_residual`]) is added to it
    /// ([`SampledCalibration::combined`]).
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// How well the classes separate without noise (computed at build).
    pub fn separability(&self) -> Separability {
        self.separability
    }

    /// The math backend.
    pub fn backend(&self) -> M {
        self.backend
    }

    /// Shortest and longest Hertz contact duration over all classes, in s.
    pub fn duration_bounds_s(&self) -> (f32, f32) {
        (self.shortest_duration_s, self.longest_duration_s)
    }

    /// The prior mass of each class that lands where another class has non-zero density
    /// (overlap) and where another class has a larger prior-weighted density (Bayes error),
    /// integrated exactly along `ln R` and by the midpoint rule along `ln u`.
    ///
    /// On a row `y` of class `i` the radii `x in [x0, x1]` map to a straight segment in
    /// `(ln F_max, ln t_c)`, which class `j` sees as a segment `(x', y')(t)`, `t in [0, 1]`, of
    /// its own box. Where it is inside that box is an interval of `t` (clipping), and there
    /// the log of `j`'s prior-weighted density, `ln prior_j + ln_normalizer_j + beta_j y'`, is
    /// linear in `t`: where it beats class `i`'s (constant on the row) is a half-line. The
    /// row's overlap and error shares are the lengths of the unions of these intervals, and
    /// they are linear in `y` between the rows where a segment end crosses a box edge or a
    /// density tie ([`Scene::next_break`]). So `[y0, y1]` is cut at those rows and each piece
    /// gets its share of the `G` midpoint rows (at least one): the error falls as `1/G^2`
    /// (a `G x G` grid of points aliased the class boundaries, which run almost parallel to
    /// the rows, and did not converge). `O((G + N) N^2)` work, once.
    fn integrate_separability(&self) -> Separability {
        let g = self.settings.separability_grid as f32;
        let mut total_prior = 0.0f32;
        let mut overlap = 0.0f32;
        let mut error = 0.0f32;
        for (i, (env, lp)) in self.envelopes.iter().zip(self.ln_priors.iter()).enumerate() {
            let prior = M::exp(*lp);
            total_prior += prior;
            let (y0, y1) = env.ln_speed;
            let span = y1 - y0;
            let (mut m_over, mut m_err, mut m_all) = (0.0f32, 0.0f32, 0.0f32);
            let mut start = y0;
            // At most 10 breaks per other class: the loop is bounded.
            for _ in 0..(10 * self.envelopes.len() + 2) {
                if start >= y1 {
                    break;
                }
                let end = self.next_break(i, start).min(y1);
                // About this piece's share of the G rows, at least one (a NaN share gives one).
                let rows = ((g * (end - start) / span) as u32).min(g as u32) + 1;
                let dy = (end - start) / rows as f32;
                for r in 0..rows {
                    let y = start + (r as f32 + 0.5) * dy;
                    let w = env.speed_density::<M>(y) * dy;
                    let (over, err) = self.row_shares(i, y);
                    m_all += w;
                    m_over += w * over;
                    m_err += w * err;
                }
                start = end;
            }
            if m_all > 0.0 {
                overlap += prior * m_over / m_all;
                error += prior * m_err / m_all;
            }
        }
        Separability {
            overlap_share: (overlap / total_prior).max(0.0).min(1.0),
            bayes_error: (error / total_prior).max(0.0).min(1.0),
        }
    }

    /// The shares of class `i`'s row `ln u = y` (uniform in `ln R`) where another class is
    /// possible and where one is more probable (see [`Scene::integrate_separability`]).
    fn row_shares(&self, i: usize, y: f32) -> (f32, f32) {
        let (Some(env), Some(lp)) = (self.envelopes.get(i), self.ln_priors.get(i)) else {
            return (0.0, 0.0);
        };
        let (x0, x1) = env.ln_radius;
        // A bent class's own density varies along the row; taken linear between its ends.
        let own = *lp + env.ln_normalizer + env.speed_beta * y;
        let own_a = own + env.ln_density_excess::<M>(x0, y);
        let own_b = if env.excess_varies_with_radius() {
            own + env.ln_density_excess::<M>(x1, y)
        } else {
            own_a
        };
        let fa = env.forward(x0, y);
        let fb = env.forward(x1, y);
        let mut possible = Intervals::<N>::EMPTY;
        let mut better = Intervals::<N>::EMPTY;
        for (j, (e2, lp2)) in self.envelopes.iter().zip(self.ln_priors.iter()).enumerate() {
            if j == i {
                continue;
            }
            let (xa, ya) = e2.invert_ln(fa.0, fa.1);
            let (xb, yb) = e2.invert_ln(fb.0, fb.1);
            let Some((lo, hi)) =
                clip(xa, xb, e2.ln_radius, (0.0, 1.0)).and_then(|t| clip(ya, yb, e2.ln_speed, t))
            else {
                continue;
            };
            possible.push(lo, hi);
            // Ties go to the lower index, as the classifier's argmax does.
            // A bent class's density has its Jacobian in place of 8/5 ([`Envelope::density`]).
            let (ea, eb) = (
                e2.ln_density_excess::<M>(xa, ya),
                e2.ln_density_excess::<M>(xb, yb),
            );
            let c0 = *lp2 + e2.ln_normalizer + e2.speed_beta * ya + ea - own_a;
            let c1 = e2.speed_beta * (yb - ya) + (eb - ea) - (own_b - own_a);
            if let Some((blo, bhi)) = beats(c0, c1, j < i, (lo, hi)) {
                better.push(blo, bhi);
            }
        }
        (possible.union_length(), better.union_length())
    }

    /// The first `ln u` above `y` (or `y1`) where, on class `i`'s rows, an end of the row's
    /// segment crosses an edge of another class's box, or another class's density at an end
    /// equals class `i`'s: all affine in `y`, so each is one division.
    fn next_break(&self, i: usize, y: f32) -> f32 {
        let (Some(env), Some(lp)) = (self.envelopes.get(i), self.ln_priors.get(i)) else {
            return f32::INFINITY;
        };
        let (x0, x1) = env.ln_radius;
        let (y0, y1) = env.ln_speed;
        let span = y1 - y0;
        let own = |yy: f32| *lp + env.ln_normalizer + env.speed_beta * yy;
        let mut next = y1;
        for (j, (e2, lp2)) in self.envelopes.iter().zip(self.ln_priors.iter()).enumerate() {
            if j == i {
                continue;
            }
            let ends = |yy: f32| {
                let (fa, fb) = (env.forward(x0, yy), env.forward(x1, yy));
                (e2.invert_ln(fa.0, fa.1), e2.invert_ln(fb.0, fb.1))
            };
            let ((xa0, ya0), (xb0, yb0)) = ends(y0);
            let ((xa1, ya1), (xb1, yb1)) = ends(y1);
            let tie = |yp: f32, yy: f32| *lp2 + e2.ln_normalizer + e2.speed_beta * yp - own(yy);
            let (rx0, rx1) = e2.ln_radius;
            let (ry0, ry1) = e2.ln_speed;
            // (value at y0, value at y1, level)
            let lines = [
                (xa0, xa1, rx0),
                (xa0, xa1, rx1),
                (xb0, xb1, rx0),
                (xb0, xb1, rx1),
                (ya0, ya1, ry0),
                (ya0, ya1, ry1),
                (yb0, yb1, ry0),
                (yb0, yb1, ry1),
                (tie(ya0, y0), tie(ya1, y1), 0.0),
                (tie(yb0, y0), tie(yb1, y1), 0.0),
            ];
            for (g0, g1, level) in lines {
                let slope = g1 - g0;
                if slope.abs() > 1e-12 {
                    let at = y0 + (level - g0) / slope * span;
                    if at > y + 1e-6 * span && at < next {
                        next = at;
                    }
                }
            }
        }
        next
    }
}

/// Between 2 and `min(n, MAX_CLASSES)` classes (`count`): `TooFewClasses` or
/// `TooManyClasses` otherwise.
fn class_count_fits(count: usize, n: usize) -> Result<(), Error> {
    if count < 2 {
        return Err(Error::TooFewClasses);
    }
    if count > n || count > MAX_CLASSES {
        return Err(Error::TooManyClasses);
    }
    Ok(())
}

/// Log priors made relative to the largest, so that exp(ln prior) stays in (0, 1] whatever
/// their scale (1e-30 or 1e30 alike).
fn relative_to_largest(ln_priors: &mut [f32]) {
    let top = ln_priors.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b));
    for lp in ln_priors.iter_mut() {
        *lp -= top;
    }
}

/// The scene's shortest pulse (s, the Hertz or bent contact time) spans at least
/// [`MIN_DURATION_SAMPLES`] at `sample_rate_hz`, the shortest pulse the detector measures
/// (that time times `contact.duration_ratio`: a damped pulse's duration from its area) at
/// least [`measured_samples_floor`], and the longest a number of samples f32 carries;
/// `OutOfRange` otherwise.
fn durations_measurable(
    shortest_s: f32,
    longest_s: f32,
    sample_rate_hz: f32,
    settings: &Settings,
) -> Result<(), Error> {
    if shortest_s * sample_rate_hz < MIN_DURATION_SAMPLES {
        return Err(Error::OutOfRange(
            "sample_rate_hz (shortest pulse < 2.5 samples)",
        ));
    }
    let measured = shortest_s * settings.contact.duration_ratio * sample_rate_hz;
    if measured < measured_samples_floor(settings) {
        return Err(Error::OutOfRange(
            "sample_rate_hz (shortest measured pulse shorter than the sampling correction reaches)",
        ));
    }
    representable(longest_s * sample_rate_hz, "longest pulse in samples")?;
    Ok(())
}

/// The fewest samples the shortest pulse the detector measures may span: where the scene's
/// sampling correction starts, [`crate::sampled_phase::PHASE_FIRST_N`] (1.6) with a phase
/// table, else [`MIN_DURATION_SAMPLES`] (2.5, where the correction by samples per pulse
/// starts, [`SAMPLED_FIRST_N`]). Below it the correction would hold its first value, which a
/// pulse's sampling error does not.
fn measured_samples_floor(settings: &Settings) -> f32 {
    #[cfg(feature = "sampled_phase")]
    if settings.sampled_phase != SampledPhase::NONE {
        return crate::sampled_phase::PHASE_FIRST_N;
    }
    let _ = settings;
    MIN_DURATION_SAMPLES.max(SAMPLED_FIRST_N)
}

/// The envelope `env` of class `c` bent by its ratio map `table`, if it has one
/// ([`Envelope::bent_by`]), else by its yield at `c.yield_pressure_pa` Pa
/// ([`Envelope::yielding`]; its material: effective modulus `e` Pa, density `rho` kg/m^3).
/// Without the `ratio_map` feature a class with a map is refused, and without `plasticity`
/// one that yields.
fn bend<M: Backend>(
    env: Envelope,
    c: &ParticleClass,
    table: Option<RatioMap>,
    e: f32,
    rho: f32,
) -> Result<Envelope, Error> {
    if let Some(map) = table {
        #[cfg(feature = "ratio_map")]
        return env.bent_by(map);
        #[cfg(not(feature = "ratio_map"))]
        {
            let _ = map;
            return Err(Error::OutOfRange(
                "ratio map (kernel built without the `ratio_map` feature)",
            ));
        }
    }
    #[cfg(feature = "plasticity")]
    if let Some(p_y) = c.yield_pressure_pa {
        return env.yielding::<M>(e, rho, positive(p_y, "yield_pressure_pa")?);
    }
    let _ = (env, c, e, rho, M::default());
    Err(Error::OutOfRange(
        "yield_pressure_pa (kernel built without the `plasticity` feature)",
    ))
}

/// Up to `N` intervals of `[0, 1]` (one per other class of a scene of `N` classes).
struct Intervals<const N: usize> {
    items: [(f32, f32); N],
    len: usize,
}

impl<const N: usize> Intervals<N> {
    const EMPTY: Intervals<N> = Intervals {
        items: [(0.0, 0.0); N],
        len: 0,
    };

    fn push(&mut self, lo: f32, hi: f32) {
        if let Some(slot) = self.items.get_mut(self.len) {
            *slot = (lo, hi);
            self.len += 1;
        }
    }

    /// Length of the union (sorts the intervals by their start).
    fn union_length(&mut self) -> f32 {
        let items = self.items.get_mut(..self.len).unwrap_or_default();
        items.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut total = 0.0f32;
        let mut reach = f32::NEG_INFINITY;
        for &(lo, hi) in items.iter() {
            let start = lo.max(reach);
            if hi > start {
                total += hi - start;
            }
            reach = reach.max(hi);
        }
        total
    }
}

/// The part of `t in (lo, hi)` where `a + t (b - a)` lies in `[r0, r1]`, or `None`.
fn clip(a: f32, b: f32, (r0, r1): (f32, f32), (lo, hi): (f32, f32)) -> Option<(f32, f32)> {
    let d = b - a;
    let (mut lo, mut hi) = (lo, hi);
    if d.abs() <= 1e-12 {
        return (r0..=r1).contains(&a).then_some((lo, hi));
    }
    let (ta, tb) = ((r0 - a) / d, (r1 - a) / d);
    lo = lo.max(ta.min(tb));
    hi = hi.min(ta.max(tb));
    (lo < hi).then_some((lo, hi))
}

/// The part of `t in (lo, hi)` where `c0 + c1 t > 0` (or `>= 0` when `tie_wins`), with
/// `|x| <= 1e-5` taken as zero (f32 rounding of equal densities), or `None`.
fn beats(c0: f32, c1: f32, tie_wins: bool, (lo, hi): (f32, f32)) -> Option<(f32, f32)> {
    const EPS: f32 = 1e-5;
    if c1.abs() <= EPS {
        let wins = c0 > EPS || (c0.abs() <= EPS && tie_wins);
        return wins.then_some((lo, hi));
    }
    let t = -c0 / c1;
    let (lo, hi) = if c1 > 0.0 {
        (lo.max(t), hi)
    } else {
        (lo, hi.min(t))
    };
    (lo < hi).then_some((lo, hi))
}

impl Scene {
    /// The paper's scene with the default backend; see [`Scene::paper_for`].
    pub fn paper() -> Result<Self, Error> {
        Self::paper_for()
    }

    /// The narrow-speed paper scene with the default backend; see [`Scene::paper_narrow_for`].
    pub fn paper_narrow() -> Result<Self, Error> {
        Self::paper_narrow_for()
    }
}

impl<M: Backend> Scene<DEFAULT_CLASSES, M> {
    /// The paper's scene with backend `M`: coal (1380 kg/m^3, 5.3 GPa, 0.32) and sandstone gangue (2487 kg/m^3,
    /// 13.5 GPa, 0.123) on a carbon-steel plate (Tables 1-2), `R` in `[0.015, 0.04]` m
    /// (Table 3), `u` in `[1, 5]` m/s (section 4.1). Sensor: 100 kS/s, 50 kg effective plate
    /// mass, 30 counts per m/s^2, 4 counts RMS noise, 16-bit ADC.
    pub fn paper_for() -> Result<Self, Error> {
        Self::paper_with_speed(Range::new(1.0, 5.0))
    }

    /// The paper's scene with the speed narrowed to `[2.5, 3.5]` m/s: the classes separate,
    /// since gangue at `u` looks like coal at about `1.70 u` and `3.5 / 2.5 < 1.70`.
    pub fn paper_narrow_for() -> Result<Self, Error> {
        Self::paper_with_speed(Range::new(2.5, 3.5))
    }

    fn paper_with_speed(speed: Range) -> Result<Self, Error> {
        let radius = Range::new(0.015, 0.04);
        let classes = [
            ParticleClass::new("coal", Material::COAL, radius, Speed::Uniform(speed)),
            ParticleClass::new("gangue", Material::SANDSTONE, radius, Speed::Uniform(speed)),
        ];
        Self::new(
            Material::CARBON_STEEL,
            &classes,
            SensorChain::from_plate(100_000.0, 50.0, 30.0, 4.0, 16),
            Settings::default(),
        )
    }
}

/// Adds the bias the equaliser of `sensor` leaves in short pulses
/// ([`crate::chain_residual`]) to the settings' sampling correction. A phase table is left as
/// it is: it is calibrated on the equalised pulses. Not inlined: a rigid scene's build never
/// calls it and must not carry its frame.
#[inline(never)]
fn add_residual(settings: &mut Settings, sensor: &SensorChain) {
    let r = sensor.dynamics.residual_at(sensor.sample_rate_hz);
    settings.contact.sampled = settings.contact.sampled.combined(&r);
}
