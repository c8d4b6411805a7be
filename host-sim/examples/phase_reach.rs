//! How much of the kernel's noiseless error on a damped pulse of 1.6-5 samples its phase table
//! leaves, and how much any table over the same coordinates could remove (`docs/few_samples.md`).
//! One impact of the law (coal, R 0.02 m, u 2 m/s; the restitution laws' pulses are
//! self-similar) is sampled at 600 samples per pulse `n` (1.6-5, log-spaced; the duration from
//! the area) and 64 phases, `(j + 0.17) / 64`, fitted with the kernel's three-sample fit, and
//! corrected
//!
//! - by the phase table with its means on the rows (`phase_calibration_on_rows` of this
//!   pulse, at its own 32 phases per row), read as the kernel reads it (`n` from the measured duration by two fixed-point
//!   steps), read at the true `n`, with 20 fixed-point steps, with `n` by bisection, and at the
//!   `n` the sums of the samples and of their squares give, `(sum v)^2 / sum v^2` over its
//!   continuous value per duration (with that `n`'s own error beside the measured duration's);
//! - by the scene build's phase table (`phase_calibration`, its means refitted to the fits as
//!   the kernel reads them), read as the kernel reads it;
//! - by fine tables (means over the phases `(j + 0.5) / 64`) over `(ln n measured, a)` (bins of
//!   0.01 x 0.01), over `(ln n measured, before / largest, after / largest)` (0.01 x 0.02 x
//!   0.02) and over `(true ln n, a)`: what those coordinates allow;
//! - by coarse tables of several sizes over `(ln n measured, a)`, read bilinearly with no
//!   fixed point, their cells the means of the nearest fits or the least-squares fit of the
//!   bilinear reading to all of them, and over `(true ln n, a)` (built and read as the
//!   scene's table is).
//!
//! It prints the root mean square of `ln F_max / ln t_c` each leaves, by band of `n`.
//!
//! `cargo run --release -p host-sim --example phase_reach -- [LAW] [E]` (LAW flores,
//! hunt_crossley, gonthier or tsuji; flores 0.3 by default).

use coalshock::math::Libm;
use coalshock::shape_fit::five_about;
use host_sim::bridge::calibrate::{C_AREA, area_energy_peak};
use host_sim::bridge::sampled_fit::{ContinuousPulse, sample_series};
use host_sim::bridge::sampled_phase::{phase_calibration, phase_calibration_on_rows};
use host_sim::physics::hertz64::Material64;
use host_sim::physics::impact::{ImpactSpec, simulate};
use host_sim::physics::law_spec::LawSpec;
use std::collections::HashMap;

/// Residuals `ln F_max / ln t_c` left on the test fits, each with its fit's true `n`.
type Residuals = Vec<(f64, [f64; 2])>;

const BANDS: [f64; 6] = [1.6, 2.0, 2.5, 3.2, 4.0, 5.0];

/// The restitution-parametrised law `name` (as a scene file names it) at restitution `e`.
fn law(name: &str, e: f64) -> LawSpec {
    LawSpec::restitution_law(name, e)
        .expect("LAW: hunt_crossley, lankarani_nikravesh, flores, gonthier or tsuji")
}

/// One fit: true `n`, measured `n`, asymmetry, before / largest, after / largest, errors.
struct Fit {
    n: f64,
    n_meas: f64,
    a: f64,
    before: f64,
    after: f64,
    err: [f64; 2],
    /// `(sum v)^2 / sum v^2`: the duration in samples the area and the energy give, over its
    /// continuous constant.
    area_energy: f64,
}

fn fit(series: &[(f64, f64)], peak: f64, duration: f64, n: f64, phase: f64) -> Option<Fit> {
    let dt = duration / n;
    let v = sample_series(series, dt, phase)?;
    let (i, _) = v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let sum: f64 = v.iter().sum();
    let sum_sq: f64 = v.iter().map(|x| x * x).sum();
    let v32: Vec<f32> = v.iter().map(|&x| x as f32).collect();
    let top = five_about(&v32, i);
    let (p, samples) = coalshock::detector::shape_fit::<Libm>(top, sum as f32, false)?;
    let m = f64::from(top[2]);
    Some(Fit {
        n,
        n_meas: f64::from(samples),
        a: f64::from(coalshock::sampled_phase::neighbour_asymmetry(
            top[1], top[2], top[3],
        )),
        before: f64::from(top[1]) / m,
        after: f64::from(top[3]) / m,
        err: [
            (f64::from(p) / peak).ln(),
            (f64::from(samples) * dt / duration).ln(),
        ],
        area_energy: sum * sum / sum_sq,
    })
}

