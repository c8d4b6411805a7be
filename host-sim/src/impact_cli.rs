//! `host-sim impact`: one sphere-on-plate impact from flags, or one per row of a CSV file,
//! answered as CSV.
//!
//! Inputs (flag `--name`, CSV column `name`; SI units):
//!
//! | name | meaning |
//! | --- | --- |
//! | `material` | sphere material by name ([`material_by_name`]) |
//! | `density`, `modulus`, `poisson` | sphere `rho` (kg/m^3), `E` (Pa), `nu`; each replaces the named material's value, all three needed without a name |
//! | `plate` | plate material by name (default `carbon_steel`) |
//! | `radius` | sphere radius `R` (m) |
//! | `speed` | approach speed `u` (m/s) |
//! | `law` | [`LawName`] (default `hertz`) |
//! | `restitution` | target coefficient of restitution `e` of a damped law |
//! | `c_max` | Adams full damping `c_max` (N s/m); for `adams` give it or `restitution` |
//! | `depth` | Adams penetration `d` (m) over which the damping ramps up (default 1e-5) |
//! | `method` | [`MethodName`] (default `dopri5`) |
//! | `tol` | Dormand-Prince `rtol = atol` on the scaled state (default 1e-9) |
//! | `steps_per_tc` | RK4 steps per Hertz contact time (default 200) |
//! | `gravity` | `true`/`false`: 9.80665 m/s^2 into the plate during contact (default false) |
//!
//! Output: the inputs as given, then [`RESULT_COLUMNS`] and `error`. A row that fails (bad
//! number, negative radius, integration limit, ...) has empty results and the message in
//! `error`; the batch goes on.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context as _, bail};
use clap::ValueEnum;

use crate::hertz64::{HERTZ_TC_FACTOR, Material64};
use crate::impact::{ImpactReport, ImpactSpec, simulate};
use crate::integrate::{Method, Tolerance};
use crate::law_spec::LawSpec;

/// Input columns of a batch file, in the order they are echoed (see the module docs).
pub const INPUT_COLUMNS: [&str; 15] = [
    "material",
    "density",
    "modulus",
    "poisson",
    "plate",
    "radius",
    "speed",
    "law",
    "restitution",
    "c_max",
    "depth",
    "method",
    "tol",
    "steps_per_tc",
    "gravity",
];

/// Names of the echoed inputs in the answer: [`INPUT_COLUMNS`] with `restitution` written as
/// `target_restitution`, since `restitution` is also a result column (the simulated one).
/// A batch file may use either name.
pub const ECHO_COLUMNS: [&str; 15] = [
    "material",
    "density",
    "modulus",
    "poisson",
    "plate",
    "radius",
    "speed",
    "law",
    "target_restitution",
    "c_max",
    "depth",
    "method",
    "tol",
    "steps_per_tc",
    "gravity",
];

/// Result columns after the inputs (SI units), followed by `error`:
/// `delta_max_m` (m), `peak_force_n` (N), `duration_s` (first contact to separation, s),
/// `pulse_duration_s` (first contact to the first zero of the force after its peak, s),
/// `rebound_speed_m_s` (m/s), `restitution` (rebound / approach speed), `impulse_n_s`
/// (`integral F dt`, N s), `steps`, `rejected_steps`, `force_evals` (integrator work).
pub const RESULT_COLUMNS: [&str; 10] = [
    "delta_max_m",
    "peak_force_n",
    "duration_s",
    "pulse_duration_s",
    "rebound_speed_m_s",
    "restitution",
    "impulse_n_s",
    "steps",
    "rejected_steps",
    "force_evals",
];

/// Named materials: `coal`, `sandstone` and `carbon_steel` (the paper's Tables 1-2), and
/// [`SANDY_MUDSTONE`]. Case-insensitive; `-` and `_` are interchangeable; `steel` means
/// `carbon_steel`.
pub fn material_by_name(name: &str) -> Option<Material64> {
    match name.trim().to_ascii_lowercase().replace('-', "_").as_str() {
        "coal" => Some(Material64::COAL),
        "sandstone" => Some(Material64::SANDSTONE),
        "carbon_steel" | "steel" => Some(Material64::CARBON_STEEL),
        "sandy_mudstone" | "mudstone" => Some(SANDY_MUDSTONE),
        _ => None,
    }
}

/// Names accepted by [`material_by_name`].
pub const MATERIAL_NAMES: [&str; 4] = ["coal", "sandstone", "carbon_steel", "sandy_mudstone"];

/// Sandy mudstone as seen in the coal-gangue literature: 2500 kg/m^3, 5.4 GPa, nu = 0.15
/// (about as stiff as the paper's coal, so told from it by density only).
pub const SANDY_MUDSTONE: Material64 = Material64 {
    density_kg_m3: 2500.0,
    modulus_pa: 5.4e9,
    poisson: 0.15,
};

