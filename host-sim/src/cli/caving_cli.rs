//! `host-sim caving`: the flags, the change taken from flags before the scene's `[caving]`
//! table before the defaults, a summary table or one JSON object, and the SVG plots.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use plotters::style::RGBColor;

use crate::report::paper::{Curve, Stroke, draw_svg};
use crate::score::caving::{CavingOptions, CavingReport, CavingSpec, Profile, load_scene, run};

/// Flags of `host-sim caving`.
#[derive(Debug, Clone, clap::Args)]
pub struct CavingArgs {
    /// Scene file (TOML), optionally with a `[caving]` table giving the change.
    #[arg(long, default_value = "scenes/paper.toml")]
    pub scene: PathBuf,
    /// Rounds simulated (1 to 10^5).
    #[arg(long, default_value_t = 100, value_parser = crate::score::counts::caving_rounds)]
    pub rounds: usize,
    /// Seed of every random draw.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Background gangue share before the change (default 0.05).
    #[arg(long)]
    pub pre_share: Option<f64>,
    /// Gangue share after the change (default 0.5).
    #[arg(long)]
    pub post_share: Option<f64>,
    /// Share to close at (default: the post-change share).
    #[arg(long)]
    pub level: Option<f64>,
    /// False alarms per impact of background flow (default 1e-5: one per 10^5 impacts).
    #[arg(long, allow_negative_numbers = true)]
    pub false_alarm_rate: Option<f64>,
    /// Step or ramp (default step).
    #[arg(long, value_enum)]
    pub profile: Option<Profile>,
    /// Impacts of a ramp (default 100; at most 10^6).
    #[arg(long, value_parser = crate::score::counts::round_impacts)]
    pub ramp_impacts: Option<usize>,
    /// Mean impacts per s, Poisson (default 20).
    #[arg(long, allow_negative_numbers = true)]
    pub rate: Option<f64>,
    /// Memory of the share estimate in impacts.
    #[arg(long, default_value_t = 100)]
    pub window: u32,
    /// Impacts before the change (at most 10^6).
    #[arg(long, default_value_t = 300, value_parser = crate::score::counts::round_impacts)]
    pub pre_impacts: usize,
    /// Impacts from the change to the end of a round (at most 10^6).
    #[arg(long, default_value_t = 600, value_parser = crate::score::counts::round_impacts)]
    pub post_impacts: usize,
    /// Pulses the naive rule looks back on (at most 10^4).
    #[arg(long, default_value_t = 20, value_parser = crate::score::counts::naive_pulses)]
    pub naive_n: usize,
    /// Background impacts behind each measured false-alarm rate (at most 10^9).
    #[arg(long, default_value_t = 1_000_000, value_parser = crate::score::counts::false_alarm_impacts)]
    pub false_alarm_impacts: usize,
    /// Name of the coal class (every other class is gangue).
    #[arg(long, default_value = "coal")]
    pub coal_class: String,
    /// Write caving_share.svg, caving_delay.svg and caving_curve.csv into this directory.
    #[arg(long)]
    pub plots: Option<PathBuf>,
}

impl CavingArgs {
    /// The options: each change setting from the flag, else the scene's `[caving]`, else the
    /// default; the level defaults to the post-change share.
    pub fn options(&self, spec: &CavingSpec) -> CavingOptions {
        let d = CavingOptions::default();
        let post_share = self.post_share.or(spec.post_share).unwrap_or(d.post_share);
        CavingOptions {
            rounds: self.rounds,
            seed: self.seed,
            pre_share: self.pre_share.or(spec.pre_share).unwrap_or(d.pre_share),
            post_share,
            level: self.level.or(spec.level).unwrap_or(post_share),
            false_alarm_rate: self
                .false_alarm_rate
                .or(spec.false_alarm_rate)
                .unwrap_or(d.false_alarm_rate),
            window_impacts: self.window,
            rate_hz: self.rate.or(spec.rate_hz).unwrap_or(d.rate_hz),
            profile: self.profile.or(spec.profile).unwrap_or(d.profile),
            ramp_impacts: self
                .ramp_impacts
                .or(spec.ramp_impacts)
                .unwrap_or(d.ramp_impacts),
            pre_impacts: self.pre_impacts,
            post_impacts: self.post_impacts,
            naive_n: self.naive_n,
            false_alarm_impacts: self.false_alarm_impacts,
            coal_class: self.coal_class.clone(),
        }
    }
}

