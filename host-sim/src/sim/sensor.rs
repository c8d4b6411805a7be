//! The sensor chain: contact force on the tail beam -> integer ADC samples.
//!
//! Stages, in order (every one optional but the rigid scale):
//!
//! 1. **Rigid beam**: `a(t) = F(t) / M` (m/s^2), `M` the effective mass in kg; expressed in
//!    counts as `u(t) = S F(t) / M` with `S` in counts per m/s^2.
//! 2. **Beam modes** (base-excited mass-spring-dampers riding on the rigid beam): mode `j` with
//!    `w_j = 2 pi f_j`, damping `zeta_j` and weight `g_j` obeys
//!    `q_j'' + 2 zeta_j w_j q_j' + w_j^2 q_j = u` and the beam's acceleration becomes
//!    `b = u + sum_j g_j q_j''` (transfer `1 + sum_j g_j s^2 / (s^2 + 2 zeta_j w_j s + w_j^2)`).
//! 3. **Accelerometer resonance**: `y'' + 2 zeta w y' + w^2 y = w^2 b`, a second-order
//!    low-pass with unit DC gain and `|H(j w)| = 1 / (2 zeta)`.
//! 4. **Sampling** at `t_n = phase_s + n / f_s` (a random phase chosen by the caller).
//! 5. **Noise**: additive white Gaussian, `noise_rms_counts` RMS, from a seeded ChaCha8 stream.
//! 6. **Offset and drift**: `+ dc_offset_counts + dc_drift_counts_per_s * t_n`.
//! 7. **ADC**: round half away from zero, then saturate at `[-2^(b-1), 2^(b-1) - 1]`.
//!
//! Stages 2-3 are linear ODEs `x' = A x + B u`, output `C x + D u`. They run on a fine grid of
//! step `h = 1 / (oversample f_s)` aligned with the sample instants, with the *exact*
//! discretisation for an input that is linear between fine points (first-order hold):
//! `x_{k+1} = Phi x_k + Gamma0 u_k + Gamma1 (u_{k+1} - u_k)`, `Phi = e^(A h)`, from one matrix
//! exponential of the augmented matrix `[[A h, B h, 0], [0, 0, 1], [0, 0, 0]]`. Where the force
//! is zero the state is advanced a whole sample at a time with `e^(A / f_s)`, and once its
//! output can no longer reach [`SLEEP_COUNTS`] it is set to zero and nothing is computed until
//! the next pulse. A chain with neither modes nor accelerometer is the pure scale
//! `round(S F(t_n) / M + noise)`: no grid, no state, no cost.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::scene::{SceneError, SensorSpec};

/// Below this bound on its future output (counts) the linear stages' state is set to zero.
pub const SLEEP_COUNTS: f64 = 1e-6;

/// A contact force history.
pub trait ForceSignal {
    /// Total contact force in N at time `t_s` (s).
    fn force_n(&self, t_s: f64) -> f64;

    /// `true` only when the force is zero on the whole closed interval `[t0_s, t1_s]`; lets the
    /// chain skip quiet stretches. The default (`false`) is always correct.
    fn is_zero_on(&self, _t0_s: f64, _t1_s: f64) -> bool {
        false
    }

    /// [`ForceSignal::force_n`] for a caller that walks forward in time: `cursor` (0 at the
    /// start of a walk) keeps the signal's position between calls, so that a signal made of
    /// many pulses need not search them all. The result is `force_n(t_s)` bit for bit, in any
    /// order of calls (walking forward is only faster). The default ignores the cursor.
    fn force_n_walk(&self, t_s: f64, _cursor: &mut usize) -> f64 {
        self.force_n(t_s)
    }

    /// [`ForceSignal::is_zero_on`] with the cursor of [`ForceSignal::force_n_walk`].
    fn is_zero_on_walk(&self, t0_s: f64, t1_s: f64, _cursor: &mut usize) -> bool {
        self.is_zero_on(t0_s, t1_s)
    }
}

/// Any function of time (s) as a force in N, never known to be zero.
#[derive(Debug, Clone, Copy)]
pub struct FnForce<F>(pub F);

impl<F: Fn(f64) -> f64> ForceSignal for FnForce<F> {
    fn force_n(&self, t_s: f64) -> f64 {
        (self.0)(t_s)
    }
}

