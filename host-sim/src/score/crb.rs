//! The Cramér-Rao bound of `(ln F_max, ln t_c)` for one force pulse sampled through the
//! scene's sensor chain in the scene's stated noise: the smallest covariance any unbiased
//! estimator of the two features can reach from the samples.
//!
//! # Model
//!
//! The samples of a pulse are `s_n(theta) = C[e^a f((t - t_0) e^(-c))](t_n) + b + w_n`, with
//! `f` the noiseless force pulse (N) of the impact, `C` the sensor chain (a linear operator
//! from force in N to counts, [`Sensor::analog_counts`]), `t_n = n / f_s` the sample instants,
//! and `w_n` white Gaussian noise of variance `sigma^2 = noise_rms_counts^2 + q^2 / 12`
//! (`q = 1` count, the ADC's quantisation step, taken as uniform and independent of the
//! signal). The parameters `theta = (a, c, t_0, b)` are `a = ln F_max - ln F_max0` and
//! `c = ln t_c - ln t_c0` (the features, shape fixed), the onset time `t_0` within the samples
//! and the baseline `b` in counts (the two nuisance parameters). The Fisher matrix is
//! `J_ij = sum_n (ds_n / d theta_i)(ds_n / d theta_j) / sigma^2`, plus the onset's support
//! information `12 / w^2` on `J_(t_0 t_0)` ([`onset_support_information`]); the bound of the
//! features is the upper left 2 x 2 block of `J^-1` (nuisances included: each one the
//! estimator does not know widens the bound).
//!
//! The support term is what the derivatives miss. A pulse's samples read noise alone before
//! its onset; the first sample whose noiseless output stands [`VISIBLE_SIGMAS`] noise RMS from
//! the baseline, `w` after the onset, brackets the onset within `w` (at least one sample
//! interval: [`onset_bracket_s`]). Without the term, a pulse that two samples see leaves three unknowns
//! `(a, c, t_0)` to two equations and no bound, though its first sample places its onset
//! within a sample; and a pulse whose onset is steepest (Tsuji's `delta^(1/4)` damping, an
//! infinite slope at contact) gets a bound far wider than its samples allow. The term is the
//! inverse variance of an onset uniform over the bracket (a Gaussian of that variance claims
//! less than the bracket does). A smooth onset in strong noise rises above the noise late,
//! so its bracket is wide and the term small; on a pulse of many samples above the noise the
//! derivatives say far more and the term moves the bound by well under a percent.
//!
//! The ADC reads each sample within its range (`sensor.adc_bits`, about `dc_offset_counts`):
//! a value beyond a limit reads as the limit. A sample whose mean lies near or past a limit
//! is a censored reading and keeps the share [`censored_share`] of its information, so a
//! clipped pulse's bound comes from its flanks and what its clipped samples still say. The
//! drift is left out.
//!
//! The derivative waveforms are computed through the chain (noise added after it):
//! `ds / da = s` exactly, and `ds / dc`, `ds / dt_0` by central differences of the chain's
//! output with the time scale and the onset moved by `+- STEP` of the pulse's duration;
//! `ds / db = 1`. The window is the pulse with [`MARGIN_SAMPLES`] before its onset and
//! `max(MARGIN_SAMPLES, duration)` after its end (the quiet samples around a pulse fix the
//! baseline; what a chain rings beyond that window is left out).

use crate::score::bayes::{normal_pdf as pdf, phi};
use crate::sim::sensor::{FnForce, ForcePulse, Sensor};

/// Quiet samples in the window before a pulse's onset (the kernel's pre-trigger ring holds 32).
pub const MARGIN_SAMPLES: usize = 32;

/// How far from the baseline, in noise RMS, a sample's noiseless output must stand to mark a
/// pulse's onset ([`onset_bracket_s`]): where one sample tells a pulse from the noise with an
/// error of `Q(1)` (16 %), the midpoint between 0 and it standing one RMS on either side.
pub const VISIBLE_SIGMAS: f64 = 2.0;

/// Relative step of the central differences in the time scale and the onset (of `t_c`).
pub const STEP: f64 = 0.005;

/// The noise variance per sample in counts^2: `noise_rms_counts^2 + 1 / 12` (white noise plus
/// the quantisation of a 1-count ADC step).
pub fn sample_variance_counts2(noise_rms_counts: f64) -> f64 {
    noise_rms_counts * noise_rms_counts + 1.0 / 12.0
}

