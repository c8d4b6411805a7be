//! Accelerometer front ends: the [`SampleSource`] seam between any accelerometer and the
//! streaming [`Monitor`](crate::Monitor) / [`Detector`](crate::Detector), and [`Iis3dwb`], a
//! driver for ST's IIS3DWB wideband vibration accelerometer over an
//! [`embedded_hal::spi::SpiDevice`].
//!
//! A firmware loop drains the sensor into a buffer and hands it to the kernel; a gap is
//! reported before the samples it precedes:
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
//! The driver never panics, never allocates and indexes nothing that can fail.

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{Operation, SpiDevice};

/// Standard gravity in m/s^2 (the `g` of the sensitivities).
const STANDARD_GRAVITY: f32 = 9.806_65;

// ---------------------------------------------------------------------------------------------
// The seam
// ---------------------------------------------------------------------------------------------

/// Samples lost before the first sample of a [`Samples`] batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Gap {
    /// No sample was lost: the batch follows the previous one without a hole.
    None,
    /// Exactly this many samples were lost (a source with a sample counter).
    Exactly(u32),
    /// At least this many samples were lost; the source cannot tell how many (a FIFO overrun
    /// flag without a counter, as on the IIS3DWB).
    AtLeast(u32),
}

impl Gap {
    /// Samples known to be lost: the exact count, the lower bound, or 0.
    pub const fn lost(self) -> u32 {
        match self {
            Gap::None => 0,
            Gap::Exactly(n) | Gap::AtLeast(n) => n,
        }
    }

    /// Whether samples were lost (the caller should report a gap to the detector).
    pub const fn is_gap(self) -> bool {
        match self {
            Gap::None => false,
            Gap::Exactly(n) | Gap::AtLeast(n) => n > 0,
        }
    }
}

/// What one [`SampleSource::read_samples`] call produced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Samples {
    /// Samples written at the start of the caller's buffer (`out[..written]`), oldest first.
    pub written: usize,
    /// Samples lost since the previous call, placed before `out[0]`.
    pub gap: Gap,
}

impl Samples {
    /// Samples known to be lost before this batch (see [`Gap::lost`]).
    pub const fn lost(&self) -> u32 {
        self.gap.lost()
    }
}

/// A source of raw samples of the impact axis: the seam between any accelerometer (or ADC,
/// replay file, simulator) and the kernel's streaming pulse detector.
///
/// Samples are raw two's-complement sensor codes (counts); the scale comes from the
/// [`SensorChain`](crate::SensorChain) of the scene, which a driver helps to fill (for the
/// IIS3DWB see [`FullScale::counts_per_m_s2`]).
///
/// An implementation is non-blocking in spirit: it returns what is available now, possibly
/// nothing, and never waits for more.
pub trait SampleSource {
    /// The error of the underlying bus or device.
    type Error;

    /// Fills up to `out.len()` samples of the impact axis, oldest first, and reports how many
    /// were written and whether samples were lost since the last call (for example a FIFO
    /// overrun), so that the caller can tell the detector about the gap
    /// ([`Monitor::gap`](crate::Monitor::gap)) before feeding `out[..written]`.
    ///
    /// A gap is reported even when nothing is written (an empty `out` still reports it), and
    /// each gap is reported once. An `Err` may have consumed samples (and a pending gap) that it
    /// cannot return: the caller should count it as a gap of unknown length.
    fn read_samples(&mut self, out: &mut [i16]) -> Result<Samples, Self::Error>;
}

impl<T: SampleSource + ?Sized> SampleSource for &mut T {
    type Error = T::Error;

    fn read_samples(&mut self, out: &mut [i16]) -> Result<Samples, Self::Error> {
        (**self).read_samples(out)
    }
}

// ---------------------------------------------------------------------------------------------
// IIS3DWB register map (datasheet DS13114; the same map as ST's reference C driver)
// ---------------------------------------------------------------------------------------------

/// Set in the first byte of an SPI frame to read (bit 7 = 1); clear to write.
const SPI_READ: u8 = 0x80;

/// FIFO_CTRL3 (09h): `BDR_XL[3:0]` (bits 3:0) = batching data rate of the accelerometer into the
/// FIFO; bits 7:4 unused (0).
const FIFO_CTRL3: u8 = 0x09;
/// BDR_XL = 1010b: accelerometer batched in the FIFO at 26 667 Hz (0000b: not batched).
const FIFO_CTRL3_BDR_XL_26K7: u8 = 0b1010;

