//! Caving rounds: coal with a background gangue share, then the coal-gangue boundary (a step
//! or a ramp of the share), simulated impact by impact through the scene's contact law and
//! sensor chain into the kernel's `Monitor` with its flow monitor; the window closes at the
//! flow alarm.
//!
//! # A round
//!
//! `pre_impacts` impacts at the background share `pi0`, then `post_impacts` more whose share
//! steps to `pi1` or rises linearly to it over `ramp_impacts`. Each impact is gangue with
//! the share of its place in the round (the group's class drawn by prior), its radius and
//! speed drawn from its class, and it arrives a Poisson time after the previous one
//! (`rate_hz` impacts per s; impacts that start while the previous one is on are pile-ups,
//! which the kernel rejects). The stream ([`crate::sim::generate::generate_planned`]) is replayed
//! through `Monitor::with_flow`; each pulse is placed at the impact whose peak it reports.
//! Every round has its own seeds; the rounds are simulated on every core and taken in order
//! ([`crate::sim::par`]), so the report does not depend on the number of threads.
//!
//! # Detectors, all at the false-alarm setting `alpha` (threshold `h = ln(1 / alpha)`)
//!
//! - **kernel**: the flow monitor's alarm, as the kernel raised it online;
//! - **reference**: the same CUSUM on the exact noiseless Hertz features of the same impacts
//!   with the scene's exact class densities (f64, [`crate::score::cusum::MixtureModel`]);
//! - **label oracle**: the same CUSUM on the true labels;
//! - **naive**: close after `k` confident gangue verdicts among the last `n` pulses, `k` the
//!   smallest whose false-alarm bound is at most `alpha` ([`NaiveRule::k_for`]);
//! - **clairvoyant**: closes exactly when the true share reaches the level.
//!
//! A detector's delay counts the impacts from the change to its alarm, the alarming one
//! included; an alarm before the change is a false alarm in the round (no delay), a round
//! without an alarm counts `post_impacts + 1` and as missed.
//!
//! # Recovery and gangue content
//!
//! The recoverable coal of a round is the coal that arrives before the true share reaches the
//! level (what the clairvoyant draws). A method draws every impact up to and including its
//! alarm (all of them without one). `recovery_rate`: recoverable coal drawn over recoverable
//! coal; `gangue_content`: gangue drawn over everything drawn; both averaged over rounds.
//! Closing before the crossing loses recovery; closing after it adds gangue.
//!
//! # False alarms, measured
//!
//! `false_alarm_impacts` (default 10^6) impacts of background flow, drawn with replacement from
//! the per-pulse records (verdict and the kernel's class likelihoods) of every simulated
//! pre-change pulse of the rounds, rejected ones included, replayed through the kernel's
//! `FlowMonitor` and the naive rule (restarted after each alarm); and once from the coal
//! pulses alone. The reference and the oracle are measured on fresh draws of the exact
//! background mixture. Alarms per 10^5 impacts.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use coalshock::flow::{FlowConfig, FlowMonitor, FlowStatus};
use coalshock::math::Backend;
use coalshock::scene::{DEFAULT_CLASSES, MAX_CLASSES};
use coalshock::{Event, Monitor, Scene, Verdict};

use crate::bridge::kernel_scene::scene_to_kernel_in;
use crate::scene::{SceneFile, SpeedSpec};
use crate::score::bayes::ClassModel;
use crate::score::cusum::{Cusum, MixtureModel, NaiveRule, increment, label_increment, median_p90};
use crate::score::evaluate::class_models;
use crate::score::replay::replay_events;
use crate::score::study_error::StudyError;
use crate::sim::generate::{PlannedImpact, generate_planned};
use crate::sim::par::map_ordered;
use crate::sim::stream::StreamOptions;

/// False-alarm settings of the delay-against-false-alarm curve (alarms per impact).
pub const CURVE_RATES: [f64; 6] = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7];

/// Draws of the exact mixture behind the reference's KL divergence.
const KL_DRAWS: usize = 200_000;

/// Why caving rounds could not run: the scoring studies' one error.
pub type CavingError = StudyError;

fn opt_err(field: &'static str, problem: impl Into<String>) -> CavingError {
    StudyError::option("caving", field, problem)
}

/// How the gangue share rises when the boundary arrives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Profile {
    /// A step ([`Profile::about`]).
    Step,
    /// A linear ramp ([`Profile::about`]).
    Ramp,
}

impl Profile {
    /// Both profiles, in the order the help lists them.
    pub const ALL: [Self; 2] = [Self::Step, Self::Ramp];

    /// The name as written on the command line and in the scene's `[caving]` table.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Step => "step",
            Self::Ramp => "ramp",
        }
    }

    /// What the share does, as the help shows it.
    pub fn about(self) -> &'static str {
        match self {
            Self::Step => "From `pi0` to `pi1` at once",
            Self::Ramp => "Linearly from `pi0` to `pi1` over `ramp_impacts` impacts",
        }
    }
}

/// The `[caving]` table a scene file may carry: the change of its caving rounds (every key
/// optional; command-line flags take precedence).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CavingSpec {
    /// Background gangue share.
    pub pre_share: Option<f64>,
    /// Gangue share after the boundary arrives.
    pub post_share: Option<f64>,
    /// Share to close at.
    pub level: Option<f64>,
    /// Alarms per impact of background flow.
    pub false_alarm_rate: Option<f64>,
    /// Step or ramp.
    pub profile: Option<Profile>,
    /// Impacts of the ramp.
    pub ramp_impacts: Option<usize>,
    /// Impacts per s.
    pub rate_hz: Option<f64>,
}

