//! `host-sim tradeoff`, the markdown table: the study rendered for a reader, with numbers in
//! engineering form.

use std::fmt::Write as _;

use crate::report::tradeoff::config::BLOCK_SAMPLES;
use crate::report::tradeoff::results::{SceneAccuracy, Tradeoff};

/// `x` with 3 significant digits and an SI-like suffix (k, M, G) for large values.
fn si(x: f64) -> String {
    let a = x.abs();
    if !x.is_finite() {
        format!("{x}")
    } else if a >= 1e9 {
        format!("{:.3} G", x / 1e9)
    } else if a >= 1e6 {
        format!("{:.3} M", x / 1e6)
    } else if a >= 1e4 {
        format!("{:.1} k", x / 1e3)
    } else if a >= 100.0 {
        format!("{x:.0}")
    } else if a >= 10.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    }
}

/// An instruction count, rounded, with thousands separated by spaces (`1 558 815`).
fn insns(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let digits = format!("{:.0}", x.abs());
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(' ');
        }
        out.push(c);
    }
    if x < 0.0 { format!("-{out}") } else { out }
}

fn acc_cell(a: &SceneAccuracy) -> String {
    format!(
        "{} {:.3} (cov. {:.2}, conf. err. {:.3})",
        a.scene, a.forced_choice, a.coverage, a.confident_error_rate
    )
}

/// The markdown table of every knob, followed by notes on how the figures were obtained.
pub fn render_table(t: &Tradeoff) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| knob | setting | host cost | Cortex-M4F (instructions) | error | accuracy: forced choice (coverage, confident error) |"
    );
    let _ = writeln!(s, "| --- | --- | --- | --- | --- | --- |");
    backend_lines(&mut s, t);
    grid_lines(&mut s, t);
    integrator_lines(&mut s, t);
    rate_lines(&mut s, t);
    notes(&mut s, t);
    s
}

/// The math backends' rows.
fn backend_lines(s: &mut String, t: &Tradeoff) {
    for b in &t.backends {
        let _ = writeln!(
            s,
            "| math backend | {} | {} ns / quiet sample ({} ns in blocks of {BLOCK_SAMPLES}); {} us / classified pulse; {} us / scene build | {} / quiet sample{}; {} / classify{}; {} / scene build | F_max {:.1e}, t_c {:.1e} | {} |",
            b.backend,
            si(b.quiet_ns),
            si(b.quiet_block_ns),
            si(b.pulse_ns / 1e3),
            si(b.build_us),
            insns(b.m4.quiet_sample),
            b.m4.quiet_block_sample
                .map(|q| format!(" ({} in blocks)", insns(q)))
                .unwrap_or_default(),
            insns(b.m4.classify),
            b.m4.pulse_total
                .map(|p| format!("; {} / whole pulse", insns(p)))
                .unwrap_or_default(),
            insns(b.m4.scene_build),
            b.max_rel_err_force,
            b.max_rel_err_duration,
            b.accuracy
                .iter()
                .map(acc_cell)
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
}

/// The separability grids' rows.
fn grid_lines(s: &mut String, t: &Tradeoff) {
    for g in &t.grids {
        let _ = writeln!(
            s,
            "| separability grid | {0} rows | {1} us / scene build; Scene {2} B, Monitor {3} B | ~{4} / scene build (est.) | bayes_error {5:.4} (err {6:.1e}), overlap {7:.4} (err {8:.1e}) | (build-time figure only) |",
            g.grid,
            si(g.build_us),
            t.sizes.scene,
            t.sizes.monitor,
            si(g.m4_build_insns_est),
            g.bayes_error,
            g.bayes_error_err,
            g.overlap,
            g.overlap_err
        );
    }
}

/// The integrator ladder's rows.
fn integrator_lines(s: &mut String, t: &Tradeoff) {
    for i in &t.integrator {
        let _ = writeln!(
            s,
            "| integrator | {} | {} impacts/s ({} us / impact, {} force evals) | - | F_max {:.1e}, t_c {:.1e} | - |",
            i.label,
            si(i.impacts_per_s),
            si(1e6 / i.impacts_per_s),
            si(i.force_evals),
            i.max_rel_err_force,
            i.max_rel_err_duration
        );
    }
}

/// The sample rates' rows.
fn rate_lines(s: &mut String, t: &Tradeoff) {
    for (_, rows) in &t.rates {
        for r in rows {
            let _ = writeln!(
                s,
                "| sample rate | {} S/s, {} | {} us / s of signal | ~{} / s of signal (est.) | shortest pulse {:.1} samples | {} |",
                si(r.sample_rate_hz),
                r.accuracy.scene,
                si(r.host_ns_per_signal_s / 1e3),
                si(r.m4_insns_per_signal_s),
                r.samples_per_shortest_pulse,
                acc_cell(&r.accuracy)
            );
        }
    }
}

/// The notes under the table: the reference separability, the kernel's sizes, the firmware
/// figures' source, refused rates, and the run's sizes.
fn notes(s: &mut String, t: &Tradeoff) {
    let r = &t.reference;
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "Reference separability of the paper scene (f64, independent densities of host-sim's \
         `bayes`): Bayes error {:.4}, overlap {:.4} on a {} x {} midpoint grid; Monte Carlo \
         oracle {:.4} +- {:.4}.",
        r.bayes_error, r.overlap, r.grid, r.grid, r.mc_bayes_error, r.mc_std_error
    );
    let z = &t.sizes;
    let _ = writeln!(
        s,
        "Kernel sizes (host, 4 classes): Scene {} B, Monitor {} B, Detector {} B, Counters {} B, \
         Envelope {} B, the same at every grid size (the grid is a loop bound of the build, \
         nothing is stored per cell).",
        z.scene, z.monitor, z.detector, z.counters, z.envelope
    );
    let _ = writeln!(s, "Cortex-M4F figures: {}.", t.firmware.source);
    for (scene, fs, why) in &t.refused_rates {
        let _ = writeln!(s, "The kernel refuses {scene} at {fs} Hz: {why}.");
    }
    let _ = writeln!(
        s,
        "Accuracy: {} impacts per class per evaluation, seed {}; host times: minimum of {} runs.",
        t.config.eval_n_per_class, t.config.seed, t.config.timing_reps
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instruction_counts_are_grouped() {
        assert_eq!(insns(1_558_815.0), "1 558 815");
        assert_eq!(insns(74.0), "74");
        assert_eq!(insns(2736.4), "2 736");
    }
}
