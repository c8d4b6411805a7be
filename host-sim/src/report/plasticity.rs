//! `host-sim plasticity`: peak force, contact time and restitution against impact speed for
//! each class of a scene, elastic (Hertz closed forms) against yielding (the class's law
//! integrated, and Thornton's closed forms when it is undamped); a table, a CSV file and SVG
//! figures.

use std::path::{Path, PathBuf};

use anyhow::Context;
use plotters::style::RGBColor;

use crate::physics::hertz64::HertzImpact64;
use crate::physics::impact::{ImpactSpec, simulate};
use crate::physics::integrate::Tolerance;
use crate::physics::law_spec::LawSpec;
use crate::physics::thornton::ThorntonImpact64;
use crate::report::paper::{Curve, Stroke, draw_svg, print_written};
use crate::report::write_stdout;
use crate::scene::{self, SceneFile};
use crate::score::yield_bayes::{YieldClass, yield_bayes_accuracy, yield_classes};

/// The SVG files written.
pub const SVG_FILES: [&str; 3] = [
    "yield_force_vs_speed.svg",
    "yield_duration_vs_speed.svg",
    "yield_restitution_vs_speed.svg",
];

/// The CSV file written.
pub const CSV_FILE: &str = "yield_vs_speed.csv";

/// What `host-sim plasticity` draws and where it writes.
#[derive(Debug, Clone, PartialEq)]
pub struct PlasticityOptions {
    /// Scene file; its classes that state `yield_pressure_pa` are drawn.
    pub scene: PathBuf,
    /// Directory for the CSV series and SVG figures (created if missing).
    pub out: PathBuf,
    /// Sphere radius in m (`None`: each class's geometric centre).
    pub radius_m: Option<f64>,
    /// Speeds per class, evenly spaced over its speed range (at least 2).
    pub points: usize,
    /// Draws per class of the noiseless Bayes limit, yielding and elastic (0: skip it; needs
    /// an undamped scene).
    pub bayes_draws: usize,
    /// Seed of the Bayes limit's draws.
    pub seed: u64,
}

impl Default for PlasticityOptions {
    /// `scenes/paper_yield.toml` into `out/plasticity`, each class's centre radius, 41 speeds,
    /// 20 000 Bayes draws per class, seed 1.
    fn default() -> Self {
        Self {
            scene: PathBuf::from("scenes/paper_yield.toml"),
            out: PathBuf::from("out/plasticity"),
            radius_m: None,
            points: 41,
            bayes_draws: 20_000,
            seed: 1,
        }
    }
}

/// One point of a class's sweep (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRow {
    /// Class name.
    pub class: String,
    /// Radius in m.
    pub radius_m: f64,
    /// Speed in m/s.
    pub speed_m_s: f64,
    /// Hertz `F_max` in N.
    pub elastic_force_n: f64,
    /// Hertz `t_c` in s.
    pub elastic_duration_s: f64,
    /// Peak force of the class's yielding law, integrated, in N.
    pub yield_force_n: f64,
    /// Force pulse duration of the yielding law, integrated, in s.
    pub yield_duration_s: f64,
    /// Restitution of the yielding law, integrated.
    pub yield_restitution: f64,
    /// Thornton's closed forms (undamped law only).
    pub closed: Option<ThorntonImpact64>,
}

