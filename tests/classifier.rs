//! Classification of analytic (exact Hertz) pulses: inside one envelope, in the overlap,
//! outside every envelope; and the inversion round trip over the whole scene.

use coalshock::material::effective_modulus_pa;
use coalshock::{Material, Measurement, Scene, Side, Verdict, hertz};

const COAL: u8 = 0;
const GANGUE: u8 = 1;

/// A noiseless measurement of the exact Hertz impact (f64 textbook formulas, not the kernel's).
fn exact(mat: Material, r: f64, u: f64) -> Measurement {
    let c = |m: &Material| (1.0 - (m.poisson as f64).powi(2)) / m.modulus_pa as f64;
    let e = 1.0 / (c(&mat) + c(&Material::CARBON_STEEL));
    let m = mat.density_kg_m3 as f64 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let k = 4.0 / 3.0 * e * r.sqrt();
    let d = (5.0 * m * u * u / (4.0 * k)).powf(0.4);
    Measurement {
        peak_force_n: (k * d.powf(1.5)) as f32,
        duration_s: (2.943_275_184_324_7 * d / u) as f32,
        sigma_ln_force: 0.0,
        sigma_ln_duration: 0.0,
        cov_ln: 0.0,
        asymmetry: 0.0,
        trigger_margin: f32::INFINITY,
        #[cfg(feature = "pulse_shape")]
        shape_fitted: false,
    }
}

#[test]
fn inversion_round_trip_over_the_scene() {
    let scene = Scene::paper().unwrap();
    let tol = if cfg!(feature = "micromath") {
        2e-2
    } else {
        2e-5
    };
    for (ci, mat) in [(COAL, Material::COAL), (GANGUE, Material::SANDSTONE)] {
        let e = effective_modulus_pa(&mat, &Material::CARBON_STEEL).unwrap();
        for i in 0..=16 {
            let r = 0.015 * (0.04f32 / 0.015).powf(i as f32 / 16.0);
            for j in 0..=16 {
                let u = 1.0 + 4.0 * j as f32 / 16.0;
                let imp = hertz::impact(e, mat.density_kg_m3, r, u).unwrap();
                let m = Measurement {
                    peak_force_n: imp.peak_force_n,
                    duration_s: imp.duration_s,
                    sigma_ln_force: 0.0,
                    sigma_ln_duration: 0.0,
                    cov_ln: 0.0,
                    asymmetry: 0.0,
                    trigger_margin: f32::INFINITY,
                    #[cfg(feature = "pulse_shape")]
                    shape_fitted: false,
                };
                let inv = scene.invert(ci, &m).unwrap();
                assert!(
                    (inv.radius_m / r - 1.0).abs() < tol,
                    "R {r} -> {}",
                    inv.radius_m
                );
                assert!(
                    (inv.speed_m_s / u - 1.0).abs() < tol,
                    "u {u} -> {}",
                    inv.speed_m_s
                );
            }
        }
    }
}

#[test]
fn narrow_scene_classifies_every_exact_pulse() {
    let scene = Scene::paper_narrow().unwrap();
    for (want, mat) in [(COAL, Material::COAL), (GANGUE, Material::SANDSTONE)] {
        for i in 0..=10 {
            let r = 0.015 * (0.04f64 / 0.015).powf(i as f64 / 10.0);
            for j in 0..=10 {
                let u = 2.5 + j as f64 / 10.0;
                match scene.classify(&exact(mat, r, u)) {
                    Verdict::Class { class, posterior } => {
                        assert_eq!(class, want, "R {r} u {u}");
                        assert!(posterior >= 0.9);
                    }
                    v => panic!("R {r} u {u}: {v:?}"),
                }
            }
        }
    }
}

#[test]
fn paper_scene_overlap_is_ambiguous_and_ends_are_confident() {
    let scene = Scene::paper().unwrap();
    // Gangue at (R, u) looks like coal at about (1.02 R, 1.70 u) (physics notes): gangue at
    // 2 m/s and coal at 3.4 m/s, mid radius, are in the overlap.
    for (mat, r, u) in [
        (Material::SANDSTONE, 0.025, 2.0),
        (Material::COAL, 0.0255, 3.4),
    ] {
        match scene.classify(&exact(mat, r, u)) {
            Verdict::Ambiguous { posterior, .. } => assert!(posterior < 0.9),
            v => panic!("{v:?}"),
        }
    }
    // Slow coal has no gangue look-alike (gangue would need u < 1); fast gangue has no coal
    // look-alike (coal would need u > 5).
    assert!(matches!(
        scene.classify(&exact(Material::COAL, 0.03, 1.2)),
        Verdict::Class { class: COAL, .. }
    ));
    assert!(matches!(
        scene.classify(&exact(Material::SANDSTONE, 0.03, 4.5)),
        Verdict::Class { class: GANGUE, .. }
    ));
}

