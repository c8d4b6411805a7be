//! ADC saturation of a scene: the share of its impacts whose pulse will clip the ADC,
//! predicted when the scene is loaded, from the class envelopes and the chain's gain.
//!
//! For each class, over a midpoint grid of [`GRID`] x [`GRID`] cells in `(ln R, y)` with `y`
//! the speed `u` (uniform speed prior) or the drop height `h` (uniform height,
//! `u = sqrt(2 g h)`), so that every cell carries the same prior weight:
//!
//! 1. the peak force `F = r_F F_max` and duration `t = r_t t_c` of the pulse, with the Hertz
//!    closed forms `F_max`, `t_c` and the class's contact law's ratios `r_F`, `r_t` (the
//!    scene's law, or Thornton's for a class that yields; 1 for Hertz;
//!    otherwise the integrator's peak and pulse duration over Hertz's, on a [`LAW_GRID`]^2
//!    grid of the class's corners and inner points, bilinear between them);
//! 2. the chain's peak output `P = G+(t) S F / M` counts above the baseline, and its deepest
//!    dip `-G-(t) S F / M` (`S / M` counts per N; `G+ = 1`, `G- = 0` for a rigid chain;
//!    otherwise the noise-free chain's response to a Hertz pulse `sin^1.5(pi s / t)` of
//!    duration `t`, at [`GAIN_POINTS`] durations log-spaced over the scene's, linear in
//!    `ln t` between them);
//! 3. the chance that a sample reaches the top code `c_max = 2^(b-1) - 1`: the sample
//!    nearest the peak lies `tau` from it, uniform in `[0, dt/2]` (`dt = 1 / f_s`), and
//!    near its top the pulse is the Hertz `P cos^1.5(pi tau / t)`; with
//!    `T = c_max - 1/2 - offset` (the value that rounds to `c_max`), the sample clips for
//!    `tau <= tau* = (t / pi) acos((T / P)^(2/3))`, so with probability
//!    `min(1, 2 tau* / dt)` when `P >= T`; the same for the dip against `c_min + 1/2`.
//!
//! The kernel's detector measures such a pulse from its unclipped flanks, on a rigid beam and
//! behind a chain, when it knows the contact's shape (the undamped Hertz law, or a
//! self-similar damped law, whose shape the scene build tabulates) and no class yields;
//! otherwise, or when the flanks are too short, it rejects the pulse as `Saturated` (a raw code at either end of the ADC range). The prediction leaves out the noise (a few counts against a full scale of
//! thousands), the drift (it depends on the stream's length) and pile-ups (two pulses within
//! one contact add up).

use crate::physics::hertz64::HertzImpact64;
use crate::physics::impact::{ImpactSpec, simulate};
use crate::physics::integrate::SimError;
use crate::physics::law_spec::LawSpec;
use crate::scene::{ClassSpec, SceneError, SceneFile, SensorSpec, SpeedSpec};
use crate::sim::sensor::{ForcePulse, PulseShape, Sensor};

/// Share of impacts above which loading a scene warns about clipping.
pub const WARN_SHARE: f64 = 0.01;

/// Cells per axis of each class's grid.
pub const GRID: usize = 200;

/// Points per axis of each class's grid of contact-law ratios (damped laws only).
pub const LAW_GRID: usize = 5;

/// Durations of the chain's peak-gain table (chains with modes or an accelerometer only).
pub const GAIN_POINTS: usize = 24;

/// Samples per pulse duration at which the chain's peak gain is found.
const GAIN_SAMPLES_PER_PULSE: f64 = 64.0;

/// Why the prediction could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SaturationError {
    /// The sensor chain is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A class's impact could not be computed or integrated.
    #[error("class {class:?}: {error}")]
    Impact {
        /// The class.
        class: String,
        /// What failed.
        error: SimError,
    },
}

/// The predicted clipping of a scene's impacts.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClipPrediction {
    /// Prior-weighted share of the scene's impacts that clip, in `[0, 1]`.
    pub share: f64,
    /// `(class name, share of its impacts that clip)`, in the scene's order.
    pub per_class: Vec<(String, f64)>,
    /// Force in N on the rigid beam that reaches the top code: `T M / S`.
    pub full_scale_force_n: f64,
    /// Largest peak gain `G+` of the chain over the scene's pulse durations (1: rigid).
    pub peak_gain: f64,
    /// The kernel measures a clipped pulse from its unclipped flanks: a self-similar contact
    /// law (undamped Hertz or restitution-parametrised) and no class that yields, on a rigid
    /// beam or behind a chain. Otherwise it rejects a clipped pulse as saturated.
    pub from_flanks: bool,
}

