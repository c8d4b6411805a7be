//! `host-sim tradeoff`: its flags, and the trade-off options they give.

use std::path::PathBuf;

use clap::Args;

use crate::report::tradeoff::TradeoffOptions;

/// Flags of `host-sim tradeoff`.
#[derive(Debug, Clone, PartialEq, Args)]
pub struct TradeoffArgs {
    /// Directory for the table, the CSV files and the SVG plots (created if missing).
    #[arg(long, default_value_os_t = TradeoffOptions::default().out)]
    pub out: PathBuf,
    /// A small, fast run (for tests): fewer impacts, grid sizes, tolerances and sample rates.
    #[arg(long)]
    pub quick: bool,
    /// Seed of every random draw (streams, Monte Carlo).
    #[arg(long, default_value_t = TradeoffOptions::default().seed)]
    pub seed: u64,
    /// The firmware check's `measures.txt` (`fw/measure.sh`, run by `bash fw/ci.sh`). Default:
    /// `$FW_OUT/measures.txt`, else `fw/measures.txt` under the cargo target directory
    /// (`$CARGO_TARGET_DIR`, the one this binary was built in, or `target/`); the command fails
    /// when there is none.
    #[arg(long)]
    pub fw_measures: Option<PathBuf>,
}

impl TradeoffArgs {
    /// The options these flags give.
    pub fn options(&self) -> TradeoffOptions {
        TradeoffOptions {
            out: self.out.clone(),
            quick: self.quick,
            seed: self.seed,
            fw_measures: self.fw_measures.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: TradeoffArgs,
    }

    #[test]
    fn no_flags_give_the_default_options() {
        let cli = Cli::try_parse_from(["tradeoff"]).expect("defaults parse");
        assert_eq!(cli.args.options(), TradeoffOptions::default());
        let cli = Cli::try_parse_from(["tradeoff", "--quick", "--seed", "3", "--out", "d"])
            .expect("parses");
        let o = cli.args.options();
        assert!(o.quick);
        assert_eq!((o.seed, o.out), (3, PathBuf::from("d")));
    }
}
