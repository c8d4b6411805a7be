//! The whole node pipeline: scene + detector + classifier + counters (+ an optional flow
//! monitor), fed one sample at a time.

use crate::classifier::{Measurement, Verdict};
use crate::counters::Counters;
use crate::detector::{Detection, Detector};
use crate::equaliser::{Equaliser, Pairs, Sink};
use crate::error::Error;
use crate::flow::{FlowConfig, FlowMonitor, FlowSlot, FlowStatus, NoFlow};
use crate::math::{Backend, DefaultBackend};
use crate::scene::{DEFAULT_CLASSES, Scene};
#[cfg(not(feature = "settle"))]
use crate::settle::NoSettle as Settler;
#[cfg(feature = "settle")]
use crate::settle::Settler;

/// One classified (or rejected) pulse.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Report {
    /// Index of the pulse's largest sample in the stream.
    pub at_sample: u64,
    /// The verdict.
    pub verdict: Verdict,
    /// The measured peak force and duration, when the pulse could be measured.
    pub measurement: Option<Measurement>,
}

/// What the monitor reports.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// A pulse ended.
    Pulse(Report),
    /// The sensor looks stuck (no change for `stuck_samples` samples).
    Stuck {
        /// Index of the sample that completed the stuck run.
        at_sample: u64,
    },
    /// The flow after a pulse (only from a monitor built with [`Monitor::with_flow`]): the
    /// gangue share estimate, its standard error and the close-window alarm. It follows the
    /// pulse's own `Pulse` event.
    Flow(FlowStatus),
}

/// Scene, detector and counters in one value of fixed size: the kernel as a node runs it;
/// `F` is what else each pulse feeds: nothing ([`NoFlow`], the default: no flow code at all)
/// or a [`FlowMonitor`] ([`Monitor::with_flow`]).
///
/// The fields keep their order (`repr(C)`): the detector and the equaliser, which every
/// sample touches, come before the scene, whose size varies with the features (a yielding
/// class's table, a phase table). On Thumb-2 a field more than 1 KB from the value's start
/// costs an extra instruction per floating-point access; left to the compiler, removing one
/// setting put the detector behind the scene and grew the size-optimised node by 0.7 KB.
#[derive(Debug, Clone)]
#[repr(C)]
pub struct Monitor<
    const N: usize = DEFAULT_CLASSES,
    M: Backend = DefaultBackend,
    F: FlowSlot<M> = NoFlow,
> {
    detector: Detector<M>,
    equaliser: Equaliser,
    counters: Counters<N>,
    flow: F,
    scene: Scene<N, M>,
    /// The equaliser's state re-estimation after a clipped sample or a gap (cold: last).
    settler: Settler,
}

impl<const N: usize, M: Backend> Monitor<N, M, NoFlow> {
    /// A monitor for a built scene.
    pub fn new(scene: Scene<N, M>) -> Self {
        let detector = Detector::new(&scene);
        let settler = Settler::new(scene.sensor().sample_rate_hz);
        Self {
            equaliser: Equaliser::new(scene.equaliser()),
            scene,
            detector,
            counters: Counters::default(),
            flow: NoFlow,
            settler,
        }
    }

    /// The monitor with a flow monitor ([`crate::flow`]) fed by every pulse: after each
    /// `Pulse` event comes an [`Event::Flow`] (from [`Monitor::feed_slice`] directly; after
    /// [`Monitor::feed`], [`Monitor::gap`] or [`Monitor::finish`] from
    /// [`Monitor::take_flow_event`]). A monitor without it does no flow work at all.
    ///
    /// ```
    /// use coalshock::{Monitor, Scene, flow::FlowConfig};
    /// let scene: Scene = Scene::paper().unwrap();
    /// let m = Monitor::new(scene).with_flow(FlowConfig::new(0.05, 0.5, 1e-5)).unwrap();
    /// assert!(m.flow().threshold() > 11.5);
    /// ```
    pub fn with_flow(self, config: FlowConfig) -> Result<Monitor<N, M, FlowMonitor<M>>, Error> {
        let flow = FlowMonitor::new(config, &self.scene)?;
        Ok(Monitor {
            scene: self.scene,
            equaliser: self.equaliser,
            detector: self.detector,
            counters: self.counters,
            flow,
            settler: self.settler,
        })
    }
}

