//! The sampling correction of a damped contact by samples per pulse and sampling phase
//! (`coalshock::SampledPhase`): the kernel's own three-sample fit on the integrator's pulses at
//! each row `n_k` and [`TABLE_PHASES`] phases, binned by the neighbour asymmetry the kernel
//! measures on the same samples. Its means are then refitted, by least squares under the
//! kernel's bilinear reading, to the fits where the kernel reads them
//! (`least_squares_as_read`), and each cell's spread is what the table leaves as the kernel
//! reads it (`spread_as_read`): between its rows as well as on them, at the samples per
//! pulse the kernel infers from the measured duration. Behind a chain that is not rigid the
//! pulses are fitted as the detector sees them there, through the chain and the kernel's
//! equaliser ([`EqualisedChain`]).

use coalshock::sampled_phase::{
    PHASE_COLUMNS, PHASE_FIRST_N, PHASE_ROWS, PHASE_STEP, SampledPhase,
};
use coalshock::scene::MIN_DURATION_SAMPLES;

use crate::bridge::equalised_fit::EqualisedChain;
use crate::bridge::sampled_fit::{ContinuousPulse, fit_sampled_at, mean_and_sigma};
use crate::physics::integrate::lu::Lu;

/// Sample phases per row of [`phase_calibration`]: `(j + 1/2) / TABLE_PHASES`, `j = 0..32`.
pub const TABLE_PHASES: usize = 32;

/// `coalshock::SampledPhase` in f64: per row `n_k = 1.6 * 1.25^k` samples per pulse, the row's
/// asymmetry range `[a_min, a_max]`, and per asymmetry point the mean and the standard deviation
/// of `ln(F_fit / F_peak)` and `ln(t_fit / t_area)` of the sampled pulses nearest it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phase64 {
    /// `[a_min, a_max]` of each row.
    pub asymmetry: [[f64; 2]; PHASE_ROWS],
    /// Mean `ln(F_fit / F_peak)`.
    pub ln_force: [[f64; PHASE_COLUMNS]; PHASE_ROWS],
    /// Mean `ln(t_fit / t_area)`.
    pub ln_duration: [[f64; PHASE_COLUMNS]; PHASE_ROWS],
    /// Standard deviation of `ln(F_fit / F_peak)` in the cell.
    pub sigma_ln_force: [[f64; PHASE_COLUMNS]; PHASE_ROWS],
    /// Standard deviation of `ln(t_fit / t_area)` in the cell.
    pub sigma_ln_duration: [[f64; PHASE_COLUMNS]; PHASE_ROWS],
}

impl Phase64 {
    /// The kernel's table: every value rounded to `f32`.
    pub fn to_kernel(&self) -> SampledPhase {
        let f = |v: &[[f64; PHASE_COLUMNS]; PHASE_ROWS]| v.map(|r| r.map(|x| x as f32));
        SampledPhase {
            asymmetry: self.asymmetry.map(|r| r.map(|x| x as f32)),
            ln_force: f(&self.ln_force),
            ln_duration: f(&self.ln_duration),
            sigma_ln_force: f(&self.sigma_ln_force),
            sigma_ln_duration: f(&self.sigma_ln_duration),
        }
    }
}

/// Samples per pulse of row `k`: `1.6 * 1.25^k`.
pub fn row_samples(k: usize) -> f64 {
    f64::from(PHASE_FIRST_N) * f64::from(PHASE_STEP).powi(k as i32)
}

/// The table of `pulses` (see the module docs): the means on the rows (`means_on_rows`),
/// refitted so that they leave the least residual as the kernel reads them
/// (`least_squares_as_read`), its spreads then taken as the kernel reads the table
/// (`spread_as_read`). Each row's pulses are sampled and fitted once, at every offset of
/// `BETWEEN_ROWS`, directly (`chain` `None`) or through `chain` and its equaliser: the table
/// is then what the kernel reads behind that chain, the equaliser's residual included (the
/// kernel adds nothing to it).
pub fn phase_calibration(pulses: &[ContinuousPulse], chain: Option<&EqualisedChain>) -> Phase64 {
    let rows = row_fits(pulses, chain);
    let check = check_fits(pulses, chain);
    let mut table = least_squares_as_read(&rows, &check, means_on_rows(&rows));
    spread_as_read(&rows, &mut table);
    table
}

