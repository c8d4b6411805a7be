//! The calibration of a damped contact against the undamped Hertz model, as the kernel's
//! detector measures a pulse: for each impact the ratios measured / Hertz of
//!
//! - the peak force, `F_peak / F_max`;
//! - the duration from the area, `(A / (C_AREA F_peak)) / t_c`, with `A = integral F dt`;
//! - the shape ratio `q = (E / (C_ENERGY F_peak^2)) / (A / (C_AREA F_peak))`, `E = integral F^2 dt`
//!   (1 for the Hertz pulse).
//!
//! For a class whose contact yields (Thornton's law) the reference is the kernel's own model of
//! it, Thornton's undamped closed forms ([`ThorntonImpact64`]) in place of Hertz's: the peak
//! `F*` and the duration the area gives, `t_A = m u (1 + e) / (C_AREA F*)`. The kernel's
//! envelope already follows both, so the ratios are what is left: the energy constant read on
//! the flatter yielding pulse, and any damping.
//!
//! The pulse comes from the f64 integrator with the scene's law; `C_AREA` and `C_ENERGY` are the
//! closed forms of the Hertz pulse (written here from their formulas, not taken from the
//! kernel). For the restitution-parametrised laws the ratios depend on the restitution alone;
//! for Adams (a fixed `c_max` and penetration depth) they vary with size and speed, which the
//! reported spread shows: such a scene's force and duration ratios are carried per class by
//! [`crate::bridge::ratio_table`] instead.

use coalshock::PulseShape;
use coalshock::sampled_phase::PHASE_FIRST_N;
use coalshock::scene::{SAMPLED_FIRST_N, SAMPLED_POINTS, SAMPLED_STEP};

use crate::bridge::equalised_fit::EqualisedChain;
use crate::bridge::pulse_shape::scene_shape;
pub use crate::bridge::sampled_fit::{ContinuousPulse, fit_sampled_at, mean_and_sigma};
use crate::bridge::sampled_fit::{force_at, reads_five_samples};
use crate::bridge::sampled_phase::{Phase64, phase_calibration};
use crate::bridge::skew_tolerance::{GridImpact, sampled_skew_tolerance};
use crate::bridge::skewness::weighted_skewness;
use crate::physics::hertz64::{HERTZ_TC_FACTOR as CONTACT_TIME_FACTOR, HertzImpact64};
use crate::physics::impact::{ImpactSpec, simulate};
use crate::physics::integrate::SimError;
use crate::physics::law_spec::LawSpec;
use crate::physics::thornton::ThorntonImpact64;
use crate::scene::SceneFile;

pub use crate::physics::hertz64::C_AREA;

/// Energy `integral F^2 dt` of the Hertz pulse over `F_max^2 t_c`:
/// `2 B(8/5, 1/2) / (2.5 * 2.9432752)`, `B(8/5, 1/2) = Gamma(8/5) sqrt(pi) / Gamma(21/10)`.
pub const C_ENERGY: f64 = 2.0 * 0.893_515_349_287_690_3 * 1.772_453_850_905_516
    / 1.046_485_846_853_560_7
    / (2.5 * CONTACT_TIME_FACTOR);

/// From this many samples in the scene's shortest pulse on, the kernel's detector fits a
/// smoothed top instead of the Hertz shape through three samples (`detector::smooth_fit`).
const SMOOTH_FROM_SAMPLES: f64 = 24.0;

/// Sample phases per point of [`sampled_calibration`].
pub const SAMPLED_PHASES: usize = 16;

/// The sampling correction of a damped contact, per point `n_k = 2.5 * 1.6^k` samples per
/// pulse (`coalshock::SampledCalibration`): mean and spread of `ln(measured / continuous)` of
/// the peak force and the duration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampled64 {
    /// Mean `ln(F_fit / F_peak)`.
    pub ln_force: [f64; SAMPLED_POINTS],
    /// Mean `ln(t_fit / t_area)`.
    pub ln_duration: [f64; SAMPLED_POINTS],
    /// Standard deviation of `ln(F_fit / F_peak)` over phases and impacts.
    pub sigma_ln_force: [f64; SAMPLED_POINTS],
    /// Standard deviation of `ln(t_fit / t_area)` over phases and impacts.
    pub sigma_ln_duration: [f64; SAMPLED_POINTS],
}

