//! How the embedded-hal front end plugs into the detector: the IIS3DWB driver
//! (the `iis3dwb` crate) over an `embedded_hal::spi::SpiDevice`, drained through
//! the `SampleSource` trait in blocks that go to `Monitor::feed_slice`.
//!
//! QEMU has no IIS3DWB, so the SPI device here is a small in-memory fake of one: it answers
//! WHO_AM_I, completes the software reset, checks that the driver configured continuous FIFO
//! mode at 26.7 kHz, and serves the replayed stream (`fw/data/paper_stream.bin`, the one
//! the node binary replays) as FIFO words, the stream on the Z axis, up to 200 new words per
//! status read and never more than the FIFO's 512. Where the recording lost samples (the `gap`
//! rows of its truth file) the fake raises the FIFO overrun flags, as the device does when
//! words are overwritten.
//!
//! The firmware first replays the stream plainly (one `Monitor::feed` per sample,
//! `Monitor::gap` with the recorded length), then through the driver, and checks that both
//! give the same events in the same order and the same counters. One difference is expected
//! and checked exactly: the IIS3DWB does not count overwritten words, so the driver reports an
//! overrun as `Gap::AtLeast(1)`, the monitor is told one lost sample, and every sample index
//! after a gap (and the `samples` and `lost_samples` counters) is short by the rest of it.
//!
//! Output lines (defmt on the node, stdout on the host):
//!
//! ```text
//! front_end reads=<read_samples calls> spi=<transactions> words=<FIFO words> overruns=<n>
//! front_end events=<n> same=<n> differ=<n> index_shift=<samples>
//! front_end counters_equal=<0|1>
//! counters samples=.. pulses=.. ambiguous=.. out=.. rejected=.. stuck=.. gaps=.. lost=.. balanced=<0|1>
//! ```
//!
//! (the `counters` line is the front end's, before the shift is added back). Exit status 0
//! when every event and counter agrees.
//!
//! Run in QEMU by `fw/src/bin/front_end.rs`, on the host by `host-sim/examples/front_end.rs`;
//! `fw/ci.sh` runs both and compares their output.

use crate::{GAPS, Input, STORED_SAMPLES, inputs, sample};
use coalshock::math::DefaultBackend;
use coalshock::scene::DEFAULT_CLASSES;
use coalshock::{Counters, Event, Monitor, Report};
use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{self, ErrorType, Operation, SpiDevice};
use iis3dwb::{Axis, Config, FullScale, Iis3dwb, SampleSource};

// ---------------------------------------------------------------------------------------------
// The fake sensor
// ---------------------------------------------------------------------------------------------

/// IIS3DWB registers the fake implements (datasheet DS13114).
const WHO_AM_I: u8 = 0x0F;
const CTRL3_C: u8 = 0x12;
const FIFO_CTRL3: u8 = 0x09;
const FIFO_CTRL4: u8 = 0x0A;
const CTRL1_XL: u8 = 0x10;
const FIFO_STATUS1: u8 = 0x3A;
const FIFO_STATUS2: u8 = 0x3B;
const FIFO_DATA_OUT_TAG: u8 = 0x78;
/// FIFO_STATUS2 flags: FIFO_OVR_IA (bit 6) and FIFO_OVR_LATCHED (bit 3).
const OVERRUN: u8 = 0x40 | 0x08;
/// FIFO capacity in words.
const FIFO_WORDS: usize = 512;
/// New samples the sensor makes between two status reads (a 2 ms drain period at 100 kS/s).
const WORDS_PER_POLL: usize = 200;

/// Why the fake refused a transaction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FakeError {
    /// A transaction shape the IIS3DWB protocol does not use.
    Unsupported,
}

impl spi::Error for FakeError {
    fn kind(&self) -> spi::ErrorKind {
        spi::ErrorKind::Other
    }
}