/// FIFO_CTRL4 (0Ah): `FIFO_MODE[2:0]` (bits 2:0); bit 3 unused; `ODR_T_BATCH[1:0]` (bits 5:4,
/// temperature batching, 00 = off); `DEC_TS_BATCH[1:0]` (bits 7:6, timestamp batching, 00 = off).
const FIFO_CTRL4: u8 = 0x0A;
/// FIFO_MODE = 000b: bypass (FIFO disabled and emptied).
const FIFO_MODE_BYPASS: u8 = 0b000;
/// FIFO_MODE = 110b: continuous (stream) mode, the oldest word is overwritten when full;
/// temperature and timestamp not batched.
const FIFO_MODE_CONTINUOUS: u8 = 0b110;

/// WHO_AM_I (0Fh): device identification, read-only.
const WHO_AM_I: u8 = 0x0F;
/// WHO_AM_I value of the IIS3DWB.
const WHO_AM_I_IIS3DWB: u8 = 0x7B;

/// CTRL1_XL (10h): `XL_EN[2:0]` (bits 7:5) = accelerometer enable / ODR; bit 4 unused (0);
/// `FS[1:0]` (bits 3:2) = full scale (see [`FullScale::fs_bits`]); LPF2_XL_EN (bit 1) = second
/// low-pass stage on the output (0 = off, the wide band is kept); bit 0 unused (0).
const CTRL1_XL: u8 = 0x10;
/// XL_EN = 101b in bits 7:5: accelerometer on at 26 667 Hz (000b: power-down).
const CTRL1_XL_EN_26K7: u8 = 0b101 << 5;
/// XL_EN = 000b: accelerometer power-down.
const CTRL1_XL_POWER_DOWN: u8 = 0;

/// CTRL3_C (12h): BOOT (bit 7), BDU (bit 6), H_LACTIVE (bit 5), PP_OD (bit 4), SIM (bit 3),
/// IF_INC (bit 2), bit 1 must be 0, SW_RESET (bit 0). Reset value 04h (IF_INC set).
const CTRL3_C: u8 = 0x12;
/// SW_RESET (bit 0): software reset of the control registers; cleared by the device when done.
const CTRL3_C_SW_RESET: u8 = 1 << 0;
/// IF_INC (bit 2): register address auto-incremented on multi-byte access (needed for the
/// FIFO status pair and burst FIFO reads).
const CTRL3_C_IF_INC: u8 = 1 << 2;
/// BDU (bit 6): block data update, output registers not updated until MSB and LSB are read.
const CTRL3_C_BDU: u8 = 1 << 6;

/// FIFO_STATUS1 (3Ah): `DIFF_FIFO[7:0]`, unread FIFO words (one word = tag + 6 bytes).
/// Read together with FIFO_STATUS2 (3Bh) in one auto-incremented access.
const FIFO_STATUS1: u8 = 0x3A;
/// FIFO_STATUS2 bits 1:0: `DIFF_FIFO[9:8]`.
const FIFO_STATUS2_DIFF_HI: u8 = 0b11;
/// FIFO_STATUS2 bit 3: FIFO_OVR_LATCHED, an overrun happened since FIFO_STATUS2 was last read
/// (cleared by reading it).
const FIFO_STATUS2_OVR_LATCHED: u8 = 1 << 3;
/// FIFO_STATUS2 bit 5: FIFO_FULL_IA, the FIFO will be full at the next ODR.
const FIFO_STATUS2_FULL_IA: u8 = 1 << 5;
/// FIFO_STATUS2 bit 6: FIFO_OVR_IA, the FIFO is full and at least one word was overwritten.
const FIFO_STATUS2_OVR_IA: u8 = 1 << 6;
/// FIFO_STATUS2 bit 7: FIFO_WTM_IA, the FIFO level reached the watermark.
const FIFO_STATUS2_WTM_IA: u8 = 1 << 7;

