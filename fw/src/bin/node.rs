//! The coalshock kernel on a Cortex-M4F node (STM32F405 class, QEMU `netduinoplus2`).
//!
//! The firmware replays the sample stream `fw/data/paper_stream.bin` that host-sim made
//! from the paper scene (`fw/stream.sh`: little-endian i16 ADC counts at 100 kS/s, with the
//! dropped samples of `paper_stream.truth.csv` reported through `Monitor::gap` at their place)
//! through the kernel and exits through semihosting (status 0 when everything ran and agreed,
//! 1 otherwise):
//!
//! 1. two measuring passes, one per math backend (`Libm`, `Micromath`): the paper scene is
//!    built, then every `feed` is timed with SysTick (deterministic under QEMU's
//!    `-icount shift=0`: one instruction per virtual nanosecond, calibrated against a counted
//!    loop) and the stack below the caller is painted and scanned; no logging;
//!    Each pass also times quiet blocks through `Monitor::feed_slice` on the paper scene and
//!    on the chain scene of `scenes/piezo_chain.toml` (three beam modes and an accelerometer
//!    stage, equalised before detection);
//! 2. a logging pass with the default backend: one line per event (pulse verdict or stuck
//!    sensor) and the counters;
//! 3. the chain scene's stream (`fw/data/chain_stream.bin`) through a monitor on the chain
//!    scene, in `feed_slice` blocks between its recorded gaps as host-sim replays it, every
//!    line after the prefix `chain `; then the `measure` lines (`fw/README.md` defines every
//!    key).
//!
//! Output lines (defmt, decoded on the host by `defmt-print --log-format {s}`):
//!
//! ```text
//! pulse <n> at=<sample> <class|ambiguous|out[:sides]|rejected> <class or reason> p_ppm=<u32> F_mN=<u32> t_ns=<u32>
//! stuck at=<sample>
//! classified <class> <count>
//! rejected <reason> <count>
//! counters samples=.. pulses=.. ambiguous=.. out=.. rejected=.. stuck=.. gaps=.. lost=.. balanced=<0|1>
//! backend <default backend>
//! measure <key> <value>
//! ```
//!
//! Run: `cargo run --release --bin node` in `fw/` (runner `fw/run.sh`). On the host,
//! `cargo run -p host-sim --example node_replay` has host-sim read the same stream
//! files and replay them through the same kernel, and prints the same
//! `pulse`/`stuck`/`classified`/`rejected`/`counters` lines, which `fw/ci.sh` compares with the
//! emulated node's line by line (plus a `truth` line, host only: the verdicts against the
//! stream's truth). The `front_end` binary feeds the same stream through the IIS3DWB driver.
#![no_std]
#![no_main]

use coalshock::RejectReason;
use coalshock::flow::{FlowConfig, FlowMonitor, FlowStatus};
use coalshock::math::{Backend, DefaultBackend, Libm, Micromath};
use coalshock::scene::DEFAULT_CLASSES;
use coalshock::{Counters, Detector, Event, Monitor, Scene, Verdict};
use coalshock_fw::exit;
use coalshock_node_rt as rt;
use coalshock_replay::{
    CHAIN, CounterLine, Input, PulseLine, Stream, build_chain_scene, build_scene, inputs,
};
use core::hint::black_box;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::{SCB, SYST, syst::SystClkSource};
use cortex_m_rt::{entry, exception};

/// SysTick value (counts down, 24 bits).
#[inline(always)]
fn now() -> u32 {
    SYST::get_current()
}

/// SysTick reload value: the counter runs `RELOAD..=0`, a period of 2^24 ticks.
const RELOAD: u32 = 0x00FF_FFFF;

/// SysTick periods completed (for regions longer than one period, e.g. the scene build).
static WRAPS: AtomicU32 = AtomicU32::new(0);

#[exception]
fn SysTick() {
    // Load and store only: thumbv6m has no atomic read-modify-write, and nothing else
    // writes this counter.
    WRAPS.store(
        WRAPS.load(Ordering::Relaxed).wrapping_add(1),
        Ordering::Relaxed,
    );
}

