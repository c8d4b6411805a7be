//! `host-sim tradeoff`, the firmware's Cortex-M4F instruction counts: read from the
//! measures file `fw/measure.sh` writes, and the estimate of instructions per second of signal
//! they give at a sample rate.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow};
use coalshock::math::{Backend, Micromath};
use serde::Serialize;

use crate::report::tradeoff::config::FIRMWARE_SAMPLE_RATE_HZ;

/// Cortex-M4F instruction counts of one backend (release build, QEMU `netduinoplus2` with
/// `-icount shift=0`, the firmware's stand-in stream at 100 kS/s; `fw/README.md` defines each).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct M4Figures {
    /// Instructions per quiet sample through `Monitor::feed`, mean (`insns_quiet_sample_mean`).
    pub quiet_sample: f64,
    /// Instructions per quiet sample through `Monitor::feed_slice` in blocks of 256, mean
    /// (`insns_quiet_block_sample_mean`), when measured.
    pub quiet_block_sample: Option<f64>,
    /// Instructions of the `feed` call that classifies a pulse, mean (`insns_classify_mean`).
    pub classify: f64,
    /// Instructions of a whole pulse, trigger to verdict, mean (`insns_pulse_total_mean`),
    /// when measured.
    pub pulse_total: Option<f64>,
    /// Instructions of building the paper scene at the default 48-row grid
    /// (`insns_scene_build`).
    pub scene_build: f64,
}

/// The firmware's figures for both backends and where they come from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FirmwareFigures {
    /// The `measures.txt` read.
    pub source: String,
    /// The `libm` backend.
    pub libm: M4Figures,
    /// The `micromath` backend.
    pub micromath: M4Figures,
}

impl FirmwareFigures {
    /// Parses the firmware check's `measures.txt` (`key value` lines, `fw/measure.sh`): the
    /// `libm_` and `micromath_` keys `insns_quiet_sample_mean`, `insns_classify_mean`,
    /// `insns_scene_build`, and the optional `insns_quiet_block_sample_mean` and
    /// `insns_pulse_total_mean`.
    pub fn parse_measures(text: &str, source: &str) -> Result<Self> {
        let get = |key: &str| -> Option<f64> {
            text.lines().find_map(|l| {
                let mut it = l.split_whitespace();
                (it.next() == Some(key))
                    .then(|| it.next().and_then(|v| v.parse::<f64>().ok()))
                    .flatten()
            })
        };
        let backend = |prefix: &str| -> Result<M4Figures> {
            let need = |k: &str| {
                let key = format!("{prefix}{k}");
                get(&key).ok_or_else(|| anyhow!("{source}: no {key}"))
            };
            Ok(M4Figures {
                quiet_sample: need("insns_quiet_sample_mean")?,
                quiet_block_sample: get(&format!("{prefix}insns_quiet_block_sample_mean")),
                classify: need("insns_classify_mean")?,
                pulse_total: get(&format!("{prefix}insns_pulse_total_mean")),
                scene_build: need("insns_scene_build")?,
            })
        };
        Ok(Self {
            source: source.to_string(),
            libm: backend("libm_")?,
            micromath: backend("micromath_")?,
        })
    }

    /// Where the firmware check writes its measures when no file is given, in order:
    /// `$FW_OUT/measures.txt` (`fw/measure.sh` writes there when `FW_OUT` is set), then
    /// `fw/measures.txt` under `$CARGO_TARGET_DIR`, under the target directory this binary runs
    /// from (`<target>/<profile>/host-sim`), and under `target/` of the working directory.
    pub fn default_paths() -> Vec<PathBuf> {
        let mut paths: Vec<PathBuf> = Vec::new();
        if let Some(d) = std::env::var_os("FW_OUT") {
            paths.push(PathBuf::from(d).join("measures.txt"));
        }
        if let Some(d) = std::env::var_os("CARGO_TARGET_DIR") {
            paths.push(PathBuf::from(d).join("fw/measures.txt"));
        }
        if let Some(target) = std::env::current_exe()
            .ok()
            .and_then(|exe| Some(exe.parent()?.parent()?.to_path_buf()))
        {
            paths.push(target.join("fw/measures.txt"));
        }
        paths.push(PathBuf::from("target/fw/measures.txt"));
        let mut unique = Vec::new();
        for p in paths {
            if !unique.contains(&p) {
                unique.push(p);
            }
        }
        unique
    }

    /// The figures of `path` (an error if it cannot be read or lacks a key), else of the first
    /// of [`Self::default_paths`] that exists and parses (one that lacks a key, for example
    /// one being rewritten by a firmware run, is skipped with a warning on stderr). With no
    /// measures file at all it fails, naming the command that makes one: the firmware's
    /// figures are measured, never assumed.
    pub fn load(path: Option<&Path>) -> Result<Self> {
        match path {
            Some(p) => Self::load_from(Some(p), vec![p.to_path_buf()]),
            None => Self::load_from(None, Self::default_paths()),
        }
    }