/// The information on the onset `t_0` (1/s^2) that the samples' support gives besides the
/// Fisher matrix's derivatives: `12 / w^2`, the inverse variance of an onset uniform within
/// a bracket of `bracket_s` = `w` s ([`onset_bracket_s`]; 0 for an unbounded bracket).
pub fn onset_support_information(bracket_s: f64) -> f64 {
    if bracket_s.is_finite() && bracket_s > 0.0 {
        12.0 / (bracket_s * bracket_s)
    } else {
        0.0
    }
}

/// The bracket (s) within which the samples place a pulse's onset at `onset_s`: from the onset
/// to the first sample after it whose noiseless output `output` (counts, sample `n` at
/// `n / sample_rate_hz`) stands `visible_counts` or more from the baseline ([`VISIBLE_SIGMAS`]
/// noise RMS in [`pulse_bound`]), and never less than one sample interval. The samples before
/// that one hardly differ from the noise, so they cannot say where within the bracket the
/// onset lies. Infinite when no sample stands so high.
pub fn onset_bracket_s(
    output: &[f64],
    onset_s: f64,
    sample_rate_hz: f64,
    visible_counts: f64,
) -> f64 {
    output
        .iter()
        .enumerate()
        .map(|(n, v)| (n as f64 / sample_rate_hz, v))
        .find(|&(t, v)| t > onset_s && v.abs() >= visible_counts)
        .map_or(f64::INFINITY, |(t, _)| {
            (t - onset_s).max(1.0 / sample_rate_hz)
        })
}

