//! After an impact that clips the ADC, or a gap, behind a chain that rings: the kernel
//! re-estimates its equaliser's state (`coalshock::settle`) and hears the impacts that follow.
//! The streams come from host-sim's exact chain (the beam's modes and the accelerometer
//! integrated on a fine grid), not from the kernel's model of it; the truth is where each
//! impact was placed.

mod common;

use coalshock::{Event, Monitor};
use host_sim::kernel_scene::scene_to_kernel;
use host_sim::scene::SceneFile;
use host_sim::sensor::{ForcePulse, ForceTrack, PulseShape, Sensor};

/// An impact that clips (its peak in counts of the rigid plate, far above the 16-bit full
/// scale) at 5 ms, then clean impacts of 3000 counts, 0.2 ms long.
const CLIPPED_AT_S: f64 = 0.005;
const CLIPPED_PEAK_COUNTS: f64 = 120_000.0;
const CLEAN_PEAK_COUNTS: f64 = 3_000.0;
const CLEAN_DURATION_S: f64 = 200e-6;

fn pulse(start_s: f64, duration_s: f64, peak_counts: f64, sensor: &Sensor) -> ForcePulse {
    ForcePulse {
        start_s,
        duration_s,
        scale: 1.0,
        shape: PulseShape::HertzSine {
            peak_force_n: peak_counts / sensor.counts_per_newton(),
        },
    }
}

/// What the kernel made of a stream: the peak index of every reported pulse, and the
/// monitor's counters of re-estimation.
struct Heard {
    reported: Vec<u64>,
    settled: u32,
    settle_samples: u64,
    pulses: u32,
}

/// Feeds `raw` in blocks of 256 (a gap of `gap.1` samples reported before index `gap.0`, its
/// samples not fed), and collects every pulse's index.
fn hear(scene: &SceneFile, raw: &[i16], gap: Option<(usize, usize)>) -> Heard {
    let mut monitor = Monitor::new(scene_to_kernel(scene).expect("kernel scene"));
    let mut reported = Vec::new();
    let mut on = |e: Event| {
        if let Event::Pulse(r) = e {
            reported.push(r.at_sample);
        }
    };
    let (before, after) = match gap {
        Some((at, lost)) => (&raw[..at], &raw[at + lost..]),
        None => (raw, &raw[raw.len()..]),
    };
    for block in before.chunks(256) {
        monitor.feed_slice(block, &mut on);
    }
    if let Some((_, lost)) = gap {
        if let Some(e) = monitor.gap(lost as u32) {
            on(e);
        }
        for block in after.chunks(256) {
            monitor.feed_slice(block, &mut on);
        }
    }
    if let Some(e) = monitor.finish() {
        on(e);
    }
    let c = monitor.counters();
    assert!(c.balanced(), "{c:?}");
    Heard {
        reported,
        settled: c.settled,
        settle_samples: c.settle_samples,
        pulses: c.pulses,
    }
}

/// The clean impacts (start times, s) that no report within 8 samples of their peak heard.
fn missed(heard: &Heard, starts: &[f64], fs: f64) -> Vec<f64> {
    starts
        .iter()
        .copied()
        .filter(|&t| {
            let peak = ((t + 0.5 * CLEAN_DURATION_S) * fs).round() as i64;
            !heard.reported.iter().any(|&r| (r as i64 - peak).abs() <= 8)
        })
        .collect()
}

/// The stream of `scene`'s sensor: the clipped impact (when `clip`), then clean impacts at
/// `starts`, 40 ms in all, with the scene's noise (seed 7).
fn stream(scene: &SceneFile, clip: bool, starts: &[f64]) -> (Vec<i16>, f64) {
    let sensor = Sensor::new(&scene.sensor).expect("sensor");
    let fs = sensor.sample_rate_hz();
    let mut pulses: Vec<ForcePulse> = starts
        .iter()
        .map(|&t| pulse(t, CLEAN_DURATION_S, CLEAN_PEAK_COUNTS, &sensor))
        .collect();
    if clip {
        pulses.push(pulse(CLIPPED_AT_S, 300e-6, CLIPPED_PEAK_COUNTS, &sensor));
    }
    let track = ForceTrack::new(pulses);
    let n = (0.040 * fs) as usize;
    (sensor.sample(&track, n, 0.0, 7), fs)
}

