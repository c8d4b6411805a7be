//! Host tests of the IIS3DWB driver against a mocked SPI device (every byte on the bus
//! checked) and of the `SampleSource` seam. Register addresses and values are written out here
//! as literal numbers from the datasheet (DS13114), independently of the crate's constants.
#![cfg(not(target_os = "none"))]

use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};
use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::spi::{Mock, Transaction};
use iis3dwb::{
    Axis, BURST_WORDS, Config, Error, FIFO_WORDS, FifoStatus, FullScale, Gap, Iis3dwb, SAMPLE_BITS,
    SAMPLE_RATE_HZ, SampleSource, Samples,
};

// --- expected bus traffic -------------------------------------------------------------------

/// One register write: a transaction carrying `[reg, value]`.
fn write(reg: u8, value: u8) -> Vec<Transaction<u8>> {
    vec![
        Transaction::transaction_start(),
        Transaction::write_vec(vec![reg, value]),
        Transaction::transaction_end(),
    ]
}

/// One read of `response.len()` bytes from `reg`: address with bit 7 set, then the bytes.
fn read(reg: u8, response: Vec<u8>) -> Vec<Transaction<u8>> {
    vec![
        Transaction::transaction_start(),
        Transaction::write(reg | 0x80),
        Transaction::read_vec(response),
        Transaction::transaction_end(),
    ]
}

/// The FIFO status pair read from 3Ah.
fn status(s1: u8, s2: u8) -> Vec<Transaction<u8>> {
    read(0x3A, vec![s1, s2])
}

/// A burst read of FIFO words from 78h.
fn fifo(words: &[[u8; 7]]) -> Vec<Transaction<u8>> {
    read(0x78, words.iter().flatten().copied().collect())
}

/// An accelerometer FIFO word (TAG_SENSOR = 02h, TAG_CNT and parity 0).
fn xl(x: i16, y: i16, z: i16) -> [u8; 7] {
    tagged(0x02 << 3, x, y, z)
}

/// A FIFO word with an arbitrary tag byte.
fn tagged(tag: u8, x: i16, y: i16, z: i16) -> [u8; 7] {
    let [xl, xh] = x.to_le_bytes();
    let [yl, yh] = y.to_le_bytes();
    let [zl, zh] = z.to_le_bytes();
    [tag, xl, xh, yl, yh, zl, zh]
}

/// The whole init sequence with `polls` reads of CTRL3_C before SW_RESET clears.
fn init_sequence(ctrl1_xl: u8, polls: usize) -> Vec<Transaction<u8>> {
    let mut t = Vec::new();
    t.extend(read(0x0F, vec![0x7B])); // WHO_AM_I
    t.extend(write(0x12, 0x05)); // CTRL3_C: SW_RESET | IF_INC
    for _ in 1..polls {
        t.extend(read(0x12, vec![0x05])); // still resetting
    }
    t.extend(read(0x12, vec![0x04])); // SW_RESET cleared
    t.extend(write(0x12, 0x44)); // CTRL3_C: BDU | IF_INC
    t.extend(write(0x09, 0x0A)); // FIFO_CTRL3: BDR_XL = 26.7 kHz
    t.extend(write(0x0A, 0x06)); // FIFO_CTRL4: continuous mode
    t.extend(write(0x10, ctrl1_xl)); // CTRL1_XL: XL on at 26.7 kHz, full scale
    t
}

fn cfg(full_scale: FullScale, axis: Axis) -> Config {
    Config { full_scale, axis }
}

/// A driver over a mock expecting `expected`.
fn driver(expected: &[Transaction<u8>], config: Config) -> Iis3dwb<Mock<u8>> {
    Iis3dwb::new(Mock::new(expected), config)
}

/// Checks that every expectation was consumed.
fn done(sensor: Iis3dwb<Mock<u8>>) {
    let mut spi = sensor.destroy();
    spi.done();
}

// --- init -----------------------------------------------------------------------------------

#[test]
fn init_sends_the_exact_sequence() {
    let mut s = driver(&init_sequence(0xA4, 1), cfg(FullScale::G16, Axis::Z));
    assert_eq!(s.init(&mut NoopDelay::new()), Ok(()));
    done(s);
}

#[test]
fn init_polls_until_the_reset_completes() {
    let mut s = driver(&init_sequence(0xA0, 3), cfg(FullScale::G2, Axis::X));
    assert_eq!(s.init(&mut NoopDelay::new()), Ok(()));
    done(s);
}

