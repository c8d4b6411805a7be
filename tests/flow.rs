//! The flow monitor inside `Monitor`: every pulse of a stream of sampled Hertz impacts is
//! followed by one `Flow` event, one `feed` per sample and `feed_slice` agree, a monitor
//! without flow gives the events it always gave, and `classify_with_likelihoods` returns
//! `classify`'s verdict.

mod common;

use coalshock::flow::FlowConfig;
use coalshock::{Event, Measurement, Monitor, Scene};

/// A stream of `n` paper-scene impacts (classes alternating, every third gangue), 400 quiet
/// samples apart, at 100 kS/s with 50/30 N per count and 4 counts of noise.
fn stream(n: usize, seed: u64) -> Vec<i32> {
    let mut rng = common::Rng::new(seed);
    let (coal, sand, steel) = (
        coalshock::Material::COAL,
        coalshock::Material::SANDSTONE,
        coalshock::Material::CARBON_STEEL,
    );
    let mut samples = vec![0i32; 64];
    for i in 0..n {
        let r = 0.015 * (0.04f64 / 0.015).powf(rng.uniform());
        let u = 1.0 + 4.0 * rng.uniform();
        let m = if i % 3 == 0 { &sand } else { &coal };
        let (f, tc) = common::hertz64(m, &steel, r, u);
        let p = common::Pulse {
            start: samples.len() as f64 + rng.uniform(),
            len: tc * 1e5,
            amp: f * 30.0 / 50.0,
            class: 0,
        };
        let base = samples.len();
        for k in base..p.end() + 400 {
            samples.push((p.at(k) + 4.0 * rng.normal()).round() as i32);
        }
    }
    samples
}

#[test]
fn every_pulse_is_followed_by_one_flow_event_and_both_feeds_agree() {
    let scene: Scene = Scene::paper().expect("paper scene");
    let samples = stream(200, 7);
    let config = FlowConfig {
        window_impacts: 40,
        ..FlowConfig::new(0.05, 0.5, 1e-5)
    };
    let mut sliced = Monitor::new(scene.clone()).with_flow(config).expect("flow");
    let mut a = Vec::new();
    sliced.feed_slice(&samples, |e| a.push(e));
    let mut single = Monitor::new(scene.clone()).with_flow(config).expect("flow");
    let mut b = Vec::new();
    for &s in &samples {
        b.extend(single.feed(s));
        b.extend(single.take_flow_event());
    }
    assert_eq!(a, b);
    let pulses = a.iter().filter(|e| matches!(e, Event::Pulse(_))).count();
    assert!(pulses >= 190, "{pulses} pulses");
    for w in a.windows(2) {
        if let [Event::Pulse(_), next] = w {
            assert!(matches!(next, Event::Flow(_)), "{next:?}");
        }
    }
    let Some(Event::Flow(last)) = a.last() else {
        panic!("no flow event last");
    };
    assert_eq!(last.pulses + last.left_out, pulses as u32);
    // A third of the lumps are gangue: far above the 5 % background, the alarm is up.
    assert!(last.alarm, "{last:?}");
    assert!(last.share > 0.15 && last.share < 0.6, "{last:?}");
    // Without the flow monitor: the same pulse events, and nothing else.
    let mut plain = Monitor::new(scene);
    let mut c = Vec::new();
    plain.feed_slice(&samples, |e| c.push(e));
    let pulses_only: Vec<_> = a
        .into_iter()
        .filter(|e| !matches!(e, Event::Flow(_)))
        .collect();
    assert_eq!(c, pulses_only);
    assert_eq!(plain.take_flow_event(), None);
}

#[test]
fn classify_with_likelihoods_gives_classify_s_verdict() {
    let scene: Scene = Scene::paper().expect("paper scene");
    let mut rng = common::Rng::new(3);
    for _ in 0..2000 {
        let m = Measurement {
            peak_force_n: (rng.uniform() * 12.0).exp() as f32,
            duration_s: (-12.0 + 6.0 * rng.uniform()).exp() as f32,
            sigma_ln_force: 0.1 * rng.uniform() as f32,
            sigma_ln_duration: 0.1 * rng.uniform() as f32,
            cov_ln: 0.0,
            asymmetry: 0.0,
            trigger_margin: f32::INFINITY,
            #[cfg(feature = "pulse_shape")]
            shape_fitted: false,
        };
        let (v, lls) = scene.classify_with_likelihoods(&m);
        assert_eq!(v, scene.classify(&m));
        assert!(lls.is_some());
    }
    let bad = Measurement {
        peak_force_n: f32::NAN,
        duration_s: 1e-4,
        sigma_ln_force: 0.0,
        sigma_ln_duration: 0.0,
        cov_ln: 0.0,
        asymmetry: 0.0,
        trigger_margin: f32::INFINITY,
        #[cfg(feature = "pulse_shape")]
        shape_fitted: false,
    };
    assert_eq!(scene.classify_with_likelihoods(&bad).1, None);
}
