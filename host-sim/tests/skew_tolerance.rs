//! The skew tolerance host-sim computes for a damped scene (`host_sim::skew_tolerance`),
//! checked against the kernel's detector rather than against its own formula:
//!
//! - Flores and Gonthier at e = 0.3 (the most skewed pulses of the restitution laws) on the
//!   paper's scene with 4 counts of noise, at rates where the shortest pulse has 1.7-3.2
//!   samples and the largest ones are the few samples the skewness check starts from: streams
//!   of true single impacts through the kernel's detector have at most a small multiple of
//!   `FALSE_REJECTION_SHARE` rejected as misshapen (2-7 % before the tolerance covered every
//!   size, speed and phase, at 27-31 kS/s);
//! - the tolerance falls smoothly as the rate rises (it jumped 0.57 -> 0.25 -> 0.05 -> 0.87
//!   between 22.2, 25, 30 and 33 kS/s when it was read off the nine calibration impacts).

use coalshock::{Detection, Detector, RejectReason};
use host_sim::kernel_scene::{calibrated_settings, scene_to_kernel};
use host_sim::law_spec::LawSpec;
use host_sim::scene::{self, SceneFile};
use host_sim::sim::generate::generate;
use host_sim::sim::stream::StreamOptions;
use host_sim::skew_tolerance::FALSE_REJECTION_SHARE;

/// The paper's scene with the contact `law`, at `rate_hz` with 4 counts of noise.
fn damped_paper(law: LawSpec, rate_hz: f64) -> SceneFile {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/paper.toml");
    let mut s = scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    s.contact = law;
    s.sensor.sample_rate_hz = rate_hz;
    s.sensor.noise_rms_counts = 4.0;
    s
}

/// Share of `n` true single impacts of `file` (no pile-ups, seed `seed`) that the kernel's
/// detector rejects as misshapen.
fn misshapen_share(file: &SceneFile, n: usize, seed: u64) -> f64 {
    let scene = scene_to_kernel(file).unwrap();
    let stream = generate(file, n, seed, &StreamOptions::default()).unwrap();
    let mut d = Detector::new(&scene);
    let misshapen = stream
        .samples
        .iter()
        .filter_map(|&s| d.feed(s as i32))
        .filter(|x| {
            matches!(
                x,
                Detection::Pulse {
                    outcome: Err(RejectReason::Misshapen),
                    ..
                }
            )
        })
        .count();
    misshapen as f64 / stream.truth.len() as f64
}

#[test]
fn the_skewness_check_rejects_few_true_single_impacts_of_a_damped_scene() {
    let laws = [
        LawSpec::Flores { restitution: 0.3 },
        LawSpec::Gonthier { restitution: 0.3 },
    ];
    let n = 2000;
    for (i, law) in laws.into_iter().enumerate() {
        for (k, rate_hz) in [25_000.0, 30_000.0, 40_000.0].into_iter().enumerate() {
            let file = damped_paper(law, rate_hz);
            let share = misshapen_share(&file, n, 10 * i as u64 + k as u64 + 1);
            let tolerance = calibrated_settings(&file).unwrap().skew_tolerance;
            println!("{law:?} {rate_hz} Hz: skew_tolerance {tolerance:.3}, misshapen {share:.4}");
            // At most 4 of 2000 against an expected share of at most 1e-3 (2 of 2000): the
            // binomial's chance of 5 or more is 5 %, of 8 or more 0.1 %.
            assert!(
                share <= 4.0 * FALSE_REJECTION_SHARE,
                "{law:?} {rate_hz}: {share}"
            );
        }
    }
}

#[test]
fn the_skew_tolerance_falls_smoothly_with_the_rate() {
    let law = LawSpec::Flores { restitution: 0.3 };
    let rates: Vec<f64> = (0..10).map(|k| 22_000.0 + 2_000.0 * k as f64).collect();
    let tolerances: Vec<f64> = rates
        .iter()
        .map(|&r| {
            f64::from(
                calibrated_settings(&damped_paper(law, r))
                    .unwrap()
                    .skew_tolerance,
            )
        })
        .collect();
    println!("{:?}", rates.iter().zip(&tolerances).collect::<Vec<_>>());
    // Needed at the slowest rate (most skewed samples), none at the fastest.
    assert!(tolerances[0] > 0.5, "{tolerances:?}");
    for w in tolerances.windows(2) {
        // Never up by more than the quantile's resolution, never down by more than a sixth.
        assert!(w[1] <= w[0] + 0.01, "{tolerances:?}");
        assert!(w[0] - w[1] <= w[0] / 6.0 + 0.01, "{tolerances:?}");
    }
}
