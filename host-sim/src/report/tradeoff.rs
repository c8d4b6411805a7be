//! `host-sim tradeoff`: what each knob of the kernel and of the simulation buys and what it
//! costs, measured in one run.
//!
//! 1. **Math backend** (`Libm` against `Micromath`): host time per quiet sample (through
//!    `Monitor::feed` and through `Monitor::feed_slice` in blocks of [`BLOCK_SAMPLES`]), per
//!    classified pulse and per scene build; the largest relative error of the kernel's `F_max`
//!    and `t_c` over the paper scene's classes and ranges against host-sim's f64 closed forms
//!    ([`crate::physics::hertz64`]); forced-choice accuracy on the paper and narrow scenes
//!    ([`crate::score::evaluate`]); the Cortex-M4F instruction counts beside them.
//! 2. **Separability grid** (`Settings::separability_grid`): scene build time, the size of the
//!    kernel types, and the error of the kernel's `bayes_error` and `overlap_share` against an
//!    independent f64 computation from [`crate::score::bayes`].
//! 3. **Integrator method and tolerance**: impacts per second against the largest relative
//!    error of `F_max` and `t_c` (undamped Hertz, over the paper scene's range) for the ladder
//!    of [`crate::physics::integrator_cases`].
//! 4. **Sample rate**: accuracy against the kernel's work per second of signal, on the host
//!    (measured) and on a Cortex-M4F (estimated from the firmware's instruction counts).
//!
//! Host times are the minimum over several repetitions measured with [`Instant`] in this
//! process: they are printed, never asserted, and mean something only in a release build.
//! Every figure goes into the markdown table ([`render_table`]), the long-format
//! [`METRICS_CSV`], the [`PARETO_CSV`] of the cost-loss points, and the [`SVG_FILES`].

use std::fmt::Write as _;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use coalshock::counters::Counters;
use coalshock::detector::Detector;
use coalshock::envelope::Envelope;
use coalshock::math::{Backend, Libm, Micromath};
use coalshock::scene::DEFAULT_CLASSES;
use coalshock::{Event, Monitor, Scene, Verdict};
use plotters::style::RGBColor;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::bridge::convert::{
    duration_bounds_from_kernel, kernel_impact_in, scene_to_kernel_in, separability_from_kernel,
};
use crate::physics::hertz64::{HertzImpact64, Material64};
use crate::physics::integrate::{ContactProblem, Method};
use crate::physics::integrator_cases::{MethodCase, ladder, relative_errors, undamped_problem};
use crate::report::paper::{Curve, Stroke, draw_svg};
use crate::scene::{self, SceneFile};
use crate::score::bayes::{ClassModel, bayes_accuracy};
use crate::score::evaluate::{EvalOptions, class_models, evaluate};
use crate::score::replay::replay_events;
use crate::sim::generate::generate;
use crate::sim::stream::{PulseModel, Stream, StreamOptions};

/// Samples per `Monitor::feed_slice` call when timing the block entry (the firmware's FIFO
/// block, `fw/budgets.txt`).
pub const BLOCK_SAMPLES: usize = 256;

/// Sample rate in Hz at which the firmware's instruction counts were measured (the paper
/// scene's sensor, `fw/README.md`).
pub const FIRMWARE_SAMPLE_RATE_HZ: f64 = 100_000.0;

/// The long-format CSV: one row per figure (`knob, setting, scene, metric, value, unit`).
pub const METRICS_CSV: &str = "tradeoff.csv";

/// The CSV of the Pareto plots: one row per point with its cost, its loss and whether it is on
/// the front of its plot and series.
pub const PARETO_CSV: &str = "pareto.csv";

/// The markdown table, as printed.
pub const TABLE_MD: &str = "tradeoff.md";

/// The SVG Pareto plots.
pub const SVG_FILES: [&str; 4] = [
    "pareto_backend.svg",
    "pareto_grid.svg",
    "pareto_integrator.svg",
    "pareto_sample_rate.svg",
];

/// Flags of `host-sim tradeoff`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct TradeoffArgs {
    /// Directory for the table, the CSV files and the SVG plots (created if missing).
    #[arg(long, default_value = "target/tradeoff")]
    pub out: PathBuf,
    /// A small, fast run (for tests): fewer impacts, grid sizes, tolerances and sample rates.
    #[arg(long)]
    pub quick: bool,
    /// Seed of every random draw (streams, Monte Carlo).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The firmware check's `measures.txt` (`fw/measure.sh`, run by `bash fw/ci.sh`). Default:
    /// `$FW_OUT/measures.txt`, else `fw/measures.txt` under the cargo target directory
    /// (`$CARGO_TARGET_DIR`, the one this binary was built in, or `target/`); the command fails
    /// when there is none.
    #[arg(long)]
    pub fw_measures: Option<PathBuf>,
}

impl Default for TradeoffArgs {
    /// The clap defaults: `target/tradeoff`, full run, seed 1, default firmware figures.
    fn default() -> Self {
        Self {
            out: PathBuf::from("target/tradeoff"),
            quick: false,
            seed: 1,
            fw_measures: None,
        }
    }
}

/// What to measure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TradeoffConfig {
    /// Seed of every random draw.
    pub seed: u64,
    /// Impacts per class of every accuracy evaluation.
    pub eval_n_per_class: usize,
    /// Repetitions of every timing (the minimum is kept).
    pub timing_reps: usize,
    /// Length in s of the noise-only stream the quiet-sample time is measured on (at the
    /// paper scene's 100 kS/s).
    pub quiet_stream_s: f64,
    /// Impacts in the stream the per-pulse time is measured on.
    pub timing_impacts: usize,
    /// Impacts in the stream of each sample rate's host timing.
    pub rate_timing_impacts: usize,
    /// Points per axis (`R` log-spaced, `u` linear) per class of the closed-form error grid.
    pub closed_form_points: usize,
    /// Separability grid sizes (midpoint rows along `ln u`, `Settings::separability_grid`) to
    /// build the paper scene with.
    pub grid_sizes: Vec<u16>,
    /// Cells per side of the f64 reference integral of the separability.
    pub reference_grid: usize,
    /// Impacts per class of the Monte Carlo cross-check of the Bayes error.
    pub bayes_mc_per_class: usize,
    /// Dormand-Prince tolerances of the integrator ladder.
    pub dopri5_tolerances: Vec<f64>,
    /// RK4 steps per contact time of the integrator ladder.
    pub rk4_steps: Vec<u32>,
    /// Points per axis (`R` log-spaced, `u` linear) per class of the integrator's problems.
    pub integrator_points: usize,
    /// Sample rates in Hz.
    pub sample_rates_hz: Vec<f64>,
}