/// The shape of one force pulse, in time since first contact.
#[derive(Debug, Clone, PartialEq)]
pub enum PulseShape {
    /// A recorded series: `force_n[k]` at `k step_s`, linear between points, and linear from
    /// the last point to zero at the pulse's `duration_s`.
    Series {
        /// Interval of the series in s.
        step_s: f64,
        /// Force in N at `0, step_s, 2 step_s, ...`.
        force_n: Vec<f64>,
    },
    /// The undamped Hertz pulse's universal shape `F_max sin^(3/2)(pi t / t_c)` (within 2.4 %
    /// of `F_max` of the exact pulse), `t_c` the pulse's `duration_s`.
    HertzSine {
        /// `F_max` in N.
        peak_force_n: f64,
    },
}

/// One force pulse placed in time.
#[derive(Debug, Clone, PartialEq)]
pub struct ForcePulse {
    /// Time of first contact in s.
    pub start_s: f64,
    /// Time from first contact to the end of the force pulse in s; the force is zero outside
    /// `[start_s, start_s + duration_s]`.
    pub duration_s: f64,
    /// Factor applied to the shape (1 for a physical pulse; larger to inject saturation).
    pub scale: f64,
    /// The shape.
    pub shape: PulseShape,
}

impl ForcePulse {
    /// Force in N at `tau_s` seconds after first contact (0 outside the pulse).
    pub fn force_at(&self, tau_s: f64) -> f64 {
        if !(tau_s > 0.0 && tau_s < self.duration_s) {
            return 0.0;
        }
        let f = match &self.shape {
            PulseShape::HertzSine { peak_force_n } => {
                let s = (std::f64::consts::PI * tau_s / self.duration_s)
                    .sin()
                    .max(0.0);
                peak_force_n * s * s.sqrt()
            }
            PulseShape::Series { step_s, force_n } => {
                let x = tau_s / step_s;
                let k = x.floor();
                let i = k as usize;
                let frac = x - k;
                match (force_n.get(i), force_n.get(i + 1)) {
                    (Some(&a), Some(&b)) => a + (b - a) * frac,
                    (Some(&a), None) => {
                        // From the last point to zero at the end of the pulse.
                        let t_last = k * step_s;
                        let span = self.duration_s - t_last;
                        if span > 0.0 {
                            a * (1.0 - (tau_s - t_last) / span).max(0.0)
                        } else {
                            0.0
                        }
                    }
                    _ => 0.0,
                }
            }
        };
        self.scale * f
    }
}

/// A sum of force pulses (possibly overlapping), sorted by start time.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ForceTrack {
    pulses: Vec<ForcePulse>,
    max_duration_s: f64,
}

impl ForceTrack {
    /// A track from pulses in any order (sorted here by start time).
    pub fn new(mut pulses: Vec<ForcePulse>) -> Self {
        pulses.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
        let max_duration_s = pulses.iter().map(|p| p.duration_s).fold(0.0, f64::max);
        Self {
            pulses,
            max_duration_s,
        }
    }

    /// The pulses, by start time.
    pub fn pulses(&self) -> &[ForcePulse] {
        &self.pulses
    }

    /// The pulses that start before `t1_s` and could still be on after `t0_s`, latest first:
    /// those starting in `[t0_s - longest duration, t1_s)`, found by binary search.
    fn candidates(&self, t0_s: f64, t1_s: f64) -> impl Iterator<Item = &ForcePulse> {
        let end = self.pulses.partition_point(|p| p.start_s < t1_s);
        let lo = t0_s - self.max_duration_s;
        self.pulses[..end]
            .iter()
            .rev()
            .take_while(move |p| p.start_s >= lo)
    }

    /// The same pulses as [`ForceTrack::candidates`], in the same order, found by walking
    /// forward from `cursor` (the first index of the previous call's window). A call earlier
    /// in time than the previous one searches afresh, so any order of calls is right.
    fn candidates_walk(
        &self,
        t0_s: f64,
        t1_s: f64,
        cursor: &mut usize,
    ) -> impl Iterator<Item = &ForcePulse> {
        let p = &self.pulses;
        let lo_t = t0_s - self.max_duration_s;
        let mut lo = (*cursor).min(p.len());
        if lo > 0 && p[lo - 1].start_s >= lo_t {
            lo = p.partition_point(|q| q.start_s < lo_t);
        }
        while lo < p.len() && p[lo].start_s < lo_t {
            lo += 1;
        }
        *cursor = lo;
        let mut end = lo;
        while end < p.len() && p[end].start_s < t1_s {
            end += 1;
        }
        p[lo..end].iter().rev()
    }
}

