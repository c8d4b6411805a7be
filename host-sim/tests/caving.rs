//! Caving rounds: the CUSUM threshold `h = ln(1 / alpha)` holds the false-alarm rate, checked
//! by simulation with an f64 likelihood ratio of the scene's exact densities (no kernel code);
//! bad options are refused naming their field; the JSON carries every field of the contract.

use coalshock::math::DefaultBackend;
use host_sim::caving::{CavingOptions, Profile, run};
use host_sim::cusum::{Cusum, MixtureModel, increment};
use host_sim::evaluate::class_models;
use host_sim::scene::SceneFile;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn paper_mixture() -> MixtureModel {
    let scene = SceneFile::paper();
    MixtureModel {
        models: class_models(&scene),
        gangue: vec![false, true],
    }
}

/// `(increment, gangue)` of one impact of the exact paper mixture with gangue share `pi`.
fn draw(m: &MixtureModel, pi: f64, pi0: f64, pi1: f64, rng: &mut ChaCha8Rng) -> f64 {
    let c = usize::from(rng.random::<f64>() < pi);
    let (x, y) = m.models[c].sample(rng.random(), rng.random());
    let (lf, lt) = m.models[c].forward(x, y);
    m.ln_ratio(lf, lt).map_or(0.0, |d| increment(pi0, pi1, d))
}

#[test]
fn threshold_from_the_false_alarm_rate_holds_it_by_simulation() {
    let m = paper_mixture();
    let (pi0, pi1) = (0.05, 0.5);
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for alpha in [1e-2, 1e-3] {
        let mut c = Cusum::for_rate(alpha);
        let n = 400_000;
        let alarms = (0..n)
            .filter(|_| c.step(draw(&m, pi0, pi0, pi1, &mut rng)))
            .count();
        let rate = alarms as f64 / n as f64;
        // ARL >= e^h = 1 / alpha: the rate is at most alpha (with room for the count's
        // Poisson spread), and the bound is not absurdly loose.
        assert!(rate <= alpha, "alpha {alpha}: measured {rate}");
        assert!(rate >= alpha / 100.0, "alpha {alpha}: measured {rate}");
    }
}

#[test]
fn delay_after_a_step_follows_lorden() {
    let m = paper_mixture();
    let (pi0, pi1) = (0.05, 0.5);
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let kl: f64 = (0..100_000)
        .map(|_| draw(&m, pi1, pi0, pi1, &mut rng))
        .sum::<f64>()
        / 1e5;
    // The independent estimate: 0.41 nats per impact.
    assert!((kl - 0.41).abs() < 0.01, "{kl}");
    let h = 1e5f64.ln();
    let mut delays = Vec::new();
    for _ in 0..400 {
        let mut c = Cusum::for_rate(1e-5);
        let d = (1..)
            .find(|_| c.step(draw(&m, pi1, pi0, pi1, &mut rng)))
            .unwrap_or(0);
        delays.push(d as f64);
    }
    let mean = delays.iter().sum::<f64>() / delays.len() as f64;
    // Lorden: about h / KL = 28 impacts (a little more for the overshoot's absence).
    assert!(
        (mean - h / kl).abs() < 0.2 * h / kl,
        "mean {mean}, h/KL {}",
        h / kl
    );
}

#[test]
fn bad_options_name_their_field() {
    let scene = SceneFile::paper();
    let base = CavingOptions::default();
    let field = |o: CavingOptions| match o.validate(&scene) {
        Err(host_sim::caving::CavingError::Option { field, .. }) => field,
        other => panic!("{other:?}"),
    };
    for a in [0.0, 1.0, -0.1, 1.5, f64::NAN] {
        let o = CavingOptions {
            false_alarm_rate: a,
            ..base.clone()
        };
        assert_eq!(field(o), "false_alarm_rate");
    }
    for level in [0.05, 0.02, 0.6, f64::NAN] {
        let o = CavingOptions {
            level,
            ..base.clone()
        };
        assert_eq!(field(o), "level");
    }
    let o = CavingOptions {
        window_impacts: 0,
        ..base.clone()
    };
    assert_eq!(field(o), "window_impacts");
    for rate_hz in [0.0, -3.0, f64::INFINITY] {
        let o = CavingOptions {
            rate_hz,
            ..base.clone()
        };
        assert_eq!(field(o), "rate_hz");
    }
    let o = CavingOptions {
        coal_class: "lignite".into(),
        ..base.clone()
    };
    assert_eq!(field(o), "coal_class");
    assert_eq!(base.validate(&scene).expect("valid"), vec![false, true]);
}

#[test]
fn json_carries_the_contract_fields() {
    let opts = CavingOptions {
        rounds: 2,
        pre_impacts: 40,
        post_impacts: 60,
        rate_hz: 400.0,
        false_alarm_impacts: 20_000,
        profile: Profile::Ramp,
        ramp_impacts: 10,
        ..CavingOptions::default()
    };
    let report = run::<DefaultBackend>(&SceneFile::paper(), &opts).expect("runs");
    assert!(report.kernel_replay_agrees);
    let v: serde_json::Value = serde_json::to_value(&report).expect("json");
    for delay in [
        "detection_delay_impacts",
        "reference_delay_impacts",
        "label_oracle_delay_impacts",
        "naive_delay_impacts",
    ] {
        for k in ["median", "p90"] {
            assert!(v[delay][k].is_number(), "{delay}.{k}: {}", v[delay]);
        }
    }
    for k in [
        "false_alarms_per_1e5_impacts",
        "recovery_rate",
        "gangue_content",
        "pre_share",
        "post_share",
        "level",
        "false_alarm_rate",
        "threshold_nats",
    ] {
        assert!(v[k].is_number(), "{k}");
    }
    for who in ["clairvoyant", "naive"] {
        assert!(v[who]["recovery_rate"].is_number(), "{who}");
        assert!(v[who]["gangue_content"].is_number(), "{who}");
    }
    assert_eq!(v["false_alarms"]["impacts"], 20_000);
    assert_eq!(v["profile"], "ramp");
    assert_eq!(v["curve"].as_array().map(Vec::len), Some(6));
    // The clairvoyant draws exactly the coal before the crossing and nothing after it.
    assert_eq!(report.clairvoyant.recovery_rate, 1.0);
}

#[test]
fn a_scene_file_may_carry_the_change() {
    let text = format!(
        "{}\n[caving]\npre_share = 0.02\npost_share = 0.3\nprofile = \"ramp\"\nramp_impacts = 50\n",
        SceneFile::paper().to_toml_string().expect("toml")
    );
    let path = std::env::temp_dir().join(format!("caving_scene_{}.toml", std::process::id()));
    std::fs::write(&path, text).expect("write");
    let (scene, spec) = host_sim::caving::load_scene(&path).expect("loads");
    std::fs::remove_file(&path).ok();
    assert_eq!(scene, SceneFile::paper());
    assert_eq!(spec.pre_share, Some(0.02));
    assert_eq!(spec.post_share, Some(0.3));
    assert_eq!(spec.profile, Some(Profile::Ramp));
    assert_eq!(spec.ramp_impacts, Some(50));
    assert_eq!(spec.level, None);
}