/// What the kernel's Hertz-shape fit (`coalshock::detector::shape_fit`) reports for the pulses
/// sampled at `n_k` samples of their own duration each, at [`SAMPLED_PHASES`] phases: the mean
/// and the standard deviation of `ln(F_fit / F_peak)` and `ln(t_fit / t_area)` over phases and
/// pulses. The fit assumes the symmetric Hertz shape; a damped pulse rises faster than it falls,
/// and at a few samples per pulse the fit then reads it low and short by an amount that depends
/// on `n` (the kernel divides it out per pulse).
pub fn sampled_calibration(pulses: &[ContinuousPulse]) -> Sampled64 {
    let mut out = Sampled64 {
        ln_force: [0.0; SAMPLED_POINTS],
        ln_duration: [0.0; SAMPLED_POINTS],
        sigma_ln_force: [0.0; SAMPLED_POINTS],
        sigma_ln_duration: [0.0; SAMPLED_POINTS],
    };
    for k in 0..SAMPLED_POINTS {
        let n = SAMPLED_FIRST_N as f64 * (SAMPLED_STEP as f64).powi(k as i32);
        let (mut f, mut t) = (Vec::new(), Vec::new());
        for p in pulses {
            let dt = p.duration_s / n;
            for phase in 0..SAMPLED_PHASES {
                if let Some((peak, samples)) = fit_sampled(p, dt, phase) {
                    f.push((peak / p.peak_n).ln());
                    t.push((samples * dt / p.duration_s).ln());
                }
            }
        }
        (out.ln_force[k], out.sigma_ln_force[k]) = mean_and_sigma(&f);
        (out.ln_duration[k], out.sigma_ln_duration[k]) = mean_and_sigma(&t);
    }
    out
}

/// The kernel's fit of `p`'s series sampled every `dt` from phase `phase / SAMPLED_PHASES`:
/// peak (N) and duration (samples).
fn fit_sampled(p: &ContinuousPulse, dt: f64, phase: usize) -> Option<(f64, f64)> {
    let phase = phase as f64 / SAMPLED_PHASES as f64;
    fit_sampled_at(p.series, dt, phase, p.five).map(|(f, t, _)| (f, t))
}

/// Points recorded per Hertz contact time when a pulse is integrated for calibration.
const POINTS_PER_PULSE: f64 = 4000.0;

/// The three ratios of one impact (dimensionless).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PulseRatios {
    /// Peak force over the Hertz `F_max`.
    pub force: f64,
    /// Duration from the area over the Hertz `t_c`.
    pub duration: f64,
    /// Shape ratio `q`.
    pub shape: f64,
}

/// The calibration of a scene's contact: the geometric means of the ratios over its classes'
/// corners and centres, and the largest `|ln|` deviation of any impact from them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration64 {
    /// Geometric-mean ratios.
    pub ratios: PulseRatios,
    /// Largest `|ln ratio - ln mean|` of each ratio over the impacts (log units).
    pub spread_ln: PulseRatios,
    /// Impacts integrated.
    pub impacts: usize,
    /// Largest deviation of the shape ratio's log when the impacts' pulses are sampled at the
    /// scene's rate ([`sampled_shape_spread`]).
    pub sampled_shape_spread: f64,
    /// What sampling at few samples per pulse adds ([`sampled_calibration`]); `None` when the
    /// scene's shortest pulse has 24 samples or more (the detector then fits a smoothed top,
    /// whose error does not depend on the pulse's skew).
    pub sampled: Option<Sampled64>,
    /// The damped contact's correction by samples per pulse and sampling phase
    /// ([`phase_calibration`]), with `sampled`; `None` for a contact of the Hertz law (a
    /// yielding one). Behind a chain that is not rigid, fitted through it and the kernel's
    /// equaliser ([`EqualisedChain`]).
    pub phase: Option<Phase64>,
    /// Mean skewness of the impacts' whole pulses (above 0.5 % of the peak; 0 for Hertz).
    pub skewness: f64,
    /// Largest distance of one impact's skewness from the mean.
    pub skewness_spread: f64,
    /// The skew tolerance the impacts' pulses sampled at the scene's rate need beside the
    /// detector's own allowance ([`sampled_skew_tolerance`]); 0 when they stay inside it.
    pub skewness_sampled_tolerance: f64,
    /// The most negative second difference `v[i-1] - 2 v[i] + v[i+1]` of any impact's pulse
    /// sampled at the scene's rate (16 sample phases), over its peak, negated: how sharply the
    /// contact's own pulse bends (0.02-0.2 for Hertz, about 0.56 for Adams with `d = 1e-5 m`
    /// at 100 kS/s).
    pub sharpest_bend: f64,
    /// Geometric mean over the impacts of the time the force stays within 2 % of its peak,
    /// as a fraction of the pulse's duration, over the same of the Hertz pulse
    /// ([`hertz_top_fraction`]): how much broader the contact's own top is (about 2-3 for a
    /// yielding pulse). The kernel's `Settings::flat_top_ratio` for a scene that yields.
    pub flat_top_ratio: f64,
    /// A damped, self-similar contact's pulse shape for the kernel's flank fit of a clipped
    /// pulse, with the largest error of any impact's pulse against it
    /// ([`scene_shape`]); `None` for a law that is not self-similar, a yielding class, or a
    /// scene whose impacts stray from the table by more than the kernel's `SHAPE_ERROR`.
    pub pulse_shape: Option<(PulseShape, f64)>,
}

