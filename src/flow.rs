//! The flow monitor: the gangue share of the recent flow, and a CUSUM that raises the
//! close-window alarm, both from the class likelihoods of every measured pulse.
//!
//! Nobody acts on one lump: a caving window closes once rock starts to come. A flow whose
//! gangue share is `pi` has, per measured pulse `x`, the mixture density
//! `f_pi(x) = pi p_G(x) + (1 - pi) p_C(x)`, with `p_G` and `p_C` the kernel's class likelihoods
//! (each group's classes mixed by their priors). Ambiguous pulses carry likelihood too and
//! are used; rejected and out-of-envelope pulses are left out and counted.
//!
//! - **Change detector**: Page's CUSUM on the mixture likelihood ratio of the level `pi1`
//!   against the background share `pi0`:
//!   `S_n = max(0, S_{n-1} + ln[(pi1 r + 1 - pi1) / (pi0 r + 1 - pi0)])`, `r = p_G / p_C`.
//!   The alarm is raised when `S_n >= h` with `h = ln(1 / alpha)`, `alpha` the false-alarm
//!   rate stated as alarms per impact. For a CUSUM on an exact likelihood ratio the mean
//!   run length to a false alarm is at least `e^h` (Lorden 1971; Siegmund 1985, the
//!   overshoot makes it longer still), so `h = ln(1 / alpha)` holds the rate at or below
//!   `alpha`; host-sim measures the rate. The expected delay after a change to `pi1` is about
//!   `h / KL(f_pi1 || f_pi0)` impacts.
//! - **Share estimate**: maximum likelihood of `pi` over the recent flow by online EM with
//!   exponential forgetting (memory `W` impacts, `lambda = 1 / W`): each pulse's posterior
//!   gangue probability `w = pi r / (pi r + 1 - pi)` is averaged in,
//!   `pi <- pi + lambda (w - pi)`, starting at `pi0`; its fixed point is the mixture
//!   maximum-likelihood share of the forgetting-weighted pulses. Standard error from the
//!   observed information `J = sum (1 - lambda)^k g_k^2` of the score
//!   `g = (r - 1) / (pi r + 1 - pi)`: `sqrt(W2 / (W1 J))` with `W1 = sum (1 - lambda)^k`,
//!   `W2 = sum (1 - lambda)^(2k)` over the pulses used (a weighted estimator's variance),
//!   at most 0.5.
//!
//! Fixed memory (204 bytes, 128 of them the classes' log priors; tests/sizes.rs), no heap;
//! one `exp` and one `ln` per pulse in a two-class scene, the square root by three Newton
//! steps (fw/budgets.txt: `insns_flow_update_max`).

use crate::classifier::Verdict;
use crate::error::Error;
use crate::math::{Backend, DefaultBackend};
use crate::scene::{MAX_CLASSES, Scene};

/// Largest `|ln(p_G / p_C)|` used: beyond it a pulse is as good as certain, and `e^30` stays
/// well inside f32.
pub const MAX_LN_RATIO: f32 = 30.0;

/// The share estimate is kept inside `[SHARE_FLOOR, 1 - SHARE_FLOOR]`.
pub const SHARE_FLOOR: f32 = 1e-3;

/// What a [`crate::Monitor`] feeds each pulse to besides the classifier: [`NoFlow`] (nothing;
/// the monitor then has no flow code at all) or a [`FlowMonitor`].
pub trait FlowSlot<M: Backend>: Clone + core::fmt::Debug {
    /// Whether pulses are fed to it (a constant, so a monitor without flow compiles none).
    const ON: bool;
    /// One pulse's verdict and class log-likelihoods (see [`FlowMonitor::record`]).
    fn record(&mut self, verdict: &Verdict, lls: Option<&[f32]>);
    /// The status after the last recorded pulse, once.
    fn take(&mut self) -> Option<FlowStatus>;
    /// Starts a new round.
    fn reset(&mut self);
}

/// No flow monitor.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoFlow;

