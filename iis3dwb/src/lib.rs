//! A `no_std` driver for ST's IIS3DWB wideband vibration accelerometer (26 667 samples/s,
//! 3 kB FIFO, ±2/4/8/16 g) over an [`embedded_hal::spi::SpiDevice`] (embedded-hal 1.0), and
//! [`SampleSource`], a small seam between any sample source and a streaming detector.
//!
//! A firmware loop drains the sensor into a buffer and hands it to its detector; a gap is
//! reported before the samples it precedes (here with the `coalshock` kernel's `Monitor`):
//!
//! ```ignore
//! let mut buf = [0i16; 128];
//! let got = sensor.read_samples(&mut buf)?;
//! if got.gap.is_gap() {
//!     monitor.gap(got.gap.lost());
//! }
//! monitor.feed_slice(buf.get(..got.written).unwrap_or(&[]), |event| { /* ... */ });
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
