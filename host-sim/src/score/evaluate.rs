//! End-to-end evaluation of the kernel on a scene: impacts drawn from the scene's priors,
//! integrated in `f64`, sent through the sensor chain, fed as integer samples to the kernel's
//! `Monitor` (the node's `f32` code, math backend `M`), and its reports scored against the
//! truth, against the scene's reference limit ([`crate::score::reference`]: physics and the stated
//! noise alone) and against Bayes-optimal decisions computed here in `f64`.
//!
//! # What is drawn
//!
//! Exactly `n_per_class` impacts of every class: `R` log-uniform, `u` uniform (or the drop
//! height uniform, `u = sqrt(2 g h)`), as the scene says. They are cut into streams of at most
//! `impacts_per_stream` impacts ([`crate::sim::generate::generate_classes`]: the scene's
//! contact law through the integrator, the sensor chain, well-separated impacts with 2-10 ms
//! of quiet between pulses, no injected faults). Behind a rigid chain each stream holds one
//! class, and stream `j` of class `c` has its own seed derived from `(seed, c, j)`. Behind a
//! chain that rings, every pulse rides on the ringing the impacts before it left, which would
//! tell its class if they were all of its class: there the impacts of all classes are
//! shuffled before they are cut, so that an impact's neighbours are drawn independently of its
//! class (stream `j` seeded from `(seed, k, j)`, `k` the number of classes). The streams are
//! simulated and replayed on every core and folded in their fixed order ([`crate::sim::par`]): one seed gives one result on every
//! machine, whatever the number of threads. Each stream is replayed through a fresh `Monitor`
//! ([`crate::score::replay::replay_events`]) and its reports are paired with the impacts
//! ([`crate::score::replay::match_truth`], nearest peak first, at most one longest contact time
//! apart).
//!
//! # Scores
//!
//! Every impact lands in one column of its class's row of the confusion matrix: the class of a
//! `Class` verdict, `ambiguous`, `out_of_envelope`, `rejected`, or `missed` (no report paired
//! with it). A row therefore sums to `n_per_class`; reports paired with no impact are counted
//! as `spurious_reports`.
//!
//! - **Forced choice**: every paired report gets the kernel's own forced choice,
//!   `Verdict::forced_choice`: the class of `Class`, the most probable class of `Ambiguous`
//!   (argmax posterior), the nearest class of `OutOfEnvelope` (the kernel always names one);
//!   `Rejected` gives no class and counts as wrong, and so does a missed impact.
//! - **Coverage**: decided pulses (a `Class` verdict) over paired pulses.
//! - **Confident-error rate**: wrong `Class` verdicts over decided pulses; the kernel reports
//!   a class when its posterior reaches `1 - confident_error_rate` (the scene's setting, or
//!   [`EvalOptions::confident_error_rate`]).
//! - **Reliability**: the posteriors the kernel states against the accuracy observed, by bin
//!   ([`crate::score::reliability`]).
//!
//! Rates are prior-weighted: class `c` contributes its counts times `p_c / n_per_class`
//! (`p_c` the normalised prior), as if impacts arrived in the proportions of the priors. With
//! equal priors they are plain shares of the counts.
//!
//! # The reference limit
//!
//! [`crate::score::reference::reference_limit`]: the best forced choice from the exact features of
//! the scene's contact law measured at the Cramér-Rao bound of the scene's sampled pulse,
//! chain and noise, on independent draws; `kernel_vs_reference` is the kernel's forced choice
//! minus it.
//!
//! # Diagnostics, all computed in `f64` from the scene file ([`crate::score::bayes`])
//!
//! - **Oracle**: the Bayes decision (argmax prior x noiseless class density) on the exact
//!   closed-form Hertz `(F_max, t_c)` of each drawn `(R, u)`: the ceiling of any classifier
//!   that sees the Hertz features without noise, on the same draws as the kernel.
//! - **Feature noise**: estimated from the spread of the kernel's measured features against
//!   the closed-form Hertz features of the drawn `(R, u)` (the features the classes are
//!   defined by), over the paired pulses that were measured and not rejected:
//!   `e_F = ln F_meas - ln F_Hertz`, `e_t = ln t_meas - ln t_Hertz`; the standard deviations
//!   and the correlation of `(e_F, e_t)` about their means. The means (the bias of detector
//!   and contact law) are reported apart and are not part of the noise. One Gaussian for all
//!   pulses: small pulses are noisier than large ones, so the limit it gives is a little
//!   pessimistic when the noise matters. The error is also split into the detector's part
//!   (measured against the simulated pulse) and the contact law's (simulated pulse against
//!   Hertz), see [`NoiseEstimate`].
//! - **Bayes at the kernel's noise**: [`crate::score::bayes::bayes_accuracy`] with that noise, on
//!   `bayes_draws_per_class` independent draws per class: the best forced-choice accuracy
//!   from Hertz features measured with unbiased Gaussian noise of the kernel's size (tied to
//!   the kernel: a worse detector lowers it).
//! - **Bayes on measured**: the same Bayes decision applied to the kernel's measured
//!   `(F, t_c)` of the same pulses (missed and rejected pulses wrong), and once more with the
//!   mean bias subtracted first. Paired with the kernel's forced choice on the same impacts,
//!   the differences isolate each loss: oracle -> Bayes on measured with the bias removed is
//!   what noise, sampling and the spread of the contact law's deviation cost; -> Bayes on
//!   measured what the constant bias costs; -> kernel what the kernel's classifier (its
//!   independent-noise likelihood, `model_sigma`, `f32`) and its rejections cost.
//!
//! `kernel_seconds` is the wall time spent in the kernel's feed calls
//! (`Monitor::feed_slice`, `gap`, `finish`), measured with `std::time::Instant` and summed
//! over the streams (over all threads, so it can exceed the run's wall time); it and
//! `kernel_ns_per_sample` are the only fields that differ between two runs of one seed.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::time::Instant;

use coalshock::math::Backend;
use coalshock::scene::{DEFAULT_CLASSES, MAX_CLASSES};
use coalshock::{Event, Monitor, Report, Scene, Verdict};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::bridge::convert::{measurement_from_kernel, separability_from_kernel};
use crate::bridge::kernel_scene::KernelParts;
use crate::physics::hertz64::HertzImpact64;
use crate::scene::SceneFile;
pub use crate::score::bayes::class_models;
use crate::score::bayes::{Accuracy, ClassModel, FeatureNoise, bayes_accuracy, decide};
use crate::score::mismatch::{ChainMismatch, drawn_chain};
use crate::score::noise_check::StatedNoiseCheck;
use crate::score::peak_snr::{PeakRow, PeakSnrTable};
use crate::score::reference::{ReferenceLimit, ReferenceOptions, reference_limit};
use crate::score::reliability::{Reliability, reliability};
use crate::score::replay::{match_truth, replay_events};
use crate::score::study_error::StudyError;
use crate::sim::generate::generate_classes;
use crate::sim::par::map_ordered;
use crate::sim::stream::{StreamOptions, Truth};

/// Default impacts per simulated stream.
pub const DEFAULT_IMPACTS_PER_STREAM: usize = 250;

/// Default Monte Carlo draws per class of the Bayes limit.
pub const DEFAULT_BAYES_DRAWS_PER_CLASS: usize = 20_000;

/// ChaCha8 stream of the Bayes-limit Monte Carlo.
const RNG_BAYES: u64 = 11;

/// Mixed into a stream's seed for the chain drawn for its kernel (`chain_drawn`).
const CHAIN_DRAW_SEED: u64 = 0xC4A1_D8A3;

/// Fewest measured pulses from which the feature noise is estimated (fewer: taken as zero).
pub const MIN_PULSES_FOR_NOISE: usize = 3;

