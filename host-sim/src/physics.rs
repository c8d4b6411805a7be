//! Layer 1, physics: the contact of a sphere on a plate in f64 — Hertz's closed forms, the
//! contact laws, and the integrator that runs them. Imports no other layer.

pub(crate) mod events;
pub mod hertz64;
pub mod impact;
pub mod integrate;
pub mod integrator_cases;
pub mod law_spec;
pub mod laws;
pub mod sim_error;
pub mod thornton;