/// Ticks since the timer started, 64 bits wide (any region length).
#[inline(never)]
fn stamp() -> u64 {
    loop {
        let w1 = WRAPS.load(Ordering::Relaxed);
        let v = now();
        let pending = SCB::is_pendst_pending();
        let w2 = WRAPS.load(Ordering::Relaxed);
        if w1 != w2 {
            continue;
        }
        // Wrapped but the handler has not run yet: the low value belongs to the next period.
        let periods = w1 as u64 + (pending && v > RELOAD / 2) as u64;
        return periods * (RELOAD as u64 + 1) + (RELOAD - v) as u64;
    }
}

/// Ticks from `t0` to `t1` (two `now()` values less than one period apart).
#[inline(always)]
fn elapsed(t0: u32, t1: u32) -> u32 {
    t0.wrapping_sub(t1) & 0x00FF_FFFF
}

/// Ticks to instructions: `ticks * cal_insns / cal_ticks`, rounded.
struct Clock {
    cal_insns: u64,
    cal_ticks: u64,
    /// Ticks of an empty timed region (two SysTick reads).
    overhead_ticks: u64,
}

impl Clock {
    /// Times `cortex_m::asm::delay(n)` for two `n`: the difference is exactly
    /// `2 (n2 - n1)` instructions (a `subs`/`bne` loop), whatever the call costs.
    fn calibrate() -> Self {
        const N1: u32 = 20_000;
        const N2: u32 = 120_000;
        let t = |n: u32| {
            let t0 = stamp();
            cortex_m::asm::delay(black_box(n));
            stamp() - t0
        };
        let (a, b) = (t(N1), t(N2));
        let mut empty = 0u64;
        for _ in 0..256 {
            let t0 = now();
            let t1 = now();
            empty += elapsed(t0, t1) as u64;
        }
        Self {
            cal_insns: 2 * (N2 - N1) as u64,
            cal_ticks: b.saturating_sub(a).max(1),
            overhead_ticks: empty,
        }
    }

    /// Instructions in `ticks` ticks spread over `regions` timed regions (the timer-read
    /// overhead of each region is taken off).
    fn insns(&self, ticks: u64, regions: u64) -> u64 {
        let overhead = self.overhead_ticks * regions / 256;
        let t = ticks.saturating_sub(overhead);
        // cal_ticks >= 1 by construction; checked_div keeps the image free of panic paths.
        (t * self.cal_insns + self.cal_ticks / 2)
            .checked_div(self.cal_ticks)
            .unwrap_or(0)
    }
}

/// Sum, count and maximum of timed regions (ticks).
#[derive(Default, Clone, Copy)]
struct Stat {
    sum: u64,
    n: u64,
    max: u32,
}

impl Stat {
    fn add(&mut self, ticks: u32) {
        self.sum += ticks as u64;
        self.n += 1;
        self.max = self.max.max(ticks);
    }
    fn mean(&self, clock: &Clock) -> u64 {
        clock
            .insns(self.sum, self.n)
            .checked_div(self.n)
            .unwrap_or(0)
    }
    fn max(&self, clock: &Clock) -> u64 {
        clock.insns(self.max as u64, 1)
    }
}

/// One sample through the kernel (not inlined, so it is timed alone).
#[inline(never)]
fn step<M: Backend>(m: &mut Monitor<DEFAULT_CLASSES, M>, sample: i32) -> Option<Event> {
    m.feed(black_box(sample))
}

/// A block of samples through the kernel's block entry (as a FIFO read would), counting
/// events.
#[inline(never)]
fn step_block<M: Backend>(m: &mut Monitor<DEFAULT_CLASSES, M>, block: &[i16]) -> u32 {
    let mut events = 0u32;
    m.feed_slice(black_box(block), |_| events += 1);
    events
}

/// Times quiet samples fed in blocks of `QUIET_BLOCK` (deterministic +-6 count noise from
/// an LCG): the block entry's cost per sample, call overhead spread over the block.
#[inline(never)]
fn quiet_blocks<M: Backend>(scene: Scene<DEFAULT_CLASSES, M>) -> (Stat, u32) {
    const QUIET_BLOCK: usize = 256;
    let mut monitor = Monitor::new(scene);
    let mut block = [0i16; QUIET_BLOCK];
    let mut lcg = 12_345u32;
    let mut stat = Stat::default();
    let mut events = 0u32;
    for round in 0..32 {
        for v in block.iter_mut() {
            lcg = lcg.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            *v = ((lcg >> 24) % 13) as i16 - 6;
        }
        let t0 = now();
        events += step_block(&mut monitor, &block);
        let t = elapsed(t0, now());
        // The first round primes the baseline: not counted.
        if round > 0 {
            stat.sum += t as u64;
            stat.n += QUIET_BLOCK as u64;
            stat.max = stat.max.max(t);
        }
    }
    (stat, events)
}

