//! `host-sim speed`: its flags, and the speed options they give.

use std::path::PathBuf;

use clap::Args;

use crate::report::speed::SpeedOptions;

/// Flags of `host-sim speed`.
#[derive(Debug, Clone, PartialEq, Args)]
pub struct SpeedArgs {
    /// Impacts of the timed evaluation, split evenly over the scene's classes.
    #[arg(long, default_value_t = SpeedOptions::default().impacts)]
    pub impacts: usize,
    /// Scene of the timed evaluation (TOML; default: the built-in paper scene, equal to
    /// `scenes/paper.toml`).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Measuring time of the integrator per law and method in s.
    #[arg(long, default_value_t = SpeedOptions::default().integrator_seconds)]
    pub integrator_seconds: f64,
    /// Also time the evaluation on one thread (the parallel speed-up).
    #[arg(long)]
    pub one_thread: bool,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

impl SpeedArgs {
    /// The options these flags give.
    pub fn options(&self) -> SpeedOptions {
        SpeedOptions {
            impacts: self.impacts,
            scene: self.scene.clone(),
            integrator_seconds: self.integrator_seconds,
            one_thread: self.one_thread,
            json: self.json,
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
        args: SpeedArgs,
    }

    #[test]
    fn no_flags_give_the_default_options() {
        let cli = Cli::try_parse_from(["speed"]).expect("defaults parse");
        assert_eq!(cli.args.options(), SpeedOptions::default());
        let cli = Cli::try_parse_from(["speed", "--impacts", "10", "--one-thread", "--json"])
            .expect("parses");
        let o = cli.args.options();
        assert_eq!(o.impacts, 10);
        assert!(o.one_thread && o.json);
    }
}
