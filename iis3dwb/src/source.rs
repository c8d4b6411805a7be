//! The seam between any accelerometer (or ADC, replay file, simulator) and a streaming
//! detector: [`SampleSource`] fills a buffer and says whether samples were lost before it.

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

/// A source of raw samples of one axis.
///
/// Samples are raw two's-complement sensor codes (counts); the scale is the consumer's (for
/// the IIS3DWB see [`FullScale::counts_per_m_s2`](crate::FullScale::counts_per_m_s2)).
///
/// An implementation is non-blocking in spirit: it returns what is available now, possibly
/// nothing, and never waits for more.
pub trait SampleSource {
    /// The error of the underlying bus or device.
    type Error;

    /// Fills up to `out.len()` samples, oldest first, and reports how many were written and
    /// whether samples were lost since the last call (for example a FIFO overrun), so that the
    /// caller can tell its detector about the gap before feeding `out[..written]`.
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
