//! Sensor faults injected into sampled impact streams: each is detected and counted (the
//! right `RejectReason` counter, `stuck_runs` or `gaps`), and none yields a confident
//! `Verdict::Class`.
//!
//! Streams are built here from the exact undamped Hertz pulse (integrated in `common`, f64,
//! independent of the kernel) with the textbook closed forms for `F_max` and `t_c`, sampled at the scene's rate with
//! seeded Gaussian noise, quantised and clipped to the ADC range. The scene is the paper's
//! narrow-speed scene (coal and sandstone, 2.5-3.5 m/s, 100 kS/s, 4 counts RMS), where a clean
//! pulse is classified with confidence: so a fault that still gets a `Class` would be a
//! confident answer on bad data.
//!
//! (host-sim's stream generator has fault options too; these streams are made here so that
//! each fault is placed exactly where the test needs it.)

mod common;

use coalshock::{Counters, Event, Monitor, RejectReason, Report, Scene, Verdict};
use common::{Pulse, Rng, hertz64};

// ---------------------------------------------------------------------------------------------
// Stream generation.

/// The scene the streams are made for.
fn scene() -> Scene {
    Scene::paper_narrow().unwrap()
}

/// A random impact of a random class of the scene starting at `start`.
fn impact(scene: &Scene, rng: &mut Rng, start: f64) -> Pulse {
    let class = (rng.next_u64() % scene.classes().len() as u64) as u8;
    let c = &scene.classes()[class as usize];
    let (r0, r1) = (c.radius_m.min as f64, c.radius_m.max as f64);
    let r = r0 * (r1 / r0).powf(rng.uniform());
    let coalshock::Speed::Uniform(s) = c.speed else {
        unreachable!()
    };
    let u = s.min as f64 + (s.max - s.min) as f64 * rng.uniform();
    let (f, t) = hertz64(&c.material, scene.plate(), r, u);
    let sensor = scene.sensor();
    Pulse {
        start,
        len: t * sensor.sample_rate_hz as f64,
        amp: f / sensor.force_per_count_n as f64,
        class,
    }
}

/// Samples `n` ADC counts: `offset + drift i + noise + pulses`, rounded and clipped.
struct Stream {
    samples: Vec<i32>,
}

fn stream(
    scene: &Scene,
    rng: &mut Rng,
    n: usize,
    pulses: &[Pulse],
    offset: f64,
    drift_per_sample: f64,
) -> Stream {
    let s = scene.sensor();
    let noise = s.noise_rms_counts as f64;
    let samples = (0..n)
        .map(|i| {
            let v = offset
                + drift_per_sample * i as f64
                + noise * rng.normal()
                + pulses.iter().map(|p| p.at(i)).sum::<f64>();
            v.round().clamp(s.adc_min as f64, s.adc_max as f64) as i32
        })
        .collect();
    Stream { samples }
}

/// Pulses spaced `gap` samples apart (plus their own length), starting at `first`.
fn train(scene: &Scene, rng: &mut Rng, count: usize, first: f64, gap: f64) -> Vec<Pulse> {
    let mut t = first;
    (0..count)
        .map(|_| {
            let jitter = rng.uniform();
            let p = impact(scene, rng, t + jitter);
            t = p.start + p.len + gap;
            p
        })
        .collect()
}

/// Everything the monitor reported for a stream.
struct Run {
    reports: Vec<Report>,
    stuck: Vec<u64>,
    counters: Counters<4>,
}

impl Run {
    fn classes(&self) -> usize {
        self.reports
            .iter()
            .filter(|r| matches!(r.verdict, Verdict::Class { .. }))
            .count()
    }
    fn rejected(&self, reason: RejectReason) -> usize {
        self.reports
            .iter()
            .filter(|r| r.verdict == Verdict::Rejected(reason))
            .count()
    }
    /// The report whose peak index is within `slack` samples of the pulse's window.
    fn report_for(&self, p: &Pulse, slack: usize) -> Vec<&Report> {
        let lo = (p.start as usize).saturating_sub(slack) as u64;
        let hi = (p.end() + slack) as u64;
        self.reports
            .iter()
            .filter(|r| (lo..=hi).contains(&r.at_sample))
            .collect()
    }
}

