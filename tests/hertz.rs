//! The Hertz closed forms against the paper's printed tables and an independent f64
//! evaluation of the textbook formulas.

mod common;

use coalshock::hertz::{self, CONTACT_TIME_FACTOR};
use coalshock::material::{Material, effective_modulus_pa};

/// Relative tolerance of the f32 closed forms against f64 for the compiled backend
/// (measured over the paper ranges: libm <= 4.5e-7, micromath <= 3.5e-3; README "Math
/// backends").
const TOL: f64 = if cfg!(feature = "micromath") {
    5e-3
} else {
    2e-6
};

/// Half a unit in the fifth printed digit, relative, for a value printed as `d.dddd x 10^n`.
fn five_digits(printed: f64) -> f64 {
    let mantissa = printed / 10f64.powi(printed.log10().floor() as i32);
    0.5e-4 / mantissa
}

#[test]
fn table_2_and_3_stiffness_to_five_printed_digits() {
    // Paper Table 3 (k in N/m^1.5 against R), Table 2 repeats R = 0.030.
    let radii = [0.015f32, 0.020, 0.025, 0.030, 0.035, 0.040];
    let sandstone = [2.1091e9, 2.4353e9, 2.7228e9, 2.9827e9, 3.2217e9, 3.4441e9];
    let coal = [9.3941e8, 1.0847e9, 1.2128e9, 1.3285e9, 1.4350e9, 1.5340e9];
    for (mat, table) in [(Material::SANDSTONE, sandstone), (Material::COAL, coal)] {
        let e = effective_modulus_pa(&mat, &Material::CARBON_STEEL).unwrap();
        for (&r, &k_paper) in radii.iter().zip(table.iter()) {
            let k = hertz::stiffness(e, r).unwrap() as f64;
            let rel = (k - k_paper).abs() / k_paper;
            // The micromath sqrt is a few percent off: the table check is for libm only.
            if cfg!(not(feature = "micromath")) {
                assert!(
                    rel <= five_digits(k_paper),
                    "R {r}: k {k} vs paper {k_paper} ({rel:.1e})"
                );
            }
        }
    }
}

/// The textbook closed forms in f64, written out independently of the kernel's log-linear
/// form: `m = 4/3 pi rho R^3`, `k = 4/3 E* sqrt R`, `delta = (5 m u^2 / (4k))^(2/5)`,
/// `F = k delta^1.5`, `t_c = 2 tau delta / u`, `J = 2 m u`.
fn textbook(a: &Material, b: &Material, r: f64, u: f64) -> [f64; 4] {
    let c = |m: &Material| (1.0 - (m.poisson as f64).powi(2)) / m.modulus_pa as f64;
    let e = 1.0 / (c(a) + c(b));
    let m = a.density_kg_m3 as f64 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let k = 4.0 / 3.0 * e * r.sqrt();
    let d = (5.0 * m * u * u / (4.0 * k)).powf(0.4);
    [d, k * d.powf(1.5), 2.0 * tau() * d / u, 2.0 * m * u]
}

/// `tau = integral_0^1 (1 - x^(5/2))^(-1/2) dx` by Gauss-Legendre-free quadrature: the
/// substitution `x = 1 - s^2` removes the endpoint singularity,
/// `tau = integral_0^1 2 s / sqrt(1 - (1 - s^2)^(5/2)) ds`, then composite Simpson (the new
/// integrand tends to `2 / sqrt(5/2)` at `s = 0`).
fn tau() -> f64 {
    let f = |s: f64| {
        if s == 0.0 {
            2.0 / 2.5f64.sqrt()
        } else {
            2.0 * s / (1.0 - (1.0 - s * s).powf(2.5)).sqrt()
        }
    };
    common::simpson(f, 20_000)
}

#[test]
fn contact_time_constant_matches_quadrature() {
    let t = 2.0 * tau();
    assert!((t - 2.943_275_184_324_7).abs() < 1e-9, "{t}");
    assert!((CONTACT_TIME_FACTOR as f64 - t).abs() / t < 1e-7);
}

#[test]
fn paper_scene_values() {
    // physics notes: coal, R = 0.03 m, u = 1 m/s: m = 0.1561 kg, delta_max = 1.166e-4 m,
    // F_max ~= 1673 N, t_c ~= 343 us.
    let e = effective_modulus_pa(&Material::COAL, &Material::CARBON_STEEL).unwrap();
    let i = hertz::impact(e, 1380.0, 0.03, 1.0).unwrap();
    let m = hertz::sphere_mass_kg(1380.0, 0.03).unwrap();
    assert!((m - 0.1561).abs() < 5e-5 * 2.0, "{m}");
    assert!(
        (i.delta_max_m - 1.166e-4).abs() < 0.05e-6 * 2.0 + TOL as f32 * 1.2e-4,
        "{}",
        i.delta_max_m
    );
    assert!(
        (i.peak_force_n / 1673.0 - 1.0).abs() < 1e-3 + TOL as f32,
        "{}",
        i.peak_force_n
    );
    assert!(
        (i.duration_s / 343e-6 - 1.0).abs() < 2e-3 + TOL as f32,
        "{}",
        i.duration_s
    );
}

#[test]
fn closed_forms_match_f64_textbook_over_paper_ranges() {
    let mut worst = [0.0f64; 4];
    for mat in [
        Material::COAL,
        Material::SANDSTONE,
        Material::ROOF_SANDSTONE,
    ] {
        let e = effective_modulus_pa(&mat, &Material::CARBON_STEEL).unwrap();
        for i in 0..=20 {
            let r = 0.015 * (0.04f64 / 0.015).powf(i as f64 / 20.0);
            for j in 0..=20 {
                let u = 1.0 + 4.0 * j as f64 / 20.0;
                let got = hertz::impact(e, mat.density_kg_m3, r as f32, u as f32).unwrap();
                let want = textbook(&mat, &Material::CARBON_STEEL, r, u);
                let got = [
                    got.delta_max_m,
                    got.peak_force_n,
                    got.duration_s,
                    got.impulse_n_s,
                ];
                for k in 0..4 {
                    worst[k] = worst[k].max((got[k] as f64 - want[k]).abs() / want[k]);
                }
            }
        }
    }
    println!(
        "worst relative error (delta, F, t_c, J): {:.2e} {:.2e} {:.2e} {:.2e}",
        worst[0], worst[1], worst[2], worst[3]
    );
    assert!(worst.iter().all(|&w| w < TOL), "{worst:?}");
}
