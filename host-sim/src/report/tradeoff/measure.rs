//! `host-sim tradeoff`, the measurements: host timings, accuracies and errors behind each row
//! of the study, one function per knob.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use coalshock::math::{Backend, Libm};
use coalshock::scene::DEFAULT_CLASSES;
use coalshock::{Event, Monitor, Verdict};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::bridge::convert::{
    duration_bounds_from_kernel, kernel_impact_in, separability_from_kernel,
};
use crate::bridge::kernel_scene::scene_to_kernel_in;
use crate::physics::hertz64::{HertzImpact64, Material64};
use crate::physics::integrate::{ContactProblem, Method};
use crate::physics::integrator_cases::{MethodCase, ladder, relative_errors, undamped_problem};
use crate::report::tradeoff::config::{BLOCK_SAMPLES, TradeoffConfig};
use crate::report::tradeoff::firmware::{FirmwareFigures, m4_instructions_per_second};
use crate::report::tradeoff::results::{
    BackendRow, GridRow, IntegratorRow, RateRow, SceneAccuracy, SeparabilityReference,
};
use crate::scene::{self, SceneFile};
use crate::score::bayes::{ClassModel, bayes_accuracy};
use crate::score::evaluate::{EvalOptions, class_models, evaluate};
use crate::score::replay::replay_events;
use crate::sim::generate::generate;
use crate::sim::stream::{PulseModel, Stream, StreamOptions};

/// Minimum wall time in s of `reps` (at least 1) runs of `f`.
fn min_seconds(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps.max(1))
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Feeds every sample through `Monitor::feed`; returns the classified (not rejected) pulses.
fn feed_each<M: Backend>(m: &mut Monitor<DEFAULT_CLASSES, M>, samples: &[i16]) -> usize {
    let mut n = 0;
    for &s in samples {
        if let Some(Event::Pulse(r)) = m.feed(black_box(i32::from(s))) {
            n += usize::from(!matches!(r.verdict, Verdict::Rejected(_)));
        }
    }
    n
}

/// Feeds the samples through `Monitor::feed_slice` in blocks of [`BLOCK_SAMPLES`].
fn feed_blocks<M: Backend>(m: &mut Monitor<DEFAULT_CLASSES, M>, samples: &[i16]) {
    for block in samples.chunks(BLOCK_SAMPLES) {
        m.feed_slice(black_box(block), |e| {
            black_box(e);
        });
    }
}

/// Which scene file a name resolves to: `scenes/<name>.toml` in the working directory, else
/// next to this package, else the built-in scene (equal to the file, see `convert` tests).
pub(crate) fn resolve_scene(name: &str, builtin: fn() -> SceneFile) -> Result<(SceneFile, String)> {
    let rel = PathBuf::from("scenes").join(format!("{name}.toml"));
    let beside = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(&rel);
    for p in [rel.clone(), beside] {
        if p.is_file() {
            return Ok((scene::load(&p)?, rel.display().to_string()));
        }
    }
    Ok((builtin(), format!("built-in {name} scene")))
}

/// Noiseless Bayes error and overlap share of `classes` by a `g x g` midpoint integral over
/// each class's `(ln R, ln u)` box in f64, with the densities of [`ClassModel::density`]:
/// a cell of class `i` counts as overlap when another class's density there is positive, as
/// error when another class's prior-weighted density is larger (ties to the lower index).
pub fn reference_separability(classes: &[ClassModel], g: usize) -> (f64, f64) {
    let total: f64 = classes.iter().map(|c| c.prior).sum();
    let (mut overlap, mut error) = (0.0, 0.0);
    let gf = g as f64;
    for (i, c) in classes.iter().enumerate() {
        let (x0, x1) = c.ln_radius;
        let (y0, y1) = c.ln_speed;
        let (dx, dy) = ((x1 - x0) / gf, (y1 - y0) / gf);
        let (mut m_all, mut m_over, mut m_err) = (0.0, 0.0, 0.0);
        for iy in 0..g {
            let y = y0 + (iy as f64 + 0.5) * dy;
            // Speed density in ln u, p(y) ~ e^(beta y), normalised on the box.
            let b = c.speed_beta;
            let w = if b.abs() < 1e-12 {
                1.0
            } else {
                b * (b * (y - y1)).exp() / (1.0 - (b * (y0 - y1)).exp()) * (y1 - y0)
            };
            let (mut row_over, mut row_err) = (0.0, 0.0);
            for ix in 0..g {
                let x = x0 + (ix as f64 + 0.5) * dx;
                let (lf, lt) = c.forward(x, y);
                let own = c.prior * c.density(lf, lt);
                let (mut possible, mut better) = (false, false);
                for (j, o) in classes.iter().enumerate() {
                    if j == i {
                        continue;
                    }
                    let d = o.prior * o.density(lf, lt);
                    possible |= d > 0.0;
                    better |= d > own || (d == own && d > 0.0 && j < i);
                }
                row_over += f64::from(u8::from(possible));
                row_err += f64::from(u8::from(better));
            }
            m_all += w * gf;
            m_over += w * row_over;
            m_err += w * row_err;
        }
        overlap += c.prior * m_over / m_all;
        error += c.prior * m_err / m_all;
    }
    (error / total, overlap / total)
}