/// [`phase_calibration`] without the refit: each cell's means are those of the fits at the
/// row's own samples per pulse (the offset 0 of `BETWEEN_ROWS`), though the kernel reads the
/// table at the samples per pulse it infers from the measured duration.
pub fn phase_calibration_on_rows(pulses: &[ContinuousPulse]) -> Phase64 {
    let rows = row_fits(pulses, None);
    let mut table = means_on_rows(&rows);
    spread_as_read(&rows, &mut table);
    table
}

/// Each row's fits of `pulses` between the offsets of `BETWEEN_ROWS` and between the phases
/// of `fits_at`, which `least_squares_as_read` holds out (`[row][offset]`).
fn check_fits(pulses: &[ContinuousPulse], chain: Option<&EqualisedChain>) -> Vec<Vec<Vec<Fit>>> {
    (0..PHASE_ROWS)
        .map(|k| {
            BETWEEN_ROWS
                .iter()
                .map(|&s| {
                    let n = row_samples(k) * f64::from(PHASE_STEP).powf(s + 1.0 / 16.0);
                    fits_at_phase(pulses, n, 0.21, chain)
                })
                .collect()
        })
        .collect()
}

/// Each row's fits of `pulses` at every offset of `BETWEEN_ROWS` (`[row][offset]`).
fn row_fits(pulses: &[ContinuousPulse], chain: Option<&EqualisedChain>) -> Vec<Vec<Vec<Fit>>> {
    (0..PHASE_ROWS)
        .map(|k| {
            BETWEEN_ROWS
                .iter()
                .map(|&s| {
                    let n = row_samples(k) * f64::from(PHASE_STEP).powf(s);
                    fits_at_phase(pulses, n, 0.5, chain)
                })
                .collect()
        })
        .collect()
}

/// One pulse sampled at `n` samples of its duration from the area, as the kernel fits it: the
/// fit's duration (samples), the neighbour asymmetry, and its errors `ln(F_fit / F_peak)` and
/// `ln(t_fit / t_area)`.
#[derive(Debug, Clone, Copy)]
struct Fit {
    samples: f64,
    asymmetry: f64,
    ln_force: f64,
    ln_duration: f64,
}

/// Each of `pulses` sampled at `n` samples per pulse and [`TABLE_PHASES`] phases,
/// `(j + offset) / TABLE_PHASES`, and fitted as the kernel fits it: directly, or through
/// `chain` and its equaliser.
fn fits_at_phase(
    pulses: &[ContinuousPulse],
    n: f64,
    offset: f64,
    chain: Option<&EqualisedChain>,
) -> Vec<Fit> {
    let mut fits = Vec::new();
    for p in pulses {
        let phase_fits = match chain {
            Some(c) => c.fits(p, n, offset),
            None => (0..TABLE_PHASES)
                .map(|j| {
                    let phase = (j as f64 + offset) / TABLE_PHASES as f64;
                    let dt = p.duration_s / n;
                    let (peak, samples, a) = fit_sampled_at(p.series, dt, phase, p.five)?;
                    Some([peak / p.peak_n, samples, a])
                })
                .collect(),
        };
        for [force_ratio, samples, asymmetry] in phase_fits.into_iter().flatten() {
            fits.push(Fit {
                samples,
                asymmetry,
                ln_force: force_ratio.ln(),
                ln_duration: (samples / n).ln(),
            });
        }
    }
    fits
}

/// The table's means and spreads on its rows: each row's fits at `n_k` samples per pulse
/// (`rows[k][0]`) go to the asymmetry point nearest their own asymmetry; a point no fit
/// reached takes its nearest filled neighbour's values.
fn means_on_rows(rows: &[Vec<Vec<Fit>>]) -> Phase64 {
    let zero = [[0.0; PHASE_COLUMNS]; PHASE_ROWS];
    let mut out = Phase64 {
        asymmetry: [[0.0; 2]; PHASE_ROWS],
        ln_force: zero,
        ln_duration: zero,
        sigma_ln_force: zero,
        sigma_ln_duration: zero,
    };
    for (k, row) in rows.iter().enumerate().take(PHASE_ROWS) {
        let Some(fits) = row.first() else {
            continue;
        };
        let lo = fits
            .iter()
            .map(|f| f.asymmetry)
            .fold(f64::INFINITY, f64::min);
        let hi = fits
            .iter()
            .map(|f| f.asymmetry)
            .fold(f64::NEG_INFINITY, f64::max);
        if lo.is_nan() || hi.is_nan() || lo > hi {
            continue;
        }
        out.asymmetry[k] = [lo, hi];
        let mut cells: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); PHASE_COLUMNS];
        for f in fits {
            let c = nearest_column([lo, hi], f.asymmetry);
            cells[c].0.push(f.ln_force);
            cells[c].1.push(f.ln_duration);
        }
        for c in 0..PHASE_COLUMNS {
            let Some(filled) = (0..PHASE_COLUMNS)
                .filter(|&d| !cells[d].0.is_empty())
                .min_by_key(|&d| d.abs_diff(c))
            else {
                continue;
            };
            (out.ln_force[k][c], out.sigma_ln_force[k][c]) = mean_and_sigma(&cells[filled].0);
            (out.ln_duration[k][c], out.sigma_ln_duration[k][c]) = mean_and_sigma(&cells[filled].1);
        }
    }
    out
}

