//! Arbitrary bytes -> a scene (plate, 0 to 5 classes, sensor chain, settings) and a sample
//! stream with pulses, stuck runs, raw samples, gaps and finishes, fed to `Monitor`.
//!
//! Asserts: no panic anywhere (`Scene::new` included, on any field value); after every call the
//! counters are balanced, `Monitor::samples_fed` equals samples fed plus samples reported lost,
//! one pulse is counted per pulse event; after every event, gap and finish (when the monitor
//! brings `counters()` up to date) `counters.samples` equals samples fed plus lost and
//! `stuck_runs` is the detector's count (at least one per stuck event); every verdict names a
//! class the scene has, with a posterior in [0, 1].

#![no_main]

use coalshock::{
    Accelerometer, BeamMode, ChainDynamics, Counters, Event, Material, Monitor, ParticleClass,
    Range, Scene, SensorChain, Settings, Speed, Verdict,
};
use libfuzzer_sys::fuzz_target;

/// Most samples one input may feed (keeps every run fast).
const MAX_SAMPLES: u64 = 400_000;

/// Reads the input front to back; zeros once it is used up.
struct Bytes<'a> {
    data: &'a [u8],
}

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        match self.data.split_first() {
            Some((&b, rest)) => {
                self.data = rest;
                b
            }
            None => 0,
        }
    }
    fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    fn i32(&mut self) -> i32 {
        self.u32() as i32
    }
    fn done(&self) -> bool {
        self.data.is_empty()
    }
    /// An f32 for a field whose sensible values are `lo..hi`: mostly log-uniform in there,
    /// sometimes a special value (NaN, infinities, zeros, negative, subnormal, huge), sometimes
    /// raw bits.
    fn f32_in(&mut self, lo: f32, hi: f32) -> f32 {
        const SPECIAL: [f32; 14] = [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            -1.0,
            f32::MIN_POSITIVE,
            1e-45,
            f32::MAX,
            -f32::MAX,
            1e-30,
            1e30,
            0.5,
            1.0,
        ];
        let tag = self.u8();
        match tag {
            0..=219 => {
                let t = self.u16() as f32 / u16::MAX as f32;
                (lo.ln() + t * (hi.ln() - lo.ln())).exp()
            }
            220..=243 => SPECIAL[(tag - 220) as usize % SPECIAL.len()],
            _ => f32::from_bits(self.u32()),
        }
    }
    fn range(&mut self, lo: f32, hi: f32) -> Range {
        let (a, b) = (self.f32_in(lo, hi), self.f32_in(lo, hi));
        match self.u8() % 16 {
            0 => Range::new(a, a),
            1 => Range::new(a, f32::from_bits(a.to_bits().wrapping_add(1))),
            2 => Range::new(a.max(b), a.min(b)),
            _ => Range::new(a.min(b), a.max(b)),
        }
    }
    fn material(&mut self) -> Material {
        let rho = self.f32_in(100.0, 20_000.0);
        let e = self.f32_in(1e6, 1e12);
        let nu = if self.u8() < 240 {
            self.u16() as f32 / u16::MAX as f32 * 0.499
        } else {
            self.f32_in(0.01, 0.5)
        };
        Material::new(rho, e, nu)
    }
    fn class(&mut self) -> ParticleClass {
        let material = self.material();
        let radius = self.range(1e-3, 0.3);
        let speed = if self.u8().is_multiple_of(4) {
            Speed::DropHeight(self.range(0.05, 20.0))
        } else {
            Speed::Uniform(self.range(0.1, 20.0))
        };
        let mut c = ParticleClass::new("class", material, radius, speed);
        c.prior = if self.u8() < 200 {
            1.0
        } else {
            self.f32_in(1e-3, 1e3)
        };
        c
    }
    fn sensor(&mut self) -> SensorChain {
        let sample_rate_hz = self.f32_in(1e4, 1e6);
        let force_per_count_n = self.f32_in(1e-2, 1e2);
        let noise_rms_counts = if self.u8() < 16 {
            0.0
        } else {
            self.f32_in(0.1, 50.0)
        };
        let (adc_min, adc_max) = match self.u8() % 8 {
            0 => (self.i32(), self.i32()),
            1 => (-2048, 2047),
            2 => (i32::MIN, i32::MAX),
            3 => (0, 65535),
            _ => (-32768, 32767),
        };
        let rigid = SensorChain {
            sample_rate_hz,
            force_per_count_n,
            noise_rms_counts,
            adc_min,
            adc_max,
            dynamics: ChainDynamics::RIGID,
        };
        // Half the inputs put a tail beam (0-4 modes, any parameters) and an accelerometer
        // stage behind the plate; a chain the kernel refuses leaves the plate rigid.
        if self.u8() < 128 {
            return rigid;
        }
        let mut d = ChainDynamics::RIGID;
        for _ in 0..self.u8() % 5 {
            let mode = BeamMode {
                frequency_hz: self.f32_in(10.0, 1e5),
                damping_ratio: self.f32_in(1e-3, 1.5),
                gain: self.f32_in(1e-3, 2.0),
            };
            d = d.with_mode(mode).unwrap_or(d);
        }
        if self.u8() < 128 {
            d = d.with_accelerometer(Accelerometer {
                frequency_hz: self.f32_in(1e2, 1e6),
                damping_ratio: self.f32_in(1e-3, 1.5),
            });
        }
        rigid.with_dynamics(d).unwrap_or(rigid)
    }
    fn settings(&mut self) -> Settings {
        let d = Settings::default();
        if self.u8() < 64 {
            return d;
        }
        let small = |b: &mut Self, dflt: u16| match b.u8() {
            0..=199 => dflt,
            200..=239 => b.u8() as u16,
            _ => b.u16(),
        };
        Settings {
            trigger_sigmas: self.f32_in(2.0, 20.0),
            release_sigmas: self.f32_in(0.5, 2.0),
            hold_samples: small(self, d.hold_samples),
            baseline_tau_s: self.f32_in(1e-4, 1.0),
            stuck_samples: small(self, d.stuck_samples),
            model_sigma: self.f32_in(1e-4, 0.5),
            confident_error_rate: self.f32_in(0.001, 0.49),
            out_sigmas: self.f32_in(1.0, 10.0),
            shape_tolerance: self.f32_in(0.01, 1.0),
            contact: coalshock::ContactCalibration {
                force_ratio: self.f32_in(0.5, 2.0),
                duration_ratio: self.f32_in(0.5, 2.0),
                shape_ratio: self.f32_in(0.5, 2.0),
                skewness: self.f32_in(0.01, 1.0),
                sampled: coalshock::SampledCalibration {
                    ln_force: [self.f32_in(-0.3, 0.1); coalshock::scene::SAMPLED_POINTS],
                    ln_duration: [self.f32_in(-0.3, 0.3); coalshock::scene::SAMPLED_POINTS],
                    sigma_ln_force: [self.f32_in(0.0, 0.2); coalshock::scene::SAMPLED_POINTS],
                    sigma_ln_duration: [self.f32_in(0.0, 0.5); coalshock::scene::SAMPLED_POINTS],
                },
            },
            skew_tolerance: self.f32_in(0.01, 1.0),
            spike_fraction: self.f32_in(0.05, 3.0),
            flat_top_ratio: self.f32_in(1.0, 3.0),
            // Mostly small grids: a 256-cell grid with four classes takes long to build.
            separability_grid: match self.u8() {
                0..=239 => 2 + (self.u8() % 40) as u16,
                240..=247 => self.u16(),
                _ => 256,
            },
            sampled_phase: self.sampled_phase(),
            // No damped table; settings with the Hertz contact fuzz the detector's own table.
            pulse_shape: coalshock::PulseShape::NONE,
        }
    }
    /// No phase table half the time, else one whose axes and cells the bytes choose.
    fn sampled_phase(&mut self) -> coalshock::SampledPhase {
        use coalshock::sampled_phase::{PHASE_COLUMNS, PHASE_ROWS};
        if self.u8() < 128 {
            return coalshock::SampledPhase::NONE;
        }
        let (lo, hi) = (self.f32_in(-1.0, 0.0), self.f32_in(0.0, 1.0));
        coalshock::SampledPhase {
            asymmetry: [[lo, hi]; PHASE_ROWS],
            ln_force: [[self.f32_in(-0.3, 0.1); PHASE_COLUMNS]; PHASE_ROWS],
            ln_duration: [[self.f32_in(-0.3, 0.3); PHASE_COLUMNS]; PHASE_ROWS],
            sigma_ln_force: [[self.f32_in(0.0, 0.2); PHASE_COLUMNS]; PHASE_ROWS],
            sigma_ln_duration: [[self.f32_in(0.0, 0.5); PHASE_COLUMNS]; PHASE_ROWS],
        }
    }
}

