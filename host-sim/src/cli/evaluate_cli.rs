//! `host-sim evaluate`: its flags, and the evaluation options they give.

use std::path::PathBuf;

use clap::Args;

use crate::score::evaluate::{BackendChoice, EvalOptions};
use crate::score::mismatch::ChainMismatch;
use crate::score::reference::ReferenceOptions;

/// Flags of `host-sim evaluate`.
#[derive(Debug, Clone, Args)]
pub struct EvaluateArgs {
    /// Scene file (TOML).
    #[arg(long)]
    pub scene: PathBuf,
    /// Impacts per class (1 to 10^7).
    #[arg(long, value_parser = crate::score::counts::impacts_per_class)]
    pub n: usize,
    /// Seed of every random draw.
    #[arg(long, default_value_t = EvalOptions::default().seed)]
    pub seed: u64,
    /// Print one JSON object instead of tables.
    #[arg(long)]
    pub json: bool,
    /// The kernel's math backend.
    #[arg(long, value_enum, default_value_t = BackendChoice::default())]
    pub backend: BackendChoice,
    /// Monte Carlo draws per class of the diagnostic Bayes limit at the kernel's noise (1 to
    /// 10^8).
    #[arg(long, default_value_t = EvalOptions::default().bayes_draws_per_class,
          value_parser = crate::score::counts::bayes_draws_per_class)]
    pub bayes_draws: usize,
    /// Monte Carlo draws per class of the reference limit.
    #[arg(long, default_value_t = ReferenceOptions::default().draws_per_class)]
    pub reference_draws: usize,
    /// The share of class verdicts allowed to be wrong, in (0, 0.5) (default: the scene
    /// file's `settings.confident_error_rate`, else 0.01).
    #[arg(long)]
    pub confident_error_rate: Option<f64>,
    /// Relative error of every chain frequency the kernel is given (0.02: 2 % high); the
    /// simulation keeps the scene's.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub chain_frequency_error: f64,
    /// Relative error of every chain damping ratio the kernel is given (-0.3: 30 % low).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub chain_damping_error: f64,
    /// Relative error of every beam mode gain the kernel is given (0.2: 20 % high).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub chain_gain_error: f64,
    /// Give each stream's kernel the chain as one node might have identified it: every
    /// stage's frequency, damping and gain off by errors drawn uniformly within the scene's
    /// chain tolerance (checks that the posteriors it widens are calibrated).
    #[arg(long)]
    pub chain_drawn: bool,
}

impl EvaluateArgs {
    /// The options these flags give.
    pub fn options(&self) -> EvalOptions {
        EvalOptions {
            n_per_class: self.n,
            seed: self.seed,
            bayes_draws_per_class: self.bayes_draws,
            chain_mismatch: ChainMismatch {
                frequency: self.chain_frequency_error,
                damping: self.chain_damping_error,
                gain: self.chain_gain_error,
            },
            reference: ReferenceOptions {
                draws_per_class: self.reference_draws,
                ..ReferenceOptions::default()
            },
            confident_error_rate: self.confident_error_rate,
            chain_drawn: self.chain_drawn,
            ..EvalOptions::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, Parser)]
    struct Cli {
        #[command(flatten)]
        args: EvaluateArgs,
    }

    #[test]
    fn flags_not_given_are_the_library_defaults() {
        let cli =
            Cli::try_parse_from(["evaluate", "--scene", "s.toml", "--n", "7"]).expect("parses");
        assert_eq!(cli.args.backend, BackendChoice::Default);
        assert!(!cli.args.json);
        let o = cli.args.options();
        assert_eq!(
            o,
            EvalOptions {
                n_per_class: 7,
                ..EvalOptions::default()
            }
        );
    }

    #[test]
    fn flags_map_onto_the_options() {
        let cli = Cli::try_parse_from([
            "evaluate",
            "--scene",
            "s.toml",
            "--n",
            "3",
            "--seed",
            "9",
            "--backend",
            "micromath",
            "--bayes-draws",
            "11",
            "--reference-draws",
            "13",
            "--confident-error-rate",
            "0.05",
            "--chain-damping-error",
            "-0.3",
        ])
        .expect("parses");
        assert_eq!(cli.args.backend, BackendChoice::Micromath);
        let o = cli.args.options();
        assert_eq!((o.n_per_class, o.seed), (3, 9));
        assert_eq!(o.bayes_draws_per_class, 11);
        assert_eq!(o.reference.draws_per_class, 13);
        assert_eq!(o.confident_error_rate, Some(0.05));
        assert_eq!(o.chain_mismatch.damping, -0.3);
        assert_eq!(o.chain_mismatch.frequency, 0.0);
        assert!(Cli::try_parse_from(["evaluate", "--scene", "s", "--n", "0"]).is_err());
    }
}
