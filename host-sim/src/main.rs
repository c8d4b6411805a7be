//! `host-sim`: the command line of the f64 companion of the coalshock kernel.
//!
//! - `host-sim paper`: the paper's scene, Table 3 and Figs 2-11 (see `PAPER.md`);
//! - `host-sim impact`: one impact, or a batch of impacts from a CSV file;
//! - `host-sim stream`: a labelled sample stream (`.bin` + `.truth.csv`, see `FORMATS.md`);
//! - `host-sim evaluate`: the kernel scored on a scene against its reference limit (see
//!   `host_sim::evaluate`, JSON fields in `FORMATS.md`);
//! - `host-sim caving`: caving rounds, the window closed at the kernel's flow alarm, against
//!   the same detector on exact features, the true labels, a clairvoyant and the naive rule
//!   (see `host_sim::caving`, `docs/caving.md`);
//! - `host-sim identify`: the beam's modes and the accelerometer's resonance estimated from a
//!   recorded stream (see `host_sim::identify`; the band from the pulses' Hertz shape with
//!   `--hertz-pulses`, or a restitution law's with `--pulse-law`), printed as a `[sensor]`
//!   table;
//! - `host-sim export`: a scene file as Rust source for a firmware (see `host_sim::export`);
//! - `host-sim plasticity`: elastic against yielding contacts of a scene's classes (see
//!   `host_sim::plasticity`, `docs/plasticity.md`);
//! - `host-sim speed`: integrator and end-to-end throughput on this machine (see
//!   `host_sim::speed`).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use host_sim::generate::generate_with_progress;
use host_sim::law_spec::LawSpec;
use host_sim::report::{write_json, write_stdout};
use host_sim::scene::{self, SceneFile};
use host_sim::stream::{FaultKind, FaultOptions, ImpactFault, PulseModel, Stream, StreamOptions};
use host_sim::stream_file::write_stream;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Scene used when `--scene` is not given (relative to the working directory).
const DEFAULT_SCENE: &str = "scenes/paper.toml";

#[derive(Debug, Parser)]
#[command(
    name = "host-sim",
    version,
    about = "f64 contact integrator, sensor chain and labelled streams around the coalshock kernel"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Reproduce the paper: Table 3 and the force and compression curves (CSV + SVG).
    Paper(host_sim::paper_cli::PaperArgs),
    /// Simulate one impact (or a batch of impacts) and print peak force, duration, restitution.
    Impact(host_sim::impact_cli::ImpactArgs),
    /// Generate a labelled sample stream: OUT.bin (little-endian i16) and OUT.truth.csv.
    Stream(StreamArgs),
    /// Evaluate the kernel on N impacts per class: confusion matrix, forced-choice accuracy,
    /// coverage, confident errors, reliability of its posteriors, against the reference limit
    /// and the oracle.
    Evaluate(host_sim::evaluate_cli::EvaluateArgs),
    /// Measure what each knob buys and costs (math backend, separability grid, integrator,
    /// sample rate): a markdown table, CSV files and SVG Pareto plots.
    Tradeoff(host_sim::tradeoff_cli::TradeoffArgs),
    /// Simulate caving rounds: the gangue share steps or ramps up, the kernel's flow monitor
    /// closes the window; delays, false alarms, recovery and gangue content.
    Caving(host_sim::caving_cli::CavingArgs),
    /// Estimate the tail beam's modes (and the accelerometer's resonance) from a recorded
    /// stream of impacts; prints the scene's [sensor] table.
    Identify(IdentifyArgs),
    /// Write a scene file as Rust source that a firmware includes: a function that builds the
    /// kernel scene exactly as host-sim does (exact f32 literals).
    Export(host_sim::export_cli::ExportArgs),
    /// Peak force, contact time and restitution against speed for a scene's yielding classes,
    /// elastic against yielding (table, CSV and SVG).
    Plasticity(host_sim::plasticity_cli::PlasticityArgs),
    /// Measure host-sim's speed on this machine: integrator impacts/s (Hertz, Adams) and the
    /// wall time of an end-to-end evaluation of N impacts.
    Speed(host_sim::speed_cli::SpeedArgs),
}

