//! From a measured pulse `(F_max, t_c)` to a verdict against the scene's class envelopes.

use crate::chain_bias::ChainSpread;
use crate::envelope::{Envelope, HERTZ_SLOPES, Inverted, NoiseXy, Side};
use crate::math::Backend;
use crate::scene::Scene;

/// A pulse the detector measured: peak contact force and contact duration, with their
/// standard deviations in log units (from the noise and the sampling).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Measurement {
    /// Peak contact force in N.
    pub peak_force_n: f32,
    /// Contact duration in s.
    pub duration_s: f32,
    /// Standard deviation of `ln F_max`.
    pub sigma_ln_force: f32,
    /// Standard deviation of `ln t_c`.
    pub sigma_ln_duration: f32,
    /// Covariance of `ln F_max` and `ln t_c` (log units squared). The duration is the area over
    /// the peak, `ln t_c = ln sum - ln F_max + const`, so it is `cov(ln sum, ln F_max) -
    /// sigma_ln_force^2`: about `-sigma_ln_force^2` when the peak and the area share little
    /// noise.
    pub cov_ln: f32,
    /// Neighbour asymmetry of the pulse's largest sample
    /// ([`crate::sampled_phase::neighbour_asymmetry`], `-1..=1`; 0 when the pulse was not
    /// read with three samples): the sampling phase, for [`crate::SampledPhase`].
    pub asymmetry: f32,
    /// How far the measured peak lies above the level that started the pulse, in standard
    /// deviations of the peak's noise: `(F_max - F_trigger) / sigma_F` (dimensionless;
    /// `f32::INFINITY` for a pulse not found by a trigger, or measured from its clipped
    /// flanks, far above it). Below [`TRIGGER_MARGIN`] the pulse may have been found only
    /// because the noise lifted it over the trigger, and that noise is in its measurement:
    /// such a pulse gets no `Class` verdict (see [`Scene::classify`]).
    pub trigger_margin: f32,
    /// Measured by its contact's shape: from its clipped flanks (the detector's flank fit), or
    /// a short damped pulse from its five samples about the largest
    /// ([`crate::short_pulse::short_shape_fit`]). Its peak and duration are then the
    /// continuous pulse's, which the scene's sampling corrections (of a fit through the top's
    /// samples) do not apply to. With the `pulse_shape` feature only (without it, only an
    /// undamped pulse, whose sampling needs no correction, is measured from its flanks).
    #[cfg(feature = "pulse_shape")]
    pub shape_fitted: bool,
}

/// The least [`Measurement::trigger_margin`] of a `Class` verdict: 3 standard deviations. A
/// pulse whose true peak lies below the trigger is measured that far above it with
/// probability at most `1 - Phi(3) = 0.13 %`; closer to the trigger, the pulses the noise
/// lifted over it are found and the ones it pushed down are not, so the measured peak is
/// biased up and the duration, the area over the peak, down (`evaluate`'s table by peak over
/// noise shows it).
pub const TRIGGER_MARGIN: f32 = 3.0;

/// Why a pulse got no class at all.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RejectReason {
    /// A sample reached the ADC's full scale, and the pulse could not be measured from its
    /// unclipped flanks (too few left, a contact whose shape the scene does not carry, a
    /// chain, or a fit that does not describe it), or a flat top clipped below full scale.
    Saturated,
    /// One sample stands alone above the threshold (EMI spike, not an impact).
    Spike,
    /// Two impacts overlap (more than one peak in one pulse).
    PileUp,
    /// Longer than any class allows (or the sensor is stuck above the threshold).
    TooLong,
    /// The stream ended in the middle of the pulse.
    Truncated,
    /// Samples were lost during the pulse.
    Gap,
    /// The measurement is not a finite positive force and duration.
    Implausible,
    /// One peak, but not the Hertz shape: the energy-to-area ratio
    /// `(sum v^2 / C_ENERGY F_max^2) / (sum v / C_AREA F_max)` departs from 1 by more than the
    /// scene's `shape_tolerance` (two impacts within one contact, a distorted pulse).
    Misshapen,
    /// Shorter than [`crate::detector::MIN_DURATION_SAMPLES`]: too few samples to measure
    /// peak and duration (the sample rate is too low for this pulse).
    TooShort,
    /// The baseline lagged a DC drift faster than it can follow: the pre-trigger samples sat
    /// more than half the trigger level off it, so peak and area would be biased.
    Drift,
}

