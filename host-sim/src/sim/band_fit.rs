//! Fits the accelerometer band's frequency and damping ratio to the pulses of a stream whose
//! contact law's pulse shape is known and the same for every impact: undamped Hertz
//! (`host-sim identify --hertz-pulses`) or a restitution-parametrised law (`--pulse-law`).
//!
//! Each pulse `k` (samples `d_kn`, counts, with the ring of the impacts before it removed) is
//! modelled as `F_k r_n(t_0k, t_ck; f_a, zeta_a)`, `r` the law's unit pulse through the whole
//! chain, the identified beam modes and the band ([`crate::sim::pulse_response`]). The cost
//! `S(f_a, zeta_a) = sum_k min_(F, t_0, t_c) sum_n (d_kn - F r_n)^2` (counts^2) profiles the
//! pulse's own parameters out: `F` in closed form (`F = <r, d> / <r, r>`, the model is linear
//! in it), `(t_0, t_c)` by Levenberg-Marquardt on that projected residual (derivatives by
//! forward differences of `10^-3 t_c`). The two shared parameters are searched by Nelder-Mead
//! in `(ln f_a, ln zeta_a)` from the best point of a coarse grid (`f_a` from 0.06 to 0.4
//! `f_s`, `zeta_a` from 0.3 to 1). The jackknife's leave-one-group-out searches start from the
//! full fit.

use rayon::prelude::*;

use crate::physics::law_spec::LawSpec;
use crate::scene::{BeamMode, Resonance};
use crate::sim::pulse_response::{ChainModel, PulseTiming, unit_area, unit_pulse};
use crate::sim::sensor::ForcePulse;

/// Groups of the jackknife (as the modes').
const GROUPS: usize = 8;
/// Coarse grid of the start: `f_a / f_s`.
const GRID_FREQUENCY: [f64; 5] = [0.06, 0.1, 0.16, 0.25, 0.4];
/// Coarse grid of the start: `zeta_a`.
const GRID_DAMPING: [f64; 3] = [0.3, 0.6, 1.0];
/// Levenberg-Marquardt iterations per pulse, at most.
const PULSE_ITERATIONS: usize = 40;
/// Nelder-Mead evaluations of the shared cost, at most.
const SEARCH_EVALUATIONS: usize = 200;
/// Nelder-Mead stops when the simplex spans less than this in `ln f_a` and `ln zeta_a`.
const SEARCH_TOLERANCE: f64 = 1e-5;

/// One pulse as the fit sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct BandPulse {
    /// Its jackknife group.
    pub group: usize,
    /// The samples with the earlier ring removed (counts), from a few samples before the onset
    /// to the free window after the pulse.
    pub samples: Vec<f64>,
}

/// The band fitted to the pulses.
#[derive(Debug, Clone, PartialEq)]
pub struct BandFit {
    /// `f_a` in Hz.
    pub frequency_hz: f64,
    /// `zeta_a` (dimensionless).
    pub damping_ratio: f64,
    /// `(f_a in Hz, zeta_a)` fitted without each jackknife group in turn.
    pub leave_out: Vec<(f64, f64)>,
    /// Pulses fitted.
    pub pulses: usize,
    /// RMS of the residual over every fitted sample (counts).
    pub residual_rms_counts: f64,
}

/// One pulse's own parameters and its sum of squared residuals (counts^2).
#[derive(Debug, Clone, Copy, PartialEq)]
struct PulseFit {
    peak_counts: f64,
    timing: PulseTiming,
    sse: f64,
}

/// Which jackknife groups a cost takes.
type Keep = dyn Fn(usize) -> bool + Sync;

/// The shared model: unit pulse and its area constant, the beam's modes, the data, the sample
/// rate (Hz).
struct Problem<'a> {
    unit: ForcePulse,
    area: f64,
    modes: &'a [BeamMode],
    pulses: &'a [BandPulse],
    fs: f64,
}

/// `F`, the residual `d - F r` and its sum of squares for the pulse at `timing`.
fn projected(band: &ChainModel, unit: &ForcePulse, d: &[f64], timing: PulseTiming) -> PulseFit {
    let r = band.response(unit, timing, d.len());
    let rr: f64 = r.iter().map(|v| v * v).sum();
    let rd: f64 = r.iter().zip(d).map(|(a, b)| a * b).sum();
    let f = if rr > 0.0 { rd / rr } else { 0.0 };
    let sse = d.iter().zip(&r).map(|(a, b)| (a - f * b).powi(2)).sum();
    PulseFit {
        peak_counts: f,
        timing,
        sse,
    }
}

