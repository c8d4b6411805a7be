//! `host-sim impact`: one sphere-on-plate impact from flags, or one per row of a CSV file,
//! answered as CSV.
//!
//! Inputs (flag `--name`, CSV column `name`; SI units; read and checked by
//! [`crate::report::impact_row`]):
//!
//! | name | meaning |
//! | --- | --- |
//! | `material` | sphere material by name (the scene files' list, [`MaterialName`]) |
//! | `density`, `modulus`, `poisson` | sphere `rho` (kg/m^3), `E` (Pa), `nu`; each replaces the named material's value, all three needed without a name |
//! | `plate` | plate material by name (default `carbon_steel` when no plate property is given) |
//! | `plate_density`, `plate_modulus`, `plate_poisson` | plate `rho` (kg/m^3), `E` (Pa), `nu`; each replaces the named plate's value; without a name `plate_modulus` and `plate_poisson` are needed (the plate's density does not enter the contact) |
//! | `radius` | sphere radius `R` (m) |
//! | `speed` | approach speed `u` (m/s) |
//! | `law` | [`LawName`] (default `hertz`) |
//! | `restitution` | target coefficient of restitution `e` of a damped law |
//! | `c_max` | Adams full damping `c_max` (N s/m); for `adams` give it or `restitution` |
//! | `depth` | Adams penetration `d` (m) over which the damping ramps up (default 1e-5) |
//! | `method` | [`MethodName`] (default `dopri5`) |
//! | `tol` | `rtol = atol` of the adaptive methods on the state scaled by the Hertz `delta_max` and by `u` (default 1e-9) |
//! | `steps_per_tc` | RK4 steps per Hertz contact time (default 200) |
//! | `gravity` | acceleration (m/s^2) pushing the sphere into the plate during the contact (default 0; 9.80665 is standard gravity) |
//!
//! An input the row's law or method does not use (`restitution` for `hertz`, `c_max` or
//! `depth` for any law but `adams`, `tol` for `rk4`, `steps_per_tc` for `dopri5`) is an
//! error. With `--batch`, a flag fills each row's empty cell and is then that row's input.
//!
//! Output: the inputs as echoed (the defaults that apply filled in), then
//! [`RESULT_COLUMNS`], `warning` and `error`. A row that fails (bad number, negative radius,
//! integration limit, ...) has empty integrator results and the message in `error`; the batch
//! goes on. `warning` says where the impact lies far outside Hertz theory
//! ([`crate::report::impact_row`]: penetration above 0.08 of the radius, speed above 1 % of the
//! sphere's bar-wave speed); a single impact also prints it on standard error.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context as _, bail};

use crate::physics::hertz64::{HERTZ_TC_FACTOR, HertzImpact64};
use crate::physics::impact::{ImpactReport, simulate};
pub use crate::report::impact_row::{
    ECHO_COLUMNS, INPUT_COLUMNS, InputRow, LawName, MethodName, fmt_f64,
};
use crate::report::impact_row::{Reading, parse_gravity, user_terms};
use crate::scene::MaterialName;

/// Result columns after the inputs (SI units), followed by `warning` and `error`.
///
/// The integrator's: `delta_max_m` (m), `peak_force_n` (N), `duration_s` (first contact to
/// separation, s), `pulse_duration_s` (first contact to the first zero of the force after
/// its peak, s), `rebound_speed_m_s` (m/s), `restitution` (rebound / approach speed),
/// `impulse_n_s` (`integral F dt`, N s). The undamped, gravity-free Hertz closed forms beside
/// them (filled whenever the inputs are valid, even if the integration fails):
/// `hertz_stiffness_n_m1_5` (`k = 4/3 E* sqrt(R)`, N/m^1.5), `mass_kg`
/// (`m = 4/3 pi rho R^3`), `hertz_delta_max_m` (`(5 m u^2 / (4 k))^(2/5)`),
/// `hertz_peak_force_n` (`k delta_max^(3/2)`), `hertz_duration_s` (`2.9432752 delta_max / u`).
/// Then the integrator's work: `steps`, `rejected_steps`, `force_evals`, `jacobian_evals`
/// (Rodas4 and Radau13; 0 for the explicit methods).
pub const RESULT_COLUMNS: [&str; 16] = [
    "delta_max_m",
    "peak_force_n",
    "duration_s",
    "pulse_duration_s",
    "rebound_speed_m_s",
    "restitution",
    "impulse_n_s",
    "hertz_stiffness_n_m1_5",
    "mass_kg",
    "hertz_delta_max_m",
    "hertz_peak_force_n",
    "hertz_duration_s",
    "steps",
    "rejected_steps",
    "force_evals",
    "jacobian_evals",
];

