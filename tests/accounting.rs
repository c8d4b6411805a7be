//! Accounting: a long stream of impacts with noise and faults mixed in (EMI spikes, pile-ups,
//! ADC saturation, dropped samples mid-pulse and between pulses, stuck runs, a stream that
//! ends mid-pulse), generated slot by slot and fed to a `Monitor` as it is made. Every
//! injected event must come out in exactly the counter it belongs to, and the counters must
//! add up exactly.
//!
//! Size: `COALSHOCK_ACCOUNTING_IMPACTS` impacts if set, else 100 000 (about 2.8e7 samples, 284 s
//! of signal at 100 kS/s; about 4.5 s in a debug build, under 1 s in release). Even slots are
//! fed sample by sample with `Monitor::feed`, odd ones in blocks with `Monitor::feed_slice`.
//!
//! Matching rule. The stream is a sequence of slots; each slot is a quiet lead-in of 150 to 300
//! samples followed by one event. A report belongs to the event whose window contains its
//! `at_sample` (the index of the pulse's largest sample), the window running from the event's
//! first sample to its last; windows never overlap. Expected outcome per event:
//!
//! | event | report(s) in its window | counter |
//! | --- | --- | --- |
//! | clean impact | one, not `Rejected` | `classified` / `ambiguous` / `out_of_envelope` |
//! | EMI spike (one sample, 200 to 20 000 counts) | one `Rejected(Spike)` | `rejected[Spike]` |
//! | pile-up (2 impacts, 0.85-1.0 t_c apart) | one `Rejected(PileUp)` | `rejected[PileUp]` |
//! | saturated impact (1.05-4 x full scale) | one `Rejected(Saturated)`, or measured from its flanks (any verdict but another rejection) | `rejected[Saturated]`, or as a clean impact |
//! | samples dropped mid-pulse + `gap` | one `Rejected(Gap)` | `rejected[Gap]`, `gaps` |
//! | samples dropped from before a pulse into it + `gap` | one `Rejected(Gap)` | `rejected[Gap]`, `gaps` |
//! | samples dropped between pulses + `gap` | none | `gaps` |
//! | stuck run (200 identical samples) | none | `stuck_runs` |
//! | stream ends mid-pulse + `finish` | one `Rejected(Truncated)` | `rejected[Truncated]` |
//!
//! A report in no window (noise crossing the 6-RMS trigger: about 1e-9 per sample) is counted
//! as spurious; it must not be a confident class, and there may be at most a handful.

mod common;

use coalshock::{Event, Monitor, RejectReason, Report, Scene, Speed, Verdict};
use common::{Pulse, Rng, hertz64};

/// What was injected in a slot.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Clean(u8),
    Spike,
    PileUp,
    Saturated,
    GapMid,
    GapBetween,
    GapIntoPulse,
    Stuck,
    Truncated,
}

impl Kind {
    /// The verdict the event's report must have (`None`: no report).
    fn accepts(self, v: &Verdict) -> bool {
        match self {
            Kind::Clean(_) => !matches!(v, Verdict::Rejected(_)),
            Kind::Spike => *v == Verdict::Rejected(RejectReason::Spike),
            Kind::PileUp => *v == Verdict::Rejected(RejectReason::PileUp),
            // Measured from its flanks when enough of them is left: its force is scaled past
            // the physical one, so any verdict but another rejection is right.
            Kind::Saturated => !matches!(v, Verdict::Rejected(r) if *r != RejectReason::Saturated),
            Kind::GapMid | Kind::GapIntoPulse => *v == Verdict::Rejected(RejectReason::Gap),
            Kind::Truncated => *v == Verdict::Rejected(RejectReason::Truncated),
            Kind::GapBetween | Kind::Stuck => false,
        }
    }
    fn reports(self) -> usize {
        match self {
            Kind::GapBetween | Kind::Stuck => 0,
            _ => 1,
        }
    }
}