impl TradeoffConfig {
    /// The full run (about a minute in a release build).
    pub fn full(seed: u64) -> Self {
        Self {
            seed,
            eval_n_per_class: 1000,
            timing_reps: 7,
            quiet_stream_s: 3.0,
            timing_impacts: 1000,
            rate_timing_impacts: 200,
            closed_form_points: 101,
            grid_sizes: vec![8, 16, 32, 48, 64, 96, 128, 192, 256],
            reference_grid: 4096,
            bayes_mc_per_class: 1_000_000,
            dopri5_tolerances: (3..=12).map(|e| 10f64.powi(-e)).collect(),
            rk4_steps: vec![10, 20, 50, 100, 200, 400],
            integrator_points: 5,
            sample_rates_hz: vec![
                10_000.0,
                26_700.0,
                50_000.0,
                100_000.0,
                200_000.0,
                500_000.0,
                1_000_000.0,
            ],
        }
    }

    /// The quick run of `--quick` and the tests (a few seconds in a debug build).
    pub fn quick(seed: u64) -> Self {
        Self {
            seed,
            eval_n_per_class: 40,
            timing_reps: 2,
            quiet_stream_s: 0.05,
            timing_impacts: 20,
            rate_timing_impacts: 10,
            closed_form_points: 9,
            grid_sizes: vec![8, 48, 192],
            reference_grid: 768,
            bayes_mc_per_class: 20_000,
            dopri5_tolerances: vec![1e-3, 1e-6, 1e-9],
            rk4_steps: vec![10, 50, 200],
            integrator_points: 2,
            sample_rates_hz: vec![10_000.0, 26_700.0, 1_000_000.0],
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Firmware figures
// ---------------------------------------------------------------------------------------------

/// Cortex-M4F instruction counts of one backend (release build, QEMU `netduinoplus2` with
/// `-icount shift=0`, the firmware's stand-in stream at 100 kS/s; `fw/README.md` defines each).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct M4Figures {
    /// Instructions per quiet sample through `Monitor::feed`, mean (`insns_quiet_sample_mean`).
    pub quiet_sample: f64,
    /// Instructions per quiet sample through `Monitor::feed_slice` in blocks of 256, mean
    /// (`insns_quiet_block_sample_mean`), when measured.
    pub quiet_block_sample: Option<f64>,
    /// Instructions of the `feed` call that classifies a pulse, mean (`insns_classify_mean`).
    pub classify: f64,
    /// Instructions of a whole pulse, trigger to verdict, mean (`insns_pulse_total_mean`),
    /// when measured.
    pub pulse_total: Option<f64>,
    /// Instructions of building the paper scene at the default 48-row grid
    /// (`insns_scene_build`).
    pub scene_build: f64,
}

/// The firmware's figures for both backends and where they come from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FirmwareFigures {
    /// The `measures.txt` read.
    pub source: String,
    /// The `libm` backend.
    pub libm: M4Figures,
    /// The `micromath` backend.
    pub micromath: M4Figures,
}

impl FirmwareFigures {
    /// Parses the firmware check's `measures.txt` (`key value` lines, `fw/measure.sh`): the
    /// `libm_` and `micromath_` keys `insns_quiet_sample_mean`, `insns_classify_mean`,
    /// `insns_scene_build`, and the optional `insns_quiet_block_sample_mean` and
    /// `insns_pulse_total_mean`.
    pub fn parse_measures(text: &str, source: &str) -> Result<Self> {
        let get = |key: &str| -> Option<f64> {
            text.lines().find_map(|l| {
                let mut it = l.split_whitespace();
                (it.next() == Some(key))
                    .then(|| it.next().and_then(|v| v.parse::<f64>().ok()))
                    .flatten()
            })
        };
        let backend = |prefix: &str| -> Result<M4Figures> {
            let need = |k: &str| {
                let key = format!("{prefix}{k}");
                get(&key).ok_or_else(|| anyhow!("{source}: no {key}"))
            };
            Ok(M4Figures {
                quiet_sample: need("insns_quiet_sample_mean")?,
                quiet_block_sample: get(&format!("{prefix}insns_quiet_block_sample_mean")),
                classify: need("insns_classify_mean")?,
                pulse_total: get(&format!("{prefix}insns_pulse_total_mean")),
                scene_build: need("insns_scene_build")?,
            })
        };
        Ok(Self {
            source: source.to_string(),
            libm: backend("libm_")?,
            micromath: backend("micromath_")?,
        })
    }

    /// Where the firmware check writes its measures when no file is given, in order:
    /// `$FW_OUT/measures.txt` (`fw/measure.sh` writes there when `FW_OUT` is set), then
    /// `fw/measures.txt` under `$CARGO_TARGET_DIR`, under the target directory this binary runs
    /// from (`<target>/<profile>/host-sim`), and under `target/` of the working directory.
    pub fn default_paths() -> Vec<PathBuf> {
        let mut paths: Vec<PathBuf> = Vec::new();
        if let Some(d) = std::env::var_os("FW_OUT") {
            paths.push(PathBuf::from(d).join("measures.txt"));
        }
        if let Some(d) = std::env::var_os("CARGO_TARGET_DIR") {
            paths.push(PathBuf::from(d).join("fw/measures.txt"));
        }
        if let Some(target) = std::env::current_exe()
            .ok()
            .and_then(|exe| Some(exe.parent()?.parent()?.to_path_buf()))
        {
            paths.push(target.join("fw/measures.txt"));
        }
        paths.push(PathBuf::from("target/fw/measures.txt"));
        let mut unique = Vec::new();
        for p in paths {
            if !unique.contains(&p) {
                unique.push(p);
            }
        }
        unique
    }

    /// The figures of `path` (an error if it cannot be read or lacks a key), else of the first
    /// of [`Self::default_paths`] that exists and parses (one that lacks a key, for example
    /// one being rewritten by a firmware run, is skipped with a warning on stderr). With no
    /// measures file at all it fails, naming the command that makes one: the firmware's
    /// figures are measured, never assumed.
    pub fn load(path: Option<&Path>) -> Result<Self> {
        match path {
            Some(p) => Self::load_from(Some(p), vec![p.to_path_buf()]),
            None => Self::load_from(None, Self::default_paths()),
        }
    }

    fn load_from(path: Option<&Path>, candidates: Vec<PathBuf>) -> Result<Self> {
        for p in &candidates {
            if p.is_file() {
                let text = std::fs::read_to_string(p)
                    .with_context(|| format!("cannot read {}", p.display()))?;
                match Self::parse_measures(&text, &p.display().to_string()) {
                    // Named without the machine's directories in the table (a default path).
                    Ok(f) if path.is_none() => {
                        return Ok(Self {
                            source: "the firmware check's measures file \
                                     (`measures.txt` of `fw/measure.sh`)"
                                .to_string(),
                            ..f
                        });
                    }
                    Ok(f) => return Ok(f),
                    Err(e) if path.is_none() => eprintln!("warning: {e}; skipped"),
                    Err(e) => return Err(e),
                }
            }
        }
        if let Some(p) = path {
            return Err(anyhow!("{}: no such file", p.display()));
        }
        let looked: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
        Err(anyhow!(
            "no firmware measures (the Cortex-M4F instruction counts of the table): looked for {}. \
             Run `bash fw/ci.sh` (or `fw/measure.sh`; both need QEMU, which fw/install.sh \
             installs) to measure the firmware, or pass --fw-measures FILE.",
            looked.join(", ")
        ))
    }