/// A named material ([`MaterialName::from_name`], the list scene files use).
pub fn material_by_name(name: &str) -> Option<crate::physics::hertz64::Material64> {
    MaterialName::from_name(name).map(MaterialName::material)
}

/// Flags of `host-sim impact`. With `--batch`, the flags are the defaults for empty or
/// missing cells of the batch file.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct ImpactArgs {
    /// Sphere material: coal, sandstone, carbon_steel, roof_sandstone, sandy_mudstone (the
    /// scene files' list).
    #[arg(long)]
    pub material: Option<String>,
    /// Sphere density rho in kg/m^3 (replaces the named material's).
    #[arg(long, allow_negative_numbers = true)]
    pub density: Option<f64>,
    /// Sphere Young's modulus E in Pa (replaces the named material's).
    #[arg(long, allow_negative_numbers = true)]
    pub modulus: Option<f64>,
    /// Sphere Poisson's ratio nu (replaces the named material's).
    #[arg(long, allow_negative_numbers = true)]
    pub poisson: Option<f64>,
    /// Plate material by name, from the same list [default: carbon_steel, unless plate
    /// properties are given].
    #[arg(long)]
    pub plate: Option<String>,
    /// Plate density in kg/m^3 (replaces the named plate's; optional: it does not enter the
    /// contact of a sphere on a plate).
    #[arg(long, allow_negative_numbers = true)]
    pub plate_density: Option<f64>,
    /// Plate Young's modulus E in Pa (replaces the named plate's; needed without --plate).
    #[arg(long, allow_negative_numbers = true)]
    pub plate_modulus: Option<f64>,
    /// Plate Poisson's ratio nu (replaces the named plate's; needed without --plate).
    #[arg(long, allow_negative_numbers = true)]
    pub plate_poisson: Option<f64>,
    /// Sphere radius R in m.
    #[arg(long, allow_negative_numbers = true)]
    pub radius: Option<f64>,
    /// Approach speed u at first contact in m/s.
    #[arg(long, allow_negative_numbers = true)]
    pub speed: Option<f64>,
    /// Contact force law.
    #[arg(long, value_enum, default_value_t = LawName::Hertz)]
    pub law: LawName,
    /// Target coefficient of restitution e of a damped law (required by all but hertz;
    /// for adams give this or --c-max).
    #[arg(long, allow_negative_numbers = true)]
    pub restitution: Option<f64>,
    /// Adams full damping c_max in N s/m (adams only).
    #[arg(long, allow_negative_numbers = true)]
    pub c_max: Option<f64>,
    /// Adams penetration d in m over which the damping ramps from 0 to c_max (adams only)
    /// [default: 1e-5].
    #[arg(long, allow_negative_numbers = true)]
    pub depth: Option<f64>,
    /// Integration method: dopri5 (Dormand-Prince 5(4), the default), dop853 (Dormand-Prince
    /// 8(5,3), cheaper at tolerances of 1e-9 and below), rodas4 (Rosenbrock on the exact
    /// Jacobian, for heavily damped, stiff contacts), radau13 (Radau IIA of order 13 on the
    /// exact Jacobian, for stiff contacts at tight tolerances), auto (dop853, switching to
    /// radau13 where the contact is stiff) or rk4 (fixed steps). The adaptive methods but
    /// dopri5 hold the rebound and creep speeds to relative accuracy.
    #[arg(long, value_enum, default_value_t = MethodName::Dopri5)]
    pub method: MethodName,
    /// Relative and absolute tolerance of the adaptive methods (all but rk4), on the state scaled by
    /// the Hertz closed forms: penetration in units of delta_max, velocity in units of the
    /// approach speed u; from 1e-14 to below 1 [default: 1e-9].
    #[arg(long, allow_negative_numbers = true)]
    pub tol: Option<f64>,
    /// RK4 steps per Hertz contact time (rk4 only) [default: 200].
    #[arg(long)]
    pub steps_per_tc: Option<u32>,
    /// Gravitational acceleration in m/s^2 that pushes the sphere into the plate during the
    /// contact: 0 for none, 9.80665 for standard gravity (the sphere still arrives at
    /// --speed) [default: 0].
    #[arg(long, value_name = "M_S2", value_parser = parse_gravity)]
    pub gravity: Option<f64>,
    /// Write the force-time series (t_s, force_n) of the single impact to this CSV file.
    #[arg(long, conflicts_with = "batch")]
    pub series: Option<PathBuf>,
    /// Sample interval of --series in s [default: the Hertz contact time / 500].
    #[arg(long, requires = "series", allow_negative_numbers = true)]
    pub series_interval: Option<f64>,
    /// Run one impact per row of this CSV file (header row of input column names).
    #[arg(long)]
    pub batch: Option<PathBuf>,
    /// Write the answer CSV here instead of standard output.
    #[arg(long)]
    pub output: Option<PathBuf>,
}