/// Options of [`evaluate`].
#[derive(Debug, Clone, PartialEq)]
pub struct EvalOptions {
    /// Impacts drawn per class (`>= 1`).
    pub n_per_class: usize,
    /// Seed of every random draw.
    pub seed: u64,
    /// Impacts per simulated stream (`>= 1`); results depend on it (the streams' seeds do),
    /// not on anything else of the machine.
    pub impacts_per_stream: usize,
    /// Monte Carlo draws per class of the Bayes limit (`>= 1`).
    pub bayes_draws_per_class: usize,
    /// Layout of the streams (default: [`StreamOptions::default`], well-separated impacts
    /// through the integrator, no faults).
    pub stream: StreamOptions,
    /// Largest distance in samples between a report's peak and an impact's peak for the two to
    /// be paired; `None`: the longest Hertz contact time of the scene in samples (at least 2).
    pub match_tolerance_samples: Option<u64>,
    /// How far the chain the kernel is given is off from the simulated one.
    pub chain_mismatch: ChainMismatch,
    /// Each stream's kernel is given the chain as one node might have identified it: every
    /// stage's parameters off by errors drawn within the scene's chain tolerance
    /// ([`crate::score::mismatch::drawn_chain`]); exclusive with `chain_mismatch`.
    pub chain_drawn: bool,
    /// The reference limit's grid, draws and phases.
    pub reference: ReferenceOptions,
    /// The confident-error rate the user accepts, in `(0, 0.5)`, replacing the scene file's
    /// `settings.confident_error_rate` (`None`: the file's, or the kernel's default 0.01).
    pub confident_error_rate: Option<f64>,
}

impl Default for EvalOptions {
    /// 1000 impacts per class, seed 1, [`DEFAULT_IMPACTS_PER_STREAM`],
    /// [`DEFAULT_BAYES_DRAWS_PER_CLASS`], default streams, automatic tolerance.
    fn default() -> Self {
        Self {
            n_per_class: 1000,
            seed: 1,
            impacts_per_stream: DEFAULT_IMPACTS_PER_STREAM,
            bayes_draws_per_class: DEFAULT_BAYES_DRAWS_PER_CLASS,
            stream: StreamOptions::default(),
            match_tolerance_samples: None,
            chain_mismatch: ChainMismatch::default(),
            chain_drawn: false,
            reference: ReferenceOptions::default(),
            confident_error_rate: None,
        }
    }
}

/// Why an evaluation could not run: the scoring studies' one error.
pub type EvalError = StudyError;

/// Counts of one true class.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ClassCounts {
    /// Class name.
    pub name: String,
    /// Normalised prior `p_c` (the weight of the class in every rate).
    pub prior: f64,
    /// Impacts drawn.
    pub impacts: u64,
    /// Impacts with a paired report.
    pub detected: u64,
    /// Paired reports with a `Class` verdict.
    pub decided: u64,
    /// Of those, the right class.
    pub decided_right: u64,
    /// Impacts whose forced choice is the right class.
    pub forced_right: u64,
    /// Impacts the oracle classifies right.
    pub oracle_right: u64,
    /// Impacts the Bayes decision on the kernel's measurement classifies right.
    pub bayes_measured_right: u64,
    /// The same with the mean bias removed from the measurement first.
    pub bayes_debiased_right: u64,
    /// Forced-choice accuracy of the class, `forced_right / impacts`.
    pub forced_choice_accuracy: f64,
}

/// Mean, spread and correlation of log errors `(e_F, e_t)` over a set of pulses.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ErrorStats {
    /// Pulses behind the figures.
    pub pulses: u64,
    /// Mean of `e_F` (dimensionless; `e^bias - 1` is the relative bias of `F_max`).
    pub bias_ln_force: f64,
    /// Mean of `e_t` (of `t_c`).
    pub bias_ln_duration: f64,
    /// Standard deviation of `e_F` about its mean.
    pub sigma_ln_force: f64,
    /// Standard deviation of `e_t` about its mean.
    pub sigma_ln_duration: f64,
    /// Correlation of `e_F` and `e_t` (0 when either spread is 0; clamped to `+-0.99`).
    pub correlation: f64,
    /// Largest `|e_F|`.
    pub worst_ln_force: f64,
    /// Largest `|e_t|`.
    pub worst_ln_duration: f64,
}

impl ErrorStats {
    /// The statistics of `(e_F, e_t)` pairs (non-finite pairs left out).
    pub fn of(errors: impl IntoIterator<Item = (f64, f64)>) -> Self {
        let e: Vec<(f64, f64)> = errors
            .into_iter()
            .filter(|(a, b)| a.is_finite() && b.is_finite())
            .collect();
        let n = e.len();
        if n == 0 {
            return Self::default();
        }
        let nf = n as f64;
        let mf = e.iter().map(|v| v.0).sum::<f64>() / nf;
        let mt = e.iter().map(|v| v.1).sum::<f64>() / nf;
        let dof = (nf - 1.0).max(1.0);
        let vf = e.iter().map(|v| (v.0 - mf).powi(2)).sum::<f64>() / dof;
        let vt = e.iter().map(|v| (v.1 - mt).powi(2)).sum::<f64>() / dof;
        let vft = e.iter().map(|v| (v.0 - mf) * (v.1 - mt)).sum::<f64>() / dof;
        let (sf, st) = (vf.sqrt(), vt.sqrt());
        Self {
            pulses: n as u64,
            bias_ln_force: mf,
            bias_ln_duration: mt,
            sigma_ln_force: sf,
            sigma_ln_duration: st,
            correlation: if sf > 0.0 && st > 0.0 {
                (vft / (sf * st)).clamp(-0.99, 0.99)
            } else {
                0.0
            },
            worst_ln_force: e.iter().map(|v| v.0.abs()).fold(0.0, f64::max),
            worst_ln_duration: e.iter().map(|v| v.1.abs()).fold(0.0, f64::max),
        }
    }
}

/// The feature noise behind the Bayes limit, and where the measurement error comes from.
///
/// Errors are `e = ln(measured) - ln(reference)` for `F_max` and `t_c`. The feature noise is
/// [`NoiseEstimate::measured_vs_hertz`] without its mean: the kernel's measurement against the
/// closed-form Hertz features of the drawn `(R, u)` (the features the classes are defined by),
/// over the paired pulses that were measured and not rejected. It splits into the detector's
/// part (measured against the simulated pulse) and the contact law's part (the simulated pulse
/// against closed-form Hertz: zero for undamped Hertz, the damping otherwise).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct NoiseEstimate {
    /// `"measured_vs_hertz"`, or `"none"` when fewer than [`MIN_PULSES_FOR_NOISE`] pulses were
    /// measured (the noise is then taken as zero).
    pub source: &'static str,
    /// Standard deviation of `ln F_max` used for the Bayes limit.
    pub sigma_ln_force: f64,
    /// Standard deviation of `ln t_c` used for the Bayes limit.
    pub sigma_ln_duration: f64,
    /// Correlation of the two used for the Bayes limit.
    pub correlation: f64,
    /// Kernel measurement against closed-form Hertz (bias and noise together).
    pub measured_vs_hertz: ErrorStats,
    /// Kernel measurement against the simulated pulse (the detector alone).
    pub measured_vs_pulse: ErrorStats,
    /// Simulated pulse against closed-form Hertz, over every impact (the contact law).
    pub pulse_vs_hertz: ErrorStats,
    /// Mean of the kernel's own `sigma_ln_force` over the measured pulses (its noise claim).
    pub kernel_sigma_ln_force: f64,
    /// Mean of the kernel's own `sigma_ln_duration` over the measured pulses.
    pub kernel_sigma_ln_duration: f64,
    /// The noise the classifier weighed each measured pulse on, against the pulse's true
    /// radius and speed ([`StatedNoiseCheck`]).
    pub stated_noise_check: StatedNoiseCheck,
}

impl NoiseEstimate {
    /// The noise as [`FeatureNoise`] for [`crate::score::bayes`] (`None` when it is zero).
    pub fn feature_noise(&self) -> Option<FeatureNoise> {
        (self.sigma_ln_force > 0.0 || self.sigma_ln_duration > 0.0).then_some(FeatureNoise {
            sigma_ln_force: self.sigma_ln_force,
            sigma_ln_duration: self.sigma_ln_duration,
            correlation: self.correlation,
        })
    }
}