/// The monitor with the bookkeeping the invariants need.
struct Fed {
    monitor: Monitor,
    fed: u64,
    lost: u64,
    pulses: u64,
    stuck: u64,
    classes: usize,
}

impl Fed {
    /// Checks an event and the invariants after a call that returned it. `synced`: the call
    /// was a gap or a finish, or returned an event, so `counters()` is up to date.
    fn event(&mut self, e: Option<Event>, synced: bool) {
        match e {
            Some(Event::Pulse(r)) => {
                self.pulses += 1;
                match r.verdict {
                    Verdict::Class { class, posterior } => {
                        assert!((class as usize) < self.classes, "class {class}");
                        assert!((0.0..=1.0).contains(&posterior), "posterior {posterior}");
                    }
                    Verdict::Ambiguous { best, posterior } => {
                        assert!((best as usize) < self.classes, "best {best}");
                        assert!((0.0..=1.0).contains(&posterior), "posterior {posterior}");
                    }
                    Verdict::OutOfEnvelope { nearest, .. } => {
                        assert!((nearest as usize) < self.classes, "nearest {nearest}");
                    }
                    Verdict::Rejected(_) => {}
                }
            }
            Some(Event::Stuck { .. }) => self.stuck += 1,
            // A monitor without a flow monitor never reports the flow.
            Some(Event::Flow(_)) => unreachable!("flow event without a flow monitor"),
            None => {}
        }
        self.check(synced || e.is_some());
    }
    fn check(&self, synced: bool) {
        let c: &Counters<4> = self.monitor.counters();
        assert!(c.balanced(), "{c:?}");
        assert_eq!(self.monitor.samples_fed(), self.fed + self.lost, "{c:?}");
        assert_eq!(c.lost_samples, self.lost, "{c:?}");
        assert_eq!(c.pulses as u64, self.pulses, "{c:?}");
        if synced {
            assert_eq!(c.samples, self.fed + self.lost, "{c:?}");
            // A stuck run is counted even when its event coincides with a pulse's.
            assert_eq!(c.stuck_runs, self.monitor.detector().stuck_runs(), "{c:?}");
            assert!(
                c.stuck_runs as u64 >= self.stuck,
                "{c:?}: {} stuck events",
                self.stuck
            );
        }
    }
    fn feed(&mut self, s: i32) {
        self.fed += 1;
        let e = self.monitor.feed(s);
        self.event(e, false);
    }
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes { data };
    let plate = b.material();
    let n = (b.u8() % 6) as usize;
    let classes: Vec<ParticleClass> = (0..n).map(|_| b.class()).collect();
    let sensor = b.sensor();
    let settings = b.settings();
    let Ok(scene) = Scene::<4>::new(plate, &classes, sensor, settings) else {
        return;
    };
    let sep = scene.separability();
    assert!((0.0..=1.0).contains(&sep.overlap_share), "{sep:?}");
    assert!((0.0..=1.0).contains(&sep.bayes_error), "{sep:?}");
    let mut f = Fed {
        monitor: Monitor::new(scene),
        fed: 0,
        lost: 0,
        pulses: 0,
        stuck: 0,
        classes: n,
    };
    let mut level: i32 = 0;
    let mut noise_state: u32 = 0x9e37_79b9;
    let mut noise = |amp: i32| {
        noise_state ^= noise_state << 13;
        noise_state ^= noise_state >> 17;
        noise_state ^= noise_state << 5;
        if amp <= 0 {
            0
        } else {
            (noise_state % (2 * amp as u32 + 1)) as i32 - amp
        }
    };
    while !b.done() && f.fed < MAX_SAMPLES {
        match b.u8() {
            // A noisy run at the current level.
            0..=79 => {
                let len = 1 + b.u16() as u32 % 4096;
                let amp = (b.u8() % 32) as i32;
                for _ in 0..len {
                    let s = level.saturating_add(noise(amp));
                    f.feed(s);
                }
            }
            // Move the level (a step, or a slow ramp over the next run).
            80..=99 => level = b.i32() >> (b.u8() % 32),
            // A pulse `sin^1.5` of a given height and length on the level, with noise.
            100..=149 => {
                let height = (b.u16() as i32) << (b.u8() % 16);
                let len = 1 + b.u16() % 2048;
                let amp = (b.u8() % 16) as i32;
                for i in 0..=len {
                    let x = core::f32::consts::PI * i as f32 / len as f32;
                    let v = height as f32 * x.sin().max(0.0).powf(1.5);
                    let s = (level as f32 + v) as i32;
                    f.feed(s.saturating_add(noise(amp)));
                }
            }
            // Literal samples.
            150..=169 => {
                let count = b.u8();
                for _ in 0..count {
                    let s = if b.u8() < 128 {
                        level.saturating_add(b.u16() as i16 as i32)
                    } else {
                        b.i32()
                    };
                    f.feed(s);
                }
            }
            // A stuck run.
            170..=179 => {
                let s = b.i32();
                for _ in 0..(1 + b.u16() % 8192) {
                    f.feed(s);
                }
            }
            // Dropped samples.
            180..=209 => {
                let lost = match b.u8() % 8 {
                    0 => b.u32(),
                    1 => u32::MAX,
                    _ => b.u8() as u32,
                };
                f.lost += lost as u64;
                let e = f.monitor.gap(lost);
                f.event(e, true);
            }
            // End of stream (feeding may go on after it).
            210..=219 => {
                let e = f.monitor.finish();
                f.event(e, true);
            }
            // One raw sample.
            _ => {
                let s = b.i32();
                f.feed(s);
            }
        }
    }
    let e = f.monitor.finish();
    f.event(e, true);
    assert_eq!(
        f.monitor.finish(),
        None,
        "a second finish has nothing to report"
    );
    f.check(true);
});