impl<const N: usize, M: Backend, F: FlowSlot<M>> Monitor<N, M, F> {
    /// The flow monitor ([`NoFlow`] for a monitor without one).
    pub fn flow(&self) -> &F {
        &self.flow
    }

    /// Starts a new round of the flow monitor (share to the background, alarm off).
    pub fn reset_flow(&mut self) {
        self.flow.reset();
    }

    /// The `Flow` event of the last pulse, once (`None` without a flow monitor or when it was
    /// taken already).
    pub fn take_flow_event(&mut self) -> Option<Event> {
        self.flow.take().map(Event::Flow)
    }

    /// Feeds one ADC sample; returns an event when a pulse ends or the sensor is stuck.
    #[inline(always)]
    pub fn feed(&mut self, sample: i32) -> Option<Event> {
        let d = if self.equaliser.design().is_identity() {
            self.detector.feed(sample)?
        } else {
            let mut settled = None;
            if self.settling(sample) {
                let (used, d) = self.settle_slice(&[sample]);
                if used == 1 {
                    return d.map(|d| self.handle(d));
                }
                settled = d;
            }
            self.watch_full_scale(sample);
            let value = self.equaliser.step(sample);
            // A clipped pulse resolved as its window ended at this sample (at full scale,
            // which starts a pulse and cannot end one).
            let fed = self.detector.feed_value(sample, value);
            settled.or(fed)?
        };
        Some(self.handle(d))
    }

    /// Feeds a block of samples (e.g. one accelerometer FIFO read), calling `on_event` for
    /// every event in order. The same result as [`Monitor::feed`] on each sample, with the
    /// per-call overhead paid once per block (see the README for the instruction counts).
    pub fn feed_slice<S: Copy + Into<i32>>(
        &mut self,
        samples: &[S],
        mut on_event: impl FnMut(Event),
    ) {
        if !self.equaliser.design().is_identity() {
            self.feed_slice_equalised(samples, &mut on_event);
            return;
        }
        let mut rest = samples;
        loop {
            let quiet = self.detector.feed_quiet(rest);
            rest = rest.get(quiet..).unwrap_or(&[]);
            let Some((&s, tail)) = rest.split_first() else {
                return;
            };
            if let Some(d) = self.detector.feed(s.into()) {
                on_event(self.handle(d));
                if let Some(e) = self.take_flow_event() {
                    on_event(e);
                }
            }
            rest = tail;
        }
    }

    /// [`Monitor::feed_slice`] behind a chain: while the detector is idle, the equaliser
    /// feeds its quiet loop directly, one pass per sample ([`Equaliser::feed_to`]); the
    /// sample that stops it (already equalised) and those of a pulse go one at a time
    /// through [`Detector::feed_value`].
    fn feed_slice_equalised<S: Copy + Into<i32>>(
        &mut self,
        samples: &[S],
        on_event: &mut impl FnMut(Event),
    ) {
        let mut rest = samples;
        loop {
            // Windows of the equaliser's re-estimation, one after another while they are
            // discarded (as `feed` opens the next at the next sample), until one is believed,
            // a sample at full scale ends them or the block does.
            while let Some(&first) = rest.first() {
                if !self.settling(first.into()) {
                    break;
                }
                let (used, settled) = self.settle_slice(rest);
                if let Some(d) = settled {
                    on_event(self.handle(d));
                    if let Some(e) = self.take_flow_event() {
                        on_event(e);
                    }
                }
                if used == 0 {
                    break;
                }
                rest = rest.get(used..).unwrap_or(&[]);
            }
            let (quiet, stop) = if self.detector.is_idle() {
                quiet_equalised(&mut self.equaliser, &mut self.detector, rest)
            } else {
                (0, None)
            };
            rest = rest.get(quiet..).unwrap_or(&[]);
            let Some((&s, tail)) = rest.split_first() else {
                return;
            };
            self.watch_full_scale(s.into());
            let value = match stop {
                Some((_, value)) => value,
                None => self.equaliser.step(s.into()),
            };
            if let Some(d) = self.detector.feed_value(s.into(), value) {
                on_event(self.handle(d));
                if let Some(e) = self.take_flow_event() {
                    on_event(e);
                }
            }
            rest = tail;
        }
    }