/// An IIS3DWB in memory, streaming the replayed recording into its FIFO.
struct FakeIis3dwb {
    regs: [u8; 128],
    /// CTRL3_C reads left before a software reset completes.
    reset_polls: u8,
    /// FIFO content: stored samples `head..next`.
    head: usize,
    next: usize,
    /// Next recorded gap of the stream.
    gap: usize,
    /// TAG_CNT of the next word (2 bits).
    tag_cnt: u8,
    /// SPI transactions served.
    transactions: u32,
    /// FIFO words read out.
    words: u32,
}

impl FakeIis3dwb {
    fn new() -> Self {
        let mut s = Self {
            regs: [0; 128],
            reset_polls: 0,
            head: 0,
            next: 0,
            gap: 0,
            tag_cnt: 0,
            transactions: 0,
            words: 0,
        };
        s.reset_registers();
        s
    }

    fn reset_registers(&mut self) {
        self.regs = [0; 128];
        self.set(WHO_AM_I, 0x7B);
        self.set(CTRL3_C, 0x04); // IF_INC
    }

    fn reg(&self, r: u8) -> u8 {
        self.regs.get(usize::from(r)).copied().unwrap_or(0)
    }

    fn set(&mut self, r: u8, v: u8) {
        if let Some(x) = self.regs.get_mut(usize::from(r)) {
            *x = v;
        }
    }

    /// Accelerometer on at 26.7 kHz and batched into a continuous FIFO, as `init` sets it.
    fn streaming(&self) -> bool {
        self.reg(CTRL1_XL) >> 5 == 0b101
            && self.reg(FIFO_CTRL3) & 0x0F == 0b1010
            && self.reg(FIFO_CTRL4) & 0x07 == 0b110
    }

    /// Time passes between two drains: up to [`WORDS_PER_POLL`] new samples enter the FIFO.
    /// At a recorded gap the words before it must have been read; then the FIFO overruns
    /// (the lost samples never appear) and filling goes on after it.
    fn acquire(&mut self) {
        if !self.streaming() {
            return;
        }
        let mut made = 0;
        while made < WORDS_PER_POLL && self.next < STORED_SAMPLES {
            if GAPS.get(self.gap).is_some_and(|g| g.position <= self.next) {
                if self.head < self.next {
                    break; // the host has not drained the words before the gap yet
                }
                self.gap += 1;
                self.set(FIFO_STATUS2, self.reg(FIFO_STATUS2) | OVERRUN);
                continue;
            }
            if self.next - self.head >= FIFO_WORDS {
                break;
            }
            self.next += 1;
            made += 1;
        }
        // A gap at the very end of the recording.
        while let Some(g) = GAPS.get(self.gap) {
            if g.position < STORED_SAMPLES || self.head < self.next {
                break;
            }
            self.gap += 1;
            self.set(FIFO_STATUS2, self.reg(FIFO_STATUS2) | OVERRUN);
        }
    }

    /// FIFO_STATUS1/2: DIFF_FIFO (10 bits) and the overrun flags.
    fn status(&self) -> [u8; 2] {
        let level = (self.next - self.head) as u16;
        [
            (level & 0xFF) as u8,
            ((level >> 8) as u8 & 0b11) | (self.reg(FIFO_STATUS2) & OVERRUN),
        ]
    }

    /// The next FIFO word: tag (TAG_SENSOR = 02h, TAG_CNT, parity), then X, Y, Z.
    fn pop_word(&mut self) -> [u8; 7] {
        if self.head >= self.next {
            return [0; 7]; // reading an empty FIFO: the device returns stale data
        }
        let z = sample(self.head);
        self.head += 1;
        self.words += 1;
        // The other axes carry something else, so reading the wrong one would show.
        let x = z.wrapping_neg() / 2;
        let y = 1000i16.wrapping_sub(z);
        let tag7 = (0x02 << 3) | (self.tag_cnt << 1);
        let tag = tag7 | ((tag7.count_ones() & 1) as u8);
        self.tag_cnt = (self.tag_cnt + 1) & 0b11;
        let [xl, xh] = x.to_le_bytes();
        let [yl, yh] = y.to_le_bytes();
        let [zl, zh] = z.to_le_bytes();
        [tag, xl, xh, yl, yh, zl, zh]
    }