impl RejectReason {
    /// Every reason, in the order [`crate::counters::Counters`] stores them.
    pub const ALL: [RejectReason; 10] = [
        RejectReason::Saturated,
        RejectReason::Spike,
        RejectReason::PileUp,
        RejectReason::TooLong,
        RejectReason::Truncated,
        RejectReason::Gap,
        RejectReason::Implausible,
        RejectReason::Misshapen,
        RejectReason::TooShort,
        RejectReason::Drift,
    ];

    /// Index into [`Self::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// Short lower-case name for logs and reports.
    pub fn name(self) -> &'static str {
        match self {
            RejectReason::Saturated => "saturated",
            RejectReason::Spike => "spike",
            RejectReason::PileUp => "pileup",
            RejectReason::TooLong => "too_long",
            RejectReason::Truncated => "truncated",
            RejectReason::Gap => "gap",
            RejectReason::Implausible => "implausible",
            RejectReason::Misshapen => "misshapen",
            RejectReason::TooShort => "too_short",
            RejectReason::Drift => "drift",
        }
    }
}

/// The verdict on one pulse.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Verdict {
    /// The class with posterior at least the scene's confidence threshold,
    /// `1 - confident_error_rate`, of a pulse [`TRIGGER_MARGIN`] standard deviations or more
    /// above its trigger.
    Class {
        /// Index into [`Scene::classes`].
        class: u8,
        /// Posterior probability of that class.
        posterior: f32,
    },
    /// Inside the overlap of two or more envelopes: no class reaches the confidence threshold
    /// (or the pulse lies within [`TRIGGER_MARGIN`] standard deviations of its trigger).
    Ambiguous {
        /// The most probable class (the forced choice).
        best: u8,
        /// Its posterior.
        posterior: f32,
    },
    /// Further than the scene's `out_sigmas` outside every envelope.
    OutOfEnvelope {
        /// The class whose envelope is nearest.
        nearest: u8,
        /// The radius that class would need, against its range.
        radius: Side,
        /// The speed that class would need, against its range.
        speed: Side,
    },
    /// No class: the pulse is not a clean single impact.
    Rejected(RejectReason),
}

impl Verdict {
    /// The forced choice: the class of `Class`, the best of `Ambiguous`, the nearest of
    /// `OutOfEnvelope`; `None` when rejected.
    pub fn forced_choice(&self) -> Option<u8> {
        match *self {
            Verdict::Class { class, .. } => Some(class),
            Verdict::Ambiguous { best, .. } => Some(best),
            Verdict::OutOfEnvelope { nearest, .. } => Some(nearest),
            Verdict::Rejected(_) => None,
        }
    }
}

/// A measured pulse as the classifier weighs it (see `Scene::pulse_point`).
struct PulsePoint {
    /// `ln F_max` (F in N) and `ln t_c` (t in s).
    lf: f32,
    lt: f32,
    /// Standard deviations of `ln F_max` and `ln t_c` with the model's, and their covariance.
    sf: f32,
    st: f32,
    cov: f32,
    /// That noise, and widened by the chain's spread.
    noise: NoiseXy,
    chain: ChainSpread,
    wide: NoiseXy,
}

/// What weighing the classes found (see `Scene::weigh_classes`).
struct Weighed {
    /// The nearest class and its squared distance in sigmas.
    nearest: u8,
    nearest_d: f32,
    /// The best class on the measurement's own noise, and its log-likelihood with prior.
    best: u8,
    best_ll: f32,
}

/// Step in `ln n` of the central difference that takes the phase table's slopes (half its
/// row step, `ln 1.25 / 2`).
#[cfg(feature = "sampled_phase")]
const SLOPE_STEP: f32 = 0.111_571_78;