impl<M: Backend> FlowSlot<M> for NoFlow {
    const ON: bool = false;
    fn record(&mut self, _: &Verdict, _: Option<&[f32]>) {}
    fn take(&mut self) -> Option<FlowStatus> {
        None
    }
    fn reset(&mut self) {}
}

impl<M: Backend> FlowSlot<M> for FlowMonitor<M> {
    const ON: bool = true;
    fn record(&mut self, verdict: &Verdict, lls: Option<&[f32]>) {
        FlowMonitor::record(self, verdict, lls);
    }
    fn take(&mut self) -> Option<FlowStatus> {
        core::mem::take(&mut self.fresh).then(|| self.status())
    }
    fn reset(&mut self) {
        FlowMonitor::reset(self);
    }
}

/// `v` cut to `[lo, hi]` by comparisons (`f32::max`/`min` are library calls on the
/// Cortex-M; `v` is not NaN here).
#[inline(always)]
fn cut(v: f32, lo: f32, hi: f32) -> f32 {
    if v < lo {
        lo
    } else if v > hi {
        hi
    } else {
        v
    }
}

/// `sqrt(x)` for `x` in `(0, 0.25]` (a variance of a share) from the exponent-halving guess
/// and three Newton steps `y <- (y + x / y) / 2`: relative error below `1e-6`, a few
/// instructions with the FPU where a library `sqrtf` costs about a hundred.
fn sqrt_newton(x: f32) -> f32 {
    let mut y = f32::from_bits((x.to_bits() >> 1) + 0x1FBD_1DF5);
    for _ in 0..3 {
        y = 0.5 * (y + x / y);
    }
    y
}

/// What the user states: the background share, the level to close at, the false-alarm rate,
/// the memory of the share estimate and which classes are gangue.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FlowConfig {
    /// Gangue share `pi0` of the flow while coal comes (the background), in `(0, 1)`.
    pub pre_share: f32,
    /// Gangue share `pi1` at which the window should close, in `(pre_share, 1)`: the CUSUM's
    /// alternative (shares above it are found sooner, shares just below it later).
    pub level: f32,
    /// At most one false alarm per `1 / false_alarm_rate` impacts of background flow:
    /// alarms per impact, in `(0, 1)` (e.g. `1e-5`).
    pub false_alarm_rate: f32,
    /// Memory of the share estimate in impacts, `W >= 1` (forgetting factor `1 - 1 / W`).
    pub window_impacts: u32,
    /// Bit `c` set: class `c` is gangue; the other classes of the scene are coal. At least one
    /// class of each.
    pub gangue_classes: u32,
}

impl FlowConfig {
    /// Background `pre_share`, closing `level`, `false_alarm_rate` per impact, a 100-impact
    /// memory, and every class but class 0 gangue.
    ///
    /// ```
    /// let c = coalshock::flow::FlowConfig::new(0.05, 0.5, 1e-5);
    /// assert_eq!(c.gangue_classes, !1);
    /// ```
    pub fn new(pre_share: f32, level: f32, false_alarm_rate: f32) -> Self {
        Self {
            pre_share,
            level,
            false_alarm_rate,
            window_impacts: 100,
            gangue_classes: !1,
        }
    }

    /// Checks every field, each error naming its field: `pre_share` and `level` in
    /// `(0, 1)` with `pre_share < level`, `false_alarm_rate` in `(0, 1)`, `window_impacts >= 1`.
    ///
    /// ```
    /// use coalshock::{Error, flow::FlowConfig};
    /// assert_eq!(FlowConfig::new(0.05, 0.5, 1.0).check(),
    ///            Err(Error::OutOfRange("false_alarm_rate")));
    /// assert_eq!(FlowConfig::new(0.05, 0.02, 1e-5).check(), Err(Error::OutOfRange("level")));
    /// ```
    pub fn check(&self) -> Result<(), Error> {
        let open_unit = |v: f32| v > 0.0 && v < 1.0;
        if !open_unit(self.pre_share) {
            return Err(Error::OutOfRange("pre_share"));
        }
        if !open_unit(self.level) || self.level <= self.pre_share {
            return Err(Error::OutOfRange("level"));
        }
        if !open_unit(self.false_alarm_rate) {
            return Err(Error::OutOfRange("false_alarm_rate"));
        }
        if self.window_impacts == 0 {
            return Err(Error::NonPositive("window_impacts"));
        }
        Ok(())
    }