/// Counts of what was injected and what came out.
#[derive(Debug, Default)]
struct Tally {
    injected: std::collections::BTreeMap<String, u64>,
    impacts: u64,
    clean_class_right: u64,
    clean_class_wrong: u64,
    clean_unsure: u64,
    spurious: Vec<Report>,
    mismatched: Vec<String>,
    /// Saturated impacts measured from their flanks, and how many of them got a class.
    saturated_measured: u64,
    saturated_classified: u64,
    lost: u64,
    fed: u64,
}

/// One slot: its samples (slot-local indices), the event's window in them, and gaps
/// `(before sample index, lost)` to report.
struct Slot {
    samples: Vec<i32>,
    window: (usize, usize),
    gaps: Vec<(usize, u32)>,
    kind: Kind,
}

struct Generator {
    scene: Scene,
    rng: Rng,
}

impl Generator {
    fn impact(&mut self, start: f64) -> Pulse {
        let n = self.scene.classes().len() as u64;
        let class = self.rng.below(n) as u8;
        let c = self.scene.classes()[class as usize].clone();
        let (r0, r1) = (c.radius_m.min as f64, c.radius_m.max as f64);
        let r = r0 * (r1 / r0).powf(self.rng.uniform());
        let Speed::Uniform(s) = c.speed else {
            unreachable!("the scene gives uniform speeds")
        };
        let u = s.min as f64 + (s.max - s.min) as f64 * self.rng.uniform();
        let (f, t) = hertz64(&c.material, self.scene.plate(), r, u);
        let sensor = self.scene.sensor();
        Pulse {
            start,
            len: t * sensor.sample_rate_hz as f64,
            amp: f / sensor.force_per_count_n as f64,
            class,
        }
    }