/// `host-sim caving`.
pub fn run_cli(args: &CavingArgs) -> Result<()> {
    let (scene, spec) = load_scene(&args.scene)?;
    let opts = args.options(&spec);
    let report = run::<coalshock::math::DefaultBackend>(&scene, &opts)
        .with_context(|| format!("caving rounds of {}", args.scene.display()))?;
    if let Some(dir) = &args.plots {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        write_plots(&report, dir)?;
    }
    if args.json {
        crate::report::write_json(&report)
    } else {
        crate::report::write_stdout(&table(&report))
    }
}

/// The summary as text.
pub fn table(r: &CavingReport) -> String {
    let d = |x: &crate::score::caving::Delay| format!("median {:6.1}  p90 {:6.1}", x.median, x.p90);
    let m = |x: &crate::score::caving::Mining| {
        format!(
            "recovery {:.4}  gangue {:.4}",
            x.recovery_rate, x.gangue_content
        )
    };
    let kernel = crate::score::caving::Mining {
        recovery_rate: r.recovery_rate,
        gangue_content: r.gangue_content,
    };
    let f = &r.false_alarms;
    format!(
        "{} rounds of {}: gangue share {} -> {} ({:?}), level {}, alarms per impact {:e} (h = {:.2} nats)\n\
         delay in impacts  kernel      {}\n                  reference   {}\n                  \
         label oracle {}\n                  naive k={} of n={} {}\n\
         KL nats/impact: kernel {:.3}, reference {:.3}, labels {:.3}\n\
         false alarms per 1e5 impacts (over {}): kernel {:.2} (pure coal {:.2}), naive {:.2}, \
         reference {:.2}, labels {:.2}\n\
         kernel      {}\nclairvoyant {}\nnaive       {}\n",
        r.rounds,
        r.scene,
        r.pre_share,
        r.post_share,
        r.profile.unwrap_or(Profile::Step),
        r.level,
        r.false_alarm_rate,
        r.threshold_nats,
        d(&r.detection_delay_impacts),
        d(&r.reference_delay_impacts),
        d(&r.label_oracle_delay_impacts),
        r.naive_rule.k,
        r.naive_rule.n,
        d(&r.naive_delay_impacts),
        r.kl_nats_per_impact.kernel,
        r.kl_nats_per_impact.reference,
        r.kl_nats_per_impact.labels,
        f.impacts,
        f.kernel_per_1e5,
        f.kernel_pure_coal_per_1e5,
        f.naive_per_1e5,
        f.reference_per_1e5,
        f.label_oracle_per_1e5,
        m(&kernel),
        m(&r.clairvoyant),
        m(&r.naive),
    )
}

const BLUE: RGBColor = RGBColor(31, 119, 180);
const ORANGE: RGBColor = RGBColor(255, 127, 14);
const GREEN: RGBColor = RGBColor(44, 160, 44);
const RED: RGBColor = RGBColor(214, 39, 40);
const GREY: RGBColor = RGBColor(110, 110, 110);

fn curve(label: &str, points: Vec<(f64, f64)>, color: RGBColor, stroke: Stroke) -> Curve {
    Curve {
        label: label.to_string(),
        points,
        color,
        stroke,
    }
}

/// Writes caving_share.svg (the first round), caving_delay.svg and caving_curve.csv.
pub fn write_plots(r: &CavingReport, dir: &Path) -> Result<()> {
    share_plot(r, dir)?;
    delay_plot(r, dir)?;
    curve_csv(r, dir)
}

/// caving_share.svg: the first round's share estimate with its band, the true share, the
/// level and the kernel's alarm.
fn share_plot(r: &CavingReport, dir: &Path) -> Result<()> {
    let t = &r.trace;
    let share: Vec<_> = t.points.iter().map(|p| (p.0 as f64, p.1)).collect();
    let hi: Vec<_> = t
        .points
        .iter()
        .map(|p| (p.0 as f64, p.1 + 2.0 * p.2))
        .collect();
    let lo: Vec<_> = t
        .points
        .iter()
        .map(|p| (p.0 as f64, p.1 - 2.0 * p.2))
        .collect();
    let truth: Vec<_> = t
        .true_share
        .iter()
        .enumerate()
        .map(|(i, &s)| (i as f64, s))
        .collect();
    let n = t.true_share.len() as f64;
    let mut curves = vec![
        curve("share estimate", share, BLUE, Stroke::Solid),
        curve("estimate + 2 standard errors", hi, BLUE, Stroke::Dashed),
        curve("estimate - 2 standard errors", lo, BLUE, Stroke::Dashed),
        curve("true share", truth, GREY, Stroke::Solid),
        curve(
            "level",
            vec![(0.0, r.level), (n, r.level)],
            ORANGE,
            Stroke::Dashed,
        ),
    ];
    if let Some(a) = t.alarm {
        let a = a as f64;
        curves.push(curve(
            "kernel alarm",
            vec![(a, 0.0), (a, 1.0)],
            RED,
            Stroke::Solid,
        ));
    }
    draw_svg(
        &dir.join("caving_share.svg"),
        &format!(
            "{}: gangue share over one round, alarm at 1 per {:.0e} impacts",
            r.scene,
            1.0 / r.false_alarm_rate
        ),
        "impact",
        "gangue share",
        &curves,
        true,
    )?;
    Ok(())
}