/// Sum of the pulses' forces at `t_s` (N); a pulse starting exactly at `t_s` has zero force
/// there, so a window that skips it gives the same sum.
fn force_sum<'a>(pulses: impl Iterator<Item = &'a ForcePulse>, t_s: f64) -> f64 {
    pulses.map(|p| p.force_at(t_s - p.start_s)).sum()
}

/// `true` when none of the pulses is on inside `(t0_s, t1_s)`.
fn none_on<'a>(mut pulses: impl Iterator<Item = &'a ForcePulse>, t0_s: f64, t1_s: f64) -> bool {
    !pulses.any(|p| p.start_s < t1_s && p.start_s + p.duration_s > t0_s)
}

impl ForceSignal for ForceTrack {
    fn force_n(&self, t_s: f64) -> f64 {
        force_sum(self.candidates(t_s, t_s), t_s)
    }

    fn is_zero_on(&self, t0_s: f64, t1_s: f64) -> bool {
        none_on(self.candidates(t0_s, t1_s), t0_s, t1_s)
    }

    fn force_n_walk(&self, t_s: f64, cursor: &mut usize) -> f64 {
        force_sum(self.candidates_walk(t_s, t_s, cursor), t_s)
    }

    fn is_zero_on_walk(&self, t0_s: f64, t1_s: f64, cursor: &mut usize) -> bool {
        none_on(self.candidates_walk(t0_s, t1_s, cursor), t0_s, t1_s)
    }
}

/// The linear stages, discretised.
#[derive(Debug, Clone)]
struct Linear {
    n: usize,
    oversample: u32,
    /// `e^(A h)`, row-major `n x n`.
    phi: Vec<f64>,
    gamma0: Vec<f64>,
    gamma1: Vec<f64>,
    /// `e^(A / f_s)`.
    phi_sample: Vec<f64>,
    c: Vec<f64>,
    d: f64,
    /// Bound on the future output per unit of each state.
    weight: Vec<f64>,
}

/// A sensor chain built from a [`SensorSpec`] (see the module docs for the stages).
#[derive(Debug, Clone)]
pub struct Sensor {
    spec: SensorSpec,
    counts_per_n: f64,
    adc_min: i32,
    adc_max: i32,
    linear: Option<Linear>,
}

impl Sensor {
    /// Builds and discretises the chain; refuses an invalid spec (see
    /// [`SensorSpec::validate`]).
    pub fn new(spec: &SensorSpec) -> Result<Self, SceneError> {
        spec.validate()?;
        let (adc_min, adc_max) = spec.adc_range();
        let linear = if spec.is_rigid() {
            None
        } else {
            Some(build_linear(spec))
        };
        Ok(Self {
            spec: spec.clone(),
            counts_per_n: spec.counts_per_m_s2 / spec.effective_mass_kg,
            adc_min,
            adc_max,
            linear,
        })
    }

    /// The spec the chain was built from.
    pub fn spec(&self) -> &SensorSpec {
        &self.spec
    }

    /// Rigid-beam scale `S / M` in counts per N.
    pub fn counts_per_newton(&self) -> f64 {
        self.counts_per_n
    }

    /// Lowest and highest ADC code.
    pub fn adc_range(&self) -> (i32, i32) {
        (self.adc_min, self.adc_max)
    }

