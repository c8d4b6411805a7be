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