/// Offsets from each row, in row steps ([`PHASE_STEP`]), at which [`phase_calibration`]
/// samples the pulses: on the row and every eighth of the way to the next (a quarter of the
/// way apart, Tsuji's error at e 0.3 changed between the samples by 5 times the spread they
/// stated).
const BETWEEN_ROWS: [f64; 8] = [0.0, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875];

/// Residuals a cell needs before `spread_as_read` takes their spread for its own.
const MIN_RESIDUALS: usize = 30;

/// Sets each cell's spreads of `table` to what the table leaves as the kernel reads it
/// (`coalshock::Scene::hertz_equivalent`): each fit of `rows` (every row at every offset of
/// [`BETWEEN_ROWS`]) measured at least [`MIN_DURATION_SAMPLES`] long is read at the samples
/// per pulse the kernel infers from the fit's duration (two fixed-point steps of
/// `ln n = ln n_measured - ln_duration(ln n, a)`) and leaves `ln(F_fit / F_peak) - ln_force`
/// and `ln(t_fit / t_area) - ln_duration` there. Each residual goes to the cell nearest where
/// it was read; a cell of at least [`MIN_RESIDUALS`] takes their root mean square. Between
/// rows the fit's error need not follow the table's interpolation (Tsuji's `t^(1/4)` onset at
/// 2.5-5 samples per pulse), and a spread taken on the rows alone misses that.
fn spread_as_read(rows: &[Vec<Vec<Fit>>], table: &mut Phase64) {
    let kernel = table.to_kernel();
    let mut cells = vec![vec![(Vec::new(), Vec::new()); PHASE_COLUMNS]; PHASE_ROWS];
    let fits = rows.iter().flatten().flatten();
    for f in fits.filter(|f| f.samples >= f64::from(MIN_DURATION_SAMPLES)) {
        let Some((ln_n, (lf, lt))) = read_as_kernel(&kernel, f.samples, f.asymmetry) else {
            continue;
        };
        let (row, col) = nearest_cell(&table.asymmetry, ln_n, f.asymmetry);
        let cell: &mut (Vec<f64>, Vec<f64>) = &mut cells[row][col];
        cell.0.push(f.ln_force - lf);
        cell.1.push(f.ln_duration - lt);
    }
    for (k, row) in cells.iter().enumerate() {
        for (c, (rf, rt)) in row.iter().enumerate() {
            if rf.len() >= MIN_RESIDUALS {
                table.sigma_ln_force[k][c] = root_mean_square(rf);
                table.sigma_ln_duration[k][c] = root_mean_square(rt);
            }
        }
    }
}

/// Weight of [`least_squares_as_read`]'s ridge toward the means on the rows, per cell, as a
/// fraction of the fits an average cell is read at: it settles the cells the kernel reads
/// little or not at all, and is negligible against the fits where it reads many.
const LS_RIDGE: f64 = 0.01;