    /// Sample rate in Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.spec.sample_rate_hz
    }

    /// `true` when the chain is the pure scale (no modes, no accelerometer resonance).
    pub fn is_rigid(&self) -> bool {
        self.linear.is_none()
    }

    /// Gain of the beam stage for a pulse much shorter than every mode's period,
    /// `1 + sum_j g_j` (1 without modes): the factor by which the modes raise the peak that
    /// the kernel reads as `F / M`.
    pub fn short_pulse_gain(&self) -> f64 {
        1.0 + self.spec.beam_modes.iter().map(|m| m.gain).sum::<f64>()
    }

    /// Noise-free output in counts (before offset, drift and the ADC) at the sample instants
    /// `t_n = phase_s + n / f_s`, `n = 0 .. n_samples`, starting from rest.
    pub fn analog_counts(
        &self,
        force: &dyn ForceSignal,
        n_samples: usize,
        phase_s: f64,
    ) -> Vec<f64> {
        let mut out = Vec::with_capacity(n_samples);
        self.for_each_analog(force, n_samples, phase_s, |v| out.push(v));
        out
    }

    /// Calls `emit` with the noise-free output of each sample in turn (see
    /// [`Sensor::analog_counts`]).
    fn for_each_analog(
        &self,
        force: &dyn ForceSignal,
        n_samples: usize,
        phase_s: f64,
        mut emit: impl FnMut(f64),
    ) {
        let fs = self.spec.sample_rate_hz;
        let k = self.counts_per_n;
        // The sample instants only move forward: the force is looked up by walking.
        let mut cursor = 0usize;
        let Some(lin) = &self.linear else {
            for i in 0..n_samples {
                emit(k * force.force_n_walk(phase_s + i as f64 / fs, &mut cursor));
            }
            return;
        };
        let os = lin.oversample as usize;
        let h = 1.0 / (fs * lin.oversample as f64);
        let fine_t = |j: usize| phase_s + j as f64 * h;
        let mut x = vec![0.0; lin.n];
        let mut next = vec![0.0; lin.n];
        let mut asleep = true;
        for i in 0..n_samples {
            let j0 = i * os;
            let (t0, t1) = (fine_t(j0), fine_t(j0 + os));
            let quiet = force.is_zero_on_walk(t0, t1, &mut cursor);
            if quiet && asleep {
                emit(0.0);
                continue;
            }
            let u_now = if quiet {
                0.0
            } else {
                k * force.force_n_walk(t0, &mut cursor)
            };
            emit(dot(&lin.c, &x) + lin.d * u_now);
            if quiet {
                mat_vec(&lin.phi_sample, &x, &mut next);
                std::mem::swap(&mut x, &mut next);
                let bound: f64 = x.iter().zip(&lin.weight).map(|(v, w)| v.abs() * w).sum();
                if bound < SLEEP_COUNTS {
                    x.iter_mut().for_each(|v| *v = 0.0);
                    asleep = true;
                }
            } else {
                asleep = false;
                let mut u0 = u_now;
                for step in 1..=os {
                    let u1 = k * force.force_n_walk(fine_t(j0 + step), &mut cursor);
                    mat_vec(&lin.phi, &x, &mut next);
                    for ((v, g0), g1) in next.iter_mut().zip(&lin.gamma0).zip(&lin.gamma1) {
                        *v += g0 * u0 + g1 * (u1 - u0);
                    }
                    std::mem::swap(&mut x, &mut next);
                    u0 = u1;
                }
            }
        }
    }

    /// Adds noise (seeded ChaCha8 stream `seed`, none drawn when the RMS is 0), offset and drift
    /// (`t_n = phase_s + n / f_s`), rounds half away from zero and saturates at the ADC range.
    pub fn digitise(&self, analog_counts: &[f64], phase_s: f64, seed: u64) -> Vec<i16> {
        let mut adc = Adc::new(self, phase_s, seed);
        analog_counts.iter().map(|&a| adc.code(a)).collect()
    }

    /// [`Sensor::analog_counts`] then [`Sensor::digitise`], without storing the analog values.
    pub fn sample(
        &self,
        force: &dyn ForceSignal,
        n_samples: usize,
        phase_s: f64,
        seed: u64,
    ) -> Vec<i16> {
        let mut adc = Adc::new(self, phase_s, seed);
        let mut out = Vec::with_capacity(n_samples);
        self.for_each_analog(force, n_samples, phase_s, |a| out.push(adc.code(a)));
        out
    }
}

/// Noise, offset, drift and quantisation, one sample after the other.
struct Adc {
    rng: ChaCha8Rng,
    sigma: f64,
    offset: f64,
    drift: f64,
    phase_s: f64,
    fs: f64,
    lo: f64,
    hi: f64,
    n: u64,
}