/// Contact force law (see [`crate::laws`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LawName {
    /// Undamped Hertz `F = k delta^1.5`.
    Hertz,
    /// MSC Adams IMPACT `F = max(0, k delta^1.5 + STEP(delta, 0, 0, d, c_max) delta')`, with
    /// `c_max` given or found for `restitution`.
    Adams,
    /// Hunt-Crossley `F = k delta^1.5 (1 + chi delta'/u)`, `chi = 3 (1 - e)/2`.
    HuntCrossley,
    /// Lankarani-Nikravesh, `chi = 3 (1 - e^2)/4`.
    LankaraniNikravesh,
    /// Flores et al., `chi = 8 (1 - e)/(5 e)`.
    Flores,
    /// Gonthier et al., `chi = (1 - e^2)/e`.
    Gonthier,
    /// Tsuji / Hertz-Mindlin DEM damping with `beta(e)`.
    Tsuji,
}

impl LawName {
    /// The name as written on the command line and in CSV.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Hertz => "hertz",
            Self::Adams => "adams",
            Self::HuntCrossley => "hunt-crossley",
            Self::LankaraniNikravesh => "lankarani-nikravesh",
            Self::Flores => "flores",
            Self::Gonthier => "gonthier",
            Self::Tsuji => "tsuji",
        }
    }

    /// Parses a name (case-insensitive, `_` for `-` allowed).
    pub fn parse(s: &str) -> Result<Self, String> {
        let norm = s.trim().to_ascii_lowercase().replace('_', "-");
        <Self as ValueEnum>::from_str(&norm, true).map_err(|_| {
            format!(
                "unknown law {s:?}: expected hertz, adams, hunt-crossley, lankarani-nikravesh, \
                 flores, gonthier or tsuji"
            )
        })
    }
}

/// Integration method (see [`crate::integrate::Method`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MethodName {
    /// Adaptive Dormand-Prince 5(4) with tolerance `tol`.
    Dopri5,
    /// Fixed-step RK4 with `steps_per_tc` steps per Hertz contact time.
    Rk4,
}

impl MethodName {
    /// The name as written on the command line and in CSV.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Dopri5 => "dopri5",
            Self::Rk4 => "rk4",
        }
    }

    /// Parses a name (case-insensitive).
    pub fn parse(s: &str) -> Result<Self, String> {
        <Self as ValueEnum>::from_str(s.trim(), true)
            .map_err(|_| format!("unknown method {s:?}: expected dopri5 or rk4"))
    }
}

/// Flags of `host-sim impact`. With `--batch`, the flags are the defaults for empty or
/// missing cells of the batch file.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct ImpactArgs {
    /// Sphere material: coal, sandstone, carbon_steel, sandy_mudstone.
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
    /// Plate material by name.
    #[arg(long, default_value = "carbon_steel")]
    pub plate: String,
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
    /// Adams full damping c_max in N s/m.
    #[arg(long, allow_negative_numbers = true)]
    pub c_max: Option<f64>,
    /// Adams penetration d in m over which the damping ramps from 0 to c_max.
    #[arg(long, default_value_t = 1e-5, allow_negative_numbers = true)]
    pub depth: f64,
    /// Integration method.
    #[arg(long, value_enum, default_value_t = MethodName::Dopri5)]
    pub method: MethodName,
    /// Dormand-Prince relative and absolute tolerance on the scaled state.
    #[arg(long, default_value_t = 1e-9, allow_negative_numbers = true)]
    pub tol: f64,
    /// RK4 steps per Hertz contact time.
    #[arg(long, default_value_t = 200)]
    pub steps_per_tc: u32,
    /// Gravity (9.80665 m/s^2) pushes the sphere into the plate during the contact.
    #[arg(long)]
    pub gravity: bool,
    /// Write the force-time series (t_s, force_n) of the single impact to this CSV file.
    #[arg(long, conflicts_with = "batch")]
    pub series: Option<PathBuf>,
    /// Sample interval of --series in s (default: the Hertz contact time / 500).
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
    /// The clap defaults: no material, radius or speed; plate `carbon_steel`, law `hertz`,
    /// d = 1e-5 m, `dopri5` at 1e-9, 200 RK4 steps per contact time, no gravity.
    fn default() -> Self {
        Self {
            material: None,
            density: None,
            modulus: None,
            poisson: None,
            plate: "carbon_steel".to_string(),
            radius: None,
            speed: None,
            law: LawName::Hertz,
            restitution: None,
            c_max: None,
            depth: 1e-5,
            method: MethodName::Dopri5,
            tol: 1e-9,
            steps_per_tc: 200,
            gravity: false,
            series: None,
            series_interval: None,
            batch: None,
            output: None,
        }
    }
}

