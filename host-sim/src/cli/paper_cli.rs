//! `host-sim paper`: its flags, and the paper configuration they give.

use std::path::PathBuf;

use clap::Args;

use crate::report::paper::PaperConfig;

/// Flags of `host-sim paper`.
#[derive(Debug, Clone, PartialEq, Args)]
pub struct PaperArgs {
    /// Directory for the CSV series and SVG figures (created if missing).
    #[arg(long, default_value = "out/paper")]
    pub out: PathBuf,
    /// Coefficient of restitution in (0, 1) the damped (Adams IMPACT) contact is calibrated
    /// to at the reference speed 1 m/s, per material and radius.
    #[arg(long, default_value_t = PaperConfig::default().restitution)]
    pub restitution: f64,
    /// Adams IMPACT penetration `d` in m over which the damping ramps up to `c_max`.
    #[arg(long, default_value_t = PaperConfig::default().depth_m)]
    pub depth: f64,
}

impl PaperArgs {
    /// The default grids with the restitution and depth of these flags.
    pub fn config(&self) -> PaperConfig {
        PaperConfig {
            restitution: self.restitution,
            depth_m: self.depth,
            ..PaperConfig::default()
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
        args: PaperArgs,
    }

    #[test]
    fn no_flags_give_the_default_config() {
        let cli = Cli::try_parse_from(["paper"]).expect("defaults parse");
        assert_eq!(cli.args.config(), PaperConfig::default());
        assert_eq!(cli.args.out, PathBuf::from("out/paper"));
        let cli = Cli::try_parse_from(["paper", "--restitution", "0.3", "--depth", "2e-5"])
            .expect("parses");
        let c = cli.args.config();
        assert_eq!((c.restitution, c.depth_m), (0.3, 2e-5));
    }
}
