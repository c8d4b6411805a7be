//! What the colour of the equalised noise behind a chain does to the detector's stated noise.
//!
//! The ADC's noise is white; behind a chain the kernel's equaliser filters it, so that the
//! samples the detector fits are correlated. One sample's RMS is `sensor noise x
//! EqualiserDesign::noise_gain`; the fits' own gains (`PeakFit::gain2`) take the samples as
//! independent, and the detector corrects them by the noise's colour
//! (`coalshock::noise_colour`). For each scene given, this example
//!
//! - feeds 2e6 samples of white noise of RMS 1 (after 4e5 of warm-up) through the scene's
//!   equaliser, as the monitor feeds raw counts, and prints the equalised RMS beside
//!   `noise_gain`, the autocorrelation at lags 1-4, and the variance of the sum of `n`
//!   consecutive samples over `n` times one sample's (1 for white noise);
//! - fits a sampled Hertz pulse (peak 50 equalised RMS, 8-20 samples per pulse, random phase,
//!   20 000 trials) with the kernel's five-sample and three-sample peak fits
//!   (`coalshock::shape_fit::peak_fit`) under white noise of the equalised RMS and under
//!   segments of the equalised noise, and prints the variance of `ln F_max` about the noiseless
//!   fit's over the stated `gain2 sigma^2 / F_max^2` (white noise's gain, `st`) and over the
//!   gain the detector states behind the chain (`NoiseColour::weighted`, `stc`); the last
//!   lines put the kernel's correlations and sums (`EqualiserDesign::noise_colour`) beside the
//!   measured ones.
//!
//! `cargo run --release -p host-sim --example noise_colour -- scenes/piezo_chain.toml
//! scenes/mems_chain.toml scenes/tail_beam.toml`

use coalshock::Equaliser;
use coalshock::equaliser::EqualiserDesign;
use coalshock::math::Libm;
use coalshock::noise_colour::NoiseColour;
use coalshock::shape_fit::{PEAK_OMEGA, five_about, peak_fit, peak_shape};
use host_sim::bridge::kernel_scene::scene_to_kernel;
use host_sim::calibrate::mean_and_sigma;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Warm-up samples of the equaliser, and the samples measured after them.
const WARM: usize = 400_000;
const LEN: usize = 2_000_000;
/// Pulses fitted per case.
const TRIALS: usize = 20_000;
/// White noise of RMS 1 is fed as counts of 1/1024 (the equaliser takes integer counts).
const SCALE: f64 = 1024.0;
/// Samples of no force either side of a pulse.
const PAD: usize = 3;

fn main() -> anyhow::Result<()> {
    println!(
        "{:<12} {:>3} {:>5} {:>9} {:>7} {:>7} {:>7} {:>9}",
        "scene", "n", "fit", "stated", "w/st", "col/st", "col/w", "col/stc"
    );
    let mut colours = Vec::new();
    for path in std::env::args().skip(1) {
        let file = host_sim::scene::load(&path)?;
        let scene = scene_to_kernel(&file)?;
        let name = std::path::Path::new(&path)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let noise = equalised_noise(scene.equaliser());
        colours.push(format!("{name:<12} {}", noise.describe(scene.equaliser())));
        let colour = scene.equaliser().noise_colour();
        for n in [8.0, 12.0, 16.0, 20.0] {
            for five in [true, false] {
                let [stated, white, coloured, stated_coloured] =
                    peak_variances(&noise, colour, n, five);
                println!(
                    "{name:<12} {n:>3} {:>5} {stated:>9.3e} {:>7.3} {:>7.3} {:>7.3} {:>9.3}",
                    if five { "five" } else { "three" },
                    white / stated,
                    coloured / stated,
                    coloured / white,
                    coloured / stated_coloured
                );
            }
        }
    }
    println!();
    for line in colours {
        println!("{line}");
    }
    Ok(())
}

/// The equalised noise (mean removed) of white noise of RMS 1, and its RMS.
struct Noise {
    samples: Vec<f64>,
    rms: f64,
}

/// White noise of RMS 1 through a fresh equaliser of `design`, after [`WARM`] samples.
fn equalised_noise(design: &EqualiserDesign) -> Noise {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let raw: Vec<i32> = (0..WARM + LEN)
        .map(|_| {
            let g: f64 = StandardNormal.sample(&mut rng);
            (g * SCALE).round() as i32
        })
        .collect();
    let mut out = vec![0.0f32; raw.len()];
    Equaliser::new(design).process(&raw, &mut out);
    let e: Vec<f64> = out[WARM..].iter().map(|&v| f64::from(v) / SCALE).collect();
    let mean = e.iter().sum::<f64>() / e.len() as f64;
    let samples: Vec<f64> = e.iter().map(|v| v - mean).collect();
    let rms = (samples.iter().map(|v| v * v).sum::<f64>() / samples.len() as f64).sqrt();
    Noise { samples, rms }
}

impl Noise {
    /// Normalised autocorrelation at `lag`.
    fn rho(&self, lag: usize) -> f64 {
        let e = &self.samples;
        let c = e.iter().zip(&e[lag..]).map(|(a, b)| a * b).sum::<f64>();
        c / (e.len() - lag) as f64 / (self.rms * self.rms)
    }

