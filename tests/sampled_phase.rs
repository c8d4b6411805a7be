//! `SampledPhase`'s lookup: a table filled from a plane `p(ln n, a) = c0 + c1 ln n + c2 a`
//! (every row with its own asymmetry range) reads the plane back exactly between its points
//! (bilinear interpolation is exact on a plane), holds it at the ends of a row's range and
//! below the first row, and reads nothing beyond the last row; the scene check refuses
//! values out of range; the neighbour asymmetry is `(after - before) / max`.

use coalshock::sampled_phase::{
    PHASE_COLUMNS, PHASE_FIRST_N, PHASE_ROWS, PHASE_STEP, SampledPhase, neighbour_asymmetry,
};

fn plane(ln_n: f32, a: f32) -> f32 {
    0.05 - 0.02 * ln_n + 0.1 * a
}

fn table() -> SampledPhase {
    let mut t = SampledPhase::NONE;
    for k in 0..PHASE_ROWS {
        let ln_n = (PHASE_FIRST_N * PHASE_STEP.powi(k as i32)).ln();
        let (lo, hi) = (-0.5 + 0.03 * k as f32, 0.4 - 0.02 * k as f32);
        t.asymmetry[k] = [lo, hi];
        for j in 0..PHASE_COLUMNS {
            let a = lo + (hi - lo) * j as f32 / (PHASE_COLUMNS - 1) as f32;
            t.ln_force[k][j] = plane(ln_n, a);
            t.ln_duration[k][j] = -plane(ln_n, a);
            t.sigma_ln_force[k][j] = 0.01;
            t.sigma_ln_duration[k][j] = 0.02;
        }
    }
    t
}

#[test]
fn lookup_is_exact_on_a_plane_and_held_at_the_ends() {
    let t = table();
    // Between rows 2 and 3 (n 2.5 .. 3.125), a inside both rows' ranges: the plane, to f32
    // rounding, as the row ranges differ and each row interpolates on its own axis.
    for (n, a) in [(2.8f32, 0.1f32), (2.6, -0.3), (5.0, 0.0), (11.0, 0.2)] {
        let (lf, lt, sf, st) = t.at(n.ln(), a).expect("inside the table");
        assert!((lf - plane(n.ln(), a)).abs() < 1e-5, "{n} {a} {lf}");
        assert!((lt + plane(n.ln(), a)).abs() < 1e-5);
        assert!((sf - 0.01).abs() < 1e-7 && (st - 0.02).abs() < 1e-7);
    }
    // Below the first row: held at row 0; beyond a row's asymmetry range: held at its end.
    let first = PHASE_FIRST_N.ln();
    let (lf, ..) = t.at((1.2f32).ln(), 0.0).unwrap();
    assert!((lf - plane(first, 0.0)).abs() < 1e-5);
    let (lf, ..) = t.at(first, 0.9).unwrap();
    assert!((lf - plane(first, 0.4)).abs() < 1e-5);
    // Beyond the last row (11.9 samples) and for the empty table: nothing.
    assert!(t.at((12.5f32).ln(), 0.0).is_none());
    assert!(t.at(f32::NAN, 0.0).is_none());
    assert!(SampledPhase::NONE.at((3.0f32).ln(), 0.0).is_none());
}

#[test]
fn check_refuses_out_of_range_tables() {
    assert!(table().check().is_ok());
    let mut t = table();
    t.sigma_ln_force[3][4] = -0.1;
    assert!(t.check().is_err());
    let mut t = table();
    t.ln_duration[0][0] = f32::NAN;
    assert!(t.check().is_err());
    let mut t = table();
    t.asymmetry[5] = [0.3, -0.3];
    assert!(t.check().is_err());
}

#[test]
fn neighbour_asymmetry_is_the_normalised_difference() {
    assert_eq!(neighbour_asymmetry(2.0, 10.0, 7.0), 0.5);
    assert_eq!(neighbour_asymmetry(7.0, 10.0, 2.0), -0.5);
    assert_eq!(neighbour_asymmetry(1.0, 0.0, 3.0), 0.0);
    assert_eq!(neighbour_asymmetry(-50.0, 1.0, 50.0), 1.0);
}