/// The share of its Fisher information about its mean that one sample keeps when the ADC
/// reads it: a Gaussian reading of mean `mean_counts` and RMS `sigma_counts` censored to
/// `[lo_counts, hi_counts]` (a value beyond either limit reads as the limit),
/// `w = Phi(b) - Phi(a) - (b phi(b) - a phi(a)) + phi(a)^2 / Phi(a) + phi(b)^2 / Phi(-b)` with
/// `a = (lo - mean) / sigma`, `b = (hi - mean) / sigma`: the expected squared score of the
/// readings within the limits and of each limit's point mass, times `sigma^2`. 1 far within
/// the limits, 1/2 + 1/pi at one of them, falling to 0 past it.
pub fn censored_share(mean_counts: f64, sigma_counts: f64, lo_counts: f64, hi_counts: f64) -> f64 {
    let (a, b) = (
        (lo_counts - mean_counts) / sigma_counts,
        (hi_counts - mean_counts) / sigma_counts,
    );
    let mass = |density: f64, tail: f64| {
        if tail > 0.0 {
            density * density / tail
        } else {
            0.0
        }
    };
    let within = phi(b) - phi(a) - (b * pdf(b) - a * pdf(a));
    let w = within + mass(pdf(a), phi(a)) + mass(pdf(b), phi(-b));
    if w.is_finite() {
        w.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// The Fisher matrix `J_ij = sum_n d_i[n] d_j[n] / variance` of the derivative waveforms
/// `derivatives` (each `ds / d theta_i` in counts per unit of `theta_i`, all of one length)
/// in white noise of `variance` counts^2.
pub fn fisher(derivatives: &[Vec<f64>], variance: f64) -> Vec<Vec<f64>> {
    derivatives
        .iter()
        .map(|di| {
            derivatives
                .iter()
                .map(|dj| di.iter().zip(dj).map(|(a, b)| a * b).sum::<f64>() / variance)
                .collect()
        })
        .collect()
}

/// The inverse of a symmetric positive definite matrix by Cholesky (`None` when it is not
/// positive definite to working precision).
// Triangular factorisation and solves read best with their indices.
#[allow(clippy::needless_range_loop)]
pub fn invert_spd(m: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = m.len();
    // L L^T = m.
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = m[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                if !(s > 1e-300 && s > 1e-13 * m[i][i].abs()) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    // Columns of m^-1 by forward and back substitution.
    let mut inv = vec![vec![0.0; n]; n];
    for col in 0..n {
        let mut y = vec![0.0; n];
        for i in 0..n {
            let e = if i == col { 1.0 } else { 0.0 };
            y[i] = (e - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
        }
        for i in (0..n).rev() {
            let v = (y[i] - (i + 1..n).map(|k| l[k][i] * inv[k][col]).sum::<f64>()) / l[i][i];
            inv[i][col] = v;
        }
    }
    Some(inv)
}

/// Covariance of `(ln F_max, ln t_c)`: `[var ln F, var ln t_c, cov]`.
pub type FeatureCovariance = [f64; 3];

/// What the samples of one pulse allow: the Cramér-Rao bound of its features and its matched
/// filter's signal-to-noise ratio (see [`pulse_bound`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PulseBound {
    /// The bound of `(ln F_max, ln t_c)`; `None` when the Fisher matrix is singular (a pulse
    /// that leaves no trace in the samples).
    pub covariance: Option<FeatureCovariance>,
    /// The matched filter's signal-to-noise ratio `d = sqrt(sum_n s_n^2 / sigma^2)`, with `s_n`
    /// the chain's noiseless output (counts) in the white noise `sigma^2` of
    /// [`sample_variance_counts2`]: the square root of the amplitude's Fisher information
    /// `J_aa` of the module docs (baseline known), with the ADC's limits left out (a clipped
    /// pulse stands far above the noise all the same). A detector that knows the pulse's shape and
    /// correlates it with the samples at every offset finds it, at a false-alarm rate
    /// `Q(eta)` per offset, with probability `Phi(d - eta)` (Neyman-Pearson).
    pub snr: f64,
}

/// The [`PulseBound`] of `pulse` (its `start_s` ignored) sampled by `sensor` with its onset
/// `onset_fraction` of a sample after a sample instant (see the module docs): one pass of
/// the pulse and its derivative waveforms through the chain gives both.
pub fn pulse_bound(sensor: &Sensor, pulse: &ForcePulse, onset_fraction: f64) -> PulseBound {
    let d = pulse.duration_s;
    let (n, t0) = window(sensor, pulse, onset_fraction);
    // The chain's output for the pulse with log time scale `c` and onset `onset_s`.
    let output = |c: f64, onset_s: f64| -> Vec<f64> {
        let scale = (-c).exp();
        let force = FnForce(|t: f64| pulse.force_at((t - onset_s) * scale));
        sensor.analog_counts(&force, n, 0.0)
    };
    let s0 = output(0.0, t0);
    let (hc, ht) = (STEP, STEP * d);
    let diff = |p: Vec<f64>, m: Vec<f64>, h: f64| -> Vec<f64> {
        p.iter().zip(&m).map(|(a, b)| (a - b) / (2.0 * h)).collect()
    };
    let ds_dc = diff(output(hc, t0), output(-hc, t0), hc);
    let ds_dt0 = diff(output(0.0, t0 + ht), output(0.0, t0 - ht), ht);
    let ones = vec![1.0; n];
    let variance = sample_variance_counts2(sensor.spec().noise_rms_counts);
    let sigma = variance.sqrt();
    let bracket_s = onset_bracket_s(&s0, t0, sensor.sample_rate_hz(), VISIBLE_SIGMAS * sigma);
    let snr = (s0.iter().map(|v| v * v).sum::<f64>() / variance).sqrt();
    // Each sample's rows scaled by the root of the information its ADC reading keeps.
    let (lo, hi) = sensor.adc_range();
    let offset = sensor.spec().dc_offset_counts;
    let kept: Vec<f64> = s0
        .iter()
        .map(|&v| {
            censored_share(v + offset, sigma, f64::from(lo) + 0.5, f64::from(hi) - 0.5).sqrt()
        })
        .collect();
    let read = |d: Vec<f64>| -> Vec<f64> { d.iter().zip(&kept).map(|(v, k)| v * k).collect() };
    let mut j = fisher(&[read(s0), read(ds_dc), read(ds_dt0), read(ones)], variance);
    j[2][2] += onset_support_information(bracket_s);
    PulseBound {
        covariance: invert_spd(&j).map(|inv| [inv[0][0], inv[1][1], inv[0][1]]),
        snr,
    }
}

/// The Cramér-Rao bound of `(ln F_max, ln t_c)` of `pulse` at one onset: the covariance of
/// [`pulse_bound`].
pub fn feature_crb(
    sensor: &Sensor,
    pulse: &ForcePulse,
    onset_fraction: f64,
) -> Option<FeatureCovariance> {
    pulse_bound(sensor, pulse, onset_fraction).covariance
}

/// The window of [`pulse_bound`] for `pulse` with its onset `onset_fraction` of a sample
/// after a sample instant: its length in samples and the onset's time in s.
fn window(sensor: &Sensor, pulse: &ForcePulse, onset_fraction: f64) -> (usize, f64) {
    let fs = sensor.sample_rate_hz();
    let pulse_samples = (pulse.duration_s * fs).ceil() as usize + 1;
    let n = MARGIN_SAMPLES + pulse_samples + MARGIN_SAMPLES.max(pulse_samples);
    (n, (MARGIN_SAMPLES as f64 + onset_fraction) / fs)
}

/// [`pulse_bound`] averaged over `phases` onsets evenly spread over one sample (`k / phases`
/// of a sample, `k = 0 .. phases`): the covariance (`None` when any phase gives `None`) and
/// the signal-to-noise ratio of an impact whose onset is uniform within a sample.
pub fn phase_averaged_bound(sensor: &Sensor, pulse: &ForcePulse, phases: usize) -> PulseBound {
    let p = phases.max(1);
    let mut sum = Some([0.0; 3]);
    let mut snr = 0.0;
    for k in 0..p {
        let b = pulse_bound(sensor, pulse, k as f64 / p as f64);
        snr += b.snr;
        sum = sum.zip(b.covariance).map(|(mut sum, c)| {
            for (s, v) in sum.iter_mut().zip(c) {
                *s += v / p as f64;
            }
            sum
        });
    }
    PulseBound {
        covariance: sum,
        snr: snr / p as f64,
    }
}

/// The covariance of [`phase_averaged_bound`].
pub fn phase_averaged_crb(
    sensor: &Sensor,
    pulse: &ForcePulse,
    phases: usize,
) -> Option<FeatureCovariance> {
    phase_averaged_bound(sensor, pulse, phases).covariance
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SensorSpec;
    use crate::sim::sensor::PulseShape;

    fn rigid(noise_rms_counts: f64) -> Sensor {
        Sensor::new(&SensorSpec::rigid(
            100_000.0,
            50.0,
            30.0,
            noise_rms_counts,
            16,
        ))
        .unwrap()
    }

    #[test]
    fn amplitude_bound_is_sigma_squared_over_the_energy_of_the_shape() {
        // One parameter, a sampled Gaussian pulse of known shape h_n: var(A) = sigma^2 /
        // sum h_n^2, and with an unknown baseline as well: sigma^2 / (sum h^2 - (sum h)^2 / N).
        let n = 200;
        let h: Vec<f64> = (0..n)
            .map(|i| (-0.5 * ((i as f64 - 100.3) / 4.0).powi(2)).exp())
            .collect();
        let var = 16.0;
        let e: f64 = h.iter().map(|v| v * v).sum();
        let inv = invert_spd(&fisher(std::slice::from_ref(&h), var)).unwrap();
        assert!((inv[0][0] / (var / e) - 1.0).abs() < 1e-12);
        let s: f64 = h.iter().sum();
        let inv = invert_spd(&fisher(&[h.clone(), vec![1.0; n]], var)).unwrap();
        let expected = var / (e - s * s / n as f64);
        assert!((inv[0][0] / expected - 1.0).abs() < 1e-12, "{inv:?}");
        // Closed form of the continuum: sum h^2 = 4 sqrt(pi) for a Gaussian of sigma 4 samples.
        assert!(
            (e / (4.0 * std::f64::consts::PI.sqrt()) - 1.0).abs() < 1e-9,
            "{e}"
        );
    }

    /// `f_max sin(pi t / t_s)^(3/2)` over `t_s` s, in closed form.
    fn hertz_sine(f_max: f64, t_s: f64) -> ForcePulse {
        ForcePulse {
            start_s: 0.0,
            duration_s: t_s,
            scale: 1.0,
            shape: PulseShape::HertzSine {
                peak_force_n: f_max,
            },
        }
    }

    /// `f_max sin(pi t / t_s)` over `t_s` s, as a series of 4097 points.
    fn half_sine(f_max: f64, t_s: f64) -> ForcePulse {
        ForcePulse {
            start_s: 0.0,
            duration_s: t_s,
            scale: 1.0,
            shape: PulseShape::Series {
                step_s: t_s / 4096.0,
                force_n: (0..=4096)
                    .map(|k| f_max * (std::f64::consts::PI * k as f64 / 4096.0).sin())
                    .collect(),
            },
        }
    }

    #[test]
    fn matched_filter_snr_of_a_long_half_sine_is_its_energy_over_the_noise() {
        // F sin(pi t / T) over N_p = T f_s samples on a rigid chain of g counts per N: the
        // samples' energy is (g F)^2 N_p / 2 (the mean of sin^2), so d = g F sqrt(N_p / 2) /
        // sigma, sigma^2 = 16 + 1/12, at every onset phase.
        let sensor = rigid(4.0);
        let g = sensor.counts_per_newton();
        let t = 4e-4; // 40 samples
        let f_max = 50.0;
        let pulse = half_sine(f_max, t);
        let expected = g * f_max * (40.0f64 / 2.0).sqrt() / (16.0f64 + 1.0 / 12.0).sqrt();
        for phase in [0.0, 0.3, 0.7] {
            let d = pulse_bound(&sensor, &pulse, phase).snr;
            assert!((d / expected - 1.0).abs() < 1e-3, "{d} against {expected}");
        }
        let d = phase_averaged_bound(&sensor, &pulse, 4).snr;
        assert!((d / expected - 1.0).abs() < 1e-3, "{d} against {expected}");
    }

    #[test]
    fn a_pulse_of_two_samples_is_bounded_by_its_onset_support() {
        // F sin(pi tau / T)^1.5 over T = 2.5 samples with its onset 0.3 of a sample after a
        // sample instant: two samples (tau = 0.7 and 1.7 samples) see it. Their Fisher matrix
        // in (a, c, t_0) alone is singular (two samples, three unknowns); the support puts the
        // onset within its sample (the first sample stands far beyond the noise), variance
        // 1 / (12 f_s^2). The two samples then fix the features given the onset and the
        // baseline (the window's 66 quiet samples give the baseline, variance sigma^2 / 66),
        // so the bound is the linear map's:
        // cov = D^-1 (sigma^2 I + g g^T / (12 f_s^2) + 1 1^T sigma^2 / 66) D^-T, D the 2 x 2
        // derivatives in (a, c) and g the derivative in t_0, all in closed form.
        let sensor = rigid(4.0);
        let (fs, gain) = (100_000.0, sensor.counts_per_newton());
        let (f_max, t) = (200.0, 2.5 / 100_000.0);
        let pulse = hertz_sine(f_max, t);
        let pi = std::f64::consts::PI;
        let h = |tau: f64| (pi * tau / t).sin().powf(1.5);
        let dh = |tau: f64| 1.5 * (pi * tau / t).sin().sqrt() * (pi * tau / t).cos() * pi / t;
        let taus = [0.7 / fs, 1.7 / fs];
        let d = taus.map(|tau| [gain * f_max * h(tau), -gain * f_max * dh(tau) * tau]);
        let g = taus.map(|tau| -gain * f_max * dh(tau));
        let var = sample_variance_counts2(4.0);
        let inner = |i: usize, j: usize| {
            let diagonal = if i == j { var } else { 0.0 };
            diagonal + g[i] * g[j] / (12.0 * fs * fs) + var / 66.0
        };
        let det = d[0][0] * d[1][1] - d[0][1] * d[1][0];
        let inv = [
            [d[1][1] / det, -d[0][1] / det],
            [-d[1][0] / det, d[0][0] / det],
        ];
        let cov = |p: usize, q: usize| {
            let mut sum = 0.0;
            for i in 0..2 {
                for j in 0..2 {
                    sum += inv[p][i] * inner(i, j) * inv[q][j];
                }
            }
            sum
        };
        let expected = [cov(0, 0), cov(1, 1), cov(0, 1)];
        let got = feature_crb(&sensor, &pulse, 0.3).unwrap();
        for (g, e) in got.iter().zip(expected) {
            assert!((g / e - 1.0).abs() < 1e-3, "{got:?} against {expected:?}");
        }
    }

    #[test]
    fn onset_bracket_runs_to_the_first_sample_clear_of_the_noise() {
        // Samples at n / 10 Hz, the onset at 0.32 s, the level 2: sample 4 (0.4 s) reads 1.5
        // (within it), sample 5 reads -2.5 (beyond it), so the onset lies within 0.18 s before
        // sample 5 and the information is 12 / 0.18^2. A first sample beyond the level gives
        // one sample interval (not the 0.08 s to it), and no sample beyond it no bound.
        let out = [0.0, 0.0, 0.0, 9.0, 1.5, -2.5, 4.0];
        let w = onset_bracket_s(&out, 0.32, 10.0, 2.0);
        assert!((w - 0.18).abs() < 1e-12, "{w}");
        assert!((onset_support_information(w) - 12.0 / 0.0324).abs() < 1e-9);
        let steep = [0.0, 0.0, 0.0, 0.0, 3.0, 1.0];
        assert!((onset_bracket_s(&steep, 0.32, 10.0, 2.0) - 0.1).abs() < 1e-12);
        assert!(onset_bracket_s(&[0.0, 1.0, -1.9], 0.05, 10.0, 2.0).is_infinite());
        assert_eq!(onset_support_information(f64::INFINITY), 0.0);
    }

    #[test]
    fn censored_share_is_the_expected_squared_score_of_a_clipped_reading() {
        // Far within the limits a reading keeps all its information; at one limit 1/2 + 1/pi
        // (the Tobit model's closed form). Elsewhere against the expected squared score of
        // the censored model summed numerically: the readings within the limits by the
        // midpoint rule, each limit's point mass `P` by a central difference of `ln P` in the
        // mean.
        assert!((censored_share(0.0, 1.0, -100.0, 100.0) - 1.0).abs() < 1e-12);
        let at_limit = censored_share(5.0, 1.0, -100.0, 5.0);
        assert!((at_limit - (0.5 + 1.0 / std::f64::consts::PI)).abs() < 1e-9);
        let (lo, hi, sigma) = (-3.0, 2.0, 1.5);
        for mean in [-4.0, -1.0, 0.0, 1.5, 2.0, 3.5, 6.0] {
            let pdf = |y: f64| {
                (-0.5 * ((y - mean) / sigma).powi(2)).exp()
                    / (sigma * (2.0 * std::f64::consts::PI).sqrt())
            };
            let steps = 200_000;
            let h = (hi - lo) / steps as f64;
            let within: f64 = (0..steps)
                .map(|k| {
                    let y = lo + (k as f64 + 0.5) * h;
                    ((y - mean) / (sigma * sigma)).powi(2) * pdf(y) * h
                })
                .sum();
            let p_low = |m: f64| phi((lo - m) / sigma);
            let p_high = |m: f64| phi((m - hi) / sigma);
            let dm = 1e-5;
            let score =
                |p: &dyn Fn(f64) -> f64| (p(mean + dm).ln() - p(mean - dm).ln()) / (2.0 * dm);
            let masses =
                score(&p_low).powi(2) * p_low(mean) + score(&p_high).powi(2) * p_high(mean);
            let expected = (within + masses) * sigma * sigma;
            let got = censored_share(mean, sigma, lo, hi);
            assert!(
                (got - expected).abs() < 1e-6,
                "mean {mean}: {got} against {expected}"
            );
        }
    }

    #[test]
    fn a_clipped_pulse_is_bounded_by_what_its_readings_keep() {
        // F sin(pi tau / T)^1.5 over 40 samples whose top 40 % lies past the 16-bit ADC's
        // upper limit: the Fisher matrix of the analytic derivatives (amplitude, time scale,
        // onset, baseline), each sample's row weighted by its censored share, and the onset's
        // support (its first sample stands far above the noise: one sample interval). The
        // bound is wider than the same pulse's unclipped one.
        let sensor = rigid(4.0);
        let (fs, gain) = (100_000.0, sensor.counts_per_newton());
        let (f_max, t) = (60_000.0 / gain, 40.0 / 100_000.0);
        let pulse = hertz_sine(f_max, t);
        let phase = 0.4;
        let pi = std::f64::consts::PI;
        let var = sample_variance_counts2(4.0);
        let n = MARGIN_SAMPLES + 41 + 41;
        let t0 = (MARGIN_SAMPLES as f64 + phase) / fs;
        let rows: Vec<[f64; 4]> = (0..n)
            .map(|k| {
                let tau = k as f64 / fs - t0;
                let (s, ds) = if tau > 0.0 && tau < t {
                    let x = pi * tau / t;
                    let ds = 1.5 * x.sin().sqrt() * x.cos() * pi / t;
                    (gain * f_max * x.sin().powf(1.5), gain * f_max * ds)
                } else {
                    (0.0, 0.0)
                };
                let w = censored_share(s, var.sqrt(), -32767.5, 32766.5).sqrt();
                [s * w, -ds * tau * w, -ds * w, w]
            })
            .collect();
        let derivatives: Vec<Vec<f64>> = (0..4)
            .map(|i| rows.iter().map(|r| r[i]).collect())
            .collect();
        let mut j = fisher(&derivatives, var);
        j[2][2] += 12.0 * fs * fs;
        let inv = invert_spd(&j).unwrap();
        let expected = [inv[0][0], inv[1][1], inv[0][1]];
        let got = feature_crb(&sensor, &pulse, phase).unwrap();
        // Within the error of the bound's central differences (STEP, 0.2 samples here).
        for (g, e) in got.iter().zip(expected) {
            assert!((g / e - 1.0).abs() < 5e-3, "{got:?} against {expected:?}");
        }
        let clipped_out = rows.iter().filter(|r| r[3] < 0.01).count();
        assert!(clipped_out >= 12, "{clipped_out}");
        // Unclipped, at half the force (a peak of 30 000 counts): var ln F scales as 1 / F^2.
        let unclipped = feature_crb(&sensor, &hertz_sine(0.5 * f_max, t), phase).unwrap()[0] / 4.0;
        println!(
            "var ln F_max: clipped {:.3e}, unclipped {unclipped:.3e} ({:.1} times)",
            got[0],
            got[0] / unclipped
        );
        assert!(got[0] > 3.0 * unclipped, "{got:?} against {unclipped}");
    }

    #[test]
    fn feature_bound_of_a_long_half_sine_matches_its_closed_form() {
        // A half-sine F sin(pi t / T) of N_p = T f_s samples in noise sigma: with the shape,
        // onset and time scale known the amplitude bound is sigma^2 / (g F)^2 / sum sin^2 =
        // 2 sigma^2 / ((g F)^2 N_p). With onset, scale and baseline unknown the bound of ln F
        // rises. The expected ratio of the full bound to the known-shape one is the (0, 0)
        // element of the inverse of the continuum Gram matrix of the four derivative
        // waveforms in x = t / T (pulse on (0, 1), window of length L in units of T):
        // ds/da = sin(pi x), ds/dc = -pi x cos(pi x), ds/d(t_0 / T) = -pi cos(pi x),
        // ds/db = 1, times <sin^2> = 1/2.
        let sensor = rigid(4.0);
        let g = sensor.counts_per_newton();
        let t = 4e-4; // 40 samples
        let f_max = 2000.0;
        let pulse = half_sine(f_max, t);
        let var = sample_variance_counts2(4.0);
        let np = t * 100_000.0;
        let known = 2.0 * var / ((g * f_max).powi(2) * np);
        let c = phase_averaged_crb(&sensor, &pulse, 8).unwrap();
        let m = 200_000;
        let pi = std::f64::consts::PI;
        let mut gram = vec![vec![0.0; 4]; 4];
        for k in 0..m {
            let x = (k as f64 + 0.5) / m as f64;
            let w = [
                (pi * x).sin(),
                -pi * x * (pi * x).cos(),
                -pi * (pi * x).cos(),
                1.0,
            ];
            for i in 0..4 {
                for j in 0..4 {
                    gram[i][j] += w[i] * w[j] / m as f64;
                }
            }
        }
        // The window: 32 samples, the pulse's 41, then 41 more; ones over all of it.
        gram[3][3] = (32.0 + 41.0 + 41.0) / np;
        let inv = invert_spd(&gram).unwrap();
        let expected = inv[0][0] * 0.5 * known;
        assert!(
            (c[0] / expected - 1.0).abs() < 0.03,
            "var ln F {} against {expected} (known shape {known})",
            c[0]
        );
        assert!(c[1] > 0.0 && c[2].abs() < (c[0] * c[1]).sqrt());
    }
}