/// Feeds `samples`, with `gaps` (before sample index, lost count) and an optional finish.
fn run(scene: Scene, samples: &[i32], gaps: &[(usize, u32)], finish: bool) -> Run {
    let mut m: Monitor = Monitor::new(scene);
    let mut out = Run {
        reports: Vec::new(),
        stuck: Vec::new(),
        counters: Counters::default(),
    };
    let take = |e: Option<Event>, out: &mut Run| match e {
        Some(Event::Pulse(r)) => out.reports.push(r),
        Some(Event::Stuck { at_sample }) => out.stuck.push(at_sample),
        Some(Event::Flow(_)) | None => {}
    };
    let mut lost = 0u64;
    for (i, &s) in samples.iter().enumerate() {
        for &(at, n) in gaps {
            if at == i {
                let e = m.gap(n);
                take(e, &mut out);
                lost += n as u64;
            }
        }
        let e = m.feed(s);
        take(e, &mut out);
    }
    if finish {
        let e = m.finish();
        take(e, &mut out);
    }
    out.counters = *m.counters();
    let c = &out.counters;
    assert!(c.balanced(), "counters do not add up: {c:?}");
    assert_eq!(
        c.pulses as usize,
        out.reports.len(),
        "one pulse counted per pulse event"
    );
    assert_eq!(m.samples_fed(), samples.len() as u64 + lost, "samples fed");
    if finish {
        // finish brings the counters the detector keeps (samples, stuck runs) up to date.
        assert_eq!(
            c.samples,
            samples.len() as u64 + lost,
            "samples = fed + lost"
        );
        assert_eq!(c.stuck_runs, m.detector().stuck_runs());
        assert!(
            c.stuck_runs as usize >= out.stuck.len(),
            "a stuck run per stuck event"
        );
    }
    assert_eq!(c.gaps as usize, gaps.len());
    out
}

/// The verdicts of a run, for messages.
fn verdicts(r: &Run) -> Vec<(u64, Verdict)> {
    r.reports.iter().map(|r| (r.at_sample, r.verdict)).collect()
}

// ---------------------------------------------------------------------------------------------
// The control: without faults, pulses are found and classified with confidence.

#[test]
fn control_clean_stream_is_classified() {
    let sc = scene();
    let mut rng = Rng::new(1);
    let pulses = train(&sc, &mut rng, 40, 200.0, 300.0);
    let n = pulses.last().unwrap().end() + 300;
    let s = stream(&sc, &mut rng, n, &pulses, 100.0, 0.0);
    let r = run(sc, &s.samples, &[], true);
    assert_eq!(r.reports.len(), pulses.len(), "{:?}", verdicts(&r));
    let mut right = 0;
    for p in &pulses {
        let rep = r.report_for(p, 2);
        assert_eq!(rep.len(), 1, "pulse {p:?}: {:?}", verdicts(&r));
        if let Verdict::Class { class, .. } = rep[0].verdict {
            right += (class == p.class) as usize;
        }
    }
    println!(
        "clean: {} of {} classified with confidence, {right} right",
        r.classes(),
        pulses.len()
    );
    assert!(right >= pulses.len() * 9 / 10, "{:?}", verdicts(&r));
}

// ---------------------------------------------------------------------------------------------
// Helpers for the fault tests.

/// A pulse of the scene alone in a quiet stream: `(pulse, samples)`, the pulse starting at
/// sample 300 and 300 quiet samples after it.
fn lone_pulse(sc: &Scene, rng: &mut Rng) -> (Pulse, Vec<i32>) {
    let start = 300.0 + rng.uniform();
    let p = impact(sc, rng, start);
    let s = stream(sc, rng, p.end() + 300, &[p], 100.0, 0.0);
    (p, s.samples)
}