    fn read(&mut self, addr: u8, buf: &mut [u8]) {
        match addr {
            FIFO_STATUS1 => {
                self.acquire();
                let s = self.status();
                for (b, v) in buf
                    .iter_mut()
                    .zip(s.into_iter().chain(core::iter::repeat(0)))
                {
                    *b = v;
                }
                if buf.len() >= 2 {
                    // Reading FIFO_STATUS2 clears the latched overrun.
                    self.set(FIFO_STATUS2, 0);
                }
            }
            FIFO_DATA_OUT_TAG => {
                for word in buf.chunks_mut(7) {
                    let w = self.pop_word();
                    for (b, v) in word.iter_mut().zip(w) {
                        *b = v;
                    }
                }
            }
            CTRL3_C if self.reset_polls > 0 => {
                self.reset_polls -= 1;
                if self.reset_polls == 0 {
                    self.set(CTRL3_C, self.reg(CTRL3_C) & !0x01);
                }
                if let Some(b) = buf.first_mut() {
                    *b = self.reg(CTRL3_C) | u8::from(self.reset_polls > 0);
                }
            }
            _ => {
                for (i, b) in buf.iter_mut().enumerate() {
                    *b = self.reg(addr.wrapping_add(i as u8) & 0x7F);
                }
            }
        }
    }

    fn write(&mut self, addr: u8, value: u8) {
        if addr == CTRL3_C && value & 0x01 != 0 {
            // SW_RESET: the control registers go back to their defaults; the bit reads as set
            // for two polls.
            self.reset_registers();
            self.reset_polls = 2;
            return;
        }
        if addr == FIFO_CTRL4 && value & 0x07 == 0 {
            self.head = self.next; // bypass mode empties the FIFO
        }
        self.set(addr, value);
    }
}

impl ErrorType for FakeIis3dwb {
    type Error = FakeError;
}

impl SpiDevice for FakeIis3dwb {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), FakeError> {
        self.transactions += 1;
        match *ops {
            // Register write: [address (bit 7 clear), value].
            [Operation::Write(&[addr, value])] if addr & 0x80 == 0 => {
                self.write(addr, value);
                Ok(())
            }
            // Register (or FIFO) read: [address | 0x80], then the bytes.
            [Operation::Write(&[addr]), Operation::Read(ref mut buf)] if addr & 0x80 != 0 => {
                self.read(addr & 0x7F, buf);
                Ok(())
            }
            _ => Err(FakeError::Unsupported),
        }
    }
}

/// The fake completes its reset without waiting; nothing to delay.
struct NoDelay;

impl DelayNs for NoDelay {
    fn delay_ns(&mut self, _ns: u32) {}
}

// ---------------------------------------------------------------------------------------------
// The check
// ---------------------------------------------------------------------------------------------

/// Events of the plain replay kept for the comparison.
const MAX_EVENTS: usize = 128;

/// Compares the front end's events, in order, with the plain replay's.
struct Checker<'a> {
    expected: &'a [Event],
    seen: usize,
    same: u32,
    differ: u32,
    /// Samples the monitor behind the driver was not told about (see the module docs).
    shift: u64,
}

impl Checker<'_> {
    fn check(&mut self, e: Event) {
        let shifted = match e {
            Event::Pulse(r) => Event::Pulse(Report {
                at_sample: r.at_sample + self.shift,
                ..r
            }),
            Event::Stuck { at_sample } => Event::Stuck {
                at_sample: at_sample + self.shift,
            },
            Event::Flow(f) => Event::Flow(f),
        };
        if self.expected.get(self.seen) == Some(&shifted) {
            self.same += 1;
        } else {
            self.differ += 1;
        }
        self.seen += 1;
    }
}