/// A paired difference of two accuracies on the same impacts.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Paired {
    /// `accuracy(a) - accuracy(b)`, prior-weighted.
    pub difference: f64,
    /// Its standard error from the per-impact differences,
    /// `sqrt(sum_c p_c^2 var_c(d) / n_c)`.
    pub std_error: f64,
}

/// The result of [`evaluate`]; `--json` prints it as one object (fields: `FORMATS.md`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evaluation {
    /// Scene name.
    pub scene: String,
    /// Class names, in the scene's order.
    pub classes: Vec<String>,
    /// The kernel's math backend.
    pub backend: &'static str,
    /// Impacts drawn per class.
    pub n_per_class: usize,
    /// Seed.
    pub seed: u64,
    /// Impacts per simulated stream.
    pub impacts_per_stream: usize,
    /// Pairing tolerance used, in samples.
    pub match_tolerance_samples: u64,
    /// Column names of [`Evaluation::confusion`]: the class names, then `ambiguous`,
    /// `out_of_envelope`, `rejected`, `missed`.
    pub columns: Vec<String>,
    /// Rows: true class; columns: [`Evaluation::columns`]. Every row sums to `n_per_class`.
    pub confusion: Vec<Vec<u64>>,
    /// Rows: true class; columns: the class names, then `none`: the forced choice (`none`:
    /// rejected or missed).
    pub forced_confusion: Vec<Vec<u64>>,
    /// Rejected pulses by the kernel's reason (`saturated`, `spike`, `pileup`, ...).
    pub rejected_by_reason: BTreeMap<&'static str, u64>,
    /// Per true class.
    pub per_class: Vec<ClassCounts>,
    /// Share of impacts whose forced choice is right (prior-weighted).
    pub forced_choice_accuracy: f64,
    /// Its standard error, `sqrt(sum_c p_c^2 a_c (1 - a_c) / n_c)`.
    pub forced_choice_std_error: f64,
    /// Decided (`Class`) over paired pulses.
    pub coverage: f64,
    /// Wrong `Class` verdicts over decided pulses.
    pub confident_error_rate: f64,
    /// Shares of impacts with an `Ambiguous` verdict.
    pub ambiguous_share: f64,
    /// Shares of impacts with an `OutOfEnvelope` verdict.
    pub out_of_envelope_share: f64,
    /// Shares of impacts with a `Rejected` verdict.
    pub rejected_share: f64,
    /// Shares of impacts no report was paired with.
    pub missed_share: f64,
    /// Reports paired with no impact.
    pub spurious_reports: u64,
    /// The posterior a class needs for a `Class` verdict, `1 - confident_error_rate`.
    pub confidence_threshold: f64,
    /// The reference limit: physics and the scene's stated noise alone
    /// ([`crate::score::reference`]).
    pub reference: ReferenceLimit,
    /// Kernel forced choice minus the reference limit (independent draws: the standard error
    /// is `sqrt(se_kernel^2 + se_reference^2)`).
    pub kernel_vs_reference: Paired,
    /// Stated posterior against observed accuracy ([`crate::score::reliability`]), over the pulses
    /// with a `Class` or `Ambiguous` verdict.
    pub reliability: Reliability,
    /// Diagnostic, tied to the kernel: the Bayes limit with the kernel's own measured feature
    /// noise ([`Evaluation::noise`]; Monte Carlo, independent draws). A worse detector lowers
    /// it; [`Evaluation::reference`] is the limit.
    pub kernel_noise_bayes_accuracy: f64,
    /// Its standard error.
    pub kernel_noise_bayes_std_error: f64,
    /// Draws behind it (all classes).
    pub kernel_noise_bayes_draws: usize,
    /// The kernel's own noiseless Bayes error of the scene (`Scene::separability`, a 48 x 48
    /// grid by default); `1 -` it is the noiseless ceiling the kernel announces.
    pub kernel_bayes_error: f64,
    /// Oracle accuracy on the same draws (exact Hertz features, no noise).
    pub oracle_accuracy: f64,
    /// Whether any class yields: then the oracle and the other diagnostics on elastic Hertz
    /// features describe a physics the scene does not have, and only the reference limit is
    /// its limit.
    pub yields: bool,
    /// The Bayes decision on the kernel's measured features of the same pulses.
    pub bayes_on_measured_accuracy: f64,
    /// The same with the mean bias removed from the measurement first.
    pub bayes_on_measured_debiased_accuracy: f64,
    /// Kernel forced choice minus Bayes on measured: what the kernel's classifier loses.
    pub kernel_vs_bayes_on_measured: Paired,
    /// Bayes on measured minus the same debiased: what the constant bias of the measured
    /// features (detector and contact law) loses.
    pub bias_loss: Paired,
    /// Bayes on measured, debiased, minus oracle: what the measurement loses (noise,
    /// sampling, the spread of the contact law's deviation, rejected and missed pulses).
    pub measured_vs_oracle: Paired,
    /// Noise and bias of the measured features.
    pub noise: NoiseEstimate,
    /// Verdicts and feature errors by the impact's peak over the force noise the detector
    /// sees ([`crate::score::peak_snr`]).
    pub by_peak_over_noise: PeakSnrTable,
    /// White-noise gain of the kernel's equaliser (1 for a rigid chain): the ADC noise RMS
    /// times it is the noise of the reconstructed force, in counts.
    pub equaliser_noise_gain: f64,
    /// The relative errors of the chain the kernel was given (all 0: the true chain).
    pub chain_mismatch: [f64; 3],
    /// Whether each stream's kernel was given a chain drawn within the scene's tolerance.
    pub chain_drawn: bool,
    /// Samples fed to the kernel (including the quiet stretches).
    pub samples_fed: u64,
    /// Pulse reports of the kernel (paired or not).
    pub pulses_detected: u64,
    /// Wall time in s spent in the kernel's feed calls.
    pub kernel_seconds: f64,
    /// `kernel_seconds / samples_fed` in ns.
    pub kernel_ns_per_sample: f64,
}

/// The kernel's math backend for [`evaluate_backend`] (the CLI's `--backend`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BackendChoice {
    /// The kernel's default ([`BackendChoice::about`]).
    #[default]
    Default,
    /// `libm`.
    Libm,
    /// `micromath`.
    Micromath,
}

impl BackendChoice {
    /// Every backend, in the order the help lists them.
    pub const ALL: [Self; 3] = [Self::Default, Self::Libm, Self::Micromath];

    /// The name as written on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Default => "default",
            Self::Libm => "libm",
            Self::Micromath => "micromath",
        }
    }

    /// The backend, as the help shows it.
    pub fn about(self) -> &'static str {
        match self {
            Self::Default => {
                "The kernel's default (`coalshock::math::DefaultBackend`: libm, or micromath \
                 with the kernel's `micromath` feature)"
            }
            Self::Libm => "`libm`",
            Self::Micromath => "`micromath`",
        }
    }
}