/// Reads a scene file and the `[caving]` table it may carry.
pub fn load_scene(path: &std::path::Path) -> anyhow::Result<(SceneFile, CavingSpec)> {
    use anyhow::Context;
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read scene file {}", path.display()))?;
    let mut table: toml::Table =
        toml::from_str(&text).with_context(|| format!("scene file {}", path.display()))?;
    let spec = match table.remove("caving") {
        Some(v) => v
            .try_into()
            .with_context(|| format!("scene file {}: [caving]", path.display()))?,
        None => CavingSpec::default(),
    };
    let rest = toml::to_string(&table)?;
    let scene = SceneFile::from_toml_str(&rest)
        .with_context(|| format!("scene file {}", path.display()))?;
    Ok((scene, spec))
}

/// Options of [`run`].
#[derive(Debug, Clone, PartialEq)]
pub struct CavingOptions {
    /// Rounds simulated (`>= 1`).
    pub rounds: usize,
    /// Seed of every random draw.
    pub seed: u64,
    /// Background gangue share `pi0`, in `(0, 1)`.
    pub pre_share: f64,
    /// Gangue share after the boundary, `pi1`, in `(pi0, 1]`.
    pub post_share: f64,
    /// Share to close at, in `(pi0, pi1]` and below 1.
    pub level: f64,
    /// At most one false alarm per `1 / false_alarm_rate` impacts; in `(0, 1)`.
    pub false_alarm_rate: f64,
    /// Memory of the share estimate in impacts (`>= 1`).
    pub window_impacts: u32,
    /// Mean impacts per s (Poisson), `> 0`.
    pub rate_hz: f64,
    /// Step or ramp.
    pub profile: Profile,
    /// Impacts of a ramp (`>= 1`).
    pub ramp_impacts: usize,
    /// Impacts before the change (`>= 1`).
    pub pre_impacts: usize,
    /// Impacts from the change to the end of a round (`>= 1`).
    pub post_impacts: usize,
    /// Pulses the naive rule looks back on (`>= 1`).
    pub naive_n: usize,
    /// Background impacts behind each measured false-alarm rate (`>= 1`).
    pub false_alarm_impacts: usize,
    /// Name of the coal class (every other class is gangue).
    pub coal_class: String,
}

impl Default for CavingOptions {
    /// 100 rounds, seed 1, 5 % -> 50 % in a step, level 50 %, one false alarm per 10^5
    /// impacts, 100-impact memory, 20 impacts/s, 300 + 600 impacts, naive over 20 pulses,
    /// 10^6 false-alarm impacts, coal class `coal`.
    fn default() -> Self {
        Self {
            rounds: 100,
            seed: 1,
            pre_share: 0.05,
            post_share: 0.5,
            level: 0.5,
            false_alarm_rate: 1e-5,
            window_impacts: 100,
            rate_hz: 20.0,
            profile: Profile::Step,
            ramp_impacts: 100,
            pre_impacts: 300,
            post_impacts: 600,
            naive_n: 20,
            false_alarm_impacts: 1_000_000,
            coal_class: "coal".to_string(),
        }
    }
}

impl CavingOptions {
    /// Checks every option (each error names it); returns the gangue flags of the classes.
    pub fn validate(&self, scene: &SceneFile) -> Result<Vec<bool>, CavingError> {
        let open_unit = |v: f64| v > 0.0 && v < 1.0;
        let at_least_one = |field, v: usize| {
            if v >= 1 {
                Ok(())
            } else {
                Err(opt_err(field, "must be >= 1"))
            }
        };
        if !open_unit(self.false_alarm_rate) {
            return Err(opt_err(
                "false_alarm_rate",
                format!("must be in (0, 1) (got {})", self.false_alarm_rate),
            ));
        }
        if !open_unit(self.pre_share) {
            return Err(opt_err(
                "pre_share",
                format!("must be in (0, 1) (got {})", self.pre_share),
            ));
        }
        if !(self.post_share > self.pre_share && self.post_share <= 1.0) {
            return Err(opt_err(
                "post_share",
                format!("must be in (pre_share, 1] (got {})", self.post_share),
            ));
        }
        if !(self.level > self.pre_share && self.level <= self.post_share && self.level < 1.0) {
            return Err(opt_err(
                "level",
                format!(
                    "must lie between the pre- and post-change shares, ({}, {}], and below 1 (got {})",
                    self.pre_share, self.post_share, self.level
                ),
            ));
        }
        if self.window_impacts == 0 {
            return Err(opt_err("window_impacts", "must be >= 1 (got 0)"));
        }
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return Err(opt_err(
                "rate_hz",
                format!("must be finite and > 0 (got {})", self.rate_hz),
            ));
        }
        at_least_one("rounds", self.rounds)?;
        at_least_one("ramp_impacts", self.ramp_impacts)?;
        at_least_one("pre_impacts", self.pre_impacts)?;
        at_least_one("post_impacts", self.post_impacts)?;
        at_least_one("naive_n", self.naive_n)?;
        at_least_one("false_alarm_impacts", self.false_alarm_impacts)?;
        let Some(coal) = scene.classes.iter().position(|c| c.name == self.coal_class) else {
            return Err(opt_err(
                "coal_class",
                format!("names no class of the scene ({:?})", self.coal_class),
            ));
        };
        Ok((0..scene.classes.len()).map(|c| c != coal).collect())
    }

    /// The true gangue share of impact `i` of a round.
    pub fn share_at(&self, i: usize) -> f64 {
        if i < self.pre_impacts {
            return self.pre_share;
        }
        match self.profile {
            Profile::Step => self.post_share,
            Profile::Ramp => {
                let f = ((i - self.pre_impacts + 1) as f64 / self.ramp_impacts as f64).min(1.0);
                self.pre_share + f * (self.post_share - self.pre_share)
            }
        }
    }

    /// The first impact whose true share reaches the level (the clairvoyant closes before it).
    pub fn crossing(&self) -> usize {
        let n = self.pre_impacts + self.post_impacts;
        (0..n)
            .find(|&i| self.share_at(i) >= self.level - 1e-12)
            .unwrap_or(n)
    }

    /// The kernel's flow configuration for `alpha` alarms per impact.
    fn flow_config(&self, gangue: &[bool], alpha: f64) -> FlowConfig {
        let mask = gangue
            .iter()
            .enumerate()
            .fold(0u32, |m, (c, &g)| m | ((g as u32) << c));
        FlowConfig {
            pre_share: self.pre_share as f32,
            level: self.level as f32,
            false_alarm_rate: alpha as f32,
            window_impacts: self.window_impacts,
            gangue_classes: mask,
        }
    }
}

