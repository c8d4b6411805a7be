//! Host-side (std, `f64`) companion of the coalshock kernel: an independent Hertz impact
//! model and contact integrator used to generate and check pulses.

pub mod bayes;
pub mod calibrate;
pub mod caving;
pub mod caving_cli;
pub mod convert;
pub mod counts;
pub mod crb;
pub mod cusum;
pub mod evaluate;
mod events;
pub mod export;
pub mod hertz64;
pub mod identify;
pub mod impact;
pub mod impact_cli;
pub mod impact_row;
pub mod integrate;
pub mod integrator_cases;
pub mod law_spec;
pub mod laws;
pub mod mismatch;
pub mod paper;
pub mod par;
pub mod plasticity;
pub mod reference;
pub mod reliability;
pub mod saturation;
pub mod scene;
pub mod sensor;
pub mod sim_error;
pub mod speed;
pub mod stream;
pub mod thornton;
pub mod tradeoff;
pub mod yield_bayes;