impl Default for ImpactArgs {
    /// The clap defaults: nothing given but law `hertz` and method `dopri5` (the other
    /// defaults are applied when a row is read, where they apply).
    fn default() -> Self {
        Self {
            material: None,
            density: None,
            modulus: None,
            poisson: None,
            plate: None,
            plate_density: None,
            plate_modulus: None,
            plate_poisson: None,
            radius: None,
            speed: None,
            law: LawName::Hertz,
            restitution: None,
            c_max: None,
            depth: None,
            method: MethodName::Dopri5,
            tol: None,
            steps_per_tc: None,
            gravity: None,
            series: None,
            series_interval: None,
            batch: None,
            output: None,
        }
    }
}

impl InputRow {
    /// The inputs that `args` gives, formatted (flags not given are empty cells).
    pub fn from_args(args: &ImpactArgs) -> Self {
        let opt = |v: Option<f64>| v.map(fmt_f64).unwrap_or_default();
        Self {
            cells: [
                args.material.clone().unwrap_or_default(),
                opt(args.density),
                opt(args.modulus),
                opt(args.poisson),
                args.plate.clone().unwrap_or_default(),
                opt(args.plate_density),
                opt(args.plate_modulus),
                opt(args.plate_poisson),
                opt(args.radius),
                opt(args.speed),
                args.law.as_str().to_string(),
                opt(args.restitution),
                opt(args.c_max),
                opt(args.depth),
                args.method.as_str().to_string(),
                opt(args.tol),
                args.steps_per_tc.map(|n| n.to_string()).unwrap_or_default(),
                opt(args.gravity),
            ],
        }
    }
}

/// One row answered: the inputs as echoed, the closed forms (when the inputs are valid),
/// the integrator's report or the message, and the warnings.
#[derive(Debug, Clone)]
pub struct Answer {
    /// The inputs as echoed.
    pub echo: InputRow,
    /// The Hertz closed forms.
    pub hertz: Option<HertzImpact64>,
    /// The integrator's report, or what is wrong.
    pub outcome: Result<ImpactReport, String>,
    /// Where the impact lies far outside Hertz theory.
    pub warnings: Vec<String>,
}

/// The result cells in [`RESULT_COLUMNS`] order: the integrator's empty without a report,
/// the closed forms empty without valid inputs.
fn result_cells(report: Option<&ImpactReport>, hertz: Option<&HertzImpact64>) -> Vec<String> {
    let f = |v: Option<f64>| v.map(fmt_f64).unwrap_or_default();
    let n = |v: Option<usize>| v.map(|v| v.to_string()).unwrap_or_default();
    vec![
        f(report.map(|r| r.delta_max_m)),
        f(report.map(|r| r.peak_force_n)),
        f(report.map(|r| r.duration_s)),
        f(report.map(|r| r.pulse_duration_s)),
        f(report.map(|r| r.rebound_speed_m_s)),
        f(report.map(|r| r.restitution)),
        f(report.map(|r| r.impulse_n_s)),
        f(hertz.map(|h| h.stiffness)),
        f(hertz.map(|h| h.mass_kg)),
        f(hertz.map(|h| h.delta_max_m)),
        f(hertz.map(|h| h.peak_force_n)),
        f(hertz.map(|h| h.duration_s)),
        n(report.map(|r| r.steps)),
        n(report.map(|r| r.rejected_steps)),
        n(report.map(|r| r.force_evals)),
        n(report.map(|r| r.jacobian_evals)),
    ]
}

/// Reads and runs one row, with `--series` interval `series` (`Some(None)`: the default
/// interval, the Hertz contact time / 500).
fn answer(row: &InputRow, series: Option<Option<f64>>) -> Answer {
    let reading = match row.read() {
        Ok(r) => r,
        Err(e) => {
            return Answer {
                echo: row.clone(),
                hertz: None,
                outcome: Err(e),
                warnings: Vec::new(),
            };
        }
    };
    let Reading {
        mut spec,
        hertz,
        echo,
        warnings,
    } = reading;
    spec.record = series
        .map(|dt| dt.unwrap_or(HERTZ_TC_FACTOR * hertz.delta_max_m / hertz.speed_m_s / 500.0));
    Answer {
        echo,
        hertz: Some(hertz),
        outcome: simulate(&spec).map_err(user_terms),
        warnings,
    }
}

