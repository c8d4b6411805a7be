//! Layer 3, sim: what the node's accelerometer would record — the sensor chain, labelled
//! sample streams and their files. Imports physics and scene.

pub mod identify;
pub mod par;
pub mod sensor;
pub mod stream;
