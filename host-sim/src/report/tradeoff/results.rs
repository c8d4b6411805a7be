//! `host-sim tradeoff`, the result: one row type per knob (backend, grid, integrator, sample
//! rate), the kernel's sizes, the f64 separability reference, and the whole study.

use coalshock::counters::Counters;
use coalshock::detector::Detector;
use coalshock::envelope::Envelope;
use coalshock::math::Libm;
use coalshock::scene::DEFAULT_CLASSES;
use coalshock::{Monitor, Scene};
use serde::Serialize;

use crate::report::tradeoff::config::TradeoffConfig;
use crate::report::tradeoff::firmware::{FirmwareFigures, M4Figures};

/// Forced-choice accuracy and friends of one scene ([`crate::score::evaluate`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneAccuracy {
    /// Scene name.
    pub scene: String,
    /// Share of impacts whose pulse got the right class when forced to choose.
    pub forced_choice: f64,
    /// Share of impacts with a confident class verdict.
    pub coverage: f64,
    /// Share of confident verdicts that are wrong.
    pub confident_error_rate: f64,
    /// The Bayes limit with the measurement noise (best achievable forced-choice accuracy).
    pub bayes_accuracy: f64,
    /// The Bayes limit on exact `(F_max, t_c)`.
    pub oracle_accuracy: f64,
    /// Samples fed to the kernel.
    pub samples_fed: f64,
    /// Pulses the kernel detected.
    pub pulses_detected: f64,
}

/// Section 1: one math backend.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BackendRow {
    /// `libm` or `micromath`.
    pub backend: &'static str,
    /// Host ns per quiet sample through `Monitor::feed`.
    pub quiet_ns: f64,
    /// Host ns per quiet sample through `Monitor::feed_slice`
    /// ([`BLOCK_SAMPLES`](crate::report::tradeoff::config::BLOCK_SAMPLES) a call).
    pub quiet_block_ns: f64,
    /// Host ns per classified pulse beyond the quiet cost of its samples:
    /// `(T_stream - N_samples t_quiet) / pulses`.
    pub pulse_ns: f64,
    /// Classified pulses in the timing stream.
    pub timed_pulses: usize,
    /// Host us per build of the paper scene.
    pub build_us: f64,
    /// Largest `|F_max / F_ref - 1|` over the paper scene's classes and ranges.
    pub max_rel_err_force: f64,
    /// Largest `|t_c / t_ref - 1|` over the same points.
    pub max_rel_err_duration: f64,
    /// Points of the closed-form grid.
    pub closed_form_points: usize,
    /// Accuracy on each scene.
    pub accuracy: Vec<SceneAccuracy>,
    /// Cortex-M4F instruction counts.
    pub m4: M4Figures,
}

/// Section 2: one separability grid size on the paper scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GridRow {
    /// Cells per side.
    pub grid: u16,
    /// Host us per build of the paper scene (libm).
    pub build_us: f64,
    /// The kernel's Bayes error (noiseless).
    pub bayes_error: f64,
    /// The kernel's overlap share.
    pub overlap: f64,
    /// `|bayes_error - reference|`.
    pub bayes_error_err: f64,
    /// `|overlap - reference|`.
    pub overlap_err: f64,
    /// Cortex-M4F instructions of the build, estimated as the measured count at 48 rows
    /// times this grid's host build time over the 48-row one.
    pub m4_build_insns_est: f64,
}

/// Sizes of the kernel types in bytes (`size_of`, host target, `DEFAULT_CLASSES` classes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct KernelSizes {
    /// `Scene<4, Libm>`.
    pub scene: usize,
    /// `Monitor<4, Libm>`.
    pub monitor: usize,
    /// `Detector<Libm>`.
    pub detector: usize,
    /// `Counters<4>`.
    pub counters: usize,
    /// One `Envelope`.
    pub envelope: usize,
}

impl KernelSizes {
    /// `size_of` of each type: properties of the types, so the same for every grid size.
    pub fn measure() -> Self {
        Self {
            scene: size_of::<Scene<DEFAULT_CLASSES, Libm>>(),
            monitor: size_of::<Monitor<DEFAULT_CLASSES, Libm>>(),
            detector: size_of::<Detector<Libm>>(),
            counters: size_of::<Counters<DEFAULT_CLASSES>>(),
            envelope: size_of::<Envelope>(),
        }
    }
}

/// The f64 reference of the paper scene's separability.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SeparabilityReference {
    /// Bayes error from the midpoint integral on the reference grid.
    pub bayes_error: f64,
    /// Overlap share from the same integral.
    pub overlap: f64,
    /// Cells per side.
    pub grid: usize,
    /// Bayes error from the Monte Carlo oracle of [`crate::score::bayes::bayes_accuracy`].
    pub mc_bayes_error: f64,
    /// Its standard error.
    pub mc_std_error: f64,
}

/// Section 3: one integrator configuration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IntegratorRow {
    /// `dopri5` or `rk4`.
    pub method: &'static str,
    /// Label (`dopri5 rtol 1e-6`, `rk4 50 steps per t_c`).
    pub label: String,
    /// The tolerance (Dopri5) or the steps per contact time (RK4).
    pub setting: f64,
    /// Impacts integrated per second (host).
    pub impacts_per_s: f64,
    /// Largest `|F_max / F_closed - 1|`.
    pub max_rel_err_force: f64,
    /// Largest `|t_c / t_closed - 1|`.
    pub max_rel_err_duration: f64,
    /// Mean force evaluations per impact.
    pub force_evals: f64,
    /// Problems integrated.
    pub problems: usize,
}

/// Section 4: one sample rate on one scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RateRow {
    /// Sample rate in Hz.
    pub sample_rate_hz: f64,
    /// Samples across the scene's shortest Hertz pulse (`t_c,min f_s`).
    pub samples_per_shortest_pulse: f64,
    /// Accuracy.
    pub accuracy: SceneAccuracy,
    /// Host ns of kernel work per second of signal (`feed_slice` replay of a stream of the
    /// scene at this rate).
    pub host_ns_per_signal_s: f64,
    /// Pulses per second of that stream.
    pub pulses_per_s: f64,
    /// Estimated Cortex-M4F instructions per second of signal
    /// ([`m4_instructions_per_second`](super::firmware::m4_instructions_per_second)).
    pub m4_insns_per_signal_s: f64,
}

/// Everything `host-sim tradeoff` measures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tradeoff {
    /// What was measured.
    pub config: TradeoffConfig,
    /// Where the scenes came from.
    pub scene_sources: Vec<String>,
    /// Section 1.
    pub backends: Vec<BackendRow>,
    /// Section 2.
    pub grids: Vec<GridRow>,
    /// Section 2: type sizes.
    pub sizes: KernelSizes,
    /// Section 2: the reference.
    pub reference: SeparabilityReference,
    /// Section 3.
    pub integrator: Vec<IntegratorRow>,
    /// Section 4: `(scene name, rows)`.
    pub rates: Vec<(String, Vec<RateRow>)>,
    /// Sample rates the kernel refused for a scene, with its reason.
    pub refused_rates: Vec<(String, f64, String)>,
    /// The firmware figures used.
    pub firmware: FirmwareFigures,
    /// Wall time of the whole computation in s.
    pub runtime_s: f64,
}
