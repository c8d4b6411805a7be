//! The sampling correction of a damped contact by samples per pulse and sampling phase
//! (`coalshock::SampledPhase`): the kernel's own three-sample fit on the integrator's pulses at
//! each row `n_k` and [`TABLE_PHASES`] phases, binned by the neighbour asymmetry the kernel
//! measures on the same samples.

use coalshock::sampled_phase::{PHASE_COLUMNS, PHASE_FIRST_N, PHASE_ROWS, PHASE_STEP};

use crate::bridge::sampled_fit::{ContinuousPulse, fit_sampled_at, mean_and_sigma};

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

/// Samples per pulse of row `k`: `1.6 * 1.25^k`.
pub fn row_samples(k: usize) -> f64 {
    f64::from(PHASE_FIRST_N) * f64::from(PHASE_STEP).powi(k as i32)
}

/// The table of `pulses` (see the module docs). Each sampled pulse goes to the asymmetry point
/// nearest its own asymmetry; a point no pulse reached takes its nearest filled neighbour's
/// values.
pub fn phase_calibration(pulses: &[ContinuousPulse]) -> Phase64 {
    let zero = [[0.0; PHASE_COLUMNS]; PHASE_ROWS];
    let mut out = Phase64 {
        asymmetry: [[0.0; 2]; PHASE_ROWS],
        ln_force: zero,
        ln_duration: zero,
        sigma_ln_force: zero,
        sigma_ln_duration: zero,
    };
    for k in 0..PHASE_ROWS {
        let n = row_samples(k);
        let mut points = Vec::new();
        for p in pulses {
            let dt = p.duration_s / n;
            for j in 0..TABLE_PHASES {
                let phase = (j as f64 + 0.5) / TABLE_PHASES as f64;
                if let Some((peak, samples, a)) = fit_sampled_at(p.series, dt, phase) {
                    let lt = (samples * dt / p.duration_s).ln();
                    points.push((a, (peak / p.peak_n).ln(), lt));
                }
            }
        }
        let lo = points.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
        let hi = points.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
        if lo.is_nan() || hi.is_nan() || lo > hi {
            continue;
        }
        out.asymmetry[k] = [lo, hi];
        let step = (hi - lo) / (PHASE_COLUMNS - 1) as f64;
        let mut cells: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); PHASE_COLUMNS];
        for &(a, lf, lt) in &points {
            let c = if step > 0.0 {
                (((a - lo) / step).round() as usize).min(PHASE_COLUMNS - 1)
            } else {
                0
            };
            cells[c].0.push(lf);
            cells[c].1.push(lt);
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