    fn of<M: Backend>(&self) -> &M4Figures {
        if M::NAME == Micromath::NAME {
            &self.micromath
        } else {
            &self.libm
        }
    }
}

/// Estimated Cortex-M4F instructions per second of signal at sample rate `f_s` (Hz) with
/// `pulses_per_s` pulses per second:
/// `f_s I_quiet + nu (I_classify + (I_pulse - I_classify) f_s / 100 kS/s)`,
/// i.e. every sample at the quiet cost, and per pulse the classification plus the in-pulse
/// samples' extra cost scaled from the 100 kS/s measurement by the number of samples a pulse
/// spans. Without a whole-pulse figure, `I_pulse - I_classify` is taken as 0.
pub fn m4_instructions_per_second(fw: &M4Figures, sample_rate_hz: f64, pulses_per_s: f64) -> f64 {
    let in_pulse = fw.pulse_total.map_or(0.0, |t| (t - fw.classify).max(0.0));
    sample_rate_hz * fw.quiet_sample
        + pulses_per_s * (fw.classify + in_pulse * sample_rate_hz / FIRMWARE_SAMPLE_RATE_HZ)
}

// ---------------------------------------------------------------------------------------------
// Results
// ---------------------------------------------------------------------------------------------

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
    /// Host ns per quiet sample through `Monitor::feed_slice` ([`BLOCK_SAMPLES`] a call).
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
    /// ([`m4_instructions_per_second`]).
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

// ---------------------------------------------------------------------------------------------
// Measuring
// ---------------------------------------------------------------------------------------------

/// Minimum wall time in s of `reps` (at least 1) runs of `f`.
fn min_seconds(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps.max(1))
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Feeds every sample through `Monitor::feed`; returns the classified (not rejected) pulses.
fn feed_each<M: Backend>(m: &mut Monitor<DEFAULT_CLASSES, M>, samples: &[i16]) -> usize {
    let mut n = 0;
    for &s in samples {
        if let Some(Event::Pulse(r)) = m.feed(black_box(i32::from(s))) {
            n += usize::from(!matches!(r.verdict, Verdict::Rejected(_)));
        }
    }
    n
}

/// Feeds the samples through `Monitor::feed_slice` in blocks of [`BLOCK_SAMPLES`].
fn feed_blocks<M: Backend>(m: &mut Monitor<DEFAULT_CLASSES, M>, samples: &[i16]) {
    for block in samples.chunks(BLOCK_SAMPLES) {
        m.feed_slice(black_box(block), |e| {
            black_box(e);
        });
    }
}

/// Which scene file a name resolves to: `scenes/<name>.toml` in the working directory, else
/// next to this package, else the built-in scene (equal to the file, see `convert` tests).
fn resolve_scene(name: &str, builtin: fn() -> SceneFile) -> Result<(SceneFile, String)> {
    let rel = PathBuf::from("scenes").join(format!("{name}.toml"));
    let beside = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(&rel);
    for p in [rel.clone(), beside] {
        if p.is_file() {
            return Ok((scene::load(&p)?, rel.display().to_string()));
        }
    }
    Ok((builtin(), format!("built-in {name} scene")))
}

/// Noiseless Bayes error and overlap share of `classes` by a `g x g` midpoint integral over
/// each class's `(ln R, ln u)` box in f64, with the densities of [`ClassModel::density`]:
/// a cell of class `i` counts as overlap when another class's density there is positive, as
/// error when another class's prior-weighted density is larger (ties to the lower index).
pub fn reference_separability(classes: &[ClassModel], g: usize) -> (f64, f64) {
    let total: f64 = classes.iter().map(|c| c.prior).sum();
    let (mut overlap, mut error) = (0.0, 0.0);
    let gf = g as f64;
    for (i, c) in classes.iter().enumerate() {
        let (x0, x1) = c.ln_radius;
        let (y0, y1) = c.ln_speed;
        let (dx, dy) = ((x1 - x0) / gf, (y1 - y0) / gf);
        let (mut m_all, mut m_over, mut m_err) = (0.0, 0.0, 0.0);
        for iy in 0..g {
            let y = y0 + (iy as f64 + 0.5) * dy;
            // Speed density in ln u, p(y) ~ e^(beta y), normalised on the box.
            let b = c.speed_beta;
            let w = if b.abs() < 1e-12 {
                1.0
            } else {
                b * (b * (y - y1)).exp() / (1.0 - (b * (y0 - y1)).exp()) * (y1 - y0)
            };
            let (mut row_over, mut row_err) = (0.0, 0.0);
            for ix in 0..g {
                let x = x0 + (ix as f64 + 0.5) * dx;
                let (lf, lt) = c.forward(x, y);
                let own = c.prior * c.density(lf, lt);
                let (mut possible, mut better) = (false, false);
                for (j, o) in classes.iter().enumerate() {
                    if j == i {
                        continue;
                    }
                    let d = o.prior * o.density(lf, lt);
                    possible |= d > 0.0;
                    better |= d > own || (d == own && d > 0.0 && j < i);
                }
                row_over += f64::from(u8::from(possible));
                row_err += f64::from(u8::from(better));
            }
            m_all += w * gf;
            m_over += w * row_over;
            m_err += w * row_err;
        }
        overlap += c.prior * m_over / m_all;
        error += c.prior * m_err / m_all;
    }
    (error / total, overlap / total)
}

/// Largest relative errors `(F_max, t_c)` of the kernel's closed forms with backend `M` over
/// each class of `scene`: `points x points` per class, `R` log-spaced and `u` linear over the
/// class's ranges, against [`HertzImpact64`] at the same (unrounded) inputs; also the number
/// of points.
pub fn closed_form_errors<M: Backend>(
    scene: &SceneFile,
    points: usize,
) -> Result<(f64, f64, usize)> {
    let plate = scene.plate.material();
    let (mut ef, mut et, mut count) = (0.0f64, 0.0f64, 0usize);
    for (m, r, u) in scene_grid(scene, points) {
        let want = HertzImpact64::new(&m, &plate, r, u)?;
        let got = kernel_impact_in::<M>(&m, &plate, r, u)?;
        ef = ef.max((got.peak_force_n / want.peak_force_n - 1.0).abs());
        et = et.max((got.duration_s / want.duration_s - 1.0).abs());
        count += 1;
    }
    Ok((ef, et, count))
}

/// `(sphere material, R in m, u in m/s)` on a `points x points` grid per class of `scene`
/// (at least 2 x 2): `R` log-spaced and `u` linear over the class's ranges.
fn scene_grid(scene: &SceneFile, points: usize) -> Vec<(Material64, f64, f64)> {
    let n = points.max(2);
    let mut out = Vec::new();
    for c in &scene.classes {
        let m = c.material.material();
        let (r, u) = (c.radius_m, c.speed_range_m_s());
        for i in 0..n {
            let radius = r.min * (r.max / r.min).powf(i as f64 / (n - 1) as f64);
            for j in 0..n {
                out.push((
                    m,
                    radius,
                    u.min + (u.max - u.min) * j as f64 / (n - 1) as f64,
                ));
            }
        }
    }
    out
}

/// Accuracy of the kernel with backend `M` on `scene` ([`crate::score::evaluate::evaluate`]).
fn accuracy_of<M: Backend + Send + Sync>(
    name: &str,
    scene: &SceneFile,
    cfg: &TradeoffConfig,
) -> Result<SceneAccuracy> {
    let opts = EvalOptions {
        n_per_class: cfg.eval_n_per_class,
        seed: cfg.seed,
        ..EvalOptions::default()
    };
    let e = evaluate::<M>(scene, &opts).map_err(|e| anyhow!("evaluating {name}: {e}"))?;
    Ok(SceneAccuracy {
        scene: name.to_string(),
        forced_choice: e.forced_choice_accuracy,
        coverage: e.coverage,
        confident_error_rate: e.confident_error_rate,
        bayes_accuracy: e.kernel_noise_bayes_accuracy,
        oracle_accuracy: e.oracle_accuracy,
        samples_fed: e.samples_fed as f64,
        pulses_detected: e.pulses_detected as f64,
    })
}

/// Stream options of the timing streams: the closed-form pulse shape (the kernel's work does
/// not depend on how the pulse was made), default gaps, no faults.
fn timing_options(lead_in_s: f64) -> StreamOptions {
    StreamOptions {
        lead_in_s,
        pulse_model: PulseModel::HertzSine,
        ..StreamOptions::default()
    }
}

fn backend_row<M: Backend + Send + Sync>(
    cfg: &TradeoffConfig,
    scenes: &[(String, SceneFile)],
    quiet: &Stream,
    pulsed: &Stream,
    fw: &FirmwareFigures,
) -> Result<BackendRow> {
    let paper = &scenes[0].1;
    let kernel = scene_to_kernel_in::<DEFAULT_CLASSES, M>(paper)?;
    let proto = Monitor::new(kernel);
    let reps = cfg.timing_reps;
    let t_quiet = min_seconds(reps, || {
        let mut m = proto.clone();
        black_box(feed_each(&mut m, &quiet.samples));
    }) / quiet.samples.len().max(1) as f64;
    let t_block = min_seconds(reps, || {
        let mut m = proto.clone();
        feed_blocks(&mut m, &quiet.samples);
        black_box(m.counters().pulses);
    }) / quiet.samples.len().max(1) as f64;
    let mut pulses = 0;
    let t_pulsed = min_seconds(reps, || {
        let mut m = proto.clone();
        pulses = feed_each(&mut m, &pulsed.samples);
    });
    let pulse_ns = if pulses > 0 {
        (t_pulsed - pulsed.samples.len() as f64 * t_quiet) / pulses as f64 * 1e9
    } else {
        f64::NAN
    };
    let build = min_seconds(reps, || {
        black_box(scene_to_kernel_in::<DEFAULT_CLASSES, M>(black_box(paper)).ok());
    });
    let (ef, et, points) = closed_form_errors::<M>(paper, cfg.closed_form_points)?;
    let accuracy = scenes
        .iter()
        .map(|(name, s)| accuracy_of::<M>(name, s, cfg))
        .collect::<Result<Vec<_>>>()?;
    Ok(BackendRow {
        backend: M::NAME,
        quiet_ns: t_quiet * 1e9,
        quiet_block_ns: t_block * 1e9,
        pulse_ns,
        timed_pulses: pulses,
        build_us: build * 1e6,
        max_rel_err_force: ef,
        max_rel_err_duration: et,
        closed_form_points: points,
        accuracy,
        m4: *fw.of::<M>(),
    })
}

fn grid_rows(
    cfg: &TradeoffConfig,
    paper: &SceneFile,
    reference: &SeparabilityReference,
    fw: &FirmwareFigures,
) -> Result<Vec<GridRow>> {
    let mut rows = Vec::new();
    let mut build_48 = None;
    let mut sizes: Vec<u16> = cfg.grid_sizes.clone();
    if !sizes.contains(&48) {
        sizes.push(48);
    }
    let mut measured = Vec::new();
    for &g in &sizes {
        let mut s = paper.clone();
        s.settings.separability_grid = Some(g);
        let kernel = scene_to_kernel_in::<DEFAULT_CLASSES, Libm>(&s)?;
        let (overlap, bayes_error) = separability_from_kernel(&kernel.separability());
        let build = min_seconds(cfg.timing_reps, || {
            black_box(scene_to_kernel_in::<DEFAULT_CLASSES, Libm>(black_box(&s)).ok());
        });
        if g == 48 {
            build_48 = Some(build);
        }
        measured.push((g, build, overlap, bayes_error));
    }
    let build_48 = build_48.unwrap_or(f64::NAN);
    for (g, build, overlap, bayes_error) in measured {
        if !cfg.grid_sizes.contains(&g) {
            continue;
        }
        rows.push(GridRow {
            grid: g,
            build_us: build * 1e6,
            bayes_error,
            overlap,
            bayes_error_err: (bayes_error - reference.bayes_error).abs(),
            overlap_err: (overlap - reference.overlap).abs(),
            m4_build_insns_est: fw.libm.scene_build * build / build_48,
        });
    }
    Ok(rows)
}

fn separability_reference(cfg: &TradeoffConfig, paper: &SceneFile) -> SeparabilityReference {
    let models = class_models(paper);
    let (bayes_error, overlap) = reference_separability(&models, cfg.reference_grid);
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut uniform = || loop {
        let u: f64 = rng.random();
        if u > 0.0 {
            return u;
        }
    };
    let mc = bayes_accuracy(&models, None, cfg.bayes_mc_per_class, &mut uniform);
    SeparabilityReference {
        bayes_error,
        overlap,
        grid: cfg.reference_grid,
        mc_bayes_error: 1.0 - mc.accuracy,
        mc_std_error: mc.std_error,
    }
}

/// The undamped problems of the integrator section: per class of `scene`, `points x points`
/// impacts (`R` log-spaced, `u` linear over the class's ranges), with their closed forms.
pub fn integrator_problems(
    scene: &SceneFile,
    points: usize,
) -> Result<Vec<(HertzImpact64, ContactProblem)>> {
    let plate = scene.plate.material();
    let mut out = Vec::new();
    for (m, r, u) in scene_grid(scene, points) {
        let h = HertzImpact64::new(&m, &plate, r, u)?;
        out.push((h, undamped_problem(&h)));
    }
    Ok(out)
}

fn integrator_rows(cfg: &TradeoffConfig, paper: &SceneFile) -> Result<Vec<IntegratorRow>> {
    let problems = integrator_problems(paper, cfg.integrator_points)?;
    let mut rows = Vec::new();
    for case in ladder(&cfg.dopri5_tolerances, &cfg.rk4_steps) {
        let (mut ef, mut et, mut evals) = (0.0f64, 0.0f64, 0usize);
        for (h, p) in &problems {
            let s = case.solve(p).with_context(|| {
                format!(
                    "{} on R = {} m, u = {} m/s",
                    case.label, h.radius_m, h.speed_m_s
                )
            })?;
            let (a, b) = relative_errors(&s, h.peak_force_n, h.duration_s);
            ef = ef.max(a);
            et = et.max(b);
            evals += s.work.force_evals;
        }
        let t = min_seconds(cfg.timing_reps, || {
            for (_, p) in &problems {
                black_box(case.solve(black_box(p)).ok());
            }
        });
        let (method, setting) = match case.method {
            Method::Dopri5 => ("dopri5", case.tol.rtol),
            Method::Rk4 { steps_per_tc } => ("rk4", f64::from(steps_per_tc)),
        };
        let MethodCase { label, .. } = case;
        rows.push(IntegratorRow {
            method,
            label,
            setting,
            impacts_per_s: problems.len() as f64 / t,
            max_rel_err_force: ef,
            max_rel_err_duration: et,
            force_evals: evals as f64 / problems.len() as f64,
            problems: problems.len(),
        });
    }
    Ok(rows)
}

#[allow(clippy::type_complexity)]
fn rate_rows(
    cfg: &TradeoffConfig,
    scenes: &[(String, SceneFile)],
    fw: &FirmwareFigures,
) -> Result<(Vec<(String, Vec<RateRow>)>, Vec<(String, f64, String)>)> {
    let mut all = Vec::new();
    let mut refused = Vec::new();
    for (name, base) in scenes {
        let mut rows = Vec::new();
        for &fs in &cfg.sample_rates_hz {
            let mut s = base.clone();
            s.sensor.sample_rate_hz = fs;
            let kernel = match scene_to_kernel_in::<DEFAULT_CLASSES, Libm>(&s) {
                Ok(k) => k,
                Err(e) => {
                    refused.push((name.clone(), fs, e.to_string()));
                    continue;
                }
            };
            let (shortest, _) = duration_bounds_from_kernel(&kernel);
            let shortest_samples = shortest * fs;
            let accuracy = accuracy_of::<Libm>(name, &s, cfg)?;
            let stream = generate(&s, cfg.rate_timing_impacts, cfg.seed, &timing_options(0.01))
                .with_context(|| format!("timing stream of {name} at {fs} Hz"))?;
            let proto = Monitor::new(kernel);
            let t = min_seconds(cfg.timing_reps, || {
                let mut m = proto.clone();
                black_box(replay_events(&stream, &mut m).len());
            });
            let signal_s = stream.timeline_samples as f64 / fs;
            let pulses_per_s = stream.truth.len() as f64 / signal_s;
            rows.push(RateRow {
                sample_rate_hz: fs,
                samples_per_shortest_pulse: shortest_samples,
                accuracy,
                host_ns_per_signal_s: t * 1e9 / signal_s,
                pulses_per_s,
                m4_insns_per_signal_s: m4_instructions_per_second(&fw.libm, fs, pulses_per_s),
            });
        }
        all.push((name.clone(), rows));
    }
    Ok((all, refused))
}

/// Measures everything of `cfg` (see the module docs); `fw` gives the Cortex-M4F figures.
pub fn compute(cfg: &TradeoffConfig, fw: FirmwareFigures) -> Result<Tradeoff> {
    let start = Instant::now();
    let (paper, paper_src) = resolve_scene("paper", SceneFile::paper)?;
    let (narrow, narrow_src) = resolve_scene("paper_narrow", SceneFile::paper_narrow)?;
    let scenes = vec![
        (paper.name.clone(), paper.clone()),
        (narrow.name.clone(), narrow),
    ];
    // Section 1.
    let quiet = generate(&paper, 0, cfg.seed, &timing_options(cfg.quiet_stream_s))
        .context("quiet timing stream")?;
    let pulsed = generate(&paper, cfg.timing_impacts, cfg.seed, &timing_options(0.01))
        .context("pulsed timing stream")?;
    let backends = vec![
        backend_row::<Libm>(cfg, &scenes, &quiet, &pulsed, &fw)?,
        backend_row::<Micromath>(cfg, &scenes, &quiet, &pulsed, &fw)?,
    ];
    // Section 2.
    let reference = separability_reference(cfg, &paper);
    let grids = grid_rows(cfg, &paper, &reference, &fw)?;
    // Section 3.
    let integrator = integrator_rows(cfg, &paper)?;
    // Section 4.
    let (rates, refused_rates) = rate_rows(cfg, &scenes, &fw)?;
    Ok(Tradeoff {
        config: cfg.clone(),
        scene_sources: vec![paper_src, narrow_src],
        backends,
        grids,
        sizes: KernelSizes::measure(),
        reference,
        integrator,
        rates,
        refused_rates,
        firmware: fw,
        runtime_s: start.elapsed().as_secs_f64(),
    })
}

// ---------------------------------------------------------------------------------------------
// Pareto fronts
// ---------------------------------------------------------------------------------------------

/// `true` for each point `(cost, loss)` that no other point dominates (both minimised: `q`
/// dominates `p` when `q.cost <= p.cost`, `q.loss <= p.loss` and one of them is smaller).
/// Non-finite points are never on the front.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(c, l)| {
            c.is_finite()
                && l.is_finite()
                && !points.iter().any(|&(c2, l2)| {
                    c2.is_finite() && l2.is_finite() && c2 <= c && l2 <= l && (c2 < c || l2 < l)
                })
        })
        .collect()
}

