//! The skew tolerance a calibrated scene needs: how far the kernel's skewness check
//! (`coalshock::detector`, `symmetric_enough`) must allow a true single impact's sampled
//! pulse to stray from the contact's calibrated skewness, beyond the allowance the check
//! makes itself.
//!
//! The check takes the skewness of a pulse's samples above the trigger, weighted by `v^2`,
//! over its `n` such samples (pulses of fewer than 8 pass), and passes it within
//! `skew_tolerance + 0.6 / n + 40 (noise / F_max) / sqrt(n) + 4 |s| min(trigger / F_max, 1/4)`
//! of the calibrated skewness `s`. A few samples of a strongly skewed (damped) pulse weigh its
//! sides unevenly, by an amount that depends on the samples per pulse, the sampling phase and
//! the share of the low tail the trigger cuts, so on the impact's size and speed and on the
//! scene's rate and noise. The tolerance is read from the pulses the scene itself draws:
//! every class's sizes and speeds at [`GRID`] x [`GRID`] quantile midpoints of its priors, each
//! sampled at the scene's rate at [`PHASES`] phases, without noise. It is the smallest value
//! that leaves at most [`FALSE_REJECTION_SHARE`] of any class's impacts outside the allowance
//! without its noise term; that term, about eight sigmas of the noise's own effect on the
//! skewness (one sigma is `5.1 (noise / F_max) / sqrt(n)`), stays whole for the noise.

use crate::bridge::sampled_fit::force_at;
use crate::bridge::skewness::weighted_skewness;
use crate::physics::hertz64::HertzImpact64;
use crate::physics::impact::ImpactSpec;
use crate::physics::integrate::SimError;
use crate::scene::SceneFile;

/// Largest share of a class's true single impacts the skewness check may reject for the
/// shape their samples give (noise aside): 1e-3, a tenth of the 1 pp by which the forced
/// choice may trail the reference limit, so that the check cannot spend that margin itself
/// (the forced choice counts a rejected impact as missed).
pub const FALSE_REJECTION_SHARE: f64 = 1e-3;

/// Quantile midpoints per class of the radius, and of the speed: `GRID^2` impacts.
pub const GRID: usize = 32;

/// Sampling phases per impact, `(k + 1/2) / PHASES` of the sample interval, for an impact of
/// up to `PHASE_BUDGET / PHASES` (16) samples; one of more samples takes fewer
/// (`phases_for`).
pub const PHASES: usize = 32;

/// Samples per impact across its phases, beyond which fewer phases are taken: a pulse of many
/// samples weighs its sides evenly at any phase.
const PHASE_BUDGET: f64 = 512.0;

/// Samples above the trigger from which the detector checks a pulse's skewness.
const CHECKED_FROM: usize = 8;

/// What the detector's skewness check sees of a scene: its trigger level and noise in counts,
/// the counts per newton of contact force on the rigid path, and the sample rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkewCheck {
    /// Trigger level above the baseline, `max(trigger_sigmas noise, 2)` counts.
    pub trigger_counts: f64,
    /// Noise RMS in counts.
    pub noise_counts: f64,
    /// Counts per newton, `counts_per_m_s2 / effective_mass_kg`.
    pub counts_per_n: f64,
    /// Sample rate in Hz.
    pub sample_rate_hz: f64,
}

impl SkewCheck {
    /// The check of `scene`'s rigid path (a chain's equaliser raises the trigger and the noise
    /// by its noise gain, 1.0-1.6 on the shipped chains, which widens the check's allowance
    /// and cuts more of the low tail; the tolerance is read without it).
    pub fn of(scene: &SceneFile) -> Self {
        let noise = scene.sensor.noise_rms_counts;
        Self {
            trigger_counts: (f64::from(scene.settings.trigger_sigmas) * noise).max(2.0),
            noise_counts: noise,
            counts_per_n: scene.sensor.counts_per_m_s2 / scene.sensor.effective_mass_kg,
            sample_rate_hz: scene.sensor.sample_rate_hz,
        }
    }
}

/// One integrated impact of a class's calibration grid: its undamped Hertz impact (radius,
/// speed, `F_max`, `t_c`) and its force-time series `(t_s, force_n)`.
#[derive(Debug, Clone, Copy)]
pub struct GridImpact<'a> {
    /// The Hertz closed forms of the impact.
    pub hertz: HertzImpact64,
    /// Its integrated force-time series, uniformly spaced from first contact.
    pub series: &'a [(f64, f64)],
}

