//! Layer 4, bridge: a host scene made into the kernel's f32 scene — the contact calibration
//! and the conversion. Imports physics and scene.

pub mod calibrate;
pub mod convert;
pub mod ratio_table;