    fn load_from(path: Option<&Path>, candidates: Vec<PathBuf>) -> Result<Self> {
        for p in &candidates {
            if p.is_file() {
                let text = std::fs::read_to_string(p)
                    .with_context(|| format!("cannot read {}", p.display()))?;
                match Self::parse_measures(&text, &p.display().to_string()) {
                    // Named without the machine's directories in the table (a default path).
                    Ok(f) if path.is_none() => {
                        return Ok(Self {
                            source: "the firmware check's measures file \
                                     (`measures.txt` of `fw/measure.sh`)"
                                .to_string(),
                            ..f
                        });
                    }
                    Ok(f) => return Ok(f),
                    Err(e) if path.is_none() => eprintln!("warning: {e}; skipped"),
                    Err(e) => return Err(e),
                }
            }
        }
        if let Some(p) = path {
            return Err(anyhow!("{}: no such file", p.display()));
        }
        let looked: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
        Err(anyhow!(
            "no firmware measures (the Cortex-M4F instruction counts of the table): looked for {}. \
             Run `bash fw/ci.sh` (or `fw/measure.sh`; both need QEMU, which fw/install.sh \
             installs) to measure the firmware, or pass --fw-measures FILE.",
            looked.join(", ")
        ))
    }

    pub(crate) fn of<M: Backend>(&self) -> &M4Figures {
        if M::NAME == Micromath::NAME {
            &self.micromath
        } else {
            &self.libm
        }
    }
}

/// Estimated Cortex-M4F instructions per second of signal at sample rate `f_s` (Hz) with
/// `pulses_per_s` pulses per second:
/// `f_s I_quiet + nu (I_classify + (I_pulse - I_classify) f_s / 100 kS/s)`,
/// i.e. every sample at the quiet cost, and per pulse the classification plus the in-pulse
/// samples' extra cost scaled from the 100 kS/s measurement by the number of samples a pulse
/// spans. Without a whole-pulse figure, `I_pulse - I_classify` is taken as 0.
pub fn m4_instructions_per_second(fw: &M4Figures, sample_rate_hz: f64, pulses_per_s: f64) -> f64 {
    let in_pulse = fw.pulse_total.map_or(0.0, |t| (t - fw.classify).max(0.0));
    sample_rate_hz * fw.quiet_sample
        + pulses_per_s * (fw.classify + in_pulse * sample_rate_hz / FIRMWARE_SAMPLE_RATE_HZ)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn m4_estimate_scales_the_in_pulse_part() {
        let fw = M4Figures {
            quiet_sample: 70.0,
            quiet_block_sample: None,
            classify: 4000.0,
            pulse_total: Some(9000.0),
            scene_build: 1000.0,
        };
        let at = |fs| m4_instructions_per_second(&fw, fs, 100.0);
        assert_eq!(at(100_000.0), 100_000.0 * 70.0 + 100.0 * 9000.0);
        assert_eq!(
            at(200_000.0),
            200_000.0 * 70.0 + 100.0 * (4000.0 + 2.0 * 5000.0)
        );
    }

    #[test]
    fn missing_measures_name_the_command_to_run() {
        let e = FirmwareFigures::load(Some(Path::new("no/such/measures.txt")))
            .expect_err("no such file");
        assert!(e.to_string().contains("no such file"), "{e}");
        let e = FirmwareFigures::load_from(None, vec![PathBuf::from("no/such/measures.txt")])
            .expect_err("nothing found");
        assert!(e.to_string().contains("bash fw/ci.sh"), "{e}");
        assert!(
            FirmwareFigures::default_paths()
                .iter()
                .any(|p| p.ends_with("fw/measures.txt"))
        );
    }

    #[test]
    fn measures_file_parses_and_missing_keys_are_errors() {
        let text = "libm_insns_quiet_sample_mean 70\nlibm_insns_classify_mean 4000\n\
                    libm_insns_scene_build 1000\nmicromath_insns_quiet_sample_mean 60\n\
                    micromath_insns_classify_mean 3000\nmicromath_insns_scene_build 2000\n\
                    micromath_insns_pulse_total_mean 5000\n";
        let f = FirmwareFigures::parse_measures(text, "x").expect("parses");
        assert_eq!(f.libm.quiet_sample, 70.0);
        assert_eq!(f.libm.pulse_total, None);
        assert_eq!(f.micromath.pulse_total, Some(5000.0));
        assert!(FirmwareFigures::parse_measures("libm_insns_quiet_sample_mean 1", "x").is_err());
    }
}
