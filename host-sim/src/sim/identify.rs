//! Estimates the tail beam's modes and the accelerometer's resonance from a recorded stream of
//! impacts (`host-sim identify`).
//!
//! # What is measured
//!
//! The chain of [`crate::sim::sensor`] is `H(s) = A(s) (1 + sum_j g_j s^2 / (s^2 + 2 zeta_j w_j s +
//! w_j^2))`, `A(s) = w_a^2 / (s^2 + 2 zeta_a w_a s + w_a^2)`, driven by the rigid signal
//! `u = S F / M` (counts). Once a pulse's force is over, the output is the chain's free
//! response: a sum of damped sinusoids `sum_j c_j z_j^n + c.c.`, one pole pair per mode
//! (`z_j = e^(p_j / f_s)`, `p_j = -zeta_j w_j + i w_j sqrt(1 - zeta_j^2)`, so `w_j = |p_j|` and
//! `zeta_j = -Re p_j / |p_j|`) and one for the accelerometer.
//!
//! # Method
//!
//! 1. **Pulses**: a linear predictor `y_n ~ sum_(k=1..8) a_k y_(n - k D)` is fitted to the
//!    stream by least squares: the modes' free ring-down is a sum of damped sinusoids, which it
//!    predicts, and a pulse is a forced response, which it does not. Samples whose prediction
//!    error exceeds 6 of its RMS (median absolute deviation) are flagged, the predictor refitted
//!    without them (3 fits), and flags closer than 1 ms (30 samples at least) form one pulse.
//!    The lag `D` is 20 us (at least one sample): at a shorter lag the predictor extrapolates a
//!    smooth, oversampled pulse and misses it (1 pulse in 60 at `D = 1` at 100 kS/s). A band-pass
//!    that flags sharp edges instead (the earlier detector) also flags a kHz mode's ringing at
//!    a low rate, where the mode's period is a few samples: the ringing joined the pulses and
//!    the free windows started after it had died. The flags run on for up to `8 D` samples
//!    after a pulse (the predictor's memory), so the free windows run from 2 samples after a
//!    pulse's last flag to 4 samples before the next pulse's first flag (the first flag is
//!    0-3 samples after the onset).
//! 2. **Poles (matrix pencil, Hua & Sarkar 1990)**: every free window gives Hankel rows
//!    `[y_k, y_(k+D), ..., y_(k+L D)]`; the rows of *all* windows are stacked (they share the
//!    poles, not the amplitudes), and the right singular vectors of the stack are the
//!    eigenvectors of its Gram matrix (`(L+1) x (L+1)`, accumulated window by window). The
//!    model order `M` is the number of eigenvalues above twice the noise floor (the median of
//!    the lower half). A pole pair is a mode if its ringing over the windows holds more than
//!    10 times the energy noise alone gives a fitted pair; `--modes N` reports the `N` that
//!    ring strongest of those (fewer if fewer ring: the output says so). With `V` the `M` leading vectors, the poles
//!    are the eigenvalues of `V0^+ V1` (`V0`, `V1`: `V` without its last, first row). A first
//!    pass at lag `D = 1` finds the highest mode; the second uses `D ~ f_s / (8 f_max)` so that
//!    the lags span a useful part of the slowest mode's period (at 100 kS/s a 180 Hz mode turns
//!    by 0.011 rad per sample: at `D = 1` its pole sits on top of `z = 1`). With
//!    `--accelerometer`, a first-pass pole that alone would hold `D` below 2 and sits 4 times
//!    above the next (a lightly damped piezo resonance ringing into the windows) is
//!    annihilated before the second pass, by filtering each window with `(1 - z q^-1)(1 -
//!    conj(z) q^-1)`: the other poles stay exactly where they are, and `f_max` is the next.
//! 3. **Gains**: each free window is fitted by linear least squares with the poles fixed
//!    (complex amplitudes `c_j`; no constant, see `fit_amplitudes`). Pulse `k` changes the amplitudes, referred
//!    to its first sample `n_0`, by the residue of `H(s) U_k(s)` at `p_j`:
//!    `Delta c_j = g_j p_j^2 U_k(p_j) / (p_j - conj p_j)`,
//!    `U_k(p) = integral u(t) e^(-p (t - t_0)) dt` (counts s; `Delta c` in counts,
//!    `p` in 1/s, `g` dimensionless). `U_k` comes from the measured pulse itself: the previous
//!    ringing (extrapolated) is subtracted, and the beam stage is inverted sample by sample
//!    (`u_n = (y_n - modes' state) / (1 + G)`, exact first-order-hold discretisation of each
//!    mode, the same as the sensor's), with the gains of the previous iteration (6 iterations
//!    from `g = 0`). Then `g_j = sum_k Re(conj K_kj Delta c_kj) / sum_k |K_kj|^2`,
//!    `K_kj = p_j^2 U_k(p_j) / (p_j - conj p_j)`: the least-squares gain over every
//!    pulse, which weights each pulse by its excitation of the mode. The accelerometer does
//!    not enter: `H = H_b A` and the stages commute, so the beam-inverted pulse is `A u`, and
//!    its transform is the `A(p_j) U(p_j)` the ring-down carries (multiplying by `A(p_j)`
//!    again, as an earlier version did, took 27 degrees of phase off a 2.1 kHz mode under a
//!    6.3 kHz, zeta 0.7 band). The sum over samples is `U_k` exactly when the pulse is
//!    band-limited below the Nyquist frequency.
//! 4. **Accelerometer** (`--accelerometer`): its resonance rings for a few samples right after
//!    the force ends. The modes' fit of the window after the pulse is extrapolated back; the
//!    pulse is over at the first sample after the peak where the remainder drops below
//!    `max(6 sigma, 3 %` of the peak), and the remainder over the next 32 samples (from one
//!    sample later) is the resonance's ring plus noise. A matrix pencil of order 4
//!    (`L = 8`; the ring's pair and room for what is left of the pulse's tail) over all pulses
//!    gives its pole: the highest-frequency oscillating one that is not within 10 % of a beam
//!    mode (what is left of a mode's misfit rings there too). It counts as identified only
//!    if its jackknife errors are within 1 % (frequency) and 20 % (damping); otherwise the
//!    output says it is not identified and the datasheet's value stays.
//!
//!    4b. **Band from the pulses' shape** (`--hertz-pulses` or `--pulse-law LAW
//!    --restitution E`, with `--accelerometer`): when the contact is undamped Hertz or a
//!    restitution-parametrised law, a pulse's force is `F_max h((t - t_0) / t_c)` with `h`
//!    known and the same for every impact ([`crate::sim::pulse_response`]), so the band need
//!    not ring to be seen: it shapes the pulse. Every pulse with free windows on both sides
//!    and no sample on a rail (two or more samples at the stream's lowest or highest code) is
//!    taken from 4 samples before its first flag to the free window after it, the ring before
//!    it removed (as in step 3), and
//!    fitted by that pulse through the chain: the modes just identified (frequency, damping,
//!    gain) and a band `(f_a, zeta_a)` shared by all pulses, discretised as the sensor does
//!    (first-order hold, 32 steps per sample). `(F_max, t_0, t_c)` are profiled out pulse by
//!    pulse, `(f_a, zeta_a)` searched by Nelder-Mead ([`crate::sim::band_fit`]); the jackknife
//!    over the same 8 groups of pulses, and the same bounds as step 4 (1 %, 20 %). Its
//!    estimate replaces step 4's. The fit is not made on step 3's beam-inverted pulse `A u`,
//!    though the band alone would then do: that inversion holds its input linear between
//!    samples, and a pulse of 3-12 samples through a 2.1 kHz mode (0.49 rad a sample at
//!    26.7 kS/s) is not; it biased the MEMS band by -1.3 to -1.5 % in frequency and -1.0 to
//!    -1.2 % in damping (seeds 1-5, 60 impacts), against -0.035 to +0.16 % and -0.02 to
//!    +0.04 % through the whole chain. The samples are taken about the stream's quiet level
//!    (`quiet_level`), not its median, which the pulses lift: the pulse model starts from zero,
//!    and an offset of 1-4 counts held the band 0.17-0.43 % low in frequency and 0.05-0.31 %
//!    in damping.
//! 5. **Uncertainty**: delete-a-group jackknife over 8 groups of windows (every 8th window);
//!    the standard error printed next to each value.
//!
//! Why the matrix pencil: Prony's method fits a linear predictor by least squares and roots
//! its polynomial: the predictor's coefficients are biased by noise on both sides of the
//! equation, and the roots of a high-order polynomial are very sensitive to those
//! coefficients, worst for poles crowded near `z = 1` as oversampled modes are. The pencil
//! keeps only the `M`-dimensional signal subspace (noise is cut by the SVD before any pole is
//! computed), needs no polynomial rooting (an `M x M` eigenproblem), and its variance is close
//! to the Cramér-Rao bound for damped sinusoids at moderate noise; unlike ESPRIT on a
//! covariance, it works from short records like the gaps between impacts, and pooling rows
//! over many windows is just summing Gram matrices.
//!
//! # Limits
//!
//! The modes must ring in the gaps between pulses (a gap of a few ms); the lowest mode is
//! resolved only to the extent that the gaps cover part of its period. Measured by
//! `tests/identify.rs` (4 counts RMS, 60 impacts, modes 180 Hz / 0.02 / 0.1, 650 Hz / 0.01 /
//! 0.05, 2.1 kHz / 0.02 / 0.03 at 100 kS/s, 0.1 at 26.7 kS/s): every frequency within 0.15 %,
//! the 650 Hz and 2.1 kHz modes' damping within 1 % and gain within 0.7 %; the 180 Hz mode's
//! damping within 8.3 % at 100 kS/s and 12.9 % at 26.7 kS/s (it turns by a third of a period
//! over a 2 ms gap), its gain within 4.5 %; the 40 kHz, 0.05 accelerometer within 0.03 % and
//! 2.3 %. A resonance above the Nyquist frequency aliases and one as damped as a MEMS part's
//! band (6.3 kHz, zeta 0.7 at 26.7 kS/s decays to a third per sample) rings for a sample or
//! two: their estimates scatter between groups and are reported as not identified. A lightly
//! damped resonance that rings on into the free windows (a 35 kHz, zeta 0.02 piezo at
//! 100 kS/s rings for about 1 ms) is annihilated before the modes' pencil (step 2); on
//! `scenes/piezo_chain.toml` (seeds 1, 2) every mode then comes within 0.02 % in frequency,
//! 2.4 % in damping and 2.8 % in gain, and the resonance within 0.01 % and 1.2 %. With
//! `--hertz-pulses` the MEMS band is identified from the pulses (step 4b): on
//! `scenes/mems_chain.toml`, 60 impacts, seeds 1-5, its frequency comes -0.035 to +0.16 % and
//! its damping -0.02 to +0.04 % off (jackknife errors 0.04-0.11 % and 0.01-0.04 %); 120 and
//! 240 impacts (seeds 1-3) give +0.06 to +0.16 % and -0.01 to +0.05 %: the frequency's small
//! excess over its jackknife error is not explained yet (`cargo test -p host-sim --release
//! --test identify mems_band -- --include-ignored --nocapture`). It holds only for an undamped
//! Hertz contact (`law = "hertz"`): a damped law's pulse has another shape. Pile-ups,
//! spikes and dropped samples are not handled (a flagged event is treated as one pulse).

