//! Checks of `host-sim impact`: a batch with a good and a bad row answers both, the bad one
//! with its message and the good one with the Hertz closed forms; a single impact from flags
//! writes its row and force-time series.

use std::path::PathBuf;

use host_sim::hertz64::{HertzImpact64, Material64};
use host_sim::impact_cli::{ECHO_COLUMNS, ImpactArgs, LawName, RESULT_COLUMNS, run, run_batch};

fn temp_dir(tag: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("host-sim-impact-cli-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// Parses answer CSV text into (header, rows) with the csv crate (cells may be quoted).
fn parse(text: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let header = r
        .headers()
        .expect("header")
        .iter()
        .map(String::from)
        .collect();
    let rows = r
        .records()
        .map(|x| x.expect("record").iter().map(String::from).collect())
        .collect();
    (header, rows)
}

fn cell<'a>(header: &[String], row: &'a [String], name: &str) -> &'a str {
    let i = header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    &row[i]
}

#[test]
fn batch_answers_good_and_bad_rows() {
    let dir = temp_dir("batch");
    let input = dir.join("in.csv");
    std::fs::write(
        &input,
        "material,radius,speed,law\n\
         coal,0.03,1.0,hertz\n\
         sandstone,-0.02,2.0,hertz\n",
    )
    .expect("write batch");
    let output = dir.join("out.csv");
    let args = ImpactArgs {
        batch: Some(input),
        output: Some(output.clone()),
        ..ImpactArgs::default()
    };
    run(&args).expect("a bad row does not fail the batch");
    let text = std::fs::read_to_string(&output).expect("answer");
    let (header, rows) = parse(&text);

    let mut expected: Vec<&str> = ECHO_COLUMNS.to_vec();
    assert_eq!(expected[11], "target_restitution");
    expected.extend(RESULT_COLUMNS);
    expected.push("warning");
    expected.push("error");
    assert_eq!(header, expected);
    assert_eq!(rows.len(), 2, "{text}");

    // Good row: undamped Hertz against the closed forms.
    let good = &rows[0];
    assert_eq!(cell(&header, good, "error"), "");
    assert_eq!(cell(&header, good, "material"), "coal");
    assert_eq!(cell(&header, good, "plate"), "carbon_steel");
    let hz = HertzImpact64::new(&Material64::COAL, &Material64::CARBON_STEEL, 0.03, 1.0)
        .expect("closed forms");
    let num = |name: &str| -> f64 {
        cell(&header, good, name)
            .parse()
            .unwrap_or_else(|_| panic!("{name} is not a number"))
    };
    assert!(rel(num("peak_force_n"), hz.peak_force_n) < 1e-7);
    assert!(rel(num("delta_max_m"), hz.delta_max_m) < 1e-7);
    assert!(rel(num("duration_s"), hz.duration_s) < 1e-7);
    assert!(rel(num("pulse_duration_s"), hz.duration_s) < 1e-7);
    assert!(rel(num("impulse_n_s"), hz.impulse_n_s) < 1e-7);
    assert!(rel(num("rebound_speed_m_s"), 1.0) < 1e-7);
    assert!(rel(num("restitution"), 1.0) < 1e-7);
    assert!(num("steps") > 0.0 && num("force_evals") > 0.0);

    // Bad row: message, no results.
    let bad = &rows[1];
    assert_eq!(cell(&header, bad, "radius"), "-0.02");
    let err = cell(&header, bad, "error");
    assert!(err.contains("radius"), "{err}");
    for c in RESULT_COLUMNS {
        assert_eq!(cell(&header, bad, c), "", "{c}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn batch_rows_take_flag_defaults_and_keep_going() {
    let input = "material,density,modulus,poisson,radius,speed,law,target_restitution,c_max,method\n\
                 ,1380,5.3e9,0.32,0.03,1,adams,0.5,,\n\
                 coal,,,,0.03,1,flores,,,\n\
                 coal,,,,0.03,1,gonthier,0.5,,rk4\n\
                 cheese,,,,0.03,1,,,,\n\
                 coal,,,,0.03,abc,,,,\n\
                 coal,,,,0.03,1,adams,,687.16,\n";
    let defaults = ImpactArgs {
        law: LawName::Hertz,
        ..ImpactArgs::default()
    };
    let mut out = Vec::new();
    let summary = run_batch(&defaults, input.as_bytes(), &mut out).expect("batch");
    assert_eq!((summary.rows, summary.failed), (6, 3));
    let (header, rows) = parse(std::str::from_utf8(&out).expect("utf8"));
    assert_eq!(rows.len(), 6);
    let err = |i: usize| cell(&header, &rows[i], "error").to_string();
    // Adams calibrated to e = 0.5 at this speed.
    assert_eq!(err(0), "");
    let e0: f64 = cell(&header, &rows[0], "restitution").parse().expect("e");
    assert!((e0 - 0.5).abs() < 1e-6, "{e0}");
    assert!(err(1).contains("needs restitution"), "{}", err(1));
    assert_eq!(err(2), "");
    assert_eq!(cell(&header, &rows[2], "method"), "rk4");
    assert!(err(3).contains("unknown material"), "{}", err(3));
    assert!(err(4).contains("not a number"), "{}", err(4));
    // Adams with the bench's c_max: F_max = 1184.18 N (BENCH_INTEGRATOR.md).
    assert_eq!(err(5), "");
    let f: f64 = cell(&header, &rows[5], "peak_force_n").parse().expect("F");
    assert!(rel(f, 1184.178956) < 1e-5, "{f}");
}

#[test]
fn unknown_batch_column_is_an_error() {
    let mut out = Vec::new();
    let r = run_batch(
        &ImpactArgs::default(),
        "material,radius_m,speed\ncoal,0.03,1\n".as_bytes(),
        &mut out,
    );
    assert!(r.is_err());
}

#[test]
fn single_impact_writes_row_and_series() {
    let dir = temp_dir("single");
    let args = ImpactArgs {
        material: Some("sandstone".into()),
        radius: Some(0.02),
        speed: Some(2.0),
        series: Some(dir.join("series.csv")),
        output: Some(dir.join("row.csv")),
        ..ImpactArgs::default()
    };
    run(&args).expect("impact");
    let (header, rows) = parse(&std::fs::read_to_string(dir.join("row.csv")).expect("row"));
    assert_eq!(rows.len(), 1);
    let hz = HertzImpact64::new(&Material64::SANDSTONE, &Material64::CARBON_STEEL, 0.02, 2.0)
        .expect("closed forms");
    let f: f64 = cell(&header, &rows[0], "peak_force_n").parse().expect("F");
    assert!(rel(f, hz.peak_force_n) < 1e-7);
    let series = std::fs::read_to_string(dir.join("series.csv")).expect("series");
    let mut lines = series.lines();
    assert_eq!(lines.next(), Some("t_s,force_n"));
    let pts: Vec<(f64, f64)> = lines
        .map(|l| {
            let (t, f) = l.split_once(',').expect("two cells");
            (t.parse().expect("t"), f.parse().expect("f"))
        })
        .collect();
    assert!(pts.len() >= 500, "{}", pts.len());
    let peak = pts.iter().map(|p| p.1).fold(0.0, f64::max);
    assert!(rel(peak, hz.peak_force_n) < 1e-3, "{peak}");

    // A failing single impact prints its row with the message and returns an error.
    let bad = ImpactArgs {
        radius: Some(-0.02),
        series: None,
        ..args
    };
    assert!(run(&bad).is_err());
    let (header, rows) = parse(&std::fs::read_to_string(dir.join("row.csv")).expect("row"));
    assert!(cell(&header, &rows[0], "error").contains("radius"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `host-sim impact args`: (exit code, stdout, stderr).
fn impact(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("impact")
        .args(args)
        .output()
        .expect("runs host-sim");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The one answer row of a single impact as (header, row).
fn single(args: &[&str]) -> (Vec<String>, Vec<String>, String) {
    let (_, out, err) = impact(args);
    let (header, mut rows) = parse(&out);
    assert_eq!(rows.len(), 1, "{out}{err}");
    (header, rows.remove(0), err)
}

#[test]
fn plate_by_properties_and_closed_form_columns() {
    let base = ["--material", "coal", "--radius", "0.03", "--speed", "2"];
    let (h, named, _) = single(&base);
    let mut props = base.to_vec();
    props.extend(["--plate-modulus", "2.06e11", "--plate-poisson", "0.28"]);
    let (h2, by_props, _) = single(&props);
    assert_eq!(cell(&h2, &by_props, "plate"), "");
    for c in RESULT_COLUMNS {
        assert_eq!(cell(&h, &named, c), cell(&h2, &by_props, c), "{c}");
    }
    // An aluminium plate (70 GPa, 0.33, no density): the closed forms written out here.
    let mut alu = base.to_vec();
    alu.extend(["--plate-modulus", "70e9", "--plate-poisson", "0.33"]);
    let (h, row, _) = single(&alu);
    assert_eq!(cell(&h, &row, "error"), "");
    let e_star = 1.0 / ((1.0 - 0.32f64.powi(2)) / 5.3e9 + (1.0 - 0.33f64.powi(2)) / 70e9);
    let k = 4.0 / 3.0 * e_star * 0.03f64.sqrt();
    let m = 4.0 / 3.0 * std::f64::consts::PI * 1380.0 * 0.03f64.powi(3);
    let d = (5.0 * m * 4.0 / (4.0 * k)).powf(0.4);
    let num = |c: &str| -> f64 { cell(&h, &row, c).parse().expect(c) };
    assert!(rel(num("hertz_stiffness_n_m1_5"), k) < 1e-14);
    assert!(rel(num("mass_kg"), m) < 1e-14);
    assert!(rel(num("hertz_delta_max_m"), d) < 1e-14);
    assert!(rel(num("hertz_peak_force_n"), k * d.powf(1.5)) < 1e-13);
    // t_c = (4/5) B(2/5, 1/2) delta_max / u, B(2/5, 1/2) = 3.6790939804058809 (mpmath).
    assert!(
        rel(
            num("hertz_duration_s"),
            0.8 * 3.679_093_980_405_881 * d / 2.0
        ) < 1e-13
    );
    // The integrator beside them agrees.
    assert!(rel(num("peak_force_n"), num("hertz_peak_force_n")) < 1e-7);
    // Without a name, both elastic constants are needed.
    let mut half = base.to_vec();
    half.extend(["--plate-modulus", "70e9"]);
    let (rc, _, err) = impact(&half);
    assert_eq!(rc, 1);
    assert!(err.contains("plate_poisson"), "{err}");
}

#[test]
fn gravity_is_an_acceleration_on_the_flag_and_in_the_batch() {
    let base = ["--material", "coal", "--radius", "0.015", "--speed", "1"];
    let (h, none, _) = single(&base);
    let mut g = base.to_vec();
    g.extend(["--gravity", "9.80665"]);
    let (_, with, _) = single(&g);
    let f = |r: &[String]| -> f64 { cell(&h, r, "peak_force_n").parse().expect("F") };
    // m g against the Hertz force raises the peak by about (5/6) m g / F_max... a little.
    let rise = f(&with) / f(&none) - 1.0;
    assert!(rise > 1e-5 && rise < 2e-3, "{rise}");
    assert_eq!(cell(&h, &with, "gravity"), "9.80665");
    // The batch column takes the same value and gives the same row.
    let mut out = Vec::new();
    let csv = "material,radius,speed,gravity\ncoal,0.015,1,9.80665\ncoal,0.015,1,true\n";
    run_batch(&ImpactArgs::default(), csv.as_bytes(), &mut out).expect("batch");
    let (hb, rows) = parse(std::str::from_utf8(&out).expect("utf8"));
    assert_eq!(
        cell(&hb, &rows[0], "peak_force_n"),
        cell(&h, &with, "peak_force_n")
    );
    let batch_err = cell(&hb, &rows[1], "error");
    let (rc, _, flag_err) = impact(&[&base[..], &["--gravity", "true"]].concat());
    assert_eq!(rc, 2);
    for e in [batch_err, flag_err.as_str()] {
        assert!(e.contains("m/s^2") && e.contains("9.80665"), "{e}");
    }
}

#[test]
fn help_shows_readable_defaults_and_the_tolerance_scale() {
    let (rc, out, _) = impact(&["--help"]);
    assert_eq!(rc, 0);
    assert!(out.contains("1e-5") && out.contains("1e-9"), "{out}");
    assert!(
        !out.contains("0.00001") && !out.contains("0.000000001"),
        "{out}"
    );
    assert!(
        out.contains("delta_max") && out.contains("approach speed u"),
        "{out}"
    );
    for m in host_sim::scene::MaterialName::ALL {
        assert!(out.contains(m.name()), "{} not in --help", m.name());
    }
}

#[test]
fn errors_and_inapplicable_inputs_in_the_users_terms() {
    let base = ["--material", "coal", "--speed", "1"];
    for (extra, needles) in [
        (
            vec!["--law", "adams", "--c-max", "100", "--depth", "-1"],
            vec!["depth = -1"],
        ),
        (
            vec!["--radius", "1e-200"],
            vec!["radius = 1e-200", "sphere mass"],
        ),
        (
            vec!["--restitution", "0.5"],
            vec!["restitution does not apply to law hertz"],
        ),
        (
            vec!["--law", "flores", "--restitution", "0.5", "--c-max", "3"],
            vec!["c_max does not apply to law flores"],
        ),
        (
            vec!["--method", "rk4", "--tol", "1e-6"],
            vec!["tol does not apply to method rk4"],
        ),
        (
            vec!["--steps-per-tc", "50"],
            vec!["steps_per_tc does not apply to method dopri5"],
        ),
        (
            vec!["--law", "adams", "--restitution", "1"],
            vec!["restitution = 1", "(0, 1)"],
        ),
    ] {
        let mut args = base.to_vec();
        if !extra.contains(&"--radius") {
            args.extend(["--radius", "0.03"]);
        }
        args.extend(extra.iter().copied());
        let (rc, out, err) = impact(&args);
        assert_eq!(rc, 1, "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: {n:?} not in {err}");
        }
        for internal in ["law.", "mass_kg", "_m =", "rtol"] {
            assert!(!err.contains(internal), "{args:?}: {internal:?} in {err}");
        }
        assert!(out.lines().count() == 2, "{out}");
    }
}

#[test]
fn impacts_far_outside_hertz_theory_are_warned_about() {
    // The paper's largest, fastest coal lump: inside both bounds.
    let (h, row, err) = single(&["--material", "coal", "--radius", "0.04", "--speed", "5"]);
    assert_eq!(cell(&h, &row, "warning"), "");
    assert!(!err.contains("warning"), "{err}");
    // u = 3e8 m/s: 705 m of penetration for a 3 cm sphere, at 1.5e5 times the wave speed.
    let (h, row, err) = single(&["--material", "coal", "--radius", "0.03", "--speed", "3e8"]);
    let w = cell(&h, &row, "warning");
    assert!(
        w.contains("penetration") && w.contains("bar-wave speed"),
        "{w}"
    );
    assert!(err.contains("warning: penetration"), "{err}");
    // Just past each bound: delta_max / R = 0.08 is at u = (0.08 R / delta_1)^(5/4) for the
    // delta_1 of u = 1 m/s; the wave bound at u = 0.01 sqrt(E / rho).
    let hz = HertzImpact64::new(&Material64::COAL, &Material64::CARBON_STEEL, 0.03, 1.0)
        .expect("closed forms");
    let u_pen = (0.08 * 0.03 / hz.delta_max_m).powf(1.25);
    let u_wave = 0.01 * (5.3e9f64 / 1380.0).sqrt();
    assert!(u_wave < u_pen, "the wave bound comes first for coal");
    for (u, warned) in [(0.99 * u_wave, false), (1.01 * u_wave, true)] {
        let s = format!("{u}");
        let (h, row, _) = single(&["--material", "coal", "--radius", "0.03", "--speed", &s]);
        assert_eq!(!cell(&h, &row, "warning").is_empty(), warned, "u = {u}");
    }
}

/// `jacobian_evals` counts the implicit methods' Jacobians apart from the force evaluations:
/// Radau13 takes at least one per accepted step (one per step's end, reused by the next), the
/// explicit Dop853 none.
#[test]
fn jacobians_are_counted_apart_for_the_implicit_methods() {
    let base = ["--material", "coal", "--radius", "0.03", "--speed", "3"];
    let num = |method: &str, name: &str| {
        let args: Vec<&str> = base.iter().copied().chain(["--method", method]).collect();
        let (header, row, err) = single(&args);
        cell(&header, &row, name)
            .parse::<f64>()
            .unwrap_or_else(|_| panic!("{name} of {method}: {err}"))
    };
    assert_eq!(num("dop853", "jacobian_evals"), 0.0);
    let (jacobians, steps) = (num("radau13", "jacobian_evals"), num("radau13", "steps"));
    assert!(jacobians >= steps && jacobians > 0.0, "{jacobians} {steps}");
}
