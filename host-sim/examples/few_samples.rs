//! What a pulse of a few samples allows, measured three ways on the same noisy impacts of a
//! scene behind a rigid chain: the kernel, the Cramér-Rao bound the reference limit takes,
//! and a brute-force maximum-likelihood fit in `f64` that knows the true pulse shape (the
//! integrator's force series of the impact, with amplitude, time scale, onset and baseline
//! unknown; independent of the kernel).
//!
//! Each class's impacts are drawn and streamed as `host-sim evaluate` draws them behind a rigid
//! chain (one stream per class, seeded `1000 SEED + class`), replayed through the kernel's
//! `Monitor`, and paired with the truth. Per band of samples per pulse
//! (the pulse's duration from its area times the sample rate) it prints, per class, the root
//! mean square error of `ln F_max` and `ln t_c` against the truth of
//!
//! - the kernel's Hertz-equivalent measurement (`Scene::hertz_equivalent`, against the
//!   closed-form Hertz features of the drawn size and speed) and the sigma it states,
//! - the maximum-likelihood fit (against the pulse's own features), and
//! - the square root of the bound, at the impact's own onset phase and averaged over four
//!   phases as the reference averages it,
//!
//! and then the forced-choice accuracy on the same impacts of the kernel, of the Bayes
//! decision (`host_sim::score::bayes::decide`) on the fit's features at the fit's own spread
//! in the band of its estimated `n` (taken over the same impacts), and of the same decision on
//! the exact features plus one Gaussian draw at the bound (own phase, and four phases), and of
//! the same decision on the kernel's features at their own spread in the band of the true `n`
//! (how much of the kernel's loss is its measurement rather than its classifier), and once more
//! with the kernel's phase table read at the pulse's true `n` instead of the `n` the kernel
//! infers from the measured duration (how much of it is that inference).
//!
//! `cargo run --release -p host-sim --example few_samples -- SCENE LAW E RATE_HZ NOISE_COUNTS
//! [N] [SEED]`: the scene file with its contact law (flores, hunt_crossley,
//! lankarani_nikravesh, gonthier or tsuji at restitution E), sample rate and noise replaced,
//! as `docs/grid-table.sh` makes its scenes; N impacts per class (2000 by default), SEED 1.
//! The fit searches durations of 0.5 to 64 samples.

use std::collections::BTreeMap;

use coalshock::{Event, Monitor};
use host_sim::bridge::kernel_scene::scene_to_kernel;
use host_sim::bridge::sampled_fit::force_at;
use host_sim::physics::impact::{ImpactSpec, simulate};
use host_sim::physics::law_spec::LawSpec;
use host_sim::score::bayes::{FeatureNoise, class_models, decide};
use host_sim::score::crb::{feature_crb, phase_averaged_crb};
use host_sim::score::replay::{match_truth, replay_events};
use host_sim::sensor::{ForcePulse, PulseShape, Sensor};
use host_sim::sim::generate::generate_classes;
use host_sim::sim::stream::{Stream, StreamOptions, Truth};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Area of the Hertz pulse over `F_max t_c`.
const C_AREA: f64 = 1.6 / 2.943_275_2;
/// Lower edges of the bands of samples per pulse.
const BANDS: [f64; 8] = [1.6, 2.0, 2.5, 3.2, 4.0, 5.0, 7.0, 12.0];
/// Samples either side of the largest one the fit and its baseline see.
const WINDOW: i64 = 40;

/// One impact of the integrator: its force series from first contact, peak, duration to the
/// first zero and from the area.
struct Pulse {
    series: Vec<(f64, f64)>,
    step_s: f64,
    peak_n: f64,
    first_zero_s: f64,
    area_s: f64,
}

fn integrate(scene: &host_sim::scene::SceneFile, t: &Truth) -> Pulse {
    let c = &scene.classes[t.class];
    let law = scene.class_law(t.class).expect("a law");
    let mut spec = ImpactSpec::new(
        c.material.material(),
        scene.plate.material(),
        t.radius_m,
        t.speed_m_s,
    );
    spec.law = law;
    let hertz_s = spec.hertz().expect("an impact").duration_s;
    let step_s = hertz_s / 2048.0;
    spec.record = Some(step_s);
    let r = simulate(&spec).expect("an impact");
    let series = r.force_series.unwrap_or_default();
    Pulse {
        series,
        step_s,
        peak_n: r.peak_force_n,
        first_zero_s: r.pulse_duration_s,
        area_s: r.impulse_n_s / (C_AREA * r.peak_force_n),
    }
}

