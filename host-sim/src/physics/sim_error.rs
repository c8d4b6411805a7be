//! The one error type of the contact simulation: what a parameter or an integration can be
//! wrong with.

/// Errors of the contact simulation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// A parameter is out of its range.
    #[error("invalid parameter {name} = {value}: must be {requirement}")]
    InvalidParameter {
        /// The parameter's name.
        name: String,
        /// The value given.
        value: f64,
        /// What it must satisfy.
        requirement: &'static str,
    },
    /// The step limit was reached before the contact ended.
    #[error("step limit of {max_steps} reached at t = {t_s} s before the contact ended")]
    MaxSteps {
        /// The limit (`Limits::max_steps` of the integrator).
        max_steps: usize,
        /// Time reached in s.
        t_s: f64,
    },
    /// The adaptive step size fell below the floating-point resolution of the time.
    #[error("step size underflow (h = {h_s} s) at t = {t_s} s")]
    StepSizeUnderflow {
        /// Time reached in s.
        t_s: f64,
        /// The step size in s.
        h_s: f64,
    },
    /// The state became NaN or infinite (an explicit method beyond its stability limit).
    #[error("non-finite state at t = {t_s} s (explicit method unstable for this damping?)")]
    NonFinite {
        /// Time reached in s.
        t_s: f64,
    },
    /// The contact had not ended at the time limit: the sphere came to rest on the plate
    /// (damping with gravity) or creeps out too slowly (heavy damping).
    #[error("contact not ended at the time limit t = {t_s} s")]
    NoSeparation {
        /// Time reached in s.
        t_s: f64,
    },
    /// No damping coefficient could be found for the target restitution.
    #[error("could not bracket c_max for restitution {target} (reached {reached})")]
    RestitutionNotBracketed {
        /// Target coefficient of restitution.
        target: f64,
        /// Restitution at the last damping tried.
        reached: f64,
    },
}
