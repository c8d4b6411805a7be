//! Scene build: presets, separability against an independent Monte Carlo, bad input.

use coalshock::{Material, Scene};

/// A class for the Monte Carlo: material, radius range (m), speed range (m/s).
type McClass = (Material, (f64, f64), (f64, f64));

/// Independent f64 Monte Carlo of the noiseless Bayes error of two classes with log-uniform R
/// and uniform u: draws (R, u) from each class, computes (F_max, t_c) with the textbook
/// formulas, and checks whether the other class's prior density there is larger.
fn bayes_error_mc(classes: &[McClass], plate: Material, n: usize) -> f64 {
    let e_star = |m: &Material| {
        let c = |m: &Material| (1.0 - (m.poisson as f64).powi(2)) / m.modulus_pa as f64;
        1.0 / (c(m) + c(&plate))
    };
    // Returns density in (ln F, ln t) of class j at an observation.
    let density = |j: usize, lf: f64, lt: f64| -> f64 {
        let (m, (r0, r1), (u0, u1)) = &classes[j];
        let e = e_star(m);
        let rho = m.density_kg_m3 as f64;
        let cf =
            (4.0 / 3.0 * e.powf(0.4) * (5.0 * std::f64::consts::PI * rho / 4.0).powf(0.6)).ln();
        let ct =
            (2.943_275_184_324_7 * (5.0 * std::f64::consts::PI * rho / (4.0 * e)).powf(0.4)).ln();
        let (a, b) = (lf - cf, lt - ct);
        let y = (a - 2.0 * b) / 1.6;
        let x = b + 0.2 * y;
        let (r, u) = (x.exp(), y.exp());
        if r < *r0 || r > *r1 || u < *u0 || u > *u1 {
            return 0.0;
        }
        // p(ln R) = 1/ln(r1/r0); p(ln u) = u / (u1 - u0); Jacobian 1.6.
        (1.0 / (r1 / r0).ln()) * (u / (u1 - u0)) / 1.6
    };
    let mut rng = 0x9E37_79B9_7F4A_7C15u64;
    let mut uniform = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut wrong = 0usize;
    for (i, (m, (r0, r1), (u0, u1))) in classes.iter().enumerate() {
        let e = e_star(m);
        let rho = m.density_kg_m3 as f64;
        for _ in 0..n {
            let r = r0 * (r1 / r0).powf(uniform());
            let u = u0 + (u1 - u0) * uniform();
            let mass = rho * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
            let k = 4.0 / 3.0 * e * r.sqrt();
            let d = (5.0 * mass * u * u / (4.0 * k)).powf(0.4);
            let (lf, lt) = ((k * d.powf(1.5)).ln(), (2.943_275_184_324_7 * d / u).ln());
            let own = density(i, lf, lt);
            if (0..classes.len()).any(|j| j != i && density(j, lf, lt) > own) {
                wrong += 1;
            }
        }
    }
    wrong as f64 / (n * classes.len()) as f64
}

#[test]
fn paper_scene_bayes_error_matches_monte_carlo() {
    let scene = Scene::paper().unwrap();
    let s = scene.separability();
    let mc = bayes_error_mc(
        &[
            (Material::COAL, (0.015, 0.04), (1.0, 5.0)),
            (Material::SANDSTONE, (0.015, 0.04), (1.0, 5.0)),
        ],
        Material::CARBON_STEEL,
        200_000,
    );
    println!(
        "paper: kernel bayes {:.4} overlap {:.4}; monte carlo {:.4}",
        s.bayes_error, s.overlap_share, mc
    );
    assert!((s.bayes_error as f64 - mc).abs() < 3e-3);
    // physics notes: about 24 % of impacts are ambiguous even without noise.
    assert!((0.22..0.26).contains(&mc), "{mc}");
}

#[test]
fn narrow_scene_separates() {
    let s = Scene::paper_narrow().unwrap().separability();
    println!("narrow: {s:?}");
    assert_eq!(s.bayes_error, 0.0);
    assert_eq!(s.overlap_share, 0.0);
}