/// `(var ln F, var ln t_c, cov)` of a measurement's own noise.
fn own_noise(m: &Measurement) -> (f32, f32, f32) {
    (
        m.sigma_ln_force * m.sigma_ln_force,
        m.sigma_ln_duration * m.sigma_ln_duration,
        m.cov_ln,
    )
}

/// `(var ln F, var ln t_c, cov)` of a measurement's noise as the phase table's correction
/// reads it. The table is read at the samples per pulse the measured duration gives, so the
/// duration's noise moves the correction: with its slopes `s_f`, `s_t` in `ln n` (a central
/// difference between the corrections `up` and `down`, [`SLOPE_STEP`] either side), `ln n`
/// moves by `d ln t / (1 + s_t)` at the fixed point, the corrected `ln F` by
/// `d ln F - s_f d ln t / (1 + s_t)` and the corrected `ln t` by `d ln t / (1 + s_t)`
/// (`1 + s_t` held at 0.5 at least).
#[cfg(feature = "sampled_phase")]
fn read_noise(
    m: &Measurement,
    up: (f32, f32, f32, f32),
    down: (f32, f32, f32, f32),
) -> (f32, f32, f32) {
    let s_f = (up.0 - down.0) / (2.0 * SLOPE_STEP);
    let s_t = (up.1 - down.1) / (2.0 * SLOPE_STEP);
    let g = 1.0 / (1.0 + s_t).max(0.5);
    let k = -s_f * g;
    let (mf, mt, mc) = (m.sigma_ln_force, m.sigma_ln_duration, m.cov_ln);
    (
        (mf * mf + 2.0 * k * mc + k * k * mt * mt).max(0.0),
        g * g * mt * mt,
        g * (mc + k * mt * mt),
    )
}

/// The noise class `env` weighs the pulse point `p` on, `(own, widened by the chain's bias)`:
/// a bent class carries the point's noise through its own map at the point, any other the
/// point's.
#[inline(always)]
fn class_noise<M: Backend>(env: &Envelope, p: &PulsePoint) -> (NoiseXy, NoiseXy) {
    env.bent_noise::<M>((p.lf, p.lt), (p.sf, p.st, p.cov), &p.chain)
        .unwrap_or((p.noise, p.wide))
}

impl<const N: usize, M: Backend> Scene<N, M> {
    /// Classifies a measured pulse.
    ///
    /// The noise of `ln F_max` and `ln t_c` is the measurement's own combined in quadrature with
    /// the scene's `model_sigma`, and with the bias a chain known only to its tolerance can
    /// leave at the pulse's duration ([`Scene::chain_bias`]). If the pulse is more than `out_sigmas` outside every envelope
    /// it is `OutOfEnvelope` (with the nearest class); otherwise the posterior of class `c` is
    /// `prior_c L_c / sum_j prior_j L_j` with `L` from [`crate::envelope::Envelope::ln_likelihood`],
    /// and the best class is reported as `Class` when its posterior reaches
    /// `1 - confident_error_rate` and the pulse lies [`TRIGGER_MARGIN`] standard deviations
    /// above its trigger ([`Measurement::trigger_margin`]), else `Ambiguous`. Never panics: a
    /// non-finite or non-positive measurement is `Rejected(Implausible)`.
    pub fn classify(&self, m: &Measurement) -> Verdict {
        self.classify_with_likelihoods(m).0
    }