/// One point of a Pareto plot.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParetoPoint {
    /// The plot (`backend`, `grid`, `integrator`, `sample_rate`).
    pub plot: &'static str,
    /// The series within the plot (a front is computed per plot and series).
    pub series: String,
    /// The knob's setting.
    pub setting: String,
    /// Cost (minimised).
    pub cost: f64,
    /// Its unit.
    pub cost_unit: &'static str,
    /// Loss (minimised).
    pub loss: f64,
    /// Its unit.
    pub loss_unit: &'static str,
    /// Whether no point of the same plot and series dominates it.
    pub on_front: bool,
}

impl Tradeoff {
    /// The points of the Pareto plots, with the front of each plot and series:
    /// backend (ns per quiet sample, max rel. error of `F_max`), grid (build us,
    /// `|bayes_error - reference|`), integrator (us per impact, max of the `F_max` and `t_c`
    /// errors; one series for all methods), sample rate per scene (Cortex-M4F instructions
    /// per second of signal, `1 - forced-choice accuracy`).
    pub fn pareto_points(&self) -> Vec<ParetoPoint> {
        let mut out = Vec::new();
        let mut push = |plot: &'static str,
                        series: &str,
                        cost_unit: &'static str,
                        loss_unit: &'static str,
                        pts: Vec<(String, f64, f64)>| {
            let front = pareto_front(&pts.iter().map(|p| (p.1, p.2)).collect::<Vec<_>>());
            for ((setting, cost, loss), on_front) in pts.into_iter().zip(front) {
                out.push(ParetoPoint {
                    plot,
                    series: series.to_string(),
                    setting,
                    cost,
                    cost_unit,
                    loss,
                    loss_unit,
                    on_front,
                });
            }
        };
        push(
            "backend",
            "paper",
            "host ns per quiet sample",
            "max rel. error F_max",
            self.backends
                .iter()
                .map(|b| (b.backend.to_string(), b.quiet_ns, b.max_rel_err_force))
                .collect(),
        );
        push(
            "grid",
            "paper",
            "host us per scene build",
            "abs. error of bayes_error",
            self.grids
                .iter()
                .map(|g| (g.grid.to_string(), g.build_us, g.bayes_error_err))
                .collect(),
        );
        push(
            "integrator",
            "all methods",
            "host us per impact",
            "max rel. error F_max, t_c",
            self.integrator
                .iter()
                .map(|r| {
                    (
                        r.label.clone(),
                        1e6 / r.impacts_per_s,
                        r.max_rel_err_force.max(r.max_rel_err_duration),
                    )
                })
                .collect(),
        );
        for (scene, rows) in &self.rates {
            push(
                "sample_rate",
                scene,
                "M4F instructions per s of signal (est.)",
                "1 - forced-choice accuracy",
                rows.iter()
                    .map(|r| {
                        (
                            format!("{} Hz", r.sample_rate_hz),
                            r.m4_insns_per_signal_s,
                            1.0 - r.accuracy.forced_choice,
                        )
                    })
                    .collect(),
            );
        }
        out
    }
}