/// The skew tolerance `scene`'s pulses need (see the module docs): the largest over its
/// classes of [`class_tolerance`], `grids[i]` holding class `i`'s integrated impacts, about
/// the calibrated skewness `skew_mean`; 0 when every class stays within the allowance.
pub fn sampled_skew_tolerance(
    scene: &SceneFile,
    grids: &[Vec<GridImpact>],
    skew_mean: f64,
) -> Result<f64, SimError> {
    let check = SkewCheck::of(scene);
    let mut worst = 0.0f64;
    for (i, grid) in grids.iter().enumerate() {
        worst = worst.max(class_tolerance(scene, i, grid, skew_mean, &check)?);
    }
    Ok(worst)
}

/// The tolerance class `class` of `scene` needs: the smallest `t >= 0` with at most
/// [`FALSE_REJECTION_SHARE`] of the weight of its impacts' sampled excesses
/// (`impact_excesses`) above `t`. Each impact at the quantile midpoints of its radius and
/// speed takes the shape of the nearest impact of `grid` (in `ln R` and `u` over their ranges;
/// the same shape for a restitution-parametrised law), stretched to its own Hertz `t_c` and
/// scaled to its own `F_max`.
pub fn class_tolerance(
    scene: &SceneFile,
    class: usize,
    grid: &[GridImpact],
    skew_mean: f64,
    check: &SkewCheck,
) -> Result<f64, SimError> {
    let c = &scene.classes[class];
    let shapes: Vec<Shape> = grid.iter().map(Shape::of).collect();
    let mut excesses = Vec::new();
    for a in 0..GRID {
        for b in 0..GRID {
            let q = |k: usize| (k as f64 + 0.5) / GRID as f64;
            let (radius_m, speed_m_s) = c.at_quantiles(q(a), q(b));
            let spec = ImpactSpec::new(
                c.material.material(),
                scene.plate.material(),
                radius_m,
                speed_m_s,
            );
            let hertz = spec.hertz()?;
            let Some(j) = nearest(scene, class, grid, &hertz) else {
                continue;
            };
            let scaled = Scaled {
                shape: &shapes[j],
                time: hertz.duration_s / grid[j].hertz.duration_s,
                force: hertz.peak_force_n / grid[j].hertz.peak_force_n,
            };
            impact_excesses(&scaled, skew_mean, check, &mut excesses);
        }
    }
    Ok(upper_quantile(&mut excesses, FALSE_REJECTION_SHARE))
}

/// The index of the impact of `grid` nearest to `hertz` in `(ln R, u)`, each over the range
/// of class `class` of `scene` (0 for a range of one value).
fn nearest(
    scene: &SceneFile,
    class: usize,
    grid: &[GridImpact],
    hertz: &HertzImpact64,
) -> Option<usize> {
    let c = &scene.classes[class];
    let (r, u) = (c.radius_m, c.speed_range_m_s());
    let unit = |v: f64, lo: f64, hi: f64| if hi > lo { (v - lo) / (hi - lo) } else { 0.0 };
    let at = |h: &HertzImpact64| {
        (
            unit(h.radius_m.ln(), r.min.ln(), r.max.ln()),
            unit(h.speed_m_s, u.min, u.max),
        )
    };
    let (x, y) = at(hertz);
    let distance = |g: &GridImpact| {
        let (gx, gy) = at(&g.hertz);
        (gx - x).powi(2) + (gy - y).powi(2)
    };
    (0..grid.len()).min_by(|&i, &k| distance(&grid[i]).total_cmp(&distance(&grid[k])))
}

/// A grid impact's force series on a uniform step (for lookups in constant time).
#[derive(Debug, Clone)]
struct Shape {
    /// Force in N at `k step_s` from first contact.
    force_n: Vec<f64>,
    /// Interval in s.
    step_s: f64,
    /// Largest force in N.
    peak_n: f64,
}

impl Shape {
    /// The series of `g` at its own first interval.
    fn of(g: &GridImpact) -> Self {
        let s = g.series;
        let step_s = match (s.first(), s.get(1)) {
            (Some(a), Some(b)) if b.0 > a.0 => b.0 - a.0,
            _ => 1.0,
        };
        let last_s = s.last().map_or(0.0, |p| p.0);
        let points = (last_s / step_s).floor() as usize + 1;
        let force_n: Vec<f64> = (0..points)
            .map(|k| force_at(s, k as f64 * step_s))
            .collect();
        let peak_n = force_n.iter().fold(0.0f64, |m, &f| m.max(f));
        Self {
            force_n,
            step_s,
            peak_n,
        }
    }