/// Median, 90th percentile and counts of a detector's delays over the rounds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Delay {
    /// Median delay in impacts (rounds with an alarm before the change left out).
    pub median: f64,
    /// 90th percentile.
    pub p90: f64,
    /// Mean.
    pub mean: f64,
    /// Rounds with an alarm at or after the change.
    pub detected: usize,
    /// Rounds without an alarm (counted as `post_impacts + 1`).
    pub missed: usize,
    /// Rounds with an alarm before the change (false alarms in the rounds).
    pub early: usize,
}

/// Recovery and gangue content of one way of closing, averaged over the rounds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Mining {
    /// Recoverable coal drawn over recoverable coal (see the module docs).
    pub recovery_rate: f64,
    /// Gangue drawn over everything drawn.
    pub gangue_content: f64,
}

/// The naive rule used.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct NaiveSetting {
    /// Confident gangue verdicts needed: the smallest `k` whose measured false-alarm rate
    /// (on the same resampled background flow as the kernel's) is at most the setting.
    pub k: usize,
    /// The smallest `k` by the bound of [`NaiveRule::k_for`] (never below `k`).
    pub k_bound: usize,
    /// Among the last `n` pulses.
    pub n: usize,
    /// Share of background pulses with a confident gangue verdict (measured).
    pub confident_gangue_rate: f64,
}

/// Measured false alarms per 10^5 impacts of background flow.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct FalseAlarms {
    /// How the kernel's and the naive rule's rates are measured.
    pub source: &'static str,
    /// Impacts behind each rate.
    pub impacts: usize,
    /// Recorded pre-change pulses drawn from.
    pub recorded_pulses: usize,
    /// Kernel flow monitor on the background flow (share `pi0`).
    pub kernel_per_1e5: f64,
    /// Kernel flow monitor on coal pulses alone.
    pub kernel_pure_coal_per_1e5: f64,
    /// Naive rule on the background flow.
    pub naive_per_1e5: f64,
    /// Reference (exact features) on fresh draws of the background mixture.
    pub reference_per_1e5: f64,
    /// Label oracle on fresh labels of the background flow.
    pub label_oracle_per_1e5: f64,
}

/// Mean CUSUM increment per impact at the post-change share (the KL divergence
/// `KL(f_pi1 || f_pi0)` when the level is the post-change share), and the Lorden delay
/// `h / KL` it predicts.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Information {
    /// Kernel: over the simulated post-change impacts (left-out pulses add 0).
    pub kernel: f64,
    /// Reference: exact features, independent draws.
    pub reference: f64,
    /// True labels (closed form).
    pub labels: f64,
}

/// One point of the delay-against-false-alarm curve.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct CurvePoint {
    /// Alarms per impact set.
    pub false_alarm_rate: f64,
    /// `h = ln(1 / rate)`.
    pub threshold_nats: f64,
    /// Kernel's false alarms per 10^5 impacts, measured as [`FalseAlarms::kernel_per_1e5`].
    pub kernel_false_alarms_per_1e5: f64,
    /// Median delays in impacts.
    pub kernel_median: f64,
    /// Reference median delay.
    pub reference_median: f64,
    /// Label-oracle median delay.
    pub label_oracle_median: f64,
    /// `h / KL` of the kernel.
    pub kernel_lorden: f64,
    /// `h / KL` of the reference.
    pub reference_lorden: f64,
}

/// The flow over one round, for the plot.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trace {
    /// `(impact, share, standard error, CUSUM)` after each used pulse.
    pub points: Vec<(usize, f64, f64, f64)>,
    /// The true share of each impact.
    pub true_share: Vec<f64>,
    /// Impact of the kernel's alarm.
    pub alarm: Option<usize>,
    /// Impact of the change.
    pub change: usize,
}

