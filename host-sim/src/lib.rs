//! Host-side (std, `f64`) companion of the coalshock kernel: an independent Hertz impact
//! model and contact integrator used to generate and check pulses.
//!
//! # Layers
//!
//! Each layer imports only the layers listed before it (`tests/layers.rs` checks it):
//!
//! 1. [`physics`]: Hertz's closed forms, the contact laws and the contact integrator;
//! 2. [`scene`]: the TOML scene file;
//! 3. [`sim`]: the sensor chain, labelled streams and their files;
//! 4. [`bridge`]: the contact calibration and the conversion to the kernel's f32 scene;
//! 5. [`score`]: the kernel scored on simulated impacts against its limits;
//! 6. [`report`]: tables, CSV files and plots;
//! 7. [`cli`]: the command-line flags, the only layer that knows clap (the binary, `main.rs`,
//!    holds those of `stream` and `identify`).
//!
//! Every module is also reachable at the crate's root (`host_sim::hertz64`), as before the
//! layers were drawn.

pub mod bridge;
pub mod cli;
pub mod physics;
pub mod report;
pub mod scene;
pub mod score;
pub mod sim;

pub use bridge::{
    calibrate, convert, equalised_fit, kernel_scene, pulse_shape, ratio_table, sampled_fit,
    sampled_phase, skew_tolerance, skewness,
};
pub use cli::{
    caving_cli, evaluate_cli, export_cli, impact_cli, paper_cli, plasticity_cli, speed_cli,
    tradeoff_cli,
};
pub use physics::{
    hertz64, impact, integrate, integrator_cases, law_spec, laws, sim_error, thornton,
};
pub use report::{export, impact_row, paper, plasticity, speed, tradeoff};
pub use score::{
    bayes, caving, counts, crb, cusum, evaluate, mismatch, noise_check, reference, reliability,
    replay, saturation, study_error, yield_bayes,
};
pub use sim::{generate, identify, par, sensor, stream, stream_file};