/// Largest relative errors `(F_max, t_c)` of the kernel's closed forms with backend `M` over
/// each class of `scene`: `points x points` per class, `R` log-spaced and `u` linear over the
/// class's ranges, against [`HertzImpact64`] at the same (unrounded) inputs; also the number
/// of points.
pub fn closed_form_errors<M: Backend>(
    scene: &SceneFile,
    points: usize,
) -> Result<(f64, f64, usize)> {
    let plate = scene.plate.material();
    let (mut ef, mut et, mut count) = (0.0f64, 0.0f64, 0usize);
    for (m, r, u) in scene_grid(scene, points) {
        let want = HertzImpact64::new(&m, &plate, r, u)?;
        let got = kernel_impact_in::<M>(&m, &plate, r, u)?;
        ef = ef.max((got.peak_force_n / want.peak_force_n - 1.0).abs());
        et = et.max((got.duration_s / want.duration_s - 1.0).abs());
        count += 1;
    }
    Ok((ef, et, count))
}

/// `(sphere material, R in m, u in m/s)` on a `points x points` grid per class of `scene`
/// (at least 2 x 2): `R` log-spaced and `u` linear over the class's ranges.
fn scene_grid(scene: &SceneFile, points: usize) -> Vec<(Material64, f64, f64)> {
    let n = points.max(2);
    let mut out = Vec::new();
    for c in &scene.classes {
        let m = c.material.material();
        let (r, u) = (c.radius_m, c.speed_range_m_s());
        for i in 0..n {
            let radius = r.min * (r.max / r.min).powf(i as f64 / (n - 1) as f64);
            for j in 0..n {
                out.push((
                    m,
                    radius,
                    u.min + (u.max - u.min) * j as f64 / (n - 1) as f64,
                ));
            }
        }
    }
    out
}

/// Accuracy of the kernel with backend `M` on `scene` ([`crate::score::evaluate::evaluate`]).
fn accuracy_of<M: Backend + Send + Sync>(
    name: &str,
    scene: &SceneFile,
    cfg: &TradeoffConfig,
) -> Result<SceneAccuracy> {
    let opts = EvalOptions {
        n_per_class: cfg.eval_n_per_class,
        seed: cfg.seed,
        ..EvalOptions::default()
    };
    let e = evaluate::<M>(scene, &opts).map_err(|e| anyhow!("evaluating {name}: {e}"))?;
    Ok(SceneAccuracy {
        scene: name.to_string(),
        forced_choice: e.forced_choice_accuracy,
        coverage: e.coverage,
        confident_error_rate: e.confident_error_rate,
        bayes_accuracy: e.kernel_noise_bayes_accuracy,
        oracle_accuracy: e.oracle_accuracy,
        samples_fed: e.samples_fed as f64,
        pulses_detected: e.pulses_detected as f64,
    })
}

/// Stream options of the timing streams: the closed-form pulse shape (the kernel's work does
/// not depend on how the pulse was made), default gaps, no faults.
pub(crate) fn timing_options(lead_in_s: f64) -> StreamOptions {
    StreamOptions {
        lead_in_s,
        pulse_model: PulseModel::HertzSine,
        ..StreamOptions::default()
    }
}

