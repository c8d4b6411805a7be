//! Faults injected into a generated stream: saturated and gapped impacts, and spikes, stuck
//! runs and dropped samples in the quiet stretches between pulses (phases 3, 6 and 7 of
//! [`crate::sim::generate`]); every draw from the stream's fault generator, in a fixed order.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::sim::sensor::{ForcePulse, Sensor};
use crate::sim::stream::{
    Clock, FaultEvent, FaultKind, FaultOptions, Gap, ImpactFault, QUIET_MARGIN_SAMPLES, Truth,
};

/// Phase 3: one draw per impact, whatever the shares. The last impact is truncated when the
/// stream ends inside it; an impact outside a pile-up is saturated (its pulse scaled to
/// `saturate_overdrive` times the ADC's full scale) or gets a gap, by the shares.
pub(crate) fn fault_impacts(
    truth: &mut [Truth],
    pulses: &mut [ForcePulse],
    faults: &FaultOptions,
    sensor: &Sensor,
    frng: &mut ChaCha8Rng,
) {
    let full_scale = sensor.adc_range().1 as f64;
    let last = truth.len().checked_sub(1);
    for (i, (t, p)) in truth.iter_mut().zip(pulses.iter_mut()).enumerate() {
        let r: f64 = frng.random();
        if faults.end_mid_pulse && Some(i) == last {
            t.fault = ImpactFault::Truncated;
        } else if t.fault == ImpactFault::None {
            if r < faults.saturate_share {
                let peak_counts = t.peak_force_n * sensor.counts_per_newton();
                let scale = (faults.saturate_overdrive * full_scale / peak_counts).max(1.0);
                p.scale = scale;
                t.scale = scale;
                t.peak_force_n *= scale;
                t.fault = ImpactFault::Saturated;
            } else if r < faults.saturate_share + faults.drop_share {
                t.fault = ImpactFault::Gap;
            }
        }
    }
}

/// The samples `[first, end)` an impact's pulse covers on the time line.
fn span(t: &Truth, clock: Clock) -> (u64, u64) {
    let a = clock.samples_to(t.time_s).floor().max(0.0) as u64;
    let b = clock
        .samples_to(t.time_s + t.duration_s.max(0.0))
        .ceil()
        .max(0.0) as u64;
    (a, b)
}

/// The pulses' spans, overlapping ones merged, in time order.
pub(crate) fn busy_spans(truth: &[Truth], clock: Clock) -> Vec<(u64, u64)> {
    let mut busy: Vec<(u64, u64)> = Vec::new();
    for (a, b) in truth.iter().map(|t| span(t, clock)) {
        match busy.last_mut() {
            Some(last) if a <= last.1 => last.1 = last.1.max(b),
            _ => busy.push((a, b)),
        }
    }
    busy
}

/// Phase 6: the drops (time-line sample, length) and the spike and stuck events placed so far.
pub(crate) struct QuietFaults<'a> {
    faults: &'a FaultOptions,
    /// The ADC's `(min, max)` codes.
    adc_range: (i32, i32),
    /// Samples of the time line.
    timeline: u64,
    /// Dropped runs: first time-line sample and length.
    pub(crate) drops: Vec<(u64, u32)>,
    /// Spikes and stuck runs, in time order.
    pub(crate) events: Vec<FaultEvent>,
}

impl<'a> QuietFaults<'a> {
    /// No faults placed yet.
    pub(crate) fn new(faults: &'a FaultOptions, sensor: &Sensor, timeline: u64) -> Self {
        QuietFaults {
            faults,
            adc_range: sensor.adc_range(),
            timeline,
            drops: Vec::new(),
            events: Vec::new(),
        }
    }

    /// A drop inside each gapped impact's pulse, uniform within a quarter contact time of
    /// its peak (one draw per gapped impact).
    pub(crate) fn drop_in_pulses(&mut self, truth: &[Truth], clock: Clock, frng: &mut ChaCha8Rng) {
        for t in truth.iter().filter(|t| t.fault == ImpactFault::Gap) {
            let (a, b) = span(t, clock);
            let quarter = (b - a) / 4;
            let lo = t.peak_sample.saturating_sub(quarter).max(1);
            let hi = (t.peak_sample + quarter).max(lo);
            let at = lo + ((hi - lo + 1) as f64 * frng.random::<f64>()) as u64;
            self.drops.push((at.min(hi), self.faults.drop_samples));
        }
    }