    /// The CUSUM threshold `h = ln(1 / false_alarm_rate)` in nats.
    ///
    /// ```
    /// let h = coalshock::flow::FlowConfig::new(0.05, 0.5, 1e-5).threshold::<coalshock::math::Libm>();
    /// assert!((h - 11.5129).abs() < 1e-3);
    /// ```
    pub fn threshold<M: Backend>(&self) -> f32 {
        -M::ln(self.false_alarm_rate)
    }
}

/// What the flow monitor says after a pulse.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FlowStatus {
    /// Pulses whose likelihoods were used.
    pub pulses: u32,
    /// Pulses left out (rejected, out of envelope, no finite likelihood).
    pub left_out: u32,
    /// Estimated gangue share of the recent flow (memory `window_impacts`).
    pub share: f32,
    /// Its standard error.
    pub std_error: f32,
    /// The CUSUM statistic `S` in nats.
    pub cusum: f32,
    /// `S` has reached the threshold: close the window (latched until [`FlowMonitor::reset`]).
    pub alarm: bool,
}

/// A validated [`FlowConfig`] with its running state (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct FlowMonitor<M: Backend = DefaultBackend> {
    config: FlowConfig,
    threshold: f32,
    forget: f32,
    /// `ln` of the summed prior weight of the gangue and of the coal classes.
    ln_prior_gangue: f32,
    ln_prior_coal: f32,
    ln_priors: [f32; MAX_CLASSES],
    classes: u8,
    /// `(gangue, coal)` class indices when each group is one class (the ratio is then a
    /// difference of two log-likelihoods).
    pair: Option<(u8, u8)>,
    state: FlowState,
    /// A status not yet taken ([`FlowSlot::take`]).
    fresh: bool,
    backend: M,
}

/// The running part of a [`FlowMonitor`].
#[derive(Debug, Clone, Copy, PartialEq)]
struct FlowState {
    pulses: u32,
    left_out: u32,
    share: f32,
    information: f32,
    weight: f32,
    weight2: f32,
    cusum: f32,
    alarm: bool,
}

impl FlowState {
    fn new(pre_share: f32) -> Self {
        Self {
            pulses: 0,
            left_out: 0,
            share: pre_share,
            information: 0.0,
            weight: 0.0,
            weight2: 0.0,
            cusum: 0.0,
            alarm: false,
        }
    }
}

impl<M: Backend> FlowMonitor<M> {
    /// A flow monitor for `scene`'s classes: [`FlowConfig::check`], then the gangue mask
    /// against the scene (`OutOfRange("gangue_classes")` unless it names at least one and
    /// leaves at least one of the scene's classes).
    ///
    /// ```
    /// use coalshock::{Scene, flow::{FlowConfig, FlowMonitor}};
    /// let scene: Scene = Scene::paper().unwrap();
    /// let flow: FlowMonitor = FlowMonitor::new(FlowConfig::new(0.05, 0.5, 1e-5), &scene).unwrap();
    /// assert!(!flow.status().alarm);
    /// ```
    pub fn new<const N: usize>(config: FlowConfig, scene: &Scene<N, M>) -> Result<Self, Error> {
        config.check()?;
        let n = scene.classes().len();
        let all = if n >= 32 { u32::MAX } else { (1u32 << n) - 1 };
        let mask = config.gangue_classes & all;
        if mask == 0 || mask == all {
            return Err(Error::OutOfRange("gangue_classes"));
        }
        let mut ln_priors = [f32::NEG_INFINITY; MAX_CLASSES];
        for (slot, &lp) in ln_priors.iter_mut().zip(scene.ln_priors()) {
            *slot = lp;
        }
        let mut this = Self {
            config: FlowConfig {
                gangue_classes: mask,
                ..config
            },
            threshold: config.threshold::<M>(),
            forget: 1.0 - 1.0 / config.window_impacts as f32,
            ln_prior_gangue: 0.0,
            ln_prior_coal: 0.0,
            ln_priors,
            classes: n as u8,
            pair: None,
            state: FlowState::new(config.pre_share),
            fresh: false,
            backend: M::default(),
        };
        if mask.count_ones() == 1 && n == 2 {
            let g = mask.trailing_zeros() as u8;
            this.pair = Some((g, 1 - g));
        }
        let zeros = [0.0f32; MAX_CLASSES];
        let (g, c) = this.group_ln_likelihoods(&zeros);
        this.ln_prior_gangue = g;
        this.ln_prior_coal = c;
        Ok(this)
    }