#[test]
fn outside_every_envelope_says_which_way() {
    let scene = Scene::paper().unwrap();
    // A coal lump of twice the largest radius: nearest is coal or gangue, radius above.
    let big = exact(Material::COAL, 0.08, 1.2);
    match scene.classify(&big) {
        Verdict::OutOfEnvelope { radius, .. } => assert_eq!(radius, Side::Above),
        v => panic!("{v:?}"),
    }
    // Coal at 0.2 m/s: speed below every class's range.
    match scene.classify(&exact(Material::COAL, 0.03, 0.2)) {
        Verdict::OutOfEnvelope { nearest, speed, .. } => {
            assert_eq!(nearest, COAL);
            assert_eq!(speed, Side::Below);
        }
        v => panic!("{v:?}"),
    }
    // Very fast sandstone, 30 m/s.
    match scene.classify(&exact(Material::SANDSTONE, 0.03, 30.0)) {
        Verdict::OutOfEnvelope { nearest, speed, .. } => {
            assert_eq!(nearest, GANGUE);
            assert_eq!(speed, Side::Above);
        }
        v => panic!("{v:?}"),
    }
}

#[test]
fn outside_every_envelope_on_a_damped_contact_corrects_once() {
    // A damped contact's calibration (peak 0.5, duration 1.5 of Hertz's): the classifier
    // divides the measured pulse by it once. Coal of R 0.08 m (twice the largest) at 3.5 m/s,
    // measured through that calibration, needs a radius above every class's range and a
    // speed inside both (gangue looks like coal at about 1.02 R, 1.70 u: 2.1 m/s). Corrected
    // twice, ln u would move by (-ln 0.5 + 2 ln 1.5) / 1.6 = 0.94 (F ~ R^2 u^1.2,
    // t_c ~ R u^-0.2), to 9.0 m/s as coal or 5.3 m/s as gangue: above either range.
    let paper = Scene::paper().unwrap();
    let mut settings = *paper.settings();
    settings.contact.force_ratio = 0.5;
    settings.contact.duration_ratio = 1.5;
    let classes: Vec<_> = paper.classes().to_vec();
    let scene: Scene = Scene::new(*paper.plate(), &classes, *paper.sensor(), settings).unwrap();
    let mut m = exact(Material::COAL, 0.08, 3.5);
    m.peak_force_n *= 0.5;
    m.duration_s *= 1.5;
    match scene.classify(&m) {
        Verdict::OutOfEnvelope { radius, speed, .. } => {
            assert_eq!(radius, Side::Above);
            assert_eq!(speed, Side::Inside);
        }
        v => panic!("{v:?}"),
    }
}

#[test]
fn bad_measurements_are_rejected_not_panicking() {
    let scene = Scene::paper().unwrap();
    for (f, t) in [
        (f32::NAN, 1e-4),
        (1e3, f32::INFINITY),
        (-1.0, 1e-4),
        (1e3, 0.0),
        (0.0, 0.0),
    ] {
        let m = Measurement {
            peak_force_n: f,
            duration_s: t,
            sigma_ln_force: f32::NAN,
            sigma_ln_duration: -1.0,
            cov_ln: f32::NAN,
            asymmetry: 0.0,
            trigger_margin: f32::INFINITY,
            #[cfg(feature = "pulse_shape")]
            shape_fitted: false,
        };
        assert_eq!(
            scene.classify(&m),
            Verdict::Rejected(coalshock::RejectReason::Implausible)
        );
    }
}

/// A pulse measured less than `TRIGGER_MARGIN` standard deviations above its trigger gets no
/// `Class` verdict, whatever its posterior: the same exact gangue impact is `Class` at the
/// margin and `Ambiguous`, with the same best class and posterior, just below it (and for a
/// margin that is not a number).
#[test]
fn a_pulse_near_its_trigger_is_ambiguous() {
    let scene = Scene::paper().unwrap();
    let clear = Measurement {
        sigma_ln_force: 0.01,
        sigma_ln_duration: 0.01,
        cov_ln: -1e-4,
        trigger_margin: coalshock::TRIGGER_MARGIN,
        #[cfg(feature = "pulse_shape")]
        shape_fitted: false,
        ..exact(Material::SANDSTONE, 0.03, 4.5)
    };
    let Verdict::Class { class, posterior } = scene.classify(&clear) else {
        panic!("{:?}", scene.classify(&clear));
    };
    assert_eq!(class, GANGUE);
    for margin in [coalshock::TRIGGER_MARGIN - 1e-3, 0.0, -5.0, f32::NAN] {
        let near = Measurement {
            trigger_margin: margin,
            #[cfg(feature = "pulse_shape")]
            shape_fitted: false,
            ..clear
        };
        assert_eq!(
            scene.classify(&near),
            Verdict::Ambiguous {
                best: class,
                posterior
            },
            "margin {margin}"
        );
    }
}
