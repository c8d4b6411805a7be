//! `host-sim tradeoff`, the long format: every figure of the study as one [`Metric`] row
//! (knob, setting, scene, metric, value, unit) of the metrics CSV.

use serde::Serialize;

use crate::report::tradeoff::results::{SceneAccuracy, Tradeoff};

/// One figure of the long-format CSV.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Metric {
    /// `backend`, `grid`, `integrator`, `sample_rate`, `reference` or `sizes`.
    pub knob: &'static str,
    /// The knob's setting.
    pub setting: String,
    /// The scene (or `paper range`).
    pub scene: String,
    /// What is measured.
    pub metric: &'static str,
    /// The value.
    pub value: f64,
    /// Its unit (`1` for dimensionless).
    pub unit: &'static str,
}

/// One figure's `(scene, metric, value, unit)` for a knob's setting.
type Figure<'a> = (&'a str, &'static str, f64, &'static str);

/// The rows of a [`Metric`] list being filled: a knob's setting and its figures, in order.
struct Rows(Vec<Metric>);

impl Rows {
    /// Appends the `figures` of `knob` at `setting`.
    fn push(&mut self, knob: &'static str, setting: &str, figures: &[Figure<'_>]) {
        for &(scene, metric, value, unit) in figures {
            self.0.push(Metric {
                knob,
                setting: setting.to_string(),
                scene: scene.to_string(),
                metric,
                value,
                unit,
            });
        }
    }

    /// The accuracy figures of `a` (on its scene) for `knob` at `setting`.
    fn accuracy(&mut self, knob: &'static str, setting: &str, a: &SceneAccuracy) {
        let sc = a.scene.as_str();
        self.push(
            knob,
            setting,
            &[
                (sc, "forced_choice_accuracy", a.forced_choice, "1"),
                (sc, "coverage", a.coverage, "1"),
                (sc, "confident_error_rate", a.confident_error_rate, "1"),
                (sc, "bayes_accuracy", a.bayes_accuracy, "1"),
                (sc, "oracle_accuracy", a.oracle_accuracy, "1"),
            ],
        );
    }
}

/// Unit of the Cortex-M4F counts.
const INSNS: &str = "instructions";

impl Tradeoff {
    /// Every figure, one [`Metric`] each: backends, grids, the reference, integrators,
    /// sample rates and the kernel's sizes, in that order.
    pub fn metrics(&self) -> Vec<Metric> {
        let mut rows = Rows(Vec::new());
        self.backend_metrics(&mut rows);
        self.grid_metrics(&mut rows);
        self.reference_and_integrator_metrics(&mut rows);
        self.rate_metrics(&mut rows);
        let z = &self.sizes;
        for (metric, v) in [
            ("scene_bytes", z.scene),
            ("monitor_bytes", z.monitor),
            ("detector_bytes", z.detector),
            ("counters_bytes", z.counters),
            ("envelope_bytes", z.envelope),
        ] {
            rows.push("sizes", "any grid", &[("any", metric, v as f64, "B")]);
        }
        rows.0
    }

    /// Host times, closed-form errors, Cortex-M4F counts and accuracies of each math backend.
    fn backend_metrics(&self, rows: &mut Rows) {
        for b in &self.backends {
            let (p, range) = ("paper", "paper range");
            rows.push(
                "backend",
                b.backend,
                &[
                    (p, "host_quiet_sample", b.quiet_ns, "ns"),
                    (p, "host_quiet_block_sample", b.quiet_block_ns, "ns"),
                    (p, "host_pulse", b.pulse_ns, "ns"),
                    (p, "host_scene_build", b.build_us, "us"),
                    (range, "max_rel_err_f_max", b.max_rel_err_force, "1"),
                    (range, "max_rel_err_t_c", b.max_rel_err_duration, "1"),
                    (p, "m4_quiet_sample", b.m4.quiet_sample, INSNS),
                    (p, "m4_classify", b.m4.classify, INSNS),
                    (p, "m4_scene_build", b.m4.scene_build, INSNS),
                ],
            );
            for a in &b.accuracy {
                rows.accuracy("backend", b.backend, a);
            }
        }
    }

    /// Build time, separability and its errors, and sizes of each separability grid.
    fn grid_metrics(&self, rows: &mut Rows) {
        for g in &self.grids {
            let p = "paper";
            rows.push(
                "grid",
                &g.grid.to_string(),
                &[
                    (p, "host_scene_build", g.build_us, "us"),
                    (p, "bayes_error", g.bayes_error, "1"),
                    (p, "overlap", g.overlap, "1"),
                    (p, "abs_err_bayes_error", g.bayes_error_err, "1"),
                    (p, "abs_err_overlap", g.overlap_err, "1"),
                    (p, "m4_scene_build_est", g.m4_build_insns_est, INSNS),
                    (p, "scene_bytes", self.sizes.scene as f64, "B"),
                    (p, "monitor_bytes", self.sizes.monitor as f64, "B"),
                ],
            );
        }
    }

    /// The f64 separability reference, then speed and errors of each integrator setting.
    fn reference_and_integrator_metrics(&self, rows: &mut Rows) {
        let r = &self.reference;
        let p = "paper";
        rows.push(
            "reference",
            &format!("f64 grid {}", r.grid),
            &[
                (p, "bayes_error", r.bayes_error, "1"),
                (p, "overlap", r.overlap, "1"),
            ],
        );
        rows.push(
            "reference",
            "monte carlo",
            &[
                (p, "bayes_error", r.mc_bayes_error, "1"),
                (p, "bayes_error_std_error", r.mc_std_error, "1"),
            ],
        );
        for i in &self.integrator {
            let range = "paper range";
            rows.push(
                "integrator",
                &i.label,
                &[
                    (range, "impacts_per_s", i.impacts_per_s, "1/s"),
                    (range, "max_rel_err_f_max", i.max_rel_err_force, "1"),
                    (range, "max_rel_err_t_c", i.max_rel_err_duration, "1"),
                    (range, "force_evals", i.force_evals, "1"),
                ],
            );
        }
    }

    /// Samples per pulse, work per second of signal and accuracy at each sample rate.
    fn rate_metrics(&self, rows: &mut Rows) {
        for (scene, rate_rows) in &self.rates {
            for r in rate_rows {
                let s = format!("{}", r.sample_rate_hz);
                let sc = scene.as_str();
                rows.push(
                    "sample_rate",
                    &s,
                    &[
                        (
                            sc,
                            "samples_per_shortest_pulse",
                            r.samples_per_shortest_pulse,
                            "1",
                        ),
                        (sc, "host_per_signal_s", r.host_ns_per_signal_s, "ns"),
                        (sc, "pulses_per_s", r.pulses_per_s, "1/s"),
                        (sc, "m4_per_signal_s_est", r.m4_insns_per_signal_s, INSNS),
                    ],
                );
                rows.accuracy("sample_rate", &s, &r.accuracy);
            }
        }
    }
}