/// The window's samples, their times and the sums that do not depend on the fit.
struct Window {
    samples: Vec<f64>,
    t_first_s: f64,
    dt: f64,
    sum: f64,
    sum_sq: f64,
}

/// Least squares of the window on `A m(t) + b`, `m` the pulse series time-scaled by `k` from
/// onset `t0_s`: the residual sum and `A`.
fn residual(p: &Pulse, w: &Window, k: f64, t0_s: f64) -> (f64, f64) {
    let (mut sm, mut smm, mut sms) = (0.0, 0.0, 0.0);
    let n = w.samples.len() as f64;
    let d = p.series.last().map_or(0.0, |x| x.0) * k;
    let first = (((t0_s - w.t_first_s) / w.dt).ceil().max(0.0)) as usize;
    let last = (((t0_s + d - w.t_first_s) / w.dt).floor().max(0.0)) as usize;
    for i in first..=last.min(w.samples.len().saturating_sub(1)) {
        let s = w.samples[i];
        let tau = (w.t_first_s + i as f64 * w.dt - t0_s) / k;
        let m = force_at(&p.series, tau);
        sm += m;
        smm += m * m;
        sms += m * s;
    }
    let det = smm * n - sm * sm;
    if det <= 0.0 {
        return (f64::INFINITY, 0.0);
    }
    let a = (sms * n - sm * w.sum) / det;
    let b = (smm * w.sum - sm * sms) / det;
    (w.sum_sq - a * sms - b * w.sum, a)
}

/// The maximum-likelihood `(ln k, t0_s, A)`: the best of two grids, one over the duration
/// (0.5-64 samples) with, at each, the onset within 2 samples of where it puts the pulse's
/// peak on the largest sample, and one over 0.5-14 samples with the onset anywhere in the 15
/// samples before the largest; then three zoomed grids about the best.
fn ml_fit(p: &Pulse, w: &Window, t_top_s: f64) -> (f64, f64, f64) {
    let dt = w.dt;
    let d = p.series.last().map_or(0.0, |x| x.0);
    let peak_at = p
        .series
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0.0, |x| x.0);
    let (lo_k, hi_k) = ((0.5 * dt / d).ln(), (64.0 * dt / d).ln());
    let mut best = (f64::INFINITY, 0.0, 0.0, 0.0);
    let search = |ks: Vec<f64>, ts: &dyn Fn(f64) -> Vec<f64>, best: &mut (f64, f64, f64, f64)| {
        for &lk in &ks {
            for t0 in ts(lk) {
                let (r, a) = residual(p, w, lk.exp(), t0);
                if a > 0.0 && r < best.0 {
                    *best = (r, lk, t0, a);
                }
            }
        }
    };
    let span = |c: f64, h: f64, m: usize| -> Vec<f64> {
        (0..=m)
            .map(|i| c - h + 2.0 * h * i as f64 / m as f64)
            .collect()
    };
    let coarse = |lk: f64| span(t_top_s - peak_at * lk.exp(), 2.0 * dt, 40);
    search(
        span(0.5 * (lo_k + hi_k), 0.5 * (hi_k - lo_k), 120),
        &coarse,
        &mut best,
    );
    let short_k = (14.0 * dt / d).ln();
    search(
        span(0.5 * (lo_k + short_k), 0.5 * (short_k - lo_k), 80),
        &|_| span(t_top_s - 7.5 * dt, 7.5 * dt, 150),
        &mut best,
    );
    let (mut hk, mut ht) = ((hi_k - lo_k) / 120.0, dt / 10.0);
    for _ in 0..3 {
        let (_, lk, t0, _) = best;
        search(
            span(lk, 2.0 * hk, 40),
            &|_| span(t0, 2.0 * ht, 40),
            &mut best,
        );
        hk /= 10.0;
        ht /= 10.0;
    }
    (best.1, best.2, best.3)
}

fn band(n: f64) -> Option<usize> {
    (n >= BANDS[0]).then(|| BANDS.iter().rposition(|&b| n >= b).unwrap_or(0))
}

/// One impact's errors, `[ln F, ln t_c]`.
#[derive(Default, Clone)]
struct Row {
    class: usize,
    band: usize,
    kernel: Option<[f64; 2]>,
    kernel_true_n: Option<[f64; 2]>,
    kernel_sigma: [f64; 2],
    kernel_forced: Option<usize>,
    ml: [f64; 2],
    ml_band: usize,
    crb_own: [f64; 3],
    crb_avg: [f64; 3],
    hertz: [f64; 2],
}