#[test]
fn init_sets_every_full_scale_code() {
    // CTRL1_XL = XL_EN 101b in bits 7:5 | FS[1:0] in bits 3:2 (00 2g, 01 16g, 10 4g, 11 8g).
    for (fs, ctrl1) in [
        (FullScale::G2, 0xA0),
        (FullScale::G4, 0xA8),
        (FullScale::G8, 0xAC),
        (FullScale::G16, 0xA4),
    ] {
        let mut s = driver(&init_sequence(ctrl1, 1), cfg(fs, Axis::Y));
        assert_eq!(s.init(&mut NoopDelay::new()), Ok(()), "{fs:?}");
        assert_eq!(s.config().full_scale, fs);
        done(s);
    }
}

#[test]
fn wrong_who_am_i_is_refused_before_any_write() {
    let mut s = driver(&read(0x0F, vec![0x6C]), cfg(FullScale::G16, Axis::Z));
    assert_eq!(s.init(&mut NoopDelay::new()), Err(Error::WrongDevice(0x6C)));
    done(s);
}

#[test]
fn a_reset_that_never_completes_times_out() {
    let mut t = read(0x0F, vec![0x7B]);
    t.extend(write(0x12, 0x05));
    for _ in 0..100 {
        t.extend(read(0x12, vec![0x05]));
    }
    let mut s = driver(&t, cfg(FullScale::G16, Axis::Z));
    assert_eq!(s.init(&mut NoopDelay::new()), Err(Error::ResetTimeout));
    done(s);
}

#[test]
fn who_am_i_reads_register_0f() {
    let mut s = driver(&read(0x0F, vec![0x7B]), cfg(FullScale::G2, Axis::X));
    assert_eq!(s.who_am_i(), Ok(0x7B));
    done(s);
}

#[test]
fn power_down_and_flush_write_the_documented_values() {
    let mut t = write(0x10, 0x00);
    t.extend(write(0x0A, 0x00));
    t.extend(write(0x0A, 0x00));
    t.extend(write(0x0A, 0x06));
    let mut s = driver(&t, cfg(FullScale::G2, Axis::X));
    assert_eq!(s.power_down(), Ok(()));
    assert_eq!(s.flush_fifo(), Ok(()));
    done(s);
}

// --- FIFO -----------------------------------------------------------------------------------

/// Five words: three accelerometer words (one with TAG_CNT and parity bits set), one
/// temperature word (tag 03h) and one timestamp word (tag 04h).
fn mixed_words() -> [[u8; 7]; 5] {
    [
        xl(0x1234, -2, i16::MIN),
        tagged(0x03 << 3, 111, 222, 333),
        xl(-1, i16::MAX, 0),
        tagged(0x04 << 3, 444, 555, 666),
        tagged((0x02 << 3) | 0b111, 7, -300, 25_000),
    ]
}

#[test]
fn fifo_words_give_the_configured_axis_and_skip_other_tags() {
    for (axis, want) in [
        (Axis::X, [0x1234, -1, 7]),
        (Axis::Y, [-2, i16::MAX, -300]),
        (Axis::Z, [i16::MIN, 0, 25_000]),
    ] {
        let mut t = status(5, 0x00);
        t.extend(fifo(&mixed_words()));
        let mut s = driver(&t, cfg(FullScale::G16, axis));
        let mut out = [0i16; 8];
        let got = s.read_samples(&mut out).unwrap();
        assert_eq!(
            got,
            Samples {
                written: 3,
                gap: Gap::None
            },
            "{axis:?}"
        );
        assert_eq!(out[..3], want, "{axis:?}");
        assert_eq!(out[3..], [0; 5], "{axis:?}: nothing written past `written`");
        done(s);
    }
}

#[test]
fn an_empty_fifo_costs_one_status_read() {
    let mut s = driver(&status(0, 0x00), cfg(FullScale::G16, Axis::Z));
    let mut out = [0i16; 4];
    let got = s.read_samples(&mut out).unwrap();
    assert_eq!(
        got,
        Samples {
            written: 0,
            gap: Gap::None
        }
    );
    done(s);
}