#[inline(never)]
fn gap<M: Backend>(m: &mut Monitor<DEFAULT_CLASSES, M>, lost: u32) -> Option<Event> {
    m.gap(lost)
}

#[inline(never)]
fn finish<M: Backend>(m: &mut Monitor<DEFAULT_CLASSES, M>) -> Option<Event> {
    m.finish()
}

/// One pulse through the flow monitor, as `Monitor::with_flow` does it after classifying:
/// `FlowMonitor::record`, then the status its `Flow` event carries (timed alone).
#[inline(never)]
fn flow_record<M: Backend>(
    flow: &mut FlowMonitor<M>,
    verdict: &Verdict,
    lls: Option<&[f32]>,
) -> FlowStatus {
    flow.record(black_box(verdict), black_box(lls));
    flow.status()
}

/// Times the flow monitor's work on one reported pulse: its class log-likelihoods computed
/// first (untimed), then [`flow_record`].
fn time_flow<M: Backend>(
    flow: &mut FlowMonitor<M>,
    scene: &Scene<DEFAULT_CLASSES, M>,
    e: &Event,
) -> Option<u32> {
    let Event::Pulse(r) = e else { return None };
    let (verdict, lls) = match r.measurement {
        Some(m) => scene.classify_with_likelihoods(&m),
        None => (r.verdict, None),
    };
    let t0 = now();
    black_box(flow_record(
        flow,
        &verdict,
        lls.as_ref().map(|l| l.as_slice()),
    ));
    Some(elapsed(t0, now()))
}

#[inline(never)]
fn new_monitor<M: Backend>(scene: Scene<DEFAULT_CLASSES, M>) -> Monitor<DEFAULT_CLASSES, M> {
    Monitor::new(scene)
}

/// FNV-1a over the verdicts (sample index, kind, class or reason): equal hashes mean the
/// same verdict sequence, whatever the posteriors' last bits.
fn hash_verdict(h: u32, at: u64, v: &Verdict) -> u32 {
    let (kind, which) = match *v {
        Verdict::Class { class, .. } => (1u8, class),
        Verdict::Ambiguous { best, .. } => (2, best),
        Verdict::OutOfEnvelope { nearest, .. } => (3, nearest),
        Verdict::Rejected(r) => (4, r.index() as u8),
    };
    let mut h = h;
    for b in (at as u32).to_le_bytes().into_iter().chain([kind, which]) {
        h = (h ^ b as u32).wrapping_mul(0x0100_0193);
    }
    h
}

/// What one measured pass over the stream gives, in ticks and bytes.
struct Figures {
    scene_ticks: u64,
    stack_scene: usize,
    stack_new: usize,
    stack_feed: usize,
    lowest: usize,
    quiet: Stat,
    quiet_block: Stat,
    quiet_block_events: u32,
    inside: Stat,
    end_class: Stat,
    end_reject: Stat,
    whole: Stat,
    finish_ticks: u32,
    counters: Counters<DEFAULT_CLASSES>,
    verdicts: u32,
}

/// A scene the node measures and the stream it replays through it.
trait Measured {
    /// The scene with backend `M`.
    fn build<M: Backend>() -> Result<Scene<DEFAULT_CLASSES, M>, coalshock::Error>;
    /// The stream: every stored sample, each recorded gap at its place.
    fn inputs() -> impl Iterator<Item = Input>;
}

/// The paper scene (`scenes/paper.toml`) and its stream (`fw/data/paper_stream.*`).
struct Paper;

impl Measured for Paper {
    fn build<M: Backend>() -> Result<Scene<DEFAULT_CLASSES, M>, coalshock::Error> {
        build_scene::<M>()
    }
    fn inputs() -> impl Iterator<Item = Input> {
        inputs()
    }
}

/// The yielding scene (`scenes/paper_yield.toml`: the paper's classes with Thornton's
/// elastic-plastic contact) and its stream (`fw/data/yield_stream.*`); feature `plasticity`.
#[cfg(feature = "plasticity")]
struct Yielding;