// ---------------------------------------------------------------------------------------------
// Output
// ---------------------------------------------------------------------------------------------

/// One figure of the long-format CSV.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Metric {
    /// `backend`, `grid`, `integrator`, `sample_rate`, `reference` or `sizes`.
    pub knob: &'static str,
    /// The knob's setting.
    pub setting: String,
    /// The scene (or `paper range`).
    pub scene: String,
    /// What is measured.
    pub metric: &'static str,
    /// The value.
    pub value: f64,
    /// Its unit (`1` for dimensionless).
    pub unit: &'static str,
}

impl Tradeoff {
    /// Every figure, one [`Metric`] each.
    pub fn metrics(&self) -> Vec<Metric> {
        let mut out = Vec::new();
        let mut m = |knob, setting: &str, scene: &str, metric, value, unit| {
            out.push(Metric {
                knob,
                setting: setting.to_string(),
                scene: scene.to_string(),
                metric,
                value,
                unit,
            })
        };
        for b in &self.backends {
            let s = b.backend;
            m("backend", s, "paper", "host_quiet_sample", b.quiet_ns, "ns");
            m(
                "backend",
                s,
                "paper",
                "host_quiet_block_sample",
                b.quiet_block_ns,
                "ns",
            );
            m("backend", s, "paper", "host_pulse", b.pulse_ns, "ns");
            m("backend", s, "paper", "host_scene_build", b.build_us, "us");
            m(
                "backend",
                s,
                "paper range",
                "max_rel_err_f_max",
                b.max_rel_err_force,
                "1",
            );
            m(
                "backend",
                s,
                "paper range",
                "max_rel_err_t_c",
                b.max_rel_err_duration,
                "1",
            );
            m(
                "backend",
                s,
                "paper",
                "m4_quiet_sample",
                b.m4.quiet_sample,
                "instructions",
            );
            m(
                "backend",
                s,
                "paper",
                "m4_classify",
                b.m4.classify,
                "instructions",
            );
            m(
                "backend",
                s,
                "paper",
                "m4_scene_build",
                b.m4.scene_build,
                "instructions",
            );
            for a in &b.accuracy {
                accuracy_metrics(&mut m, "backend", s, a);
            }
        }
        for g in &self.grids {
            let s = g.grid.to_string();
            m("grid", &s, "paper", "host_scene_build", g.build_us, "us");
            m("grid", &s, "paper", "bayes_error", g.bayes_error, "1");
            m("grid", &s, "paper", "overlap", g.overlap, "1");
            m(
                "grid",
                &s,
                "paper",
                "abs_err_bayes_error",
                g.bayes_error_err,
                "1",
            );
            m("grid", &s, "paper", "abs_err_overlap", g.overlap_err, "1");
            m(
                "grid",
                &s,
                "paper",
                "m4_scene_build_est",
                g.m4_build_insns_est,
                "instructions",
            );
            m(
                "grid",
                &s,
                "paper",
                "scene_bytes",
                self.sizes.scene as f64,
                "B",
            );
            m(
                "grid",
                &s,
                "paper",
                "monitor_bytes",
                self.sizes.monitor as f64,
                "B",
            );
        }
        let r = &self.reference;
        let rs = format!("f64 grid {}", r.grid);
        m("reference", &rs, "paper", "bayes_error", r.bayes_error, "1");
        m("reference", &rs, "paper", "overlap", r.overlap, "1");
        m(
            "reference",
            "monte carlo",
            "paper",
            "bayes_error",
            r.mc_bayes_error,
            "1",
        );
        m(
            "reference",
            "monte carlo",
            "paper",
            "bayes_error_std_error",
            r.mc_std_error,
            "1",
        );
        for i in &self.integrator {
            let s = i.label.as_str();
            m(
                "integrator",
                s,
                "paper range",
                "impacts_per_s",
                i.impacts_per_s,
                "1/s",
            );
            m(
                "integrator",
                s,
                "paper range",
                "max_rel_err_f_max",
                i.max_rel_err_force,
                "1",
            );
            m(
                "integrator",
                s,
                "paper range",
                "max_rel_err_t_c",
                i.max_rel_err_duration,
                "1",
            );
            m(
                "integrator",
                s,
                "paper range",
                "force_evals",
                i.force_evals,
                "1",
            );
        }
        for (scene, rows) in &self.rates {
            for r in rows {
                let s = format!("{}", r.sample_rate_hz);
                m(
                    "sample_rate",
                    &s,
                    scene,
                    "samples_per_shortest_pulse",
                    r.samples_per_shortest_pulse,
                    "1",
                );
                m(
                    "sample_rate",
                    &s,
                    scene,
                    "host_per_signal_s",
                    r.host_ns_per_signal_s,
                    "ns",
                );
                m(
                    "sample_rate",
                    &s,
                    scene,
                    "pulses_per_s",
                    r.pulses_per_s,
                    "1/s",
                );
                m(
                    "sample_rate",
                    &s,
                    scene,
                    "m4_per_signal_s_est",
                    r.m4_insns_per_signal_s,
                    "instructions",
                );
                accuracy_metrics(&mut m, "sample_rate", &s, &r.accuracy);
            }
        }
        let z = &self.sizes;
        for (metric, v) in [
            ("scene_bytes", z.scene),
            ("monitor_bytes", z.monitor),
            ("detector_bytes", z.detector),
            ("counters_bytes", z.counters),
            ("envelope_bytes", z.envelope),
        ] {
            m("sizes", "any grid", "any", metric, v as f64, "B");
        }
        out
    }
}

