#![doc = include_str!("../README.md")]
#![no_std]
// `f32::clamp` asserts `min <= max` and so brings a panic path into the firmware image; the
// kernel writes `.max(lo).min(hi)` instead.
#![allow(clippy::manual_clamp)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

pub mod chain_bias;
pub mod chain_residual;
pub mod classifier;
mod complex;
pub mod counters;
pub mod detector;
pub mod envelope;
pub mod equaliser;
pub mod error;
pub mod flow;
pub mod hertz;
pub mod material;
pub mod math;
pub mod monitor;
#[cfg(feature = "noise_colour")]
pub mod noise_colour;
#[cfg(feature = "pulse_shape")]
pub mod pulse_shape;
pub mod pulse_window;
pub mod ratio_map;
pub mod sampled;
pub mod sampled_phase;
pub mod scene;
#[cfg(feature = "serde")]
pub mod settings_serde;
pub mod settle;
#[cfg(all(feature = "settle", feature = "pulse_shape"))]
pub mod settle_clip;
pub mod shape_fit;
#[cfg(feature = "pulse_shape")]
pub mod short_pulse;
pub mod thornton;

pub use chain_bias::ChainBias;
pub use classifier::{Measurement, RejectReason, TRIGGER_MARGIN, Verdict};
pub use counters::Counters;
pub use detector::{Detection, Detector};
pub use envelope::{Envelope, Range, Side};
pub use equaliser::{
    Accelerometer, BeamMode, ChainDynamics, ChainTolerance, Equaliser, EqualiserDesign,
};
pub use error::Error;
pub use flow::{FlowConfig, FlowMonitor, FlowSlot, FlowStatus, NoFlow};
pub use material::Material;
pub use monitor::{Event, Monitor, Report};
#[cfg(feature = "pulse_shape")]
pub use scene::PulseShape;
pub use scene::{
    ContactCalibration, ParticleClass, SampledCalibration, SampledPhase, Scene, SensorChain,
    Settings, Speed,
};