/// The result of [`run`]; `--json` prints it.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct CavingReport {
    /// Scene name.
    pub scene: String,
    /// Rounds.
    pub rounds: usize,
    /// Seed.
    pub seed: u64,
    /// `step` or `ramp`.
    pub profile: Option<Profile>,
    /// Impacts of a ramp.
    pub ramp_impacts: usize,
    /// Background share.
    pub pre_share: f64,
    /// Share after the change.
    pub post_share: f64,
    /// Share to close at.
    pub level: f64,
    /// Alarms per impact set.
    pub false_alarm_rate: f64,
    /// `h = ln(1 / false_alarm_rate)`.
    pub threshold_nats: f64,
    /// Impacts per s.
    pub rate_hz: f64,
    /// Memory of the share estimate.
    pub window_impacts: u32,
    /// Impacts before the change.
    pub pre_impacts: usize,
    /// Impacts from the change to the end of a round.
    pub post_impacts: usize,
    /// The kernel's flow alarm.
    pub detection_delay_impacts: Delay,
    /// The same CUSUM on exact noiseless features with the scene's exact likelihoods.
    pub reference_delay_impacts: Delay,
    /// The same CUSUM on the true labels.
    pub label_oracle_delay_impacts: Delay,
    /// The naive rule.
    pub naive_delay_impacts: Delay,
    /// Its setting.
    pub naive_rule: NaiveSetting,
    /// Kernel false alarms per 10^5 background impacts (measured, see `false_alarms`).
    pub false_alarms_per_1e5_impacts: f64,
    /// Every measured false-alarm rate.
    pub false_alarms: FalseAlarms,
    /// Kernel: recoverable coal drawn over recoverable coal.
    pub recovery_rate: f64,
    /// Kernel: gangue drawn over everything drawn.
    pub gangue_content: f64,
    /// Closing exactly when the true share reaches the level.
    pub clairvoyant: Mining,
    /// The naive rule.
    pub naive: Mining,
    /// The reference detector.
    pub reference: Mining,
    /// The label oracle.
    pub label_oracle: Mining,
    /// Information per impact.
    pub kl_nats_per_impact: Information,
    /// `h / KL` per detector.
    pub lorden_delay_impacts: Information,
    /// The kernel's `FlowMonitor` rerun on the recorded per-pulse ratios (the path of the
    /// false-alarm measurement and of the curve) closes every round where the online
    /// monitor did.
    pub kernel_replay_agrees: bool,
    /// Pulses reported by the kernel over all rounds.
    pub pulses: usize,
    /// Share of them the flow monitor left out (rejected, out of envelope).
    pub left_out_share: f64,
    /// Delay against false-alarm setting.
    pub curve: Vec<CurvePoint>,
    /// The flow over the first round.
    #[serde(skip)]
    pub trace: Trace,
}

/// One impact of a round.
#[derive(Debug, Clone, Copy)]
struct ImpactRec {
    gangue: bool,
    /// Exact `ln(p_G / p_C)` of its noiseless features.
    exact_ln_ratio: Option<f64>,
}

/// One pulse the kernel reported.
#[derive(Debug, Clone, Copy)]
struct PulseRec {
    /// The impact it reports.
    impact: usize,
    /// The kernel's `ln(p_G / p_C)` when the flow monitor used it.
    ln_ratio: Option<f32>,
    confident_gangue: bool,
    status: Option<FlowStatus>,
}

/// One simulated round.
#[derive(Debug, Clone)]
struct Round {
    impacts: Vec<ImpactRec>,
    pulses: Vec<PulseRec>,
}

/// SplitMix64 finaliser.
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// A class of the group `gangue`, drawn by prior within the group.
fn draw_class(models: &[ClassModel], gangue: &[bool], want: bool, u: f64) -> usize {
    let total: f64 = (0..models.len())
        .filter(|&c| gangue[c] == want)
        .map(|c| models[c].prior)
        .sum();
    let mut acc = 0.0;
    let mut last = 0;
    for c in (0..models.len()).filter(|&c| gangue[c] == want) {
        acc += models[c].prior / total;
        last = c;
        if u < acc {
            return c;
        }
    }
    last
}

/// The impacts of round `round`: classes by the share profile, sizes and speeds from the
/// classes, Poisson arrival times.
fn plan_round(
    scene: &SceneFile,
    opts: &CavingOptions,
    mixture: &MixtureModel,
    round: usize,
) -> (Vec<PlannedImpact>, Vec<ImpactRec>) {
    let mut rng = ChaCha8Rng::seed_from_u64(mix(opts.seed ^ mix(round as u64)));
    let n = opts.pre_impacts + opts.post_impacts;
    let (mut plan, mut recs) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let mut t = 0.0;
    for i in 0..n {
        let gangue = rng.random::<f64>() < opts.share_at(i);
        let class = draw_class(&mixture.models, &mixture.gangue, gangue, rng.random());
        let c = &scene.classes[class];
        let (ur, us): (f64, f64) = (rng.random(), rng.random());
        let (r0, r1) = (c.radius_m.min.ln(), c.radius_m.max.ln());
        let radius_m = (r0 + ur * (r1 - r0)).exp();
        let speed_m_s = match c.speed {
            SpeedSpec::Uniform(s) => s.min + us * (s.max - s.min),
            SpeedSpec::DropHeight(h) => crate::scene::drop_speed_m_s(h.min + us * (h.max - h.min)),
        };
        let (lf, lt) = mixture.models[class].forward(radius_m.ln(), speed_m_s.ln());
        plan.push(PlannedImpact {
            class,
            radius_m,
            speed_m_s,
            start_s: t,
        });
        recs.push(ImpactRec {
            gangue,
            exact_ln_ratio: mixture.ln_ratio(lf, lt),
        });
        t += -(1.0 - rng.random::<f64>()).ln() / opts.rate_hz;
    }
    (plan, recs)
}

