//! `host-sim tradeoff`, the files: the metrics and Pareto CSVs, the markdown table and the
//! Pareto SVG plots, written into the output directory.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use plotters::style::RGBColor;
use serde::Serialize;

use crate::report::paper::{Curve, Stroke, draw_svg};
use crate::report::tradeoff::config::{METRICS_CSV, PARETO_CSV, SVG_FILES, TABLE_MD};
use crate::report::tradeoff::pareto::ParetoPoint;
use crate::report::tradeoff::results::Tradeoff;
use crate::report::tradeoff::table::render_table;

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