    /// The next slot: `last` makes it the stream's end (a truncated pulse).
    fn slot(&mut self, last: bool, buf: &mut Vec<i32>) -> Slot {
        let lead = 150 + self.rng.below(151) as usize;
        let start = lead as f64 + self.rng.uniform();
        let roll = self.rng.below(1000);
        let kind = if last {
            Kind::Truncated
        } else {
            match roll {
                0..=699 => Kind::Clean(0),
                700..=779 => Kind::Spike,
                780..=849 => Kind::PileUp,
                850..=899 => Kind::Saturated,
                900..=949 => Kind::GapMid,
                950..=969 => Kind::GapBetween,
                970..=984 => Kind::GapIntoPulse,
                _ => Kind::Stuck,
            }
        };
        let mut pulses: [Option<Pulse>; 2] = [None, None];
        let mut kind = kind;
        let full = self.scene.sensor().adc_max as f64;
        match kind {
            Kind::Clean(_) | Kind::GapMid | Kind::GapIntoPulse | Kind::Truncated => {
                let p = self.impact(start);
                if let Kind::Clean(_) = kind {
                    kind = Kind::Clean(p.class);
                }
                pulses[0] = Some(p);
            }
            Kind::PileUp => {
                let a = self.impact(start);
                let offset = 0.85 + 0.15 * self.rng.uniform();
                let mut b = self.impact(a.start + offset * a.len);
                b.amp = a.amp * (0.6 + 1.4 * self.rng.uniform());
                b.len = a.len * (0.8 + 0.4 * self.rng.uniform());
                pulses = [Some(a), Some(b)];
            }
            Kind::Saturated => {
                let mut p = self.impact(start);
                p.amp = full * (1.05 + 2.95 * self.rng.uniform());
                pulses[0] = Some(p);
            }
            Kind::Spike | Kind::GapBetween | Kind::Stuck => {}
        }
        let end = match (kind, pulses) {
            (Kind::Truncated, [Some(p), _]) => {
                (p.start + (0.2 + 0.6 * self.rng.uniform()) * p.len) as usize
            }
            (_, [_, Some(b)]) => b.end() + 1,
            (_, [Some(a), None]) => a.end() + 1,
            _ => lead + 1,
        };
        let len = match kind {
            Kind::Stuck => lead + 200,
            // Room for the dropped samples.
            Kind::GapMid => end + 10,
            _ => end,
        };
        let noise = self.scene.sensor().noise_rms_counts as f64;
        let (lo, hi) = (
            self.scene.sensor().adc_min as f64,
            self.scene.sensor().adc_max as f64,
        );
        buf.clear();
        for i in 0..len {
            let mut v = 100.0 + noise * self.rng.normal();
            for p in pulses.iter().flatten() {
                v += p.at(i);
            }
            buf.push(v.round().clamp(lo, hi) as i32);
        }
        let mut window = (lead, len);
        let mut gaps = Vec::new();
        match kind {
            Kind::Spike => {
                let h = 200.0 * 100f64.powf(self.rng.uniform());
                buf[lead] = (buf[lead] as f64 + h).min(full - 1.0) as i32;
            }
            Kind::Stuck => {
                let v = buf[lead];
                buf[lead..].iter_mut().for_each(|s| *s = v);
            }
            Kind::GapMid => {
                // Drop 1 to 10 samples from 30 % to 70 % of the pulse (the detector is in the
                // pulse by then), and report them.
                let p = pulses[0].unwrap_or_else(|| unreachable!());
                let at = (p.start + (0.3 + 0.4 * self.rng.uniform()) * p.len) as usize;
                let lost = 1 + self.rng.below(10) as usize;
                buf.drain(at..at + lost);
                gaps.push((at, lost as u32));
                window.1 += lost;
            }
            Kind::GapIntoPulse => {
                // Samples dropped from 40 before the pulse to 15-60 % into it: the stream
                // resumes inside the pulse.
                let p = pulses[0].unwrap_or_else(|| unreachable!());
                let from = lead - 40;
                let to = (p.start + (0.15 + 0.45 * self.rng.uniform()) * p.len) as usize;
                buf.drain(from..to);
                gaps.push((from, (to - from) as u32));
                window.0 = from;
            }
            Kind::GapBetween => {
                let lost = 1 + self.rng.below(1000) as u32;
                gaps.push((lead - 60, lost));
                window = (lead - 60, lead - 60 + lost as usize);
            }
            _ => {}
        }
        let samples = std::mem::take(buf);
        Slot {
            samples,
            window,
            gaps,
            kind,
        }
    }
}

/// An event whose reports may still come.
struct Open {
    window: (u64, u64),
    kind: Kind,
    reports: Vec<Report>,
}

/// Checks an event's reports against what it must give.
fn close(e: Open, tally: &mut Tally) {
    let ok =
        e.reports.len() == e.kind.reports() && e.reports.iter().all(|r| e.kind.accepts(&r.verdict));
    if !ok {
        tally.mismatched.push(format!(
            "{:?} at {}..{}: {:?}",
            e.kind,
            e.window.0,
            e.window.1,
            e.reports
                .iter()
                .map(|r| (r.at_sample, r.verdict))
                .collect::<Vec<_>>()
        ));
    }
    if let (Kind::Saturated, [r]) = (e.kind, e.reports.as_slice()) {
        if !matches!(r.verdict, Verdict::Rejected(_)) {
            tally.saturated_measured += 1;
        }
        if matches!(r.verdict, Verdict::Class { .. }) {
            tally.saturated_classified += 1;
        }
    }
    if let (Kind::Clean(truth), [r]) = (e.kind, e.reports.as_slice()) {
        match r.verdict {
            Verdict::Class { class, .. } if class == truth => tally.clean_class_right += 1,
            Verdict::Class { .. } => tally.clean_class_wrong += 1,
            _ => tally.clean_unsure += 1,
        }
    }
}