fn rows_of(scene: &host_sim::scene::SceneFile, stream: &Stream, n: usize) -> Vec<Row> {
    let kscene = scene_to_kernel(scene).expect("kernel scene");
    let sensor = Sensor::new(&scene.sensor).expect("sensor");
    let g = sensor.counts_per_newton();
    let fs = stream.sample_rate_hz;
    let dt = 1.0 / fs;
    let models = class_models(scene);
    let mut monitor: Monitor = Monitor::new(kscene.clone());
    let reports: Vec<_> = replay_events(stream, &mut monitor)
        .into_iter()
        .filter_map(|e| match e {
            Event::Pulse(r) => Some(r),
            _ => None,
        })
        .collect();
    let matching = match_truth(&reports, &stream.truth, 20);
    let mut report_of = vec![None; stream.truth.len()];
    for p in &matching.pairs {
        report_of[p.truth] = Some(p.report);
    }
    let mut rows = Vec::new();
    for (t, rep) in stream.truth.iter().zip(report_of).take(n) {
        let p = integrate(scene, t);
        let n_area = p.area_s * fs;
        let Some(b) = band(n_area) else { continue };
        let (lf, lt) = models[t.class].forward(t.radius_m.ln(), t.speed_m_s.ln());
        let truth_ln = [p.peak_n.ln(), p.first_zero_s.ln()];
        let mut row = Row {
            class: t.class,
            band: b,
            hertz: [lf, lt],
            ..Row::default()
        };
        if let Some(r) = rep.map(|i| &reports[i]) {
            row.kernel_forced = r.verdict.forced_choice().map(usize::from);
            if let Some(m) = r.measurement {
                let h = kscene.hertz_equivalent(&m);
                row.kernel = Some([
                    f64::from(h.peak_force_n).ln() - lf,
                    f64::from(h.duration_s).ln() - lt,
                ]);
                row.kernel_sigma = [h.sigma_ln_force.into(), h.sigma_ln_duration.into()];
                let c = &kscene.settings().contact;
                let ln_n = (n_area as f32).ln();
                row.kernel_true_n = kscene.settings().sampled_phase.at(ln_n, m.asymmetry).map(
                    |(lf_c, lt_c, _, _)| {
                        [
                            f64::from(m.peak_force_n / (c.force_ratio * lf_c.exp())).ln() - lf,
                            f64::from(m.duration_s / (c.duration_ratio * lt_c.exp())).ln() - lt,
                        ]
                    },
                );
            }
        }
        // The noisy samples about the largest noiseless one.
        let top = ((t.peak_time_s - stream.phase_s) * fs).round() as i64;
        let idx: Vec<i64> = (top - WINDOW..=top + WINDOW).collect();
        let samples: Vec<f64> = idx
            .iter()
            .map(|&i| f64::from(stream.samples[i as usize]))
            .collect();
        let s_top = (0..samples.len())
            .max_by(|&a, &b| samples[a].total_cmp(&samples[b]))
            .unwrap_or(0);
        let t_first_s = stream.phase_s + (top - WINDOW) as f64 * dt;
        let w = Window {
            sum: samples.iter().sum(),
            sum_sq: samples.iter().map(|s| s * s).sum(),
            samples,
            t_first_s,
            dt,
        };
        let (lk, _t0, a) = ml_fit(&p, &w, t_first_s + s_top as f64 * dt);
        row.ml = [
            (a / g).ln() + p.peak_n.ln() - truth_ln[0] + (p.series_peak() / p.peak_n).ln(),
            lk,
        ];
        row.ml_band = band(lk.exp() * n_area).unwrap_or(0);
        let pulse = ForcePulse {
            start_s: 0.0,
            duration_s: p.series.last().map_or(0.0, |x| x.0),
            scale: 1.0,
            shape: PulseShape::Series {
                step_s: p.step_s,
                force_n: p.series.iter().map(|x| x.1).collect(),
            },
        };
        let onset = ((t.time_s - stream.phase_s) * fs).rem_euclid(1.0);
        row.crb_own = feature_crb(&sensor, &pulse, onset).unwrap_or([100.0, 100.0, 0.0]);
        row.crb_avg = phase_averaged_crb(&sensor, &pulse, 4).unwrap_or([100.0, 100.0, 0.0]);
        rows.push(row);
    }
    rows
}

trait SeriesPeak {
    fn series_peak(&self) -> f64;
}