#[cfg(feature = "plasticity")]
impl Measured for Yielding {
    fn build<M: Backend>() -> Result<Scene<DEFAULT_CLASSES, M>, coalshock::Error> {
        coalshock_replay::build_yield_scene::<M>()
    }
    fn inputs() -> impl Iterator<Item = Input> {
        coalshock_replay::YIELD.inputs()
    }
}

/// The yielding scene with the default backend (feature `plasticity`): a measuring pass over
/// its stream (its figures reported with the prefix `yield_`), then a logging pass (every
/// line after the prefix `yield `), one `feed` per sample as for the paper stream. Also
/// reports `yield_table_class_bytes`, the RAM a class's yield table adds to its envelope
/// (`size_of::<Option<RatioMap>>()`), and whether every pulse was counted once. Returns
/// whether both passes gave the same counters, and the lowest stack address touched.
#[cfg(feature = "plasticity")]
#[inline(never)]
fn yield_pass(clock: &Clock) -> (bool, usize) {
    let Some((f, scene)) = measured_pass::<Yielding, DefaultBackend>() else {
        refused()
    };
    let (counters, _) = replay_logged("yield ", Monitor::new(scene), Yielding::inputs());
    report("yield_", &f, clock);
    let measure = |key: &str, value: u64| defmt::println!("measure {=str} {=u64}", key, value);
    measure(
        "yield_table_class_bytes",
        core::mem::size_of::<Option<coalshock::ratio_map::RatioMap>>() as u64,
    );
    measure("yield_counters_balanced", counters.balanced() as u64);
    (counters == f.counters, f.lowest.min(rt::lowest_touched()))
}

/// Builds the scene `S` with backend `M` and feeds the whole of its stream through a monitor,
/// timing every call and measuring the stack below this function of each phase. No
/// logging. Returns the figures and the scene (for the logging pass).
#[inline(never)]
fn measured_pass<S: Measured, M: Backend>() -> Option<(Figures, Scene<DEFAULT_CLASSES, M>)> {
    let mut lowest = rt::lowest_touched();

    // Scene build.
    let base = rt::paint();
    let t0 = stamp();
    let built = S::build::<M>();
    let scene_ticks = stamp() - t0;
    let stack_scene = rt::used_since(base);
    lowest = lowest.min(rt::lowest_touched());
    let scene = built.ok()?;

    // Monitor (detector + counters) from the scene.
    let base = rt::paint();
    let mut monitor = new_monitor(scene.clone());
    let stack_new = rt::used_since(base);
    lowest = lowest.min(rt::lowest_touched());

    // Every sample, timed alone.
    let (mut quiet, mut inside, mut end_class, mut end_reject, mut whole) = (
        Stat::default(),
        Stat::default(),
        Stat::default(),
        Stat::default(),
        Stat::default(),
    );
    let mut current = 0u32;
    let mut verdicts = 0x811C_9DC5u32;
    let base = rt::paint();
    for input in S::inputs() {
        let s = match input {
            Input::Sample(s) => s,
            Input::Gap(lost) => {
                // A recorded gap (not timed): a pulse in progress is rejected.
                if let Some(Event::Pulse(r)) = gap(&mut monitor, lost) {
                    verdicts = hash_verdict(verdicts, r.at_sample, &r.verdict);
                    current = 0;
                }
                continue;
            }
        };
        let was_active = monitor.detector().in_pulse();
        let t0 = now();
        let ev = step(&mut monitor, s);
        let t = elapsed(t0, now());
        let active = monitor.detector().in_pulse();
        match ev {
            Some(Event::Pulse(r)) => {
                current += t;
                verdicts = hash_verdict(verdicts, r.at_sample, &r.verdict);
                if matches!(r.verdict, Verdict::Rejected(_)) {
                    end_reject.add(t);
                } else {
                    end_class.add(t);
                    whole.add(current);
                }
                current = 0;
            }
            _ if !was_active && !active => quiet.add(t),
            _ => {
                inside.add(t);
                current += t;
            }
        }
    }
    let t0 = now();
    let last = finish(&mut monitor);
    let finish_ticks = elapsed(t0, now());
    if let Some(Event::Pulse(r)) = last {
        verdicts = hash_verdict(verdicts, r.at_sample, &r.verdict);
    }
    let stack_feed = rt::used_since(base);
    lowest = lowest.min(rt::lowest_touched());
    let (quiet_block, quiet_block_events) = quiet_blocks(scene.clone());
    let figures = Figures {
        scene_ticks,
        stack_scene,
        stack_new,
        stack_feed,
        lowest,
        quiet,
        quiet_block,
        quiet_block_events,
        inside,
        end_class,
        end_reject,
        whole,
        finish_ticks,
        counters: *monitor.counters(),
        verdicts,
    };
    Some((figures, scene))
}

