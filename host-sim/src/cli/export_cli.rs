//! `host-sim export`: its flags (the scene file and the output), handed to
//! [`crate::report::export::run`].

use std::path::PathBuf;

use clap::Args;

/// Flags of `host-sim export`.
#[derive(Debug, Clone, Args)]
pub struct ExportArgs {
    /// Scene file (TOML).
    #[arg(long)]
    pub scene: PathBuf,
    /// Output Rust file (default: standard output).
    #[arg(long)]
    pub out: Option<PathBuf>,
}