impl SeriesPeak for Pulse {
    /// The largest force of the series (the fit's `A` scales it, not the peak).
    fn series_peak(&self) -> f64 {
        self.series.iter().map(|x| x.1).fold(0.0, f64::max)
    }
}

fn rms(v: impl Iterator<Item = f64>) -> (f64, usize) {
    let (mut s, mut n) = (0.0, 0);
    for x in v {
        s += x * x;
        n += 1;
    }
    ((s / n.max(1) as f64).sqrt(), n)
}

/// The restitution-parametrised law `name` (as a scene file names it) at restitution `e`.
fn law(name: &str, e: f64) -> LawSpec {
    LawSpec::restitution_law(name, e)
        .expect("LAW: hunt_crossley, lankarani_nikravesh, flores, gonthier or tsuji")
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize| {
        args.get(i)
            .expect("SCENE LAW E RATE_HZ NOISE_COUNTS [N] [SEED]")
    };
    let mut scene = host_sim::scene::load(arg(1)).expect("scene");
    scene.contact = law(arg(2), arg(3).parse().expect("E"));
    scene.sensor.sample_rate_hz = arg(4).parse().expect("RATE_HZ");
    scene.sensor.noise_rms_counts = arg(5).parse().expect("NOISE_COUNTS");
    let n: usize = args.get(6).map_or(2000, |s| s.parse().expect("N"));
    let seed: u64 = args.get(7).map_or(1, |s| s.parse().expect("SEED"));
    let k = scene.classes.len();
    let mut rows = Vec::new();
    for c in 0..k {
        let stream = generate_classes(
            &scene,
            &vec![c; n],
            seed * 1000 + c as u64,
            &StreamOptions::default(),
        )
        .expect("stream");
        rows.extend(rows_of(&scene, &stream, n));
    }
    print_errors(&scene, &rows);
    print_accuracy(&scene, &rows, seed);
}

fn print_errors(scene: &host_sim::scene::SceneFile, rows: &[Row]) {
    println!(
        "| class | samples per pulse | impacts | kernel rms ln F | ln t_c | kernel stated sigma ln F | ln t_c | ML rms ln F | ln t_c | sqrt CRB own phase ln F | ln t_c | sqrt CRB phase-averaged ln F | ln t_c |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for c in 0..scene.classes.len() {
        for (b, lo) in BANDS.iter().enumerate() {
            let rs: Vec<&Row> = rows
                .iter()
                .filter(|r| r.class == c && r.band == b)
                .collect();
            if rs.is_empty() {
                continue;
            }
            let hi = BANDS.get(b + 1).map_or("".to_string(), |h| format!("{h}"));
            let kern: Vec<[f64; 2]> = rs.iter().filter_map(|r| r.kernel).collect();
            let (kf, _) = rms(kern.iter().map(|e| e[0]));
            let (kt, _) = rms(kern.iter().map(|e| e[1]));
            let (sf, _) = rms(rs.iter().map(|r| r.kernel_sigma[0]));
            let (st, _) = rms(rs.iter().map(|r| r.kernel_sigma[1]));
            let (mf, _) = rms(rs.iter().map(|r| r.ml[0]));
            let (mt, _) = rms(rs.iter().map(|r| r.ml[1]));
            let (of, _) = rms(rs.iter().map(|r| r.crb_own[0].sqrt()));
            let (ot, _) = rms(rs.iter().map(|r| r.crb_own[1].sqrt()));
            let (af, _) = rms(rs.iter().map(|r| r.crb_avg[0].sqrt()));
            let (at, _) = rms(rs.iter().map(|r| r.crb_avg[1].sqrt()));
            println!(
                "| {} | {lo}-{hi} | {} | {kf:.4} | {kt:.4} | {sf:.4} | {st:.4} | {mf:.4} | {mt:.4} | {of:.4} | {ot:.4} | {af:.4} | {at:.4} |",
                scene.classes[c].name,
                rs.len()
            );
        }
    }
}

