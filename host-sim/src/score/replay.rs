//! A stream replayed through the kernel: its samples fed to a `Monitor` block by block, with
//! its gaps, and the monitor's reports paired with the stream's truth impacts.

use coalshock::math::Backend;
use coalshock::{Event, FlowSlot, Monitor, Report};

use crate::sim::stream::{Stream, Truth};

/// Feeds a stream to a monitor: the stored samples in blocks (`Monitor::feed_slice`),
/// `Monitor::gap` at every recorded gap, `Monitor::finish` at the end. Returns every event.
pub fn replay_events<const N: usize, M: Backend, F: FlowSlot<M>>(
    stream: &Stream,
    monitor: &mut Monitor<N, M, F>,
) -> Vec<Event> {
    let mut out = Vec::new();
    let mut pos = 0usize;
    for g in &stream.gaps {
        let end = g.position.clamp(pos, stream.samples.len());
        monitor.feed_slice(&stream.samples[pos..end], |e| out.push(e));
        out.extend(monitor.gap(g.lost));
        pos = end;
    }
    monitor.feed_slice(&stream.samples[pos..], |e| out.push(e));
    out.extend(monitor.finish());
    out
}

/// [`replay_events`], keeping the pulse reports only.
pub fn replay<const N: usize, M: Backend>(
    stream: &Stream,
    monitor: &mut Monitor<N, M>,
) -> Vec<Report> {
    replay_events(stream, monitor)
        .into_iter()
        .filter_map(|e| match e {
            Event::Pulse(r) => Some(r),
            Event::Stuck { .. } | Event::Flow(_) => None,
        })
        .collect()
}

/// A report paired with a truth impact.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pair {
    /// Index into the reports.
    pub report: usize,
    /// Index into the truth.
    pub truth: usize,
    /// `report.at_sample - truth.peak_sample` in samples.
    pub offset_samples: i64,
}

/// Reports paired with truth impacts.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Matching {
    /// Pairs, in report order.
    pub pairs: Vec<Pair>,
    /// Reports with no truth impact within the tolerance.
    pub unmatched_reports: Vec<usize>,
    /// Truth impacts no report was paired with.
    pub unmatched_truth: Vec<usize>,
}

/// Pairs each report with the truth impact nearest in peak time (`at_sample` against
/// `peak_sample`), one to one, nearest pairs first, at most `tolerance_samples` apart.
pub fn match_truth(reports: &[Report], truth: &[Truth], tolerance_samples: u64) -> Matching {
    let mut order: Vec<usize> = (0..truth.len()).collect();
    order.sort_by_key(|&i| truth[i].peak_sample);
    let mut candidates: Vec<(u64, usize, usize)> = Vec::new();
    for (r, rep) in reports.iter().enumerate() {
        let lo = rep.at_sample.saturating_sub(tolerance_samples);
        let start = order.partition_point(|&i| truth[i].peak_sample < lo);
        for &t in &order[start..] {
            let d = truth[t].peak_sample.abs_diff(rep.at_sample);
            if truth[t].peak_sample > rep.at_sample.saturating_add(tolerance_samples) {
                break;
            }
            candidates.push((d, r, t));
        }
    }
    candidates.sort_unstable();
    let mut report_used = vec![false; reports.len()];
    let mut truth_used = vec![false; truth.len()];
    let mut pairs = Vec::new();
    for (_, r, t) in candidates {
        if !report_used[r] && !truth_used[t] {
            report_used[r] = true;
            truth_used[t] = true;
            pairs.push(Pair {
                report: r,
                truth: t,
                offset_samples: reports[r].at_sample as i64 - truth[t].peak_sample as i64,
            });
        }
    }
    pairs.sort_by_key(|p| p.report);
    let unmatched = |used: &[bool]| {
        used.iter()
            .enumerate()
            .filter(|(_, u)| !**u)
            .map(|(i, _)| i)
            .collect()
    };
    Matching {
        pairs,
        unmatched_reports: unmatched(&report_used),
        unmatched_truth: unmatched(&truth_used),
    }
}