    /// Force in N at `t_s` from first contact, linear between points, 0 outside.
    fn at(&self, t_s: f64) -> f64 {
        let x = t_s / self.step_s;
        if x.is_nan() || x < 0.0 {
            return 0.0;
        }
        let i = x as usize;
        match (self.force_n.get(i), self.force_n.get(i + 1)) {
            (Some(&a), Some(&b)) => a + (b - a) * (x - i as f64),
            _ => 0.0,
        }
    }

    /// Length of the series in s.
    fn length_s(&self) -> f64 {
        self.force_n.len().saturating_sub(1) as f64 * self.step_s
    }
}

/// A shape stretched by `time` and scaled by `force`: `F(t) = force * shape(t / time)`.
struct Scaled<'a> {
    shape: &'a Shape,
    time: f64,
    force: f64,
}

/// Phases taken of an impact of `samples` samples per pulse: [`PHASES`] up to
/// `PHASE_BUDGET / PHASES` samples, `PHASE_BUDGET / samples` above, at least 2.
fn phases_for(samples: f64) -> usize {
    ((PHASE_BUDGET / samples).floor() as usize).clamp(2, PHASES)
}

/// Appends to `out` the impact `p`'s sampled excesses ([`sampled_excess`]) with their weights,
/// `1 / phases` each (one impact weighs 1); an impact too short for [`CHECKED_FROM`] samples
/// above the trigger at any phase passes (excess `-inf`, weight 1).
fn impact_excesses(p: &Scaled, skew_mean: f64, check: &SkewCheck, out: &mut Vec<(f64, f64)>) {
    let samples = p.shape.length_s() * p.time * check.sample_rate_hz;
    if samples.floor() + 1.0 < CHECKED_FROM as f64 {
        out.push((f64::NEG_INFINITY, 1.0));
        return;
    }
    let phases = phases_for(samples);
    let mut above = Vec::new();
    for k in 0..phases {
        let phase = (k as f64 + 0.5) / phases as f64;
        let excess =
            sampled_excess(p, phase, skew_mean, check, &mut above).unwrap_or(f64::NEG_INFINITY);
        out.push((excess, 1.0 / phases as f64));
    }
}

/// How far the skewness the check reads of `p` sampled from `phase` (of the interval) after
/// first contact falls outside its allowance without the noise term,
/// `|skew - skew_mean| - 0.6 / n - 4 |skew_mean| min(trigger / F_max, 1/4)`, `F_max` the
/// pulse's own peak (which the detector's fit estimates); `None` below [`CHECKED_FROM`]
/// samples above the trigger. `above` is a scratch buffer for the samples above the trigger
/// (its contents on entry do not matter), kept by the caller across phases.
fn sampled_excess(
    p: &Scaled,
    phase: f64,
    skew_mean: f64,
    check: &SkewCheck,
    above: &mut Vec<(f64, f64)>,
) -> Option<f64> {
    let dt = 1.0 / check.sample_rate_hz;
    let scale = p.force * check.counts_per_n;
    let length_s = p.shape.length_s() * p.time;
    above.clear();
    let mut k = 0.0;
    while (k + phase) * dt < length_s {
        let v = scale * p.shape.at((k + phase) * dt / p.time);
        if v > check.trigger_counts {
            above.push((k, v));
        }
        k += 1.0;
    }
    let n = above.len();
    if n < CHECKED_FROM {
        return None;
    }
    let skew = weighted_skewness(above);
    let cut = check.trigger_counts / (scale * p.shape.peak_n);
    let allowed = 0.6 / n as f64 + 4.0 * skew_mean.abs() * cut.min(0.25);
    Some((skew - skew_mean).abs() - allowed)
}

/// The smallest `t >= 0` such that the values above `t` weigh at most `share` of the total
/// weight of `values` (`(value, weight)`); sorts `values`.
fn upper_quantile(values: &mut [(f64, f64)], share: f64) -> f64 {
    let total: f64 = values.iter().map(|v| v.1).sum();
    values.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut above = 0.0;
    for &(value, weight) in values.iter() {
        if above + weight > share * total {
            return value.max(0.0);
        }
        above += weight;
    }
    0.0
}