fn band(n: f64) -> usize {
    BANDS.iter().rposition(|&b| n >= b).unwrap_or(0)
}

/// Root mean square per band of `residuals` `(n, [ln F, ln t])`.
fn print_rms(name: &str, residuals: &[(f64, [f64; 2])]) {
    let mut s = vec![[0.0f64; 3]; BANDS.len()];
    for (n, r) in residuals {
        let b = band(*n);
        s[b][0] += r[0] * r[0];
        s[b][1] += r[1] * r[1];
        s[b][2] += 1.0;
    }
    let cells: Vec<String> = s[..BANDS.len() - 1]
        .iter()
        .map(|c| format!("{:.4} / {:.4}", (c[0] / c[2]).sqrt(), (c[1] / c[2]).sqrt()))
        .collect();
    println!("| {name} | {} |", cells.join(" | "));
}

/// Residuals of `test` against the means of `train` in the bins `key` gives.
fn binned<K: std::hash::Hash + Eq>(
    train: &[Fit],
    test: &[Fit],
    key: impl Fn(&Fit) -> K,
) -> Residuals {
    let mut sums: HashMap<K, [f64; 3]> = HashMap::new();
    for f in train {
        let e = sums.entry(key(f)).or_insert([0.0; 3]);
        e[0] += f.err[0];
        e[1] += f.err[1];
        e[2] += 1.0;
    }
    test.iter()
        .filter_map(|f| {
            let s = sums.get(&key(f))?;
            Some((f.n, [f.err[0] - s[0] / s[2], f.err[1] - s[1] / s[2]]))
        })
        .collect()
}

/// Each cell of `row` the mean of `sums` (`[sum ln F, sum ln t, count]`) at the nearest
/// column that holds any.
fn fill_nearest(row: &mut [[f64; 2]], sums: &[[f64; 3]]) {
    for (c, cell) in row.iter_mut().enumerate() {
        let filled = (0..sums.len())
            .filter(|&d| sums[d][2] > 0.0)
            .min_by_key(|&d| d.abs_diff(c));
        if let Some(d) = filled {
            let s = sums[d];
            *cell = [s[0] / s[2], s[1] / s[2]];
        }
    }
}

/// A table of `rows` rows (`ln n measured` from `ln_first`, step `ln_step`) by `cols`
/// asymmetry points, means of the nearest training fits, read bilinearly (as
/// `SampledPhase::at` reads): the residuals of `test`.
fn coarse(
    train: &[Fit],
    test: &[Fit],
    ln_first: f64,
    ln_step: f64,
    rows: usize,
    cols: usize,
) -> Residuals {
    let row_of = |f: &Fit| ((f.n_meas.ln() - ln_first) / ln_step).round();
    let mut axes = vec![[f64::INFINITY, f64::NEG_INFINITY]; rows];
    for f in train {
        let r = row_of(f);
        if r >= 0.0 && (r as usize) < rows {
            let ax = &mut axes[r as usize];
            ax[0] = ax[0].min(f.a);
            ax[1] = ax[1].max(f.a);
        }
    }
    let col_of = |r: usize, a: f64| {
        let [lo, hi] = axes[r];
        let step = (hi - lo) / (cols - 1) as f64;
        if step > 0.0 {
            ((a - lo) / step).clamp(0.0, (cols - 1) as f64)
        } else {
            0.0
        }
    };
    let mut sums = vec![vec![[0.0f64; 3]; cols]; rows];
    for f in train {
        let r = row_of(f);
        if r >= 0.0 && (r as usize) < rows {
            let r = r as usize;
            let c = col_of(r, f.a).round() as usize;
            sums[r][c][0] += f.err[0];
            sums[r][c][1] += f.err[1];
            sums[r][c][2] += 1.0;
        }
    }
    let mut mean = vec![vec![[0.0f64; 2]; cols]; rows];
    for (row, sums) in mean.iter_mut().zip(&sums) {
        fill_nearest(row, sums);
    }
    let read_row = |r: usize, a: f64| {
        let pos = col_of(r, a);
        let i = (pos.floor() as usize).min(cols - 2);
        let t = pos - i as f64;
        let (m0, m1) = (mean[r][i], mean[r][i + 1]);
        [m0[0] + (m1[0] - m0[0]) * t, m0[1] + (m1[1] - m0[1]) * t]
    };
    test.iter()
        .filter_map(|f| {
            let x = ((f.n_meas.ln() - ln_first) / ln_step).max(0.0);
            if x > (rows - 1) as f64 {
                return None;
            }
            let i = (x.floor() as usize).min(rows - 2);
            let t = x - i as f64;
            let (v0, v1) = (read_row(i, f.a), read_row(i + 1, f.a));
            let v = [v0[0] + (v1[0] - v0[0]) * t, v0[1] + (v1[1] - v0[1]) * t];
            Some((f.n, [f.err[0] - v[0], f.err[1] - v[1]]))
        })
        .collect()
}