/// Flags of `host-sim identify`.
#[derive(Debug, Clone, Args)]
struct IdentifyArgs {
    /// Recorded stream: little-endian i16 samples (OUT.bin of `host-sim stream`).
    #[arg(long)]
    stream: PathBuf,
    /// Sample rate of the stream in Hz.
    #[arg(long)]
    sample_rate: f64,
    /// Number of beam modes to report (default: as many as ring above the noise).
    #[arg(long)]
    modes: Option<usize>,
    /// Also estimate the accelerometer's resonance.
    #[arg(long)]
    accelerometer: bool,
    /// The contact is undamped Hertz (`law = "hertz"`): fit the accelerometer's band to the
    /// pulses' known shape rather than to its ring after them (with --accelerometer; for a
    /// band too damped to ring, such as a MEMS part's).
    #[arg(long, conflicts_with = "pulse_law")]
    hertz_pulses: bool,
    /// The contact law whose pulse shape the band is fitted to, as a scene's `[contact] law`
    /// names it: hertz (as --hertz-pulses), hunt_crossley, lankarani_nikravesh, flores,
    /// gonthier or tsuji (with --restitution and --accelerometer).
    #[arg(long)]
    pulse_law: Option<String>,
    /// The restitution of --pulse-law, in (0, 1].
    #[arg(long, requires = "pulse_law")]
    restitution: Option<f64>,
    /// Noise RMS in counts (default: estimated from the stream).
    #[arg(long)]
    noise_rms: Option<f64>,
}

impl IdentifyArgs {
    fn options(&self) -> Result<host_sim::identify::IdentifyOptions> {
        Ok(host_sim::identify::IdentifyOptions {
            sample_rate_hz: self.sample_rate,
            modes: self.modes,
            accelerometer: self.accelerometer,
            pulse_law: self.pulse_law()?,
            noise_rms_counts: self.noise_rms,
        })
    }

    /// The law of `--hertz-pulses` or `--pulse-law NAME --restitution E`, if either is given.
    fn pulse_law(&self) -> Result<Option<LawSpec>> {
        let Some(name) = self.pulse_law.as_deref() else {
            return Ok(self.hertz_pulses.then_some(LawSpec::Hertz));
        };
        if name == "hertz" {
            return Ok(Some(LawSpec::Hertz));
        }
        if LawSpec::restitution_law(name, 1.0).is_none() {
            anyhow::bail!(
                "--pulse-law {name}: expected hertz, hunt_crossley, lankarani_nikravesh, \
                 flores, gonthier or tsuji"
            );
        }
        let Some(e) = self.restitution else {
            anyhow::bail!("--pulse-law {name}: give its --restitution too");
        };
        if !host_sim::laws::restitution_in_range(e, false) {
            anyhow::bail!("--restitution must be in (0, 1] (got {e})");
        }
        Ok(LawSpec::restitution_law(name, e))
    }
}

/// `host-sim identify`: reads the samples, prints the `[sensor]` table.
fn run_identify(args: &IdentifyArgs) -> Result<()> {
    let bytes = std::fs::read(&args.stream)
        .with_context(|| format!("reading the stream {}", args.stream.display()))?;
    if bytes.len() % 2 != 0 {
        anyhow::bail!(
            "--stream {}: {} bytes is not a whole number of i16 samples",
            args.stream.display(),
            bytes.len()
        );
    }
    let samples: Vec<i16> = bytes
        .chunks_exact(2)
        .map(|b| i16::from_le_bytes([b[0], b[1]]))
        .collect();
    let id = host_sim::identify::identify(&samples, &args.options()?)
        .with_context(|| format!("identifying the chain from {}", args.stream.display()))?;
    write_stdout(&id.to_toml())
}

/// How each impact's force pulse is made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum PulseModelArg {
    /// The contact integrator with the scene's force law.
    Integrator,
    /// The closed-form undamped shape F_max sin^(3/2)(pi t / t_c).
    HertzSine,
}

