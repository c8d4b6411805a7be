//! Layer 4, bridge: a host scene made into the kernel's f32 scene — the contact calibration
//! and ratio tables (f64 integrator runs), the pure conversion to f32, and the kernel scene
//! that composes them. Imports physics, scene and sim (the chain a damped
//! contact's sampling correction is calibrated through).

pub mod calibrate;
pub mod convert;
pub mod equalised_fit;
pub mod kernel_scene;
pub mod pulse_shape;
pub mod ratio_table;
pub mod sampled_fit;
pub mod sampled_phase;
pub mod skew_tolerance;
pub mod skewness;