    /// The configuration (the gangue mask cut to the scene's classes).
    pub fn config(&self) -> &FlowConfig {
        &self.config
    }

    /// The CUSUM threshold `h = ln(1 / false_alarm_rate)` in nats.
    pub fn threshold(&self) -> f32 {
        self.threshold
    }

    /// Starts a new round: share back to `pre_share`, statistic to 0, alarm off, counts to 0.
    pub fn reset(&mut self) {
        self.state = FlowState::new(self.config.pre_share);
        self.fresh = false;
    }

    /// `(ln sum_G prior_j L_j, ln sum_C prior_j L_j)` by log-sum-exp over each group.
    fn group_ln_likelihoods(&self, lls: &[f32]) -> (f32, f32) {
        let n = (self.classes as usize).min(lls.len());
        let terms = lls.iter().zip(self.ln_priors.iter()).take(n);
        let group = |i: usize| ((self.config.gangue_classes >> i) & 1) == 1;
        let (mut max_g, mut max_c) = (f32::NEG_INFINITY, f32::NEG_INFINITY);
        for (i, (&ll, &lp)) in terms.clone().enumerate() {
            let m = if group(i) { &mut max_g } else { &mut max_c };
            if ll + lp > *m {
                *m = ll + lp;
            }
        }
        let (mut sum_g, mut sum_c) = (0.0f32, 0.0f32);
        for (i, (&ll, &lp)) in terms.enumerate() {
            let (s, m) = if group(i) {
                (&mut sum_g, max_g)
            } else {
                (&mut sum_c, max_c)
            };
            *s += if ll + lp == m {
                1.0
            } else {
                M::exp(ll + lp - m)
            };
        }
        let lse = |m: f32, s: f32| if s == 1.0 { m } else { m + M::ln(s) };
        (lse(max_g, sum_g), lse(max_c, sum_c))
    }

    /// `ln(p_G / p_C)` of a pulse with class log-likelihoods `lls` (element `c` for class
    /// `c`, without priors, as [`Scene::classify_with_likelihoods`] gives them), cut to
    /// `+-MAX_LN_RATIO`; `None` when neither group has a finite likelihood.
    ///
    /// ```
    /// use coalshock::{Scene, flow::{FlowConfig, FlowMonitor}};
    /// let scene: Scene = Scene::paper().unwrap();
    /// let flow: FlowMonitor = FlowMonitor::new(FlowConfig::new(0.05, 0.5, 1e-5), &scene).unwrap();
    /// assert_eq!(flow.ln_ratio(&[-1.0, 1.0]), Some(2.0));
    /// assert_eq!(flow.ln_ratio(&[f32::NEG_INFINITY; 2]), None);
    /// ```
    pub fn ln_ratio(&self, lls: &[f32]) -> Option<f32> {
        let (g, c) = match self.pair {
            Some((g, c)) => (
                lls.get(g as usize).copied().unwrap_or(f32::NEG_INFINITY),
                lls.get(c as usize).copied().unwrap_or(f32::NEG_INFINITY),
            ),
            None => self.group_ln_likelihoods(lls),
        };
        let d = (g - self.ln_prior_gangue) - (c - self.ln_prior_coal);
        if d.is_nan() || (g == f32::NEG_INFINITY && c == f32::NEG_INFINITY) {
            return None;
        }
        Some(cut(d, -MAX_LN_RATIO, MAX_LN_RATIO))
    }

