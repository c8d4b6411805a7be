//! How much of the kernel's error of `(ln F_max, ln t_c)` on a damped pulse of a few samples
//! is the sample's phase, and how much of it a correction that follows the phase could
//! remove: the diagnosis behind the strongly damped scenes' misses at 25 kS/s and below
//! (`docs/grid.md`).
//!
//! One impact of the law is integrated (the restitution laws' pulses are self-similar: the
//! example checks that a second impact of another material, size and speed gives the same
//! errors), sampled at `n` samples of its duration from the area (2.4 to 14) at 64 phases,
//! and fitted with the kernel's own `shape_fit` (largest sample, its neighbours, the sum).
//! Per band of `n` it prints the root mean square of the fit's error left
//!
//! - by a correction that knows `n` but not the phase (the phase mean at each `n`: the best a
//!   table over samples per pulse alone, `SampledCalibration`, can do), and
//! - by a table over `n` (8 points, `2.5 x 1.25^k`) and the neighbours' asymmetry
//!   `a = (after - before) / largest` (8 cells between the smallest and the largest `a` seen
//!   at that `n`), linear in both; the phase is what sets `a`.
//!
//! `cargo run --release -p host-sim --example sampled_phase -- [LAW] [E]` (LAW flores,
//! hunt_crossley, lankarani_nikravesh, gonthier or tsuji; E the restitution; flores 0.5 by
//! default).

use coalshock::detector::shape_fit;
use coalshock::math::Libm;
use coalshock::shape_fit::five_about;
use host_sim::bridge::calibrate::{C_AREA, area_energy_peak};
use host_sim::bridge::sampled_fit::force_at;
use host_sim::physics::hertz64::Material64;
use host_sim::physics::impact::{ImpactSpec, simulate};
use host_sim::physics::law_spec::LawSpec;

/// Phases per `n`.
const PHASES: usize = 64;
/// Table points in `n` and cells in the asymmetry.
const POINTS: usize = 8;
const CELLS: usize = 8;

/// One fit: `n`, `ln(F_fit / F)`, `ln(t_fit / t)`, asymmetry.
type Fit = (f64, f64, f64, f64);

/// The restitution-parametrised law `name` (as a scene file names it) at restitution `e`.
fn law(name: &str, e: f64) -> LawSpec {
    LawSpec::restitution_law(name, e)
        .expect("LAW: hunt_crossley, lankarani_nikravesh, flores, gonthier or tsuji")
}

/// The force series of one impact, its peak, its duration from the area and that over the
/// Hertz contact time.
fn pulse(
    sphere: Material64,
    radius_m: f64,
    speed_m_s: f64,
    law: LawSpec,
) -> (Vec<(f64, f64)>, f64, f64, f64) {
    let mut spec = ImpactSpec::new(sphere, Material64::CARBON_STEEL, radius_m, speed_m_s);
    spec.law = law;
    let hertz_s = spec.hertz().expect("an impact").duration_s;
    spec.record = Some(hertz_s / 8000.0);
    let series = simulate(&spec)
        .expect("an impact")
        .force_series
        .unwrap_or_default();
    let (area, _, peak) = area_energy_peak(&series);
    let duration = area / (C_AREA * peak);
    (series, peak, duration, duration / hertz_s)
}

/// The kernel's fit of the pulse sampled at `n` samples of `duration_s`, at each phase.
fn fits(series: &[(f64, f64)], peak: f64, duration_s: f64, n: f64) -> Vec<Fit> {
    let dt = duration_s / n;
    let (t0, t1) = (series[0].0, series[series.len() - 1].0);
    let mut out = Vec::new();
    for ph in 0..PHASES {
        let mut t = t0 - dt + dt * ph as f64 / PHASES as f64;
        let mut v = Vec::new();
        while t < t1 + dt {
            v.push(force_at(series, t));
            t += dt;
        }
        let Some((i, &top)) = v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)) else {
            continue;
        };
        let before = if i > 0 { v[i - 1] } else { 0.0 };
        let after = v.get(i + 1).copied().unwrap_or(0.0);
        let sum: f64 = v.iter().sum();
        let v32: Vec<f32> = v.iter().map(|&x| x as f32).collect();
        // A damped contact's pulse is read with the three samples about its top (`five` false).
        if let Some((f, samples)) = shape_fit::<Libm>(five_about(&v32, i), sum as f32, false) {
            let lf = (f as f64 / peak).ln();
            let lt = (samples as f64 * dt / duration_s).ln();
            out.push((n, lf, lt, (after - before) / top));
        }
    }
    out
}

/// Per table point: the smallest and largest asymmetry and the cells' mean errors.
struct Point {
    ln_n: f64,
    lo: f64,
    hi: f64,
    force: [f64; CELLS],
    duration: [f64; CELLS],
}