/// Runs one row: `Ok(report)` or the error message.
pub fn run_row(row: &InputRow) -> Result<ImpactReport, String> {
    answer(row, None).outcome
}

fn header() -> Vec<&'static str> {
    let mut h: Vec<&str> = ECHO_COLUMNS.to_vec();
    h.extend(RESULT_COLUMNS);
    h.push("warning");
    h.push("error");
    h
}

fn answer_record(a: &Answer) -> Vec<String> {
    let mut rec: Vec<String> = a.echo.cells.to_vec();
    rec.extend(result_cells(a.outcome.as_ref().ok(), a.hertz.as_ref()));
    rec.push(a.warnings.join("; "));
    rec.push(a.outcome.as_ref().err().cloned().unwrap_or_default());
    rec
}

/// Counts of a batch run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BatchSummary {
    /// Rows read.
    pub rows: usize,
    /// Rows that failed (their `error` cell is filled).
    pub failed: usize,
    /// Rows with a warning (their `warning` cell is filled).
    pub warned: usize,
}

/// Runs one impact per CSV row of `input` and writes the answer CSV to `output`.
///
/// The first row names the columns ([`INPUT_COLUMNS`] or [`ECHO_COLUMNS`], any subset in any
/// order; an unknown name is an error for the whole file). An empty or missing cell takes the value from
/// `defaults` (the flags). Every row is answered, in order, by one row of the inputs as
/// echoed (given cell, else the default), [`RESULT_COLUMNS`] and `error`; a row that cannot
/// be read or simulated gets its message in `error` and the batch goes on.
pub fn run_batch(
    defaults: &ImpactArgs,
    input: impl Read,
    output: impl Write,
) -> anyhow::Result<BatchSummary> {
    let mut reader = csv::ReaderBuilder::new()
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(input);
    let head = reader
        .headers()
        .context("cannot read the batch header")?
        .clone();
    let map = column_map(&head)?;
    let base = InputRow::from_args(defaults);
    let mut writer = csv::Writer::from_writer(output);
    writer.write_record(header())?;
    let mut summary = BatchSummary::default();
    for (line, rec) in reader.records().enumerate() {
        summary.rows += 1;
        let mut row = base.clone();
        let unread = |message: String| Answer {
            echo: row.clone(),
            hertz: None,
            outcome: Err(message),
            warnings: Vec::new(),
        };
        let a = match rec {
            Ok(rec) if rec.len() > map.len() => unread(format!(
                "row {} has {} cells, the header {}",
                line + 1,
                rec.len(),
                map.len()
            )),
            Ok(rec) => {
                for (cell, &i) in rec.iter().zip(&map) {
                    if !cell.is_empty() {
                        row.cells[i] = cell.to_string();
                    }
                }
                answer(&row, None)
            }
            Err(e) => unread(format!("cannot read row {}: {e}", line + 1)),
        };
        summary.failed += a.outcome.is_err() as usize;
        summary.warned += !a.warnings.is_empty() as usize;
        writer.write_record(answer_record(&a))?;
    }
    writer.flush()?;
    Ok(summary)
}

/// The input column of each batch header cell (names case-blind, `-` read as `_`; the echoed
/// columns accepted too); an unknown name is an error that lists the accepted ones.
fn column_map(head: &csv::StringRecord) -> anyhow::Result<Vec<usize>> {
    let mut map = Vec::with_capacity(head.len());
    for name in head.iter() {
        let norm = name.trim().to_ascii_lowercase().replace('-', "_");
        let found = INPUT_COLUMNS
            .iter()
            .position(|c| *c == norm)
            .or_else(|| ECHO_COLUMNS.iter().position(|c| *c == norm));
        match found {
            Some(i) => map.push(i),
            None => bail!(
                "unknown batch column {name:?}; accepted: {}",
                INPUT_COLUMNS.join(", ")
            ),
        }
    }
    Ok(map)
}

fn open_output(path: Option<&Path>) -> anyhow::Result<Box<dyn Write>> {
    Ok(match path {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        )),
        None => Box::new(std::io::stdout().lock()),
    })
}

/// Writes `(t_s, force_n)` rows with header `t_s,force_n`.
fn write_series(path: &Path, series: &[(f64, f64)]) -> anyhow::Result<()> {
    let mut w = csv::Writer::from_path(path)
        .with_context(|| format!("cannot create {}", path.display()))?;
    w.write_record(["t_s", "force_n"])?;
    for &(t, f) in series {
        w.write_record([fmt_f64(t), fmt_f64(f)])?;
    }
    w.flush()?;
    Ok(())
}