impl ClipPrediction {
    /// One line: the share, per class, and what sets it.
    pub fn summary(&self) -> String {
        let classes: Vec<String> = self
            .per_class
            .iter()
            .map(|(n, s)| format!("{n} {:.2} %", 100.0 * s))
            .collect();
        format!(
            "ADC clipping: {:.2} % of the scene's impacts are predicted to reach full scale \
             ({}); full scale is {:.4} kN on the rigid beam, chain peak gain up to {:.3}",
            100.0 * self.share,
            classes.join(", "),
            self.full_scale_force_n / 1e3,
            self.peak_gain
        )
    }

    /// The warning when more than [`WARN_SHARE`] of the impacts clip.
    pub fn warning(&self) -> Option<String> {
        let fate = if self.from_flanks {
            "the kernel measures them from their unclipped flanks where it can (wider \
             sigmas, so less coverage) and rejects the rest as saturated"
        } else {
            "the kernel rejects them as saturated (it reads clipped flanks only under the \
             Hertz law or a restitution-parametrised one, with no class that yields)"
        };
        (self.share > WARN_SHARE).then(|| {
            format!(
                "{:.2} % of the scene's impacts will clip the ADC (more than {} %): {fate}; \
                 lower sensor.counts_per_m_s2 or raise sensor.adc_bits",
                100.0 * self.share,
                100.0 * WARN_SHARE
            )
        })
    }
}

/// Predicts the share of `scene`'s impacts that clip the ADC (see the module docs).
pub fn predict(scene: &SceneFile) -> Result<ClipPrediction, SaturationError> {
    let sensor = Sensor::new(&scene.sensor)?;
    let (lo, hi) = sensor.adc_range();
    let offset = scene.sensor.dc_offset_counts;
    let ends = Ends {
        top: hi as f64 - 0.5 - offset,
        bottom: -(lo as f64 + 0.5 - offset),
        dt_s: 1.0 / sensor.sample_rate_hz(),
        counts_per_n: sensor.counts_per_newton(),
    };
    let laws = (0..scene.classes.len())
        .map(|i| LawRatios::new(scene, i))
        .collect::<Result<Vec<_>, _>>()?;
    let (t_lo, t_hi) = duration_span(scene, &laws)?;
    let gain = ChainGain::new(&scene.sensor, t_lo, t_hi)?;
    let probs = scene.class_probabilities();
    let mut per_class = Vec::with_capacity(scene.classes.len());
    let mut share = 0.0;
    for ((c, law), p) in scene.classes.iter().zip(&laws).zip(&probs) {
        let s = class_share(scene, c, law, &gain, &ends)?;
        share += p * s;
        per_class.push((c.name.clone(), s));
    }
    Ok(ClipPrediction {
        share,
        per_class,
        full_scale_force_n: ends.top / ends.counts_per_n,
        peak_gain: gain.largest(),
        from_flanks: scene.contact.self_similar() && !scene.yields(),
    })
}

/// The ADC's ends as margins above and below the baseline, in counts.
struct Ends {
    /// `c_max - 1/2 - offset`.
    top: f64,
    /// `-(c_min + 1/2 - offset)` (positive).
    bottom: f64,
    /// Sample interval in s.
    dt_s: f64,
    /// `S / M` in counts per N.
    counts_per_n: f64,
}

impl Ends {
    /// Probability that a pulse of peak `peak` counts above the baseline (or dip `dip` below
    /// it) and duration `t_s` has a sample at an end of the ADC.
    fn clip_probability(&self, peak: f64, dip: f64, t_s: f64) -> f64 {
        let one = |p: f64, limit: f64| {
            // A NaN peak (never from valid closed forms) counts as no clipping.
            if p.is_nan() || p < limit {
                return 0.0;
            }
            let tau = t_s / std::f64::consts::PI * (limit / p).powf(2.0 / 3.0).acos();
            (2.0 * tau / self.dt_s).min(1.0)
        };
        one(peak, self.top).max(one(dip, self.bottom))
    }
}

/// Speed in m/s at the prior coordinate `y` of a class (speed, or drop height).
fn speed_at(c: &ClassSpec, y: f64) -> f64 {
    match c.speed {
        SpeedSpec::Uniform(_) => y,
        SpeedSpec::DropHeight(_) => crate::scene::drop_speed_m_s(y),
    }
}

/// The prior coordinate's range of a class: speed (m/s) or drop height (m).
fn prior_range(c: &ClassSpec) -> (f64, f64) {
    match c.speed {
        SpeedSpec::Uniform(r) | SpeedSpec::DropHeight(r) => (r.min, r.max),
    }
}