/// A table of `rows` rows at true `n = 1.6 step^k` by `cols` asymmetry points, each row's
/// means from the pulse sampled at that `n` and 32 phases (as `phase_calibration` takes
/// them), read as the kernel reads its table (two fixed-point steps from the measured `n`):
/// the residuals of `test`.
#[allow(clippy::too_many_arguments)]
fn coarse_true(
    series: &[(f64, f64)],
    peak: f64,
    duration: f64,
    test: &[Fit],
    step: f64,
    rows: usize,
    cols: usize,
) -> Residuals {
    let n_of = |k: usize| 1.6 * step.powi(k as i32);
    let mut axes = vec![[0.0f64; 2]; rows];
    let mut mean = vec![vec![[0.0f64; 2]; cols]; rows];
    for k in 0..rows {
        let fits: Vec<Fit> = (0..32)
            .filter_map(|j| fit(series, peak, duration, n_of(k), (j as f64 + 0.5) / 32.0))
            .collect();
        let lo = fits.iter().map(|f| f.a).fold(f64::INFINITY, f64::min);
        let hi = fits.iter().map(|f| f.a).fold(f64::NEG_INFINITY, f64::max);
        axes[k] = [lo, hi];
        let mut sums = vec![[0.0f64; 3]; cols];
        let st = (hi - lo) / (cols - 1) as f64;
        for f in &fits {
            let c = if st > 0.0 {
                ((f.a - lo) / st).round() as usize
            } else {
                0
            };
            sums[c][0] += f.err[0];
            sums[c][1] += f.err[1];
            sums[c][2] += 1.0;
        }
        fill_nearest(&mut mean[k], &sums);
    }
    let at = |ln_n: f64, a: f64| -> Option<[f64; 2]> {
        let x = ((ln_n - 1.6f64.ln()) / step.ln()).max(0.0);
        if x > (rows - 1) as f64 {
            return None;
        }
        let i = (x.floor() as usize).min(rows - 2);
        let t = x - i as f64;
        let row = |k: usize| {
            let [lo, hi] = axes[k];
            let st = (hi - lo) / (cols - 1) as f64;
            let pos = if st > 0.0 {
                ((a - lo) / st).clamp(0.0, (cols - 1) as f64)
            } else {
                0.0
            };
            let j = (pos.floor() as usize).min(cols - 2);
            let u = pos - j as f64;
            let (m0, m1) = (mean[k][j], mean[k][j + 1]);
            [m0[0] + (m1[0] - m0[0]) * u, m0[1] + (m1[1] - m0[1]) * u]
        };
        let (v0, v1) = (row(i), row(i + 1));
        Some([v0[0] + (v1[0] - v0[0]) * t, v0[1] + (v1[1] - v0[1]) * t])
    };
    test.iter()
        .filter_map(|f| {
            let ln_meas = f.n_meas.ln();
            let mut ln_n = ln_meas;
            for _ in 0..2 {
                ln_n = ln_meas - at(ln_n, f.a)?[1];
            }
            let v = at(ln_n, f.a)?;
            Some((f.n, [f.err[0] - v[0], f.err[1] - v[1]]))
        })
        .collect()
}