/// What the two replays gave.
pub struct Outcome {
    /// `read_samples` calls.
    pub reads: u32,
    /// SPI transactions the fake served.
    pub transactions: u32,
    /// FIFO words read out.
    pub words: u32,
    /// Overruns the driver reported.
    pub overruns: u32,
    /// Events of the plain replay.
    pub events: u32,
    /// Front-end events equal to the plain replay's (after the index shift).
    pub same: u32,
    /// Front-end events that differ, plus any missing or extra.
    pub differ: u32,
    /// Samples the monitor behind the driver was not told about.
    pub shift: u64,
    /// The front end's counters (before the shift is added back).
    pub front: Counters<DEFAULT_CLASSES>,
    /// The counters, shifted back, equal the plain replay's.
    pub counters_equal: bool,
}

impl Outcome {
    /// Every event and counter agrees.
    pub fn ok(&self) -> bool {
        self.differ == 0 && self.same == self.events && self.counters_equal
    }
}

/// Replays the stream plainly, then through the driver and the fake sensor, and compares.
pub fn run() -> Result<Outcome, &'static str> {
    let scene = crate::build_scene::<DefaultBackend>().map_err(|_| "the scene was refused")?;

    // Plain replay: one feed per sample, the recorded gap lengths.
    let mut plain = Monitor::new(scene.clone());
    let mut expected: heapless::Vec<Event, MAX_EVENTS> = heapless::Vec::new();
    for input in inputs() {
        let e = match input {
            Input::Sample(s) => plain.feed(s),
            Input::Gap(lost) => plain.gap(lost),
        };
        if let Some(e) = e {
            expected
                .push(e)
                .map_err(|_| "more events than MAX_EVENTS")?;
        }
    }
    if let Some(e) = plain.finish() {
        expected
            .push(e)
            .map_err(|_| "more events than MAX_EVENTS")?;
    }

    // Through the front end: driver, SampleSource, feed_slice.
    let config = Config {
        full_scale: FullScale::G16,
        axis: Axis::Z,
    };
    let mut sensor = Iis3dwb::new(FakeIis3dwb::new(), config);
    sensor
        .init(&mut NoDelay)
        .map_err(|_| "the IIS3DWB driver could not start the sensor")?;
    let mut monitor = Monitor::new(scene);
    let mut checker = Checker {
        expected: &expected,
        seen: 0,
        same: 0,
        differ: 0,
        shift: 0,
    };
    let (mut reads, mut overruns) = (0u32, 0u32);
    let mut buf = [0i16; 256];
    loop {
        let got = sensor
            .read_samples(&mut buf)
            .map_err(|_| "the IIS3DWB driver failed to read the FIFO")?;
        reads += 1;
        if got.gap.is_gap() {
            if let Some(e) = monitor.gap(got.lost()) {
                checker.check(e);
            }
            // What the recording really lost there.
            let lost = GAPS.get(overruns as usize).map_or(0, |g| g.lost);
            checker.shift += u64::from(lost.saturating_sub(got.lost()));
            overruns += 1;
        }
        if got.written == 0 && !got.gap.is_gap() {
            break; // the fake makes new words at every status read until the recording ends
        }
        let block = buf.get(..got.written).unwrap_or(&[]);
        monitor.feed_slice(block, |e| checker.check(e));
    }
    if let Some(e) = monitor.finish() {
        checker.check(e);
    }

    let front = *monitor.counters();
    let mut shifted = front;
    shifted.samples += checker.shift;
    shifted.lost_samples += checker.shift;
    let fake = sensor.destroy();
    Ok(Outcome {
        reads,
        transactions: fake.transactions,
        words: fake.words,
        overruns,
        events: expected.len() as u32,
        same: checker.same,
        differ: checker.differ + (checker.seen as u32).abs_diff(expected.len() as u32),
        shift: checker.shift,
        front,
        counters_equal: shifted == *plain.counters() && overruns as usize == GAPS.len(),
    })
}