/// The fraction of its contact time a Hertz pulse spends within 2 % of its peak:
/// `F >= 0.98 F_max` where `delta >= x0 delta_max`, `x0 = 0.98^(2/3)`, so the fraction is
/// `2 integral_x0^1 dx / sqrt(1 - x^(5/2)) / 2.9432752` (in units `delta_max / u`), taken with
/// `x = 1 - w^2` (a smooth integrand) by Simpson's rule on 400 intervals: 0.0995.
pub fn hertz_top_fraction() -> f64 {
    let x0 = 0.98f64.powf(2.0 / 3.0);
    let top = (1.0 - x0).sqrt();
    let f = |w: f64| {
        if w <= 0.0 {
            // 2 w / sqrt(1 - (1 - w^2)^(5/2)) -> 2 / sqrt(5/2) as w -> 0.
            2.0 / 2.5f64.sqrt()
        } else {
            2.0 * w / (1.0 - (1.0 - w * w).powf(2.5)).sqrt()
        }
    };
    let n = 400;
    let h = top / n as f64;
    let mut sum = f(0.0) + f(top);
    for k in 1..n {
        sum += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    2.0 * sum * h / 3.0 / CONTACT_TIME_FACTOR
}

/// The time the force series `series` (`(t_s, force_n)`, uniformly spaced) stays within 2 %
/// of its peak, as a fraction of `duration_s`.
fn top_fraction(series: &[(f64, f64)], duration_s: f64) -> f64 {
    let peak = series.iter().fold(0.0f64, |m, p| m.max(p.1));
    let dt = match (series.first(), series.get(1)) {
        (Some(a), Some(b)) => b.0 - a.0,
        _ => return 0.0,
    };
    let above = series.iter().filter(|p| p.1 >= 0.98 * peak).count();
    above as f64 * dt / duration_s
}

/// Skewness `E[(t - mu)^3] / E[(t - mu)^2]^(3/2)` of the force series `series`
/// (`(t_s, force_n)`, uniformly spaced) weighted by the force squared, over the points above
/// `cut` times the peak (as the detector takes the part above its trigger level).
pub fn skewness(series: &[(f64, f64)], cut: f64) -> f64 {
    let peak = series.iter().fold(0.0f64, |m, p| m.max(p.1));
    let above: Vec<(f64, f64)> = series
        .iter()
        .copied()
        .filter(|p| p.1 > cut * peak)
        .collect();
    weighted_skewness(&above)
}

/// `series` (`(t_s, force_n)`) sampled every `1 / sample_rate_hz` at phase `k` of 16: from
/// its first time plus `k / 16` of the interval, while before its last time.
fn phase_samples(
    series: &[(f64, f64)],
    sample_rate_hz: f64,
    k: usize,
) -> impl Iterator<Item = (f64, f64)> + '_ {
    let dt = 1.0 / sample_rate_hz;
    let (first, last) = match (series.first(), series.last()) {
        (Some(a), Some(b)) => (a.0, b.0),
        _ => (0.0, 0.0),
    };
    std::iter::successors(Some(first + dt * k as f64 / 16.0), move |t| Some(t + dt))
        .take_while(move |&t| t < last)
        .map(move |t| (t, force_at(series, t)))
}