/// The `measure` lines of one backend's pass; `prefix` is "" for the default backend.
fn report(prefix: &str, f: &Figures, clock: &Clock) {
    let m = |key: &str, value: u64| {
        defmt::println!("measure {=str}{=str} {=u64}", prefix, key, value);
    };
    m("stack_scene_bytes", f.stack_scene as u64);
    m("stack_monitor_new_bytes", f.stack_new as u64);
    m("stack_feed_bytes", f.stack_feed as u64);
    m(
        "stack_kernel_bytes",
        f.stack_scene.max(f.stack_new).max(f.stack_feed) as u64,
    );
    m("insns_scene_build", clock.insns(f.scene_ticks, 1));
    m(
        "samples",
        f.quiet.n + f.inside.n + f.end_class.n + f.end_reject.n,
    );
    m("quiet_samples", f.quiet.n);
    m("insns_quiet_sample_mean", f.quiet.mean(clock));
    m("insns_quiet_sample_max", f.quiet.max(clock));
    // Block entry: the timer-read overhead is taken off once per block, then the ticks are
    // spread over the block's samples.
    m(
        "insns_quiet_block_sample_mean",
        clock
            .insns(f.quiet_block.sum, f.quiet_block.n / 256)
            .checked_div(f.quiet_block.n)
            .unwrap_or(0),
    );
    m("quiet_block_events", f.quiet_block_events as u64);
    m("pulse_samples", f.inside.n);
    m("insns_pulse_sample_mean", f.inside.mean(clock));
    m("insns_pulse_sample_max", f.inside.max(clock));
    m("classified_pulses", f.end_class.n);
    m("insns_classify_mean", f.end_class.mean(clock));
    m("insns_classify_max", f.end_class.max(clock));
    m("insns_pulse_total_mean", f.whole.mean(clock));
    m("insns_pulse_total_max", f.whole.max(clock));
    m("rejected_pulses", f.end_reject.n);
    m("insns_reject_max", f.end_reject.max(clock));
    m("insns_finish", clock.insns(f.finish_ticks as u64, 1));
}

fn log_event<M: Backend>(prefix: &str, n: u32, e: &Event, scene: &Scene<DEFAULT_CLASSES, M>) {
    match e {
        Event::Pulse(r) => {
            let l = PulseLine::new(r, scene.classes());
            defmt::println!(
                "{=str}pulse {=u32} at={=u64} {=str} {=str} p_ppm={=u32} F_mN={=u32} t_ns={=u32}",
                prefix,
                n,
                l.at,
                l.kind,
                l.who,
                l.posterior_ppm,
                l.force_mn,
                l.duration_ns
            );
        }
        Event::Stuck { at_sample } => {
            defmt::println!("{=str}stuck at={=u64}", prefix, at_sample)
        }
        Event::Flow(f) => defmt::println!(
            "{=str}flow pulses={=u32} share_ppm={=u32} alarm={=bool}",
            prefix,
            f.pulses,
            (f.share * 1e6) as u32,
            f.alarm
        ),
    }
}

fn log_counters<M: Backend>(prefix: &str, m: &Monitor<DEFAULT_CLASSES, M>) {
    let c = m.counters();
    for (class, count) in m.scene().classes().iter().zip(c.classified.iter()) {
        defmt::println!(
            "{=str}classified {=str} {=u32}",
            prefix,
            class.name.as_str(),
            count
        );
    }
    for reason in RejectReason::ALL {
        defmt::println!(
            "{=str}rejected {=str} {=u32}",
            prefix,
            reason.name(),
            c.rejected_for(reason)
        );
    }
    coalshock_fw::log_counters(prefix, &CounterLine::new(c));
}

fn refused() -> ! {
    // No core::fmt on the node: the host replay (`cargo run -p host-sim --example node_replay`) builds the
    // same scene and prints the error.
    defmt::println!("error scene: the paper or chain scene was refused");
    exit(false)
}