/// The force means of `start` (`means_on_rows`) refitted to the fits as the kernel reads the
/// table. The means on the rows are those of fits at the row's true samples per pulse, but
/// the kernel reads the table at the samples per pulse it infers from the measured duration
/// (two fixed-point steps), and between rows, so a fit at `n_k` is read elsewhere than the
/// cell that averaged it (Flores e 0.5 at 2.5-3.2 samples per pulse: 0.028 / 0.042 rms of
/// `ln F` / `ln t` as read against 0.017 / 0.024 at the true `n`).
///
/// Every fit of `rows` measured at least [`MIN_DURATION_SAMPLES`] long (the detector
/// measures no shorter pulse) is read where the kernel reads `start` (`read_as_kernel`), and
/// the force means solved that, under the kernel's bilinear weights at those positions, leave
/// the least sum of squares of `ln(F_fit / F_peak)` less the mean read, with a ridge of
/// [`LS_RIDGE`] toward `start`. Where the kernel reads depends on the duration means alone,
/// so this is a linear problem, and the duration means stay those on the rows: refitted the
/// same way (iterated, since the positions move with them) they lowered the noiseless
/// residual as read for Flores and Hunt-Crossley at e 0.6 but cost the grid's Flores and
/// Gonthier e 0.6 at their lowest rate and 15 counts 0.2-0.5 pp of forced choice (seeds
/// 1-3), where the force refit alone costs 0.05-0.13 pp.
///
/// The refit is kept only if on `check`, fits of the same pulses between the offsets and the
/// phases of `rows` that are not fitted, it leaves, per row of true samples per pulse, no
/// more of `ln F` and of `ln t` than `start` does times [`LS_ROW_TOLERANCE`], and less in sum
/// over the rows of mean squares; else `start` is returned. Chosen on the fitted fits
/// themselves, a refit could lower their residual and raise it between them (Tsuji, and
/// every law at e 0.9). In the example `phase_reach` the refit is kept for Flores, Gonthier
/// and Lankarani-Nikravesh at e 0.3 and 0.6 and Hunt-Crossley at e 0.3, and `start` for
/// Hunt-Crossley at e 0.6 and every law at e 0.9 and Tsuji. The asymmetry axes and the
/// reading are the kernel's and do not change.
fn least_squares_as_read(
    rows: &[Vec<Vec<Fit>>],
    check: &[Vec<Vec<Fit>>],
    start: Phase64,
) -> Phase64 {
    let (fit_on, held) = (measured_fits(rows), measured_fits(check));
    if fit_on.is_empty() || held.is_empty() {
        return start;
    }
    let (a, b) = normal_equations(&fit_on, &start);
    let Some(lu) = Lu::new(a) else {
        return start;
    };
    let mut refit = start;
    for (i, v) in lu.solve(b).iter().enumerate() {
        refit.ln_force[i / PHASE_COLUMNS][i % PHASE_COLUMNS] = v.clamp(-2.0, 2.0);
    }
    let (old, new) = (row_residuals(&start, &held), row_residuals(&refit, &held));
    let total = |r: &[[f64; 2]; PHASE_ROWS]| r.iter().map(|x| x[0] + x[1]).sum::<f64>();
    let bound = LS_ROW_TOLERANCE * LS_ROW_TOLERANCE;
    let no_row_worse = new
        .iter()
        .zip(&old)
        .all(|(x, s)| (0..2).all(|m| x[m] <= s[m] * bound + 1e-12));
    if no_row_worse && total(&new) < total(&old) {
        refit
    } else {
        start
    }
}

/// Table cells, `PHASE_ROWS * PHASE_COLUMNS`, the unknowns of [`least_squares_as_read`].
const CELLS: usize = PHASE_ROWS * PHASE_COLUMNS;

/// `(row of true samples per pulse, fit)` of every fit in `set` the detector measures (at
/// least [`MIN_DURATION_SAMPLES`] long).
fn measured_fits(set: &[Vec<Vec<Fit>>]) -> Vec<(usize, Fit)> {
    set.iter()
        .enumerate()
        .flat_map(|(k, r)| r.iter().flatten().map(move |f| (k, *f)))
        .filter(|(_, f)| f.samples >= f64::from(MIN_DURATION_SAMPLES))
        .collect()
}

/// `(W^T W + r I, W^T y + r m)`: the normal equations of the force means `m` of the cells,
/// where row `W_i` of `W` holds the kernel's bilinear weights where it reads `start` at fit
/// `i`, `y_i = ln(F_fit / F_peak)` of that fit, and `r` the ridge [`LS_RIDGE`] (per cell, as
/// a share of the fits per cell) toward `start`'s means.
fn normal_equations(
    fits: &[(usize, Fit)],
    start: &Phase64,
) -> ([[f64; CELLS]; CELLS], [f64; CELLS]) {
    let kernel = start.to_kernel();
    let mut a = [[0.0; CELLS]; CELLS];
    let mut b = [0.0; CELLS];
    for (_, f) in fits {
        let Some((ln_n, _)) = read_as_kernel(&kernel, f.samples, f.asymmetry) else {
            continue;
        };
        let w = bilinear_weights(&start.asymmetry, ln_n, f.asymmetry);
        for &(i, wi) in &w {
            b[i] += wi * f.ln_force;
            for &(j, wj) in &w {
                a[i][j] += wi * wj;
            }
        }
    }
    let ridge = LS_RIDGE * fits.len() as f64 / CELLS as f64;
    for (i, row) in a.iter_mut().enumerate() {
        row[i] += ridge;
        b[i] += ridge * start.ln_force[i / PHASE_COLUMNS][i % PHASE_COLUMNS];
    }
    (a, b)
}