/// `host-sim impact`: with `--batch FILE`, [`run_batch`] (a summary of failed and warned rows
/// goes to standard error; failed rows do not make it fail). Otherwise one impact from the
/// flags, printed as a header and one row, its warnings also on standard error; if it fails
/// the row carries the message in `error` and the command fails too. `--series FILE` also
/// writes its force-time series, sampled every `--series-interval` s (default: Hertz
/// `t_c = 2.9432752 delta_max/u` over 500).
pub fn run(args: &ImpactArgs) -> anyhow::Result<()> {
    let out = open_output(args.output.as_deref())?;
    if let Some(batch) = &args.batch {
        let file = std::fs::File::open(batch)
            .with_context(|| format!("cannot open {}", batch.display()))?;
        let s = run_batch(args, std::io::BufReader::new(file), out)?;
        if s.failed > 0 {
            eprintln!(
                "{} of {} impacts failed (see the error column)",
                s.failed, s.rows
            );
        }
        if s.warned > 0 {
            eprintln!(
                "warning: {} of {} impacts lie far outside Hertz theory (see the warning column)",
                s.warned, s.rows
            );
        }
        return Ok(());
    }
    let a = answer(
        &InputRow::from_args(args),
        args.series.as_ref().map(|_| args.series_interval),
    );
    for w in &a.warnings {
        eprintln!("warning: {w}");
    }
    let mut writer = csv::Writer::from_writer(out);
    writer.write_record(header())?;
    writer.write_record(answer_record(&a))?;
    writer.flush()?;
    drop(writer);
    match a.outcome {
        Ok(report) => {
            if let (Some(path), Some(series)) = (&args.series, &report.force_series) {
                write_series(path, series)?;
            }
            Ok(())
        }
        Err(e) => bail!("impact failed: {e}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clap_defaults_match_default() {
        use clap::Parser;
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            args: ImpactArgs,
        }
        let cli = Cli::try_parse_from(["impact"]).expect("defaults parse");
        assert_eq!(cli.args, ImpactArgs::default());
        let cli = Cli::try_parse_from(["impact", "--radius", "-0.01", "--law", "hunt-crossley"])
            .expect("negative numbers parse");
        assert_eq!(cli.args.radius, Some(-0.01));
        assert_eq!(cli.args.law, LawName::HuntCrossley);
    }

    #[test]
    fn names_parse() {
        assert_eq!(
            LawName::parse("Lankarani_Nikravesh"),
            Ok(LawName::LankaraniNikravesh)
        );
        assert!(LawName::parse("bogus").is_err());
        assert_eq!(MethodName::parse("RK4"), Ok(MethodName::Rk4));
        assert!(material_by_name("Carbon-Steel").is_some());
        assert!(material_by_name("cheese").is_none());
        for m in MaterialName::ALL {
            assert_eq!(material_by_name(m.name()), Some(m.material()), "{m:?}");
        }
    }

    #[test]
    fn bad_rows_are_messages() {
        let args = ImpactArgs {
            material: Some("coal".into()),
            radius: Some(0.03),
            speed: Some(1.0),
            ..ImpactArgs::default()
        };
        let mut row = InputRow::from_args(&args);
        assert!(run_row(&row).is_ok());
        for (col, val, needle) in [
            ("radius", "abc", "not a number"),
            ("radius", "-1", "radius"),
            ("speed", "nan", "speed"),
            ("law", "flores", "needs restitution"),
            ("material", "cheese", "unknown material"),
            ("gravity", "maybe", "gravity"),
            ("steps_per_tc", "-3", "steps_per_tc"),
            ("tol", "0", "tol = 0"),
        ] {
            let i = INPUT_COLUMNS
                .iter()
                .position(|c| *c == col)
                .expect("column");
            let old = std::mem::replace(&mut row.cells[i], val.to_string());
            let err = run_row(&row).expect_err(col);
            assert!(err.contains(needle), "{col}={val}: {err}");
            row.cells[i] = old;
        }
    }

    #[test]
    fn fmt_round_trips() {
        for x in [0.0, 1e-5, 0.03, 1673.0, 2.98e9, -4.2e-12] {
            assert_eq!(fmt_f64(x).parse::<f64>(), Ok(x));
        }
        assert_eq!(fmt_f64(0.03), "0.03");
        assert_eq!(fmt_f64(1e-5), "1e-5");
    }
}