/// The largest `|ln q_sampled - ln q|` of the force series `series` (`(t_s, force_n)`) sampled
/// every `1 / sample_rate_hz` at 16 phases: `q_sampled = (sum v^2 / (C_ENERGY F^2)) /
/// (sum v / (C_AREA F))` with the series' own peak `F`, against the same from the fine series.
/// A skewed pulse of a few samples sums unevenly; the detector's shape check must allow it.
pub fn sampled_shape_spread(series: &[(f64, f64)], sample_rate_hz: f64) -> f64 {
    let peak = series.iter().fold(0.0f64, |m, p| m.max(p.1));
    if peak <= 0.0 || sample_rate_hz.is_nan() || sample_rate_hz <= 0.0 {
        return 0.0;
    }
    let ln_q = |sum: f64, sum_sq: f64| (sum_sq * C_AREA / (sum * peak * C_ENERGY)).ln();
    let fine_sum: f64 = series.iter().map(|p| p.1.max(0.0)).sum();
    let fine_sq: f64 = series.iter().map(|p| p.1.max(0.0).powi(2)).sum();
    let reference = ln_q(fine_sum, fine_sq);
    let mut worst = 0.0f64;
    for k in 0..16 {
        let (mut sum, mut sum_sq) = (0.0, 0.0);
        for (_, v) in phase_samples(series, sample_rate_hz, k) {
            sum += v;
            sum_sq += v * v;
        }
        if sum > 0.0 {
            worst = worst.max((ln_q(sum, sum_sq) - reference).abs());
        }
    }
    worst
}

/// The most negative second difference of the force series `series` (`(t_s, force_n)`)
/// sampled every `1 / sample_rate_hz` at 16 phases, over its peak, negated (0 or more).
pub fn sharpest_bend(series: &[(f64, f64)], sample_rate_hz: f64) -> f64 {
    let (Some(first), Some(last)) = (series.first(), series.last()) else {
        return 0.0;
    };
    let peak = series.iter().fold(0.0f64, |m, p| m.max(p.1));
    if peak <= 0.0 || sample_rate_hz.is_nan() || sample_rate_hz <= 0.0 {
        return 0.0;
    }
    let dt = 1.0 / sample_rate_hz;
    let at = |t: f64| force_at(series, t);
    let mut worst = 0.0f64;
    for k in 0..16 {
        let mut t = first.0 - 2.0 * dt + dt * k as f64 / 16.0;
        let (mut prev, mut mid) = (at(t - dt), at(t));
        while t <= last.0 + dt {
            let next = at(t + dt);
            worst = worst.min(prev + next - 2.0 * mid);
            (prev, mid) = (mid, next);
            t += dt;
        }
    }
    -worst / peak
}

/// The ratios of one impact, from its integrated force-time series (trapezoid sums on
/// `POINTS_PER_PULSE` points per Hertz contact time), against the Hertz impact, or against
/// Thornton's undamped impact for [`LawSpec::Thornton`] (its peak `F*` and the duration its
/// area gives, [`ThorntonImpact64::area_duration_s`]).
pub fn pulse_ratios(spec: &ImpactSpec) -> Result<PulseRatios, SimError> {
    pulse_ratios_and_series(spec).map(|p| p.ratios)
}

/// One integrated impact as the calibration sees it.
struct Pulse64 {
    /// Its ratios ([`pulse_ratios`]).
    ratios: PulseRatios,
    /// Its force-time series `(t_s, force_n)`.
    series: Vec<(f64, f64)>,
    /// The time within 2 % of the peak over the pulse's duration.
    top_fraction: f64,
    /// The pulse's peak force in N.
    peak_n: f64,
    /// Its duration from the area with the Hertz shape, `A / (C_AREA F_peak)`, in s.
    area_duration_s: f64,
}