/// Simulates round `round` and replays it through a `Monitor` with the flow monitor.
fn simulate_round<const N: usize, M: Backend>(
    scene: &SceneFile,
    kernel: &Scene<N, M>,
    opts: &CavingOptions,
    mixture: &MixtureModel,
    round: usize,
) -> Result<Round, CavingError> {
    let (plan, impacts) = plan_round(scene, opts, mixture, round);
    let seed = mix(opts.seed.wrapping_add(0x5eed) ^ mix(round as u64));
    let stream = generate_planned(scene, &plan, seed, &StreamOptions::default())?;
    let config = opts.flow_config(&mixture.gangue, opts.false_alarm_rate);
    let mut monitor = Monitor::new(kernel.clone())
        .with_flow(config)
        .map_err(|e| opt_err("flow", e.to_string()))?;
    let flow = FlowMonitor::<M>::new(config, kernel).map_err(|e| opt_err("flow", e.to_string()))?;
    let peaks: Vec<u64> = stream.truth.iter().map(|t| t.peak_sample).collect();
    let mut pulses: Vec<PulseRec> = Vec::new();
    for e in replay_events(&stream, &mut monitor) {
        match e {
            Event::Pulse(r) => {
                let impact = peaks.partition_point(|&p| p <= r.at_sample + 3).max(1) - 1;
                let lls = r
                    .measurement
                    .and_then(|m| kernel.classify_with_likelihoods(&m).1);
                let used = matches!(r.verdict, Verdict::Class { .. } | Verdict::Ambiguous { .. });
                let ln_ratio = lls.filter(|_| used).and_then(|l| flow.ln_ratio(&l));
                let confident_gangue = matches!(r.verdict,
                    Verdict::Class { class, .. } if mixture.gangue.get(class as usize) == Some(&true));
                pulses.push(PulseRec {
                    impact,
                    ln_ratio,
                    confident_gangue,
                    status: None,
                });
            }
            Event::Flow(s) => {
                if let Some(p) = pulses.last_mut() {
                    p.status = Some(s);
                }
            }
            Event::Stuck { .. } => {}
        }
    }
    Ok(Round { impacts, pulses })
}

/// The impact at which the kernel's flow monitor (rerun offline on the recorded ratios at
/// `alpha`) raises its alarm.
fn kernel_close<M: Backend>(round: &Round, flow: &mut FlowMonitor<M>) -> Option<usize> {
    flow.reset();
    for p in &round.pulses {
        match p.ln_ratio {
            Some(d) => flow.update(d),
            None => flow.leave_out(),
        }
        if flow.status().alarm {
            return Some(p.impact);
        }
    }
    None
}

/// The impact at which the naive rule raises its alarm.
fn naive_close(round: &Round, k: usize, n: usize) -> Option<usize> {
    let mut rule = NaiveRule::new(k, n);
    round
        .pulses
        .iter()
        .find(|p| rule.step(p.confident_gangue))
        .map(|p| p.impact)
}

/// The impact at which a CUSUM on per-impact increments raises its alarm.
fn impact_close(round: &Round, alpha: f64, inc: impl Fn(&ImpactRec) -> f64) -> Option<usize> {
    let mut c = Cusum::for_rate(alpha);
    round.impacts.iter().position(|i| c.step(inc(i)))
}

/// Delays of the closes over the rounds.
fn delays(closes: &[Option<usize>], opts: &CavingOptions) -> Delay {
    let change = opts.pre_impacts;
    let mut d = Delay::default();
    let mut v = Vec::new();
    for c in closes {
        match c {
            Some(i) if *i < change => d.early += 1,
            Some(i) => {
                d.detected += 1;
                v.push((i - change + 1) as f64);
            }
            None => {
                d.missed += 1;
                v.push((opts.post_impacts + 1) as f64);
            }
        }
    }
    (d.median, d.p90) = median_p90(&v);
    d.mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    d
}

/// Recovery and gangue content of closing at `closes` (impact drawn last; `None`: all drawn).
fn mining(rounds: &[Round], closes: &[Option<usize>], crossing: usize) -> Mining {
    let mut m = Mining::default();
    for (r, c) in rounds.iter().zip(closes) {
        let drawn = c.map_or(r.impacts.len(), |i| i + 1);
        let coal = |end: usize| r.impacts[..end].iter().filter(|i| !i.gangue).count() as f64;
        let recoverable = coal(crossing.min(r.impacts.len()));
        m.recovery_rate += if recoverable > 0.0 {
            coal(drawn.min(crossing)) / recoverable
        } else {
            1.0
        };
        m.gangue_content += (drawn as f64 - coal(drawn)) / drawn.max(1) as f64;
    }
    let n = rounds.len().max(1) as f64;
    m.recovery_rate /= n;
    m.gangue_content /= n;
    m
}

/// The naive rule at the false-alarm setting (see [`NaiveSetting`]).
fn naive_setting(pre: &[&PulseRec], opts: &CavingOptions, q0: f64) -> NaiveSetting {
    let n = opts.naive_n;
    let allowed = opts.false_alarm_rate * opts.false_alarm_impacts as f64;
    let k = (1..=n)
        .find(|&k| {
            if pre.is_empty() {
                return false;
            }
            let mut rng = ChaCha8Rng::seed_from_u64(mix(opts.seed ^ 0xFA15E));
            let mut rule = NaiveRule::new(k, n);
            let alarms = (0..opts.false_alarm_impacts)
                .filter(|_| {
                    let p = pre[rng.random_range(0..pre.len())];
                    rule.step(p.confident_gangue)
                })
                .count();
            alarms as f64 <= allowed
        })
        .unwrap_or(n);
    NaiveSetting {
        k,
        k_bound: NaiveRule::k_for(q0, n, opts.false_alarm_rate),
        n,
        confident_gangue_rate: q0,
    }
}

