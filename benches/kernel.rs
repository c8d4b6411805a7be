//! Host benchmarks of the kernel: ns per quiet sample (one `feed` call each, and through
//! `feed_slice` in blocks of 256, rigid and behind a chain of three beam modes and an
//! accelerometer), per classified pulse, per scene build. Quiet figures are for 10 000
//! samples.
//! Run with `cargo bench --bench kernel` and `cargo bench --bench kernel --features micromath`.

use coalshock::hertz::impact;
use coalshock::material::effective_modulus_pa;
use coalshock::{
    Accelerometer, BeamMode, ChainDynamics, Material, Measurement, Monitor, Scene, SensorChain,
};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

/// A quiet stream: baseline 0 with a deterministic +-4 count pattern.
fn quiet(n: usize) -> Vec<i32> {
    (0..n).map(|i| ((i * 7919) % 9) as i32 - 4).collect()
}

/// One 15-sample Hertz pulse of 2000 counts (sin^1.5 shape) followed by 200 quiet samples.
fn pulse_block() -> Vec<i32> {
    let mut v: Vec<i32> = (0..15)
        .map(|i| {
            (2000.0
                * (std::f64::consts::PI * (i as f64 + 0.5) / 15.0)
                    .sin()
                    .powf(1.5)) as i32
        })
        .collect();
    v.extend(quiet(200));
    v
}

fn bench(c: &mut Criterion) {
    let backend = coalshock::math::BACKEND;
    let scene: Scene = Scene::paper().expect("paper scene");
    let q = quiet(10_000);
    c.bench_function(&format!("{backend}/quiet sample"), |b| {
        let mut m = Monitor::new(scene.clone());
        for &s in &q {
            m.feed(s);
        }
        b.iter(|| {
            for &s in &q {
                black_box(m.feed(black_box(s)));
            }
        })
    });
    c.bench_function(
        &format!("{backend}/quiet sample, feed_slice blocks of 256"),
        |b| {
            let mut m = Monitor::new(scene.clone());
            for &s in &q {
                m.feed(s);
            }
            b.iter(|| {
                for chunk in q.chunks(256) {
                    m.feed_slice(black_box(chunk), |e| {
                        black_box(e);
                    });
                }
            })
        },
    );
    // scenes/piezo_chain.toml's chain on the paper scene's classes.
    let mode = |frequency_hz, damping_ratio, gain| BeamMode {
        frequency_hz,
        damping_ratio,
        gain,
    };
    let dynamics = ChainDynamics::RIGID
        .with_mode(mode(180.0, 0.02, 0.1))
        .and_then(|d| d.with_mode(mode(650.0, 0.01, 0.05)))
        .and_then(|d| d.with_mode(mode(2100.0, 0.02, 0.1)))
        .expect("three modes")
        .with_accelerometer(Accelerometer {
            frequency_hz: 35_000.0,
            damping_ratio: 0.02,
        });
    let sensor = SensorChain::from_plate(100_000.0, 50.0, 30.0, 4.0, 16)
        .with_dynamics(dynamics)
        .expect("chain");
    let chain_scene: Scene =
        Scene::new(*scene.plate(), scene.classes(), sensor, *scene.settings()).expect("chain");
    c.bench_function(
        &format!("{backend}/quiet sample behind a chain, feed_slice blocks of 256"),
        |b| {
            let mut m = Monitor::new(chain_scene.clone());
            for chunk in q.chunks(256) {
                m.feed_slice(chunk, |_| {});
            }
            b.iter(|| {
                for chunk in q.chunks(256) {
                    m.feed_slice(black_box(chunk), |e| {
                        black_box(e);
                    });
                }
            })
        },
    );
    let block = pulse_block();
    let mut warm = Monitor::new(scene.clone());
    for &s in &q {
        warm.feed(s);
    }
    c.bench_function(&format!("{backend}/pulse (15 samples) + 200 quiet"), |b| {
        let mut m = warm.clone();
        b.iter(|| {
            for &s in &block {
                black_box(m.feed(black_box(s)));
            }
        })
    });
    // Coal of R = 25 mm at 3 m/s: inside both envelopes (the overlap), the costly case.
    let e = effective_modulus_pa(&Material::COAL, &Material::CARBON_STEEL).expect("materials");
    let hit = impact(e, Material::COAL.density_kg_m3, 0.025, 3.0).expect("impact");
    let meas = Measurement {
        peak_force_n: hit.peak_force_n,
        duration_s: hit.duration_s,
        sigma_ln_force: 0.002,
        sigma_ln_duration: 0.005,
        cov_ln: -4e-6,
        asymmetry: 0.0,
        trigger_margin: f32::INFINITY,
        #[cfg(feature = "pulse_shape")]
        shape_fitted: false,
    };
    c.bench_function(&format!("{backend}/classify one measurement"), |b| {
        b.iter(|| black_box(scene.classify(black_box(&meas))))
    });
    c.bench_function(&format!("{backend}/build paper scene"), |b| {
        b.iter(|| black_box(Scene::paper()))
    });
    #[cfg(feature = "pulse_shape")]
    short_pulse(c, backend);
}

/// A short damped pulse's fit by its contact's shape (`coalshock::short_pulse`), which the
/// detector adds to a pulse below 7.8 samples: the Hertz table at 3 samples per contact time
/// with one count of noise, its peak 0.3 samples after the largest sample.
#[cfg(feature = "pulse_shape")]
fn short_pulse(c: &mut Criterion, backend: &str) {
    use coalshock::pulse_shape::PulseShape;
    use coalshock::short_pulse::short_shape_fit;
    let shape = PulseShape::hertz();
    let noise = [0.6, -1.1, 0.3, 0.9, -0.4];
    let mut ys = [0.0f32; 5];
    for (j, y) in ys.iter_mut().enumerate() {
        let k = j as f32 - 2.0;
        *y = 1000.0 * shape.at((k - 0.3) / 3.0 + 0.5).0 + noise[j];
    }
    c.bench_function(
        &format!("{backend}/short pulse by its shape (3 samples)"),
        |b| b.iter(|| black_box(short_shape_fit(black_box(&ys), 1.0, &shape, 3.0))),
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