    /// Reports `lost` dropped samples (see [`Detector::gap`]).
    pub fn gap(&mut self, lost: u32) -> Option<Event> {
        self.counters.gaps = self.counters.gaps.saturating_add(1);
        self.counters.lost_samples = self.counters.lost_samples.saturating_add(lost as u64);
        let d = self.detector.gap(lost);
        // What the chain rang during the gap is unknown: the equaliser starts afresh, and its
        // state is re-estimated from the quiet samples that follow.
        self.equaliser.reset();
        if !self.equaliser.design().is_identity() {
            self.settler.arm();
        }
        self.sync();
        Some(self.handle(d?))
    }

    /// Ends the stream (a pulse in progress is rejected as truncated).
    pub fn finish(&mut self) -> Option<Event> {
        let d = self.detector.finish();
        self.sync();
        Some(self.handle(d?))
    }

    /// Samples fed so far, including those reported lost (always current, unlike
    /// `counters().samples`, which is brought up to date at each event, gap and finish so the
    /// quiet path stays short).
    pub fn samples_fed(&self) -> u64 {
        self.detector.samples_fed()
    }

    /// `true` when `next` (a raw sample) and those after it go to the equaliser's state
    /// re-estimation ([`crate::settle`]): a window is open, or one waits for an idle detector
    /// and `next` is below full scale (a sample at full scale goes to the detector, and a
    /// window open at it ends).
    #[inline(always)]
    fn settling(&mut self, next: i32) -> bool {
        if self.settler.is_armed() && self.detector.is_idle() && !self.full_scale(next) {
            let baseline = self.detector.baseline();
            #[cfg(all(feature = "settle", feature = "pulse_shape"))]
            if let Some(anchor) = self.detector.clip_anchor() {
                let design = *self.equaliser.design();
                self.settler.start_anchored(baseline, &design, anchor);
                return self.settler.in_window();
            }
            self.settler.start(baseline);
        }
        self.settler.in_window()
    }

    /// `true` for a raw sample at either end of the ADC's range.
    #[inline(always)]
    fn full_scale(&self, raw: i32) -> bool {
        let sensor = self.scene.sensor();
        raw >= sensor.adc_max || raw <= sensor.adc_min
    }

    /// A raw sample at full scale leaves the equaliser's sections off the chain's state: arm
    /// their re-estimation. At the top of the range always (the quiet loop stops there); at
    /// its bottom inside a pulse (the quiet loop does not stop there, and [`Monitor::feed`]
    /// and [`Monitor::feed_slice`] must do the same).
    #[inline(always)]
    fn watch_full_scale(&mut self, raw: i32) {
        let sensor = self.scene.sensor();
        if raw >= sensor.adc_max || (raw <= sensor.adc_min && !self.detector.is_idle()) {
            self.settler.arm();
        }
    }