/// A number in shortest round-trip form: plain for `1e-3 <= |x| < 1e7` (and 0), else
/// scientific (`1.0680041269757393e-4`).
pub fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-3..1e7).contains(&a) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// One impact's inputs as text cells, in [`INPUT_COLUMNS`] order (empty = not given).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct InputRow {
    /// The cells.
    pub cells: [String; 15],
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
                args.plate.clone(),
                opt(args.radius),
                opt(args.speed),
                args.law.as_str().to_string(),
                opt(args.restitution),
                opt(args.c_max),
                fmt_f64(args.depth),
                args.method.as_str().to_string(),
                fmt_f64(args.tol),
                args.steps_per_tc.to_string(),
                args.gravity.to_string(),
            ],
        }
    }

    /// The cell of input column `name`, or `""` for an unknown name.
    pub fn get(&self, name: &str) -> &str {
        INPUT_COLUMNS
            .iter()
            .position(|c| *c == name)
            .map(|i| self.cells[i].trim())
            .unwrap_or("")
    }

    fn num(&self, name: &str) -> Result<Option<f64>, String> {
        let s = self.get(name);
        if s.is_empty() {
            return Ok(None);
        }
        s.parse::<f64>()
            .map(Some)
            .map_err(|_| format!("{name}: {s:?} is not a number"))
    }

    fn required(&self, name: &str) -> Result<f64, String> {
        self.num(name)?.ok_or_else(|| format!("{name} is missing"))
    }

    /// The simulation this row asks for, or a message saying what is wrong with it.
    ///
    /// Numbers are checked for range by [`simulate`] itself (it refuses a non-positive
    /// radius, speed, density or modulus, `nu` outside (-1, 0.5], a restitution outside its
    /// law's range, ...).
    pub fn to_spec(&self) -> Result<ImpactSpec, String> {
        let name = self.get("material");
        let mut sphere = if name.is_empty() {
            None
        } else {
            Some(material_by_name(name).ok_or_else(|| {
                format!(
                    "unknown material {name:?}: expected one of {} or density/modulus/poisson",
                    MATERIAL_NAMES.join(", ")
                )
            })?)
        };
        let props = [
            self.num("density")?,
            self.num("modulus")?,
            self.num("poisson")?,
        ];
        if sphere.is_none() {
            match props {
                [Some(d), Some(e), Some(nu)] => {
                    sphere = Some(Material64 {
                        density_kg_m3: d,
                        modulus_pa: e,
                        poisson: nu,
                    });
                }
                _ => {
                    return Err("give material, or all of density, modulus and poisson".into());
                }
            }
        }
        let mut sphere = sphere.unwrap_or(Material64::COAL);
        if let Some(d) = props[0] {
            sphere.density_kg_m3 = d;
        }
        if let Some(e) = props[1] {
            sphere.modulus_pa = e;
        }
        if let Some(nu) = props[2] {
            sphere.poisson = nu;
        }
        let plate_name = match self.get("plate") {
            "" => "carbon_steel",
            p => p,
        };
        let plate = material_by_name(plate_name).ok_or_else(|| {
            format!(
                "unknown plate {plate_name:?}: expected one of {}",
                MATERIAL_NAMES.join(", ")
            )
        })?;
        let radius = self.required("radius")?;
        let speed = self.required("speed")?;
        let law_name = match self.get("law") {
            "" => LawName::Hertz,
            s => LawName::parse(s)?,
        };
        let restitution = self.num("restitution")?;
        let c_max = self.num("c_max")?;
        let depth = self.num("depth")?.unwrap_or(1e-5);
        let need_e =
            || restitution.ok_or_else(|| format!("law {} needs restitution", law_name.as_str()));
        let law = match law_name {
            LawName::Hertz => LawSpec::Hertz,
            LawName::Adams => match (c_max, restitution) {
                (Some(c), None) => LawSpec::Adams {
                    c_max_n_s_m: c,
                    d_m: depth,
                },
                (None, Some(e)) => LawSpec::AdamsRestitution {
                    restitution: e,
                    d_m: depth,
                },
                (Some(_), Some(_)) => {
                    return Err("law adams: give c_max or restitution, not both".into());
                }
                (None, None) => return Err("law adams needs c_max or restitution".into()),
            },
            LawName::HuntCrossley => LawSpec::HuntCrossley {
                restitution: need_e()?,
            },
            LawName::LankaraniNikravesh => LawSpec::LankaraniNikravesh {
                restitution: need_e()?,
            },
            LawName::Flores => LawSpec::Flores {
                restitution: need_e()?,
            },
            LawName::Gonthier => LawSpec::Gonthier {
                restitution: need_e()?,
            },
            LawName::Tsuji => LawSpec::Tsuji {
                restitution: need_e()?,
            },
        };
        let method = match self.get("method") {
            "" => MethodName::Dopri5,
            s => MethodName::parse(s)?,
        };
        let tol = self.num("tol")?.unwrap_or(1e-9);
        let steps = match self.get("steps_per_tc") {
            "" => 200,
            s => s
                .parse::<u32>()
                .map_err(|_| format!("steps_per_tc: {s:?} is not a whole number >= 1"))?,
        };
        let gravity = match self.get("gravity").to_ascii_lowercase().as_str() {
            "" | "false" | "0" | "no" => false,
            "true" | "1" | "yes" => true,
            s => return Err(format!("gravity: {s:?} is not true or false")),
        };
        let mut spec = ImpactSpec::new(sphere, plate, radius, speed);
        spec.law = law;
        spec.method = match method {
            MethodName::Dopri5 => Method::Dopri5,
            MethodName::Rk4 => Method::Rk4 {
                steps_per_tc: steps,
            },
        };
        spec.tolerance = Tolerance::new(tol);
        spec.gravity = gravity;
        Ok(spec)
    }
}