/// Clean impacts 2, 4, 7, 11, 16, 22 and 29 ms after the one that clips: each is heard,
/// behind the tail beam's three modes and a 35 kHz piezo at 100 kS/s, and behind the same
/// beam and the 6.3 kHz MEMS band at 26.7 kS/s. Before the re-estimation the equaliser rang
/// with thousands of counts for tens of milliseconds after the clipped impact and the
/// detector, waiting it out, missed most of them.
#[test]
fn impacts_after_one_that_clips_are_heard() {
    let after_ms = [2.0, 4.0, 7.0, 11.0, 16.0, 22.0, 29.0];
    let starts: Vec<f64> = after_ms.iter().map(|ms| CLIPPED_AT_S + ms * 1e-3).collect();
    for name in ["piezo_chain.toml", "mems_chain.toml"] {
        let scene = common::shipped_scene(name);
        let (raw, fs) = stream(&scene, true, &starts);
        let full = raw.iter().filter(|&&s| s == i16::MAX).count();
        assert!(
            full >= 3,
            "{name}: the impact must clip ({full} samples at full scale)"
        );
        let heard = hear(&scene, &raw, None);
        let lost = missed(&heard, &starts, fs);
        println!(
            "{name}: {} of {} clean impacts heard after the clipped one; {} re-estimation(s), \
             {} samples ({:.2} ms) spent; {} pulses reported",
            starts.len() - lost.len(),
            starts.len(),
            heard.settled,
            heard.settle_samples,
            heard.settle_samples as f64 / fs * 1e3,
            heard.pulses
        );
        assert!(lost.is_empty(), "{name}: missed the impacts at {lost:?} s");
        assert!(heard.settled >= 1, "{name}: no re-estimation");
        // The clipped impact, the clean ones, nothing spurious.
        assert_eq!(heard.pulses as usize, starts.len() + 1, "{name}");
    }
}

/// A gap of 40 samples while the beam rings from an impact of 25 000 counts (none clips):
/// the equaliser restarts from rest, is re-estimated, and the impacts 3 to 25 ms after the
/// gap are heard.
#[test]
fn impacts_after_a_gap_in_the_ringing_are_heard() {
    let scene = common::shipped_scene("piezo_chain.toml");
    let sensor = Sensor::new(&scene.sensor).expect("sensor");
    let fs = sensor.sample_rate_hz();
    let gap_at_s = 0.0080;
    let after_ms = [3.0, 6.0, 10.0, 15.0, 25.0];
    let starts: Vec<f64> = after_ms.iter().map(|ms| gap_at_s + ms * 1e-3).collect();
    let mut pulses: Vec<ForcePulse> = starts
        .iter()
        .map(|&t| pulse(t, CLEAN_DURATION_S, CLEAN_PEAK_COUNTS, &sensor))
        .collect();
    pulses.push(pulse(0.005, 300e-6, 25_000.0, &sensor));
    let n = (0.040 * fs) as usize;
    let raw = sensor.sample(&ForceTrack::new(pulses), n, 0.0, 11);
    assert!(raw.iter().all(|&s| s < i16::MAX), "nothing clips here");
    let gap = ((gap_at_s * fs) as usize, 40);
    let heard = hear(&scene, &raw, Some(gap));
    let lost = missed(&heard, &starts, fs);
    println!(
        "gap: {} of {} impacts heard after it; {} re-estimation(s), {} samples spent",
        starts.len() - lost.len(),
        starts.len(),
        heard.settled,
        heard.settle_samples
    );
    assert!(lost.is_empty(), "missed the impacts at {lost:?} s");
    assert!(heard.settled >= 1);
}
