//! Layer 7, cli: the command lines of host-sim, whose flags (and, for `impact`, batch files)
//! are parsed here into the plain options of the layers below; the only layer that knows clap.

pub mod caving_cli;
pub mod evaluate_cli;
pub mod export_cli;
pub mod impact_cli;
pub mod paper_cli;
pub mod plasticity_cli;
pub mod speed_cli;
pub mod tradeoff_cli;
pub mod value_enums;