    /// The CUSUM increment of one pulse with likelihood ratio `r = e^ln_ratio`:
    /// `ln[(pi1 r + 1 - pi1) / (pi0 r + 1 - pi0)]` in nats.
    ///
    /// ```
    /// use coalshock::{Scene, flow::{FlowConfig, FlowMonitor}};
    /// let scene: Scene = Scene::paper().unwrap();
    /// let flow: FlowMonitor = FlowMonitor::new(FlowConfig::new(0.05, 0.5, 1e-5), &scene).unwrap();
    /// assert!((flow.increment(30.0) - 10.0f32.ln()).abs() < 1e-4); // a sure gangue lump
    /// assert!(flow.increment(0.0).abs() < 1e-6); // a pulse that tells nothing
    /// ```
    pub fn increment(&self, ln_ratio: f32) -> f32 {
        let r = M::exp(ln_ratio);
        let (p0, p1) = (self.config.pre_share, self.config.level);
        M::ln((p1 * r + (1.0 - p1)) / (p0 * r + (1.0 - p0)))
    }

    /// Takes one pulse's verdict and class log-likelihoods (as
    /// [`Scene::classify_with_likelihoods`] returns them): a `Class` or `Ambiguous` verdict
    /// with a finite ratio updates the share and the CUSUM ([`FlowMonitor::update`]); anything
    /// else is left out and counted. Returns whether the pulse was used.
    pub fn record(&mut self, verdict: &Verdict, lls: Option<&[f32]>) -> bool {
        self.fresh = true;
        let ratio = match (verdict, lls) {
            (Verdict::Class { .. } | Verdict::Ambiguous { .. }, Some(l)) => self.ln_ratio(l),
            _ => None,
        };
        match ratio {
            Some(d) => {
                self.update(d);
                true
            }
            None => {
                self.state.left_out = self.state.left_out.saturating_add(1);
                false
            }
        }
    }

    /// One used pulse with `ln(p_G / p_C) = ln_ratio` (see the module docs for the formulas).
    pub fn update(&mut self, ln_ratio: f32) {
        // Not NaN: a NaN ratio counts as no information (0).
        let d = if ln_ratio.is_nan() {
            0.0
        } else {
            cut(ln_ratio, -MAX_LN_RATIO, MAX_LN_RATIO)
        };
        let r = M::exp(d);
        let (p0, p1) = (self.config.pre_share, self.config.level);
        let s = &mut self.state;
        let step = M::ln((p1 * r + (1.0 - p1)) / (p0 * r + (1.0 - p0)));
        let cusum = s.cusum + step;
        s.cusum = if cusum > 0.0 { cusum } else { 0.0 };
        s.alarm |= s.cusum >= self.threshold;
        let mix = s.share * r + (1.0 - s.share);
        let g = (r - 1.0) / mix;
        let w = s.share * r / mix;
        let k = self.forget;
        s.information = k * s.information + g * g;
        s.weight = k * s.weight + 1.0;
        s.weight2 = k * k * s.weight2 + 1.0;
        let share = s.share + (1.0 - k) * (w - s.share);
        s.share = cut(share, SHARE_FLOOR, 1.0 - SHARE_FLOOR);
        s.pulses = s.pulses.saturating_add(1);
    }

    /// Counts a pulse left out (e.g. a rejected one).
    pub fn leave_out(&mut self) {
        self.state.left_out = self.state.left_out.saturating_add(1);
    }

    /// The share, its standard error, the statistic and the alarm now.
    pub fn status(&self) -> FlowStatus {
        let s = &self.state;
        let var = s.weight2 / (s.weight * s.information);
        let std_error = if var > 0.0 && var < 0.25 {
            sqrt_newton(var)
        } else {
            0.5
        };
        FlowStatus {
            pulses: s.pulses,
            left_out: s.left_out,
            share: s.share,
            std_error,
            cusum: s.cusum,
            alarm: s.alarm,
        }
    }