/// Flags of `host-sim stream`.
#[derive(Debug, Clone, Args)]
struct StreamArgs {
    /// Scene file (TOML). Default: scenes/paper.toml if it exists, else the built-in paper
    /// scene.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Number of impacts (1 to 10^7).
    #[arg(long, value_parser = host_sim::counts::stream_impacts)]
    n: usize,
    /// Seed of every random draw (impacts, timing, noise, faults).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output: writes OUT.bin and OUT.truth.csv (a trailing .bin is dropped first).
    #[arg(long)]
    out: PathBuf,
    /// How each force pulse is made.
    #[arg(long, value_enum, default_value_t = PulseModelArg::Integrator)]
    pulse_model: PulseModelArg,
    /// Quiet gap between pulses in ms, uniform between these two values.
    #[arg(long, num_args = 2, value_names = ["MIN", "MAX"], default_values_t = [2.0, 10.0])]
    gap_ms: Vec<f64>,
    /// Share of impacts that start less than one contact time after the previous one.
    #[arg(long, default_value_t = 0.0)]
    pileup_share: f64,
    /// Share of impacts scaled to 1.5 x the ADC's full scale (measured from their flanks on a
    /// rigid beam where the kernel can, else rejected as saturated).
    #[arg(long, default_value_t = 0.0)]
    saturate_share: f64,
    /// Share of impacts that lose samples near their peak (a recorded gap).
    #[arg(long, default_value_t = 0.0)]
    drop_share: f64,
    /// Share of quiet stretches between pulses with a single-sample EMI spike.
    #[arg(long, default_value_t = 0.0)]
    spike_share: f64,
    /// Share of quiet stretches with a stuck run (the value held for 100 samples).
    #[arg(long, default_value_t = 0.0)]
    stuck_share: f64,
    /// Share of quiet stretches that lose samples (a recorded gap).
    #[arg(long, default_value_t = 0.0)]
    drop_quiet_share: f64,
    /// Samples lost per drop.
    #[arg(long, default_value_t = 8)]
    drop_samples: u32,
    /// DC drift in counts per s added to the scene's.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    drift: f64,
    /// End the stream right after the peak of the last impact.
    #[arg(long)]
    end_mid_pulse: bool,
}

impl StreamArgs {
    fn options(&self) -> StreamOptions {
        let ms = |i: usize| self.gap_ms.get(i).copied().unwrap_or(f64::NAN) * 1e-3;
        StreamOptions {
            gap_s: [ms(0), ms(1)],
            pileup_share: self.pileup_share,
            pulse_model: match self.pulse_model {
                PulseModelArg::Integrator => PulseModel::Integrator,
                PulseModelArg::HertzSine => PulseModel::HertzSine,
            },
            faults: FaultOptions {
                saturate_share: self.saturate_share,
                drop_share: self.drop_share,
                spike_share: self.spike_share,
                stuck_share: self.stuck_share,
                drop_quiet_share: self.drop_quiet_share,
                drop_samples: self.drop_samples,
                drift_counts_per_s: self.drift,
                end_mid_pulse: self.end_mid_pulse,
                ..FaultOptions::default()
            },
            ..StreamOptions::default()
        }
    }
}

/// The scene of `--scene`, else [`DEFAULT_SCENE`] if it exists, else the built-in paper scene.
fn resolve_scene(path: Option<&Path>) -> Result<(SceneFile, String)> {
    match path {
        Some(p) => Ok((scene::load(p)?, p.display().to_string())),
        None if Path::new(DEFAULT_SCENE).is_file() => {
            Ok((scene::load(DEFAULT_SCENE)?, DEFAULT_SCENE.to_string()))
        }
        None => Ok((SceneFile::paper(), "built-in paper scene".to_string())),
    }
}

/// Reports on standard error the share of the scene's impacts predicted to clip the ADC
/// (`host_sim::saturation`), as a warning above 1 %, and warns when a calibrated contact
/// leaves its shortest measured pulse fewer samples than its sampling correction starts from
/// (1.6 for a damped law, `coalshock::sampled_phase::PHASE_FIRST_N`, 2.5 for an undamped one
/// that yields), naming the rate the kernel, which refuses such a scene, needs
/// (`host_sim::calibrate::sampling_warning`).
fn report_saturation(scene: &SceneFile) {
    match host_sim::saturation::predict(scene) {
        Ok(p) => {
            eprintln!("{}", p.summary());
            if let Some(w) = p.warning() {
                eprintln!("warning: {w}");
            }
        }
        Err(e) => eprintln!("warning: the ADC clipping could not be predicted: {e}"),
    }
    match host_sim::calibrate::sampling_warning(scene) {
        Ok(Some(w)) => eprintln!("warning: {w}"),
        Ok(None) => {}
        Err(e) => eprintln!("warning: the samples per pulse could not be predicted: {e}"),
    }
}