/// FIFO_DATA_OUT_TAG (78h): `TAG_SENSOR[4:0]` (bits 7:3), `TAG_CNT[1:0]` (bits 2:1), TAG_PARITY
/// (bit 0). It is followed by FIFO_DATA_OUT_X_L..Z_H (79h..7Eh), the six data bytes of the word
/// (X, Y, Z, each little-endian two's complement). With IF_INC set the address rolls back from
/// 7Eh to 78h, so one burst read returns consecutive words.
const FIFO_DATA_OUT_TAG: u8 = 0x78;
/// TAG_SENSOR value of an accelerometer word (03h: temperature, 04h: timestamp).
const TAG_SENSOR_XL: u8 = 0x02;

/// Bytes per FIFO word: tag + X, Y, Z (2 bytes each).
const WORD_BYTES: usize = 7;
/// FIFO words read per SPI transaction (a 112-byte stack buffer).
pub const BURST_WORDS: usize = 16;

/// IIS3DWB output data rate and FIFO batching rate, in Hz: the `sample_rate_hz` of
/// [`SensorChain`](crate::SensorChain) (nominal; the device's ODR has a part-to-part tolerance
/// of its own).
pub const IIS3DWB_SAMPLE_RATE_HZ: f32 = 26_667.0;
/// IIS3DWB bits per sample: the `adc_bits` of
/// [`SensorChain::from_plate`](crate::SensorChain::from_plate).
pub const IIS3DWB_SAMPLE_BITS: u8 = 16;
/// IIS3DWB FIFO capacity in accelerometer words (3 kB / 6 data bytes).
pub const IIS3DWB_FIFO_WORDS: u16 = 512;

/// Polls of SW_RESET before [`Error::ResetTimeout`].
const RESET_POLLS: u32 = 100;
/// Delay between two polls of SW_RESET, in µs (so the reset is given at least 10 ms).
const RESET_POLL_US: u32 = 100;

// ---------------------------------------------------------------------------------------------
// IIS3DWB driver types
// ---------------------------------------------------------------------------------------------

/// An error of the [`Iis3dwb`] driver.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<CommE> {
    /// The SPI bus or chip select failed.
    Comm(CommE),
    /// WHO_AM_I did not read 0x7B: another (or no) device answers; the value read is carried.
    WrongDevice(u8),
    /// The software reset did not complete (SW_RESET still set after about 10 ms of polling).
    ResetTimeout,
}

impl<CommE: core::fmt::Debug> core::fmt::Display for Error<CommE> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Comm(e) => write!(f, "bus error: {e:?}"),
            Error::WrongDevice(id) => write!(f, "WHO_AM_I is {id:#04x}, expected 0x7b"),
            Error::ResetTimeout => write!(f, "software reset did not complete"),
        }
    }
}

impl<CommE: core::fmt::Debug> core::error::Error for Error<CommE> {}

/// Accelerometer full scale of the IIS3DWB.
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

    /// Counts per m/s^2 (with g = 9.80665 m/s^2): the `counts_per_m_s2` of
    /// [`SensorChain::from_plate`](crate::SensorChain::from_plate), about 1671.6 at ±2 g.
    pub fn counts_per_m_s2(self) -> f32 {
        1.0e6 / (self.sensitivity_ug_per_lsb() as f32 * STANDARD_GRAVITY)
    }
}

/// The axis of the IIS3DWB that carries the impact (normal to the plate).
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

/// Configuration applied by [`Iis3dwb::init`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Accelerometer full scale.
    pub full_scale: FullScale,
    /// Axis returned by [`SampleSource::read_samples`].
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
    /// The level reached the watermark (FIFO_WTM_IA; the driver leaves the watermark at 0).
    pub watermark: bool,
}

impl FifoStatus {
    /// Decodes FIFO_STATUS1 (`s1`) and FIFO_STATUS2 (`s2`).
    pub const fn from_registers(s1: u8, s2: u8) -> Self {
        Self {
            level: (((s2 & FIFO_STATUS2_DIFF_HI) as u16) << 8) | s1 as u16,
            overrun: s2 & (FIFO_STATUS2_OVR_IA | FIFO_STATUS2_OVR_LATCHED) != 0,
            full: s2 & FIFO_STATUS2_FULL_IA != 0,
            watermark: s2 & FIFO_STATUS2_WTM_IA != 0,
        }
    }
}