/// A `rows x cols` table over `(ln n measured, a)` (rows from `ln_first`, `ln_step` apart; each
/// row's asymmetry axis the range of the training fits within a row step of it) whose node
/// values are the least-squares fit of the bilinear reading to the training fits (with a weak
/// penalty on neighbours' differences where fits are few): the residuals of `test`.
fn least_squares_measured(
    train: &[Fit],
    test: &[Fit],
    ln_first: f64,
    ln_step: f64,
    rows: usize,
    cols: usize,
) -> Residuals {
    let x_of = |f: &Fit| (f.n_meas.ln() - ln_first) / ln_step;
    let mut axes = vec![[f64::INFINITY, f64::NEG_INFINITY]; rows];
    for f in train {
        let x = x_of(f);
        for (k, ax) in axes.iter_mut().enumerate() {
            if (x - k as f64).abs() <= 1.0 {
                ax[0] = ax[0].min(f.a);
                ax[1] = ax[1].max(f.a);
            }
        }
    }
    // The nodes and weights of the bilinear reading at (x, a).
    let weights = |x: f64, a: f64| -> Option<Vec<(usize, f64)>> {
        if !(0.0..=(rows - 1) as f64).contains(&x) {
            return None;
        }
        let i = (x.floor() as usize).min(rows - 2);
        let t = x - i as f64;
        let mut w = Vec::with_capacity(4);
        for (k, wk) in [(i, 1.0 - t), (i + 1, t)] {
            let [lo, hi] = axes[k];
            let st = (hi - lo) / (cols - 1) as f64;
            let pos = if st > 0.0 {
                ((a - lo) / st).clamp(0.0, (cols - 1) as f64)
            } else {
                0.0
            };
            let j = (pos.floor() as usize).min(cols - 2);
            let u = pos - j as f64;
            w.push((k * cols + j, wk * (1.0 - u)));
            w.push((k * cols + j + 1, wk * u));
        }
        Some(w)
    };
    let m = rows * cols;
    let mut ata = vec![vec![0.0f64; m]; m];
    let mut aty = vec![[0.0f64; 2]; m];
    for f in train {
        let Some(w) = weights(x_of(f), f.a) else {
            continue;
        };
        for &(p, wp) in &w {
            aty[p][0] += wp * f.err[0];
            aty[p][1] += wp * f.err[1];
            for &(q, wq) in &w {
                ata[p][q] += wp * wq;
            }
        }
    }
    let lambda = 1e-3;
    for k in 0..rows {
        for j in 0..cols {
            let p = k * cols + j;
            for q in [
                (j + 1 < cols).then(|| p + 1),
                (k + 1 < rows).then(|| p + cols),
            ]
            .into_iter()
            .flatten()
            {
                ata[p][p] += lambda;
                ata[q][q] += lambda;
                ata[p][q] -= lambda;
                ata[q][p] -= lambda;
            }
        }
    }
    let v = solve(ata, aty);
    test.iter()
        .filter_map(|f| {
            let w = weights(x_of(f), f.a)?;
            let mut e = f.err;
            for (p, wp) in w {
                e[0] -= wp * v[p][0];
                e[1] -= wp * v[p][1];
            }
            Some((f.n, e))
        })
        .collect()
}

/// `a x = b` (two right-hand sides) by Gaussian elimination with partial pivoting.
fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap_or(c);
        a.swap(c, p);
        b.swap(c, p);
        let d = a[c][c];
        if d.abs() < 1e-300 {
            continue;
        }
        for r in c + 1..n {
            let f = a[r][c] / d;
            if f != 0.0 {
                let (top, rest) = a.split_at_mut(r);
                for (x, y) in rest[0][c..].iter_mut().zip(&top[c][c..]) {
                    *x -= f * y;
                }
                let bc = b[c];
                b[r][0] -= f * bc[0];
                b[r][1] -= f * bc[1];
            }
        }
    }
    let mut x = vec![[0.0f64; 2]; n];
    for c in (0..n).rev() {
        let mut s = b[c];
        for k in c + 1..n {
            s[0] -= a[c][k] * x[k][0];
            s[1] -= a[c][k] * x[k][1];
        }
        x[c] = [s[0] / a[c][c], s[1] / a[c][c]];
    }
    x
}

/// The residual `ln F_max / ln t_c` that `t` leaves on `f` read at `ln_n`, by `f`'s true `n`.
fn left_at(t: &coalshock::SampledPhase, f: &Fit, ln_n: f32) -> Option<(f64, [f64; 2])> {
    let (lf, lt, _, _) = t.at(ln_n, f.a as f32)?;
    Some((f.n, [f.err[0] - f64::from(lf), f.err[1] - f64::from(lt)]))
}

/// The `ln n` that `steps` fixed-point steps of `ln n = ln n_measured - ln_duration(ln n, a)`
/// settle on (the kernel takes two).
fn fixed_point(t: &coalshock::SampledPhase, f: &Fit, steps: usize) -> Option<f32> {
    let ln_meas = f.n_meas.ln() as f32;
    let mut ln_n = ln_meas;
    for _ in 0..steps {
        ln_n = ln_meas - t.at(ln_n, f.a as f32)?.1;
    }
    Some(ln_n)
}