    /// Feeds the front of `samples` to the open window of the re-estimation
    /// ([`Settler::run`]) and tells the detector and the counters what it took. Returns how
    /// many samples it took and, when the re-estimation ended (a window believed, or the last
    /// one discarded), the measurement of a clipped pulse that waited for it. A discarded
    /// window with another to come leaves the pulse waiting: right after a clipped pulse the
    /// state error can hide the pulse's own tail, which the detector then ended early, and
    /// that tail in the first window leaves it unbelieved; the next window starts at the
    /// pulse's anchor again. A sample at full scale ends the wait in the detector.
    #[cold]
    #[inline(never)]
    fn settle_slice<S: Copy + Into<i32>>(&mut self, samples: &[S]) -> (usize, Option<Detection>) {
        let sensor = self.scene.sensor();
        let adc = (sensor.adc_min, sensor.adc_max);
        let mut raw = samples.iter().map(|&s| s.into());
        let noise = self.detector.noise();
        let taken = self.settler.run(&mut self.equaliser, noise, adc, &mut raw);
        self.detector.skip_settled(taken.samples, taken.last_raw);
        let c = &mut self.counters;
        if taken.quiet_ms.is_some() {
            c.settled = c.settled.saturating_add(1);
        }
        c.settle_samples = c.settle_samples.saturating_add(taken.samples as u64);
        #[cfg(all(feature = "settle", feature = "pulse_shape"))]
        if !(self.settler.in_window() || self.settler.is_armed()) {
            return (
                taken.samples as usize,
                self.detector.resolve_clip(taken.clip),
            );
        }
        (taken.samples as usize, None)
    }

    /// Brings the counters the detector keeps (samples, stuck runs) into `counters`.
    fn sync(&mut self) {
        self.counters.samples = self.detector.samples_fed();
        self.counters.stuck_runs = self.detector.stuck_runs();
    }

    #[cold]
    #[inline(never)]
    fn handle(&mut self, d: Detection) -> Event {
        self.sync();
        match d {
            Detection::Stuck { at_sample } => Event::Stuck { at_sample },
            Detection::Pulse { at_sample, outcome } => {
                // The equaliser's output lags the ADC by its delay.
                let at_sample =
                    at_sample.saturating_sub(self.equaliser.design().delay_samples() as u64);
                let (verdict, measurement) = if F::ON {
                    let (verdict, lls) = match outcome {
                        Ok(m) => self.scene.classify_with_likelihoods(&m),
                        Err(r) => (Verdict::Rejected(r), None),
                    };
                    self.flow
                        .record(&verdict, lls.as_ref().map(|l| l.as_slice()));
                    (verdict, outcome.ok())
                } else {
                    match outcome {
                        Ok(m) => (self.scene.classify(&m), Some(m)),
                        Err(r) => (Verdict::Rejected(r), None),
                    }
                };
                self.counters.record(&verdict);
                Event::Pulse(Report {
                    at_sample,
                    verdict,
                    measurement,
                })
            }
        }
    }

    /// The scene.
    pub fn scene(&self) -> &Scene<N, M> {
        &self.scene
    }

    /// The detector.
    pub fn detector(&self) -> &Detector<M> {
        &self.detector
    }

    /// The counters.
    pub fn counters(&self) -> &Counters<N> {
        &self.counters
    }
}

/// The equaliser feeding the detector's quiet loop over `samples` (one copy per sample type
/// and backend in an image, whatever the caller's event handler: not inlined).
#[inline(never)]
fn quiet_equalised<S: Copy + Into<i32>, M: Backend>(
    equaliser: &mut Equaliser,
    detector: &mut Detector<M>,
    samples: &[S],
) -> (usize, Option<(i32, f32)>) {
    equaliser.feed_to(samples, QuietLoop(detector))
}

/// The detector's quiet loop as the equaliser's sink ([`Detector::feed_quiet_pairs`]).
struct QuietLoop<'a, M: Backend>(&'a mut Detector<M>);

impl<M: Backend> Sink for QuietLoop<'_, M> {
    type Output = (usize, Option<(i32, f32)>);
    #[inline(always)]
    fn take(self, pairs: &mut impl Pairs) -> Self::Output {
        self.0.feed_quiet_pairs(pairs)
    }
}