    /// [`Scene::classify`], and with it the class log-likelihoods it weighed: element `c` is
    /// `ln L_c` of class `c` (without its prior; `-inf` where f32 rounds the likelihood to
    /// zero; classes past [`Scene::classes`] are `-inf`), or `None` when the measurement is
    /// `Rejected(Implausible)`. The verdict is exactly [`Scene::classify`]'s.
    ///
    /// ```
    /// use coalshock::{Measurement, Scene, Verdict};
    /// let scene: Scene = Scene::paper().unwrap();
    /// let m = Measurement { peak_force_n: 2000.0, duration_s: 1.2e-4,
    ///                       sigma_ln_force: 0.01, sigma_ln_duration: 0.01,
    ///                       cov_ln: -1e-4, asymmetry: 0.0,
    ///                       trigger_margin: f32::INFINITY,
    ///                       #[cfg(feature = "pulse_shape")] shape_fitted: false };
    /// let (verdict, lls) = scene.classify_with_likelihoods(&m);
    /// assert_eq!(verdict, scene.classify(&m));
    /// assert!(lls.is_some());
    /// ```
    #[inline(never)]
    pub fn classify_with_likelihoods(&self, m: &Measurement) -> (Verdict, Option<[f32; N]>) {
        let Some(h) = self.plausible_hertz(m) else {
            return (Verdict::Rejected(RejectReason::Implausible), None);
        };
        let m = &h;
        let point = self.pulse_point(m);
        let mut lls = [f32::NEG_INFINITY; crate::scene::MAX_CLASSES];
        let mut class_lls = [f32::NEG_INFINITY; N];
        let w = self.weigh_classes(&point, &mut lls, &mut class_lls);
        let s = self.settings();
        let best_wide = lls
            .get(w.best as usize)
            .copied()
            .unwrap_or(f32::NEG_INFINITY);
        if w.nearest_d > s.out_sigmas * s.out_sigmas
            || !w.best_ll.is_finite()
            || !best_wide.is_finite()
        {
            let inv = self.invert_hertz(w.nearest, m);
            let verdict = Verdict::OutOfEnvelope {
                nearest: w.nearest,
                radius: inv.map_or(Side::Inside, |v| v.radius_side),
                speed: inv.map_or(Side::Inside, |v| v.speed_side),
            };
            return (verdict, Some(class_lls));
        }
        // Posterior of the chosen class by log-sum-exp, on the widened noise.
        let n = self.envelopes().len();
        let top = lls.iter().take(n).fold(f32::NEG_INFINITY, |a, &b| a.max(b));
        let sum: f32 = lls.iter().take(n).map(|&ll| M::exp(ll - top)).sum();
        let posterior = M::exp(best_wide - top) / sum;
        let verdict = if posterior >= s.confidence_threshold() && m.trigger_margin >= TRIGGER_MARGIN
        {
            Verdict::Class {
                class: w.best,
                posterior,
            }
        } else {
            Verdict::Ambiguous {
                best: w.best,
                posterior,
            }
        };
        (verdict, Some(class_lls))
    }

    /// The Hertz-equivalent measurement `m` as a point `(ln F_max, ln t_c)` with its noise: the
    /// measurement's sigmas (0 where not finite) in quadrature with `model_sigma`, their
    /// covariance clamped to `+-sf st`, and that noise widened by the chain's bias at `t_c`.
    #[inline(always)]
    fn pulse_point(&self, m: &Measurement) -> PulsePoint {
        let s = self.settings();
        let model2 = s.model_sigma * s.model_sigma;
        let finite_or = |v: f32| if v.is_finite() { v } else { 0.0 };
        let (a, b) = (finite_or(m.sigma_ln_force), finite_or(m.sigma_ln_duration));
        let sf = M::sqrt(a * a + model2);
        let st = M::sqrt(b * b + model2);
        let lf = M::ln(m.peak_force_n);
        let lt = M::ln(m.duration_s);
        // The duration is the area over the peak: an error of the measured `ln F_max` comes
        // with its opposite in `ln t_c` (the model's tolerance does not).
        let cov = finite_or(m.cov_ln).max(-(sf * st)).min(sf * st);
        let noise = NoiseXy::new::<M>(sf, st, cov);
        let chain = self.chain_bias().spread(lt);
        let wide = noise.with_chain::<M>(&chain, HERTZ_SLOPES);
        PulsePoint {
            lf,
            lt,
            sf,
            st,
            cov,
            noise,
            chain,
            wide,
        }
    }