/// The sweep of every yielding class of `scene` over `points` speeds of its range, at
/// `radius_m` or the class's geometric centre radius. Errors, naming the field, when no class
/// yields or an argument is out of range.
pub fn sweep(
    scene: &SceneFile,
    radius_m: Option<f64>,
    points: usize,
) -> anyhow::Result<Vec<SweepRow>> {
    anyhow::ensure!(points >= 2, "--points must be at least 2 (got {points})");
    if let Some(r) = radius_m {
        anyhow::ensure!(r.is_finite() && r > 0.0, "--radius must be > 0 m (got {r})");
    }
    anyhow::ensure!(
        scene.yields(),
        "the scene has no class with yield_pressure_pa: nothing yields"
    );
    let plate = scene.plate.material();
    let mut rows = Vec::new();
    for (i, c) in scene.classes.iter().enumerate() {
        let Some(p_y) = c.yield_pressure_pa else {
            continue;
        };
        let law = scene.class_law(i)?;
        let radius = radius_m.unwrap_or((c.radius_m.min * c.radius_m.max).sqrt());
        let u = c.speed_range_m_s();
        for j in 0..points {
            let speed = u.min + (u.max - u.min) * j as f64 / (points - 1) as f64;
            let mut spec = ImpactSpec::new(c.material.material(), plate, radius, speed);
            spec.law = law;
            spec.tolerance = Tolerance::new(1e-10);
            let hertz: HertzImpact64 = spec.hertz()?;
            let report = simulate(&spec)?;
            let undamped = matches!(law, LawSpec::Thornton { damping: None, .. });
            rows.push(SweepRow {
                class: c.name.clone(),
                radius_m: radius,
                speed_m_s: speed,
                elastic_force_n: hertz.peak_force_n,
                elastic_duration_s: hertz.duration_s,
                yield_force_n: report.peak_force_n,
                yield_duration_s: report.pulse_duration_s,
                yield_restitution: report.restitution,
                closed: if undamped {
                    Some(ThorntonImpact64::new(&hertz, p_y)?)
                } else {
                    None
                },
            });
        }
    }
    Ok(rows)
}

/// Writes the sweep as CSV to `path`.
fn write_csv(rows: &[SweepRow], path: &Path) -> anyhow::Result<()> {
    let mut w =
        csv::Writer::from_path(path).with_context(|| format!("cannot write {}", path.display()))?;
    w.write_record([
        "class",
        "radius_m",
        "speed_m_s",
        "elastic_force_n",
        "elastic_duration_s",
        "yield_force_n",
        "yield_duration_s",
        "yield_restitution",
        "thornton_force_n",
        "thornton_duration_s",
        "thornton_restitution",
    ])?;
    for r in rows {
        let closed = |f: fn(&ThorntonImpact64) -> f64| r.closed.as_ref().map(f);
        let opt = |v: Option<f64>| v.map(|x| format!("{x:.9e}")).unwrap_or_default();
        w.write_record([
            r.class.clone(),
            format!("{}", r.radius_m),
            format!("{}", r.speed_m_s),
            format!("{:.9e}", r.elastic_force_n),
            format!("{:.9e}", r.elastic_duration_s),
            format!("{:.9e}", r.yield_force_n),
            format!("{:.9e}", r.yield_duration_s),
            format!("{:.9}", r.yield_restitution),
            opt(closed(|t| t.peak_force_n)),
            opt(closed(|t| t.duration_s)),
            opt(closed(|t| t.restitution)),
        ])?;
    }
    w.flush()?;
    Ok(())
}

/// The curves of one figure: per class, elastic (dashed), yielding (solid) and Thornton's
/// closed forms (markers) of the quantity `y` (elastic value `None` for restitution, 1).
fn curves(rows: &[SweepRow], y: fn(&SweepRow) -> [Option<f64>; 3]) -> Vec<Curve> {
    const COLORS: [RGBColor; 4] = [
        RGBColor(20, 20, 20),
        RGBColor(200, 70, 20),
        RGBColor(30, 90, 200),
        RGBColor(40, 150, 60),
    ];
    let mut names: Vec<&str> = rows.iter().map(|r| r.class.as_str()).collect();
    names.dedup();
    let mut out = Vec::new();
    for (k, name) in names.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let of = |i: usize| -> Vec<(f64, f64)> {
            rows.iter()
                .filter(|r| r.class == *name)
                .filter_map(|r| y(r)[i].map(|v| (r.speed_m_s, v)))
                .collect()
        };
        for (i, what, stroke) in [
            (0, "elastic (Hertz)", Stroke::Dashed),
            (1, "yielding (integrated)", Stroke::Solid),
            (2, "Thornton closed form", Stroke::Markers),
        ] {
            let points = of(i);
            if !points.is_empty() {
                out.push(Curve {
                    label: format!("{name}: {what}"),
                    points,
                    color,
                    stroke,
                });
            }
        }
    }
    out
}

