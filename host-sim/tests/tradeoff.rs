//! `host-sim tradeoff --quick`: the files are complete and finite, and the measured trade-offs
//! go the way the physics and the numerics say (timings are printed by the command, never
//! asserted here).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::OnceLock;

use host_sim::tradeoff::{
    FirmwareFigures, METRICS_CSV, PARETO_CSV, SVG_FILES, TABLE_MD, Tradeoff, TradeoffConfig,
    compute, write_outputs,
};

/// The quick run, computed once for every test, and the directory its files went to.
fn quick() -> &'static (Tradeoff, PathBuf) {
    static RUN: OnceLock<(Tradeoff, PathBuf)> = OnceLock::new();
    RUN.get_or_init(|| {
        let t = compute(&TradeoffConfig::quick(1), test_figures()).expect("the quick run succeeds");
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("tradeoff-quick");
        write_outputs(&t, &dir).expect("files written");
        (t, dir)
    })
}

/// Firmware figures for the quick run: made-up counts in the form of `fw/measure.sh`'s
/// `measures.txt` (the command itself reads the measured file; nothing here is a measurement).
fn test_figures() -> FirmwareFigures {
    let text = "libm_insns_quiet_sample_mean 70\nlibm_insns_quiet_block_sample_mean 30\n\
                libm_insns_classify_mean 4000\nlibm_insns_pulse_total_mean 9000\n\
                libm_insns_scene_build 60000\nmicromath_insns_quiet_sample_mean 70\n\
                micromath_insns_classify_mean 3500\nmicromath_insns_scene_build 70000\n";
    FirmwareFigures::parse_measures(text, "test figures").expect("parses")
}

fn read_csv(name: &str) -> Vec<BTreeMap<String, String>> {
    let path = quick().1.join(name);
    let mut r = csv::Reader::from_path(&path).expect("csv opens");
    r.deserialize()
        .map(|row| row.expect("csv row parses"))
        .collect()
}

#[test]
fn metrics_csv_has_every_row_and_finite_values() {
    let (t, _) = quick();
    let rows = read_csv(METRICS_CSV);
    assert_eq!(rows.len(), t.metrics().len());
    for r in &rows {
        let v: f64 = r["value"].parse().expect("numeric value");
        assert!(v.is_finite(), "{r:?}");
    }
    let has = |knob: &str, setting: &str, scene: &str, metric: &str| {
        rows.iter().any(|r| {
            r["knob"] == knob
                && r["setting"] == setting
                && r["scene"] == scene
                && r["metric"] == metric
        })
    };
    let cfg = &t.config;
    for backend in ["libm", "micromath"] {
        for m in [
            "host_quiet_sample",
            "host_pulse",
            "m4_quiet_sample",
            "m4_classify",
        ] {
            assert!(has("backend", backend, "paper", m), "{backend} {m}");
        }
        assert!(has("backend", backend, "paper range", "max_rel_err_f_max"));
        for scene in ["paper", "paper_narrow"] {
            assert!(has("backend", backend, scene, "forced_choice_accuracy"));
        }
    }
    for g in &cfg.grid_sizes {
        assert!(
            has("grid", &g.to_string(), "paper", "abs_err_bayes_error"),
            "grid {g}"
        );
    }
    for tol in &cfg.dopri5_tolerances {
        assert!(has(
            "integrator",
            &format!("dopri5 rtol {tol:.0e}"),
            "paper range",
            "impacts_per_s"
        ));
    }
    for n in &cfg.rk4_steps {
        assert!(has(
            "integrator",
            &format!("rk4 {n} steps per t_c"),
            "paper range",
            "max_rel_err_t_c"
        ));
    }
    for fs in &cfg.sample_rates_hz {
        for scene in ["paper", "paper_narrow"] {
            // 10 kS/s leaves the paper's shortest pulses 1.1 samples: the kernel refuses it.
            let refused = t
                .refused_rates
                .iter()
                .any(|(s, f, _)| s == scene && f == fs);
            assert_eq!(refused, *fs < 20_000.0, "{scene} at {fs}");
            if refused {
                continue;
            }
            assert!(
                has(
                    "sample_rate",
                    &fs.to_string(),
                    scene,
                    "forced_choice_accuracy"
                ),
                "{fs} {scene}"
            );
            assert!(has(
                "sample_rate",
                &fs.to_string(),
                scene,
                "m4_per_signal_s_est"
            ));
        }
    }
    assert_eq!(t.refused_rates.len(), 2, "{:?}", t.refused_rates);
}

/// `(cost, loss, on_front)` of one Pareto point.
type Point = (f64, f64, bool);

#[test]
fn pareto_csv_is_finite_and_its_fronts_are_non_dominated() {
    let rows = read_csv(PARETO_CSV);
    assert_eq!(rows.len(), quick().0.pareto_points().len());
    let mut groups: BTreeMap<(String, String), Vec<Point>> = BTreeMap::new();
    for r in &rows {
        let cost: f64 = r["cost"].parse().expect("cost");
        let loss: f64 = r["loss"].parse().expect("loss");
        assert!(cost.is_finite() && loss.is_finite(), "{r:?}");
        let on = r["on_front"] == "true";
        groups
            .entry((r["plot"].clone(), r["series"].clone()))
            .or_default()
            .push((cost, loss, on));
    }
    for plot in ["backend", "grid", "integrator", "sample_rate"] {
        assert!(groups.keys().any(|(p, _)| p == plot), "no {plot} points");
    }
    for (key, pts) in &groups {
        let dominated = |&(c, l, _): &Point| {
            pts.iter()
                .any(|&(c2, l2, _)| c2 <= c && l2 <= l && (c2 < c || l2 < l))
        };
        assert!(pts.iter().any(|p| p.2), "{key:?}: empty front");
        for p in pts {
            assert_eq!(p.2, !dominated(p), "{key:?}: {p:?}");
        }
    }
}