fn impacts() -> u64 {
    match std::env::var("COALSHOCK_ACCOUNTING_IMPACTS") {
        Ok(v) => v
            .parse()
            .unwrap_or_else(|_| panic!("COALSHOCK_ACCOUNTING_IMPACTS={v} is not a number")),
        Err(_) => 100_000,
    }
}

#[test]
fn every_injected_event_is_accounted_for() {
    let t0 = std::time::Instant::now();
    let target = impacts();
    let scene = Scene::paper_narrow().unwrap();
    let mut m: Monitor = Monitor::new(scene.clone());
    let mut g = Generator {
        scene,
        rng: Rng::new(0x5eed),
    };
    let mut tally = Tally::default();
    let mut buf = Vec::new();
    // Reports not yet assigned, and the events whose reports may still come.
    let mut pending: Vec<Report> = Vec::new();
    let mut open: std::collections::VecDeque<Open> = std::collections::VecDeque::new();
    let mut base: u64 = 0; // stream index of the slot's first sample
    let mut last = false;
    let mut slot_index = 0u64;
    while !last {
        last = tally.impacts + 2 >= target;
        let slot = g.slot(last, &mut buf);
        *tally
            .injected
            .entry(
                format!("{:?}", slot.kind)
                    .split('(')
                    .next()
                    .unwrap_or("")
                    .to_string(),
            )
            .or_insert(0) += 1;
        tally.impacts += match slot.kind {
            Kind::PileUp => 2,
            Kind::Clean(_)
            | Kind::Saturated
            | Kind::GapMid
            | Kind::GapIntoPulse
            | Kind::Truncated => 1,
            _ => 0,
        };
        let mut lost_here = 0u64;
        // The samples between gaps, fed one by one (even slots) or as blocks through
        // `feed_slice` (odd slots, the FIFO path with the quiet fast loop).
        let mut from = 0;
        let cuts = slot.gaps.iter().map(|&(at, lost)| (at, Some(lost)));
        for (to, lost) in cuts.chain([(slot.samples.len(), None)]) {
            let chunk = &slot.samples[from..to];
            if slot_index.is_multiple_of(2) {
                for &s in chunk {
                    if let Some(Event::Pulse(r)) = m.feed(s) {
                        pending.push(r);
                    }
                }
            } else {
                m.feed_slice(chunk, |e| {
                    if let Event::Pulse(r) = e {
                        pending.push(r);
                    }
                });
            }
            if let Some(lost) = lost {
                if let Some(Event::Pulse(r)) = m.gap(lost) {
                    pending.push(r);
                }
                lost_here += lost as u64;
            }
            from = to;
        }
        slot_index += 1;
        if last {
            if let Some(Event::Pulse(r)) = m.finish() {
                pending.push(r);
            }
        }
        tally.fed += slot.samples.len() as u64;
        tally.lost += lost_here;
        open.push_back(Open {
            window: (base + slot.window.0 as u64, base + slot.window.1 as u64),
            kind: slot.kind,
            reports: Vec::new(),
        });
        base += slot.samples.len() as u64 + lost_here;
        // Assign the reports to the open event whose window holds their peak.
        for r in pending.drain(..) {
            match open
                .iter_mut()
                .find(|e| (e.window.0..=e.window.1).contains(&r.at_sample))
            {
                Some(e) => e.reports.push(r),
                None => tally.spurious.push(r),
            }
        }
        // A pulse is reported `hold` samples after it ends: an event whose window ended more
        // than 100 samples ago has all its reports.
        while open
            .front()
            .is_some_and(|e| last || e.window.1 + 100 < base)
        {
            if let Some(e) = open.pop_front() {
                close(e, &mut tally);
            }
        }
        buf = slot.samples;
    }
    let c = *m.counters();
    let secs = t0.elapsed().as_secs_f64();
    println!(
        "{} impacts in {} samples ({:.1} s of signal) in {secs:.2} s: injected {:?}",
        tally.impacts,
        tally.fed + tally.lost,
        (tally.fed + tally.lost) as f64 / 1e5,
        tally.injected
    );
    println!(
        "clean impacts: {} right class, {} wrong class, {} ambiguous or out of envelope; spurious reports {:?}",
        tally.clean_class_right, tally.clean_class_wrong, tally.clean_unsure, tally.spurious
    );
    println!(
        "saturated impacts measured from their flanks: {} of {} ({} given a class)",
        tally.saturated_measured,
        tally.injected.get("Saturated").copied().unwrap_or(0),
        tally.saturated_classified
    );
    println!("counters: {c:?}");

    // Every event came out as expected.
    assert!(
        tally.mismatched.is_empty(),
        "{} events not accounted as expected; first: {:#?}",
        tally.mismatched.len(),
        &tally.mismatched[..tally.mismatched.len().min(20)]
    );
    // Noise triggers: rare, and never a confident class.
    assert!(tally.spurious.len() <= 3, "{:?}", tally.spurious);
    assert!(
        tally
            .spurious
            .iter()
            .all(|r| !matches!(r.verdict, Verdict::Class { .. }))
    );

    // The counters add up exactly.
    let n = |k: &str| tally.injected.get(k).copied().unwrap_or(0);
    let spurious = tally.spurious.len() as u64;
    let rejected = |r: RejectReason| c.rejected_for(r) as u64;
    assert!(c.balanced(), "{c:?}");
    assert_eq!(c.outcomes(), c.pulses as u64);
    assert_eq!(c.samples, tally.fed + tally.lost);
    assert_eq!(c.lost_samples, tally.lost);
    assert_eq!(
        c.gaps as u64,
        n("GapMid") + n("GapBetween") + n("GapIntoPulse")
    );
    assert_eq!(c.stuck_runs as u64, n("Stuck"));
    assert_eq!(
        c.pulses as u64,
        n("Clean")
            + n("Spike")
            + n("PileUp")
            + n("Saturated")
            + n("GapMid")
            + n("GapIntoPulse")
            + n("Truncated")
            + spurious
    );
    let classified: u64 = c.classified.iter().map(|&v| v as u64).sum();
    assert_eq!(
        classified + c.ambiguous as u64 + c.out_of_envelope as u64,
        n("Clean") + tally.saturated_measured + spurious_unrejected(&tally)
    );
    assert_eq!(
        classified,
        tally.clean_class_right + tally.clean_class_wrong + tally.saturated_classified
    );
    assert_eq!(
        rejected(RejectReason::Spike),
        n("Spike") + spurious_rejected(&tally, RejectReason::Spike)
    );
    assert_eq!(rejected(RejectReason::PileUp), n("PileUp"));
    assert_eq!(
        rejected(RejectReason::Saturated) + tally.saturated_measured,
        n("Saturated")
    );
    assert_eq!(rejected(RejectReason::Gap), n("GapMid") + n("GapIntoPulse"));
    assert_eq!(rejected(RejectReason::Truncated), n("Truncated"));
    assert_eq!(rejected(RejectReason::TooLong), 0);
    assert_eq!(
        rejected(RejectReason::Implausible),
        spurious_rejected(&tally, RejectReason::Implausible)
    );
    // Clean impacts of the narrow scene separate: a confident wrong class is a defect.
    assert!(
        tally.clean_class_wrong * 1000 <= n("Clean"),
        "{} of {} clean impacts got a confident wrong class",
        tally.clean_class_wrong,
        n("Clean")
    );
}

fn spurious_unrejected(t: &Tally) -> u64 {
    t.spurious
        .iter()
        .filter(|r| !matches!(r.verdict, Verdict::Rejected(_)))
        .count() as u64
}

fn spurious_rejected(t: &Tally, reason: RejectReason) -> u64 {
    t.spurious
        .iter()
        .filter(|r| r.verdict == Verdict::Rejected(reason))
        .count() as u64
}