/// Per row of true samples per pulse, the mean squares of `ln F` and `ln t` that `table`
/// leaves on `fits` as the kernel reads it (`[0, 0]` for a row without fits).
fn row_residuals(table: &Phase64, fits: &[(usize, Fit)]) -> [[f64; 2]; PHASE_ROWS] {
    let kernel = table.to_kernel();
    let mut sums = [[0.0; 3]; PHASE_ROWS];
    for (k, f) in fits {
        if let Some((_, (lf, lt))) = read_as_kernel(&kernel, f.samples, f.asymmetry) {
            sums[*k][0] += (f.ln_force - lf).powi(2);
            sums[*k][1] += (f.ln_duration - lt).powi(2);
            sums[*k][2] += 1.0;
        }
    }
    sums.map(|[f, t, n]| if n > 0.0 { [f / n, t / n] } else { [0.0, 0.0] })
}

/// Factor by which [`least_squares_as_read`] lets one row's root mean square residual grow.
const LS_ROW_TOLERANCE: f64 = 1.03;

/// The cells (`row * PHASE_COLUMNS + column`) and weights at which `coalshock::SampledPhase::at`
/// reads `(ln n, a)` in a table of asymmetry axes `axes`: linear between the rows either side
/// of `ln n` (held at the ends), and on each of them linear between the asymmetry points
/// either side of `a` on its own axis (held at the ends).
fn bilinear_weights(axes: &[[f64; 2]; PHASE_ROWS], ln_n: f64, a: f64) -> Vec<(usize, f64)> {
    let position = |at: f64, points: usize| {
        let last = (points - 1) as f64;
        let at = if at.is_finite() {
            at.clamp(0.0, last)
        } else {
            0.0
        };
        let i = (at as usize).min(points - 2);
        (i, at - i as f64)
    };
    let x = (ln_n - f64::from(PHASE_FIRST_N).ln()) / f64::from(PHASE_STEP).ln();
    let (i, f) = position(x, PHASE_ROWS);
    let mut w = Vec::with_capacity(4);
    for (k, wk) in [(i, 1.0 - f), (i + 1, f)] {
        let [lo, hi] = axes[k];
        let step = (hi - lo) / (PHASE_COLUMNS - 1) as f64;
        let pos = if step > 0.0 { (a - lo) / step } else { 0.0 };
        let (c, g) = position(pos, PHASE_COLUMNS);
        w.push((k * PHASE_COLUMNS + c, wk * (1.0 - g)));
        w.push((k * PHASE_COLUMNS + c + 1, wk * g));
    }
    w
}

/// `sqrt(mean(r^2))`.
fn root_mean_square(r: &[f64]) -> f64 {
    (r.iter().map(|x| x * x).sum::<f64>() / r.len() as f64).sqrt()
}

/// What the kernel reads in `kernel` for a fit of `samples` samples' duration and asymmetry
/// `a`: the `ln n` it settles on and the mean `(ln force, ln duration)` there; `None` beyond
/// the table.
fn read_as_kernel(kernel: &SampledPhase, samples: f64, a: f64) -> Option<(f64, (f64, f64))> {
    let ln_measured = samples.ln() as f32;
    let mut ln_n = ln_measured;
    for _ in 0..2 {
        ln_n = ln_measured - kernel.at(ln_n, a as f32)?.1;
    }
    let (lf, lt, _, _) = kernel.at(ln_n, a as f32)?;
    Some((f64::from(ln_n), (f64::from(lf), f64::from(lt))))
}

/// The cell nearest `(ln n, a)`: the row nearest `ln n` (held at the ends), and the asymmetry
/// point of that row nearest `a` ([`nearest_column`]).
fn nearest_cell(axes: &[[f64; 2]; PHASE_ROWS], ln_n: f64, a: f64) -> (usize, usize) {
    let x = (ln_n - f64::from(PHASE_FIRST_N).ln()) / f64::from(PHASE_STEP).ln();
    let row = (x.round().max(0.0) as usize).min(PHASE_ROWS - 1);
    (row, nearest_column(axes[row], a))
}

/// The asymmetry point nearest `a` on a row whose points span `[lo, hi]` (held at the ends;
/// the first for a row of one point).
fn nearest_column([lo, hi]: [f64; 2], a: f64) -> usize {
    let step = (hi - lo) / (PHASE_COLUMNS - 1) as f64;
    if step > 0.0 {
        ((a - lo) / step)
            .round()
            .clamp(0.0, (PHASE_COLUMNS - 1) as f64) as usize
    } else {
        0
    }
}
