//! Register map of the IIS3DWB (datasheet DS13114; the same map as ST's reference C driver):
//! the registers the driver uses, as typed addresses, and their bit fields.

/// SPI frame: bit 7 of the first byte set to read, clear to write.
pub const SPI_READ: u8 = 0x80;

/// The registers the driver accesses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[allow(non_camel_case_types)]
#[repr(u8)]
pub enum Register {
    /// FIFO_CTRL1 (07h): `WTM[7:0]`, the FIFO watermark (low 8 bits of 9).
    FIFO_CTRL1 = 0x07,
    /// FIFO_CTRL2 (08h): `WTM8` (bit 0), the watermark's ninth bit; STOP_ON_WTM (bit 7).
    FIFO_CTRL2 = 0x08,
    /// FIFO_CTRL3 (09h): `BDR_XL[3:0]` (bits 3:0), the rate at which the accelerometer is
    /// batched into the FIFO; bits 7:4 unused (0).
    FIFO_CTRL3 = 0x09,
    /// FIFO_CTRL4 (0Ah): `FIFO_MODE[2:0]` (bits 2:0); `ODR_T_BATCH[1:0]` (bits 5:4) and
    /// `DEC_TS_BATCH[1:0]` (bits 7:6), temperature and timestamp batching (00 = off).
    FIFO_CTRL4 = 0x0A,
    /// INT1_CTRL (0Dh): what the INT1 pin signals (INT1_FIFO_TH in bit 3, ...).
    INT1_CTRL = 0x0D,
    /// WHO_AM_I (0Fh): device identification, read-only, [`WHO_AM_I_VALUE`].
    WHO_AM_I = 0x0F,
    /// CTRL1_XL (10h): `XL_EN[2:0]` (bits 7:5), accelerometer on/off; `FS[1:0]` (bits 3:2),
    /// full scale; LPF2_XL_EN (bit 1), second low-pass stage; bits 4 and 0 unused (0).
    CTRL1_XL = 0x10,
    /// CTRL3_C (12h): BOOT (7), BDU (6), H_LACTIVE (5), PP_OD (4), SIM (3), IF_INC (2), bit 1
    /// must be 0, SW_RESET (0). Reset value 04h (IF_INC set).
    CTRL3_C = 0x12,
    /// FIFO_STATUS1 (3Ah): `DIFF_FIFO[7:0]`, unread FIFO words. Read together with
    /// FIFO_STATUS2 (3Bh) in one auto-incremented access.
    FIFO_STATUS1 = 0x3A,
    /// FIFO_DATA_OUT_TAG (78h): `TAG_SENSOR[4:0]` (bits 7:3), `TAG_CNT[1:0]` (bits 2:1),
    /// TAG_PARITY (bit 0), followed by X, Y, Z (79h..7Eh, little-endian). With IF_INC set the
    /// address rolls back from 7Eh to 78h, so one burst read returns consecutive words.
    FIFO_DATA_OUT_TAG = 0x78,
}

impl Register {
    /// The register's address.
    pub const fn addr(self) -> u8 {
        self as u8
    }
}

/// WHO_AM_I value of the IIS3DWB.
pub const WHO_AM_I_VALUE: u8 = 0x7B;

/// Bits of FIFO_CTRL2.
pub mod fifo_ctrl2 {
    /// WTM8 (bit 0): bit 8 of the watermark.
    pub const WTM8: u8 = 1 << 0;
}

/// Bits of FIFO_CTRL3.
pub mod fifo_ctrl3 {
    /// BDR_XL = 1010b: accelerometer batched in the FIFO at 26 667 Hz (0000b: not batched).
    pub const BDR_XL_26K7: u8 = 0b1010;
}

/// Values of FIFO_CTRL4.
pub mod fifo_ctrl4 {
    /// FIFO_MODE = 000b: bypass (FIFO disabled and emptied).
    pub const MODE_BYPASS: u8 = 0b000;
    /// FIFO_MODE = 110b: continuous (stream) mode, the oldest word is overwritten when full;
    /// temperature and timestamp not batched.
    pub const MODE_CONTINUOUS: u8 = 0b110;
}

/// Bits of INT1_CTRL.
pub mod int1_ctrl {
    /// INT1_FIFO_TH (bit 3): the FIFO watermark on INT1.
    pub const FIFO_TH: u8 = 1 << 3;
}

/// Bits of CTRL1_XL.
pub mod ctrl1_xl {
    /// XL_EN = 101b in bits 7:5: accelerometer on at 26 667 Hz.
    pub const XL_EN_26K7: u8 = 0b101 << 5;
    /// XL_EN = 000b: accelerometer power-down.
    pub const POWER_DOWN: u8 = 0;
    /// Shift of `FS[1:0]`.
    pub const FS_SHIFT: u8 = 2;
}

/// Bits of CTRL3_C.
pub mod ctrl3_c {
    /// SW_RESET (bit 0): software reset of the control registers; cleared by the device when
    /// done.
    pub const SW_RESET: u8 = 1 << 0;
    /// IF_INC (bit 2): register address auto-incremented on multi-byte access.
    pub const IF_INC: u8 = 1 << 2;
    /// BDU (bit 6): block data update.
    pub const BDU: u8 = 1 << 6;
}

/// Bits of FIFO_STATUS2 (3Bh).
pub mod fifo_status2 {
    /// Bits 1:0: `DIFF_FIFO[9:8]`.
    pub const DIFF_HI: u8 = 0b11;
    /// Bit 3: FIFO_OVR_LATCHED, an overrun happened since FIFO_STATUS2 was last read (cleared
    /// by reading it).
    pub const OVR_LATCHED: u8 = 1 << 3;
    /// Bit 5: FIFO_FULL_IA, the FIFO will be full at the next ODR.
    pub const FULL_IA: u8 = 1 << 5;
    /// Bit 6: FIFO_OVR_IA, the FIFO is full and at least one word was overwritten.
    pub const OVR_IA: u8 = 1 << 6;
    /// Bit 7: FIFO_WTM_IA, the FIFO level reached the watermark.
    pub const WTM_IA: u8 = 1 << 7;
}

/// TAG_SENSOR value (bits 7:3 of the tag byte) of an accelerometer word (03h: temperature,
/// 04h: timestamp).
pub const TAG_SENSOR_XL: u8 = 0x02;