/// The trapezoid integrals of the force series `series` (`(t_s, force_n)`, negative force
/// taken as 0): area `int F dt` (N s), energy `int F^2 dt` (N^2 s), and the largest force after
/// the first point (N).
pub fn area_energy_peak(series: &[(f64, f64)]) -> (f64, f64, f64) {
    let (mut area, mut energy, mut peak) = (0.0f64, 0.0f64, 0.0f64);
    for w in series.windows(2) {
        let (t0, f0) = (w[0].0, w[0].1.max(0.0));
        let (t1, f1) = (w[1].0, w[1].1.max(0.0));
        area += 0.5 * (t1 - t0) * (f0 + f1);
        energy += 0.5 * (t1 - t0) * (f0 * f0 + f1 * f1);
        peak = peak.max(f1);
    }
    (area, energy, peak)
}

/// [`pulse_ratios`], the force-time series it was computed from and what the detector reads
/// of it (peak, duration from the area, top fraction).
fn pulse_ratios_and_series(spec: &ImpactSpec) -> Result<Pulse64, SimError> {
    let hertz = spec.hertz()?;
    let (reference_force_n, reference_duration_s) = match spec.law {
        LawSpec::Thornton {
            yield_pressure_pa, ..
        } => {
            let t = ThorntonImpact64::new(&hertz, yield_pressure_pa)?;
            (t.peak_force_n, t.area_duration_s)
        }
        _ => (hertz.peak_force_n, hertz.duration_s),
    };
    let mut spec = spec.clone();
    spec.record = Some(hertz.duration_s / POINTS_PER_PULSE);
    let report = simulate(&spec)?;
    let series = report.force_series.unwrap_or_default();
    let (area, energy, peak) = area_energy_peak(&series);
    let peak = peak.max(report.peak_force_n);
    let t_area = area / (C_AREA * peak);
    let t_energy = energy / (C_ENERGY * peak * peak);
    let top_fraction = top_fraction(&series, report.pulse_duration_s);
    Ok(Pulse64 {
        ratios: PulseRatios {
            force: peak / reference_force_n,
            duration: t_area / reference_duration_s,
            shape: t_energy / t_area,
        },
        series,
        top_fraction,
        peak_n: peak,
        area_duration_s: t_area,
    })
}

/// The calibration of `scene`'s contact law, or `None` for the undamped Hertz law with no
/// yielding class (the kernel's own model: every ratio is 1). Integrates each class, with its
/// own law ([`SceneFile::class_law`]), at radius {min, geometric centre, max} x speed {min,
/// centre, max}. A damped contact's phase table is fitted through `chain`, the scene's chain
/// and the kernel's equaliser, when it is not rigid (`None`: as sampled on a rigid beam).
pub fn calibrate(
    scene: &SceneFile,
    chain: Option<&EqualisedChain>,
) -> Result<Option<Calibration64>, SimError> {
    if scene.contact == LawSpec::Hertz && !scene.yields() {
        return Ok(None);
    }
    let GridPulses {
        all,
        skews,
        bend,
        sampled,
        pulses,
        shortest_s,
        ln_top,
        hertz,
    } = integrate_grid(scene)?;
    let fs = scene.sensor.sample_rate_hz;
    let damped = scene.contact != LawSpec::Hertz;
    let pulse_shape = (damped && !scene.yields())
        .then(|| scene_shape(scene.contact, all.iter().map(|(_, s)| s.as_slice())))
        .flatten();
    let sampled_fit = (shortest_s * fs < SMOOTH_FROM_SAMPLES)
        .then(|| sampled_of_grid(&all, &pulses, damped, reads_five_samples(scene), chain));
    let (sampled_fit, phase) = sampled_fit.map_or((None, None), |(s, p)| (Some(s), p));
    let n = all.len() as f64;
    let skew_mean = skews.iter().sum::<f64>() / n;
    let sampled_tolerance = sampled_skew_tolerance(scene, &class_grids(&all, &hertz), skew_mean)?;
    let all: Vec<PulseRatios> = all.into_iter().map(|(r, _)| r).collect();
    let mean = |f: fn(&PulseRatios) -> f64| all.iter().map(|p| f(p).ln()).sum::<f64>() / n;
    let (lf, ld, ls) = (mean(|p| p.force), mean(|p| p.duration), mean(|p| p.shape));
    let spread = |f: fn(&PulseRatios) -> f64, m: f64| {
        all.iter()
            .map(|p| (f(p).ln() - m).abs())
            .fold(0.0, f64::max)
    };
    Ok(Some(Calibration64 {
        ratios: PulseRatios {
            force: lf.exp(),
            duration: ld.exp(),
            shape: ls.exp(),
        },
        spread_ln: PulseRatios {
            force: spread(|p| p.force, lf),
            duration: spread(|p| p.duration, ld),
            shape: spread(|p| p.shape, ls),
        },
        impacts: all.len(),
        skewness: skew_mean,
        skewness_spread: skews
            .iter()
            .map(|s| (s - skew_mean).abs())
            .fold(0.0, f64::max),
        skewness_sampled_tolerance: sampled_tolerance,
        sharpest_bend: bend,
        sampled_shape_spread: sampled,
        sampled: sampled_fit,
        phase,
        flat_top_ratio: (ln_top / n).exp(),
        pulse_shape,
    }))
}