#[test]
fn reads_are_capped_by_the_buffer_and_split_into_bursts() {
    // 40 words waiting, room for 20: bursts of BURST_WORDS (16) then 4; 20 stay in the FIFO.
    assert_eq!(BURST_WORDS, 16);
    let words: Vec<[u8; 7]> = (0..20).map(|i| xl(0, 0, 100 * i - 1000)).collect();
    let mut t = status(40, 0x00);
    t.extend(fifo(&words[..16]));
    t.extend(fifo(&words[16..]));
    let mut s = driver(&t, cfg(FullScale::G8, Axis::Z));
    let mut out = [0i16; 20];
    let got = s.read_samples(&mut out).unwrap();
    assert_eq!(got.written, 20);
    let want: Vec<i16> = (0..20).map(|i| 100 * i - 1000).collect();
    assert_eq!(out[..], want[..]);
    done(s);
}

#[test]
fn the_ten_bit_level_uses_diff_fifo_high_bits() {
    // FIFO_STATUS2 = 0x01 → DIFF_FIFO = 0x100 + 0x02 = 258 words; 2 slots → 2 words read.
    let mut t = status(0x02, 0x01);
    t.extend(fifo(&[xl(5, 0, 0), xl(6, 0, 0)]));
    let mut s = driver(&t, cfg(FullScale::G4, Axis::X));
    let mut out = [0i16; 2];
    let got = s.read_samples(&mut out).unwrap();
    assert_eq!(
        got,
        Samples {
            written: 2,
            gap: Gap::None
        }
    );
    assert_eq!(out, [5, 6]);
    done(s);
}

#[test]
fn overrun_is_reported_as_lost_samples() {
    // FIFO_OVR_IA (bit 6) with a full FIFO (DIFF_FIFO = 512 = 0x200).
    let mut t = status(0x00, 0x40 | 0x02);
    t.extend(fifo(&[xl(0, 0, 42), xl(0, 0, 43), xl(0, 0, 44)]));
    let mut s = driver(&t, cfg(FullScale::G16, Axis::Z));
    let mut out = [0i16; 3];
    let got = s.read_samples(&mut out).unwrap();
    assert_eq!(got.written, 3);
    assert_eq!(got.gap, Gap::AtLeast(1));
    assert!(got.gap.is_gap());
    assert_eq!(got.lost(), 1);
    assert_eq!(out, [42, 43, 44]);
    done(s);
}

#[test]
fn latched_overrun_is_reported_even_with_nothing_to_read() {
    // FIFO_OVR_LATCHED (bit 3) alone, FIFO empty: a gap, no data transaction.
    let mut t = status(0, 0x08);
    // An empty buffer still consumes and reports the flag.
    t.extend(status(3, 0x40));
    let mut s = driver(&t, cfg(FullScale::G16, Axis::Z));
    let got = s.read_samples(&mut [0i16; 4]).unwrap();
    assert_eq!(
        got,
        Samples {
            written: 0,
            gap: Gap::AtLeast(1)
        }
    );
    let got = s.read_samples(&mut []).unwrap();
    assert_eq!(
        got,
        Samples {
            written: 0,
            gap: Gap::AtLeast(1)
        }
    );
    done(s);
}

#[test]
fn fifo_status_decodes_every_flag() {
    let mut s = driver(&status(0xFF, 0xFB), cfg(FullScale::G2, Axis::X));
    let st = s.fifo_status().unwrap();
    assert_eq!(
        st,
        FifoStatus {
            level: 1023,
            overrun: true,
            full: true,
            watermark: true
        }
    );
    done(s);
    assert_eq!(
        FifoStatus::from_registers(0x10, 0x00),
        FifoStatus {
            level: 16,
            overrun: false,
            full: false,
            watermark: false
        }
    );
    assert!(FifoStatus::from_registers(0, 0x08).overrun);
    assert!(FifoStatus::from_registers(0, 0x40).overrun);
    assert!(FifoStatus::from_registers(0, 0x20).full);
    assert!(FifoStatus::from_registers(0, 0x80).watermark);
}

// --- bus errors -----------------------------------------------------------------------------

/// An SPI device whose every transaction fails.
struct BrokenBus;

impl ErrorType for BrokenBus {
    type Error = ErrorKind;
}

impl SpiDevice for BrokenBus {
    fn transaction(&mut self, _: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        Err(ErrorKind::ModeFault)
    }
}

