//! A `no_std` driver for ST's IIS3DWB wideband vibration accelerometer (26 667 samples/s,
//! 3 kB FIFO, ±2/4/8/16 g) over an [`embedded_hal::spi::SpiDevice`] (embedded-hal 1.0), and
//! [`SampleSource`], a small seam between any sample source and a streaming detector.
//!
//! A firmware loop drains the sensor into a buffer and hands it to its detector; a gap is
//! reported before the samples it precedes. With the `coalshock` kernel's `Monitor`, and a
//! stand-in source here (on a board it is the driver, whose FIFO watermark interrupt calls
//! `drain`, as `fw/src/bin/reference_node.rs` does):
//!
//! ```
//! use coalshock::{Event, Monitor, Scene};
//! use iis3dwb::{Gap, SampleSource, Samples};
//!
//! /// Samples per drained block: the FIFO watermark (half the FIFO, about 9.6 ms at
//! /// 26 667 samples/s, and as long again before it overruns).
//! const BLOCK: usize = 256;
//!
//! /// Drains `source` block by block into `monitor` until less than a block is left; a
//! /// failed read is a gap of unknown length. Returns the events, counted.
//! fn drain<S: SampleSource>(
//!     source: &mut S,
//!     monitor: &mut Monitor,
//!     buf: &mut [i16; BLOCK],
//!     on_event: &mut impl FnMut(Event),
//! ) {
//!     loop {
//!         let Ok(got) = source.read_samples(buf) else {
//!             if let Some(e) = monitor.gap(1) {
//!                 on_event(e);
//!             }
//!             return;
//!         };
//!         if got.gap.is_gap()
//!             && let Some(e) = monitor.gap(got.lost())
//!         {
//!             on_event(e);
//!         }
//!         monitor.feed_slice(buf.get(..got.written).unwrap_or(&[]), |e| on_event(e));
//!         if got.written < BLOCK {
//!             return;
//!         }
//!     }
//! }
//!
//! /// A quiet plate: `left` samples of noise within ±4 counts (a linear congruential
//! /// generator), then an empty FIFO; `lost` samples dropped before the first batch.
//! struct Quiet {
//!     left: usize,
//!     lost: u32,
//!     state: u32,
//! }
//!
//! impl SampleSource for Quiet {
//!     type Error = ();
//!     fn read_samples(&mut self, out: &mut [i16]) -> Result<Samples, ()> {
//!         let written = out.len().min(self.left);
//!         for s in out.iter_mut().take(written) {
//!             self.state = self.state.wrapping_mul(1_103_515_245).wrapping_add(12_345);
//!             *s = ((self.state >> 16) % 9) as i16 - 4;
//!         }
//!         self.left -= written;
//!         let gap = if self.lost > 0 { Gap::AtLeast(self.lost) } else { Gap::None };
//!         self.lost = 0;
//!         Ok(Samples { written, gap })
//!     }
//! }
//!
//! let mut monitor = Monitor::new(Scene::paper().expect("the paper scene builds"));
//! let mut buf = [0i16; BLOCK];
//! let mut events = 0;
//! let mut plate = Quiet { left: 1000, lost: 3, state: 1 };
//! drain(&mut plate, &mut monitor, &mut buf, &mut |_| events += 1);
//! assert_eq!(monitor.samples_fed(), 1003, "the 1 000 read and the 3 lost: the clock keeps time");
//! assert_eq!(monitor.counters().lost_samples, 3, "the gap is counted");
//! assert_eq!(events, 0, "a quiet plate reports no pulse");
//! ```
//!
//! Layout: [`register`] (addresses and bit fields from datasheet DS13114), [`Iis3dwb`] (the
//! driver, in `device.rs`), the configuration, status and error types, and the seam.
//!
//! The driver never panics, never allocates and indexes nothing that can fail.
#![no_std]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod device;
pub mod register;
mod source;
mod types;

pub use device::Iis3dwb;
pub use source::{Gap, SampleSource, Samples};
pub use types::{
    Axis, BURST_WORDS, Config, Error, FIFO_WORDS, FifoStatus, FullScale, SAMPLE_BITS,
    SAMPLE_RATE_HZ,
};