/// Alarms of the kernel's flow monitor and of the naive rule over `impacts` pulses drawn
/// with replacement from `records` (restarted after each alarm).
fn bootstrap_alarms<M: Backend>(
    records: &[&PulseRec],
    impacts: usize,
    flow: &mut FlowMonitor<M>,
    naive: Option<(usize, usize)>,
    rng: &mut ChaCha8Rng,
) -> (usize, usize) {
    if records.is_empty() {
        return (0, 0);
    }
    flow.reset();
    let mut rule = naive.map(|(k, n)| NaiveRule::new(k, n));
    let (mut kernel, mut naive_alarms) = (0, 0);
    for _ in 0..impacts {
        let p = records[rng.random_range(0..records.len())];
        match p.ln_ratio {
            Some(d) => flow.update(d),
            None => flow.leave_out(),
        }
        if flow.status().alarm {
            kernel += 1;
            flow.reset();
        }
        if let Some(r) = rule.as_mut() {
            naive_alarms += r.step(p.confident_gangue) as usize;
        }
    }
    (kernel, naive_alarms)
}

/// `(ln ratio, gangue)` of one fresh impact of the exact mixture with share `pi`.
fn exact_draw(mixture: &MixtureModel, pi: f64, rng: &mut ChaCha8Rng) -> (Option<f64>, bool) {
    let gangue = rng.random::<f64>() < pi;
    let class = draw_class(&mixture.models, &mixture.gangue, gangue, rng.random());
    let m = &mixture.models[class];
    let (x, y) = m.sample(rng.random(), rng.random());
    let (lf, lt) = m.forward(x, y);
    (mixture.ln_ratio(lf, lt), gangue)
}

/// Alarms of the reference and of the label oracle over `impacts` fresh background impacts.
fn exact_alarms(
    mixture: &MixtureModel,
    opts: &CavingOptions,
    alpha: f64,
    rng: &mut ChaCha8Rng,
) -> (usize, usize) {
    let (p0, p1) = (opts.pre_share, opts.level);
    let (mut reference, mut labels) = (Cusum::for_rate(alpha), Cusum::for_rate(alpha));
    let (mut a, mut b) = (0, 0);
    for _ in 0..opts.false_alarm_impacts {
        let (d, g) = exact_draw(mixture, p0, rng);
        a += reference.step(d.map_or(0.0, |d| increment(p0, p1, d))) as usize;
        b += labels.step(label_increment(p0, p1, g)) as usize;
    }
    (a, b)
}

/// Mean increment per impact at the post-change share: kernel from the rounds' impacts at
/// that share, reference from fresh draws, labels in closed form.
fn information(rounds: &[Round], mixture: &MixtureModel, opts: &CavingOptions) -> Information {
    let (p0, p1, post) = (opts.pre_share, opts.level, opts.post_share);
    let (mut sum, mut n) = (0.0, 0usize);
    for r in rounds {
        let at_post = |i: usize| (opts.share_at(i) - post).abs() < 1e-12;
        n += (0..r.impacts.len()).filter(|&i| at_post(i)).count();
        sum += r
            .pulses
            .iter()
            .filter(|p| at_post(p.impact))
            .filter_map(|p| p.ln_ratio)
            .map(|d| increment(p0, p1, d as f64))
            .sum::<f64>();
    }
    let mut rng = ChaCha8Rng::seed_from_u64(mix(opts.seed ^ 0xC0A1));
    let reference = (0..KL_DRAWS)
        .map(|_| exact_draw(mixture, post, &mut rng).0)
        .map(|d| d.map_or(0.0, |d| increment(p0, p1, d)))
        .sum::<f64>()
        / KL_DRAWS as f64;
    Information {
        kernel: sum / n.max(1) as f64,
        reference,
        labels: post * label_increment(p0, p1, true)
            + (1.0 - post) * label_increment(p0, p1, false),
    }
}

/// Runs the caving rounds (see the module docs).
pub fn run<M: Backend + Send + Sync>(
    scene: &SceneFile,
    opts: &CavingOptions,
) -> Result<CavingReport, CavingError> {
    scene.validate()?;
    if scene.classes.len() <= DEFAULT_CLASSES {
        run_n::<DEFAULT_CLASSES, M>(scene, opts)
    } else {
        run_n::<MAX_CLASSES, M>(scene, opts)
    }
}