fn run_stream(args: &StreamArgs) -> Result<()> {
    let (scene, from) = resolve_scene(args.scene.as_deref())?;
    report_saturation(&scene);
    let options = args.options();
    let bar = ProgressBar::new(args.n as u64);
    if std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} impacts ({eta})")
                .context("progress bar template")?
                .progress_chars("=> "),
        );
        bar.set_message("simulating");
    } else {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    let stream = generate_with_progress(&scene, args.n, args.seed, &options, &mut |done| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let stream = stream.with_context(|| format!("generating a stream of {from}"))?;
    let (bin, csv) = write_stream(&stream, &args.out)?;
    print_summary(&stream, &from, args.seed, &bin, &csv)
}

/// Prints what the stream holds (impacts per class, its faults) and the files written, in one
/// write.
fn print_summary(s: &Stream, scene: &str, seed: u64, bin: &Path, csv: &Path) -> Result<()> {
    let count = |f: ImpactFault| s.truth.iter().filter(|t| t.fault == f).count();
    let events = |k: FaultKind| s.events.iter().filter(|e| e.kind == k).count();
    let classes: String = s
        .class_names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let n = s.truth.iter().filter(|t| t.class == i).count();
            format!("  {name}: {n}\n")
        })
        .collect();
    write_stdout(&format!(
        "{} impacts of {scene} (seed {seed}) in {} samples at {} Hz ({:.3} s)\n{classes}\
         faults: {} pile-up impacts, {} saturated, {} gaps in pulses, {} truncated, {} gaps \
         ({} samples lost), {} spikes, {} stuck runs\nwrote {} and {}\n",
        s.truth.len(),
        s.timeline_samples,
        s.sample_rate_hz,
        s.timeline_samples as f64 / s.sample_rate_hz,
        count(ImpactFault::PileUp),
        count(ImpactFault::Saturated),
        count(ImpactFault::Gap),
        count(ImpactFault::Truncated),
        s.gaps.len(),
        s.gaps.iter().map(|g| g.lost as u64).sum::<u64>(),
        events(FaultKind::Spike),
        events(FaultKind::Stuck),
        bin.display(),
        csv.display()
    ))
}