/// [`evaluate_with_progress`] with the backend chosen at run time.
pub fn evaluate_backend(
    backend: BackendChoice,
    scene: &SceneFile,
    opts: &EvalOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Evaluation, EvalError> {
    match backend {
        BackendChoice::Default => {
            evaluate_with_progress::<coalshock::math::DefaultBackend>(scene, opts, progress)
        }
        BackendChoice::Libm => {
            evaluate_with_progress::<coalshock::math::Libm>(scene, opts, progress)
        }
        BackendChoice::Micromath => {
            evaluate_with_progress::<coalshock::math::Micromath>(scene, opts, progress)
        }
    }
}

/// Evaluates the kernel with math backend `M` on `scene` (see the module docs).
pub fn evaluate<M: Backend + Send + Sync>(
    scene: &SceneFile,
    opts: &EvalOptions,
) -> Result<Evaluation, EvalError> {
    evaluate_with_progress::<M>(scene, opts, &mut |_, _| {})
}

/// [`evaluate`], calling `progress(done, total)` with the impacts simulated and fed so far.
pub fn evaluate_with_progress<M: Backend + Send + Sync>(
    scene: &SceneFile,
    opts: &EvalOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Evaluation, EvalError> {
    let mut scene = scene.clone();
    if let Some(rate) = opts.confident_error_rate {
        scene.settings.confident_error_rate = rate as f32;
    }
    scene.validate()?;
    if scene.classes.len() <= DEFAULT_CLASSES {
        run::<DEFAULT_CLASSES, M>(&scene, opts, progress)
    } else {
        run::<MAX_CLASSES, M>(&scene, opts, progress)
    }
}

/// One impact's outcome.
#[derive(Debug, Clone, Copy)]
struct Outcome {
    class: usize,
    /// Closed-form Hertz `(ln F_max, ln t_c)` of the drawn `(R, u)`.
    hertz_ln: (f64, f64),
    /// `(ln F, ln t_c)` of the simulated pulse.
    true_ln: (f64, f64),
    /// The kernel's measurement, when it made one.
    measured: Option<MeasuredLn>,
    /// Confusion column.
    column: usize,
    /// Kernel forced choice.
    forced: Option<usize>,
    /// The posterior the kernel stated for its best class (`Class` and `Ambiguous`).
    posterior: Option<f64>,
    oracle: usize,
    /// The measurement's error in the true class's `(ln R, ln u)` over the sigmas the
    /// classifier weighed it on ([`crate::score::noise_check`]).
    z: Option<(f64, f64)>,
}

/// A kernel measurement in logs, with the kernel's own standard deviations.
#[derive(Debug, Clone, Copy)]
struct MeasuredLn {
    ln_force: f64,
    ln_duration: f64,
    sigma_ln_force: f64,
    sigma_ln_duration: f64,
}

fn option_err(field: &'static str, problem: impl Into<String>) -> EvalError {
    StudyError::option("evaluation", field, problem)
}

/// SplitMix64 finaliser: a well-mixed 64-bit value of `x`.
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// Seed of stream `chunk` of tag `tag` (its class, or the number of classes for a stream that
/// mixes them: `stream_jobs`).
fn stream_seed(seed: u64, tag: usize, chunk: usize) -> u64 {
    mix(seed ^ mix(((tag as u64) << 40) ^ chunk as u64))
}

/// Phase 1: the options' counts and the chain mismatch's relative errors are in range.
fn validate_options(opts: &EvalOptions) -> Result<(), EvalError> {
    if opts.n_per_class == 0 {
        return Err(option_err("n_per_class", "must be >= 1"));
    }
    if opts.impacts_per_stream == 0 {
        return Err(option_err("impacts_per_stream", "must be >= 1"));
    }
    if opts.bayes_draws_per_class == 0 {
        return Err(option_err("bayes_draws_per_class", "must be >= 1"));
    }
    opts.stream.validate()?;
    let m = &opts.chain_mismatch;
    for (name, v) in [
        ("chain_frequency_error", m.frequency),
        ("chain_damping_error", m.damping),
        ("chain_gain_error", m.gain),
    ] {
        if !(v.is_finite() && v > -1.0 && v < 1.0) {
            return Err(option_err(name, "must be a relative error in (-1, 1)"));
        }
    }
    if opts.chain_drawn && !m.is_none() {
        return Err(option_err(
            "chain_drawn",
            "draws the chain within its tolerance: give no chain error with it",
        ));
    }
    Ok(())
}

/// Phase 2, the pairing tolerance in samples: as given, or the longest contact time of the
/// scene (largest radius at the lowest speed of each class, `t_c f_s` rounded up, at least 2).
fn match_tolerance(scene: &SceneFile, opts: &EvalOptions) -> Result<u64, EvalError> {
    if let Some(t) = opts.match_tolerance_samples {
        return Ok(t);
    }
    let plate = scene.plate.material();
    let mut longest = 0.0f64;
    for c in &scene.classes {
        let h = HertzImpact64::new(
            &c.material.material(),
            &plate,
            c.radius_m.max,
            c.speed_range_m_s().min,
        )
        .map_err(|e| option_err("scene", e.to_string()))?;
        longest = longest.max(h.duration_s);
    }
    Ok(((longest * scene.sensor.sample_rate_hz).ceil() as u64).max(2))
}

/// Phase 3's result: every stream's outcomes and counts, folded in stream order.
#[derive(Default)]
struct Replayed {
    outcomes: Vec<Outcome>,
    rejected_by_reason: BTreeMap<&'static str, u64>,
    samples_fed: u64,
    pulses_detected: u64,
    spurious: u64,
    kernel_seconds: f64,
}

/// The kernel scene the streams are replayed through, and the parts it was built from (for a
/// stream given a chain of its own, `chain_drawn`).
#[derive(Clone, Copy)]
struct KernelOf<'a, const N: usize, M: Backend> {
    scene: &'a Scene<N, M>,
    parts: &'a KernelParts,
}

/// Phase 3: `n_per_class` impacts of each class in streams of at most `impacts_per_stream`,
/// each with its own seed, simulated and replayed on every core and folded in order
/// (`progress(done, total)` after each stream).
fn replay_streams<const N: usize, M: Backend + Send + Sync>(
    scene: &SceneFile,
    opts: &EvalOptions,
    kernel: KernelOf<'_, N, M>,
    models: &[ClassModel],
    tolerance: u64,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Replayed, EvalError> {
    let total = opts.n_per_class * scene.classes.len();
    let jobs = stream_jobs(scene.classes.len(), opts, scene.sensor.is_rigid());
    let run_job = |_: usize, job: &StreamJob| -> Result<ChunkResult, EvalError> {
        if opts.chain_drawn {
            let seed = stream_seed(opts.seed ^ CHAIN_DRAW_SEED, job.tag, job.chunk);
            let drawn = kernel
                .parts
                .scene_in::<N, M>(&drawn_chain(scene, seed).sensor)?;
            return run_stream::<N, M>(scene, opts, &drawn, models, tolerance, job);
        }
        run_stream::<N, M>(scene, opts, kernel.scene, models, tolerance, job)
    };
    let mut all = Replayed {
        outcomes: Vec::with_capacity(total),
        ..Replayed::default()
    };
    let mut done = 0usize;
    map_ordered(&jobs, run_job, |_, r| {
        let r = r?;
        all.outcomes.extend(r.outcomes);
        for reason in r.rejected {
            *all.rejected_by_reason.entry(reason).or_default() += 1;
        }
        all.samples_fed += r.samples_fed;
        all.pulses_detected += r.pulses_detected;
        all.spurious += r.spurious;
        all.kernel_seconds += r.kernel_seconds;
        done += r.impacts;
        progress(done, total);
        Ok::<(), EvalError>(())
    })?;
    Ok(all)
}

/// Phase 5's result: per class counts, the confusion matrices and the per-impact indicators
/// (kernel forced, Bayes on measured, Bayes on debiased measured, oracle) of each class.
struct Tally {
    per_class: Vec<ClassCounts>,
    confusion: Vec<Vec<u64>>,
    forced_confusion: Vec<Vec<u64>>,
    indicators: Vec<Vec<[f64; 4]>>,
}

/// Phase 5: every outcome counted into its class, its confusion cells and its indicators;
/// the Bayes decisions on the kernel's measurement use `noise`'s feature noise and bias.
fn tally(
    scene: &SceneFile,
    outcomes: &[Outcome],
    models: &[ClassModel],
    noise: &NoiseEstimate,
    n_per_class: usize,
) -> Tally {
    let k = scene.classes.len();
    let (col_rej, col_miss) = (k + 2, k + 3);
    let feature_noise = noise.feature_noise();
    let bias = &noise.measured_vs_hertz;
    let mut t = Tally {
        per_class: scene
            .classes
            .iter()
            .zip(scene.class_probabilities())
            .map(|(c, p)| ClassCounts {
                name: c.name.clone(),
                prior: p,
                ..ClassCounts::default()
            })
            .collect(),
        confusion: vec![vec![0u64; k + 4]; k],
        forced_confusion: vec![vec![0u64; k + 1]; k],
        indicators: vec![Vec::with_capacity(n_per_class); k],
    };
    for o in outcomes {
        let c = &mut t.per_class[o.class];
        c.impacts += 1;
        t.confusion[o.class][o.column] += 1;
        t.forced_confusion[o.class][o.forced.unwrap_or(k).min(k)] += 1;
        c.detected += (o.column != col_miss) as u64;
        c.decided += (o.column < k) as u64;
        c.decided_right += (o.column < k && o.column == o.class) as u64;
        let forced = o.forced == Some(o.class);
        let oracle = o.oracle == o.class;
        let (mut bm, mut bd) = (false, false);
        if let (Some(m), false) = (o.measured, o.column == col_rej || o.column == col_miss) {
            let fnoise = feature_noise.as_ref();
            bm = decide(models, m.ln_force, m.ln_duration, fnoise) == o.class;
            let (lf, ld) = (
                m.ln_force - bias.bias_ln_force,
                m.ln_duration - bias.bias_ln_duration,
            );
            bd = decide(models, lf, ld, fnoise) == o.class;
        }
        c.forced_right += forced as u64;
        c.oracle_right += oracle as u64;
        c.bayes_measured_right += bm as u64;
        c.bayes_debiased_right += bd as u64;
        t.indicators[o.class].push([forced, bm, bd, oracle].map(|b| b as u8 as f64));
    }
    for c in &mut t.per_class {
        c.forced_choice_accuracy = share(c.forced_right, c.impacts);
    }
    t
}

impl Tally {
    /// Prior-weighted share of a class count: `sum_c prior_c f(c) / impacts_c`.
    fn weighted(&self, f: impl Fn(&ClassCounts) -> u64) -> f64 {
        self.per_class
            .iter()
            .map(|c| c.prior * share(f(c), c.impacts))
            .sum()
    }

    /// Standard error of the prior-weighted forced-choice accuracy:
    /// `sqrt(sum_c prior_c^2 a_c (1 - a_c) / n_c)`.
    fn forced_choice_std_error(&self) -> f64 {
        self.per_class
            .iter()
            .map(|c| {
                let a = share(c.forced_right, c.impacts);
                c.prior * c.prior * a * (1.0 - a) / c.impacts.max(1) as f64
            })
            .sum::<f64>()
            .sqrt()
    }

    /// Prior-weighted share of the impacts in confusion column `col`.
    fn column_share(&self, col: usize) -> f64 {
        self.per_class
            .iter()
            .enumerate()
            .map(|(i, c)| c.prior * share(self.confusion[i][col], c.impacts))
            .sum()
    }

    /// Prior-weighted mean of the paired difference of indicators `a` and `b`, with its
    /// standard error (each class's sample variance over its impacts).
    fn paired(&self, a: usize, b: usize) -> Paired {
        let mut difference = 0.0;
        let mut var = 0.0;
        for (c, rows) in self.per_class.iter().zip(&self.indicators) {
            let n = rows.len().max(1) as f64;
            let d: Vec<f64> = rows.iter().map(|r| r[a] - r[b]).collect();
            let mean = d.iter().sum::<f64>() / n;
            let v = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
            difference += c.prior * mean;
            var += c.prior * c.prior * v / n;
        }
        Paired {
            difference,
            std_error: var.sqrt(),
        }
    }
}

/// `num / den`, 0 when `den` is not positive.
fn ratio(num: f64, den: f64) -> f64 {
    if den > 0.0 { num / den } else { 0.0 }
}

/// The evaluation of `scene` with `opts`, in phases: options, pairing tolerance, streams
/// replayed, noise and the limits (Bayes, reference), tallies, and the rates of [`Evaluation`].
fn run<const N: usize, M: Backend + Send + Sync>(
    scene: &SceneFile,
    opts: &EvalOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Evaluation, EvalError> {
    validate_options(opts)?;
    let told = opts.chain_mismatch.applied_to(scene);
    let parts = KernelParts::of(&told)?;
    let kernel_scene = parts.scene_in::<N, M>(&told.sensor)?;
    let models = class_models(scene);
    let tolerance = match_tolerance(scene, opts)?;
    let kernel = KernelOf {
        scene: &kernel_scene,
        parts: &parts,
    };
    let replayed = replay_streams::<N, M>(scene, opts, kernel, &models, tolerance, progress)?;
    // 4. Noise, the Bayes limit (independent Monte Carlo draws) and the reference limit.
    let k = scene.classes.len();
    let noise = estimate_noise(&replayed.outcomes, k + 2);
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    rng.set_stream(RNG_BAYES);
    let mut uniform = || ((rng.random::<u64>() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let fnoise = noise.feature_noise();
    let bayes = bayes_accuracy(
        &models,
        fnoise.as_ref(),
        opts.bayes_draws_per_class,
        &mut uniform,
    );
    let threshold = kernel_scene.settings().confidence_threshold() as f64;
    let reference = reference_limit(scene, &opts.reference, opts.seed, threshold)?;
    let tally = tally(scene, &replayed.outcomes, &models, &noise, opts.n_per_class);
    let limits = Limits {
        bayes,
        reference,
        kernel_bayes_error: separability_from_kernel(&kernel_scene.separability()).1,
        equaliser_noise_gain: kernel_scene.equaliser().noise_gain() as f64,
        confidence_threshold: kernel_scene.settings().confidence_threshold() as f64,
    };
    Ok(assemble::<M>(
        scene, opts, tolerance, replayed, noise, tally, limits,
    ))
}

/// Phase 4's limits and the kernel scene's figures an [`Evaluation`] reports.
struct Limits {
    bayes: Accuracy,
    reference: ReferenceLimit,
    kernel_bayes_error: f64,
    equaliser_noise_gain: f64,
    confidence_threshold: f64,
}

/// Phase 6: the rates of an [`Evaluation`] from the tallies, the limits and the totals.
fn assemble<M: Backend>(
    scene: &SceneFile,
    opts: &EvalOptions,
    tolerance: u64,
    replayed: Replayed,
    noise: NoiseEstimate,
    t: Tally,
    limits: Limits,
) -> Evaluation {
    let k = scene.classes.len();
    let forced_choice_accuracy = t.weighted(|c| c.forced_right);
    let forced_choice_std_error = t.forced_choice_std_error();
    let (detected, decided) = (t.weighted(|c| c.detected), t.weighted(|c| c.decided));
    let decided_wrong = t.weighted(|c| c.decided - c.decided_right);
    let names = scene.classes.iter().map(|c| c.name.clone());
    let extra = ["ambiguous", "out_of_envelope", "rejected", "missed"].map(String::from);
    let priors = scene.class_probabilities();
    let m = &opts.chain_mismatch;
    let Limits {
        bayes, reference, ..
    } = limits;
    Evaluation {
        scene: scene.name.clone(),
        classes: names.clone().collect(),
        backend: M::NAME,
        n_per_class: opts.n_per_class,
        seed: opts.seed,
        impacts_per_stream: opts.impacts_per_stream,
        match_tolerance_samples: tolerance,
        yields: scene.yields(),
        columns: names.chain(extra).collect(),
        forced_choice_accuracy,
        forced_choice_std_error,
        coverage: ratio(decided, detected),
        confident_error_rate: ratio(decided_wrong, decided),
        ambiguous_share: t.column_share(k),
        out_of_envelope_share: t.column_share(k + 1),
        rejected_share: t.column_share(k + 2),
        missed_share: t.column_share(k + 3),
        spurious_reports: replayed.spurious,
        equaliser_noise_gain: limits.equaliser_noise_gain,
        chain_mismatch: [m.frequency, m.damping, m.gain],
        chain_drawn: opts.chain_drawn,
        confidence_threshold: limits.confidence_threshold,
        kernel_vs_reference: Paired {
            difference: forced_choice_accuracy - reference.accuracy,
            std_error: forced_choice_std_error.hypot(reference.std_error),
        },
        reference,
        by_peak_over_noise: by_peak_over_noise(
            scene,
            &replayed.outcomes,
            limits.equaliser_noise_gain,
            k,
        ),
        reliability: reliability(replayed.outcomes.iter().filter_map(|o| {
            let w = priors[o.class] / opts.n_per_class as f64;
            o.posterior.map(|p| (p, o.forced == Some(o.class), w))
        })),
        kernel_noise_bayes_accuracy: bayes.accuracy,
        kernel_noise_bayes_std_error: bayes.std_error,
        kernel_noise_bayes_draws: bayes.n,
        kernel_bayes_error: limits.kernel_bayes_error,
        oracle_accuracy: t.weighted(|c| c.oracle_right),
        bayes_on_measured_accuracy: t.weighted(|c| c.bayes_measured_right),
        bayes_on_measured_debiased_accuracy: t.weighted(|c| c.bayes_debiased_right),
        kernel_vs_bayes_on_measured: t.paired(0, 1),
        bias_loss: t.paired(1, 2),
        measured_vs_oracle: t.paired(2, 3),
        noise,
        confusion: t.confusion,
        forced_confusion: t.forced_confusion,
        rejected_by_reason: replayed.rejected_by_reason,
        per_class: t.per_class,
        samples_fed: replayed.samples_fed,
        pulses_detected: replayed.pulses_detected,
        kernel_seconds: replayed.kernel_seconds,
        kernel_ns_per_sample: ratio(replayed.kernel_seconds * 1e9, replayed.samples_fed as f64),
    }
}

/// One stream: the class of each of its impacts, simulated and replayed.
#[derive(Debug, PartialEq)]
struct StreamJob {
    /// The stream's class, or the number of classes for a stream that mixes them.
    tag: usize,
    /// Index of the stream within its tag.
    chunk: usize,
    /// The class of each impact, in stream order (a byte each: at most `MAX_CLASSES`).
    classes: Vec<u8>,
}

/// Mixed into the seed of the shuffle that interleaves the classes (`stream_jobs`).
const INTERLEAVE_SEED: u64 = 0x1E7E_A5ED;

/// The streams of an evaluation: `n_per_class` impacts of each of `k` classes in streams of
/// at most `impacts_per_stream`. Behind a rigid chain a pulse carries nothing of the impacts
/// before it, and each stream holds one class (tag `c`). Behind a chain that rings, every
/// impact rides on the ringing the ones before it left, which would tell its class if they
/// were of its class too; there the `k n_per_class` impacts are shuffled (seeded by `seed`),
/// so that an impact's neighbours are drawn independently of its class, and cut into streams
/// (tag `k`).
fn stream_jobs(k: usize, opts: &EvalOptions, rigid_chain: bool) -> Vec<StreamJob> {
    let per = opts.impacts_per_stream.max(1);
    let k = k.min(MAX_CLASSES);
    if rigid_chain {
        let mut jobs = Vec::new();
        for (class, byte) in (0..k).zip(0u8..) {
            let (mut left, mut chunk) = (opts.n_per_class, 0);
            while left > 0 {
                let n = left.min(per);
                jobs.push(StreamJob {
                    tag: class,
                    chunk,
                    classes: vec![byte; n],
                });
                left -= n;
                chunk += 1;
            }
        }
        return jobs;
    }
    let mut all: Vec<u8> = (0u8..)
        .take(k)
        .flat_map(|c| std::iter::repeat_n(c, opts.n_per_class))
        .collect();
    all.shuffle(&mut ChaCha8Rng::seed_from_u64(mix(
        opts.seed ^ INTERLEAVE_SEED
    )));
    all.chunks(per)
        .enumerate()
        .map(|(chunk, classes)| StreamJob {
            tag: k,
            chunk,
            classes: classes.to_vec(),
        })
        .collect()
}

/// What one stream contributes to the evaluation.
struct ChunkResult {
    impacts: usize,
    outcomes: Vec<Outcome>,
    /// Reason of every rejected verdict, in stream order.
    rejected: Vec<&'static str>,
    samples_fed: u64,
    pulses_detected: u64,
    spurious: u64,
    kernel_seconds: f64,
}

/// Simulates stream `job` (seed from `(opts.seed, tag, chunk)`), replays it through a fresh
/// `Monitor` and scores every impact.
fn run_stream<const N: usize, M: Backend + Send + Sync>(
    scene: &SceneFile,
    opts: &EvalOptions,
    kernel_scene: &coalshock::Scene<N, M>,
    models: &[ClassModel],
    tolerance: u64,
    job: &StreamJob,
) -> Result<ChunkResult, EvalError> {
    let classes: Vec<usize> = job.classes.iter().map(|&c| usize::from(c)).collect();
    let stream = generate_classes(
        scene,
        &classes,
        stream_seed(opts.seed, job.tag, job.chunk),
        &opts.stream,
    )?;
    let mut monitor: Monitor<N, M> = Monitor::new(kernel_scene.clone());
    let start = Instant::now();
    let events = replay_events(&stream, &mut monitor);
    let kernel_seconds = start.elapsed().as_secs_f64();
    let reports: Vec<_> = events
        .into_iter()
        .filter_map(|e| match e {
            Event::Pulse(r) => Some(r),
            Event::Stuck { .. } | Event::Flow(_) => None,
        })
        .collect();
    let matching = match_truth(&reports, &stream.truth, tolerance);
    let mut report_of = vec![None; stream.truth.len()];
    for p in &matching.pairs {
        report_of[p.truth] = Some(p.report);
    }
    let mut outcomes = Vec::with_capacity(classes.len());
    let mut rejected = Vec::new();
    for (t, rep) in stream.truth.iter().zip(report_of) {
        let report = rep.map(|i| &reports[i]);
        let mut o = outcome_of(models, t.class, t, report, &mut rejected);
        o.z = report
            .and_then(|r| r.measurement)
            .and_then(|m| located_z(kernel_scene, t, &m));
        outcomes.push(o);
    }
    Ok(ChunkResult {
        impacts: classes.len(),
        outcomes,
        rejected,
        samples_fed: monitor.samples_fed(),
        pulses_detected: reports.len() as u64,
        spurious: matching.unmatched_reports.len() as u64,
        kernel_seconds,
    })
}

/// The outcome of impact `t` of class `class`: the oracle's decision on its closed-form Hertz
/// features, and the kernel's verdict and measurement from its paired `report` (none: missed);
/// a rejected verdict's reason goes onto `rejected`.
fn outcome_of(
    models: &[ClassModel],
    class: usize,
    t: &Truth,
    report: Option<&Report>,
    rejected: &mut Vec<&'static str>,
) -> Outcome {
    let k = models.len();
    let (col_amb, col_out, col_rej, col_miss) = (k, k + 1, k + 2, k + 3);
    let (lf, lt) = models[class].forward(t.radius_m.ln(), t.speed_m_s.ln());
    let oracle = decide(models, lf, lt, None);
    let true_ln = (t.peak_force_n.ln(), t.duration_s.ln());
    let mut o = Outcome {
        class,
        hertz_ln: (lf, lt),
        true_ln,
        measured: None,
        column: col_miss,
        forced: None,
        posterior: None,
        oracle,
        z: None,
    };
    if let Some(r) = report {
        o.forced = r.verdict.forced_choice().map(usize::from);
        o.posterior = match r.verdict {
            Verdict::Class { posterior, .. } | Verdict::Ambiguous { posterior, .. } => {
                Some(posterior as f64)
            }
            _ => None,
        };
        o.column = match r.verdict {
            Verdict::Class { class, .. } => class as usize,
            Verdict::Ambiguous { .. } => col_amb,
            Verdict::OutOfEnvelope { .. } => col_out,
            Verdict::Rejected(reason) => {
                rejected.push(reason.name());
                col_rej
            }
        };
        o.measured = r.measurement.map(|m| {
            let m = measurement_from_kernel(&m);
            MeasuredLn {
                ln_force: m.peak_force_n.ln(),
                ln_duration: m.duration_s.ln(),
                sigma_ln_force: m.sigma_ln_force,
                sigma_ln_duration: m.sigma_ln_duration,
            }
        });
    }
    o
}

/// The table by peak over noise ([`crate::score::peak_snr`]): the force noise the detector
/// sees is the ADC's noise RMS through the equaliser, `noise_rms_counts * gain *
/// effective_mass_kg / counts_per_m_s2` (N).
fn by_peak_over_noise(
    scene: &SceneFile,
    outcomes: &[Outcome],
    equaliser_noise_gain: f64,
    k: usize,
) -> PeakSnrTable {
    let s = &scene.sensor;
    let noise_force_n =
        s.noise_rms_counts * equaliser_noise_gain * s.effective_mass_kg / s.counts_per_m_s2;
    PeakSnrTable::of(
        noise_force_n,
        outcomes.iter().map(|o| PeakRow {
            peak_over_noise: o.true_ln.0.exp() / noise_force_n,
            detected: o.column != k + 3,
            confident: (o.column < k).then_some(o.column == o.class),
            error_ln: o
                .measured
                .map(|m| (m.ln_force - o.hertz_ln.0, m.ln_duration - o.hertz_ln.1)),
            z: o.z,
        }),
    )
}

/// Impact `t`'s measurement `m` located in its true class's `(ln R, ln u)`
/// (`coalshock::Scene::located`), its errors over the sigmas the classifier weighed it on.
fn located_z<const N: usize, M: Backend>(
    scene: &coalshock::Scene<N, M>,
    t: &Truth,
    m: &coalshock::Measurement,
) -> Option<(f64, f64)> {
    let (x, y, noise) = scene.located(u8::try_from(t.class).ok()?, m)?;
    Some((
        (x as f64 - t.radius_m.ln()) / noise.sigma_x as f64,
        (y as f64 - t.speed_m_s.ln()) / noise.sigma_y as f64,
    ))
}

/// `a / b`, 0 when `b = 0`.
fn share(a: u64, b: u64) -> f64 {
    if b == 0 { 0.0 } else { a as f64 / b as f64 }
}

/// The feature noise and the error statistics (see [`NoiseEstimate`]).
fn estimate_noise(outcomes: &[Outcome], col_rej: usize) -> NoiseEstimate {
    let measured: Vec<(&Outcome, MeasuredLn)> = outcomes
        .iter()
        .filter(|o| o.column < col_rej)
        .filter_map(|o| o.measured.map(|m| (o, m)))
        .collect();
    let vs_hertz = ErrorStats::of(
        measured
            .iter()
            .map(|(o, m)| (m.ln_force - o.hertz_ln.0, m.ln_duration - o.hertz_ln.1)),
    );
    let n = measured.len();
    let mean = |f: &dyn Fn(&MeasuredLn) -> f64| {
        measured.iter().map(|(_, m)| f(m)).sum::<f64>() / n.max(1) as f64
    };
    let enough = n >= MIN_PULSES_FOR_NOISE;
    NoiseEstimate {
        source: if enough { "measured_vs_hertz" } else { "none" },
        sigma_ln_force: if enough { vs_hertz.sigma_ln_force } else { 0.0 },
        sigma_ln_duration: if enough {
            vs_hertz.sigma_ln_duration
        } else {
            0.0
        },
        correlation: if enough { vs_hertz.correlation } else { 0.0 },
        measured_vs_hertz: vs_hertz,
        measured_vs_pulse: ErrorStats::of(
            measured
                .iter()
                .map(|(o, m)| (m.ln_force - o.true_ln.0, m.ln_duration - o.true_ln.1)),
        ),
        pulse_vs_hertz: ErrorStats::of(
            outcomes
                .iter()
                .map(|o| (o.true_ln.0 - o.hertz_ln.0, o.true_ln.1 - o.hertz_ln.1)),
        ),
        kernel_sigma_ln_force: mean(&|m| m.sigma_ln_force),
        kernel_sigma_ln_duration: mean(&|m| m.sigma_ln_duration),
        stated_noise_check: StatedNoiseCheck::of(measured.iter().filter_map(|(o, _)| o.z)),
    }
}

/// A share as a percentage, `7.3` wide with its unit (`" 76.309 %"`).
fn pct(v: f64) -> String {
    format!("{:7.3} %", 100.0 * v)
}

impl Evaluation {
    /// The evaluation as human-readable tables (what `host-sim evaluate` prints without
    /// `--json`): the header, the confusion matrices, the kernel's rates, its feature errors,
    /// the reference limit, the diagnostics, the paired losses and the run's figures.
    pub fn table(&self) -> String {
        let mut s = String::new();
        self.header_text(&mut s);
        self.confusion_text(&mut s);
        self.kernel_text(&mut s);
        self.feature_error_text(&mut s);
        s += &self.by_peak_over_noise.text();
        s += &self.reference_table();
        self.diagnostics_text(&mut s);
        self.paired_loss_text(&mut s);
        self.run_text(&mut s);
        s
    }

    /// The scene, its classes, the impacts, seed and backend.
    fn header_text(&self, s: &mut String) {
        let _ = writeln!(
            s,
            "scene {} ({} classes), {} impacts per class, seed {}, backend {}",
            if self.scene.is_empty() {
                "(unnamed)"
            } else {
                &self.scene
            },
            self.classes.len(),
            self.n_per_class,
            self.seed,
            self.backend
        );
    }

    /// The verdicts' and the forced choice's confusion matrices, and the rejections by reason.
    fn confusion_text(&self, s: &mut String) {
        let width = self
            .columns
            .iter()
            .map(|c| c.len())
            .chain(std::iter::once(10))
            .max()
            .unwrap_or(10)
            + 2;
        let matrix = |s: &mut String, title: &str, cols: &[String], rows: &[Vec<u64>]| {
            let _ = writeln!(s, "\n{title}");
            let _ = write!(s, "{:<width$}", "true \\ kernel");
            for c in cols {
                let _ = write!(s, "{c:>width$}");
            }
            let _ = writeln!(s);
            for (name, row) in self.classes.iter().zip(rows) {
                let _ = write!(s, "{name:<width$}");
                for v in row {
                    let _ = write!(s, "{v:>width$}");
                }
                let _ = writeln!(s);
            }
        };
        matrix(s, "verdicts", &self.columns, &self.confusion);
        let mut forced_cols = self.classes.clone();
        forced_cols.push("none".into());
        matrix(
            s,
            "forced choice (none: rejected or missed)",
            &forced_cols,
            &self.forced_confusion,
        );
        if !self.rejected_by_reason.is_empty() {
            let reasons: Vec<String> = self
                .rejected_by_reason
                .iter()
                .map(|(r, n)| format!("{r} {n}"))
                .collect();
            let _ = writeln!(s, "rejected: {}", reasons.join(", "));
        }
    }

    /// The kernel's forced-choice accuracy (overall and per class), coverage and rates.
    fn kernel_text(&self, s: &mut String) {
        let _ = writeln!(s, "\nkernel");
        let _ = writeln!(
            s,
            "  forced-choice accuracy      {} +- {:.3} %",
            pct(self.forced_choice_accuracy),
            100.0 * self.forced_choice_std_error
        );
        for c in &self.per_class {
            let _ = writeln!(s, "    {:<24}  {}", c.name, pct(c.forced_choice_accuracy));
        }
        let _ = writeln!(s, "  coverage (decided)          {}", pct(self.coverage));
        let _ = writeln!(
            s,
            "  confident-error rate        {}",
            pct(self.confident_error_rate)
        );
        let _ = writeln!(
            s,
            "  ambiguous / out / rejected / missed   {} / {} / {} / {}",
            pct(self.ambiguous_share).trim(),
            pct(self.out_of_envelope_share).trim(),
            pct(self.rejected_share).trim(),
            pct(self.missed_share).trim()
        );
        let _ = writeln!(s, "  spurious reports            {}", self.spurious_reports);
    }

    /// The errors of the kernel's features against the Hertz and the simulated pulse.
    fn feature_error_text(&self, s: &mut String) {
        let n = &self.noise;
        let _ = writeln!(s, "\nfeature errors, ln(measured) - ln(reference)");
        let _ = writeln!(
            s,
            "  {:<26}{:>8}{:>10}{:>10}{:>10}{:>10}{:>10}{:>8}",
            "", "pulses", "bias F", "sigma F", "worst F", "bias t_c", "sigma t_c", "corr"
        );
        for (what, e) in [
            ("kernel vs Hertz", &n.measured_vs_hertz),
            ("kernel vs simulated pulse", &n.measured_vs_pulse),
            ("simulated pulse vs Hertz", &n.pulse_vs_hertz),
        ] {
            let _ = writeln!(
                s,
                "  {what:<26}{:>8}{:>+10.4}{:>10.4}{:>10.4}{:>+10.4}{:>10.4}{:>+8.3}",
                e.pulses,
                e.bias_ln_force,
                e.sigma_ln_force,
                e.worst_ln_force,
                e.bias_ln_duration,
                e.sigma_ln_duration,
                e.correlation
            );
        }
        let _ = writeln!(
            s,
            "  the kernel's own sigma: F {:.4}, t_c {:.4} (mean over its measurements)",
            n.kernel_sigma_ln_force, n.kernel_sigma_ln_duration
        );
        let _ = write!(s, "\n{}", n.stated_noise_check.text());
    }

    /// The f64 diagnostics at the kernel's measured noise.
    fn diagnostics_text(&self, s: &mut String) {
        let _ = writeln!(s, "\ndiagnostics (f64, at the kernel's measured noise)");
        if self.yields {
            let _ = writeln!(
                s,
                "  (on the elastic Hertz features: this scene's classes yield, so these figures \
                 are not its physics; its limit is the reference limit above)"
            );
        }
        let _ = writeln!(
            s,
            "  Bayes at the kernel's noise {} +- {:.3} % ({} draws)",
            pct(self.kernel_noise_bayes_accuracy),
            100.0 * self.kernel_noise_bayes_std_error,
            self.kernel_noise_bayes_draws
        );
        let _ = writeln!(
            s,
            "  oracle (exact F, t_c)       {}   (kernel's noiseless grid: {})",
            pct(self.oracle_accuracy),
            pct(1.0 - self.kernel_bayes_error).trim()
        );
        let _ = writeln!(
            s,
            "  Bayes on kernel measurement {}",
            pct(self.bayes_on_measured_accuracy)
        );
        let _ = writeln!(
            s,
            "    same, bias removed        {}",
            pct(self.bayes_on_measured_debiased_accuracy)
        );
    }

    /// The paired losses on the same impacts.
    fn paired_loss_text(&self, s: &mut String) {
        let _ = writeln!(s, "\npaired losses (same impacts)");
        if self.yields {
            let _ = writeln!(
                s,
                "  (on the elastic Hertz features, as the diagnostics above)"
            );
        }
        let paired = |s: &mut String, what: &str, p: &Paired| {
            let _ = writeln!(
                s,
                "  {what:<52} {:+.3} +- {:.3} %",
                100.0 * p.difference,
                100.0 * p.std_error
            );
        };
        paired(
            s,
            "measurement (Bayes on measured, debiased - oracle)",
            &self.measured_vs_oracle,
        );
        paired(
            s,
            "constant bias (Bayes on measured - debiased)",
            &self.bias_loss,
        );
        paired(
            s,
            "kernel classifier (kernel - Bayes on measured)",
            &self.kernel_vs_bayes_on_measured,
        );
    }

    /// The chain given to the kernel and the samples, pulses and time of the run.
    fn run_text(&self, s: &mut String) {
        let [mf, md, mg] = self.chain_mismatch;
        let _ = writeln!(
            s,
            "\nequaliser noise gain {:.4}; chain given to the kernel off by frequency {:+}, \
             damping {:+}, gain {:+} (relative)",
            self.equaliser_noise_gain, mf, md, mg
        );
        if self.chain_drawn {
            let _ = writeln!(
                s,
                "each stream's kernel given a chain drawn within the scene's chain tolerance"
            );
        }
        let _ = writeln!(
            s,
            "{} samples fed, {} pulses reported, {:.4} s in the kernel ({:.1} ns per sample)",
            self.samples_fed, self.pulses_detected, self.kernel_seconds, self.kernel_ns_per_sample
        );
    }
}

impl Evaluation {
    /// The reference limit, the kernel against it, and the reliability table, as text.
    fn reference_table(&self) -> String {
        let r = &self.reference;
        let d = &self.kernel_vs_reference;
        format!(
            "\nreference limit (physics and the scene's stated noise, independent of the kernel)\n\
             \x20 reference limit             {:7.3} % +- {:.3} % ({} draws, {} features, \
             duration {:?}, Cramer-Rao sigma ln F {:.4}, ln t_c {:.4})\n\
             \x20 noiseless ceiling           {:7.3} % +- {:.3} %\n\
             \x20 found at the limit          {:7.3} % (matched filter at {} noise RMS: the \
             trigger's false-alarm rate)\n\
             \x20 coverage at the limit       {:7.3} % (Bayes posterior >= {:.4} under the \
             scene's priors; {:.3} % of those wrong)\n\
             \x20 kernel - reference          {:+7.3} pp +- {:.3} pp\n\
             \nreliability (confidence threshold {:.4}: confident errors at most {:.2} %)\n{}",
            100.0 * r.accuracy,
            100.0 * r.std_error,
            r.draws,
            r.features,
            r.duration_feature,
            r.mean_sigma_ln_force,
            r.mean_sigma_ln_duration,
            100.0 * r.noiseless_accuracy,
            100.0 * r.noiseless_std_error,
            100.0 * r.detected_share,
            r.detection_sigmas,
            100.0 * r.coverage,
            r.confidence_threshold,
            100.0 * r.confident_error_rate,
            100.0 * d.difference,
            100.0 * d.std_error,
            self.confidence_threshold,
            100.0 * (1.0 - self.confidence_threshold),
            self.reliability.table()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(n_per_class: usize) -> EvalOptions {
        EvalOptions {
            n_per_class,
            impacts_per_stream: 250,
            ..EvalOptions::default()
        }
    }

    /// Every class's `n_per_class` impacts, each once.
    fn counts(jobs: &[StreamJob], k: usize) -> Vec<usize> {
        let mut c = vec![0; k];
        for &class in jobs.iter().flat_map(|j| &j.classes) {
            c[usize::from(class)] += 1;
        }
        c
    }

    #[test]
    fn a_rigid_chain_keeps_one_class_per_stream() {
        let jobs = stream_jobs(2, &opts(600), true);
        assert_eq!(counts(&jobs, 2), [600, 600]);
        assert_eq!(jobs.len(), 6);
        assert!(
            jobs.iter()
                .all(|j| j.classes.iter().all(|&c| usize::from(c) == j.tag))
        );
        assert!(jobs.iter().all(|j| j.classes.len() <= 250));
    }

    #[test]
    fn behind_a_ringing_chain_an_impact_s_neighbour_is_independent_of_its_class() {
        let (k, n) = (3, 4000);
        let jobs = stream_jobs(k, &opts(n), false);
        assert_eq!(counts(&jobs, k), [n; 3]);
        assert!(jobs.iter().all(|j| j.tag == k && j.classes.len() <= 250));
        // Of consecutive impacts in a stream, a share 1/k are of one class when the order is
        // independent of the class (one class per stream: all of them). The count of such
        // pairs is binomial; 5 standard errors.
        let pairs: Vec<bool> = jobs
            .iter()
            .flat_map(|j| j.classes.windows(2).map(|w| w[0] == w[1]))
            .collect();
        let same = pairs.iter().filter(|&&b| b).count() as f64;
        let m = pairs.len() as f64;
        let p = 1.0 / k as f64;
        assert!(
            (same / m - p).abs() < 5.0 * (p * (1.0 - p) / m).sqrt(),
            "{same} of {m}"
        );
        // One seed, one layout; another seed, another.
        assert_eq!(jobs, stream_jobs(k, &opts(n), false));
        let other = EvalOptions { seed: 2, ..opts(n) };
        assert_ne!(jobs, stream_jobs(k, &other, false));
    }
}