    /// The math backend.
    pub fn backend(&self) -> M {
        self.backend
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;

    fn paper() -> Scene<4, Libm> {
        Scene::<4, Libm>::paper_for().unwrap_or_else(|_| unreachable!())
    }

    fn monitor(config: FlowConfig) -> FlowMonitor<Libm> {
        FlowMonitor::new(config, &paper()).unwrap_or_else(|_| unreachable!())
    }

    #[test]
    fn newton_square_root_is_within_a_millionth() {
        let mut x = 1e-12f32;
        while x <= 0.25 {
            let rel = (sqrt_newton(x) as f64 / (x as f64).sqrt() - 1.0).abs();
            assert!(rel < 1e-6, "{x}: {rel}");
            x *= 1.07;
        }
    }

    #[test]
    fn bad_inputs_name_their_field() {
        let s = paper();
        let base = FlowConfig::new(0.05, 0.5, 1e-5);
        let err = |c: FlowConfig| FlowMonitor::<Libm>::new(c, &s).err();
        for rate in [0.0, 1.0, -1e-3, 2.0, f32::NAN] {
            let c = FlowConfig {
                false_alarm_rate: rate,
                ..base
            };
            assert_eq!(err(c), Some(Error::OutOfRange("false_alarm_rate")));
        }
        for level in [0.05, 0.01, 1.0, f32::NAN] {
            let c = FlowConfig { level, ..base };
            assert_eq!(err(c), Some(Error::OutOfRange("level")));
        }
        for pre_share in [0.0, 1.0, f32::NAN] {
            let c = FlowConfig { pre_share, ..base };
            assert_eq!(err(c), Some(Error::OutOfRange("pre_share")));
        }
        let c = FlowConfig {
            window_impacts: 0,
            ..base
        };
        assert_eq!(err(c), Some(Error::NonPositive("window_impacts")));
        for mask in [0, 0b11, 0b100] {
            let c = FlowConfig {
                gangue_classes: mask,
                ..base
            };
            assert_eq!(err(c), Some(Error::OutOfRange("gangue_classes")));
        }
    }

    #[test]
    fn sure_gangue_raises_the_alarm_after_h_over_ln_ten_pulses() {
        let mut f = monitor(FlowConfig::new(0.05, 0.5, 1e-5));
        // Each sure gangue pulse adds ln(0.5 / 0.05) = ln 10; h = ln 1e5 = 5 ln 10.
        for i in 1..=5 {
            assert!(!f.status().alarm, "alarm before pulse {i}");
            f.update(MAX_LN_RATIO);
        }
        assert!(f.status().alarm);
        f.reset();
        assert_eq!(f.status().cusum, 0.0);
        assert!(!f.status().alarm);
    }

    #[test]
    fn share_estimate_follows_perfect_labels() {
        let mut f = monitor(FlowConfig {
            window_impacts: 200,
            ..FlowConfig::new(0.05, 0.5, 1e-5)
        });
        // Every third pulse a sure gangue lump: the share converges near 1/3.
        for i in 0..2000 {
            f.update(if i % 3 == 0 {
                MAX_LN_RATIO
            } else {
                -MAX_LN_RATIO
            });
        }
        let s = f.status();
        assert!((s.share - 1.0 / 3.0).abs() < 0.03, "{s:?}");
        // Perfect labels over ~200 impacts: sqrt(p (1 - p) / 400) with the weights' spread.
        assert!(s.std_error > 0.015 && s.std_error < 0.04, "{s:?}");
    }

    #[test]
    fn rejected_and_uninformative_pulses_are_left_out_and_counted() {
        let mut f = monitor(FlowConfig::new(0.05, 0.5, 1e-5));
        let rejected = Verdict::Rejected(crate::classifier::RejectReason::PileUp);
        assert!(!f.record(&rejected, None));
        let amb = Verdict::Ambiguous {
            best: 0,
            posterior: 0.6,
        };
        assert!(!f.record(&amb, Some(&[f32::NEG_INFINITY; 4])));
        assert!(f.record(
            &amb,
            Some(&[0.0, 0.1, f32::NEG_INFINITY, f32::NEG_INFINITY])
        ));
        let s = f.status();
        assert_eq!((s.pulses, s.left_out), (1, 2));
    }
}