/// Driver of ST's IIS3DWB wideband accelerometer (26 667 samples/s, 3 kB FIFO of 512 words,
/// 16-bit two's complement, ±2/4/8/16 g) over an SPI device (mode 0 or 3, up to 10 MHz).
///
/// [`init`](Self::init) checks WHO_AM_I, resets the device and streams the accelerometer into
/// the FIFO in continuous mode; [`SampleSource::read_samples`] then drains the configured axis.
/// At 26.7 kS/s the 512-word FIFO lasts about 19 ms: drain it faster than that or the driver
/// reports a [`Gap::AtLeast`].
#[derive(Debug)]
pub struct Iis3dwb<SPI> {
    spi: SPI,
    config: Config,
}

impl<SPI: SpiDevice> Iis3dwb<SPI> {
    /// A driver for the device behind `spi`; nothing is sent until [`init`](Self::init).
    pub fn new(spi: SPI, config: Config) -> Self {
        Self { spi, config }
    }

    /// Gives the SPI device back.
    pub fn destroy(self) -> SPI {
        self.spi
    }

    /// The configuration.
    pub fn config(&self) -> Config {
        self.config
    }

    /// Checks the device, resets it and starts streaming, in this order:
    ///
    /// 1. WHO_AM_I (0Fh) must read 0x7B, else [`Error::WrongDevice`];
    /// 2. CTRL3_C (12h) = 0x05 (SW_RESET | IF_INC), then CTRL3_C is polled every 100 µs until
    ///    SW_RESET clears (at most 100 polls, else [`Error::ResetTimeout`]);
    /// 3. CTRL3_C = 0x44 (BDU | IF_INC);
    /// 4. FIFO_CTRL3 (09h) = 0x0A (BDR_XL = 26 667 Hz);
    /// 5. FIFO_CTRL4 (0Ah) = 0x06 (continuous mode, no temperature or timestamp batching);
    /// 6. CTRL1_XL (10h) = 0xA0 | FS << 2 (accelerometer on at 26 667 Hz with the full scale,
    ///    LPF2 off), last so that the FIFO is ready when data starts.
    ///
    /// Call it at least 10 ms (the boot time) after power-up.
    pub fn init<D: DelayNs>(&mut self, delay: &mut D) -> Result<(), Error<SPI::Error>> {
        let id = self.who_am_i()?;
        if id != WHO_AM_I_IIS3DWB {
            return Err(Error::WrongDevice(id));
        }
        self.write_reg(CTRL3_C, CTRL3_C_SW_RESET | CTRL3_C_IF_INC)?;
        self.wait_reset(delay)?;
        self.write_reg(CTRL3_C, CTRL3_C_BDU | CTRL3_C_IF_INC)?;
        self.write_reg(FIFO_CTRL3, FIFO_CTRL3_BDR_XL_26K7)?;
        self.write_reg(FIFO_CTRL4, FIFO_MODE_CONTINUOUS)?;
        self.write_reg(CTRL1_XL, self.ctrl1_xl())
    }

    /// Reads WHO_AM_I (0Fh); 0x7B for an IIS3DWB.
    pub fn who_am_i(&mut self) -> Result<u8, Error<SPI::Error>> {
        let mut id = [0u8];
        self.read_regs(WHO_AM_I, &mut id)?;
        let [id] = id;
        Ok(id)
    }

    /// Reads FIFO_STATUS1 and FIFO_STATUS2 in one access (this clears FIFO_OVR_LATCHED, so an
    /// overrun seen here is not reported again by [`SampleSource::read_samples`]).
    pub fn fifo_status(&mut self) -> Result<FifoStatus, Error<SPI::Error>> {
        let mut s = [0u8; 2];
        self.read_regs(FIFO_STATUS1, &mut s)?;
        let [s1, s2] = s;
        Ok(FifoStatus::from_registers(s1, s2))
    }

    /// Empties the FIFO and restarts it: FIFO_CTRL4 = 0x00 (bypass) then 0x06 (continuous).
    /// Use it to resynchronise after a long stall; the samples dropped are not reported.
    pub fn flush_fifo(&mut self) -> Result<(), Error<SPI::Error>> {
        self.write_reg(FIFO_CTRL4, FIFO_MODE_BYPASS)?;
        self.write_reg(FIFO_CTRL4, FIFO_MODE_CONTINUOUS)
    }