use nalgebra::{Complex, DMatrix, DVector, SymmetricEigen};

use crate::physics::law_spec::LawSpec;
use crate::scene::BeamMode;
use crate::sim::band_fit::{BandPulse, fit_band};
use crate::sim::identify_tolerance::{
    self as tolerance, BAND_FIT_FLOOR, RING_FLOOR, TOLERANCE_SIGMAS,
    UNIDENTIFIED_RESONANCE_TOLERANCE,
};
use crate::sim::sensor::expm;

/// Order `q` of the pulse detector's linear predictor.
const PREDICTOR_ORDER: usize = 8;
/// Lag `D` of the predictor in s (at least one sample): see step 1 of the module docs.
const PREDICTOR_LAG_S: f64 = 20e-6;
/// Fits of the predictor (each without the samples the previous one failed on).
const PREDICTOR_PASSES: usize = 3;
/// Detector threshold in the prediction error's RMS (median absolute deviation).
const DETECT_SIGMAS: f64 = 6.0;
/// Flags closer than this (s, at least 30 samples) belong to one pulse: longer than any
/// contact time of the scenes (at most 0.6 ms), shorter than the gaps between impacts.
const MERGE_S: f64 = 1e-3;
/// A free window starts this many samples after a pulse's last flag (the flags already run
/// `q D` samples past the pulse's end).
const AFTER_PULSE: usize = 2;
/// A free window ends this many samples before the next pulse's first flag.
const BEFORE_PULSE: usize = 4;
/// Lags `L` of the pencil for the modes (columns `L + 1`).
const MODE_LAGS: usize = 48;
/// Samples of the accelerometer's ring used per pulse.
const ACCEL_WINDOW: usize = 32;
/// Lags of the pencil for the accelerometer.
const ACCEL_LAGS: usize = 8;
/// A resonance pole within this relative distance of a beam mode's frequency is that mode.
const MODE_CLASH: f64 = 0.1;
/// Largest relative jackknife error of an accelerometer's frequency that counts as identified.
const ACCEL_FREQUENCY_SCATTER: f64 = 0.01;
/// Largest relative jackknife error of its damping ratio that counts as identified.
const ACCEL_DAMPING_SCATTER: f64 = 0.2;
/// Groups of the jackknife.
const GROUPS: usize = 8;
/// Iterations of the gain / inverse-filter fixed point.
const GAIN_ITERATIONS: usize = 6;

/// A window's fit: complex amplitudes `c_j` (counts).
type WindowFit = Vec<Complex<f64>>;

/// One pulse's `(jackknife group, K_j, Delta c_j)` (see step 3 of the module docs).
type PulseResidues = (usize, Vec<Complex<f64>>, Vec<Complex<f64>>);

/// What `identify` is told.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdentifyOptions {
    /// Sample rate of the stream in Hz.
    pub sample_rate_hz: f64,
    /// Number of beam modes to report (`None`: as many as the singular values show).
    pub modes: Option<usize>,
    /// Also estimate the accelerometer's resonance.
    pub accelerometer: bool,
    /// The contact law whose pulse shape is known (undamped Hertz, or a restitution-parametrised
    /// law at its restitution: [`LawSpec::self_similar`]): fit the accelerometer's band to the
    /// pulses' shape (step 4b of the module docs) instead of its ring after them. Needs
    /// `accelerometer`. `None`: from the ring.
    pub pulse_law: Option<LawSpec>,
    /// Noise RMS in counts (`None`: estimated from the stream).
    pub noise_rms_counts: Option<f64>,
}

/// A value with its standard error (jackknife).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The estimate.
    pub value: f64,
    /// Its standard error, same unit.
    pub std_error: f64,
}

impl Estimate {
    /// `(value, std_error)`, as [`crate::sim::identify_tolerance`] takes it.
    fn pair(self) -> (f64, f64) {
        (self.value, self.std_error)
    }
}

/// One beam mode as identified.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeEstimate {
    /// Natural frequency in Hz.
    pub frequency_hz: Estimate,
    /// Damping ratio.
    pub damping_ratio: Estimate,
    /// Gain `g` (dimensionless).
    pub gain: Estimate,
}

/// The accelerometer's resonance as identified.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResonanceEstimate {
    /// Natural frequency in Hz.
    pub frequency_hz: Estimate,
    /// Damping ratio.
    pub damping_ratio: Estimate,
    /// Pulses whose ring (or, fitted to the Hertz shape, whose samples) were used.
    pub pulses: usize,
    /// What it was identified from.
    pub source: ResonanceSource,
}

/// Where the accelerometer's resonance was read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResonanceSource {
    /// Its ring right after the pulses (step 4).
    Ring,
    /// The pulses themselves, fitted with the contact law's shape through the band (step 4b,
    /// `--hertz-pulses` or `--pulse-law`).
    Pulses,
}

/// What `identify` found.
#[derive(Debug, Clone, PartialEq)]
pub struct Identification {
    /// Sample rate in Hz (as given).
    pub sample_rate_hz: f64,
    /// Noise RMS in counts (given or estimated).
    pub noise_rms_counts: f64,
    /// `true` when the noise RMS was estimated.
    pub noise_estimated: bool,
    /// Pulses found.
    pub pulses: usize,
    /// Free windows used for the poles.
    pub windows: usize,
    /// Pulses used for the gains.
    pub gain_pulses: usize,
    /// Lag `D` of the modes' pencil in samples.
    pub lag: usize,
    /// Modes asked for with `--modes`.
    pub modes_asked: Option<usize>,
    /// Beam modes by frequency.
    pub modes: Vec<ModeEstimate>,
    /// The accelerometer's resonance (if asked and found).
    pub accelerometer: Option<ResonanceEstimate>,
    /// `true` when the resonance was asked for.
    pub accelerometer_asked: bool,
    /// The law whose pulse shape the band was to be fitted to (`--hertz-pulses`, `--pulse-law`).
    pub pulse_law: Option<LawSpec>,
}

