//! `host-sim plasticity`: its flags, and the plasticity options they give.

use std::path::PathBuf;

use clap::Args;

use crate::report::plasticity::PlasticityOptions;

/// Flags of `host-sim plasticity`.
#[derive(Debug, Clone, PartialEq, Args)]
pub struct PlasticityArgs {
    /// Scene file; its classes that state `yield_pressure_pa` are drawn.
    #[arg(long, default_value_os_t = PlasticityOptions::default().scene)]
    pub scene: PathBuf,
    /// Directory for the CSV series and SVG figures (created if missing).
    #[arg(long, default_value_os_t = PlasticityOptions::default().out)]
    pub out: PathBuf,
    /// Sphere radius in m (default: each class's geometric centre).
    #[arg(long)]
    pub radius: Option<f64>,
    /// Speeds per class, evenly spaced over its speed range (at least 2).
    #[arg(long, default_value_t = PlasticityOptions::default().points)]
    pub points: usize,
    /// Draws per class of the noiseless Bayes limit, yielding and elastic (0: skip it; needs
    /// an undamped scene).
    #[arg(long, default_value_t = PlasticityOptions::default().bayes_draws)]
    pub bayes_draws: usize,
    /// Seed of the Bayes limit's draws.
    #[arg(long, default_value_t = PlasticityOptions::default().seed)]
    pub seed: u64,
}

impl PlasticityArgs {
    /// The options these flags give.
    pub fn options(&self) -> PlasticityOptions {
        PlasticityOptions {
            scene: self.scene.clone(),
            out: self.out.clone(),
            radius_m: self.radius,
            points: self.points,
            bayes_draws: self.bayes_draws,
            seed: self.seed,
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
        args: PlasticityArgs,
    }

    #[test]
    fn no_flags_give_the_default_options() {
        let cli = Cli::try_parse_from(["plasticity"]).expect("defaults parse");
        assert_eq!(cli.args.options(), PlasticityOptions::default());
        let cli = Cli::try_parse_from(["plasticity", "--radius", "0.02", "--points", "5"])
            .expect("parses");
        let o = cli.args.options();
        assert_eq!((o.radius_m, o.points), (Some(0.02), 5));
    }
}