/// What [`integrate_grid`] gathers from a scene's impacts, in grid order.
struct GridPulses {
    /// Each impact's ratios and force-time series `(t_s, force_n)`.
    all: Vec<(PulseRatios, Vec<(f64, f64)>)>,
    /// Each impact's skewness ([`skewness`] above 0.5 % of the peak).
    skews: Vec<f64>,
    /// The sharpest bend of any pulse ([`sharpest_bend`]).
    bend: f64,
    /// The largest [`sampled_shape_spread`] of any pulse.
    sampled: f64,
    /// Each impact's peak force (N) and duration from the area (s).
    pulses: Vec<(f64, f64)>,
    /// The shortest Hertz contact time of the grid (s).
    shortest_s: f64,
    /// Sum over the impacts of `ln (top_fraction / Hertz's)`.
    ln_top: f64,
    /// Each impact's undamped Hertz closed forms.
    hertz: Vec<HertzImpact64>,
}

/// Integrates each class of `scene`, with its own law ([`SceneFile::class_law`]), at radius
/// {min, geometric centre, max} x speed {min, centre, max}, and gathers what [`calibrate`]
/// needs of each pulse.
fn integrate_grid(scene: &SceneFile) -> Result<GridPulses, SimError> {
    let plate = scene.plate.material();
    let mut g = GridPulses {
        all: Vec::new(),
        skews: Vec::new(),
        bend: 0.0,
        sampled: 0.0,
        pulses: Vec::new(),
        shortest_s: f64::INFINITY,
        ln_top: 0.0,
        hertz: Vec::new(),
    };
    let fs = scene.sensor.sample_rate_hz;
    for (i, class) in scene.classes.iter().enumerate() {
        let (r, u) = (class.radius_m, class.speed_range_m_s());
        let radii_m: [f64; GRID_AXIS] = [r.min, (r.min * r.max).sqrt(), r.max];
        let speeds_m_s: [f64; GRID_AXIS] = [u.min, 0.5 * (u.min + u.max), u.max];
        for radius in radii_m {
            for speed in speeds_m_s {
                let mut spec = ImpactSpec::new(class.material.material(), plate, radius, speed);
                spec.law = scene.class_law(i)?;
                let p = pulse_ratios_and_series(&spec)?;
                g.ln_top += (p.top_fraction / hertz_top_fraction()).ln();
                let hertz = spec.hertz()?;
                g.shortest_s = g.shortest_s.min(hertz.duration_s);
                g.hertz.push(hertz);
                g.pulses.push((p.peak_n, p.area_duration_s));
                g.bend = g.bend.max(sharpest_bend(&p.series, fs));
                g.skews.push(skewness(&p.series, 0.005));
                g.sampled = g.sampled.max(sampled_shape_spread(&p.series, fs));
                g.all.push((p.ratios, p.series));
            }
        }
    }
    Ok(g)
}