/// Why a stream cannot be identified.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum IdentifyError {
    /// An option out of range.
    #[error("{field}: {message}")]
    Invalid {
        /// The option, as the user names it.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// Not enough pulses or ring-down to work on.
    #[error("{0}")]
    NotEnough(String),
}

fn invalid(field: &'static str, message: String) -> IdentifyError {
    IdentifyError::Invalid { field, message }
}

/// A detected pulse: first and last flagged sample, and its largest sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PulseSpan {
    /// First flagged sample.
    pub first: usize,
    /// Last flagged sample.
    pub last: usize,
    /// Sample of the largest `|y|` between them.
    pub peak: usize,
}

/// Median of a slice (0 for an empty one); sorts a copy.
fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// Coefficients `a_k` of the linear predictor `y_n ~ sum_(k=1..q) a_k y_(n - k D)` fitted by
/// least squares over the samples `n` whose regressors and target are all unmasked (`None` if
/// too few are).
fn fit_predictor(y: &[f64], lag: usize, mask: &[bool]) -> Option<Vec<f64>> {
    let q = PREDICTOR_ORDER;
    let span = q * lag;
    let mut ata = DMatrix::<f64>::zeros(q, q);
    let mut atb = DVector::<f64>::zeros(q);
    let mut rows = 0;
    for n in span..y.len() {
        if (0..=q).any(|k| mask[n - k * lag]) {
            continue;
        }
        for a in 0..q {
            let xa = y[n - (a + 1) * lag];
            atb[a] += xa * y[n];
            for b in a..q {
                ata[(a, b)] += xa * y[n - (b + 1) * lag];
            }
        }
        rows += 1;
    }
    if rows < 4 * q {
        return None;
    }
    for a in 0..q {
        for b in 0..a {
            ata[(a, b)] = ata[(b, a)];
        }
    }
    ata.lu().solve(&atb).map(|x| x.iter().copied().collect())
}

/// Prediction error `e_n = y_n - sum_k a_k y_(n - k D)` (0 for the first `q D` samples).
fn prediction_error(y: &[f64], a: &[f64], lag: usize) -> Vec<f64> {
    let span = a.len() * lag;
    (0..y.len())
        .map(|n| {
            if n < span {
                return 0.0;
            }
            y[n] - a
                .iter()
                .enumerate()
                .map(|(k, ak)| ak * y[n - (k + 1) * lag])
                .sum::<f64>()
        })
        .collect()
}

/// Pulses of `y` (baseline removed): see step 1 of the module docs.
pub fn find_pulses(y: &[f64], sample_rate_hz: f64) -> Vec<PulseSpan> {
    let merge = ((MERGE_S * sample_rate_hz) as usize).max(30);
    let lag = ((PREDICTOR_LAG_S * sample_rate_hz).round() as usize).max(1);
    let span = PREDICTOR_ORDER * lag;
    if y.len() <= 8 * span {
        return Vec::new();
    }
    // The predictor is fitted, the samples it fails on masked, and refitted without them.
    let mut mask = vec![false; y.len()];
    for _ in 0..PREDICTOR_PASSES {
        let Some(a) = fit_predictor(y, lag, &mask) else {
            return Vec::new();
        };
        let e = prediction_error(y, &a, lag);
        let med = median(&e[span..]);
        let dev: Vec<f64> = e[span..].iter().map(|x| (x - med).abs()).collect();
        let thr = DETECT_SIGMAS * (1.4826 * median(&dev)).max(0.5);
        for (n, m) in mask.iter_mut().enumerate() {
            *m = n >= span && (e[n] - med).abs() > thr;
        }
    }
    let mut spans: Vec<PulseSpan> = Vec::new();
    for n in (0..y.len()).filter(|&n| mask[n]) {
        match spans.last_mut() {
            Some(s) if n - s.last <= merge => s.last = n,
            _ => spans.push(PulseSpan {
                first: n,
                last: n,
                peak: n,
            }),
        }
    }
    for s in &mut spans {
        s.peak = (s.first..=s.last)
            .max_by(|&a, &b| y[a].abs().total_cmp(&y[b].abs()))
            .unwrap_or(s.first);
    }
    spans
}

/// The Gram matrix `Y^T Y` of one window's Hankel rows `[w_k, w_(k+D), ..., w_(k+L D)]` and
/// its row count (none if the window is too short).
fn gram(w: &[f64], lag: usize, lags: usize) -> Option<(DMatrix<f64>, usize)> {
    let span = lag * lags;
    if w.len() < span + 1 + lags {
        return None;
    }
    let rows = w.len() - span;
    let c = lags + 1;
    let mut g = DMatrix::zeros(c, c);
    for i in 0..c {
        for j in i..c {
            let (a, b) = (&w[i * lag..i * lag + rows], &w[j * lag..j * lag + rows]);
            let s: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
            g[(i, j)] = s;
            g[(j, i)] = s;
        }
    }
    Some((g, rows))
}

/// Result of a pooled matrix pencil.
#[derive(Debug, Clone)]
pub struct Pencil {
    /// Poles of lag `D` (`z^D`), as many as the order.
    pub poles: Vec<Complex<f64>>,
    /// Eigenvalues of the pooled Gram matrix, largest first (squared singular values).
    pub eigenvalues: Vec<f64>,
    /// Hankel rows pooled.
    pub rows: usize,
    /// Noise variance per sample implied by the eigenvalue floor (counts^2).
    pub noise_var: f64,
}

/// Matrix pencil on a pooled Gram matrix of `rows` rows; order `Some(m)` or from the
/// eigenvalues (above twice the median of the lower half), at least `min_order`.
fn pencil_from_gram(
    g: &DMatrix<f64>,
    rows: usize,
    order: Option<usize>,
    min_order: usize,
) -> Option<Pencil> {
    let c = g.nrows();
    let eig = SymmetricEigen::new(g.clone());
    let mut idx: Vec<usize> = (0..c).collect();
    idx.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let values: Vec<f64> = idx.iter().map(|&i| eig.eigenvalues[i]).collect();
    let floor = median(&values[c / 2..]);
    let auto = values.iter().take_while(|&&v| v > 2.0 * floor).count();
    let m = order.unwrap_or(auto).max(min_order).min(c - 2);
    if m == 0 {
        return None;
    }
    let mut v = DMatrix::zeros(c, m);
    for (col, &i) in idx.iter().take(m).enumerate() {
        v.set_column(col, &eig.eigenvectors.column(i));
    }
    let v0 = v.rows(0, c - 1).into_owned();
    let v1 = v.rows(1, c - 1).into_owned();
    let normal = v0.transpose() * &v0;
    let rhs = v0.transpose() * &v1;
    let phi = normal.lu().solve(&rhs)?;
    let poles: Vec<Complex<f64>> = phi.complex_eigenvalues().iter().copied().collect();
    Some(Pencil {
        poles,
        eigenvalues: values,
        rows,
        noise_var: floor / rows.max(1) as f64,
    })
}

/// Matrix pencil (Hua & Sarkar) pooled over `windows`: Hankel rows at lag `lag` with `lags + 1`
/// columns, order chosen from the singular values but at least `min_order`. Windows shorter
/// than `lag lags + lags + 1` are skipped. `None` if no window is long enough.
pub fn matrix_pencil(
    windows: &[&[f64]],
    lag: usize,
    lags: usize,
    min_order: usize,
) -> Option<Pencil> {
    let (g, rows) = pooled_gram(windows, lag, lags)?;
    pencil_from_gram(&g, rows, None, min_order)
}

/// The Gram matrices of `windows` summed, and the rows pooled (`None` if no window is long
/// enough).
fn pooled_gram(windows: &[&[f64]], lag: usize, lags: usize) -> Option<(DMatrix<f64>, usize)> {
    let mut total = DMatrix::zeros(lags + 1, lags + 1);
    let mut rows = 0;
    for w in windows {
        if let Some((g, r)) = gram(w, lag, lags) {
            total += g;
            rows += r;
        }
    }
    (rows > 0).then_some((total, rows))
}

/// A continuous pole `p` (1/s) from a pole `z` of lag `lag` samples.
fn s_from_z(z: Complex<f64>, lag: usize, fs: f64) -> Complex<f64> {
    z.ln() * (fs / lag as f64)
}

/// `(frequency_hz, damping_ratio)` of a continuous pole.
fn freq_damping(p: Complex<f64>) -> (f64, f64) {
    let w = p.norm();
    (w / (2.0 * std::f64::consts::PI), -p.re / w)
}