impl Adc {
    fn new(sensor: &Sensor, phase_s: f64, seed: u64) -> Self {
        let spec = &sensor.spec;
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed),
            sigma: spec.noise_rms_counts,
            offset: spec.dc_offset_counts,
            drift: spec.dc_drift_counts_per_s,
            phase_s,
            fs: spec.sample_rate_hz,
            lo: sensor.adc_min as f64,
            hi: sensor.adc_max as f64,
            n: 0,
        }
    }

    /// The code of the next sample with noise-free value `analog` (counts).
    fn code(&mut self, analog: f64) -> i16 {
        let mut v = analog + self.offset;
        if self.drift != 0.0 {
            v += self.drift * (self.phase_s + self.n as f64 / self.fs);
        }
        if self.sigma > 0.0 {
            let z: f64 = StandardNormal.sample(&mut self.rng);
            v += self.sigma * z;
        }
        self.n += 1;
        // max/min (not clamp): a NaN becomes the lowest code instead of panicking.
        v.round().max(self.lo).min(self.hi) as i16
    }
}

/// Assembles `A, B, C, D` in scaled states and discretises them.
///
/// States (all in counts): per mode `(w^2 q, w q')`, then the accelerometer `(y, y' / w_a)`.
/// Mode: `q~' = w v~`, `v~' = w (u - q~) - 2 zeta w v~`; beam acceleration
/// `b = (1 + G) u - sum g (q~ + 2 zeta v~)`, `G = sum g`; accelerometer
/// `y' = w_a v~_a`, `v~_a' = w_a (b - y) - 2 zeta_a w_a v~_a`.
fn build_linear(spec: &SensorSpec) -> Linear {
    let Continuous {
        n,
        a,
        b,
        c,
        d,
        weight,
    } = continuous(spec);
    let h = 1.0 / (spec.sample_rate_hz * spec.oversample as f64);
    let (phi, gamma0, gamma1) = first_order_hold(&a, &b, n, h);
    let t_sample = 1.0 / spec.sample_rate_hz;
    let a_t: Vec<f64> = a.iter().map(|x| x * t_sample).collect();
    let phi_sample = expm(&a_t, n);
    Linear {
        n,
        oversample: spec.oversample,
        phi,
        gamma0,
        gamma1,
        phi_sample,
        c,
        d,
        weight,
    }
}

/// The chain's continuous state-space model `x' = A x + B u`, `y = C x + D u` in the scaled
/// states of [`build_linear`] (`A` row-major, `n x n`), with each state's weight in the
/// bound of its ringing amplitude.
struct Continuous {
    n: usize,
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
    d: f64,
    weight: Vec<f64>,
}

/// The continuous model of `spec`'s beam modes and accelerometer (see [`build_linear`]).
fn continuous(spec: &SensorSpec) -> Continuous {
    let two_pi = 2.0 * std::f64::consts::PI;
    let modes = &spec.beam_modes;
    let n = 2 * modes.len() + if spec.accelerometer.is_some() { 2 } else { 0 };
    let mut a = vec![0.0; n * n];
    let mut b = vec![0.0; n];
    let mut c = vec![0.0; n];
    let g_sum: f64 = modes.iter().map(|m| m.gain).sum();
    let mut weight = vec![0.0; n];
    for (j, m) in modes.iter().enumerate() {
        let (q, v) = (2 * j, 2 * j + 1);
        let w = two_pi * m.frequency_hz;
        a[q * n + v] = w;
        a[v * n + q] = -w;
        a[v * n + v] = -2.0 * m.damping_ratio * w;
        b[v] = w;
        c[q] = -m.gain;
        c[v] = -2.0 * m.damping_ratio * m.gain;
        // Ringing amplitude of the mode's term is at most |g| sqrt(q~^2 + v~^2) (1 + 2 zeta).
        let wt = m.gain.abs() * (1.0 + 2.0 * m.damping_ratio);
        weight[q] = wt;
        weight[v] = wt;
    }
    let mut d = 1.0 + g_sum;
    if let Some(r) = &spec.accelerometer {
        let (y, v) = (n - 2, n - 1);
        let w = two_pi * r.frequency_hz;
        let z = r.damping_ratio;
        a[y * n + v] = w;
        a[v * n + y] = -w;
        a[v * n + v] = -2.0 * z * w;
        for (j, m) in modes.iter().enumerate() {
            a[v * n + 2 * j] = -w * m.gain;
            a[v * n + 2 * j + 1] = -w * 2.0 * m.damping_ratio * m.gain;
        }
        b[v] = w * (1.0 + g_sum);
        c.iter_mut().for_each(|x| *x = 0.0);
        c[y] = 1.0;
        d = 0.0;
        // The resonance amplifies its input by at most 1/(2 zeta_a); 1 + 1/zeta_a is a safe bound.
        let amp = 1.0 + 1.0 / z;
        weight.iter_mut().for_each(|x| *x *= amp);
        weight[y] = amp;
        weight[v] = amp;
    }
    Continuous {
        n,
        a,
        b,
        c,
        d,
        weight,
    }
}