    /// Weighs every class at the pulse's point: each class's log-likelihood on the widened
    /// noise with its prior into `lls` and without into `class_lls`, the nearest envelope in
    /// sigmas, and the best class chosen on the measurement's own noise.
    #[inline(always)]
    fn weigh_classes(
        &self,
        p: &PulsePoint,
        lls: &mut [f32; crate::scene::MAX_CLASSES],
        class_lls: &mut [f32; N],
    ) -> Weighed {
        let (lf, lt) = (p.lf, p.lt);
        let (mut nearest, mut nearest_d) = (0u8, f32::INFINITY);
        let mut best = 0u8;
        let mut best_ll = f32::NEG_INFINITY;
        for (i, (((env, lp), slot), raw)) in self
            .envelopes()
            .iter()
            .zip(self.ln_priors())
            .zip(lls.iter_mut())
            .zip(class_lls.iter_mut())
            .enumerate()
        {
            let (noise, wide) = class_noise::<M>(env, p);
            let d = env.outside_sigmas_squared(lf, lt, wide);
            if d < nearest_d {
                nearest_d = d;
                nearest = i as u8;
            }
            *raw = env.ln_likelihood::<M>(lf, lt, wide);
            *slot = *raw + lp;
            // The class is chosen on the measurement's own noise (the Bayes choice when the
            // chain is right); the chain's tolerance only lowers how sure the verdict is.
            let ll = if wide == noise {
                *slot
            } else {
                env.ln_likelihood::<M>(lf, lt, noise) + lp
            };
            if ll > best_ll {
                best_ll = ll;
                best = i as u8;
            }
        }
        Weighed {
            nearest,
            nearest_d,
            best,
            best_ll,
        }
    }

    /// Where class `class` puts a measured pulse, and on what noise the classifier weighs it
    /// there: the Hertz-equivalent measurement ([`Scene::hertz_equivalent`]) inverted through
    /// the class's envelope to `(x, y) = (ln R, ln u)` (R in m, u in m/s), with the standard
    /// deviations of `x` and `y` widened by the chain's bias at the pulse's duration, exactly
    /// as [`Scene::classify`] weighs the class. A host that knows the impact's true radius and
    /// speed can check the stated noise: `(x - ln R) / sigma_x` and `(y - ln u) / sigma_y`
    /// should be standard normal. `None` for a class past the scene's or a measurement
    /// `classify` rejects as implausible.
    ///
    /// ```
    /// use coalshock::{Measurement, Scene};
    /// let scene: Scene = Scene::paper().unwrap();
    /// let m = Measurement { peak_force_n: 2000.0, duration_s: 1.2e-4,
    ///                       sigma_ln_force: 0.01, sigma_ln_duration: 0.01,
    ///                       cov_ln: -1e-4, asymmetry: 0.0,
    ///                       trigger_margin: f32::INFINITY,
    ///                       #[cfg(feature = "pulse_shape")] shape_fitted: false };
    /// let (x, y, noise) = scene.located(0, &m).unwrap();
    /// let inv = scene.invert(0, &m).unwrap();
    /// assert!((x.exp() / inv.radius_m - 1.0).abs() < 1e-5);
    /// assert!((y.exp() / inv.speed_m_s - 1.0).abs() < 1e-5);
    /// assert!(noise.sigma_x > 0.0 && noise.sigma_y > 0.0);
    /// assert!(scene.located(9, &m).is_none());
    /// ```
    pub fn located(&self, class: u8, m: &Measurement) -> Option<(f32, f32, NoiseXy)> {
        let h = self.plausible_hertz(m)?;
        let env = self.envelopes().get(class as usize)?;
        let p = self.pulse_point(&h);
        let (_, wide) = class_noise::<M>(env, &p);
        let (x, y) = env.invert_ln(p.lf, p.lt);
        Some((x, y, wide))
    }

    /// The radius and speed class `class` would need for the measured pulse (after
    /// [`Scene::hertz_equivalent`]).
    pub fn invert(&self, class: u8, m: &Measurement) -> Option<Inverted> {
        self.invert_hertz(class, &self.hertz_equivalent(m))
    }

    /// The radius and speed class `class` would need for a measurement `h` that is already
    /// Hertz-equivalent (no correction applied again).
    fn invert_hertz(&self, class: u8, h: &Measurement) -> Option<Inverted> {
        self.envelopes()
            .get(class as usize)
            .map(|e| e.invert::<M>(h.peak_force_n, h.duration_s))
    }