/// A pole `p` from frequency and damping (upper half-plane).
fn pole(f_hz: f64, zeta: f64) -> Complex<f64> {
    let w = 2.0 * std::f64::consts::PI * f_hz;
    Complex::new(-zeta * w, w * (1.0 - zeta * zeta).max(0.0).sqrt())
}

/// Oscillating, decaying poles of a pencil as `(f, zeta)`, lowest frequency first.
fn modes_of(p: &Pencil, lag: usize, fs: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = p
        .poles
        .iter()
        .filter(|z| z.im > 1e-9 && z.norm() < 1.0)
        .map(|&z| freq_damping(s_from_z(z, lag, fs)))
        .filter(|&(f, zeta)| f > 0.0 && f < 0.5 * fs && zeta > 0.0 && zeta < 0.5)
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// Least-squares fit of `w` (origin at its first sample) by the damped sinusoids of `poles`
/// (continuous, upper half-plane): `c_j` with `w_n ~ sum_j 2 Re(c_j z_j^n)`. No constant is
/// fitted (the stream's median is removed first): over a window shorter than a slow mode's
/// period, a constant and that mode are nearly collinear, and the mode's amplitude, which the
/// gains rest on, would scatter (at 100 kS/s its gain's error grew tenfold with a constant).
/// `None` if the window is too short.
fn fit_amplitudes(w: &[f64], poles: &[Complex<f64>], fs: f64) -> Option<WindowFit> {
    let m = 2 * poles.len();
    if w.len() < m + 4 {
        return None;
    }
    let zs: Vec<Complex<f64>> = poles.iter().map(|p| (p / fs).exp()).collect();
    let mut ata = DMatrix::<f64>::zeros(m, m);
    let mut atb = DVector::<f64>::zeros(m);
    let mut pw: Vec<Complex<f64>> = vec![Complex::new(1.0, 0.0); zs.len()];
    let mut row = vec![0.0; m];
    for &y in w {
        for (j, p) in pw.iter().enumerate() {
            // 2 Re(c z^n) = 2 (c.re Re z^n - c.im Im z^n).
            row[2 * j] = 2.0 * p.re;
            row[2 * j + 1] = -2.0 * p.im;
        }
        for a in 0..m {
            atb[a] += row[a] * y;
            for b in a..m {
                ata[(a, b)] += row[a] * row[b];
            }
        }
        for (p, z) in pw.iter_mut().zip(&zs) {
            *p *= z;
        }
    }
    for a in 0..m {
        for b in 0..a {
            ata[(a, b)] = ata[(b, a)];
        }
    }
    let x = ata.lu().solve(&atb)?;
    let c = (0..poles.len())
        .map(|j| Complex::new(x[2 * j], x[2 * j + 1]))
        .collect();
    Some(c)
}

/// The pole the modes' pencil must not see, and the highest frequency (Hz) it then has to
/// resolve. With `--accelerometer`, the fastest pole of the first pass is the accelerometer's
/// (found again by its own fit, step 4) when it alone would hold the lag below 2 samples and
/// sits 4 times above the next: a lightly damped piezo resonance that rings on into the free
/// windows. Otherwise none, and the fastest pole sets the lag.
fn split_fast(rough: &[(f64, f64)], accelerometer: bool, fs: f64) -> (Option<(f64, f64)>, f64) {
    let mut by_f: Vec<(f64, f64)> = rough.to_vec();
    by_f.sort_by(|a, b| b.0.total_cmp(&a.0));
    match by_f.as_slice() {
        [top, next, ..] if accelerometer && fs / (8.0 * top.0) < 2.0 && top.0 > 4.0 * next.0 => {
            (Some(*top), next.0)
        }
        [top, ..] => (None, top.0),
        [] => (None, 0.0),
    }
}

/// `w` filtered by `(1 - z q^-1)(1 - conj(z) q^-1)`, `z = e^(p / f_s)` the pole of `fast`
/// (`(f, zeta)`): the filter annihilates that damped sinusoid's ringing exactly and keeps
/// every other pole of the window (a linear filter of a sum of damped exponentials only
/// rescales their amplitudes). Two samples shorter; `w` itself when `fast` is `None`.
fn annihilate(w: &[f64], fast: Option<(f64, f64)>, fs: f64) -> Vec<f64> {
    let Some((f, zeta)) = fast else {
        return w.to_vec();
    };
    let z = (pole(f, zeta) / fs).exp();
    let (a1, a2) = (-2.0 * z.re, z.norm_sqr());
    w.windows(3).map(|x| x[2] + a1 * x[1] + a2 * x[0]).collect()
}

/// `sum_j 2 Re(c_j z_j^k)` at offset `k` (any sign) from the fit's origin.
fn ring_at(c: &[Complex<f64>], poles: &[Complex<f64>], fs: f64, k: f64) -> f64 {
    c.iter()
        .zip(poles)
        .map(|(c, p)| 2.0 * (c * (p * (k / fs)).exp()).re)
        .sum::<f64>()
}

/// One mode discretised for the inverse filter: state `(w^2 q, w q')` as in the sensor.
struct ModeStep {
    phi: [f64; 4],
    gamma0: [f64; 2],
    gamma1: [f64; 2],
    /// Output `-g (q~ + 2 zeta v~)` per unit gain.
    c: [f64; 2],
}

fn mode_step(f_hz: f64, zeta: f64, fs: f64) -> ModeStep {
    let w = 2.0 * std::f64::consts::PI * f_hz;
    let h = 1.0 / fs;
    // Augmented [[A h, B h, 0], [0, 0, 1], [0, 0, 0]] for a first-order hold.
    let mut aug = [0.0; 16];
    aug[1] = w * h;
    aug[4] = -w * h;
    aug[5] = -2.0 * zeta * w * h;
    aug[4 + 2] = w * h;
    aug[2 * 4 + 3] = 1.0;
    let e = expm(&aug, 4);
    ModeStep {
        phi: [e[0], e[1], e[4], e[5]],
        gamma0: [e[2], e[6]],
        gamma1: [e[3], e[7]],
        c: [-1.0, -2.0 * zeta],
    }
}

/// The rigid signal `u` under the beam stage: inverts `y = (1 + G) u - sum_j g_j (q~ + 2 zeta
/// v~)` sample by sample from rest.
fn invert_beam(y: &[f64], steps: &[ModeStep], gains: &[f64]) -> Vec<f64> {
    let g_sum: f64 = gains.iter().sum();
    let mut x = vec![[0.0f64; 2]; steps.len()];
    let mut u_prev = 0.0;
    let mut out = Vec::with_capacity(y.len());
    for &yn in y {
        // x_n = Phi x + Gamma0 u_prev + Gamma1 (u_n - u_prev): split the part known now.
        let mut known = 0.0;
        let mut per_u = 1.0 + g_sum;
        let mut base = vec![[0.0f64; 2]; steps.len()];
        for (j, (s, xs)) in steps.iter().zip(&x).enumerate() {
            let b0 = s.phi[0] * xs[0] + s.phi[1] * xs[1] + (s.gamma0[0] - s.gamma1[0]) * u_prev;
            let b1 = s.phi[2] * xs[0] + s.phi[3] * xs[1] + (s.gamma0[1] - s.gamma1[1]) * u_prev;
            base[j] = [b0, b1];
            known += gains[j] * (s.c[0] * b0 + s.c[1] * b1);
            per_u += gains[j] * (s.c[0] * s.gamma1[0] + s.c[1] * s.gamma1[1]);
        }
        let u = (yn - known) / per_u;
        for ((xs, b), s) in x.iter_mut().zip(&base).zip(steps) {
            *xs = [b[0] + s.gamma1[0] * u, b[1] + s.gamma1[1] * u];
        }
        u_prev = u;
        out.push(u);
    }
    out
}

/// Jackknife standard error of leave-one-group-out estimates.
fn jackknife(values: &[f64]) -> f64 {
    let g = values.len();
    if g < 2 {
        return f64::NAN;
    }
    let mean = values.iter().sum::<f64>() / g as f64;
    let ss: f64 = values.iter().map(|v| (v - mean) * (v - mean)).sum();
    ((g - 1) as f64 / g as f64 * ss).sqrt()
}

/// Nearest `(f, zeta)` of `cands` to frequency `f` within 10 %.
fn nearest(cands: &[(f64, f64)], f: f64) -> Option<(f64, f64)> {
    cands
        .iter()
        .copied()
        .filter(|c| (c.0 / f - 1.0).abs() < 0.1)
        .min_by(|a, b| (a.0 - f).abs().total_cmp(&(b.0 - f).abs()))
}

/// Phase 0: the options are in range.
fn validate_identify(opts: &IdentifyOptions) -> Result<(), IdentifyError> {
    let fs = opts.sample_rate_hz;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(invalid(
            "--sample-rate",
            format!("must be a positive number of Hz (got {fs})"),
        ));
    }
    if let Some(s) = opts.noise_rms_counts
        && !(s.is_finite() && s > 0.0)
    {
        return Err(invalid(
            "--noise-rms",
            format!("must be a positive number of counts (got {s})"),
        ));
    }
    if opts.modes == Some(0) {
        return Err(invalid("--modes", "must be at least 1".to_string()));
    }
    if let Some(law) = opts.pulse_law {
        if !opts.accelerometer {
            return Err(invalid(
                "--hertz-pulses / --pulse-law",
                "fits the accelerometer's band to the pulses: give --accelerometer too".to_string(),
            ));
        }
        if !law.self_similar() {
            return Err(invalid(
                "--pulse-law",
                "needs a law whose pulse has one shape for every impact: hertz, hunt_crossley, \
                 lankarani_nikravesh, flores, gonthier or tsuji"
                    .to_string(),
            ));
        }
    }
    Ok(())
}

