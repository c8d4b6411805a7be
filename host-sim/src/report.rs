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

/// Writes `text` to standard output and flushes it, the error naming it; a reader that closed
/// the pipe gives an [`std::io::ErrorKind::BrokenPipe`] in the chain, which the binary takes
/// for the end of the command.
pub fn write_stdout(text: &str) -> anyhow::Result<()> {
    use anyhow::Context;
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .context("writing to standard output")
}

/// Writes `value` to standard output as pretty-printed JSON and a newline ([`write_stdout`]).
pub fn write_json<T: serde::Serialize>(value: &T) -> anyhow::Result<()> {
    write_stdout(&format!("{}\n", serde_json::to_string_pretty(value)?))
}