/// [`sampled_calibration`] of the grid's pulses: their series (`all`) with their peak force
/// (N) and duration from the area (s) (`pulses`); for a damped contact (`damped`) also the
/// correction by samples per pulse and sampling phase ([`phase_calibration`]), through
/// `chain` where there is one; `five` as the kernel reads them ([`reads_five_samples`]).
fn sampled_of_grid(
    all: &[(PulseRatios, Vec<(f64, f64)>)],
    pulses: &[(f64, f64)],
    damped: bool,
    five: bool,
    chain: Option<&EqualisedChain>,
) -> (Sampled64, Option<Phase64>) {
    let continuous: Vec<ContinuousPulse> = all
        .iter()
        .zip(pulses)
        .map(|((_, series), &(peak_n, duration_s))| ContinuousPulse {
            series,
            peak_n,
            duration_s,
            five,
        })
        .collect();
    let phase = damped.then(|| phase_calibration(&continuous, chain));
    (sampled_calibration(&continuous), phase)
}

/// Radii, and speeds, per class that [`integrate_grid`] integrates (its arrays have this
/// length, so the two cannot disagree).
const GRID_AXIS: usize = 3;

/// Impacts per class that [`integrate_grid`] integrates: radius x speed.
const GRID_PER_CLASS: usize = GRID_AXIS * GRID_AXIS;

/// The grid's impacts by class, as [`sampled_skew_tolerance`] takes them: each impact's
/// series (`all`, in grid order) with its Hertz closed forms (`hertz`).
fn class_grids<'a>(
    all: &'a [(PulseRatios, Vec<(f64, f64)>)],
    hertz: &[HertzImpact64],
) -> Vec<Vec<GridImpact<'a>>> {
    all.chunks(GRID_PER_CLASS)
        .zip(hertz.chunks(GRID_PER_CLASS))
        .map(|(pulses, hertz)| {
            pulses
                .iter()
                .zip(hertz)
                .map(|((_, series), &hertz)| GridImpact { hertz, series })
                .collect()
        })
        .collect()
}

/// Samples in the shortest pulse the kernel's detector measures in `scene`: the shortest Hertz
/// contact time of its classes (smallest radius, largest speed) times the calibration's
/// duration ratio (the damped pulse's duration from its area over the Hertz time: 0.78 for
/// Flores at e 0.5, 0.58 at e 0.3) times the sample rate; `None` for a contact the kernel
/// models exactly (no calibration).
pub fn shortest_measured_samples(scene: &SceneFile) -> Result<Option<f64>, SimError> {
    // The duration ratio alone is read: the chain does not change it.
    let Some(cal) = calibrate(scene, None)? else {
        return Ok(None);
    };
    let plate = scene.plate.material();
    let mut shortest_s = f64::INFINITY;
    for class in &scene.classes {
        let spec = ImpactSpec::new(
            class.material.material(),
            plate,
            class.radius_m.min,
            class.speed_range_m_s().max,
        );
        shortest_s = shortest_s.min(spec.hertz()?.duration_s);
    }
    Ok(Some(
        shortest_s * cal.ratios.duration * scene.sensor.sample_rate_hz,
    ))
}

/// A warning when the shortest pulse the detector measures in `scene`
/// ([`shortest_measured_samples`]) has fewer samples than its sampling correction starts from:
/// the phase table's first row, `coalshock::sampled_phase::PHASE_FIRST_N` (1.6), for a damped
/// law, else the 2.5 of the correction by samples per pulse, with the rate that gives it. The
/// kernel refuses such a scene (`coalshock::Scene::new`); this names the rate it needs. `None`
/// otherwise.
pub fn sampling_warning(scene: &SceneFile) -> Result<Option<String>, SimError> {
    let first = if scene.contact == LawSpec::Hertz {
        f64::from(SAMPLED_FIRST_N)
    } else {
        f64::from(PHASE_FIRST_N)
    };
    Ok(shortest_measured_samples(scene)?
        .filter(|&n| n < first)
        .map(|n| {
            format!(
                "the shortest pulse the detector measures (its duration from the area) has \
                 {n:.2} samples, below the {first:.1} its sampling correction starts from, so the \
                 kernel refuses this sample rate; raise it to at least {:.0} Hz",
                scene.sensor.sample_rate_hz * first / n
            )
        }))
}