fn table_point(fits: &[Fit]) -> Point {
    let lo = fits.iter().map(|f| f.3).fold(f64::INFINITY, f64::min);
    let hi = fits.iter().map(|f| f.3).fold(f64::NEG_INFINITY, f64::max);
    let mut sums = [[0.0f64; 3]; CELLS];
    for f in fits {
        let c = (((f.3 - lo) / (hi - lo) * CELLS as f64) as usize).min(CELLS - 1);
        sums[c][0] += 1.0;
        sums[c][1] += f.1;
        sums[c][2] += f.2;
    }
    let mean = |k: usize| sums.map(|s| if s[0] > 0.0 { s[k] / s[0] } else { 0.0 });
    Point {
        ln_n: fits[0].0.ln(),
        lo,
        hi,
        force: mean(1),
        duration: mean(2),
    }
}

/// The table's `(ln F, ln t)` correction at `n` and asymmetry `a`, linear in `ln n` and in
/// the cell coordinate.
fn lookup(table: &[Point], n: f64, a: f64) -> (f64, f64) {
    let x = n.ln();
    let k = table
        .partition_point(|p| p.ln_n <= x)
        .clamp(1, table.len() - 1);
    let w = ((x - table[k - 1].ln_n) / (table[k].ln_n - table[k - 1].ln_n)).clamp(0.0, 1.0);
    let at = |p: &Point| {
        let s = (((a - p.lo) / (p.hi - p.lo)).clamp(0.0, 1.0) * CELLS as f64 - 0.5)
            .clamp(0.0, (CELLS - 1) as f64);
        let j = (s as usize).min(CELLS - 2);
        let u = s - j as f64;
        (
            p.force[j] * (1.0 - u) + p.force[j + 1] * u,
            p.duration[j] * (1.0 - u) + p.duration[j + 1] * u,
        )
    };
    let (a0, a1) = (at(&table[k - 1]), at(&table[k]));
    (a0.0 * (1.0 - w) + a1.0 * w, a0.1 * (1.0 - w) + a1.1 * w)
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0.0);
    for x in v {
        s += x * x;
        n += 1.0;
    }
    if n > 0.0 { (s / n).sqrt() } else { 0.0 }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("flores", |s| s.as_str());
    let e: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.5);
    let (series, peak, duration, ratio) = pulse(Material64::COAL, 0.02, 2.0, law(name, e));
    let (other, other_peak, other_duration, _) =
        pulse(Material64::SANDSTONE, 0.035, 4.5, law(name, e));
    let ns: Vec<f64> = (0..=100)
        .map(|k| 2.4 * (14.0f64 / 2.4).powf(k as f64 / 100.0))
        .collect();
    let mut all = Vec::new();
    let mut differs = 0.0f64;
    for &n in &ns {
        let (a, b) = (
            fits(&series, peak, duration, n),
            fits(&other, other_peak, other_duration, n),
        );
        for (x, y) in a.iter().zip(&b) {
            differs = differs.max((x.1 - y.1).abs()).max((x.2 - y.2).abs());
        }
        all.push(a);
    }
    let table: Vec<Point> = (0..POINTS)
        .map(|k| table_point(&fits(&series, peak, duration, 2.5 * 1.25f64.powi(k as i32))))
        .collect();
    println!(
        "{name} e {e}: duration from the area over the Hertz contact time {ratio:.3} (samples \
         per pulse below count that duration); coal R 0.02 m u 2 m/s against sandstone \
         R 0.035 m u 4.5 m/s, largest difference of the fit's errors {differs:.1e}"
    );
    println!(
        "| samples per pulse | phase-blind rms ln F | ln t | (n, asymmetry) table rms ln F | ln t |"
    );
    println!("|---|---|---|---|---|");
    for (lo, hi) in [
        (2.5, 3.2),
        (3.2, 4.0),
        (4.0, 5.0),
        (5.0, 7.0),
        (7.0, 10.0),
        (10.0, 11.9),
    ] {
        let band: Vec<&Vec<Fit>> = all.iter().filter(|f| f[0].0 >= lo && f[0].0 < hi).collect();
        let blind = |k: usize| {
            rms(band.iter().flat_map(|f| {
                let m = f
                    .iter()
                    .map(|x| if k == 1 { x.1 } else { x.2 })
                    .sum::<f64>()
                    / f.len() as f64;
                f.iter()
                    .map(move |x| if k == 1 { x.1 - m } else { x.2 - m })
            }))
        };
        let table_rms = |k: usize| {
            rms(band.iter().flat_map(|f| f.iter()).map(|x| {
                let (cf, ct) = lookup(&table, x.0, x.3);
                if k == 1 { x.1 - cf } else { x.2 - ct }
            }))
        };
        println!(
            "| {lo}-{hi} | {:.4} | {:.4} | {:.4} | {:.4} |",
            blind(1),
            blind(2),
            table_rms(1),
            table_rms(2)
        );
    }
}