#[entry]
fn main() -> ! {
    let Some(mut cp) = cortex_m::Peripherals::take() else {
        exit(false)
    };
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(RELOAD);
    cp.SYST.clear_current();
    cp.SYST.enable_interrupt();
    cp.SYST.enable_counter();
    let clock = Clock::calibrate();

    // Measuring passes, one per math backend; the default backend's figures are the
    // unprefixed ones the budgets apply to.
    let Some((libm, libm_scene)) = measured_pass::<Paper, Libm>() else {
        refused()
    };
    let Some((micro, micro_scene)) = measured_pass::<Paper, Micromath>() else {
        refused()
    };
    let default_is_libm = DefaultBackend::NAME == Libm::NAME;
    let default = if default_is_libm { &libm } else { &micro };

    // Logging pass with the default backend: one line per event, then the counters.
    let (same, flow) = if default_is_libm {
        log_pass(Monitor::new(libm_scene), &default.counters)
    } else {
        log_pass(Monitor::new(micro_scene), &default.counters)
    };

    // The chain scene (default backend): its build and quiet blocks timed, then its stream,
    // logged with the prefix `chain `.
    let base = rt::paint();
    let t0 = stamp();
    let built = build_chain_scene::<DefaultBackend>();
    let chain_scene_ticks = stamp() - t0;
    let stack_chain_scene = rt::used_since(base);
    let Ok(chain_scene) = built else { refused() };
    let (chain_quiet, chain_quiet_events) = quiet_blocks(chain_scene.clone());
    let chain = chain_pass(&CHAIN, chain_scene);
    // The yielding scene (feature `plasticity`): measured, then logged with the prefix `yield `.
    #[cfg(feature = "plasticity")]
    let (yield_same, yield_lowest) = yield_pass(&clock);
    #[cfg(not(feature = "plasticity"))]
    let (yield_same, yield_lowest) = (true, usize::MAX);

    let measure = |key: &str, value: u64| defmt::println!("measure {=str} {=u64}", key, value);
    defmt::println!("backend {=str}", DefaultBackend::NAME);
    measure(
        "kernel_ram_bytes",
        core::mem::size_of::<Monitor<DEFAULT_CLASSES, DefaultBackend>>() as u64,
    );
    measure(
        "scene_bytes",
        core::mem::size_of::<Scene<DEFAULT_CLASSES, DefaultBackend>>() as u64,
    );
    measure(
        "detector_bytes",
        core::mem::size_of::<Detector<DefaultBackend>>() as u64,
    );
    // Part of every monitor (rigid or not): the chain monitor is the same type and size.
    measure(
        "equaliser_bytes",
        core::mem::size_of::<coalshock::Equaliser>() as u64,
    );
    measure(
        "counters_bytes",
        core::mem::size_of::<Counters<DEFAULT_CLASSES>>() as u64,
    );
    // The monitor's slot for the equaliser's state re-estimation: the kernel's `Settler` with
    // the feature `settle`, its zero-size `NoSettle` without it.
    #[cfg(feature = "settle")]
    type SettleSlot = coalshock::settle::Settler;
    #[cfg(not(feature = "settle"))]
    type SettleSlot = coalshock::settle::NoSettle;
    measure("settle_bytes", core::mem::size_of::<SettleSlot>() as u64);
    report("", default, &clock);
    // Quiet blocks through `feed_slice` on the chain scene, as `insns_quiet_block_sample_mean`.
    measure("insns_chain_scene_build", clock.insns(chain_scene_ticks, 1));
    measure("stack_chain_scene_bytes", stack_chain_scene as u64);
    measure(
        "insns_quiet_block_sample_chain_mean",
        clock
            .insns(chain_quiet.sum, chain_quiet.n / 256)
            .checked_div(chain_quiet.n)
            .unwrap_or(0),
    );
    measure("quiet_block_chain_events", chain_quiet_events as u64);
    measure("flow_pulses", flow.n);
    measure("insns_flow_update_mean", flow.mean(&clock));
    measure("insns_flow_update_max", flow.max(&clock));
    report("libm_", &libm, &clock);
    report("micromath_", &micro, &clock);
    let lowest = libm
        .lowest
        .min(micro.lowest)
        .min(yield_lowest)
        .min(rt::lowest_touched());
    measure("stack_total_bytes", (rt::stack_region().1 - lowest) as u64);
    measure("cal_ticks", clock.cal_ticks);
    measure("cal_insns", clock.cal_insns);
    measure("passes_agree", same as u64);
    measure("counters_balanced", default.counters.balanced() as u64);
    measure("chain_counters_balanced", chain.balanced() as u64);
    measure("chain_samples", chain.samples);
    measure(
        "backends_same_verdicts",
        (libm.verdicts == micro.verdicts) as u64,
    );
    exit(same && yield_same)
}