/// No report of the run is a confident class.
fn no_class(r: &Run, what: &str) {
    assert_eq!(
        r.classes(),
        0,
        "{what}: a fault got a confident class: {:?}",
        verdicts(r)
    );
}

/// A scene like the paper's narrow scene with changed settings.
fn scene_with(change: impl FnOnce(&mut coalshock::Settings)) -> Scene {
    let sc = scene();
    let mut settings = *sc.settings();
    change(&mut settings);
    Scene::new(*sc.plate(), sc.classes(), *sc.sensor(), settings).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Saturation and clipping.

/// Pulses scaled past the ADC's full scale: each is rejected `Saturated`, or measured from its
/// unclipped flanks, and then (its force scaled past any class's) out of the envelopes. Those
/// just past full scale (up to 1.45 times) are all measured.
#[test]
fn adc_saturation_is_measured_from_flanks_or_rejected() {
    let sc = scene();
    let full = sc.sensor().adc_max as f64;
    let mut rng = Rng::new(2);
    let mut pulses = train(&sc, &mut rng, 20, 300.0, 400.0);
    for (k, p) in pulses.iter_mut().enumerate() {
        // 1.05 to 5 times full scale.
        p.amp = full * (1.05 + 0.2 * k as f64);
    }
    let n = pulses.last().unwrap().end() + 300;
    let s = stream(&sc, &mut rng, n, &pulses, 100.0, 0.0);
    let r = run(sc, &s.samples, &[], true);
    let mut measured = 0;
    for p in &pulses {
        let rep = r.report_for(p, 2);
        assert_eq!(rep.len(), 1, "{p:?}: {:?}", verdicts(&r));
        match rep[0].verdict {
            Verdict::Rejected(RejectReason::Saturated) => {
                assert!(p.amp > 1.45 * full, "{p:?}: rejected")
            }
            Verdict::OutOfEnvelope { .. } => measured += 1,
            v => panic!("{p:?}: {v:?}"),
        }
    }
    assert_eq!(
        r.counters.rejected_for(RejectReason::Saturated) as usize + measured,
        pulses.len()
    );
    no_class(&r, "ADC saturation");
}

#[test]
fn analog_clipping_below_full_scale_is_not_classified() {
    // An amplifier that clips before the ADC does: a flat top of identical samples well below
    // the ADC's full scale, on a sensor whose noise is 4 counts RMS (so four or more identical
    // samples at the peak do not happen by chance).
    let sc = scene();
    let mut rng = Rng::new(5);
    let mut got = Vec::new();
    for k in 0..30 {
        let (p, mut s) = lone_pulse(&sc, &mut rng);
        let clip = 0.6 + 0.3 * k as f64 / 29.0;
        let top = (100.0 + clip * p.amp) as i32;
        s.iter_mut().for_each(|v| *v = (*v).min(top));
        let flat = s.iter().filter(|&&v| v == top).count();
        let r = run(scene(), &s, &[], true);
        got.push((clip, flat, verdicts(&r)));
    }
    let classed: Vec<_> = got
        .iter()
        .filter(|g| g.2.iter().any(|v| matches!(v.1, Verdict::Class { .. })))
        .collect();
    assert!(
        classed.is_empty(),
        "flat-topped (clipped) pulses classified with confidence: {classed:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// Stuck sensor.

#[test]
fn stuck_sensor_is_counted_and_never_classified() {
    let sc = scene();
    let (lo, hi) = (sc.sensor().adc_min, sc.sensor().adc_max);
    let mut rng = Rng::new(4);
    // Stuck at the baseline level, above it, at either rail: one stuck run each; a level above
    // the trigger is also a pulse that never ends (TooLong).
    // (A stuck-low run drags the baseline down; when the sensor comes back the jump is a pulse
    // that ends as TooLong too.)
    for (level, too_long) in [
        (100, false),
        (97, false),
        (3000, true),
        (hi, true),
        (lo, true),
    ] {
        let pulses = train(&sc, &mut rng, 6, 300.0, 400.0);
        let n = pulses.last().unwrap().end() + 300;
        let mut s = stream(&sc, &mut rng, n + 3000, &pulses, 100.0, 0.0).samples;
        s[n..n + 2000].iter_mut().for_each(|v| *v = level);
        let r = run(sc.clone(), &s, &[], true);
        assert_eq!(r.counters.stuck_runs, 1, "stuck at {level}: {:?}", r.stuck);
        assert!(r.stuck[0] >= n as u64 && r.stuck[0] < (n + 2000) as u64);
        assert_eq!(
            r.counters.rejected_for(RejectReason::TooLong) == 1,
            too_long,
            "stuck at {level}: {:?}",
            verdicts(&r)
        );
        // The pulses before the fault are classified; nothing from the fault is.
        let during: Vec<_> = r
            .reports
            .iter()
            .filter(|x| x.at_sample >= n as u64)
            .collect();
        assert!(
            during
                .iter()
                .all(|x| matches!(x.verdict, Verdict::Rejected(_))),
            "stuck at {level}: {during:?}"
        );
        assert_eq!(
            r.classes(),
            pulses.len(),
            "stuck at {level}: {:?}",
            verdicts(&r)
        );
    }
}

#[test]
fn stuck_run_completing_with_a_pulse_event_is_still_counted() {
    // A sensor stuck high: the pulse it starts ends as TooLong after max_samples, and the run
    // of identical samples completes after stuck_samples. Whatever stuck_samples is, a stuck
    // run of 3000 samples must be counted once, even when both complete on the same sample.
    let mut rng = Rng::new(6);
    let mut lost = Vec::new();
    for stuck in 8u16..400 {
        let sc = scene_with(|s| s.stuck_samples = stuck);
        let mut s = stream(&sc, &mut rng, 4000, &[], 100.0, 0.0).samples;
        s[500..3500].iter_mut().for_each(|v| *v = 5000);
        let r = run(sc, &s, &[], true);
        assert_eq!(r.counters.rejected_for(RejectReason::TooLong), 1);
        if r.counters.stuck_runs != 1 {
            lost.push((stuck, r.counters.stuck_runs));
        }
    }
    assert!(
        lost.is_empty(),
        "stuck runs not counted for (stuck_samples, stuck_runs): {lost:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// DC drift.

/// Runs the same pulses and noise with and without a drift of `rms_per_s` noise RMS per second.
fn drift_run(rms_per_s: f64, seed: u64) -> (Vec<Pulse>, Run, Run) {
    let sc = scene();
    let per_sample =
        rms_per_s * sc.sensor().noise_rms_counts as f64 / sc.sensor().sample_rate_hz as f64;
    let mut rng = Rng::new(seed);
    let pulses = train(&sc, &mut rng, 40, 300.0, 2500.0);
    let n = pulses.last().unwrap().end() + 300;
    let start = -(per_sample * n as f64) / 2.0;
    let flat = stream(&sc, &mut Rng::new(seed + 100), n, &pulses, 100.0, 0.0);
    let drift = stream(
        &sc,
        &mut Rng::new(seed + 100),
        n,
        &pulses,
        100.0 + start,
        per_sample,
    );
    (
        pulses,
        run(sc.clone(), &flat.samples, &[], true),
        run(sc, &drift.samples, &[], true),
    )
}

#[test]
fn slow_dc_drift_still_finds_and_classifies_every_pulse() {
    // +-100 noise RMS per second (400 counts/s, 0.4 s of stream: +-160 counts end to end): the
    // baseline lags by slope x tau = 2 RMS, inside the 6 RMS trigger margin.
    for (rate, seed) in [(100.0, 10), (-100.0, 11), (50.0, 12)] {
        let (pulses, flat, drift) = drift_run(rate, seed);
        for p in &pulses {
            let (a, b) = (flat.report_for(p, 2), drift.report_for(p, 2));
            assert_eq!(
                b.len(),
                1,
                "drift {rate}: pulse {p:?} found {} times",
                b.len()
            );
            assert_eq!(
                a[0].verdict.forced_choice(),
                b[0].verdict.forced_choice(),
                "drift {rate}: {p:?}"
            );
            assert!(
                matches!(b[0].verdict, Verdict::Class { class, .. } if class == p.class),
                "drift {rate}: {p:?} {:?}",
                b[0].verdict
            );
        }
        // Anything else the drift caused (noise crossing a lagging threshold) is no class.
        let extra: Vec<_> = drift
            .reports
            .iter()
            .filter(|x| {
                !pulses.iter().any(|p| {
                    !drift.report_for(p, 2).is_empty()
                        && drift.report_for(p, 2)[0].at_sample == x.at_sample
                })
            })
            .collect();
        assert!(
            extra
                .iter()
                .all(|x| !matches!(x.verdict, Verdict::Class { .. })),
            "drift {rate}: {extra:?}"
        );
    }
}

#[test]
fn drift_faster_than_the_baseline_gives_no_wrong_class() {
    // Beyond trigger_sigmas / baseline_tau_s = 300 RMS/s the baseline cannot follow: pulses are
    // lost in TooLong runs, but no report is a confident wrong (or phantom) class.
    for (rate, seed) in [(1000.0, 20), (-1000.0, 21), (3000.0, 22), (10_000.0, 23)] {
        let (pulses, _, drift) = drift_run(rate, seed);
        for x in &drift.reports {
            if let Verdict::Class { class, .. } = x.verdict {
                let p = pulses.iter().find(|p| {
                    drift
                        .report_for(p, 2)
                        .iter()
                        .any(|y| y.at_sample == x.at_sample)
                });
                assert!(
                    p.is_some_and(|p| p.class == class),
                    "drift {rate}: class {class} at {} for {p:?}",
                    x.at_sample
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// EMI spikes.

#[test]
fn single_sample_spikes_are_rejected_as_spikes() {
    let sc = scene();
    let full = sc.sensor().adc_max;
    let mut rng = Rng::new(8);
    let heights = [100, 200, 500, 1000, 3000, 10_000, 30_000, 40_000];
    let mut s = stream(&sc, &mut rng, 1000 * (heights.len() + 1), &[], 100.0, 0.0).samples;
    for (k, h) in heights.iter().enumerate() {
        let at = 1000 * (k + 1);
        s[at] = (s[at] + h).min(full);
    }
    let r = run(sc, &s, &[], true);
    assert_eq!(r.reports.len(), heights.len(), "{:?}", verdicts(&r));
    for (k, x) in r.reports.iter().enumerate() {
        assert_eq!(x.at_sample, 1000 * (k as u64 + 1));
        // A spike that reaches full scale is (also) a saturated sample.
        let want = if s[x.at_sample as usize] >= full {
            RejectReason::Saturated
        } else {
            RejectReason::Spike
        };
        assert_eq!(x.verdict, Verdict::Rejected(want), "spike {}", heights[k]);
    }
    let full_scale = heights.iter().filter(|&&h| h + 200 >= full).count() as u32;
    assert_eq!(
        r.counters.rejected_for(RejectReason::Spike),
        heights.len() as u32 - full_scale
    );
    assert_eq!(r.counters.rejected_for(RejectReason::Saturated), full_scale);
    no_class(&r, "spikes");
}

#[test]
fn small_spikes_are_never_classified() {
    // 25 to 100 counts (6 to 25 noise RMS): at the trigger level a neighbour can be above a
    // fifth of the spike, so not every one is a Spike; none may be a class.
    let sc = scene();
    let mut rng = Rng::new(9);
    let mut s = stream(&sc, &mut rng, 200_000, &[], 100.0, 0.0).samples;
    for k in 0..190 {
        s[1000 * (k + 1)] += 25 + (k as i32 * 3) % 76;
    }
    let r = run(sc, &s, &[], true);
    no_class(&r, "small spikes");
    assert!(r.reports.len() <= 190, "{}", r.reports.len());
    assert!(r.rejected(RejectReason::Spike) >= 150, "{:?}", verdicts(&r));
}

#[test]
fn negative_spikes_do_not_disturb_the_detector() {
    // One sample far below the baseline (an EMI spike of the other sign, -100 to -30000
    // counts) is no impact. It must not drag the baseline so far that the following noise
    // triggers pulses.
    let sc = scene();
    let mut rng = Rng::new(9);
    let mut s = stream(&sc, &mut rng, 200_000, &[], 100.0, 0.0).samples;
    let depths: Vec<i32> = (0..190).map(|k| 100 + 157 * k).collect();
    for (k, d) in depths.iter().enumerate() {
        s[1000 * (k + 1)] -= d;
    }
    let r = run(sc, &s, &[], true);
    no_class(&r, "negative spikes");
    let first: Vec<_> = r
        .reports
        .iter()
        .take(5)
        .map(|x| {
            (
                x.at_sample,
                depths[(x.at_sample as usize / 1000).clamp(1, 190) - 1],
                x.verdict,
            )
        })
        .collect();
    assert!(
        r.reports.is_empty(),
        "{} pulses reported after negative spikes; first (sample, depth of the spike before, verdict): {first:?}",
        r.reports.len()
    );
}

#[test]
fn short_bursts_are_never_classified() {
    // EMI bursts of 2 to 4 samples: far shorter than the shortest pulse the scene allows.
    let sc = scene();
    let mut rng = Rng::new(12);
    let mut s = stream(&sc, &mut rng, 30_000, &[], 100.0, 0.0).samples;
    let mut k = 0;
    for w in 2..=4 {
        for h in [50, 500, 5000, 20_000] {
            k += 1;
            (0..w).for_each(|j| s[1000 * k + j] += h);
        }
    }
    let r = run(sc, &s, &[], true);
    assert_eq!(r.reports.len(), k, "{:?}", verdicts(&r));
    no_class(&r, "bursts");
}

#[test]
fn spike_on_a_pulse_is_not_classified() {
    // A spike of half the pulse's height or more on one sample of a real pulse corrupts its
    // peak (and so the measured duration): no confident class, right or wrong.
    let sc = scene();
    let mut rng = Rng::new(13);
    let mut bad = Vec::new();
    for k in 0..40 {
        let (p, mut s) = lone_pulse(&sc, &mut rng);
        let h = 0.5 + 0.05 * (k % 10) as f64;
        let at = (p.start + (0.1 + 0.8 * rng.uniform()) * p.len) as usize;
        s[at] += (h * p.amp) as i32;
        let r = run(scene(), &s, &[], true);
        if r.classes() > 0 {
            bad.push((h, (at as f64 - p.start) / p.len, p.class, verdicts(&r)));
        }
    }
    assert!(
        bad.is_empty(),
        "{} of 40 spiked pulses classified with confidence (height, phase, truth, verdicts): {bad:?}",
        bad.len()
    );
}

// ---------------------------------------------------------------------------------------------
// Dropped samples.

#[test]
fn gap_mid_pulse_rejects_the_pulse_and_classifies_nothing_of_it() {
    // `lost` samples dropped from inside a pulse, reported with Monitor::gap: the pulse is
    // rejected as Gap, and the rest of it after the gap must not come back as a new pulse
    // with a class.
    let sc = scene();
    let mut rng = Rng::new(14);
    let mut bad = Vec::new();
    for frac in [0.2, 0.35, 0.5, 0.65, 0.8] {
        for lost in [1usize, 3, 10] {
            let (p, mut s) = lone_pulse(&sc, &mut rng);
            let at = (p.start + frac * p.len) as usize;
            s.drain(at..at + lost);
            let r = run(scene(), &s, &[(at, lost as u32)], true);
            assert_eq!(r.counters.gaps, 1);
            assert_eq!(r.counters.lost_samples, lost as u64);
            if r.rejected(RejectReason::Gap) != 1 || r.classes() > 0 {
                bad.push((frac, lost, verdicts(&r)));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "(phase, lost, verdicts) of pulses cut by a gap: {bad:?}"
    );
}

#[test]
fn gap_hiding_the_start_of_a_pulse_is_not_classified() {
    // The gap starts before the pulse and ends inside it: the detector resumes mid-pulse, with
    // no pre-trigger history. What follows is not a whole impact: one Rejected(Gap).
    let sc = scene();
    let mut rng = Rng::new(15);
    let mut bad = Vec::new();
    for k in 0..40 {
        let frac = 0.1 + 0.6 * (k % 8) as f64 / 7.0;
        let (p, mut s) = lone_pulse(&sc, &mut rng);
        let (from, to) = (p.start as usize - 10, (p.start + frac * p.len) as usize);
        s.drain(from..to);
        let r = run(scene(), &s, &[(from, (to - from) as u32)], true);
        if r.classes() > 0 || r.reports.len() != 1 || r.rejected(RejectReason::Gap) != 1 {
            bad.push((frac, verdicts(&r)));
        }
    }
    assert!(
        bad.is_empty(),
        "(phase at which the stream resumed, verdicts): {bad:?}"
    );
}

#[test]
fn gaps_between_pulses_are_only_counted() {
    let sc = scene();
    let mut rng = Rng::new(16);
    let pulses = train(&sc, &mut rng, 20, 300.0, 400.0);
    let n = pulses.last().unwrap().end() + 300;
    let full = stream(&sc, &mut rng, n, &pulses, 100.0, 0.0).samples;
    // A gap halfway between consecutive pulses, of 1 to 100 samples (never into a pulse),
    // plus one of u32::MAX samples at the end.
    let mut samples = Vec::new();
    let mut gaps = Vec::new();
    let mut next = 0;
    for (k, w) in pulses.windows(2).enumerate() {
        let mid = (w[0].end() + w[1].start as usize) / 2;
        let lost = [1usize, 7, 100][k % 3].min(w[1].start as usize - w[0].end() - 40);
        samples.extend_from_slice(&full[next..mid]);
        gaps.push((samples.len(), lost as u32));
        next = mid + lost;
    }
    samples.extend_from_slice(&full[next..]);
    gaps.push((samples.len() - 1, u32::MAX));
    let r = run(sc, &samples, &gaps, true);
    assert_eq!(r.counters.gaps as usize, gaps.len());
    assert_eq!(
        r.counters.rejected_for(RejectReason::Gap),
        0,
        "{:?}",
        verdicts(&r)
    );
    assert_eq!(r.reports.len(), pulses.len(), "{:?}", verdicts(&r));
    assert_eq!(r.classes(), pulses.len(), "{:?}", verdicts(&r));
}

// ---------------------------------------------------------------------------------------------
// Pile-up.

/// Two impacts, the second starting `offset` contact durations after the first, with
/// `ratio` times its peak.
fn pile_up(rng: &mut Rng, offset: f64, ratio: f64) -> (Pulse, Run) {
    let sc = scene();
    let jitter = rng.uniform();
    let a = impact(&sc, rng, 300.0 + jitter);
    let mut b = impact(&sc, rng, a.start + offset * a.len);
    b.amp = a.amp * ratio;
    b.len = a.len * (0.8 + 0.4 * rng.uniform());
    let s = stream(&sc, rng, b.end() + 300, &[a, b], 100.0, 0.0);
    (a, run(sc, &s.samples, &[], true))
}

#[test]
fn pile_up_with_a_valley_is_rejected_as_pile_up() {
    // The second impact starts once the first has fallen below 3/4 of its peak and more than
    // 1/4 of it: the detector's rule (a rise of more than 1/4 of the peak from a valley below
    // 3/4 of it) sees two peaks.
    let mut rng = Rng::new(17);
    for k in 0..60 {
        let offset = 0.8 + 0.2 * (k % 6) as f64 / 5.0;
        let ratio = [0.6, 1.0, 1.5, 2.0][k % 4];
        let (_, r) = pile_up(&mut rng, offset, ratio);
        assert_eq!(
            r.reports.len(),
            1,
            "offset {offset} ratio {ratio}: {:?}",
            verdicts(&r)
        );
        assert_eq!(
            r.reports[0].verdict,
            Verdict::Rejected(RejectReason::PileUp),
            "offset {offset} ratio {ratio}"
        );
    }
}

#[test]
fn pile_up_within_one_contact_duration_is_not_classified() {
    // Two impacts 0.3 to 1.0 contact durations apart, peaks 0.5 to 2 times each other. From
    // 0.65 t_c on, the sum is rejected (PileUp from its valley, or Misshapen from its energy
    // ratio or its skewness): never a class. Closer, a few sums stay within the tolerances of
    // one larger Hertz pulse (equal peaks are symmetric; a small second peak early on hardly
    // skews the sum): at most 6 of the 56 such cases here may get a class (1 does;
    // docs/robustness.md).
    let mut rng = Rng::new(18);
    let (mut far, mut near, mut near_cases) = (Vec::new(), Vec::new(), 0);
    for k in 0..120 {
        let offset = 0.3 + 0.7 * (k % 15) as f64 / 14.0;
        let ratio = [0.5, 0.75, 1.0, 1.5, 2.0][k % 5];
        let (_, r) = pile_up(&mut rng, offset, ratio);
        let case = ((offset * 100.0).round() / 100.0, ratio);
        if offset > 0.62 {
            if r.classes() > 0 {
                far.push(case);
            }
        } else {
            near_cases += 1;
            if r.classes() > 0 {
                near.push(case);
            }
        }
    }
    assert!(
        far.is_empty(),
        "pile-ups >= 0.65 t_c apart classified: {far:?}"
    );
    assert_eq!(near_cases, 56);
    eprintln!("{} of 56 close pile-ups classified: {near:?}", near.len());
    assert!(
        near.len() <= 6,
        "{} of 56 close pile-ups classified, (offset in t_c, peak ratio): {near:?}",
        near.len()
    );
}

// ---------------------------------------------------------------------------------------------
// End of stream.

#[test]
fn stream_ending_mid_pulse_is_truncated() {
    let sc = scene();
    let mut rng = Rng::new(19);
    for frac in [0.05, 0.3, 0.5, 0.7, 0.95] {
        let (p, s) = lone_pulse(&sc, &mut rng);
        let end = (p.start + frac * p.len) as usize + 1;
        let mut m: Monitor = Monitor::new(scene());
        let mut events: Vec<Event> = s[..end].iter().filter_map(|&v| m.feed(v)).collect();
        assert!(events.is_empty(), "{events:?}");
        assert!(m.detector().in_pulse() || frac < 0.1, "frac {frac}");
        if let Some(e) = m.finish() {
            events.push(e);
        }
        // A second finish has nothing more to say.
        assert_eq!(m.finish(), None);
        let c = m.counters();
        assert!(c.balanced());
        if m.detector().in_pulse() {
            panic!("still in a pulse after finish");
        }
        match events.as_slice() {
            [Event::Pulse(r)] => assert_eq!(r.verdict, Verdict::Rejected(RejectReason::Truncated)),
            [] => assert!(frac < 0.1, "frac {frac}: nothing reported"),
            e => panic!("frac {frac}: {e:?}"),
        }
        assert_eq!(
            c.rejected_for(RejectReason::Truncated) as usize,
            events.len()
        );
        assert_eq!(c.classified.iter().sum::<u32>(), 0);
    }
    // Finishing a quiet stream reports nothing.
    let mut m: Monitor = Monitor::new(scene());
    (0..100).for_each(|i| assert!(m.feed(100 + i % 3).is_none()));
    assert_eq!(m.finish(), None);
    assert_eq!(m.counters().pulses, 0);
}