fn accuracy_metrics(
    m: &mut impl FnMut(&'static str, &str, &str, &'static str, f64, &'static str),
    knob: &'static str,
    setting: &str,
    a: &SceneAccuracy,
) {
    let sc = a.scene.as_str();
    m(
        knob,
        setting,
        sc,
        "forced_choice_accuracy",
        a.forced_choice,
        "1",
    );
    m(knob, setting, sc, "coverage", a.coverage, "1");
    m(
        knob,
        setting,
        sc,
        "confident_error_rate",
        a.confident_error_rate,
        "1",
    );
    m(knob, setting, sc, "bayes_accuracy", a.bayes_accuracy, "1");
    m(knob, setting, sc, "oracle_accuracy", a.oracle_accuracy, "1");
}

/// `x` with 3 significant digits and an SI-like suffix (k, M, G) for large values.
fn si(x: f64) -> String {
    let a = x.abs();
    if !x.is_finite() {
        format!("{x}")
    } else if a >= 1e9 {
        format!("{:.3} G", x / 1e9)
    } else if a >= 1e6 {
        format!("{:.3} M", x / 1e6)
    } else if a >= 1e4 {
        format!("{:.1} k", x / 1e3)
    } else if a >= 100.0 {
        format!("{x:.0}")
    } else if a >= 10.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    }
}