/// The residual vector of [`projected`].
fn residual(band: &ChainModel, unit: &ForcePulse, d: &[f64], timing: PulseTiming) -> Vec<f64> {
    let p = projected(band, unit, d, timing);
    let r = band.response(unit, timing, d.len());
    d.iter()
        .zip(&r)
        .map(|(a, b)| a - p.peak_counts * b)
        .collect()
}

/// A first guess from the samples: the peak, the contact time from the area over the peak
/// (`area = c F_max t_c`, `c` the unit pulse's area, [`unit_area`]) and the onset half a
/// contact and the band's delay `2 zeta / w` before the peak.
fn first_guess(d: &[f64], fs: f64, delay_s: f64, c: f64) -> PulseTiming {
    let (np, peak) =
        d.iter().enumerate().fold(
            (0, 0.0f64),
            |b, (i, &v)| if v.abs() > b.1.abs() { (i, v) } else { b },
        );
    let area: f64 = d.iter().sum::<f64>() / fs;
    let tc = if peak != 0.0 {
        (area / (peak * c)).clamp(0.5 / fs, 40.0 / fs)
    } else {
        1.0 / fs
    };
    PulseTiming {
        onset_s: np as f64 / fs - delay_s - 0.5 * tc,
        duration_s: tc,
    }
}