/// Writes [`SVG_FILES`] into `dir`; returns their paths.
fn write_svgs(rows: &[SweepRow], dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    type Pick = fn(&SweepRow) -> [Option<f64>; 3];
    let force: Pick = |r| {
        [
            Some(r.elastic_force_n / 1e3),
            Some(r.yield_force_n / 1e3),
            r.closed.map(|t| t.peak_force_n / 1e3),
        ]
    };
    let duration: Pick = |r| {
        [
            Some(r.elastic_duration_s * 1e6),
            Some(r.yield_duration_s * 1e6),
            r.closed.map(|t| t.duration_s * 1e6),
        ]
    };
    let restitution: Pick = |r| {
        [
            Some(1.0),
            Some(r.yield_restitution),
            r.closed.map(|t| t.restitution),
        ]
    };
    let specs = [
        (
            SVG_FILES[0],
            "Peak force against speed",
            "peak force F_max (kN)",
            force,
        ),
        (
            SVG_FILES[1],
            "Contact time against speed",
            "contact time t_c (us)",
            duration,
        ),
        (
            SVG_FILES[2],
            "Restitution against speed",
            "coefficient of restitution e",
            restitution,
        ),
    ];
    let mut paths = Vec::new();
    for (file, caption, y_label, pick) in specs {
        let path = dir.join(file);
        draw_svg(
            &path,
            caption,
            "impact speed u (m/s)",
            y_label,
            &curves(rows, pick),
            true,
        )?;
        paths.push(path);
    }
    Ok(paths)
}

/// Prints the noiseless Bayes limit of `scene` with its yield pressures and with none.
fn print_bayes(scene: &SceneFile, draws: usize, seed: u64) -> anyhow::Result<()> {
    let yielding = yield_classes(scene)?;
    let elastic: Vec<YieldClass> = yielding
        .iter()
        .map(|c| YieldClass {
            yield_pressure_pa: None,
            ..*c
        })
        .collect();
    let y = yield_bayes_accuracy(&yielding, draws, seed)?;
    let e = yield_bayes_accuracy(&elastic, draws, seed)?;
    write_stdout(&format!(
        "noiseless Bayes limit (exact F_max, t_c), {} draws: yielding {:.2} % +- {:.2} %, \
         elastic {:.2} % +- {:.2} %\n",
        y.n,
        100.0 * y.accuracy,
        100.0 * y.std_error,
        100.0 * e.accuracy,
        100.0 * e.std_error
    ))
}

/// `host-sim plasticity`: the sweep of every yielding class, printed as a table and written
/// as [`CSV_FILE`] and [`SVG_FILES`] into `args.out`.
pub fn run(args: &PlasticityOptions) -> anyhow::Result<()> {
    let scene = scene::load(&args.scene)?;
    let rows = sweep(&scene, args.radius_m, args.points)?;
    let every = ((args.points - 1) / 4).max(1);
    let table: String = rows
        .iter()
        .enumerate()
        .filter(|(i, _)| (i % args.points).is_multiple_of(every))
        .map(|(_, r)| {
            format!(
                "{}  {:.4}  {:.2}  {:.0}  {:.0}  {:.1}  {:.1}  {:.3}\n",
                r.class,
                r.radius_m,
                r.speed_m_s,
                r.elastic_force_n,
                r.yield_force_n,
                r.elastic_duration_s * 1e6,
                r.yield_duration_s * 1e6,
                r.yield_restitution
            )
        })
        .collect();
    write_stdout(&format!(
        "class  R (m)  u (m/s)  F_Hertz (N)  F_yield (N)  t_Hertz (us)  t_yield (us)  e\n{table}"
    ))?;
    if args.bayes_draws > 0 {
        print_bayes(&scene, args.bayes_draws, args.seed)?;
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let csv_path = args.out.join(CSV_FILE);
    write_csv(&rows, &csv_path)?;
    let mut files = vec![csv_path];
    files.extend(write_svgs(&rows, &args.out)?);
    print_written(&files)
}
