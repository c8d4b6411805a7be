//! Configuration, status and error types of the driver, and the device's fixed figures.

use crate::register::fifo_status2;

/// Standard gravity in m/s^2 (the `g` of the sensitivities).
const STANDARD_GRAVITY: f32 = 9.806_65;

/// Output data rate and FIFO batching rate, in Hz (nominal; the device's ODR has a
/// part-to-part tolerance of its own).
pub const SAMPLE_RATE_HZ: f32 = 26_667.0;
/// Bits per sample (16-bit two's complement).
pub const SAMPLE_BITS: u8 = 16;
/// FIFO capacity in accelerometer words (3 kB / 6 data bytes).
pub const FIFO_WORDS: u16 = 512;
/// Bytes per FIFO word: tag + X, Y, Z (2 bytes each).
pub(crate) const WORD_BYTES: usize = 7;
/// FIFO words read per SPI transaction (a 112-byte stack buffer).
pub const BURST_WORDS: usize = 16;

/// An error of the driver.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<CommE> {
    /// The SPI bus or chip select failed.
    Comm(CommE),
    /// WHO_AM_I did not read 0x7B: another (or no) device answers; the value read is carried.
    WrongDevice(u8),
    /// The software reset did not complete (SW_RESET still set after about 10 ms of polling).
    ResetTimeout,
    /// A FIFO watermark above the FIFO's 512 words was asked for.
    InvalidWatermark(u16),
}

impl<CommE> From<CommE> for Error<CommE> {
    fn from(e: CommE) -> Self {
        Error::Comm(e)
    }
}

impl<CommE: core::fmt::Debug> core::fmt::Display for Error<CommE> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Comm(e) => write!(f, "bus error: {e:?}"),
            Error::WrongDevice(id) => write!(f, "WHO_AM_I is {id:#04x}, expected 0x7b"),
            Error::ResetTimeout => write!(f, "software reset did not complete"),
            Error::InvalidWatermark(w) => {
                write!(f, "FIFO watermark {w} above the FIFO's {FIFO_WORDS} words")
            }
        }
    }
}

impl<CommE: core::fmt::Debug> core::error::Error for Error<CommE> {}

/// Accelerometer full scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FullScale {
    /// ±2 g, 0.061 mg/LSB.
    G2,
    /// ±4 g, 0.122 mg/LSB.
    G4,
    /// ±8 g, 0.244 mg/LSB.
    G8,
    /// ±16 g, 0.488 mg/LSB.
    G16,
}

impl FullScale {
    /// `FS[1:0]` code of CTRL1_XL (bits 3:2): 00 = ±2 g, 01 = ±16 g, 10 = ±4 g, 11 = ±8 g
    /// (note the out-of-order ±16 g code).
    pub const fn fs_bits(self) -> u8 {
        match self {
            FullScale::G2 => 0b00,
            FullScale::G16 => 0b01,
            FullScale::G4 => 0b10,
            FullScale::G8 => 0b11,
        }
    }

    /// Full scale in g (2, 4, 8 or 16).
    pub const fn g(self) -> u8 {
        match self {
            FullScale::G2 => 2,
            FullScale::G4 => 4,
            FullScale::G8 => 8,
            FullScale::G16 => 16,
        }
    }

    /// Typical sensitivity in µg per LSB (61, 122, 244 or 488; datasheet typical values).
    pub const fn sensitivity_ug_per_lsb(self) -> u32 {
        match self {
            FullScale::G2 => 61,
            FullScale::G4 => 122,
            FullScale::G8 => 244,
            FullScale::G16 => 488,
        }
    }

    /// Counts per m/s^2 (with g = 9.80665 m/s^2), about 1671.6 at ±2 g: the scale a
    /// detector's sensor chain needs to turn codes into acceleration.
    pub fn counts_per_m_s2(self) -> f32 {
        1.0e6 / (self.sensitivity_ug_per_lsb() as f32 * STANDARD_GRAVITY)
    }
}

/// The axis that carries the signal of interest (for an impact plate: the plate's normal).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axis {
    /// X axis (FIFO data bytes 1..2 of a word).
    X,
    /// Y axis (FIFO data bytes 3..4 of a word).
    Y,
    /// Z axis (FIFO data bytes 5..6 of a word).
    Z,
}

/// Configuration applied by [`Iis3dwb::init`](crate::Iis3dwb::init).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Accelerometer full scale.
    pub full_scale: FullScale,
    /// Axis returned by [`SampleSource::read_samples`](crate::SampleSource::read_samples).
    pub axis: Axis,
}

/// FIFO state as read from FIFO_STATUS1/2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FifoStatus {
    /// Unread FIFO words (DIFF_FIFO, 0..=1023; the FIFO holds 512 accelerometer words).
    pub level: u16,
    /// Words were overwritten (FIFO_OVR_IA or FIFO_OVR_LATCHED): samples were lost.
    pub overrun: bool,
    /// The FIFO will be full at the next sample (FIFO_FULL_IA).
    pub full: bool,
    /// The level reached the watermark (FIFO_WTM_IA).
    pub watermark: bool,
}

impl FifoStatus {
    /// Decodes FIFO_STATUS1 (`s1`) and FIFO_STATUS2 (`s2`).
    pub const fn from_registers(s1: u8, s2: u8) -> Self {
        Self {
            level: (((s2 & fifo_status2::DIFF_HI) as u16) << 8) | s1 as u16,
            overrun: s2 & (fifo_status2::OVR_IA | fifo_status2::OVR_LATCHED) != 0,
            full: s2 & fifo_status2::FULL_IA != 0,
            watermark: s2 & fifo_status2::WTM_IA != 0,
        }
    }
}