/// The Hertz closed forms of class `c` at radius `r_m` and prior coordinate `y`.
fn hertz_at(
    scene: &SceneFile,
    c: &ClassSpec,
    r_m: f64,
    y: f64,
) -> Result<HertzImpact64, SaturationError> {
    HertzImpact64::new(
        &c.material.material(),
        &scene.plate.material(),
        r_m,
        speed_at(c, y),
    )
    .map_err(|error| SaturationError::Impact {
        class: c.name.clone(),
        error,
    })
}

/// The share of class `c`'s impacts that clip.
fn class_share(
    scene: &SceneFile,
    c: &ClassSpec,
    law: &LawRatios,
    gain: &ChainGain,
    ends: &Ends,
) -> Result<f64, SaturationError> {
    let (x0, x1) = (c.radius_m.min.ln(), c.radius_m.max.ln());
    let (y0, y1) = prior_range(c);
    let mut sum = 0.0;
    for i in 0..GRID {
        let a = (i as f64 + 0.5) / GRID as f64;
        for j in 0..GRID {
            let b = (j as f64 + 0.5) / GRID as f64;
            let hz = hertz_at(scene, c, (x0 + a * (x1 - x0)).exp(), y0 + b * (y1 - y0))?;
            let (rf, rt) = law.at(a, b);
            let t = rt * hz.duration_s;
            let amplitude = ends.counts_per_n * rf * hz.peak_force_n;
            let (up, down) = gain.at(t);
            sum += ends.clip_probability(up * amplitude, down * amplitude, t);
        }
    }
    Ok(sum / (GRID * GRID) as f64)
}

/// A class's contact-law ratios `(F / F_max, t / t_c)` on the unit square of its prior
/// coordinates `(a, b)` (see the module docs).
struct LawRatios {
    /// `LAW_GRID x LAW_GRID` ratios, row `i` along `a`; empty for undamped Hertz.
    table: Vec<(f64, f64)>,
}

impl LawRatios {
    fn new(scene: &SceneFile, class: usize) -> Result<Self, SaturationError> {
        let c = &scene.classes[class];
        let err = |error| SaturationError::Impact {
            class: c.name.clone(),
            error,
        };
        let law = scene.class_law(class).map_err(err)?;
        if law == LawSpec::Hertz {
            return Ok(Self { table: Vec::new() });
        }
        let (x0, x1) = (c.radius_m.min.ln(), c.radius_m.max.ln());
        let (y0, y1) = prior_range(c);
        let mut table = Vec::with_capacity(LAW_GRID * LAW_GRID);
        for i in 0..LAW_GRID {
            let a = i as f64 / (LAW_GRID - 1) as f64;
            for j in 0..LAW_GRID {
                let b = j as f64 / (LAW_GRID - 1) as f64;
                let r = (x0 + a * (x1 - x0)).exp();
                let u = speed_at(c, y0 + b * (y1 - y0));
                let mut spec = ImpactSpec::new(c.material.material(), scene.plate.material(), r, u);
                spec.law = law;
                let hz = spec.hertz().map_err(err)?;
                let rep = simulate(&spec).map_err(err)?;
                table.push((
                    rep.peak_force_n / hz.peak_force_n,
                    rep.pulse_duration_s / hz.duration_s,
                ));
            }
        }
        Ok(Self { table })
    }

    /// Bilinear in the table at `(a, b)` in `[0, 1]^2`.
    fn at(&self, a: f64, b: f64) -> (f64, f64) {
        if self.table.is_empty() {
            return (1.0, 1.0);
        }
        let n = LAW_GRID - 1;
        let (fa, fb) = (a * n as f64, b * n as f64);
        let (i, j) = ((fa as usize).min(n - 1), (fb as usize).min(n - 1));
        let (wa, wb) = (fa - i as f64, fb - j as f64);
        let v = |i: usize, j: usize| self.table[i * LAW_GRID + j];
        let mix =
            |p: (f64, f64), q: (f64, f64), w: f64| (p.0 + w * (q.0 - p.0), p.1 + w * (q.1 - p.1));
        mix(
            mix(v(i, j), v(i, j + 1), wb),
            mix(v(i + 1, j), v(i + 1, j + 1), wb),
            wa,
        )
    }

    /// Smallest and largest duration ratio.
    fn duration_span(&self) -> (f64, f64) {
        self.table
            .iter()
            .fold(None, |acc: Option<(f64, f64)>, &(_, t)| {
                Some(acc.map_or((t, t), |(lo, hi)| (lo.min(t), hi.max(t))))
            })
            .unwrap_or((1.0, 1.0))
    }
}

