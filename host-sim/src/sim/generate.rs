//! Labelled stream generation: impacts drawn from a scene's priors (or given by a plan), their
//! contact force from the integrator, through the sensor chain, with the injected faults of
//! [`crate::sim::faults`], and the truth of every impact and fault ([`crate::sim::stream`]).
//!
//! Determinism: one seed gives one stream on every machine. Three independent ChaCha8 streams
//! are derived from it (impacts and timing; sensor noise; faults), so switching a fault on
//! or off does not change the impacts. The impacts are drawn one after another; their pulses are
//! simulated on every core ([`crate::sim::par`]) and taken in order, so nothing depends on the
//! number of threads.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::physics::hertz64::HertzImpact64;
use crate::physics::impact::{ImpactSpec, simulate};
use crate::physics::integrate::SimError;
use crate::scene::SceneFile;
use crate::sim::faults::{QuietFaults, busy_spans, fault_impacts, remove_dropped};
use crate::sim::par::map_ordered;
use crate::sim::sensor::{ForcePulse, ForceTrack, PulseShape, Sensor};
use crate::sim::stream::{
    Clock, ImpactFault, MAX_STREAM_SAMPLES, PulseModel, Stream, StreamError, StreamOptions, Truth,
    opt_err,
};

/// ChaCha8 stream of the impacts and their timing.
const RNG_IMPACTS: u64 = 1;
/// ChaCha8 stream of the sensor noise seed.
const RNG_NOISE: u64 = 2;
/// ChaCha8 stream of the faults.
const RNG_FAULTS: u64 = 3;

/// One impact before simulation.
#[derive(Debug, Clone)]
struct Draw {
    class: usize,
    radius_m: f64,
    speed_m_s: f64,
    start_s: f64,
    hertz: HertzImpact64,
    pileup: bool,
}

/// The closed-form undamped pulse `F_max sin^(3/2)(pi t / t_c)` of an impact (the shape the
/// integrator is replaced by under [`PulseModel::HertzSine`]).
pub fn hertz_sine_pulse(hertz: &HertzImpact64, start_s: f64) -> ForcePulse {
    ForcePulse {
        start_s,
        duration_s: hertz.duration_s,
        scale: 1.0,
        shape: PulseShape::HertzSine {
            peak_force_n: hertz.peak_force_n,
        },
    }
}

/// Makes a stream of `n_impacts` impacts of `scene` from `seed`.
pub fn generate(
    scene: &SceneFile,
    n_impacts: usize,
    seed: u64,
    options: &StreamOptions,
) -> Result<Stream, StreamError> {
    generate_with_progress(scene, n_impacts, seed, options, &mut |_| {})
}

fn rng_for(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(stream);
    r
}

/// [`generate`], calling `progress(done)` after each impact is simulated.
pub fn generate_with_progress(
    scene: &SceneFile,
    n_impacts: usize,
    seed: u64,
    options: &StreamOptions,
    progress: &mut dyn FnMut(usize),
) -> Result<Stream, StreamError> {
    generate_inner(scene, Source::Drawn, n_impacts, seed, options, progress)
}

/// [`generate`] with every impact of class `class` (index in the scene's order) instead of a
/// class drawn from the priors; radius, speed, timing, noise and faults are drawn exactly as
/// [`generate`] draws them. A class index out of range is an option error.
pub fn generate_class(
    scene: &SceneFile,
    class: usize,
    n_impacts: usize,
    seed: u64,
    options: &StreamOptions,
) -> Result<Stream, StreamError> {
    generate_classes(scene, &vec![class; n_impacts], seed, options)
}

/// [`generate`] with impact `i` of class `classes[i]` (indices in the scene's order) instead
/// of a class drawn from the priors; radius, speed, timing, noise and faults are drawn exactly
/// as [`generate`] draws them, so `[c; n]` gives [`generate_class`]'s stream. A class index out
/// of range is an option error.
pub fn generate_classes(
    scene: &SceneFile,
    classes: &[usize],
    seed: u64,
    options: &StreamOptions,
) -> Result<Stream, StreamError> {
    if let Some(&class) = classes.iter().find(|&&c| c >= scene.classes.len()) {
        return Err(opt_err(
            "class",
            format!(
                "must be a class index below {} (got {class})",
                scene.classes.len()
            ),
        ));
    }
    generate_inner(
        scene,
        Source::Classes(classes),
        classes.len(),
        seed,
        options,
        &mut |_| {},
    )
}

/// One impact of a given class, size, speed and time (see [`generate_planned`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannedImpact {
    /// Index of the class in the scene.
    pub class: usize,
    /// Sphere radius in m.
    pub radius_m: f64,
    /// Impact speed in m/s.
    pub speed_m_s: f64,
    /// First contact in s after the lead-in (`options.lead_in_s`); impacts that start while
    /// the previous one is on are marked as pile-ups.
    pub start_s: f64,
}

