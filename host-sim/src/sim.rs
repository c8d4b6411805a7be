//! Layer 3, sim: what the node's accelerometer would record — the sensor chain, labelled
//! sample streams, their generation, faults and files. Imports physics and scene.

pub mod band_fit;
pub mod faults;
pub mod generate;
pub mod identify;
pub mod identify_tolerance;
pub mod par;
pub mod pulse_response;
pub mod sensor;
pub mod stream;
pub mod stream_file;