/// Phase 1: the free windows `[start, end)` of `len` samples around `pulses`: `windows[0]` is
/// the lead-in, `windows[k + 1]` follows pulse `k`.
fn free_windows(pulses: &[PulseSpan], len: usize) -> Vec<(usize, usize)> {
    let mut starts = vec![0usize];
    starts.extend(pulses.iter().map(|p| p.last + AFTER_PULSE));
    let mut ends: Vec<usize> = pulses
        .iter()
        .map(|p| p.first.saturating_sub(BEFORE_PULSE))
        .collect();
    ends.push(len);
    starts
        .iter()
        .zip(&ends)
        .map(|(s, e)| {
            // A stream may end inside a pulse: its window then starts past the data.
            let s = (*s).min(len);
            (s, (*e).max(s).min(len))
        })
        .collect()
}

/// Phase 2's second pass: the Grams of the free windows after the pulses at `lag`, by
/// jackknife group, and the order the first pass found.
struct Grams {
    lag: usize,
    fs: f64,
    group_gram: Vec<DMatrix<f64>>,
    group_rows: [usize; GROUPS],
    total_gram: DMatrix<f64>,
    total_rows: usize,
    /// Windows that gave a Gram.
    used: usize,
    min_order: usize,
}

impl Grams {
    /// The Grams of `slices[1..]` at a lag suited to the highest frequency `f_max` (Hz) to
    /// resolve: at most an eighth of its period, at most the median window over
    /// `2 MODE_LAGS`, at least 1; pencils of order at least `min_order`.
    fn new(slices: &[&[f64]], f_max: f64, min_order: usize, fs: f64) -> Self {
        let mut lens: Vec<f64> = slices[1..].iter().map(|w| w.len() as f64).collect();
        lens.retain(|&l| l > 0.0);
        let med_len = median(&lens);
        let lag = ((fs / (8.0 * f_max)).floor() as usize)
            .min((med_len / (2.0 * MODE_LAGS as f64)).floor() as usize)
            .max(1);
        let mut group_gram = vec![DMatrix::<f64>::zeros(MODE_LAGS + 1, MODE_LAGS + 1); GROUPS];
        let mut group_rows = [0usize; GROUPS];
        let mut used = 0;
        for (i, w) in slices.iter().enumerate().skip(1) {
            if let Some((g, r)) = gram(w, lag, MODE_LAGS) {
                group_gram[i % GROUPS] += g;
                group_rows[i % GROUPS] += r;
                used += 1;
            }
        }
        let zero = DMatrix::zeros(MODE_LAGS + 1, MODE_LAGS + 1);
        let total_gram: DMatrix<f64> = group_gram.iter().fold(zero, |acc, g| acc + g);
        Grams {
            lag,
            fs,
            total_rows: group_rows.iter().sum(),
            group_gram,
            group_rows,
            total_gram,
            used,
            min_order,
        }
    }

    /// The modes `(f, zeta)` of the pencil of Gram `g` over `rows` rows; poles above a quarter
    /// of the lag's Nyquist frequency are aliases or noise.
    fn refine(&self, g: &DMatrix<f64>, rows: usize) -> Vec<(f64, f64)> {
        if rows == 0 {
            return Vec::new();
        }
        let f_top = 0.25 * self.fs / self.lag as f64;
        let mut m = pencil_from_gram(g, rows, None, self.min_order)
            .map(|p| modes_of(&p, self.lag, self.fs))
            .unwrap_or_default();
        m.retain(|&(f, _)| f < f_top);
        m
    }

    /// The modes of every group but `g` (the jackknife's leave-one-group-out pencils).
    fn leave_out(&self, g: usize) -> Vec<(f64, f64)> {
        let gram = &self.total_gram - &self.group_gram[g];
        self.refine(&gram, self.total_rows - self.group_rows[g])
    }
}

/// Phase 3: the modes of `modes_fz` (ascending frequency) that ring above the noise (energy
/// over every fitted window above `20 sigma^2` per window), the strongest `--modes` when
/// asked, in ascending frequency.
fn ringing_modes(
    slices: &[&[f64]],
    modes_fz: &[(f64, f64)],
    noise_rms: f64,
    asked: Option<usize>,
    fs: f64,
) -> Result<Vec<(f64, f64)>, IdentifyError> {
    let poles: Vec<Complex<f64>> = modes_fz.iter().map(|&(f, z)| pole(f, z)).collect();
    let fits: Vec<Option<WindowFit>> = slices
        .iter()
        .map(|w| fit_amplitudes(w, &poles, fs))
        .collect();
    let energy: Vec<f64> = (0..poles.len())
        .map(|j| {
            fits.iter()
                .zip(slices)
                .filter_map(|(f, w)| f.as_ref().map(|c| (c[j], w.len())))
                .map(|(c, len)| {
                    // Energy of 2 Re(c z^n) over the window: 2 |c|^2 sum |z|^(2n).
                    let decay = (2.0 * poles[j].re / fs).exp();
                    2.0 * c.norm_sqr() * (1.0 - decay.powi(len as i32)) / (1.0 - decay).max(1e-12)
                })
                .sum()
        })
        .collect();
    let n_fits = fits.iter().filter(|f| f.is_some()).count().max(1) as f64;
    let mut keep: Vec<usize> = (0..poles.len()).collect();
    keep.sort_by(|&a, &b| energy[b].total_cmp(&energy[a]));
    keep.retain(|&j| energy[j] > 20.0 * noise_rms * noise_rms * n_fits);
    if let Some(n) = asked {
        keep.truncate(n);
    }
    keep.sort_by(|&a, &b| modes_fz[a].0.total_cmp(&modes_fz[b].0));
    if keep.is_empty() {
        return Err(IdentifyError::NotEnough(
            "no mode rings above the noise in the gaps between pulses".to_string(),
        ));
    }
    Ok(keep.iter().map(|&j| modes_fz[j]).collect())
}

/// The recording cut into free windows, with the modes' poles and each window's amplitudes.
struct Rings<'a> {
    y: &'a [f64],
    pulses: &'a [PulseSpan],
    windows: &'a [(usize, usize)],
    fits: &'a [Option<WindowFit>],
    poles: &'a [Complex<f64>],
    fs: f64,
}