    /// At most one spike, stuck run or drop in each quiet stretch between two busy spans
    /// (three draws per stretch: which fault, where, and the spike's size), at least
    /// [`QUIET_MARGIN_SAMPLES`] from either pulse; a stretch too short gets none.
    pub(crate) fn place_between_pulses(
        &mut self,
        busy: &[(u64, u64)],
        samples: &mut [i16],
        frng: &mut ChaCha8Rng,
    ) {
        let f = self.faults;
        for w in busy.windows(2) {
            let r: f64 = frng.random();
            let r_pos: f64 = frng.random();
            let r_val: f64 = frng.random();
            let (lo, hi) = (
                w[0].1 + QUIET_MARGIN_SAMPLES,
                w[1].0.saturating_sub(QUIET_MARGIN_SAMPLES),
            );
            let timeline = self.timeline;
            let fits = |len: u64| hi >= lo + len && lo + len <= timeline;
            let pick = |len: u64| lo + ((hi - lo - len + 1) as f64 * r_pos) as u64;
            if r < f.spike_share {
                if fits(1) {
                    self.spike(pick(1), r_val, samples);
                }
            } else if r < f.spike_share + f.stuck_share {
                if fits(f.stuck_samples as u64) {
                    self.stuck(pick(f.stuck_samples as u64), samples);
                }
            } else if r < f.spike_share + f.stuck_share + f.drop_quiet_share
                && fits(f.drop_samples as u64)
            {
                self.drops
                    .push((pick(f.drop_samples as u64), f.drop_samples));
            }
        }
    }

    /// A spike at sample `at`: `a + r_val (b - a)` counts added (`spike_counts = [a, b]`),
    /// clipped to the ADC's range.
    fn spike(&mut self, at: u64, r_val: f64, samples: &mut [i16]) {
        let [a, b] = self.faults.spike_counts;
        let value = a + r_val * (b - a);
        if let Some(s) = samples.get_mut(at as usize) {
            let (lo_c, hi_c) = self.adc_range;
            *s = (*s as f64 + value)
                .round()
                .max(lo_c as f64)
                .min(hi_c as f64) as i16;
        }
        self.events.push(FaultEvent {
            kind: FaultKind::Spike,
            at_sample: at,
            length: 1,
            value,
        });
    }

    /// A stuck run from sample `at`: `stuck_samples` samples held at the value of the first.
    fn stuck(&mut self, at: u64, samples: &mut [i16]) {
        let len = self.faults.stuck_samples;
        let held = samples.get(at as usize).copied().unwrap_or(0);
        for s in samples.iter_mut().skip(at as usize).take(len as usize) {
            *s = held;
        }
        self.events.push(FaultEvent {
            kind: FaultKind::Stuck,
            at_sample: at,
            length: len,
            value: held as f64,
        });
    }
}

/// Phase 7: the samples with the dropped runs removed (overlapping runs merged, runs past the
/// time line ignored), and the gaps they leave, by stored position.
pub(crate) fn remove_dropped(
    samples: &[i16],
    mut drops: Vec<(u64, u32)>,
    timeline: u64,
) -> (Vec<i16>, Vec<Gap>) {
    drops.sort_unstable();
    let mut kept = Vec::with_capacity(samples.len());
    let mut gaps = Vec::new();
    let mut next = 0u64;
    for (at, len) in drops {
        let at = at.max(next);
        if at >= timeline {
            break;
        }
        let end = (at + len as u64).min(timeline);
        kept.extend_from_slice(&samples[next as usize..at as usize]);
        gaps.push(Gap {
            position: kept.len(),
            at_sample: at,
            lost: (end - at) as u32,
        });
        next = end;
    }
    kept.extend_from_slice(&samples[next as usize..]);
    (kept, gaps)
}