/// Runs the command; an error is the user's to read, its causes after it, without a stack
/// backtrace whatever `RUST_BACKTRACE` says (exit code 1; clap's own refusals exit with 2).
/// An error whose chain holds a broken pipe (the reader closed standard output early, as
/// `| head` does) ends the command quietly with exit code 141, what a shell reports for a
/// process that SIGPIPE ended: no one is left to read a message, and a script under
/// `set -o pipefail` still sees that the command stopped (one that writes files after its
/// report has not written them).
fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    match run(&cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) if is_broken_pipe(&e) => std::process::ExitCode::from(BROKEN_PIPE_EXIT),
        Err(e) => {
            eprintln!("Error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Exit code of a command whose reader closed standard output: 128 + SIGPIPE (13).
const BROKEN_PIPE_EXIT: u8 = 141;

/// Whether `e`'s chain holds an I/O error of kind `BrokenPipe`, on its own or inside a CSV
/// writer's error (`impact` writes its rows through one, whose error hides its I/O cause).
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    let broken = |io: &std::io::Error| io.kind() == std::io::ErrorKind::BrokenPipe;
    e.chain().any(|cause| {
        cause.downcast_ref::<std::io::Error>().is_some_and(broken)
            || cause
                .downcast_ref::<csv::Error>()
                .is_some_and(|c| matches!(c.kind(), csv::ErrorKind::Io(io) if broken(io)))
    })
}

fn run(cli: &Cli) -> Result<()> {
    match &cli.command {
        Command::Paper(args) => host_sim::paper::run(&args.config(), &args.out),
        Command::Impact(args) => host_sim::impact_cli::run(args),
        Command::Stream(args) => run_stream(args),
        Command::Evaluate(args) => run_evaluate(args),
        Command::Tradeoff(args) => host_sim::tradeoff::run(&args.options()),
        Command::Identify(args) => run_identify(args),
        Command::Export(args) => host_sim::export::run(&args.scene, args.out.as_deref()),
        Command::Caving(args) => host_sim::caving_cli::run_cli(args),
        Command::Plasticity(args) => host_sim::plasticity::run(&args.options()),
        Command::Speed(args) => host_sim::speed::run(&args.options()),
    }
}

/// `host-sim evaluate`: tables on stdout (or one JSON object with `--json`), progress on a
/// terminal's stderr.
fn run_evaluate(args: &host_sim::evaluate_cli::EvaluateArgs) -> Result<()> {
    let scene = scene::load(&args.scene)?;
    report_saturation(&scene);
    let bar = ProgressBar::new(0);
    if std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template("evaluating [{bar:40}] {pos}/{len} impacts ({eta})")
                .context("progress bar template")?
                .progress_chars("=> "),
        );
    } else {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    let eval = host_sim::evaluate::evaluate_backend(
        args.backend,
        &scene,
        &args.options(),
        &mut |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    );
    bar.finish_and_clear();
    let eval = eval.with_context(|| format!("evaluating {}", args.scene.display()))?;
    if args.json {
        write_json(&eval)
    } else {
        write_stdout(&eval.table())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn stream_flags_map_onto_the_options() {
        let cli = Cli::try_parse_from([
            "host-sim",
            "stream",
            "--n",
            "5",
            "--out",
            "x",
            "--gap-ms",
            "1",
            "3",
            "--spike-share",
            "0.5",
            "--drift",
            "-20",
        ])
        .expect("parses");
        let Command::Stream(args) = cli.command else {
            panic!("not the stream command");
        };
        let o = args.options();
        assert_eq!(o.gap_s, [0.001, 0.003]);
        assert_eq!(o.faults.spike_share, 0.5);
        assert_eq!(o.faults.drift_counts_per_s, -20.0);
        assert_eq!(o.pulse_model, PulseModel::Integrator);
        o.validate().expect("valid");
    }

    #[test]
    fn identify_flags_map_onto_the_options() {
        let cli = Cli::try_parse_from([
            "host-sim",
            "identify",
            "--stream",
            "a.bin",
            "--sample-rate",
            "26667",
            "--modes",
            "2",
            "--accelerometer",
            "--hertz-pulses",
        ])
        .expect("parses");
        let Command::Identify(args) = cli.command else {
            panic!("not the identify command");
        };
        let o = args.options().expect("valid");
        assert_eq!(o.sample_rate_hz, 26667.0);
        assert_eq!(o.modes, Some(2));
        assert!(o.accelerometer);
        assert_eq!(o.pulse_law, Some(LawSpec::Hertz));
        assert_eq!(o.noise_rms_counts, None);
    }

    /// `--pulse-law NAME --restitution E` gives that law; a name not in the list, a missing or
    /// out-of-range restitution, or both shape flags are errors that name the flag.
    #[test]
    fn identify_pulse_law_flags() {
        let options = |extra: &[&str]| {
            let mut argv = vec!["host-sim", "identify", "--stream", "a.bin"];
            argv.extend(["--sample-rate", "26667", "--accelerometer"]);
            argv.extend(extra);
            let cli = Cli::try_parse_from(argv).map_err(|e| e.to_string())?;
            let Command::Identify(args) = cli.command else {
                panic!("not the identify command");
            };
            args.options().map_err(|e| e.to_string())
        };
        let o = options(&["--pulse-law", "flores", "--restitution", "0.5"]).expect("valid");
        assert_eq!(o.pulse_law, Some(LawSpec::Flores { restitution: 0.5 }));
        assert_eq!(
            options(&["--pulse-law", "hertz"]).expect("valid").pulse_law,
            Some(LawSpec::Hertz)
        );
        assert_eq!(options(&[]).expect("valid").pulse_law, None);
        let e = options(&["--pulse-law", "granite", "--restitution", "0.5"]).unwrap_err();
        assert!(e.starts_with("--pulse-law granite"), "{e}");
        let e = options(&["--pulse-law", "adams"]).unwrap_err();
        assert!(e.starts_with("--pulse-law adams: expected"), "{e}");
        let e = options(&["--pulse-law", "tsuji"]).unwrap_err();
        assert!(e.contains("--restitution"), "{e}");
        let e = options(&["--pulse-law", "tsuji", "--restitution", "1.5"]).unwrap_err();
        assert!(e.starts_with("--restitution"), "{e}");
        let e = options(&["--hertz-pulses", "--pulse-law", "flores"]).unwrap_err();
        assert!(e.contains("--pulse-law"), "{e}");
    }
}