impl Rings<'_> {
    /// The accelerometer's resonance from the ring-downs ([`identify_accelerometer`]), with
    /// every mode the pencil saw (`refined`, `(f_hz, zeta)`, reported or not: `--modes`)
    /// ringing on after the pulses, over noise `noise_rms` (counts).
    fn accelerometer(&self, refined: &[(f64, f64)], noise_rms: f64) -> Option<ResonanceEstimate> {
        let seen: Vec<f64> = refined.iter().map(|m| m.0).collect();
        let modes = ModesSeen {
            poles: self.poles,
            frequencies_hz: &seen,
        };
        identify_accelerometer(
            self.y,
            self.pulses,
            self.windows,
            self.fits,
            &modes,
            noise_rms,
            self.fs,
        )
    }

    /// Pulse `k`'s `(group, K_j, Delta c_j)` under the current `gains`: the pulse with the
    /// ring before it removed, inverted through the beam into the rigid signal `u`,
    /// `K_j = p_j^2 U(p_j) / (p_j - conj p_j)` and the jump of each mode's amplitude across
    /// it. `None` without free ring-down on both sides.
    fn residues(&self, k: usize, steps: &[ModeStep], gains: &[f64]) -> Option<PulseResidues> {
        let (fs, poles) = (self.fs, self.poles);
        let (n0, u) = self.inverted(k, steps, gains)?;
        let (Some(cb), Some(ca)) = (&self.fits[k], &self.fits[k + 1]) else {
            return None;
        };
        let (wb, wa) = (self.windows[k].0, self.windows[k + 1].0);
        let mut kk = Vec::with_capacity(poles.len());
        let mut dc = Vec::with_capacity(poles.len());
        for (j, pj) in poles.iter().enumerate() {
            let uk: Complex<f64> = u
                .iter()
                .enumerate()
                .map(|(i, &v)| (-pj * (i as f64 / fs)).exp() * v)
                .sum::<Complex<f64>>()
                / fs;
            let kj = pj * pj * uk / (pj - pj.conj());
            let before = cb[j] * (pj * ((n0 as f64 - wb as f64) / fs)).exp();
            let after = ca[j] * (pj * ((n0 as f64 - wa as f64) / fs)).exp();
            kk.push(kj);
            dc.push(after - before);
        }
        Some((k % GROUPS, kk, dc))
    }

    /// Pulse `k` from [`BEFORE_PULSE`] samples before its first flag to the free window after
    /// it, the ring before it removed and the beam stage inverted under `gains`: its first
    /// sample and the rigid signal through the accelerometer, `A u` (counts). `None` without
    /// free ring-down on both sides.
    fn inverted(&self, k: usize, steps: &[ModeStep], gains: &[f64]) -> Option<(usize, Vec<f64>)> {
        let (n0, pulse) = self.segment(k)?;
        Some((n0, invert_beam(&pulse, steps, gains)))
    }

    /// Pulse `k` from [`BEFORE_PULSE`] samples before its first flag to the free window after
    /// it, the ring before it removed: its first sample and the samples (counts). `None`
    /// without free ring-down on both sides.
    fn segment(&self, k: usize) -> Option<(usize, Vec<f64>)> {
        let (fs, y, poles) = (self.fs, self.y, self.poles);
        let (Some(cb), Some(_)) = (&self.fits[k], &self.fits[k + 1]) else {
            return None;
        };
        let wb = self.windows[k].0;
        let n0 = self.pulses[k].first.saturating_sub(BEFORE_PULSE);
        let n1 = self.windows[k + 1].0;
        if n1 <= n0 || n1 > y.len() {
            return None;
        }
        let pulse: Vec<f64> = (n0..n1)
            .map(|n| y[n] - ring_at(cb, poles, fs, n as f64 - wb as f64))
            .collect();
        Some((n0, pulse))
    }

    /// Phase 4: the gains `g_j = sum Re(conj K_j Delta c_j) / sum |K_j|^2` over the pulses,
    /// iterated [`GAIN_ITERATIONS`] times (each inversion uses the last gains), with the last
    /// iteration's residues per pulse.
    fn gains(&self, steps: &[ModeStep]) -> Result<(Vec<f64>, Vec<PulseResidues>), IdentifyError> {
        let mut gains = vec![0.0; self.poles.len()];
        let mut per_pulse: Vec<PulseResidues> = Vec::new();
        for _ in 0..GAIN_ITERATIONS {
            per_pulse = (0..self.pulses.len())
                .filter_map(|k| self.residues(k, steps, &gains))
                .collect();
            if per_pulse.is_empty() {
                return Err(IdentifyError::NotEnough(
                    "no pulse has free ring-down on both sides".to_string(),
                ));
            }
            for (j, g) in gains.iter_mut().enumerate() {
                *g = gain_of(&per_pulse, j, None).unwrap_or(0.0);
            }
        }
        Ok((gains, per_pulse))
    }
}

impl Rings<'_> {
    /// Step 4b of the module docs: the band fitted to the pulses (earlier ring removed) that are not
    /// clipped (no sample on a rail of `samples`, [`rails`]), identified only within the
    /// jackknife bounds of step 4.
    fn band_from_pulses(
        &self,
        samples: &[i16],
        modes: &[BeamMode],
        law: LawSpec,
    ) -> Option<ResonanceEstimate> {
        let (lo, hi) = rails(samples);
        let pulses: Vec<BandPulse> = (0..self.pulses.len())
            .filter_map(|k| {
                let (n0, u) = self.segment(k)?;
                let span = &samples[n0..n0 + u.len()];
                let clipped = span.iter().any(|&v| Some(v) == lo || Some(v) == hi);
                (!clipped).then_some(BandPulse {
                    group: k % GROUPS,
                    samples: u,
                })
            })
            .collect();
        let fit = fit_band(&pulses, modes, self.fs, law)?;
        let full = (fit.frequency_hz, fit.damping_ratio);
        within_bounds(full, &fit.leave_out, fit.pulses, ResonanceSource::Pulses)
    }
}

/// The resonance `(f in Hz, zeta)` with its jackknife errors over the leave-one-group-out
/// estimates `leave_out`, or `None` when they scatter by more than the tolerance the scene's
/// chain needs ([`ACCEL_FREQUENCY_SCATTER`], [`ACCEL_DAMPING_SCATTER`]).
fn within_bounds(
    (f, z): (f64, f64),
    leave_out: &[(f64, f64)],
    pulses: usize,
    source: ResonanceSource,
) -> Option<ResonanceEstimate> {
    let fj: Vec<f64> = leave_out.iter().map(|g| g.0).collect();
    let zj: Vec<f64> = leave_out.iter().map(|g| g.1).collect();
    let (f_se, z_se) = (jackknife(&fj), jackknife(&zj));
    if !(f_se < ACCEL_FREQUENCY_SCATTER * f && z_se < ACCEL_DAMPING_SCATTER * z) {
        return None;
    }
    Some(ResonanceEstimate {
        frequency_hz: Estimate {
            value: f,
            std_error: f_se,
        },
        damping_ratio: Estimate {
            value: z,
            std_error: z_se,
        },
        pulses,
        source,
    })
}

/// The codes a clipped stream sits on: its lowest and highest code when two or more samples
/// hold it (`None` for a code reached once, as a peak that fits the ADC's range is).
fn rails(samples: &[i16]) -> (Option<i16>, Option<i16>) {
    let rail =
        |code: Option<i16>| code.filter(|&c| samples.iter().filter(|&&v| v == c).count() >= 2);
    (
        rail(samples.iter().copied().min()),
        rail(samples.iter().copied().max()),
    )
}

/// Mode `j`'s least-squares gain over `per_pulse` (leaving out jackknife group `skip`), `None`
/// when no pulse carries it.
fn gain_of(per_pulse: &[PulseResidues], j: usize, skip: Option<usize>) -> Option<f64> {
    let (num, den) = per_pulse
        .iter()
        .filter(|(grp, _, _)| Some(*grp) != skip)
        .fold((0.0, 0.0), |(n, d), (_, kk, dc)| {
            (n + (kk[j].conj() * dc[j]).re, d + kk[j].norm_sqr())
        });
    (den > 0.0).then(|| num / den)
}

/// Phase 5: each mode's frequency, damping and gain with its jackknife standard error over
/// the [`GROUPS`] leave-one-group-out estimates.
fn jackknifed_modes(
    grams: &Grams,
    modes_fz: &[(f64, f64)],
    gains: &[f64],
    per_pulse: &[PulseResidues],
) -> Vec<ModeEstimate> {
    let loo_modes: Vec<Vec<(f64, f64)>> = (0..GROUPS).map(|g| grams.leave_out(g)).collect();
    let mut modes = Vec::with_capacity(modes_fz.len());
    for (j, &(f, z)) in modes_fz.iter().enumerate() {
        let (mut fj, mut zj, mut gj) = (Vec::new(), Vec::new(), Vec::new());
        for (g, lm) in loo_modes.iter().enumerate() {
            if let Some((fl, zl)) = nearest(lm, f) {
                fj.push(fl);
                zj.push(zl);
            }
            gj.extend(gain_of(per_pulse, j, Some(g)));
        }
        let estimate = |value, others: &[f64]| Estimate {
            value,
            std_error: jackknife(others),
        };
        modes.push(ModeEstimate {
            frequency_hz: estimate(f, &fj),
            damping_ratio: estimate(z, &zj),
            gain: estimate(gains[j], &gj),
        });
    }
    modes
}

/// A free window of samples, `[start, end)`.
type Window = (usize, usize);

/// Step 1 of the module docs: the pulses of `y` (at least 3) and the free windows between
/// them.
fn pulses_and_windows(y: &[f64], fs: f64) -> Result<(Vec<PulseSpan>, Vec<Window>), IdentifyError> {
    let pulses = find_pulses(y, fs);
    if pulses.len() < 3 {
        return Err(IdentifyError::NotEnough(format!(
            "found {} pulses in {} samples; at least 3 are needed",
            pulses.len(),
            y.len()
        )));
    }
    let windows = free_windows(&pulses, y.len());
    Ok((pulses, windows))
}