fn run_n<const N: usize, M: Backend + Send + Sync>(
    scene: &SceneFile,
    opts: &CavingOptions,
) -> Result<CavingReport, CavingError> {
    let gangue = opts.validate(scene)?;
    let kernel = scene_to_kernel_in::<N, M>(scene)?;
    let mixture = MixtureModel {
        models: class_models(scene),
        gangue,
    };
    let rounds = simulate_rounds(scene, &kernel, opts, &mixture)?;
    let flow_for = |a: f64| {
        FlowMonitor::<M>::new(opts.flow_config(&mixture.gangue, a), &kernel)
            .map_err(|e| opt_err("flow", e.to_string()))
    };
    let pre = pre_change_pulses(&rounds, opts);
    let kl = information(&rounds, &mixture, opts);
    let curve = CURVE_RATES
        .iter()
        .map(|&a| {
            curve_point(
                &rounds,
                &pre,
                opts,
                a,
                &kl,
                &|a| reference_closes(&rounds, opts, a),
                &|a| label_closes(&rounds, opts, a),
                flow_for(a),
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let closes = Closes::at_setting(&rounds, &pre, &mixture, opts, &flow_for)?;
    Ok(report(scene, opts, &rounds, closes, kl, curve))
}

/// Every round, simulated on every core with its own seeds, taken in order.
fn simulate_rounds<const N: usize, M: Backend + Send + Sync>(
    scene: &SceneFile,
    kernel: &Scene<N, M>,
    opts: &CavingOptions,
    mixture: &MixtureModel,
) -> Result<Vec<Round>, CavingError> {
    let round_ids: Vec<usize> = (0..opts.rounds).collect();
    let mut rounds = Vec::with_capacity(opts.rounds);
    map_ordered(
        &round_ids,
        |_, &r| simulate_round(scene, kernel, opts, mixture, r),
        |_, round| {
            rounds.push(round?);
            Ok::<(), CavingError>(())
        },
    )?;
    Ok(rounds)
}

/// The pulses of every round before the change.
fn pre_change_pulses<'a>(rounds: &'a [Round], opts: &CavingOptions) -> Vec<&'a PulseRec> {
    rounds
        .iter()
        .flat_map(|r| r.pulses.iter().filter(|p| p.impact < opts.pre_impacts))
        .collect()
}

/// Each round's close by the exact-feature reference at false-alarm rate `alpha`.
fn reference_closes(rounds: &[Round], opts: &CavingOptions, alpha: f64) -> Vec<Option<usize>> {
    let (p0, p1) = (opts.pre_share, opts.level);
    rounds
        .iter()
        .map(|r| {
            impact_close(r, alpha, |i| {
                i.exact_ln_ratio.map_or(0.0, |d| increment(p0, p1, d))
            })
        })
        .collect()
}

/// Each round's close by the label oracle at false-alarm rate `alpha`.
fn label_closes(rounds: &[Round], opts: &CavingOptions, alpha: f64) -> Vec<Option<usize>> {
    let (p0, p1) = (opts.pre_share, opts.level);
    rounds
        .iter()
        .map(|r| impact_close(r, alpha, |i| label_increment(p0, p1, i.gangue)))
        .collect()
}

/// Where each detector closed each round at the chosen false-alarm rate, with the false
/// alarms measured there.
struct Closes {
    /// The kernel's flow monitor, as it ran in the rounds.
    online: Vec<Option<usize>>,
    /// The exact-feature reference.
    reference: Vec<Option<usize>>,
    /// The label oracle.
    labels: Vec<Option<usize>>,
    /// The naive k-of-n rule and its closes.
    naive: NaiveSetting,
    naive_closes: Vec<Option<usize>>,
    /// The measured false-alarm rates.
    false_alarms: FalseAlarms,
    /// Whether replaying the kernel's pulses through a fresh monitor closes where it did.
    kernel_replay_agrees: bool,
}

impl Closes {
    fn at_setting<M: Backend>(
        rounds: &[Round],
        pre: &[&PulseRec],
        mixture: &MixtureModel,
        opts: &CavingOptions,
        flow_for: &dyn Fn(f64) -> Result<FlowMonitor<M>, CavingError>,
    ) -> Result<Self, CavingError> {
        let alpha = opts.false_alarm_rate;
        let online: Vec<Option<usize>> = rounds
            .iter()
            .map(|r| {
                r.pulses
                    .iter()
                    .find(|p| p.status.is_some_and(|s| s.alarm))
                    .map(|p| p.impact)
            })
            .collect();
        let q0 = pre.iter().filter(|p| p.confident_gangue).count() as f64 / pre.len().max(1) as f64;
        let naive = naive_setting(pre, opts, q0);
        let naive_closes = rounds
            .iter()
            .map(|r| naive_close(r, naive.k, naive.n))
            .collect();
        let false_alarms =
            measure_false_alarms(rounds, pre, mixture, opts, &naive, &flow_for(alpha)?);
        let mut replay = flow_for(alpha)?;
        let kernel_replay_agrees = rounds
            .iter()
            .zip(&online)
            .all(|(r, c)| kernel_close(r, &mut replay) == *c);
        Ok(Self {
            online,
            reference: reference_closes(rounds, opts, alpha),
            labels: label_closes(rounds, opts, alpha),
            naive,
            naive_closes,
            false_alarms,
            kernel_replay_agrees,
        })
    }
}

/// The report of the rounds: delays, mining outcomes and information of every detector.
fn report(
    scene: &SceneFile,
    opts: &CavingOptions,
    rounds: &[Round],
    c: Closes,
    kl: Information,
    curve: Vec<CurvePoint>,
) -> CavingReport {
    let h = -opts.false_alarm_rate.ln();
    let crossing = opts.crossing();
    let kernel_mining = mining(rounds, &c.online, crossing);
    let pulses: usize = rounds.iter().map(|r| r.pulses.len()).sum();
    let left_out = rounds
        .iter()
        .flat_map(|r| &r.pulses)
        .filter(|p| p.ln_ratio.is_none())
        .count();
    CavingReport {
        scene: scene.name.clone(),
        rounds: opts.rounds,
        seed: opts.seed,
        profile: Some(opts.profile),
        ramp_impacts: opts.ramp_impacts,
        pre_share: opts.pre_share,
        post_share: opts.post_share,
        level: opts.level,
        false_alarm_rate: opts.false_alarm_rate,
        threshold_nats: h,
        rate_hz: opts.rate_hz,
        window_impacts: opts.window_impacts,
        pre_impacts: opts.pre_impacts,
        post_impacts: opts.post_impacts,
        detection_delay_impacts: delays(&c.online, opts),
        reference_delay_impacts: delays(&c.reference, opts),
        label_oracle_delay_impacts: delays(&c.labels, opts),
        naive_delay_impacts: delays(&c.naive_closes, opts),
        naive_rule: c.naive,
        false_alarms_per_1e5_impacts: c.false_alarms.kernel_per_1e5,
        false_alarms: c.false_alarms,
        recovery_rate: kernel_mining.recovery_rate,
        gangue_content: kernel_mining.gangue_content,
        clairvoyant: mining(
            rounds,
            &vec![crossing.checked_sub(1); rounds.len()],
            crossing,
        ),
        naive: mining(rounds, &c.naive_closes, crossing),
        reference: mining(rounds, &c.reference, crossing),
        label_oracle: mining(rounds, &c.labels, crossing),
        kl_nats_per_impact: kl,
        lorden_delay_impacts: lorden_delays(h, kl),
        kernel_replay_agrees: c.kernel_replay_agrees,
        pulses,
        left_out_share: left_out as f64 / pulses.max(1) as f64,
        curve,
        trace: trace(rounds, opts),
    }
}

/// Lorden's delay to the threshold `h` (nats) at `kl` nats per impact, `h / KL` impacts, for
/// the kernel, the reference and the labels.
fn lorden_delays(h: f64, kl: Information) -> Information {
    Information {
        kernel: h / kl.kernel,
        reference: h / kl.reference,
        labels: h / kl.labels,
    }
}

/// Every measured false-alarm rate at the setting (see the module docs).
fn measure_false_alarms<M: Backend>(
    rounds: &[Round],
    pre: &[&PulseRec],
    mixture: &MixtureModel,
    opts: &CavingOptions,
    naive: &NaiveSetting,
    flow: &FlowMonitor<M>,
) -> FalseAlarms {
    let per_1e5 = |alarms: usize| alarms as f64 * 1e5 / opts.false_alarm_impacts as f64;
    let mut rng = ChaCha8Rng::seed_from_u64(mix(opts.seed ^ 0xFA15E));
    let mut flow = flow.clone();
    let n = opts.false_alarm_impacts;
    let (kernel, naive_alarms) =
        bootstrap_alarms(pre, n, &mut flow, Some((naive.k, naive.n)), &mut rng);
    let coal: Vec<&PulseRec> = rounds
        .iter()
        .flat_map(|r| {
            r.pulses
                .iter()
                .filter(|p| p.impact < opts.pre_impacts && !r.impacts[p.impact].gangue)
        })
        .collect();
    let (pure, _) = bootstrap_alarms(&coal, n, &mut flow, None, &mut rng);
    let (reference, labels) = exact_alarms(mixture, opts, opts.false_alarm_rate, &mut rng);
    FalseAlarms {
        source: "kernel and naive: background impacts drawn with replacement from the recorded \
                 per-pulse likelihoods and verdicts of the simulated pre-change pulses; \
                 reference and label oracle: fresh draws of the exact background mixture",
        impacts: n,
        recorded_pulses: pre.len(),
        kernel_per_1e5: per_1e5(kernel),
        kernel_pure_coal_per_1e5: per_1e5(pure),
        naive_per_1e5: per_1e5(naive_alarms),
        reference_per_1e5: per_1e5(reference),
        label_oracle_per_1e5: per_1e5(labels),
    }
}

/// One point of the delay-against-false-alarm curve.
#[allow(clippy::too_many_arguments)]
fn curve_point<M: Backend>(
    rounds: &[Round],
    pre: &[&PulseRec],
    opts: &CavingOptions,
    alpha: f64,
    kl: &Information,
    reference_at: &dyn Fn(f64) -> Vec<Option<usize>>,
    labels_at: &dyn Fn(f64) -> Vec<Option<usize>>,
    flow: Result<FlowMonitor<M>, CavingError>,
) -> Result<CurvePoint, CavingError> {
    let mut flow = flow?;
    let kernel: Vec<_> = rounds.iter().map(|r| kernel_close(r, &mut flow)).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(mix(opts.seed ^ alpha.to_bits()));
    let (fa, _) = bootstrap_alarms(pre, opts.false_alarm_impacts, &mut flow, None, &mut rng);
    let h = -alpha.ln();
    Ok(CurvePoint {
        false_alarm_rate: alpha,
        threshold_nats: h,
        kernel_false_alarms_per_1e5: fa as f64 * 1e5 / opts.false_alarm_impacts as f64,
        kernel_median: delays(&kernel, opts).median,
        reference_median: delays(&reference_at(alpha), opts).median,
        label_oracle_median: delays(&labels_at(alpha), opts).median,
        kernel_lorden: h / kl.kernel,
        reference_lorden: h / kl.reference,
    })
}

/// The flow over the first round.
fn trace(rounds: &[Round], opts: &CavingOptions) -> Trace {
    let Some(r) = rounds.first() else {
        return Trace::default();
    };
    Trace {
        points: r
            .pulses
            .iter()
            .filter_map(|p| {
                let s = p.status?;
                Some((p.impact, s.share as f64, s.std_error as f64, s.cusum as f64))
            })
            .collect(),
        true_share: (0..r.impacts.len()).map(|i| opts.share_at(i)).collect(),
        alarm: r
            .pulses
            .iter()
            .find(|p| p.status.is_some_and(|s| s.alarm))
            .map(|p| p.impact),
        change: opts.pre_impacts,
    }
}
