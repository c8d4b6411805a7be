//! Layer 7, cli: the command lines of `host-sim impact` and `host-sim caving`, whose flags and
//! batch files are parsed here and handed to the layers below.

pub mod caving_cli;
pub mod impact_cli;