/// The `ln n` of `ln n + ln_duration(ln n, a) = ln n_measured` by 30 bisections over the
/// table's rows.
fn bisection(t: &coalshock::SampledPhase, f: &Fit) -> Option<f32> {
    let ln_meas = f.n_meas.ln() as f32;
    let h = |x: f32| t.at(x, f.a as f32).map(|v| x + v.1 - ln_meas);
    let (mut lo, mut hi) = (1.6f32.ln(), 11.9f32.ln());
    if h(lo)? > 0.0 {
        hi = lo;
    }
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if h(mid)? > 0.0 { hi = mid } else { lo = mid }
    }
    Some(0.5 * (lo + hi))
}

/// `(label, residuals)` of the phase tables read each way over the test fits (see the module
/// docs), and the error of `ln n` from the area and the energy.
fn readings(
    series: &[(f64, f64)],
    duration: f64,
    table: &coalshock::SampledPhase,
    least_squares: &coalshock::SampledPhase,
    test: &[Fit],
) -> Vec<(&'static str, Residuals)> {
    // The continuous pulse's (integral F)^2 / (integral F^2) over its duration from the area.
    let (mut e2, mut a1) = (0.0, 0.0);
    for w in series.windows(2) {
        let h = w[1].0 - w[0].0;
        a1 += 0.5 * h * (w[0].1 + w[1].1);
        e2 += 0.5 * h * (w[0].1 * w[0].1 + w[1].1 * w[1].1);
    }
    let ae_per_duration = a1 * a1 / e2 / duration;
    // The detector measures no pulse shorter than MIN_DURATION_SAMPLES.
    let measured = |f: &&Fit| f.n_meas >= f64::from(coalshock::scene::MIN_DURATION_SAMPLES);
    let read =
        |t: &coalshock::SampledPhase, only_measured: bool, at: &dyn Fn(&Fit) -> Option<f32>| {
            test.iter()
                .filter(|f| !only_measured || measured(f))
                .filter_map(|f| left_at(t, f, at(f)?))
                .collect::<Vec<_>>()
        };
    let two_steps = |t| move |f: &Fit| fixed_point(t, f, 2);
    vec![
        (
            "none (the fit's own error)",
            test.iter().map(|f| (f.n, f.err)).collect(),
        ),
        (
            "the phase table on the rows, read as the kernel reads it",
            read(table, false, &two_steps(table)),
        ),
        (
            "the scene's phase table (least squares as read), read as the kernel reads it",
            read(least_squares, false, &two_steps(least_squares)),
        ),
        (
            "the phase table on the rows, as read, pulses measured >= 2.5 samples",
            read(table, true, &two_steps(table)),
        ),
        (
            "the scene's phase table (least squares as read), as read, pulses measured >= 2.5 samples",
            read(least_squares, true, &two_steps(least_squares)),
        ),
        (
            "the phase table on the rows, read at the true n",
            read(table, false, &|f| Some(f.n.ln() as f32)),
        ),
        (
            "the phase table on the rows, read at n from the area and the energy",
            read(table, false, &|f| {
                Some((f.area_energy / ae_per_duration).ln() as f32)
            }),
        ),
        (
            "error of ln n from the area and the energy / of the measured duration",
            test.iter()
                .map(|f| {
                    (
                        f.n,
                        [
                            (f.area_energy / ae_per_duration / f.n).ln(),
                            (f.n_meas / f.n).ln(),
                        ],
                    )
                })
                .collect(),
        ),
        (
            "the phase table on the rows, 20 fixed-point steps",
            read(table, false, &|f| fixed_point(table, f, 20)),
        ),
        (
            "the phase table on the rows, n by bisection",
            read(table, false, &|f| bisection(table, f)),
        ),
    ]
}