/// A class's yield pressure must be finite and positive (a typed error naming it); a yielding
/// class bends its envelope and lengthens the scene's longest pulse (Thornton's contact
/// lasts longer), and the same classes without it build the Hertz scene exactly.
#[test]
#[cfg(feature = "plasticity")]
fn yield_pressure_is_checked_and_bends_the_envelope() {
    use coalshock::{Error, ParticleClass, Range, SensorChain, Settings, Speed};
    let radius = Range::new(0.015, 0.04);
    let speed = Speed::Uniform(Range::new(1.0, 5.0));
    let build = |p_coal: Option<f32>| {
        let mut coal = ParticleClass::new("coal", Material::COAL, radius, speed);
        coal.yield_pressure_pa = p_coal;
        let gangue = ParticleClass::new("gangue", Material::SANDSTONE, radius, speed);
        Scene::<4>::new(
            Material::CARBON_STEEL,
            &[coal, gangue],
            SensorChain::from_plate(100_000.0, 50.0, 30.0, 4.0, 16),
            Settings::default(),
        )
    };
    for bad in [0.0, -3e7, f32::NAN, f32::INFINITY] {
        let err = build(Some(bad)).err();
        assert!(
            matches!(
                err,
                Some(
                    Error::NonPositive("yield_pressure_pa") | Error::NonFinite("yield_pressure_pa")
                )
            ),
            "{bad}: {err:?}"
        );
    }
    let elastic = build(None).unwrap();
    assert_eq!(elastic, Scene::paper().unwrap());
    let yielding = build(Some(30e6)).unwrap();
    assert!(yielding.envelopes()[0].ratio_map.is_some());
    assert!(yielding.envelopes()[1].ratio_map.is_none());
    assert!(yielding.duration_bounds_s().1 > 1.3 * elastic.duration_bounds_s().1);
}

/// The shortest Hertz contact time (s) of the paper scene (coal and sandstone on steel, R 0.015
/// m, 5 m/s), from the textbook closed form in f64.
fn paper_shortest_hertz_s() -> f64 {
    let c = |m: &Material| (1.0 - (m.poisson as f64).powi(2)) / m.modulus_pa as f64;
    [Material::COAL, Material::SANDSTONE]
        .iter()
        .map(|mat| {
            let e = 1.0 / (c(mat) + c(&Material::CARBON_STEEL));
            let (r, u) = (0.015f64, 5.0f64);
            let m = mat.density_kg_m3 as f64 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
            let d = (5.0 * m * u * u / (4.0 * e * 4.0 / 3.0 * r.sqrt())).powf(0.4);
            2.943_275_184_324_7 * d / u
        })
        .fold(f64::INFINITY, f64::min)
}

/// The paper scene at `rate_hz` with a damped contact whose measured duration is 0.6 of
/// Hertz's, with or without a phase table.
fn damped_paper_at(rate_hz: f64, phase_table: bool) -> Result<Scene, coalshock::Error> {
    let paper = Scene::paper().unwrap();
    let mut settings = *paper.settings();
    settings.contact.duration_ratio = 0.6;
    #[cfg(feature = "sampled_phase")]
    if phase_table {
        let mut t = coalshock::SampledPhase::NONE;
        t.asymmetry[0] = [-0.5, 0.5];
        settings.sampled_phase = t;
    }
    #[cfg(not(feature = "sampled_phase"))]
    let _ = phase_table;
    let mut sensor = *paper.sensor();
    sensor.sample_rate_hz = rate_hz as f32;
    let classes: Vec<_> = paper.classes().to_vec();
    Scene::new(*paper.plate(), &classes, sensor, settings)
}

/// A damped pulse the detector measures at 0.6 of the Hertz time: at 3 Hertz samples it has
/// 1.8, below the 2.5 where the correction by samples per pulse starts, and is refused; with
/// a phase table (from 1.6 samples) it is accepted; at 1.55 measured samples (2.6 Hertz samples) neither is.
#[test]
fn a_rate_is_refused_where_the_measured_pulse_is_shorter_than_the_correction_reaches() {
    let t = paper_shortest_hertz_s();
    let at_measured = |n: f64| n / (0.6 * t);
    let refused = |r: Result<Scene, coalshock::Error>| match r {
        Err(coalshock::Error::OutOfRange(what)) => what.contains("shortest measured pulse"),
        _ => false,
    };
    assert!(refused(damped_paper_at(at_measured(1.8), false)));
    assert!(damped_paper_at(at_measured(2.6), false).is_ok());
    if cfg!(feature = "sampled_phase") {
        assert!(damped_paper_at(at_measured(1.8), true).is_ok());
        assert!(refused(damped_paper_at(at_measured(1.55), true)));
    }
}
