//! One seed gives one result whatever the number of threads: `evaluate`, `stream` generation
//! and `caving` run on a pool of 1 thread and of 2 threads must agree bit for bit (every field
//! but the measured kernel time).

mod common;

use coalshock::math::DefaultBackend;
use common::shipped_scene;
use host_sim::caving::{CavingOptions, run as run_caving};
use host_sim::evaluate::{EvalOptions, evaluate};
use host_sim::generate::generate;
use host_sim::scene::SceneFile;
use host_sim::stream::{PulseModel, StreamOptions};

/// Runs `f` on a pool of `threads` threads.
fn on_pool<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}

/// The evaluation as JSON without the two wall-time fields.
fn evaluation_json(scene: &SceneFile, threads: usize) -> serde_json::Value {
    let opts = EvalOptions {
        n_per_class: 60,
        seed: 7,
        impacts_per_stream: 15,
        bayes_draws_per_class: 500,
        ..EvalOptions::default()
    };
    let e = on_pool(threads, || evaluate::<DefaultBackend>(scene, &opts)).expect("evaluates");
    let mut v = serde_json::to_value(&e).expect("json");
    let o = v.as_object_mut().expect("an object");
    for timed in ["kernel_seconds", "kernel_ns_per_sample"] {
        assert!(o.remove(timed).is_some(), "{timed} is a field");
    }
    v
}

#[test]
fn evaluate_is_the_same_on_one_and_two_threads() {
    // The rigid chain and one with beam modes and an accelerometer.
    for name in ["paper.toml", "piezo_chain.toml"] {
        let scene = shipped_scene(name);
        let one = evaluation_json(&scene, 1);
        let two = evaluation_json(&scene, 2);
        assert_eq!(one, two, "{name}");
        assert_eq!(one["confusion"].as_array().map(Vec::len), Some(2));
    }
}

#[test]
fn stream_is_the_same_on_one_and_two_threads() {
    let scene = shipped_scene("paper_adams.toml");
    let opts = StreamOptions {
        pulse_model: PulseModel::Integrator,
        pileup_share: 0.2,
        ..StreamOptions::default()
    };
    let one = on_pool(1, || generate(&scene, 40, 3, &opts)).expect("a stream");
    let two = on_pool(2, || generate(&scene, 40, 3, &opts)).expect("a stream");
    assert_eq!(one.truth.len(), 40);
    assert_eq!(one, two);
}

#[test]
fn caving_is_the_same_on_one_and_two_threads() {
    let opts = CavingOptions {
        rounds: 4,
        pre_impacts: 30,
        post_impacts: 30,
        rate_hz: 400.0,
        false_alarm_impacts: 5_000,
        ..CavingOptions::default()
    };
    let scene = SceneFile::paper();
    let one = on_pool(1, || run_caving::<DefaultBackend>(&scene, &opts)).expect("runs");
    let two = on_pool(2, || run_caving::<DefaultBackend>(&scene, &opts)).expect("runs");
    assert_eq!(one.pulses, two.pulses);
    assert_eq!(one, two);
}