/// An instruction count, rounded, with thousands separated by spaces (`1 558 815`).
fn insns(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let digits = format!("{:.0}", x.abs());
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(' ');
        }
        out.push(c);
    }
    if x < 0.0 { format!("-{out}") } else { out }
}

fn acc_cell(a: &SceneAccuracy) -> String {
    format!(
        "{} {:.3} (cov. {:.2}, conf. err. {:.3})",
        a.scene, a.forced_choice, a.coverage, a.confident_error_rate
    )
}

/// The markdown table of every knob, followed by notes on how the figures were obtained.
pub fn render_table(t: &Tradeoff) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| knob | setting | host cost | Cortex-M4F (instructions) | error | accuracy: forced choice (coverage, confident error) |"
    );
    let _ = writeln!(s, "| --- | --- | --- | --- | --- | --- |");
    for b in &t.backends {
        let _ = writeln!(
            s,
            "| math backend | {} | {} ns / quiet sample ({} ns in blocks of {BLOCK_SAMPLES}); {} us / classified pulse; {} us / scene build | {} / quiet sample{}; {} / classify{}; {} / scene build | F_max {:.1e}, t_c {:.1e} | {} |",
            b.backend,
            si(b.quiet_ns),
            si(b.quiet_block_ns),
            si(b.pulse_ns / 1e3),
            si(b.build_us),
            insns(b.m4.quiet_sample),
            b.m4.quiet_block_sample
                .map(|q| format!(" ({} in blocks)", insns(q)))
                .unwrap_or_default(),
            insns(b.m4.classify),
            b.m4.pulse_total
                .map(|p| format!("; {} / whole pulse", insns(p)))
                .unwrap_or_default(),
            insns(b.m4.scene_build),
            b.max_rel_err_force,
            b.max_rel_err_duration,
            b.accuracy
                .iter()
                .map(acc_cell)
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    for g in &t.grids {
        let _ = writeln!(
            s,
            "| separability grid | {0} rows | {1} us / scene build; Scene {2} B, Monitor {3} B | ~{4} / scene build (est.) | bayes_error {5:.4} (err {6:.1e}), overlap {7:.4} (err {8:.1e}) | (build-time figure only) |",
            g.grid,
            si(g.build_us),
            t.sizes.scene,
            t.sizes.monitor,
            si(g.m4_build_insns_est),
            g.bayes_error,
            g.bayes_error_err,
            g.overlap,
            g.overlap_err
        );
    }
    for i in &t.integrator {
        let _ = writeln!(
            s,
            "| integrator | {} | {} impacts/s ({} us / impact, {} force evals) | - | F_max {:.1e}, t_c {:.1e} | - |",
            i.label,
            si(i.impacts_per_s),
            si(1e6 / i.impacts_per_s),
            si(i.force_evals),
            i.max_rel_err_force,
            i.max_rel_err_duration
        );
    }
    for (_, rows) in &t.rates {
        for r in rows {
            let _ = writeln!(
                s,
                "| sample rate | {} S/s, {} | {} us / s of signal | ~{} / s of signal (est.) | shortest pulse {:.1} samples | {} |",
                si(r.sample_rate_hz),
                r.accuracy.scene,
                si(r.host_ns_per_signal_s / 1e3),
                si(r.m4_insns_per_signal_s),
                r.samples_per_shortest_pulse,
                acc_cell(&r.accuracy)
            );
        }
    }
    let r = &t.reference;
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "Reference separability of the paper scene (f64, independent densities of host-sim's \
         `bayes`): Bayes error {:.4}, overlap {:.4} on a {} x {} midpoint grid; Monte Carlo \
         oracle {:.4} +- {:.4}.",
        r.bayes_error, r.overlap, r.grid, r.grid, r.mc_bayes_error, r.mc_std_error
    );
    let z = &t.sizes;
    let _ = writeln!(
        s,
        "Kernel sizes (host, 4 classes): Scene {} B, Monitor {} B, Detector {} B, Counters {} B, \
         Envelope {} B, the same at every grid size (the grid is a loop bound of the build, \
         nothing is stored per cell).",
        z.scene, z.monitor, z.detector, z.counters, z.envelope
    );
    let _ = writeln!(s, "Cortex-M4F figures: {}.", t.firmware.source);
    for (scene, fs, why) in &t.refused_rates {
        let _ = writeln!(s, "The kernel refuses {scene} at {fs} Hz: {why}.");
    }
    let _ = writeln!(
        s,
        "Accuracy: {} impacts per class per evaluation, seed {}; host times: minimum of {} runs.",
        t.config.eval_n_per_class, t.config.seed, t.config.timing_reps
    );
    s
}

fn write_csv<T: Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let mut w = csv::Writer::from_path(path)
        .with_context(|| format!("cannot create {}", path.display()))?;
    for r in rows {
        w.serialize(r)?;
    }
    w.flush()?;
    Ok(())
}

/// How one Pareto plot is drawn: its caption, axis labels, which points, and the axis
/// transforms from a point's cost and loss.
struct PlotSpec {
    caption: &'static str,
    x_desc: &'static str,
    y_desc: &'static str,
    plot: &'static str,
    x: fn(&ParetoPoint) -> f64,
    y: fn(&ParetoPoint) -> f64,
    y_from_zero: bool,
}

/// `log10(max(v, 1e-17))`.
fn lg(v: f64) -> f64 {
    v.max(1e-17).log10()
}