/// The answer row: the result cells in [`RESULT_COLUMNS`] order, empty on error.
fn result_cells(report: Option<&ImpactReport>) -> Vec<String> {
    match report {
        Some(r) => vec![
            fmt_f64(r.delta_max_m),
            fmt_f64(r.peak_force_n),
            fmt_f64(r.duration_s),
            fmt_f64(r.pulse_duration_s),
            fmt_f64(r.rebound_speed_m_s),
            fmt_f64(r.restitution),
            fmt_f64(r.impulse_n_s),
            r.steps.to_string(),
            r.rejected_steps.to_string(),
            r.force_evals.to_string(),
        ],
        None => vec![String::new(); RESULT_COLUMNS.len()],
    }
}

/// Runs one row: `Ok(report)` or the error message.
pub fn run_row(row: &InputRow) -> Result<ImpactReport, String> {
    let spec = row.to_spec()?;
    simulate(&spec).map_err(|e| e.to_string())
}

fn header() -> Vec<&'static str> {
    let mut h: Vec<&str> = ECHO_COLUMNS.to_vec();
    h.extend(RESULT_COLUMNS);
    h.push("error");
    h
}

fn answer_record(row: &InputRow, outcome: &Result<ImpactReport, String>) -> Vec<String> {
    let mut rec: Vec<String> = row.cells.to_vec();
    rec.extend(result_cells(outcome.as_ref().ok()));
    rec.push(outcome.as_ref().err().cloned().unwrap_or_default());
    rec
}

/// Counts of a batch run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BatchSummary {
    /// Rows read.
    pub rows: usize,
    /// Rows that failed (their `error` cell is filled).
    pub failed: usize,
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
    let base = InputRow::from_args(defaults);
    let mut writer = csv::Writer::from_writer(output);
    writer.write_record(header())?;
    let mut summary = BatchSummary::default();
    for (line, rec) in reader.records().enumerate() {
        summary.rows += 1;
        let mut row = base.clone();
        let outcome = match rec {
            Ok(rec) if rec.len() > map.len() => Err(format!(
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
                run_row(&row)
            }
            Err(e) => Err(format!("cannot read row {}: {e}", line + 1)),
        };
        if outcome.is_err() {
            summary.failed += 1;
        }
        writer.write_record(answer_record(&row, &outcome))?;
    }
    writer.flush()?;
    Ok(summary)
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

/// `host-sim impact`: with `--batch FILE`, [`run_batch`] (a summary of failed rows goes to
/// standard error; failed rows do not make it fail). Otherwise one impact from the flags,
/// printed as a header and one row; if it fails the row carries the message in `error` and
/// the command fails too. `--series FILE` also writes its force-time series, sampled every
/// `--series-interval` s (default: Hertz `t_c = 2.9432752 delta_max/u` over 500).
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
        return Ok(());
    }
    let row = InputRow::from_args(args);
    let outcome = row.to_spec().and_then(|mut spec| {
        if args.series.is_some() {
            let interval = match args.series_interval {
                Some(dt) => dt,
                None => {
                    let hz = spec.hertz().map_err(|e| e.to_string())?;
                    HERTZ_TC_FACTOR * hz.delta_max_m / hz.speed_m_s / 500.0
                }
            };
            spec.record = Some(interval);
        }
        simulate(&spec).map_err(|e| e.to_string())
    });
    let mut writer = csv::Writer::from_writer(out);
    writer.write_record(header())?;
    writer.write_record(answer_record(&row, &outcome))?;
    writer.flush()?;
    drop(writer);
    match outcome {
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
        for n in MATERIAL_NAMES {
            assert!(material_by_name(n).is_some(), "{n}");
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
            ("tol", "0", "rtol"),
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