/// Step 2 of the module docs: the noise, the pencil's Gram matrices at the refined lag and
/// the modes they resolve.
struct PoleSearch {
    /// Noise RMS in counts (given, or the first pass's residual).
    noise_rms: f64,
    /// The Gram matrices of the free windows at the refined lag.
    grams: Grams,
    /// Every mode `(f in Hz, zeta)` the refined pencil finds.
    refined: Vec<(f64, f64)>,
}

/// Poles: a first pass at lag 1, then at a lag suited to the highest mode. The order comes
/// from the singular values; `--modes N` picks the `N` strongest modes later.
fn pole_search(
    slices: &[&[f64]],
    pulses: usize,
    opts: &IdentifyOptions,
    fs: f64,
) -> Result<PoleSearch, IdentifyError> {
    let rough = matrix_pencil(&slices[1..], 1, MODE_LAGS, 0).ok_or_else(|| {
        IdentifyError::NotEnough(format!(
            "no free ring-down of at least {} samples between the {} pulses",
            2 * MODE_LAGS + 1,
            pulses
        ))
    })?;
    let noise_rms = opts
        .noise_rms_counts
        .unwrap_or_else(|| rough.noise_var.sqrt());
    let rough_modes = modes_of(&rough, 1, fs);
    if rough_modes.is_empty() {
        return Err(IdentifyError::NotEnough(
            "the ring-down between pulses shows no damped oscillation above the noise".to_string(),
        ));
    }
    let (fast, f_max) = split_fast(&rough_modes, opts.accelerometer, fs);
    let filtered: Vec<Vec<f64>> = slices.iter().map(|w| annihilate(w, fast, fs)).collect();
    let slices_for_poles: Vec<&[f64]> = filtered.iter().map(|w| w.as_slice()).collect();
    let grams = Grams::new(&slices_for_poles, f_max, 2 * rough_modes.len(), fs);
    // The refined pencil resolves what the first pass merges (poles crowded near z = 1); its
    // band (a quarter of the lag's Nyquist frequency) holds every mode of the first pass.
    let refined = grams.refine(&grams.total_gram, grams.total_rows);
    Ok(PoleSearch {
        noise_rms,
        grams,
        refined,
    })
}

/// Identifies the chain from `samples` (ADC codes in time order): see the module docs.
pub fn identify(samples: &[i16], opts: &IdentifyOptions) -> Result<Identification, IdentifyError> {
    validate_identify(opts)?;
    let fs = opts.sample_rate_hz;
    let y = less_median(samples);

    // 1. Pulses and free windows.
    let (pulses, windows) = pulses_and_windows(&y, fs)?;
    let slices: Vec<&[f64]> = windows.iter().map(|&(s, e)| &y[s..e]).collect();

    // 2. Poles.
    let PoleSearch {
        noise_rms,
        grams,
        refined,
    } = pole_search(&slices, pulses.len(), opts, fs)?;
    let mut modes_fz = refined.clone();
    modes_fz.sort_by(|a, b| a.0.total_cmp(&b.0));

    // 3. Amplitudes of every window, and the modes that ring above the noise.
    let modes_fz = ringing_modes(&slices, &modes_fz, noise_rms, opts.modes, fs)?;
    let poles: Vec<Complex<f64>> = modes_fz.iter().map(|&(f, z)| pole(f, z)).collect();
    let fits: Vec<Option<WindowFit>> = slices
        .iter()
        .map(|w| fit_amplitudes(w, &poles, fs))
        .collect();

    // 4. The accelerometer, then the gains. The gains need not know the accelerometer: the
    // beam-inverted pulse is the rigid signal already filtered by it, `A U`, and the
    // ring-down it leaves is that of `H_b (A U)`.
    let rings = Rings {
        y: &y,
        pulses: &pulses,
        windows: &windows,
        fits: &fits,
        poles: &poles,
        fs,
    };
    let accel = if opts.accelerometer {
        rings.accelerometer(&refined, noise_rms)
    } else {
        None
    };
    let steps: Vec<ModeStep> = modes_fz.iter().map(|&(f, z)| mode_step(f, z, fs)).collect();
    let (gains, per_pulse) = rings.gains(&steps)?;
    let accel = if let Some(law) = opts.pulse_law {
        let modes: Vec<BeamMode> = modes_fz
            .iter()
            .zip(&gains)
            .map(|(&(frequency_hz, damping_ratio), &gain)| BeamMode {
                frequency_hz,
                damping_ratio,
                gain,
            })
            .collect();
        // The pulse model starts from zero: the samples about the stream's quiet level.
        let level = quiet_level(&slices, &fits, &poles, fs);
        let y_quiet: Vec<f64> = y.iter().map(|v| v - level).collect();
        let fits_quiet: Vec<Option<WindowFit>> = windows
            .iter()
            .map(|&(s, e)| fit_amplitudes(&y_quiet[s..e], &poles, fs))
            .collect();
        let quiet = Rings {
            y: &y_quiet,
            fits: &fits_quiet,
            ..rings
        };
        quiet.band_from_pulses(samples, &modes, law)
    } else {
        accel
    };

    // 5. Jackknife.
    Ok(Identification {
        sample_rate_hz: fs,
        noise_rms_counts: noise_rms,
        noise_estimated: opts.noise_rms_counts.is_none(),
        pulses: pulses.len(),
        windows: grams.used,
        gain_pulses: per_pulse.len(),
        lag: grams.lag,
        modes_asked: opts.modes,
        modes: jackknifed_modes(&grams, &modes_fz, &gains, &per_pulse),
        accelerometer: accel,
        accelerometer_asked: opts.accelerometer,
        pulse_law: opts.pulse_law,
    })
}

/// The quiet level of the samples about their median (counts): the constant that, fitted
/// jointly with every free window's own amplitudes of the modes `poles` (`fits`, each window's
/// fit of itself), fits the windows best. The median is not that level: the pulses, a few percent of the samples and all of
/// one sign, lift it (by 2-4 counts on `scenes/mems_chain.toml`). A window's constant alone
/// would be nearly collinear with a slow mode over a short window (see [`fit_amplitudes`]);
/// shared by all windows, among them the quiet lead-in before the first pulse, it is not:
/// `sum_w <r1_w, ry_w> / sum_w <r1_w, r1_w>`, `ry_w` and `r1_w` the residuals of the window's
/// fit of itself and of a constant, which weights each window by what of a constant its modes
/// cannot take up.
fn quiet_level(
    slices: &[&[f64]],
    fits: &[Option<WindowFit>],
    poles: &[Complex<f64>],
    fs: f64,
) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (w, fit) in slices.iter().zip(fits) {
        let ones = vec![1.0; w.len()];
        let (Some(cy), Some(c1)) = (fit, fit_amplitudes(&ones, poles, fs)) else {
            continue;
        };
        for (n, &v) in w.iter().enumerate() {
            let ry = v - ring_at(cy, poles, fs, n as f64);
            let r1 = 1.0 - ring_at(&c1, poles, fs, n as f64);
            num += r1 * ry;
            den += r1 * r1;
        }
    }
    if den > 0.0 { num / den } else { 0.0 }
}

/// The samples (counts) less their median: the signal about its quiet level.
fn less_median(samples: &[i16]) -> Vec<f64> {
    let raw: Vec<f64> = samples.iter().map(|&v| v as f64).collect();
    let base = median(&raw);
    raw.iter().map(|v| v - base).collect()
}

/// The beam's modes as `identify_accelerometer` needs them.
struct ModesSeen<'a> {
    /// Poles of the modes fitted to the windows (1/s, upper half-plane).
    poles: &'a [Complex<f64>],
    /// Frequencies (Hz) of every mode the pencil found, fitted or not.
    frequencies_hz: &'a [f64],
}

/// The ring right after each pulse, from where the pulse has fallen to the noise (or 3 % of
/// its height) to [`ACCEL_WINDOW`] samples on, with the modes' fit of the following window
/// subtracted; rings too short for the pencil are left out.
fn accelerometer_rings(
    y: &[f64],
    pulses: &[PulseSpan],
    windows: &[(usize, usize)],
    fits: &[Option<WindowFit>],
    poles: &[Complex<f64>],
    noise_rms: f64,
    fs: f64,
) -> Vec<Vec<f64>> {
    let mut rings: Vec<Vec<f64>> = Vec::new();
    for (k, p) in pulses.iter().enumerate() {
        let Some(ca) = &fits[k + 1] else {
            continue;
        };
        let wa = windows[k + 1].0;
        let model = |n: usize| ring_at(ca, poles, fs, n as f64 - wa as f64);
        let height = y[p.peak] - model(p.peak);
        let thr = (6.0 * noise_rms).max(0.03 * height.abs());
        let Some(end) = (p.peak + 1..wa).find(|&n| (y[n] - model(n)).abs() < thr) else {
            continue;
        };
        let start = end + 1;
        let stop = (start + ACCEL_WINDOW).min(windows[k + 1].1);
        if stop < start + 2 * ACCEL_LAGS + 2 {
            continue;
        }
        rings.push((start..stop).map(|n| y[n] - model(n)).collect());
    }
    rings
}

