//! The result of one contact integration in SI units, and its continuous output.

use crate::physics::hertz64::positive;
use crate::physics::integrate::dense::{Segment, eval_segments, find_segment_walk};
use crate::physics::integrate::{Scales, SimError, WorkStats};
use crate::physics::laws::ForceLaw;

/// Result of one contact integration (SI units).
#[derive(Debug, Clone)]
pub struct ContactSolution {
    /// Maximum penetration in m (root of `delta'` on the continuous output).
    pub delta_max_m: f64,
    /// Time of the maximum penetration in s after first contact.
    pub t_delta_max_s: f64,
    /// Peak contact force in N (maximum over the continuous output).
    pub peak_force_n: f64,
    /// Time of the peak force in s after first contact.
    pub t_peak_s: f64,
    /// Contact duration in s (first contact to separation, `delta` back to 0).
    pub duration_s: f64,
    /// Duration of the main force pulse in s: from first contact to the first zero of the
    /// force after its peak. Equal to `duration_s` for undamped Hertz; shorter for a damped
    /// law whose clamp at zero engages before separation (the sphere then moves force-free
    /// while `delta > 0`, and for Adams a small force may return just before separation, when
    /// `k delta^1.5` outgrows the STEP-ramped damping).
    pub pulse_duration_s: f64,
    /// Rebound speed `-delta'` at separation in m/s.
    pub rebound_speed_m_s: f64,
    /// Contact impulse `integral F dt = m (u + u_rebound) + m g t_c` in N s (momentum
    /// balance of the equation of motion).
    pub impulse_n_s: f64,
    /// Work done.
    pub work: WorkStats,
    /// The scales used.
    pub scales: Scales,
    pub(super) law: ForceLaw,
    /// For a history-dependent law: the scaled time of the turn and the law after it.
    pub(super) turned: Option<(f64, ForceLaw)>,
    pub(super) segments: Vec<Segment>,
}

impl ContactSolution {
    /// Coefficient of restitution `e = u_rebound / u` (dimensionless).
    pub fn restitution(&self) -> f64 {
        self.rebound_speed_m_s / self.scales.speed_m_s
    }

    /// State `(delta_m, delta_dot_m_s)` at `t_s` seconds after first contact from the
    /// continuous output, or `None` outside `[0, duration_s]`.
    pub fn state_at(&self, t_s: f64) -> Option<(f64, f64)> {
        let tau = t_s / self.scales.time_s;
        let y = eval_segments(&self.segments, tau)?;
        Some((y[0] * self.scales.delta_m, y[1] * self.scales.speed_m_s))
    }

    /// Contact force in N at `t_s` from the continuous output, or `None` outside the contact.
    pub fn force_at(&self, t_s: f64) -> Option<f64> {
        let law = law_at(&self.law, self.turned.as_ref(), t_s / self.scales.time_s);
        self.state_at(t_s).map(|(d, dd)| law.force(d, dd))
    }

    /// Times (s) of the accepted step boundaries, from 0 to the contact end.
    pub fn step_times_s(&self) -> Vec<f64> {
        let mut out: Vec<f64> = self
            .segments
            .iter()
            .map(|s| s.t0 * self.scales.time_s)
            .collect();
        out.push(self.duration_s);
        out
    }

    /// The force-time series `(t_s, force_n)` sampled every `interval_s` from 0 up to the
    /// contact end. Errors if the interval is not positive or gives more than 10^7 samples.
    pub fn sample_force(&self, interval_s: f64) -> Result<Vec<(f64, f64)>, SimError> {
        positive("record interval_s", interval_s)?;
        let n = (self.duration_s / interval_s).floor();
        if n.is_nan() || n >= 1e7 {
            return Err(SimError::InvalidParameter {
                name: "record interval_s".to_string(),
                value: interval_s,
                requirement: "at most 1e7 samples per contact",
            });
        }
        let n = n as usize;
        let mut out = Vec::with_capacity(n + 1);
        // The times only move forward: each segment is found by walking, not searching; the
        // values are those of `force_at` bit for bit.
        let mut cursor = 0usize;
        for i in 0..=n {
            let t = i as f64 * interval_s;
            let tau = t / self.scales.time_s;
            if let Some((j, theta)) = find_segment_walk(&self.segments, tau, &mut cursor) {
                let y = self.segments[j].eval(theta);
                let (d, dd) = (y[0] * self.scales.delta_m, y[1] * self.scales.speed_m_s);
                let law = law_at(&self.law, self.turned.as_ref(), tau);
                out.push((t, law.force(d, dd)));
            }
        }
        Ok(out)
    }

    /// The law that was integrated (for a history-dependent law, as it was at first contact).
    pub fn law(&self) -> &ForceLaw {
        &self.law
    }

    /// For a history-dependent law ([`ForceLaw::awaits_turn`]): the time in s at which the
    /// penetration turned and the law from then on ([`ForceLaw::turned_at`]).
    pub fn turned(&self) -> Option<(f64, &ForceLaw)> {
        self.turned
            .as_ref()
            .map(|(tau, law)| (tau * self.scales.time_s, law))
    }
}

/// The law in force at scaled time `tau`: `first` before the turn, the turned law from it on.
pub(super) fn law_at<'a>(
    first: &'a ForceLaw,
    turned: Option<&'a (f64, ForceLaw)>,
    tau: f64,
) -> &'a ForceLaw {
    match turned {
        Some((t_turn, law)) if tau >= *t_turn => law,
        _ => first,
    }
}