#[test]
fn micromath_is_less_accurate_than_libm_within_the_documented_tolerance() {
    let (t, _) = quick();
    let by = |name: &str| {
        t.backends
            .iter()
            .find(|b| b.backend == name)
            .expect("backend measured")
    };
    let (libm, micro) = (by("libm"), by("micromath"));
    // tests/hertz.rs: libm within 2e-6, micromath within 5e-3 (README: 3.4e-3 measured).
    assert!(libm.max_rel_err_force < 2e-6, "{}", libm.max_rel_err_force);
    assert!(
        libm.max_rel_err_duration < 2e-6,
        "{}",
        libm.max_rel_err_duration
    );
    assert!(micro.max_rel_err_force > libm.max_rel_err_force);
    assert!(
        micro.max_rel_err_force < 5e-3,
        "{}",
        micro.max_rel_err_force
    );
    assert!(
        micro.max_rel_err_duration < 5e-3,
        "{}",
        micro.max_rel_err_duration
    );
    assert!(
        micro.max_rel_err_force > 1e-4,
        "micromath suspiciously exact"
    );
}

#[test]
fn tighter_integrator_tolerance_gives_smaller_error() {
    let (t, _) = quick();
    for method in ["dopri5", "rk4"] {
        let mut rows: Vec<_> = t.integrator.iter().filter(|r| r.method == method).collect();
        assert!(rows.len() >= 3, "{method}");
        // From loosest to tightest: rtol down, steps up.
        rows.sort_by(|a, b| {
            if method == "dopri5" {
                b.setting.total_cmp(&a.setting)
            } else {
                a.setting.total_cmp(&b.setting)
            }
        });
        let err = |r: &&host_sim::tradeoff::IntegratorRow| {
            r.max_rel_err_force.max(r.max_rel_err_duration)
        };
        for w in rows.windows(2) {
            assert!(err(&w[1]) < err(&w[0]), "{} -> {}", w[0].label, w[1].label);
            assert!(w[1].force_evals > w[0].force_evals, "{}", w[1].label);
        }
    }
}

#[test]
fn faster_sampling_does_not_lose_accuracy_on_the_narrow_scene() {
    let (t, _) = quick();
    let (_, rows) = t
        .rates
        .iter()
        .find(|(s, _)| s == "paper_narrow")
        .expect("narrow scene measured");
    let lo = rows
        .iter()
        .min_by(|a, b| a.sample_rate_hz.total_cmp(&b.sample_rate_hz))
        .expect("rows");
    let hi = rows
        .iter()
        .max_by(|a, b| a.sample_rate_hz.total_cmp(&b.sample_rate_hz))
        .expect("rows");
    assert_eq!(
        (lo.sample_rate_hz, hi.sample_rate_hz),
        (26_700.0, 1_000_000.0)
    );
    assert!(
        hi.accuracy.forced_choice >= lo.accuracy.forced_choice,
        "{} < {}",
        hi.accuracy.forced_choice,
        lo.accuracy.forced_choice
    );
    assert!(
        hi.accuracy.forced_choice > 0.9,
        "{}",
        hi.accuracy.forced_choice
    );
    // More samples per second is more work, on the node's estimate.
    assert!(hi.m4_insns_per_signal_s > 10.0 * lo.m4_insns_per_signal_s);
}

#[test]
fn separability_grid_error_against_the_f64_reference() {
    let (t, _) = quick();
    let r = &t.reference;
    // The reference integral agrees with the Monte Carlo oracle.
    assert!(
        (r.bayes_error - r.mc_bayes_error).abs() < 4.0 * r.mc_std_error + 1e-3,
        "{r:?}"
    );
    assert!(r.bayes_error > 0.2 && r.bayes_error < 0.27, "{r:?}");
    let coarse = t.grids.iter().find(|g| g.grid == 8).expect("grid 8");
    let default = t.grids.iter().find(|g| g.grid == 48).expect("grid 48");
    // The kernel's row-exact quadrature converges from the coarsest grid on: 8 and 48 rows
    // agree with each other and with the f64 reference (itself a 768-cell grid here).
    println!("grid 8: {coarse:?}\ngrid 48: {default:?}\nreference: {r:?}");
    assert!(
        (default.bayes_error - coarse.bayes_error).abs() < 2e-4,
        "{coarse:?} {default:?}"
    );
    assert!(default.bayes_error_err < 2e-3, "{default:?}");
    // The kernel types do not depend on the grid: one size for all.
    assert!(t.sizes.monitor >= t.sizes.scene + t.sizes.detector);
}

#[test]
fn table_and_svg_files_are_written() {
    let (_, dir) = quick();
    let table = std::fs::read_to_string(dir.join(TABLE_MD)).expect("table");
    for knob in [
        "math backend",
        "separability grid",
        "integrator",
        "sample rate",
    ] {
        assert!(table.contains(&format!("| {knob} |")), "{knob}");
    }
    for f in SVG_FILES {
        let svg = std::fs::read_to_string(dir.join(f)).expect("svg");
        assert!(svg.contains("<svg") && svg.contains("</svg>"), "{f}");
    }
}