/// Levenberg-Marquardt on `(t_0, t_c)` of one pulse from `start`, `F` profiled.
fn fit_pulse(band: &ChainModel, unit: &ForcePulse, d: &[f64], start: PulseTiming) -> PulseFit {
    let mut best = projected(band, unit, d, start);
    let mut lambda = 1e-3;
    for _ in 0..PULSE_ITERATIONS {
        let t = best.timing;
        let step = 1e-3 * t.duration_s;
        let shifted = |d0: f64, dc: f64| PulseTiming {
            onset_s: t.onset_s + d0,
            duration_s: t.duration_s + dc,
        };
        let r0 = residual(band, unit, d, t);
        let diff = |a: PulseTiming| -> Vec<f64> {
            let ra = residual(band, unit, d, a);
            ra.iter().zip(&r0).map(|(x, y)| (x - y) / step).collect()
        };
        let j0 = diff(shifted(step, 0.0));
        let j1 = diff(shifted(0.0, step));
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let (a00, a01, a11) = (dot(&j0, &j0), dot(&j0, &j1), dot(&j1, &j1));
        let (g0, g1) = (dot(&j0, &r0), dot(&j1, &r0));
        let mut improved = false;
        while lambda < 1e8 {
            let (b00, b11) = (a00 * (1.0 + lambda), a11 * (1.0 + lambda));
            let det = b00 * b11 - a01 * a01;
            let (s0, s1) = ((-g0 * b11 + g1 * a01) / det, (-g1 * b00 + g0 * a01) / det);
            let trial = shifted(s0, s1);
            if trial.duration_s > 0.0 && det > 0.0 {
                let p = projected(band, unit, d, trial);
                if p.sse < best.sse {
                    let gain = best.sse - p.sse;
                    best = p;
                    lambda = (lambda / 3.0).max(1e-9);
                    improved = gain > 1e-12 * best.sse.max(1e-300);
                    break;
                }
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    best
}

impl Problem<'_> {
    /// The shared cost at `(ln f_a, ln zeta_a)` over the pulses `keep` selects, each pulse
    /// refitted from `fits` (updated; a pulse without a fit starts from [`first_guess`]).
    fn cost(&self, x: [f64; 2], fits: &mut [Option<PulseFit>], keep: &Keep) -> f64 {
        let (f, z) = (x[0].exp(), x[1].exp());
        let band = Resonance {
            frequency_hz: f,
            damping_ratio: z,
        };
        let Some(band) = ChainModel::new(self.modes, band, self.fs) else {
            return f64::INFINITY;
        };
        let delay = z / (std::f64::consts::PI * f);
        fits.par_iter_mut()
            .zip(self.pulses.par_iter())
            .filter(|(_, p)| keep(p.group))
            .map(|(fit, p)| {
                let start = fit.map_or_else(
                    || first_guess(&p.samples, self.fs, delay, self.area),
                    |q| q.timing,
                );
                let done = fit_pulse(&band, &self.unit, &p.samples, start);
                *fit = Some(done);
                done.sse
            })
            .sum()
    }
}

/// Nelder-Mead minimum of `cost` over two parameters from `start` with initial steps `step`
/// (reflection 1, expansion 2, contraction 1/2, shrink 1/2): `(minimum, value)`.
fn nelder_mead(
    cost: &mut dyn FnMut([f64; 2]) -> f64,
    start: [f64; 2],
    step: [f64; 2],
) -> ([f64; 2], f64) {
    let mut s: Vec<([f64; 2], f64)> = [
        start,
        [start[0] + step[0], start[1]],
        [start[0], start[1] + step[1]],
    ]
    .into_iter()
    .map(|x| (x, cost(x)))
    .collect();
    let along =
        |a: [f64; 2], b: [f64; 2], t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
    let mut evaluations = 3;
    while evaluations < SEARCH_EVALUATIONS {
        s.sort_by(|a, b| a.1.total_cmp(&b.1));
        let span = (1..3)
            .map(|i| {
                (s[i].0[0] - s[0].0[0])
                    .abs()
                    .max((s[i].0[1] - s[0].0[1]).abs())
            })
            .fold(0.0, f64::max);
        if span < SEARCH_TOLERANCE {
            break;
        }
        let centre = along(s[0].0, s[1].0, 0.5);
        let r = along(s[2].0, centre, 2.0);
        let fr = cost(r);
        evaluations += 1;
        if fr < s[0].1 {
            let e = along(s[2].0, centre, 3.0);
            let fe = cost(e);
            evaluations += 1;
            s[2] = if fe < fr { (e, fe) } else { (r, fr) };
        } else if fr < s[1].1 {
            s[2] = (r, fr);
        } else {
            let c = along(s[2].0, centre, if fr < s[2].1 { 1.5 } else { 0.5 });
            let fc = cost(c);
            evaluations += 1;
            if fc < s[2].1.min(fr) {
                s[2] = (c, fc);
            } else {
                for i in 1..3 {
                    let x = along(s[0].0, s[i].0, 0.5);
                    s[i] = (x, cost(x));
                }
                evaluations += 2;
            }
        }
    }
    s.sort_by(|a, b| a.1.total_cmp(&b.1));
    s[0]
}

impl Problem<'_> {
    /// The grid point of least cost, each pulse fitted afresh at every point: `(ln f_a, ln
    /// zeta_a)` and the pulses' fits there.
    fn grid_start(&self) -> ([f64; 2], Vec<Option<PulseFit>>) {
        let mut best = (f64::INFINITY, [0.0; 2], Vec::new());
        for rf in GRID_FREQUENCY {
            for z in GRID_DAMPING {
                let x = [(rf * self.fs).ln(), z.ln()];
                let mut fits = vec![None; self.pulses.len()];
                let c = self.cost(x, &mut fits, &|_| true);
                if c < best.0 {
                    best = (c, x, fits);
                }
            }
        }
        (best.1, best.2)
    }

    /// Nelder-Mead from `start` (first steps `step` in `ln f_a` and `ln zeta_a`) over the
    /// pulses of every group but `skip`, the pulses' fits warm-started from `fits`: `(ln f_a,
    /// ln zeta_a)`, the cost and the fits.
    fn search(
        &self,
        start: [f64; 2],
        step: f64,
        fits: &[Option<PulseFit>],
        skip: Option<usize>,
    ) -> ([f64; 2], f64, Vec<Option<PulseFit>>) {
        let mut fits = fits.to_vec();
        let keep = move |g: usize| Some(g) != skip;
        let (x, c) = nelder_mead(&mut |x| self.cost(x, &mut fits, &keep), start, [step, step]);
        // The fits at the minimum (the search's last evaluation need not be it).
        let c = self.cost(x, &mut fits, &keep).min(c);
        (x, c, fits)
    }
}

/// The band fitted to `pulses` (sample rate `sample_rate_hz`, Hz) of the contact law `law`
/// with its leave-one-group-out fits; `None` without pulses or when the law's shape cannot be
/// tabulated (a law whose shape changes with the impact, [`LawSpec::self_similar`]).
pub fn fit_band(
    pulses: &[BandPulse],
    modes: &[BeamMode],
    sample_rate_hz: f64,
    law: LawSpec,
) -> Option<BandFit> {
    if pulses.is_empty() {
        return None;
    }
    let unit = unit_pulse(law)?;
    let problem = Problem {
        area: unit_area(&unit),
        unit,
        modes,
        pulses,
        fs: sample_rate_hz,
    };
    let (start, fits) = problem.grid_start();
    let (x, cost, fits) = problem.search(start, 0.1, &fits, None);
    let leave_out = (0..GROUPS)
        .map(|g| {
            let (xg, _, _) = problem.search(x, 0.02, &fits, Some(g));
            (xg[0].exp(), xg[1].exp())
        })
        .collect();
    let samples: usize = pulses.iter().map(|p| p.samples.len()).sum();
    Some(BandFit {
        frequency_hz: x[0].exp(),
        damping_ratio: x[1].exp(),
        leave_out,
        pulses: pulses.len(),
        residual_rms_counts: (cost / samples.max(1) as f64).sqrt(),
    })
}