pub(crate) fn backend_row<M: Backend + Send + Sync>(
    cfg: &TradeoffConfig,
    scenes: &[(String, SceneFile)],
    quiet: &Stream,
    pulsed: &Stream,
    fw: &FirmwareFigures,
) -> Result<BackendRow> {
    let paper = &scenes[0].1;
    let kernel = scene_to_kernel_in::<DEFAULT_CLASSES, M>(paper)?;
    let proto = Monitor::new(kernel);
    let reps = cfg.timing_reps;
    let t_quiet = min_seconds(reps, || {
        let mut m = proto.clone();
        black_box(feed_each(&mut m, &quiet.samples));
    }) / quiet.samples.len().max(1) as f64;
    let t_block = min_seconds(reps, || {
        let mut m = proto.clone();
        feed_blocks(&mut m, &quiet.samples);
        black_box(m.counters().pulses);
    }) / quiet.samples.len().max(1) as f64;
    let mut pulses = 0;
    let t_pulsed = min_seconds(reps, || {
        let mut m = proto.clone();
        pulses = feed_each(&mut m, &pulsed.samples);
    });
    let pulse_ns = if pulses > 0 {
        (t_pulsed - pulsed.samples.len() as f64 * t_quiet) / pulses as f64 * 1e9
    } else {
        f64::NAN
    };
    let build = min_seconds(reps, || {
        black_box(scene_to_kernel_in::<DEFAULT_CLASSES, M>(black_box(paper)).ok());
    });
    let (ef, et, points) = closed_form_errors::<M>(paper, cfg.closed_form_points)?;
    let accuracy = scenes
        .iter()
        .map(|(name, s)| accuracy_of::<M>(name, s, cfg))
        .collect::<Result<Vec<_>>>()?;
    Ok(BackendRow {
        backend: M::NAME,
        quiet_ns: t_quiet * 1e9,
        quiet_block_ns: t_block * 1e9,
        pulse_ns,
        timed_pulses: pulses,
        build_us: build * 1e6,
        max_rel_err_force: ef,
        max_rel_err_duration: et,
        closed_form_points: points,
        accuracy,
        m4: *fw.of::<M>(),
    })
}

pub(crate) fn grid_rows(
    cfg: &TradeoffConfig,
    paper: &SceneFile,
    reference: &SeparabilityReference,
    fw: &FirmwareFigures,
) -> Result<Vec<GridRow>> {
    let mut rows = Vec::new();
    let mut build_48 = None;
    let mut sizes: Vec<u16> = cfg.grid_sizes.clone();
    if !sizes.contains(&48) {
        sizes.push(48);
    }
    let mut measured = Vec::new();
    for &g in &sizes {
        let mut s = paper.clone();
        s.settings.separability_grid = g;
        let kernel = scene_to_kernel_in::<DEFAULT_CLASSES, Libm>(&s)?;
        let (overlap, bayes_error) = separability_from_kernel(&kernel.separability());
        let build = min_seconds(cfg.timing_reps, || {
            black_box(scene_to_kernel_in::<DEFAULT_CLASSES, Libm>(black_box(&s)).ok());
        });
        if g == 48 {
            build_48 = Some(build);
        }
        measured.push((g, build, overlap, bayes_error));
    }
    let build_48 = build_48.unwrap_or(f64::NAN);
    for (g, build, overlap, bayes_error) in measured {
        if !cfg.grid_sizes.contains(&g) {
            continue;
        }
        rows.push(GridRow {
            grid: g,
            build_us: build * 1e6,
            bayes_error,
            overlap,
            bayes_error_err: (bayes_error - reference.bayes_error).abs(),
            overlap_err: (overlap - reference.overlap).abs(),
            m4_build_insns_est: fw.libm.scene_build * build / build_48,
        });
    }
    Ok(rows)
}

pub(crate) fn separability_reference(
    cfg: &TradeoffConfig,
    paper: &SceneFile,
) -> SeparabilityReference {
    let models = class_models(paper);
    let (bayes_error, overlap) = reference_separability(&models, cfg.reference_grid);
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut uniform = || loop {
        let u: f64 = rng.random();
        if u > 0.0 {
            return u;
        }
    };
    let mc = bayes_accuracy(&models, None, cfg.bayes_mc_per_class, &mut uniform);
    SeparabilityReference {
        bayes_error,
        overlap,
        grid: cfg.reference_grid,
        mc_bayes_error: 1.0 - mc.accuracy,
        mc_std_error: mc.std_error,
    }
}