/// The spread of the errors `err` gives, per band `band` gives: the noise a Bayes decision on
/// those errors' features takes.
fn band_noise(
    rows: &[Row],
    err: impl Fn(&Row) -> Option<[f64; 2]>,
    band: impl Fn(&Row) -> usize,
) -> BTreeMap<usize, FeatureNoise> {
    let mut out = BTreeMap::new();
    for b in 0..BANDS.len() {
        let es: Vec<[f64; 2]> = rows
            .iter()
            .filter(|r| band(r) == b)
            .filter_map(&err)
            .collect();
        let (sf, _) = rms(es.iter().map(|e| e[0]));
        let (st, _) = rms(es.iter().map(|e| e[1]));
        let cov = es.iter().map(|e| e[0] * e[1]).sum::<f64>() / es.len().max(1) as f64;
        let corr = if sf > 0.0 && st > 0.0 {
            (cov / (sf * st)).clamp(-0.99, 0.99)
        } else {
            0.0
        };
        out.insert(
            b,
            FeatureNoise {
                sigma_ln_force: sf.max(1e-6),
                sigma_ln_duration: st.max(1e-6),
                correlation: corr,
            },
        );
    }
    out
}

fn print_accuracy(scene: &host_sim::scene::SceneFile, rows: &[Row], seed: u64) {
    let models = class_models(scene);
    let noise = band_noise(rows, |r| Some(r.ml), |r| r.ml_band);
    let kernel_noise = band_noise(rows, |r| r.kernel, |r| r.band);
    let true_n_noise = band_noise(rows, |r| r.kernel_true_n, |r| r.band);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let priors: Vec<f64> = scene.classes.iter().map(|c| c.prior).collect();
    let total: f64 = priors.iter().sum();
    let all = BANDS.len();
    let mut right = vec![[0.0f64; 6]; all + 1];
    let mut count = vec![[0.0f64; 1]; all + 1];
    for r in rows {
        let w = priors[r.class] / total;
        let n_class = rows.iter().filter(|x| x.class == r.class).count() as f64;
        let w = w / n_class;
        let bi = r.band;
        count[bi][0] += w;
        count[all][0] += w;
        let kernel = r.kernel_forced == Some(r.class);
        let kernel_bayes = r.kernel.is_some_and(|e| {
            let nz = kernel_noise[&r.band];
            decide(&models, r.hertz[0] + e[0], r.hertz[1] + e[1], Some(&nz)) == r.class
        });
        let true_n_bayes = r.kernel_true_n.is_some_and(|e| {
            let nz = true_n_noise[&r.band];
            decide(&models, r.hertz[0] + e[0], r.hertz[1] + e[1], Some(&nz)) == r.class
        });
        let nz = noise[&r.ml_band];
        let ml = decide(
            &models,
            r.hertz[0] + r.ml[0],
            r.hertz[1] + r.ml[1],
            Some(&nz),
        ) == r.class;
        let mut crb_draw = |c: [f64; 3]| {
            let (sf, st) = (c[0].sqrt(), c[1].sqrt());
            let rho = (c[2] / (sf * st)).clamp(-0.999, 0.999);
            let z1: f64 = StandardNormal.sample(&mut rng);
            let z2: f64 = StandardNormal.sample(&mut rng);
            let ef = sf * z1;
            let et = st * (rho * z1 + (1.0 - rho * rho).sqrt() * z2);
            let nz = FeatureNoise {
                sigma_ln_force: sf.max(1e-6),
                sigma_ln_duration: st.max(1e-6),
                correlation: rho.clamp(-0.99, 0.99),
            };
            decide(&models, r.hertz[0] + ef, r.hertz[1] + et, Some(&nz)) == r.class
        };
        let own = crb_draw(r.crb_own);
        let avg = crb_draw(r.crb_avg);
        for (j, ok) in [kernel, ml, own, avg, kernel_bayes, true_n_bayes]
            .into_iter()
            .enumerate()
        {
            if ok {
                right[bi][j] += w;
                right[all][j] += w;
            }
        }
    }
    println!();
    println!(
        "| samples per pulse | share of impacts | kernel forced choice | Bayes on the ML fit | Bayes at the CRB, own phase | Bayes at the CRB, phase-averaged | Bayes on the kernel's features | same, its table read at the true n |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for b in 0..=all {
        if count[b][0] == 0.0 {
            continue;
        }
        let name = if b == all {
            "all".to_string()
        } else {
            format!(
                "{}-{}",
                BANDS[b],
                BANDS.get(b + 1).map_or("".into(), |h| h.to_string())
            )
        };
        let c = count[b][0];
        println!(
            "| {name} | {:.1} % | {:.2} % | {:.2} % | {:.2} % | {:.2} % | {:.2} % | {:.2} % |",
            100.0 * c,
            100.0 * right[b][0] / c,
            100.0 * right[b][1] / c,
            100.0 * right[b][2] / c,
            100.0 * right[b][3] / c,
            100.0 * right[b][4] / c,
            100.0 * right[b][5] / c
        );
    }
}