/// Feeds the stream with logging; `true` when the counters equal the measuring pass's.
#[inline(never)]
fn log_pass<M: Backend>(
    monitor: Monitor<DEFAULT_CLASSES, M>,
    measured: &Counters<DEFAULT_CLASSES>,
) -> (bool, Stat) {
    let (counters, flow) = replay_logged("", monitor, inputs());
    (counters == *measured, flow)
}

/// Feeds `inputs` (one `feed` per sample, `gap` at each recorded gap, then `finish`) with
/// logging: every event line and the counters after `prefix`. Returns the counters and the
/// flow monitor's cost per pulse, timed on every pulse of this pass (the caving setting:
/// background 5 %, level 50 %, one false alarm per 10^5 impacts).
#[inline(never)]
fn replay_logged<M: Backend>(
    prefix: &str,
    mut monitor: Monitor<DEFAULT_CLASSES, M>,
    inputs: impl Iterator<Item = Input>,
) -> (Counters<DEFAULT_CLASSES>, Stat) {
    let mut flow_stat = Stat::default();
    let mut flow = FlowMonitor::new(FlowConfig::new(0.05, 0.5, 1e-5), monitor.scene()).ok();
    let mut n = 0u32;
    for input in inputs {
        let event = match input {
            Input::Sample(s) => monitor.feed(s),
            Input::Gap(lost) => monitor.gap(lost),
        };
        if let Some(e) = event {
            log_event(prefix, n, &e, monitor.scene());
            if let Some(t) = flow
                .as_mut()
                .and_then(|f| time_flow(f, monitor.scene(), &e))
            {
                flow_stat.add(t);
            }
            n += 1;
        }
    }
    if let Some(e) = monitor.finish() {
        log_event(prefix, n, &e, monitor.scene());
        if let Some(t) = flow
            .as_mut()
            .and_then(|f| time_flow(f, monitor.scene(), &e))
        {
            flow_stat.add(t);
        }
    }
    log_counters(prefix, &monitor);
    (*monitor.counters(), flow_stat)
}

/// Samples per `feed_slice` call of the chain replay (a multiple of the kernel's equaliser
/// block, so the equaliser's blocks fall where host-sim's do).
const REPLAY_BLOCK: usize = 256;

/// The chain scene's stream through a monitor on the chain scene (default backend), as
/// host-sim replays it (`host_sim::replay::replay_events`): the stored samples between two
/// recorded gaps through `Monitor::feed_slice` (in blocks of [`REPLAY_BLOCK`]),
/// `Monitor::gap` at each gap, then `Monitor::finish`. Every line is logged after the prefix
/// `chain `.
#[inline(never)]
fn chain_pass(
    stream: &Stream,
    scene: Scene<DEFAULT_CLASSES, DefaultBackend>,
) -> Counters<DEFAULT_CLASSES> {
    const PREFIX: &str = "chain ";
    let mut monitor = Monitor::new(scene.clone());
    let total = stream.stored_samples();
    let mut block = [0i16; REPLAY_BLOCK];
    let mut n = 0u32;
    let mut pos = 0usize;
    let mut log = |e: &Event| {
        log_event(PREFIX, n, e, &scene);
        n += 1;
    };
    let ends = stream.gaps.iter().map(|g| (g.position, Some(g.lost)));
    for (end, lost) in ends.chain([(total, None)]) {
        let end = end.min(total).max(pos);
        while pos < end {
            let len = (end - pos).min(REPLAY_BLOCK);
            for (i, b) in block.iter_mut().take(len).enumerate() {
                *b = stream.sample(pos + i);
            }
            monitor.feed_slice(block.get(..len).unwrap_or(&[]), |e| log(&e));
            pos += len;
        }
        if let Some(e) = lost.and_then(|lost| monitor.gap(lost)) {
            log(&e);
        }
    }
    if let Some(e) = monitor.finish() {
        log(&e);
    }
    log_counters(PREFIX, &monitor);
    *monitor.counters()
}