/// Passes `ok` transactions to a mock, then fails.
struct FailAfter {
    inner: Mock<u8>,
    ok: usize,
}

impl ErrorType for FailAfter {
    type Error = ErrorKind;
}

impl SpiDevice for FailAfter {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        if self.ok == 0 {
            return Err(ErrorKind::Overrun);
        }
        self.ok -= 1;
        self.inner.transaction(ops)
    }
}

#[test]
fn a_bus_error_propagates_as_comm() {
    let mut s = Iis3dwb::new(BrokenBus, cfg(FullScale::G16, Axis::Z));
    assert_eq!(
        s.init(&mut NoopDelay::new()),
        Err(Error::Comm(ErrorKind::ModeFault))
    );
    assert_eq!(
        s.read_samples(&mut [0; 4]),
        Err(Error::Comm(ErrorKind::ModeFault))
    );
    assert_eq!(s.fifo_status(), Err(Error::Comm(ErrorKind::ModeFault)));
    assert_eq!(s.power_down(), Err(Error::Comm(ErrorKind::ModeFault)));
}

#[test]
fn a_bus_error_in_the_middle_of_a_drain_propagates() {
    // The status read succeeds, the FIFO burst fails.
    let mock = Mock::new(&status(4, 0x00));
    let mut s = Iis3dwb::new(
        FailAfter { inner: mock, ok: 1 },
        cfg(FullScale::G16, Axis::Z),
    );
    assert_eq!(
        s.read_samples(&mut [0; 4]),
        Err(Error::Comm(ErrorKind::Overrun))
    );
    s.destroy().inner.done();
}

#[test]
fn a_bus_error_during_the_reset_poll_propagates() {
    let mut t = read(0x0F, vec![0x7B]);
    t.extend(write(0x12, 0x05));
    let mock = Mock::new(&t);
    let mut s = Iis3dwb::new(
        FailAfter { inner: mock, ok: 2 },
        cfg(FullScale::G2, Axis::X),
    );
    assert_eq!(
        s.init(&mut NoopDelay::new()),
        Err(Error::Comm(ErrorKind::Overrun))
    );
    s.destroy().inner.done();
}

// --- helpers and the seam -------------------------------------------------------------------

#[test]
fn full_scale_sensitivities_and_counts() {
    let table = [
        (FullScale::G2, 2, 61, 0b00),
        (FullScale::G4, 4, 122, 0b10),
        (FullScale::G8, 8, 244, 0b11),
        (FullScale::G16, 16, 488, 0b01),
    ];
    for (fs, g, ug, bits) in table {
        assert_eq!(fs.g(), g);
        assert_eq!(fs.sensitivity_ug_per_lsb(), ug);
        assert_eq!(fs.fs_bits(), bits);
        // counts/(m/s^2) = 1 / (sensitivity in g/LSB * 9.80665 m/s^2 per g)
        let want = 1.0 / (ug as f64 * 1e-6 * 9.806_65);
        let got = fs.counts_per_m_s2() as f64;
        assert!((got / want - 1.0).abs() < 1e-6, "{fs:?}: {got} vs {want}");
        // Full scale is reached near the top of the 16-bit code range.
        let codes_at_full_scale = g as f64 * 9.806_65 * got;
        assert!(
            (30_000.0..=33_000.0).contains(&codes_at_full_scale),
            "{fs:?}"
        );
    }
    assert!((FullScale::G2.counts_per_m_s2() - 1671.6).abs() < 0.1);
    assert_eq!(SAMPLE_RATE_HZ, 26_667.0);
    assert_eq!(SAMPLE_BITS, 16);
    assert_eq!(FIFO_WORDS, 512);
}

#[test]
fn gap_counts() {
    assert_eq!(Gap::None.lost(), 0);
    assert!(!Gap::None.is_gap());
    assert_eq!(Gap::Exactly(7).lost(), 7);
    assert!(Gap::Exactly(7).is_gap());
    assert!(!Gap::Exactly(0).is_gap());
    assert_eq!(Gap::AtLeast(1).lost(), 1);
    let s = Samples {
        written: 3,
        gap: Gap::Exactly(9),
    };
    assert_eq!(s.lost(), 9);
}

/// A replay source: the seam is usable for any source, not only the driver.
struct Replay<'a> {
    data: &'a [i16],
    lose_before: Option<(usize, u32)>,
}