/// The undamped problems of the integrator section: per class of `scene`, `points x points`
/// impacts (`R` log-spaced, `u` linear over the class's ranges), with their closed forms.
pub fn integrator_problems(
    scene: &SceneFile,
    points: usize,
) -> Result<Vec<(HertzImpact64, ContactProblem)>> {
    let plate = scene.plate.material();
    let mut out = Vec::new();
    for (m, r, u) in scene_grid(scene, points) {
        let h = HertzImpact64::new(&m, &plate, r, u)?;
        out.push((h, undamped_problem(&h)));
    }
    Ok(out)
}

pub(crate) fn integrator_rows(
    cfg: &TradeoffConfig,
    paper: &SceneFile,
) -> Result<Vec<IntegratorRow>> {
    let problems = integrator_problems(paper, cfg.integrator_points)?;
    let mut rows = Vec::new();
    for case in ladder(&cfg.dopri5_tolerances, &cfg.rk4_steps) {
        let (mut ef, mut et, mut evals) = (0.0f64, 0.0f64, 0usize);
        for (h, p) in &problems {
            let s = case.solve(p).with_context(|| {
                format!(
                    "{} on R = {} m, u = {} m/s",
                    case.label, h.radius_m, h.speed_m_s
                )
            })?;
            let (a, b) = relative_errors(&s, h.peak_force_n, h.duration_s);
            ef = ef.max(a);
            et = et.max(b);
            evals += s.work.force_evals;
        }
        let t = min_seconds(cfg.timing_reps, || {
            for (_, p) in &problems {
                black_box(case.solve(black_box(p)).ok());
            }
        });
        let (method, setting) = match case.method {
            Method::Dopri5 => ("dopri5", case.tol.rtol),
            Method::Dop853 => ("dop853", case.tol.rtol),
            Method::Rodas4 => ("rodas4", case.tol.rtol),
            Method::Radau13 => ("radau13", case.tol.rtol),
            Method::Auto => ("auto", case.tol.rtol),
            Method::Rk4 { steps_per_tc } => ("rk4", f64::from(steps_per_tc)),
        };
        let MethodCase { label, .. } = case;
        rows.push(IntegratorRow {
            method,
            label,
            setting,
            impacts_per_s: problems.len() as f64 / t,
            max_rel_err_force: ef,
            max_rel_err_duration: et,
            force_evals: evals as f64 / problems.len() as f64,
            problems: problems.len(),
        });
    }
    Ok(rows)
}

#[allow(clippy::type_complexity)]
pub(crate) fn rate_rows(
    cfg: &TradeoffConfig,
    scenes: &[(String, SceneFile)],
    fw: &FirmwareFigures,
) -> Result<(Vec<(String, Vec<RateRow>)>, Vec<(String, f64, String)>)> {
    let mut all = Vec::new();
    let mut refused = Vec::new();
    for (name, base) in scenes {
        let mut rows = Vec::new();
        for &fs in &cfg.sample_rates_hz {
            let mut s = base.clone();
            s.sensor.sample_rate_hz = fs;
            let kernel = match scene_to_kernel_in::<DEFAULT_CLASSES, Libm>(&s) {
                Ok(k) => k,
                Err(e) => {
                    refused.push((name.clone(), fs, e.to_string()));
                    continue;
                }
            };
            let (shortest, _) = duration_bounds_from_kernel(&kernel);
            let shortest_samples = shortest * fs;
            let accuracy = accuracy_of::<Libm>(name, &s, cfg)?;
            let stream = generate(&s, cfg.rate_timing_impacts, cfg.seed, &timing_options(0.01))
                .with_context(|| format!("timing stream of {name} at {fs} Hz"))?;
            let proto = Monitor::new(kernel);
            let t = min_seconds(cfg.timing_reps, || {
                let mut m = proto.clone();
                black_box(replay_events(&stream, &mut m).len());
            });
            let signal_s = stream.timeline_samples as f64 / fs;
            let pulses_per_s = stream.truth.len() as f64 / signal_s;
            rows.push(RateRow {
                sample_rate_hz: fs,
                samples_per_shortest_pulse: shortest_samples,
                accuracy,
                host_ns_per_signal_s: t * 1e9 / signal_s,
                pulses_per_s,
                m4_insns_per_signal_s: m4_instructions_per_second(&fw.libm, fs, pulses_per_s),
            });
        }
        all.push((name.clone(), rows));
    }
    Ok((all, refused))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_separability_of_the_narrow_scene_is_zero() {
        let (b, o) = reference_separability(&class_models(&SceneFile::paper_narrow()), 64);
        assert_eq!((b, o), (0.0, 0.0));
    }
}