/// Prints the rows of the coarse tables over `(ln n measured, a)` (means and least squares)
/// and over `(true ln n, a)`, from the smallest measured `n` `low`.
fn print_coarse(
    series: &[(f64, f64)],
    peak: f64,
    duration: f64,
    train: &[Fit],
    test: &[Fit],
    low: f64,
) {
    let on_measured = format!("apart from {low:.2}");
    let means = |rows, step: f64, cols| coarse(train, test, low.ln(), step.ln(), rows, cols);
    let least = |rows, step: f64, cols| {
        least_squares_measured(train, test, low.ln(), step.ln(), rows, cols)
    };
    let true_n = |rows, step, cols| coarse_true(series, peak, duration, test, step, rows, cols);
    type Build<'a> = &'a dyn Fn(usize, f64, usize) -> Residuals;
    type Sizes<'a> = &'a [(usize, f64, usize)];
    let kinds: [(&str, &str, Sizes, Build); 3] = [
        (
            "table over (ln n measured, a), rows",
            &on_measured,
            &[
                (10, 1.25, 8),
                (10, 1.25, 16),
                (16, 1.15, 8),
                (20, 1.12, 8),
                (20, 1.12, 16),
            ],
            &means,
        ),
        (
            "least-squares table over (ln n measured, a), rows",
            &on_measured,
            &[(10, 1.25, 8), (10, 1.25, 16), (20, 1.12, 8), (20, 1.12, 16)],
            &least,
        ),
        (
            "table over (true ln n, a), rows",
            "apart, read as the kernel reads",
            &[
                (10, 1.25, 8),
                (10, 1.25, 16),
                (19, 1.12, 8),
                (19, 1.12, 16),
                (37, 1.06, 32),
            ],
            &true_n,
        ),
    ];
    for (what, tail, sizes, build) in kinds {
        for &(rows, step, cols) in sizes {
            print_rms(
                &format!("{rows} x {cols} {what} {step} {tail}"),
                &build(rows, step, cols),
            );
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("flores", |s| s.as_str());
    let e: f64 = args.get(2).map_or(0.3, |s| s.parse().expect("E"));
    let mut spec = ImpactSpec::new(Material64::COAL, Material64::CARBON_STEEL, 0.02, 2.0);
    spec.law = law(name, e);
    let hertz_s = spec.hertz().expect("an impact").duration_s;
    spec.record = Some(hertz_s / 8000.0);
    let series = simulate(&spec)
        .expect("an impact")
        .force_series
        .unwrap_or_default();
    let (area, _, peak) = area_energy_peak(&series);
    let duration = area / (C_AREA * peak);
    let pulse = ContinuousPulse {
        series: &series,
        peak_n: peak,
        duration_s: duration,
        // A restitution law is self-similar; below 7.8 samples the fit reads three anyway.
        five: true,
    };
    let table = phase_calibration_on_rows(std::slice::from_ref(&pulse)).to_kernel();
    let least_squares = phase_calibration(std::slice::from_ref(&pulse), None).to_kernel();
    let ns: Vec<f64> = (0..600)
        .map(|i| 1.6 * (5.0f64 / 1.6).powf(i as f64 / 599.0))
        .collect();
    let fits = |offset: f64| -> Vec<Fit> {
        ns.iter()
            .flat_map(|&n| (0..64).map(move |j| (n, (j as f64 + offset) / 64.0)))
            .filter_map(|(n, ph)| fit(&series, peak, duration, n, ph))
            .collect()
    };
    let (train, test) = (fits(0.5), fits(0.17));
    println!(
        "{name} e {e}: rms of ln F_max / ln t_c left, noiseless, by samples per pulse (duration from the area)"
    );
    println!("| correction | 1.6-2 | 2-2.5 | 2.5-3.2 | 3.2-4 | 4-5 |");
    println!("|---|---|---|---|---|---|");
    for (label, residuals) in readings(&series, duration, &table, &least_squares, &test) {
        print_rms(label, &residuals);
    }
    let q = |x: f64, w: f64| (x / w).round() as i64;
    print_rms(
        "fine table over (ln n measured, a)",
        &binned(&train, &test, |f| (q(f.n_meas.ln(), 0.01), q(f.a, 0.01))),
    );
    print_rms(
        "fine table over (ln n measured, before, after)",
        &binned(&train, &test, |f| {
            (q(f.n_meas.ln(), 0.01), q(f.before, 0.02), q(f.after, 0.02))
        }),
    );
    let low = test
        .iter()
        .filter(|f| f.n < 1.65)
        .map(|f| f.n_meas)
        .fold(f64::INFINITY, f64::min);
    println!("(smallest measured n at true n 1.6-1.65: {low:.3})");
    print_coarse(&series, peak, duration, &train, &test, low);
    print_rms(
        "fine table over (true ln n, a)",
        &binned(&train, &test, |f| (q(f.n.ln(), 0.01), q(f.a, 0.01))),
    );
}