impl SampleSource for Replay<'_> {
    type Error = core::convert::Infallible;

    fn read_samples(&mut self, out: &mut [i16]) -> Result<Samples, Self::Error> {
        let n = out.len().min(self.data.len());
        let (head, tail) = self.data.split_at(n);
        out[..n].copy_from_slice(head);
        self.data = tail;
        let gap = match self.lose_before.take() {
            Some((0, lost)) => Gap::Exactly(lost),
            Some((k, lost)) => {
                self.lose_before = Some((k - 1, lost));
                Gap::None
            }
            None => Gap::None,
        };
        Ok(Samples { written: n, gap })
    }
}

/// Drains a source generically, recording (samples, gaps) as a firmware loop would.
fn drain<S: SampleSource>(mut src: S, chunk: usize) -> (Vec<i16>, Vec<u32>)
where
    S::Error: core::fmt::Debug,
{
    let mut samples = Vec::new();
    let mut gaps = Vec::new();
    let mut buf = vec![0i16; chunk];
    loop {
        let got = src.read_samples(&mut buf).unwrap();
        if got.gap.is_gap() {
            gaps.push(got.lost());
        }
        if got.written == 0 {
            return (samples, gaps);
        }
        samples.extend_from_slice(&buf[..got.written]);
    }
}

#[test]
fn the_seam_works_through_a_mutable_reference() {
    let data: Vec<i16> = (0..10).collect();
    let mut src = Replay {
        data: &data,
        lose_before: Some((1, 5)),
    };
    let (samples, gaps) = drain(&mut src, 4);
    assert_eq!(samples, data);
    assert_eq!(gaps, vec![5]);
}

#[test]
fn errors_display() {
    let e: Error<ErrorKind> = Error::WrongDevice(0x6C);
    assert_eq!(e.to_string(), "WHO_AM_I is 0x6c, expected 0x7b");
    assert_eq!(
        Error::<ErrorKind>::ResetTimeout.to_string(),
        "software reset did not complete"
    );
    assert!(
        Error::Comm(ErrorKind::Other)
            .to_string()
            .starts_with("bus error")
    );
}

#[test]
fn bus_errors_convert_into_comm() {
    let e: Error<ErrorKind> = ErrorKind::Overrun.into();
    assert_eq!(e, Error::Comm(ErrorKind::Overrun));
    assert_eq!(
        Error::<ErrorKind>::InvalidWatermark(512).to_string(),
        "FIFO watermark 512 above the FIFO's 512 words"
    );
}

// --- watermark and INT1 -----------------------------------------------------------------------

#[test]
fn watermark_writes_fifo_ctrl1_then_wtm8() {
    // FIFO_CTRL1 (07h) = WTM[7:0]; FIFO_CTRL2 (08h) bit 0 = WTM8, STOP_ON_WTM (bit 7) clear.
    let mut t = write(0x07, 0x80);
    t.extend(write(0x08, 0x00));
    t.extend(write(0x07, 0x2C));
    t.extend(write(0x08, 0x01));
    t.extend(write(0x07, 0xFF));
    t.extend(write(0x08, 0x01));
    let mut s = driver(&t, cfg(FullScale::G16, Axis::Z));
    assert_eq!(s.set_fifo_watermark(128), Ok(()));
    assert_eq!(s.set_fifo_watermark(300), Ok(()));
    assert_eq!(s.set_fifo_watermark(511), Ok(()));
    done(s);
}

#[test]
fn a_watermark_beyond_the_fifo_is_refused_before_any_write() {
    let mut s = driver(&[], cfg(FullScale::G16, Axis::Z));
    assert_eq!(s.set_fifo_watermark(512), Err(Error::InvalidWatermark(512)));
    assert_eq!(
        s.set_fifo_watermark(u16::MAX),
        Err(Error::InvalidWatermark(u16::MAX))
    );
    done(s);
}

#[test]
fn int1_routing_writes_int1_ctrl() {
    // INT1_CTRL (0Dh): INT1_FIFO_TH is bit 3.
    let mut t = write(0x0D, 0x08);
    t.extend(write(0x0D, 0x00));
    let mut s = driver(&t, cfg(FullScale::G16, Axis::Z));
    assert_eq!(s.route_fifo_watermark_to_int1(true), Ok(()));
    assert_eq!(s.route_fifo_watermark_to_int1(false), Ok(()));
    done(s);
}
