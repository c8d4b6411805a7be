//! The driver: [`Iis3dwb`] over an [`embedded_hal::spi::SpiDevice`].

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{Operation, SpiDevice};

use crate::register::{
    Register, SPI_READ, TAG_SENSOR_XL, WHO_AM_I_VALUE, ctrl1_xl, ctrl3_c, fifo_ctrl2, fifo_ctrl3,
    fifo_ctrl4, int1_ctrl,
};
use crate::source::{Gap, SampleSource, Samples};
use crate::types::{Axis, BURST_WORDS, Config, Error, FIFO_WORDS, FifoStatus, WORD_BYTES};

/// Polls of SW_RESET before [`Error::ResetTimeout`].
const RESET_POLLS: u32 = 100;
/// Delay between two polls of SW_RESET, in µs (so the reset is given at least 10 ms).
const RESET_POLL_US: u32 = 100;

/// Driver of ST's IIS3DWB wideband accelerometer (26 667 samples/s, 3 kB FIFO of 512 words,
/// 16-bit two's complement, ±2/4/8/16 g) over an SPI device (mode 0 or 3, up to 10 MHz).
///
/// [`init`](Self::init) checks WHO_AM_I, resets the device and streams the accelerometer into
/// the FIFO in continuous mode; [`SampleSource::read_samples`] then drains the configured axis.
/// At 26.7 kS/s the 512-word FIFO lasts about 19 ms: drain it faster than that or the driver
/// reports a [`Gap::AtLeast`]. For an interrupt-driven drain, set a watermark
/// ([`set_fifo_watermark`](Self::set_fifo_watermark)) and route it to the INT1 pin
/// ([`route_fifo_watermark_to_int1`](Self::route_fifo_watermark_to_int1)).
///
/// The driver never panics, never allocates and indexes nothing that can fail.
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
    /// The reset clears the watermark and the INT1 routing: set them after `init`.
    /// Call it at least 10 ms (the boot time) after power-up.
    pub fn init<D: DelayNs>(&mut self, delay: &mut D) -> Result<(), Error<SPI::Error>> {
        let id = self.who_am_i()?;
        if id != WHO_AM_I_VALUE {
            return Err(Error::WrongDevice(id));
        }
        self.write_reg(Register::CTRL3_C, ctrl3_c::SW_RESET | ctrl3_c::IF_INC)?;
        self.wait_reset(delay)?;
        self.write_reg(Register::CTRL3_C, ctrl3_c::BDU | ctrl3_c::IF_INC)?;
        self.write_reg(Register::FIFO_CTRL3, fifo_ctrl3::BDR_XL_26K7)?;
        self.write_reg(Register::FIFO_CTRL4, fifo_ctrl4::MODE_CONTINUOUS)?;
        self.write_reg(Register::CTRL1_XL, self.ctrl1_xl())
    }

    /// Reads WHO_AM_I (0Fh); 0x7B for an IIS3DWB.
    pub fn who_am_i(&mut self) -> Result<u8, Error<SPI::Error>> {
        let mut id = [0u8];
        self.read_regs(Register::WHO_AM_I, &mut id)?;
        let [id] = id;
        Ok(id)
    }

    /// Reads FIFO_STATUS1 and FIFO_STATUS2 in one access (this clears FIFO_OVR_LATCHED, so an
    /// overrun seen here is not reported again by [`SampleSource::read_samples`]).
    pub fn fifo_status(&mut self) -> Result<FifoStatus, Error<SPI::Error>> {
        let mut s = [0u8; 2];
        self.read_regs(Register::FIFO_STATUS1, &mut s)?;
        let [s1, s2] = s;
        Ok(FifoStatus::from_registers(s1, s2))
    }

    /// Sets the FIFO watermark to `words` (0..=511; 0 disables it): FIFO_CTRL1 (07h) =
    /// `WTM[7:0]`, then FIFO_CTRL2 (08h) = `WTM8` (STOP_ON_WTM left clear, so the FIFO keeps
    /// streaming past the watermark). A larger value is refused with
    /// [`Error::InvalidWatermark`] before anything is sent.
    pub fn set_fifo_watermark(&mut self, words: u16) -> Result<(), Error<SPI::Error>> {
        if words >= FIFO_WORDS {
            return Err(Error::InvalidWatermark(words));
        }
        let [lo, hi] = words.to_le_bytes();
        self.write_reg(Register::FIFO_CTRL1, lo)?;
        self.write_reg(Register::FIFO_CTRL2, hi & fifo_ctrl2::WTM8)
    }

    /// Routes the FIFO watermark flag to the INT1 pin (INT1_CTRL (0Dh) = 0x08, INT1_FIFO_TH),
    /// or nothing to it (`false`: 0x00). INT1 is push-pull and active high after
    /// [`init`](Self::init), and stays high while the FIFO holds at least the watermark: an
    /// edge-triggered interrupt must drain the FIFO below it to see the next edge.
    pub fn route_fifo_watermark_to_int1(&mut self, on: bool) -> Result<(), Error<SPI::Error>> {
        let value = if on { int1_ctrl::FIFO_TH } else { 0 };
        self.write_reg(Register::INT1_CTRL, value)
    }

    /// Empties the FIFO and restarts it: FIFO_CTRL4 = 0x00 (bypass) then 0x06 (continuous).
    /// Use it to resynchronise after a long stall; the samples dropped are not reported.
    pub fn flush_fifo(&mut self) -> Result<(), Error<SPI::Error>> {
        self.write_reg(Register::FIFO_CTRL4, fifo_ctrl4::MODE_BYPASS)?;
        self.write_reg(Register::FIFO_CTRL4, fifo_ctrl4::MODE_CONTINUOUS)
    }

    /// Stops the accelerometer (CTRL1_XL = 0x00) and the FIFO (FIFO_CTRL4 = 0x00, bypass).
    /// [`init`](Self::init) starts it again.
    pub fn power_down(&mut self) -> Result<(), Error<SPI::Error>> {
        self.write_reg(Register::CTRL1_XL, ctrl1_xl::POWER_DOWN)?;
        self.write_reg(Register::FIFO_CTRL4, fifo_ctrl4::MODE_BYPASS)
    }

    /// CTRL1_XL value: XL_EN = 26 667 Hz, FS from the configuration, LPF2 off.
    fn ctrl1_xl(&self) -> u8 {
        ctrl1_xl::XL_EN_26K7 | (self.config.full_scale.fs_bits() << ctrl1_xl::FS_SHIFT)
    }

    /// Polls SW_RESET until the device clears it.
    fn wait_reset<D: DelayNs>(&mut self, delay: &mut D) -> Result<(), Error<SPI::Error>> {
        for _ in 0..RESET_POLLS {
            delay.delay_us(RESET_POLL_US);
            let mut c = [0u8];
            self.read_regs(Register::CTRL3_C, &mut c)?;
            let [c] = c;
            if c & ctrl3_c::SW_RESET == 0 {
                return Ok(());
            }
        }
        Err(Error::ResetTimeout)
    }

    /// Writes one register: one transaction of `[reg, value]` (bit 7 of `reg` clear).
    fn write_reg(&mut self, reg: Register, value: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[reg.addr() & !SPI_READ, value])?;
        Ok(())
    }

    /// Reads `buf.len()` registers from `reg` on: one transaction writing `reg | 0x80` then
    /// reading `buf` (auto-increment, or the FIFO roll-back from 7Eh to 78h).
    fn read_regs(&mut self, reg: Register, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        self.spi.transaction(&mut [
            Operation::Write(&[reg.addr() | SPI_READ]),
            Operation::Read(buf),
        ])?;
        Ok(())
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
            self.read_regs(Register::FIFO_DATA_OUT_TAG, bytes)?;
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
