//! Host-side (std, `f64`) companion of the coalshock kernel: an independent Hertz impact
//! model and contact integrator used to generate and check pulses.

pub mod bayes;
pub mod hertz64;
pub mod impact;
pub mod integrate;
pub mod laws;