/// A stream of the impacts of `plan` (class, radius, speed and start time given), through the
/// scene's contact law and sensor chain, with `seed` for the sample phase, the noise and the
/// faults; `options.gap_s` and `pileup_share` are not used.
pub fn generate_planned(
    scene: &SceneFile,
    plan: &[PlannedImpact],
    seed: u64,
    options: &StreamOptions,
) -> Result<Stream, StreamError> {
    for (i, p) in plan.iter().enumerate() {
        if p.class >= scene.classes.len() {
            return Err(opt_err(
                "plan.class",
                format!("impact {i}: no class {}", p.class),
            ));
        }
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !(ok(p.radius_m) && ok(p.speed_m_s) && p.start_s.is_finite() && p.start_s >= 0.0) {
            return Err(opt_err(
                "plan",
                format!("impact {i}: radius and speed must be > 0, start >= 0"),
            ));
        }
    }
    generate_inner(
        scene,
        Source::Plan(plan),
        plan.len(),
        seed,
        options,
        &mut |_| {},
    )
}

/// Where a stream's impacts come from.
#[derive(Clone, Copy)]
enum Source<'a> {
    /// Drawn from the scene's priors.
    Drawn,
    /// Impact `i` of class `classes[i]`, its size and speed drawn.
    Classes(&'a [usize]),
    /// Given impact by impact.
    Plan(&'a [PlannedImpact]),
}

/// The stream of `n_impacts` impacts from `source`, in seven phases: impacts and timing, force
/// pulses, faults on impacts, time line length, sensor, faults between pulses, dropped samples.
fn generate_inner(
    scene: &SceneFile,
    source: Source<'_>,
    n_impacts: usize,
    seed: u64,
    options: &StreamOptions,
    progress: &mut dyn FnMut(usize),
) -> Result<Stream, StreamError> {
    scene.validate()?;
    options.validate()?;
    let faults = &options.faults;
    let mut sensor_spec = scene.sensor.clone();
    sensor_spec.dc_drift_counts_per_s += faults.drift_counts_per_s;
    let sensor = Sensor::new(&sensor_spec)?;
    let fs = sensor.sample_rate_hz();
    let mut rng = rng_for(seed, RNG_IMPACTS);
    let clock = Clock {
        fs,
        phase_s: rng.random::<f64>() / fs,
    };
    // 1. Impacts and timing.
    let draws = draw_impacts(scene, source, n_impacts, options, &mut rng, clock)?;
    // 2. Force pulses.
    let fine_step_s = if sensor.is_rigid() {
        f64::INFINITY
    } else {
        1.0 / (fs * sensor_spec.oversample as f64)
    };
    let (mut pulses, mut truth) =
        simulate_pulses(scene, &draws, options, fine_step_s, clock, progress)?;
    // 3. Faults on impacts (drawn for every impact, so the draws do not depend on the shares).
    let mut frng = rng_for(seed, RNG_FAULTS);
    fault_impacts(&mut truth, &mut pulses, faults, &sensor, &mut frng);
    // 4. Time line length.
    let timeline = timeline_samples(&pulses, &truth, options, clock)?;
    // 5. Sensor.
    let noise_seed = rng_for(seed, RNG_NOISE).random::<u64>();
    let track = ForceTrack::new(pulses);
    let mut samples = sensor.sample(&track, timeline as usize, clock.phase_s, noise_seed);
    // 6. Faults between pulses and drops inside pulses.
    let mut quiet = QuietFaults::new(faults, &sensor, timeline);
    quiet.drop_in_pulses(&truth, clock, &mut frng);
    quiet.place_between_pulses(&busy_spans(&truth, clock), &mut samples, &mut frng);
    // 7. Remove the dropped samples.
    let (kept, gaps) = remove_dropped(&samples, quiet.drops, timeline);
    Ok(Stream {
        sample_rate_hz: fs,
        phase_s: clock.phase_s,
        class_names: scene.classes.iter().map(|c| c.name.clone()).collect(),
        samples: kept,
        timeline_samples: timeline,
        truth,
        gaps,
        events: quiet.events,
    })
}

/// The class, radius (m) and speed (m/s) of an impact drawn from the scene's priors with the
/// uniform draws `r = [class, radius, speed]`: the class by its prior (or `fixed_class`), the
/// radius log-uniform and the speed (or drop height) uniform in the class's ranges.
fn draw_class_size_speed(
    scene: &SceneFile,
    fixed_class: Option<usize>,
    [r_class, r_radius, r_speed]: [f64; 3],
) -> (usize, f64, f64) {
    let probs = scene.class_probabilities();
    let mut acc = 0.0;
    let class = fixed_class.unwrap_or_else(|| {
        probs
            .iter()
            .position(|p| {
                acc += p;
                r_class < acc
            })
            .unwrap_or(probs.len() - 1)
    });
    let (radius_m, speed_m_s) = scene.classes[class].at_quantiles(r_radius, r_speed);
    (class, radius_m, speed_m_s)
}

/// What decides an impact's first contact: whether it is the first, when the impacts before
/// it are over (s), its planned start (s, on the stream's clock) if any, and its uniform
/// draws for a pile-up, the gap and the pile-up's offset.
struct Start {
    first: bool,
    busy_until: f64,
    planned_s: Option<f64>,
    uniforms: [f64; 3],
}

impl Start {
    /// The first contact in s and whether the impact piles up on `prev`: the planned start
    /// (a pile-up if the previous impact is still on), or a pile-up at `pileup_offset_tc` of
    /// the previous contact time with probability `pileup_share`, or the end of the previous
    /// impacts plus a gap uniform in `gap_s`.
    fn of(&self, prev: Option<&Draw>, options: &StreamOptions) -> (f64, bool) {
        let [r_pile, r_gap, r_offset] = self.uniforms;
        match (self.planned_s, prev) {
            (Some(start_s), _) => (start_s, start_s < self.busy_until && !self.first),
            (None, Some(prev)) if !self.first && r_pile < options.pileup_share => {
                let [a, b] = options.pileup_offset_tc;
                let offset_s = (a + r_offset * (b - a)) * prev.hertz.duration_s;
                (prev.start_s + offset_s, true)
            }
            (None, _) => {
                let [a, b] = options.gap_s;
                let gap_s = if self.first { 0.0 } else { a + r_gap * (b - a) };
                (self.busy_until + gap_s, false)
            }
        }
    }
}

/// Phase 1: every impact's class, size, speed and first contact, in order; an impact that
/// starts while the one before is on marks both as a pile-up. Six uniform draws per impact,
/// whatever its source, so the stream's other draws do not depend on the source.
fn draw_impacts(
    scene: &SceneFile,
    source: Source<'_>,
    n_impacts: usize,
    options: &StreamOptions,
    rng: &mut ChaCha8Rng,
    clock: Clock,
) -> Result<Vec<Draw>, StreamError> {
    let plate = scene.plate.material();
    let mut draws: Vec<Draw> = Vec::with_capacity(n_impacts.min(1 << 16));
    let mut busy_until = clock.phase_s + options.lead_in_s;
    for i in 0..n_impacts {
        let (r_class, r_radius, r_speed): (f64, f64, f64) =
            (rng.random(), rng.random(), rng.random());
        let (r_pile, r_gap, r_offset): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
        let (planned, fixed_class) = match source {
            Source::Plan(plan) => (plan.get(i), None),
            Source::Drawn => (None, None),
            Source::Classes(classes) => (None, classes.get(i).copied()),
        };
        let (class, radius_m, speed_m_s) = match planned {
            Some(p) => (p.class, p.radius_m, p.speed_m_s),
            None => draw_class_size_speed(scene, fixed_class, [r_class, r_radius, r_speed]),
        };
        let material = scene.classes[class].material.material();
        let hertz =
            HertzImpact64::new(&material, &plate, radius_m, speed_m_s).map_err(|error| {
                StreamError::Simulation {
                    impact: i,
                    radius_m,
                    speed_m_s,
                    error,
                }
            })?;
        let start = Start {
            first: i == 0,
            busy_until,
            planned_s: planned.map(|p| clock.phase_s + options.lead_in_s + p.start_s),
            uniforms: [r_pile, r_gap, r_offset],
        };
        let (start_s, pileup) = start.of(draws.last(), options);
        if let (true, Some(prev)) = (pileup, draws.last_mut()) {
            prev.pileup = true;
        }
        busy_until = busy_until.max(start_s + hertz.duration_s);
        let so_far = clock.samples_to(busy_until).ceil();
        if planned.is_none() && (so_far.is_nan() || so_far > MAX_STREAM_SAMPLES as f64) {
            return Err(StreamError::TooLong(so_far.min(u64::MAX as f64) as u64));
        }
        draws.push(Draw {
            class,
            radius_m,
            speed_m_s,
            start_s,
            hertz,
            pileup,
        });
    }
    Ok(draws)
}

/// Phase 2: each impact's force pulse and truth. A pulse depends on its draw only: simulated on
/// every core, taken in order (`progress(done)` after each).
fn simulate_pulses(
    scene: &SceneFile,
    draws: &[Draw],
    options: &StreamOptions,
    fine_step_s: f64,
    clock: Clock,
    progress: &mut dyn FnMut(usize),
) -> Result<(Vec<ForcePulse>, Vec<Truth>), StreamError> {
    let mut pulses = Vec::with_capacity(draws.len());
    let mut truth = Vec::with_capacity(draws.len());
    let make_pulse = |i: usize, d: &Draw| match options.pulse_model {
        PulseModel::HertzSine => Ok((
            hertz_sine_pulse(&d.hertz, d.start_s),
            0.5 * d.hertz.duration_s,
            d.hertz.peak_force_n,
            d.hertz.duration_s,
        )),
        PulseModel::Integrator => simulate_pulse(scene, d, options, fine_step_s).map_err(|error| {
            StreamError::Simulation {
                impact: i,
                radius_m: d.radius_m,
                speed_m_s: d.speed_m_s,
                error,
            }
        }),
    };
    map_ordered(draws, make_pulse, |i, made| {
        let d = &draws[i];
        let (pulse, peak_tau_s, peak_force_n, duration_s) = made?;
        let peak_time_s = d.start_s + peak_tau_s;
        truth.push(Truth {
            class: d.class,
            radius_m: d.radius_m,
            speed_m_s: d.speed_m_s,
            time_s: d.start_s,
            peak_time_s,
            peak_sample: clock.samples_to(peak_time_s).round().max(0.0) as u64,
            peak_force_n,
            duration_s,
            scale: 1.0,
            fault: if d.pileup {
                ImpactFault::PileUp
            } else {
                ImpactFault::None
            },
        });
        pulses.push(pulse);
        progress(i + 1);
        Ok::<(), StreamError>(())
    })?;
    Ok((pulses, truth))
}

/// Phase 4: samples of the time line, from sample 0 to `tail_s` after the last pulse ends (or
/// through the last impact's peak when the stream ends inside it).
fn timeline_samples(
    pulses: &[ForcePulse],
    truth: &[Truth],
    options: &StreamOptions,
    clock: Clock,
) -> Result<u64, StreamError> {
    let end_s = pulses
        .iter()
        .map(|p| p.start_s + p.duration_s)
        .fold(clock.phase_s + options.lead_in_s, f64::max)
        + options.tail_s;
    let mut timeline = clock.samples_to(end_s).ceil().max(1.0) as u64;
    if let (true, Some(t)) = (options.faults.end_mid_pulse, truth.last()) {
        timeline = timeline.min(t.peak_sample + 1);
    }
    if timeline > MAX_STREAM_SAMPLES {
        return Err(StreamError::TooLong(timeline));
    }
    Ok(timeline)
}

/// Simulates one impact: `(pulse, time of peak after first contact in s, peak force in N,
/// force pulse duration in s)`.
fn simulate_pulse(
    scene: &SceneFile,
    d: &Draw,
    options: &StreamOptions,
    fine_step_s: f64,
) -> Result<(ForcePulse, f64, f64, f64), SimError> {
    let c = &scene.classes[d.class];
    let mut spec = ImpactSpec::new(
        c.material.material(),
        scene.plate.material(),
        d.radius_m,
        d.speed_m_s,
    );
    spec.law = scene.class_law(d.class)?;
    let step_s = (d.hertz.duration_s / options.record_points_per_pulse as f64).min(fine_step_s);
    spec.record = Some(step_s);
    let report = simulate(&spec)?;
    let force_n: Vec<f64> = report
        .force_series
        .unwrap_or_default()
        .into_iter()
        .map(|(_, f)| f)
        .collect();
    // Peak time: the largest recorded point, refined by a parabola through its neighbours.
    let (k, _) = force_n
        .iter()
        .enumerate()
        .fold((0, f64::NEG_INFINITY), |best, (i, &f)| {
            if f > best.1 { (i, f) } else { best }
        });
    let mut peak_tau = k as f64 * step_s;
    if let (Some(&a), Some(&b), Some(&c)) = (
        k.checked_sub(1).and_then(|j| force_n.get(j)),
        force_n.get(k),
        force_n.get(k + 1),
    ) {
        let curv = a - 2.0 * b + c;
        if curv < 0.0 {
            peak_tau += 0.5 * (a - c) / curv * step_s;
        }
    }
    let pulse = ForcePulse {
        start_s: d.start_s,
        duration_s: report.duration_s,
        scale: 1.0,
        shape: PulseShape::Series { step_s, force_n },
    };
    Ok((
        pulse,
        peak_tau,
        report.peak_force_n,
        report.pulse_duration_s,
    ))
}
