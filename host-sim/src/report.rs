//! Layer 6, report: tables, CSV files and plots made from the layers below — the paper's
//! reproduction, the trade-off study, plasticity, speed, impact rows and the scene export.

pub mod best_rate;
pub mod equal_accuracy;
pub mod export;
pub mod impact_row;
pub mod ode_solvers_ref;
pub mod paper;
pub mod plasticity;
pub mod speed;
pub mod tradeoff;
