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

//!
//! The study is in parts, lowest first: [`config`], [`firmware`], [`results`], [`measure`],
//! [`pareto`], [`metrics`], [`table`], [`outputs`]; this module runs them ([`compute`],
//! [`run`]) and re-exports their public items.

pub mod config;
pub mod firmware;
pub mod measure;
pub mod metrics;
pub mod outputs;
pub mod pareto;
pub mod results;
pub mod table;

pub use config::{
    BLOCK_SAMPLES, FIRMWARE_SAMPLE_RATE_HZ, METRICS_CSV, PARETO_CSV, SVG_FILES, TABLE_MD,
    TradeoffConfig, TradeoffOptions,
};
pub use firmware::{FirmwareFigures, M4Figures, m4_instructions_per_second};
pub use measure::{closed_form_errors, integrator_problems, reference_separability};
pub use metrics::Metric;
pub use outputs::write_outputs;
pub use pareto::{ParetoPoint, pareto_front};
pub use results::{
    BackendRow, GridRow, IntegratorRow, KernelSizes, RateRow, SceneAccuracy, SeparabilityReference,
    Tradeoff,
};
use std::time::Instant;
pub use table::render_table;

use anyhow::{Context, Result};
use coalshock::math::{Libm, Micromath};

use crate::scene::SceneFile;
use crate::sim::generate::generate;
use measure::{
    backend_row, grid_rows, integrator_rows, rate_rows, resolve_scene, separability_reference,
    timing_options,
};

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

/// `host-sim tradeoff`: measures (full or quick), prints the table and the run time, writes
/// the files into `args.out` and lists them.
pub fn run(args: &TradeoffOptions) -> Result<()> {
    let cfg = if args.quick {
        TradeoffConfig::quick(args.seed)
    } else {
        TradeoffConfig::full(args.seed)
    };
    let fw = FirmwareFigures::load(args.fw_measures.as_deref())?;
    let t = compute(&cfg, fw)?;
    crate::report::write_stdout(&format!(
        "{}Run time: {:.1} s.\n",
        render_table(&t),
        t.runtime_s
    ))?;
    let files = write_outputs(&t, &args.out)?;
    crate::report::paper::print_written(&files)
}
