//! `host-sim tradeoff`, its options and run sizes: the constants of the study, the command's
//! options and the configuration (full or quick) every measurement reads.

use std::path::PathBuf;

use serde::Serialize;

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

/// What `host-sim tradeoff` runs and where it writes.
#[derive(Debug, Clone, PartialEq)]
pub struct TradeoffOptions {
    /// Directory for the table, the CSV files and the SVG plots (created if missing).
    pub out: PathBuf,
    /// The small, fast run ([`TradeoffConfig::quick`]) instead of the full one.
    pub quick: bool,
    /// Seed of every random draw (streams, Monte Carlo).
    pub seed: u64,
    /// The firmware check's `measures.txt`; `None`: where
    /// [`crate::report::tradeoff::FirmwareFigures::load`] looks for it.
    pub fw_measures: Option<PathBuf>,
}

impl Default for TradeoffOptions {
    /// `target/tradeoff`, full run, seed 1, the firmware figures where the check leaves them.
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