/// Shortest and longest pulse of the scene in s: the Hertz `t_c = c R u^(-1/5)` at the
/// classes' corners times the law's duration ratios.
fn duration_span(scene: &SceneFile, laws: &[LawRatios]) -> Result<(f64, f64), SaturationError> {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for (c, law) in scene.classes.iter().zip(laws) {
        let (y0, y1) = prior_range(c);
        let (r_lo, r_hi) = law.duration_span();
        for r in [c.radius_m.min, c.radius_m.max] {
            for y in [y0, y1] {
                let t = hertz_at(scene, c, r, y)?.duration_s;
                lo = lo.min(t * r_lo);
                hi = hi.max(t * r_hi);
            }
        }
    }
    Ok((lo, hi))
}

/// The chain's peak gain `G+(t)` and dip gain `G-(t)` for a Hertz pulse of duration `t`.
struct ChainGain {
    /// `(ln t, G+, G-)`, increasing in `t`; empty for a rigid chain.
    table: Vec<(f64, f64, f64)>,
}

impl ChainGain {
    fn new(spec: &SensorSpec, t_lo: f64, t_hi: f64) -> Result<Self, SceneError> {
        if spec.is_rigid() {
            return Ok(Self { table: Vec::new() });
        }
        let (l0, l1) = (t_lo.ln(), t_hi.ln().max(t_lo.ln() + 1e-9));
        let table = (0..GAIN_POINTS)
            .map(|k| {
                let lt = l0 + (l1 - l0) * k as f64 / (GAIN_POINTS - 1) as f64;
                let (up, down) = peak_gains(spec, lt.exp())?;
                Ok((lt, up, down))
            })
            .collect::<Result<Vec<_>, SceneError>>()?;
        Ok(Self { table })
    }

    /// `(G+, G-)` at duration `t_s`, linear in `ln t` (held beyond the table's ends).
    fn at(&self, t_s: f64) -> (f64, f64) {
        let Some(first) = self.table.first() else {
            return (1.0, 0.0);
        };
        let lt = t_s.ln();
        let k = self.table.partition_point(|p| p.0 < lt);
        if k == 0 {
            return (first.1, first.2);
        }
        let Some(&(l1, u1, d1)) = self.table.get(k) else {
            let last = self.table[self.table.len() - 1];
            return (last.1, last.2);
        };
        let (l0, u0, d0) = self.table[k - 1];
        let w = (lt - l0) / (l1 - l0);
        (u0 + w * (u1 - u0), d0 + w * (d1 - d0))
    }

    /// Largest `G+` of the table (1 for a rigid chain).
    fn largest(&self) -> f64 {
        if self.table.is_empty() {
            return 1.0;
        }
        self.table
            .iter()
            .map(|p| p.1)
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// `(G+, G-)` of the noise-free chain `spec` for a Hertz pulse of duration `t_s`: its
/// largest output and deepest dip over `S F_max / M`, from first contact until the slowest
/// stage has rung for 1.25 periods, sampled at `max(64 / t, 16 f)` for the chain's highest
/// resonance `f`.
fn peak_gains(spec: &SensorSpec, t_s: f64) -> Result<(f64, f64), SceneError> {
    let freqs: Vec<f64> = spec
        .beam_modes
        .iter()
        .map(|m| m.frequency_hz)
        .chain(spec.accelerometer.map(|a| a.frequency_hz))
        .collect();
    let f_hi = freqs.iter().copied().fold(0.0, f64::max);
    let f_lo = freqs.iter().copied().fold(f64::INFINITY, f64::min);
    let rate = (GAIN_SAMPLES_PER_PULSE / t_s).max(16.0 * f_hi);
    let mut fine = spec.clone();
    fine.sample_rate_hz = rate;
    fine.noise_rms_counts = 0.0;
    fine.dc_offset_counts = 0.0;
    fine.dc_drift_counts_per_s = 0.0;
    let sensor = Sensor::new(&fine)?;
    let start_s = 2.0 / rate;
    let pulse = ForcePulse {
        start_s,
        duration_s: t_s,
        scale: 1.0,
        shape: PulseShape::HertzSine {
            peak_force_n: 1.0 / sensor.counts_per_newton(),
        },
    };
    let track = crate::sim::sensor::ForceTrack::new(vec![pulse]);
    let span_s = start_s + t_s + 1.25 / f_lo;
    let n = (span_s * rate).ceil() as usize + 1;
    let out = sensor.analog_counts(&track, n, 0.0);
    let up = out.iter().copied().fold(0.0, f64::max);
    let down = out.iter().copied().fold(0.0, |m: f64, v| m.max(-v));
    Ok((up, down))
}