    /// Stops the accelerometer (CTRL1_XL = 0x00) and the FIFO (FIFO_CTRL4 = 0x00, bypass).
    /// [`init`](Self::init) starts it again.
    pub fn power_down(&mut self) -> Result<(), Error<SPI::Error>> {
        self.write_reg(CTRL1_XL, CTRL1_XL_POWER_DOWN)?;
        self.write_reg(FIFO_CTRL4, FIFO_MODE_BYPASS)
    }

    /// CTRL1_XL value: XL_EN = 26 667 Hz, FS from the configuration, LPF2 off.
    fn ctrl1_xl(&self) -> u8 {
        CTRL1_XL_EN_26K7 | (self.config.full_scale.fs_bits() << 2)
    }

    /// Polls SW_RESET until the device clears it.
    fn wait_reset<D: DelayNs>(&mut self, delay: &mut D) -> Result<(), Error<SPI::Error>> {
        for _ in 0..RESET_POLLS {
            delay.delay_us(RESET_POLL_US);
            let mut c = [0u8];
            self.read_regs(CTRL3_C, &mut c)?;
            let [c] = c;
            if c & CTRL3_C_SW_RESET == 0 {
                return Ok(());
            }
        }
        Err(Error::ResetTimeout)
    }

    /// Writes one register: one transaction of `[reg, value]` (bit 7 of `reg` clear).
    fn write_reg(&mut self, reg: u8, value: u8) -> Result<(), Error<SPI::Error>> {
        self.spi
            .write(&[reg & !SPI_READ, value])
            .map_err(Error::Comm)
    }

    /// Reads `buf.len()` registers from `reg` on: one transaction writing `reg | 0x80` then
    /// reading `buf` (auto-increment, or the FIFO roll-back from 7Eh to 78h).
    fn read_regs(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[reg | SPI_READ]), Operation::Read(buf)])
            .map_err(Error::Comm)
    }

    /// The configured axis of a FIFO word, or `None` for a word that is not accelerometer data.
    fn decode(&self, word: &[u8]) -> Option<i16> {
        let &[tag, xl, xh, yl, yh, zl, zh] = word else {
            return None;
        };
        if tag >> 3 != TAG_SENSOR_XL {
            return None;
        }
        let (lo, hi) = match self.config.axis {
            Axis::X => (xl, xh),
            Axis::Y => (yl, yh),
            Axis::Z => (zl, zh),
        };
        Some(i16::from_le_bytes([lo, hi]))
    }
}

impl<SPI: SpiDevice> SampleSource for Iis3dwb<SPI> {
    type Error = Error<SPI::Error>;

    /// Reads the FIFO status (one transaction of 2 bytes from 3Ah), then
    /// `min(level, out.len())` words in bursts of at most [`BURST_WORDS`] words (one
    /// transaction each: 78h | 0x80 then 7 bytes per word). Words whose TAG_SENSOR is not the
    /// accelerometer are consumed and skipped, so `written` can be less than the words read.
    ///
    /// An overrun (FIFO_OVR_IA or FIFO_OVR_LATCHED) is reported as [`Gap::AtLeast`]`(1)`: the
    /// device does not count overwritten words, and the gap is placed before this batch
    /// although it may have happened during the previous drain.
    ///
    /// A bus error in a burst after the first loses the words already drained in this call.
    fn read_samples(&mut self, out: &mut [i16]) -> Result<Samples, Self::Error> {
        let status = self.fifo_status()?;
        let gap = if status.overrun {
            Gap::AtLeast(1)
        } else {
            Gap::None
        };
        let mut words_left = usize::from(status.level).min(out.len());
        let capacity = out.len();
        let mut slots = out.iter_mut();
        let mut buf = [0u8; BURST_WORDS * WORD_BYTES];
        while words_left > 0 {
            let words = words_left.min(BURST_WORDS);
            let Some(bytes) = buf.get_mut(..words * WORD_BYTES) else {
                break;
            };
            self.read_regs(FIFO_DATA_OUT_TAG, bytes)?;
            for word in bytes.chunks_exact(WORD_BYTES) {
                // A slot is taken only for an accelerometer word.
                if let Some(value) = self.decode(word) {
                    if let Some(slot) = slots.next() {
                        *slot = value;
                    }
                }
            }
            words_left = words_left.saturating_sub(words);
        }
        Ok(Samples {
            written: capacity.saturating_sub(slots.len()),
            gap,
        })
    }
}