/// Draws one Pareto plot into `path`: every series as dots, the front of each series as a
/// line.
fn draw_pareto(path: &Path, spec: &PlotSpec, all: &[ParetoPoint]) -> Result<()> {
    const COLORS: [RGBColor; 4] = [
        RGBColor(20, 20, 20),
        RGBColor(200, 70, 20),
        RGBColor(30, 100, 200),
        RGBColor(40, 150, 60),
    ];
    let (x, y) = (spec.x, spec.y);
    let points: Vec<&ParetoPoint> = all.iter().filter(|p| p.plot == spec.plot).collect();
    let mut series: Vec<&str> = Vec::new();
    for p in &points {
        if !series.contains(&p.series.as_str()) {
            series.push(&p.series);
        }
    }
    let mut curves = Vec::new();
    for (k, name) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let of: Vec<&&ParetoPoint> = points
            .iter()
            .filter(|p| p.series == *name && x(p).is_finite() && y(p).is_finite())
            .collect();
        curves.push(Curve {
            label: name.to_string(),
            points: of.iter().map(|p| (x(p), y(p))).collect(),
            color,
            stroke: Stroke::Points,
        });
        let mut front: Vec<(f64, f64)> = of
            .iter()
            .filter(|p| p.on_front)
            .map(|p| (x(p), y(p)))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        curves.push(Curve {
            label: format!("{name}: Pareto front"),
            points: front,
            color,
            stroke: Stroke::Solid,
        });
    }
    draw_svg(
        path,
        spec.caption,
        spec.x_desc,
        spec.y_desc,
        &curves,
        spec.y_from_zero,
    )
}

/// Writes the table, [`METRICS_CSV`], [`PARETO_CSV`] and [`SVG_FILES`] into `dir` (created if
/// missing); returns their paths.
pub fn write_outputs(t: &Tradeoff, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let table = dir.join(TABLE_MD);
    std::fs::write(&table, render_table(t))
        .with_context(|| format!("cannot write {}", table.display()))?;
    let metrics = dir.join(METRICS_CSV);
    write_csv(&metrics, &t.metrics())?;
    let points = t.pareto_points();
    let pareto = dir.join(PARETO_CSV);
    write_csv(&pareto, &points)?;
    let specs = [
        PlotSpec {
            caption: "Math backend: host time per quiet sample vs F_max error",
            x_desc: "host ns per quiet sample",
            y_desc: "log10 max rel. error of F_max",
            plot: "backend",
            x: |p| p.cost,
            y: |p| lg(p.loss),
            y_from_zero: false,
        },
        PlotSpec {
            caption: "Separability grid: build time vs Bayes-error error (paper scene)",
            x_desc: "log10 host us per scene build",
            y_desc: "|bayes_error - f64 reference|",
            plot: "grid",
            x: |p| lg(p.cost),
            y: |p| p.loss,
            y_from_zero: true,
        },
        PlotSpec {
            caption: "Contact integrator: speed vs accuracy (undamped Hertz, paper range)",
            x_desc: "log10 impacts per second",
            y_desc: "log10 max rel. error of F_max and t_c",
            plot: "integrator",
            x: |p| lg(1e6 / p.cost),
            y: |p| lg(p.loss),
            y_from_zero: false,
        },
        PlotSpec {
            caption: "Sample rate: Cortex-M4F work vs accuracy",
            x_desc: "log10 M4F instructions per second of signal (est.)",
            y_desc: "forced-choice accuracy",
            plot: "sample_rate",
            x: |p| lg(p.cost),
            y: |p| 1.0 - p.loss,
            y_from_zero: false,
        },
    ];
    let svgs: Vec<PathBuf> = SVG_FILES.iter().map(|f| dir.join(f)).collect();
    for (path, spec) in svgs.iter().zip(&specs) {
        draw_pareto(path, spec, &points)?;
    }
    let mut out = vec![table, metrics, pareto];
    out.extend(svgs);
    Ok(out)
}

/// `host-sim tradeoff`: measures (full or quick), prints the table and the run time, writes
/// the files into `args.out` and lists them.
pub fn run(args: &TradeoffArgs) -> Result<()> {
    let cfg = if args.quick {
        TradeoffConfig::quick(args.seed)
    } else {
        TradeoffConfig::full(args.seed)
    };
    let fw = FirmwareFigures::load(args.fw_measures.as_deref())?;
    let t = compute(&cfg, fw)?;
    print!("{}", render_table(&t));
    println!("Run time: {:.1} s.", t.runtime_s);
    let files = write_outputs(&t, &args.out)?;
    crate::report::paper::print_written(&files);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instruction_counts_are_grouped() {
        assert_eq!(insns(1_558_815.0), "1 558 815");
        assert_eq!(insns(74.0), "74");
        assert_eq!(insns(2736.4), "2 736");
    }

    #[test]
    fn pareto_front_of_a_small_set() {
        let pts = [
            (1.0, 5.0),
            (2.0, 3.0),
            (3.0, 3.0),
            (4.0, 1.0),
            (5.0, 2.0),
            (f64::NAN, 0.0),
        ];
        assert_eq!(pareto_front(&pts), [true, true, false, true, false, false]);
    }

    #[test]
    fn m4_estimate_scales_the_in_pulse_part() {
        let fw = M4Figures {
            quiet_sample: 70.0,
            quiet_block_sample: None,
            classify: 4000.0,
            pulse_total: Some(9000.0),
            scene_build: 1000.0,
        };
        let at = |fs| m4_instructions_per_second(&fw, fs, 100.0);
        assert_eq!(at(100_000.0), 100_000.0 * 70.0 + 100.0 * 9000.0);
        assert_eq!(
            at(200_000.0),
            200_000.0 * 70.0 + 100.0 * (4000.0 + 2.0 * 5000.0)
        );
    }

    #[test]
    fn missing_measures_name_the_command_to_run() {
        let e = FirmwareFigures::load(Some(Path::new("no/such/measures.txt")))
            .expect_err("no such file");
        assert!(e.to_string().contains("no such file"), "{e}");
        let e = FirmwareFigures::load_from(None, vec![PathBuf::from("no/such/measures.txt")])
            .expect_err("nothing found");
        assert!(e.to_string().contains("bash fw/ci.sh"), "{e}");
        assert!(
            FirmwareFigures::default_paths()
                .iter()
                .any(|p| p.ends_with("fw/measures.txt"))
        );
    }

    #[test]
    fn measures_file_parses_and_missing_keys_are_errors() {
        let text = "libm_insns_quiet_sample_mean 70\nlibm_insns_classify_mean 4000\n\
                    libm_insns_scene_build 1000\nmicromath_insns_quiet_sample_mean 60\n\
                    micromath_insns_classify_mean 3000\nmicromath_insns_scene_build 2000\n\
                    micromath_insns_pulse_total_mean 5000\n";
        let f = FirmwareFigures::parse_measures(text, "x").expect("parses");
        assert_eq!(f.libm.quiet_sample, 70.0);
        assert_eq!(f.libm.pulse_total, None);
        assert_eq!(f.micromath.pulse_total, Some(5000.0));
        assert!(FirmwareFigures::parse_measures("libm_insns_quiet_sample_mean 1", "x").is_err());
    }

    #[test]
    fn reference_separability_of_the_narrow_scene_is_zero() {
        let (b, o) = reference_separability(&class_models(&SceneFile::paper_narrow()), 64);
        assert_eq!((b, o), (0.0, 0.0));
    }
}