/// `x' = A x + B u` over a step `h` with `u` linear within it (first-order hold): the
/// transition `Phi = e^(A h)` and the input gains `Gamma0`, `Gamma1` of `u` at the step's
/// start and of its slope, from the exponential of the augmented matrix.
fn first_order_hold(a: &[f64], b: &[f64], n: usize, h: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let m = n + 2;
    let mut aug = vec![0.0; m * m];
    for r in 0..n {
        for col in 0..n {
            aug[r * m + col] = a[r * n + col] * h;
        }
        aug[r * m + n] = b[r] * h;
    }
    aug[n * m + n + 1] = 1.0;
    let e = expm(&aug, m);
    let mut phi = vec![0.0; n * n];
    let mut gamma0 = vec![0.0; n];
    let mut gamma1 = vec![0.0; n];
    for r in 0..n {
        phi[r * n..(r + 1) * n].copy_from_slice(&e[r * m..r * m + n]);
        gamma0[r] = e[r * m + n];
        gamma1[r] = e[r * m + n + 1];
    }
    (phi, gamma0, gamma1)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `out = m x` for a row-major square `m`.
fn mat_vec(m: &[f64], x: &[f64], out: &mut [f64]) {
    let n = x.len();
    for (r, o) in out.iter_mut().enumerate() {
        *o = dot(&m[r * n..(r + 1) * n], x);
    }
}

/// `a b` for row-major `n x n` matrices.
fn mat_mul(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut out = vec![0.0; n * n];
    for r in 0..n {
        for k in 0..n {
            let v = a[r * n + k];
            if v != 0.0 {
                for c in 0..n {
                    out[r * n + c] += v * b[k * n + c];
                }
            }
        }
    }
    out
}

/// Matrix exponential `e^M` of a row-major `n x n` matrix by scaling and squaring: `M / 2^s`
/// with 1-norm at most 1/2, Taylor series to 24 terms (truncation below 1e-30), squared `s`
/// times.
pub(crate) fn expm(m: &[f64], n: usize) -> Vec<f64> {
    let norm = (0..n)
        .map(|c| (0..n).map(|r| m[r * n + c].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let s = if norm > 0.5 {
        (norm / 0.5).log2().ceil() as i32
    } else {
        0
    };
    let scale = 0.5f64.powi(s);
    let ms: Vec<f64> = m.iter().map(|x| x * scale).collect();
    let mut result = vec![0.0; n * n];
    let mut term = vec![0.0; n * n];
    for i in 0..n {
        result[i * n + i] = 1.0;
        term[i * n + i] = 1.0;
    }
    for k in 1..=24 {
        term = mat_mul(&term, &ms, n);
        let inv = 1.0 / k as f64;
        term.iter_mut().for_each(|x| *x *= inv);
        result.iter_mut().zip(&term).for_each(|(r, t)| *r += t);
    }
    for _ in 0..s {
        result = mat_mul(&result, &result, n);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expm_of_rotation() {
        let th = 3.0;
        let e = expm(&[0.0, th, -th, 0.0], 2);
        let want = [th.cos(), th.sin(), -th.sin(), th.cos()];
        for (a, b) in e.iter().zip(want) {
            assert!((a - b).abs() < 1e-13, "{e:?}");
        }
    }

    #[test]
    fn series_pulse_interpolates_and_ends_at_zero() {
        let p = ForcePulse {
            start_s: 1.0,
            duration_s: 2.5,
            scale: 2.0,
            shape: PulseShape::Series {
                step_s: 1.0,
                force_n: vec![0.0, 10.0, 4.0],
            },
        };
        let track = ForceTrack::new(vec![p]);
        assert_eq!(track.force_n(1.5), 10.0);
        assert_eq!(track.force_n(2.5), 14.0);
        assert_eq!(track.force_n(3.25), 4.0);
        assert_eq!(track.force_n(3.5), 0.0);
        assert!(track.is_zero_on(3.5, 9.0));
        assert!(track.is_zero_on(0.0, 1.0));
        assert!(!track.is_zero_on(0.0, 1.1));
    }
}