    /// Variance of the sum of `n` consecutive samples over `n` times one sample's.
    fn sum_factor(&self, n: usize) -> f64 {
        let sums: Vec<f64> = self
            .samples
            .chunks_exact(n)
            .map(|c| c.iter().sum())
            .collect();
        let var = sums.iter().map(|s| s * s).sum::<f64>() / sums.len() as f64;
        var / (n as f64 * self.rms * self.rms)
    }

    /// RMS against `noise_gain`, the autocorrelation at lags 1-4 and the sum's factor.
    fn describe(&self, design: &EqualiserDesign) -> String {
        format!(
            "rms {:.4} noise_gain {:.4}  rho 1-4 {:+.3} {:+.3} {:+.3} {:+.3} (stated {:+.3} {:+.3} {:+.3} {:+.3})  sum of 16: {:.3}, of 64: {:.3} (stated {:.3}, {:.3})",
            self.rms,
            design.noise_gain(),
            self.rho(1),
            self.rho(2),
            self.rho(3),
            self.rho(4),
            design.noise_colour().rho(1),
            design.noise_colour().rho(2),
            design.noise_colour().rho(3),
            design.noise_colour().rho(4),
            self.sum_factor(16),
            self.sum_factor(64),
            design.noise_colour().sum_variance(16.0) / 16.0,
            design.noise_colour().sum_variance(64.0) / 64.0
        )
    }
}

/// `[stated, white, coloured, stated coloured]` variances of `ln F_max` of a Hertz pulse of `n`
/// samples fitted through five samples or three (`five`), about the noiseless fit's at the
/// same phase; the last as the detector states it behind the chain (`NoiseColour::weighted`).
fn peak_variances(noise: &Noise, colour: &NoiseColour, n: f64, five: bool) -> [f64; 4] {
    let mut rng = ChaCha8Rng::seed_from_u64(11 + n as u64);
    let len = n.ceil() as usize + 1 + 2 * PAD;
    let peak = 50.0 * noise.rms;
    let (mut white, mut coloured, mut stated) = (Vec::new(), Vec::new(), 0.0);
    let mut stated_coloured = 0.0;
    for _ in 0..TRIALS {
        let phase: f64 = rng.random();
        let clean: Vec<f64> = (0..len)
            .map(|k| {
                let t = k as f64 - PAD as f64 + phase;
                let x = PEAK_OMEGA as f64 * (t - 0.5 * n) / n;
                if t > 0.0 && t < n {
                    peak * f64::from(peak_shape(x as f32).0.max(0.0))
                } else {
                    0.0
                }
            })
            .collect();
        let (lo, hi) = (PAD, PAD + n.ceil() as usize);
        let with = |add: &dyn Fn(usize) -> f64| -> Vec<f64> {
            clean.iter().enumerate().map(|(k, c)| c + add(k)).collect()
        };
        let w: Vec<f64> = (0..len)
            .map(|_| noise.rms * Distribution::<f64>::sample(&StandardNormal, &mut rng))
            .collect();
        let off = rng.random_range(0..noise.samples.len() - len);
        let fits = [
            fit(&clean, colour, lo, hi, five),
            fit(&with(&|k| w[k]), colour, lo, hi, five),
            fit(&with(&|k| noise.samples[off + k]), colour, lo, hi, five),
        ];
        if let [Some((p0, _, _)), Some((pw, g2, _)), Some((pc, _, g2c))] = fits {
            white.push((pw / p0).ln());
            coloured.push((pc / p0).ln());
            stated += g2 * noise.rms * noise.rms / (pw * pw);
            stated_coloured += g2c * noise.rms * noise.rms / (pc * pc);
        }
    }
    [
        stated / white.len() as f64,
        variance(&white),
        variance(&coloured),
        stated_coloured / coloured.len() as f64,
    ]
}

/// The kernel's peak fit of the pulse in `y[lo..hi]`: its peak, `gain2`, and `gain2` in the
/// noise of `colour`.
fn fit(
    y: &[f64],
    colour: &NoiseColour,
    lo: usize,
    hi: usize,
    five: bool,
) -> Option<(f64, f64, f64)> {
    let y: Vec<f32> = y.iter().map(|&v| v as f32).collect();
    let i = (lo..hi).max_by(|&a, &b| y[a].total_cmp(&y[b]))?;
    let sum: f32 = y[lo..hi].iter().sum();
    let f = peak_fit::<Libm>(five_about(&y, i), sum, (hi - lo) as f32, five)?;
    let (top, per_sample) = f.weights();
    let (coloured, _) = colour.weighted(&top, per_sample, (hi - lo) as f32);
    Some((f64::from(f.peak), f64::from(f.gain2), f64::from(coloured)))
}

/// Variance of `d` about its mean (`host_sim::calibrate::mean_and_sigma`).
fn variance(d: &[f64]) -> f64 {
    let (_, sigma) = mean_and_sigma(d);
    sigma * sigma
}