    /// The Hertz-equivalent of `m` ([`Scene::hertz_equivalent`]) when both `m` and it are a
    /// finite positive force and duration; `None` (what `classify` rejects as implausible)
    /// otherwise.
    #[inline(always)]
    fn plausible_hertz(&self, m: &Measurement) -> Option<Measurement> {
        let ok = |m: &Measurement| {
            let pos = |v: f32| v.is_finite() && v > 0.0;
            pos(m.peak_force_n) && pos(m.duration_s)
        };
        if !ok(m) {
            return None;
        }
        let h = self.hertz_equivalent(m);
        ok(&h).then_some(h)
    }

    /// The impact of the kernel's own model (undamped Hertz, or Thornton's undamped yield for a
    /// class that states a yield pressure) a measurement stands for: `F_max / force_ratio` and
    /// `t_c / duration_ratio` of the scene's [`crate::ContactCalibration`], each also divided by
    /// (except for a pulse measured by its contact's shape, `Measurement::shape_fitted`)
    /// the sampling correction at the pulse's samples per pulse (whose spread joins the
    /// measurement's sigmas, and where the phase table is read, the measurement's own noise
    /// carried through the table's slopes in `ln n`, since the measured duration picks where
    /// it is read); the identity for an undamped elastic contact.
    pub fn hertz_equivalent(&self, m: &Measurement) -> Measurement {
        let c = &self.settings().contact;
        #[cfg(feature = "pulse_shape")]
        let shape_fitted = m.shape_fitted;
        #[cfg(not(feature = "pulse_shape"))]
        let shape_fitted = false;
        if shape_fitted || !self.settings().corrects_sampling() {
            return Measurement {
                peak_force_n: m.peak_force_n / c.force_ratio,
                duration_s: m.duration_s / c.duration_ratio,
                ..*m
            };
        }
        // The phase table where it reaches, else the correction by samples per pulse.
        #[cfg(feature = "sampled_phase")]
        let table = &self.settings().sampled_phase;
        let at = |ln_n: f32| {
            #[cfg(feature = "sampled_phase")]
            if let Some(v) = table.at(ln_n, m.asymmetry) {
                return v;
            }
            c.sampled.at(ln_n)
        };
        // The table stands at the pulse's true samples per pulse, the measured duration over
        // its correction: two fixed-point steps, which contract while the correction's
        // slope in `ln n` is below 1 (0.22 at most behind the 6.3 kHz MEMS band).
        let ln_measured = M::ln(m.duration_s * self.sensor().sample_rate_hz);
        let mut ln_n = ln_measured;
        for _ in 0..2 {
            ln_n = ln_measured - at(ln_n).1;
        }
        #[cfg(feature = "sampled_phase")]
        let read = table.at(ln_n, m.asymmetry);
        #[cfg(feature = "sampled_phase")]
        let ((lf, lt, sf, st), (var_f, var_t, cov)) = match read {
            Some(v) => (
                v,
                read_noise(m, at(ln_n + SLOPE_STEP), at(ln_n - SLOPE_STEP)),
            ),
            None => (c.sampled.at(ln_n), own_noise(m)),
        };
        #[cfg(not(feature = "sampled_phase"))]
        let ((lf, lt, sf, st), (var_f, var_t, cov)) = (at(ln_n), own_noise(m));
        Measurement {
            peak_force_n: m.peak_force_n / (c.force_ratio * M::exp(lf)),
            duration_s: m.duration_s / (c.duration_ratio * M::exp(lt)),
            sigma_ln_force: M::sqrt(var_f + sf * sf),
            sigma_ln_duration: M::sqrt(var_t + st * st),
            // The calibration's spread of the peak comes back opposite in the duration too.
            cov_ln: cov - sf * sf,
            asymmetry: m.asymmetry,
            trigger_margin: m.trigger_margin,
            #[cfg(feature = "pulse_shape")]
            shape_fitted: m.shape_fitted,
        }
    }
}