/// caving_delay.svg: the median delay of each detector, and `h / KL`, against false alarms.
fn delay_plot(r: &CavingReport, dir: &Path) -> Result<()> {
    let pts = |f: fn(&crate::score::caving::CurvePoint) -> f64| -> Vec<(f64, f64)> {
        r.curve
            .iter()
            .map(|p| ((1.0 / p.false_alarm_rate).log10(), f(p)))
            .collect()
    };
    draw_svg(
        &dir.join("caving_delay.svg"),
        &format!(
            "{}: median delay against false alarms ({} -> {})",
            r.scene, r.pre_share, r.post_share
        ),
        "log10 impacts per false alarm",
        "median delay (impacts)",
        &[
            curve("kernel", pts(|p| p.kernel_median), BLUE, Stroke::Points),
            curve(
                "reference (exact features)",
                pts(|p| p.reference_median),
                GREEN,
                Stroke::Points,
            ),
            curve(
                "label oracle",
                pts(|p| p.label_oracle_median),
                GREY,
                Stroke::Points,
            ),
            curve(
                "h / KL kernel",
                pts(|p| p.kernel_lorden),
                BLUE,
                Stroke::Dashed,
            ),
            curve(
                "h / KL reference",
                pts(|p| p.reference_lorden),
                GREEN,
                Stroke::Dashed,
            ),
        ],
        true,
    )?;
    Ok(())
}

/// caving_curve.csv: the delay-against-false-alarm curve.
fn curve_csv(r: &CavingReport, dir: &Path) -> Result<()> {
    let mut csv = String::from(
        "false_alarm_rate,threshold_nats,kernel_false_alarms_per_1e5,kernel_median,reference_median,label_oracle_median,kernel_lorden,reference_lorden\n",
    );
    for p in &r.curve {
        csv += &format!(
            "{:e},{:.4},{:.3},{},{},{},{:.2},{:.2}\n",
            p.false_alarm_rate,
            p.threshold_nats,
            p.kernel_false_alarms_per_1e5,
            p.kernel_median,
            p.reference_median,
            p.label_oracle_median,
            p.kernel_lorden,
            p.reference_lorden
        );
    }
    let path = dir.join("caving_curve.csv");
    std::fs::write(&path, csv).with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, Parser)]
    struct Cli {
        #[command(flatten)]
        args: CavingArgs,
    }

    #[test]
    fn flags_override_the_scene_which_overrides_the_defaults() {
        let spec = CavingSpec {
            pre_share: Some(0.1),
            post_share: Some(0.3),
            rate_hz: Some(5.0),
            profile: Some(Profile::Ramp),
            ..CavingSpec::default()
        };
        let cli = Cli::try_parse_from(["caving", "--post-share", "0.4", "--rounds", "3"])
            .expect("parses");
        let o = cli.args.options(&spec);
        assert_eq!(o.pre_share, 0.1);
        assert_eq!(o.post_share, 0.4);
        assert_eq!(o.level, 0.4, "the level defaults to the post-change share");
        assert_eq!(o.rate_hz, 5.0);
        assert_eq!(o.profile, Profile::Ramp);
        assert_eq!(o.false_alarm_rate, 1e-5);
        assert_eq!(o.rounds, 3);
        let cli = Cli::try_parse_from(["caving", "--rate", "-1"]).expect("parses");
        let err = cli
            .args
            .options(&CavingSpec::default())
            .validate(&crate::scene::SceneFile::paper());
        assert!(format!("{:?}", err).contains("rate_hz"), "{err:?}");
    }
}
