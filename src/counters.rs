//! Counters of every outcome, so that no pulse is ever silently lost.

use crate::classifier::{RejectReason, Verdict};

/// Every pulse seen ends in exactly one of these counters:
/// `pulses = sum(classified) + ambiguous + out_of_envelope + sum(rejected)`
/// ([`Counters::balanced`]). Counters saturate at their maximum instead of wrapping.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters<const N: usize> {
    /// Samples fed, including those reported lost through a gap, as of the last event, gap or
    /// finish ([`crate::Monitor::samples_fed`] is always current).
    pub samples: u64,
    /// Pulses seen.
    pub pulses: u32,
    /// Pulses given each class with confidence.
    pub classified: [u32; N],
    /// Pulses in the overlap of envelopes.
    pub ambiguous: u32,
    /// Pulses outside every envelope.
    pub out_of_envelope: u32,
    /// Rejected pulses, indexed by [`RejectReason::index`].
    pub rejected: [u32; RejectReason::ALL.len()],
    /// Gaps reported (e.g. FIFO overruns).
    pub gaps: u32,
    /// Samples reported lost in those gaps.
    pub lost_samples: u64,
    /// Times the equaliser's state was re-estimated after a sample at full scale or a gap
    /// ([`crate::settle`]; always 0 behind a rigid chain).
    pub settled: u32,
    /// Samples spent on those re-estimations (their windows, believed or not), which the
    /// detector did not search for pulses.
    pub settle_samples: u64,
    /// Runs of identical samples on a noisy sensor (stuck sensor), as of the last event, gap
    /// or finish (counted by the detector even when a stuck event coincides with a pulse).
    pub stuck_runs: u32,
}

impl<const N: usize> Default for Counters<N> {
    fn default() -> Self {
        Self {
            samples: 0,
            pulses: 0,
            classified: [0; N],
            ambiguous: 0,
            out_of_envelope: 0,
            rejected: [0; RejectReason::ALL.len()],
            gaps: 0,
            lost_samples: 0,
            settled: 0,
            settle_samples: 0,
            stuck_runs: 0,
        }
    }
}

impl<const N: usize> Counters<N> {
    /// Counts one pulse with its verdict.
    pub fn record(&mut self, verdict: &Verdict) {
        self.pulses = self.pulses.saturating_add(1);
        let slot = match *verdict {
            Verdict::Class { class, .. } => self.classified.get_mut(class as usize),
            Verdict::Ambiguous { .. } => Some(&mut self.ambiguous),
            Verdict::OutOfEnvelope { .. } => Some(&mut self.out_of_envelope),
            Verdict::Rejected(r) => self.rejected.get_mut(r.index()),
        };
        match slot {
            Some(c) => *c = c.saturating_add(1),
            // A class index the scene does not have: counted, as implausible.
            None => {
                if let Some(c) = self.rejected.get_mut(RejectReason::Implausible.index()) {
                    *c = c.saturating_add(1);
                }
            }
        }
    }

    /// Rejected pulses for one reason.
    pub fn rejected_for(&self, reason: RejectReason) -> u32 {
        self.rejected.get(reason.index()).copied().unwrap_or(0)
    }

    /// Sum of every outcome counter, in u64 so it cannot overflow.
    pub fn outcomes(&self) -> u64 {
        let s = |a: &[u32]| a.iter().map(|&v| v as u64).sum::<u64>();
        s(&self.classified)
            + self.ambiguous as u64
            + self.out_of_envelope as u64
            + s(&self.rejected)
    }

    /// `true` when every pulse seen is in exactly one outcome counter.
    pub fn balanced(&self) -> bool {
        self.outcomes() == self.pulses as u64
    }
}