/// Step 4 of the module docs: the resonance's ring right after each pulse, the modes' fit of
/// the following window subtracted.
fn identify_accelerometer(
    y: &[f64],
    pulses: &[PulseSpan],
    windows: &[(usize, usize)],
    fits: &[Option<WindowFit>],
    modes: &ModesSeen,
    noise_rms: f64,
    fs: f64,
) -> Option<ResonanceEstimate> {
    let rings = accelerometer_rings(y, pulses, windows, fits, modes.poles, noise_rms, fs);
    let is_mode = |f: f64| {
        modes
            .frequencies_hz
            .iter()
            .any(|fm| (fm / f - 1.0).abs() < MODE_CLASH)
    };
    let estimate = |sel: &dyn Fn(usize) -> bool| -> Option<(f64, f64)> {
        let ws: Vec<&[f64]> = rings
            .iter()
            .enumerate()
            .filter(|(i, _)| sel(*i))
            .map(|(_, r)| r.as_slice())
            .collect();
        // Order 4: the ring's pair and room for what is left of the pulse's tail.
        let (g, rows) = pooled_gram(&ws, 1, ACCEL_LAGS)?;
        let p = pencil_from_gram(&g, rows, Some(4), 0)?;
        // The highest oscillating pole that is not one of the beam's modes left over.
        modes_of(&p, 1, fs)
            .into_iter()
            .rev()
            .find(|&(f, _)| !is_mode(f))
    };
    let full = estimate(&|_| true)?;
    let leave_out: Vec<(f64, f64)> = (0..GROUPS)
        .filter_map(|g| estimate(&|i| i % GROUPS != g))
        .collect();
    // A resonance that scatters between groups beyond the bounds is not identified: none
    // rings, or it is above the Nyquist frequency, or so damped that it rings for a sample or
    // two.
    within_bounds(full, &leave_out, rings.len(), ResonanceSource::Ring)
}

/// Significant digits for a value with standard error `se`: two digits of the error.
fn fmt_value(v: f64, se: f64) -> String {
    let digits = if se.is_finite() && se > 0.0 {
        (1 - se.log10().floor() as i32).max(0) as usize
    } else {
        6
    };
    format!("{v:.digits$}")
}

impl Identification {
    /// The comment lines above the table: what was found, and what is not identified.
    fn toml_header(&self) -> String {
        let mut s = String::new();
        s.push_str(&format!(
            "# host-sim identify: {} pulses, {} free windows (pencil lag {} samples), gains from \
             {} pulses; noise {:.2} counts RMS ({}).\n",
            self.pulses,
            self.windows,
            self.lag,
            self.gain_pulses,
            self.noise_rms_counts,
            if self.noise_estimated {
                "estimated"
            } else {
                "given"
            }
        ));
        s.push_str(
            "# +- values: jackknife standard errors over 8 groups of pulses. effective_mass_kg, \
             counts_per_m_s2\n# and adc_bits are not identified from a stream: keep the \
             scene's.\n",
        );
        if let Some(n) = self.modes_asked
            && n > self.modes.len()
        {
            s.push_str(&format!(
                "# {n} modes asked for, {} ring above the noise.\n",
                self.modes.len()
            ));
        }
        s
    }

    /// The scene's `chain_tolerance` this identification supports for the beam modes,
    /// `[frequency, damping, gain]` (relative): for each, the largest [`TOLERANCE_SIGMAS`]
    /// `sigma / |value|` over the identified modes, at least
    /// [`TOLERANCE_FLOOR`](crate::sim::identify_tolerance::TOLERANCE_FLOOR), rounded up to two
    /// digits ([`tolerance::modes_tolerance`]).
    pub fn chain_tolerance(&self) -> [f64; 3] {
        tolerance::modes_tolerance(
            self.modes
                .iter()
                .map(|m| [m.frequency_hz, m.damping_ratio, m.gain].map(Estimate::pair)),
        )
    }

    /// The scene's `accelerometer_tolerance` this identification supports, `[frequency,
    /// damping]` (relative), when the resonance was asked for: identified, the larger of
    /// [`TOLERANCE_SIGMAS`] standard errors and its method's floor ([`RING_FLOOR`],
    /// [`BAND_FIT_FLOOR`]); not identified, the kernel's default
    /// ([`UNIDENTIFIED_RESONANCE_TOLERANCE`], 2 % and 30 %), for the datasheet's value that
    /// stays.
    pub fn accelerometer_tolerance(&self) -> Option<[f64; 2]> {
        if !self.accelerometer_asked {
            return None;
        }
        Some(match &self.accelerometer {
            Some(a) => {
                let floor = match a.source {
                    ResonanceSource::Ring => RING_FLOOR,
                    ResonanceSource::Pulses => BAND_FIT_FLOOR,
                };
                tolerance::resonance_tolerance(
                    [a.frequency_hz, a.damping_ratio].map(Estimate::pair),
                    floor,
                )
            }
            None => UNIDENTIFIED_RESONANCE_TOLERANCE,
        })
    }

    /// The `[sensor]` table (identified entries only), with standard errors as comments.
    pub fn to_toml(&self) -> String {
        let mut s = self.toml_header();
        s.push_str("[sensor]\n");
        s.push_str(&format!("sample_rate_hz = {:?}\n", self.sample_rate_hz));
        s.push_str(&format!(
            "noise_rms_counts = {}\n",
            fmt_value(self.noise_rms_counts, 0.01)
        ));
        let [f, z, g] = self.chain_tolerance();
        s.push_str(&format!(
            "chain_tolerance = {{ frequency = {f}, damping = {z}, gain = {g} }}  # the modes: the \
             larger of {} standard errors and the errors on simulated streams\n",
            TOLERANCE_SIGMAS
        ));
        if let Some([f, z]) = self.accelerometer_tolerance() {
            let why = if self.accelerometer.is_some() {
                "the same for the accelerometer"
            } else {
                "not identified: the kernel's default"
            };
            s.push_str(&format!(
                "accelerometer_tolerance = {{ frequency = {f}, damping = {z} }}  # {why}\n"
            ));
        }
        if self.pulse_law.is_some() && self.accelerometer.is_none() {
            s.push_str(
                "# accelerometer: not identified: the band fitted to the pulses' shape scatters \
                 between groups beyond\n# 1 % in frequency or 20 % in damping. Keep the \
                 datasheet's value.\n",
            );
        } else if self.accelerometer_asked && self.accelerometer.is_none() {
            s.push_str(
                "# accelerometer: not identified: no resonance rings after the pulses \
                 consistently (none, one above the\n# Nyquist frequency, or one damped so \
                 heavily that it rings for a sample or two, as a MEMS part's\n# band at zeta \
                 0.7 does at 26.7 kS/s). Keep the datasheet's value.\n",
            );
        }
        if let Some(a) = &self.accelerometer {
            let from = match a.source {
                ResonanceSource::Ring => "rings",
                ResonanceSource::Pulses if self.pulse_law == Some(LawSpec::Hertz) => {
                    "Hertz pulses fitted"
                }
                ResonanceSource::Pulses => "pulses fitted with the law's shape",
            };
            s.push_str(&format!(
                "accelerometer = {{ frequency_hz = {}, damping_ratio = {} }}  # +- {:.3} Hz, \
                 +- {:.4} ({} {from})\n",
                fmt_value(a.frequency_hz.value, a.frequency_hz.std_error),
                fmt_value(a.damping_ratio.value, a.damping_ratio.std_error),
                a.frequency_hz.std_error,
                a.damping_ratio.std_error,
                a.pulses
            ));
        }
        for m in &self.modes {
            s.push_str("\n[[sensor.beam_modes]]\n");
            for (name, e) in [
                ("frequency_hz", m.frequency_hz),
                ("damping_ratio", m.damping_ratio),
                ("gain", m.gain),
            ] {
                s.push_str(&format!(
                    "{name} = {}  # +- {:.2e}\n",
                    fmt_value(e.value, e.std_error),
                    e.std_error
                ));
            }
        }
        s
    }
}
