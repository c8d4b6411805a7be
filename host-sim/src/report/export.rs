//! `host-sim export`: a scene file as Rust source that a firmware includes, a function that
//! builds the kernel `Scene` exactly as [`crate::bridge::kernel_scene::scene_to_kernel`]
//! builds it from the file: the same materials, classes (names, radius and speed ranges,
//! priors), sensor chain (`SensorChain::from_plate` and, for a chain with modes or an
//! accelerometer, its dynamics designed with the firmware's math backend) and the settings of
//! [`crate::bridge::kernel_scene::calibrated_settings`] (the contact calibration of a damped
//! law and the tolerances it widens), every `f32` written as the shortest literal that reads
//! back to the same bits (`{:?}` of the `f32`).
//!
//! The firmware's scenes (`fw/replay/src/scenes/`) are made this way by `fw/stream.sh`, and
//! `fw/stream.sh --check` fails unless they are reproduced byte for byte.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use coalshock::ratio_map::RatioMap;
use coalshock::sampled_phase::{PHASE_COLUMNS, PHASE_ROWS};
use coalshock::{
    Accelerometer, BeamMode, ChainDynamics, ChainTolerance, ContactCalibration, Material,
    ParticleClass, PulseShape, Range, SampledCalibration, SampledPhase, Settings, Speed,
};

use crate::bridge::convert::{
    ConvertError, class_to_kernel, dynamics_to_kernel, material_to_kernel, ratio_maps_to_kernel,
};
use crate::bridge::kernel_scene::{SceneCalibration, scene_to_kernel};
use crate::scene::{SceneFile, SensorSpec};

/// `host-sim export`: reads the scene file `scene_path`, writes the source to `out` (standard
/// output when `None`), creating its directory where missing (as `stream --out` does).
pub fn run(scene_path: &Path, out: Option<&Path>) -> Result<()> {
    let scene = crate::scene::load(scene_path)?;
    // The path as given when relative (the project's own `scenes/...`), else its file name:
    // the header names no directory of the machine it was made on.
    let shown = if scene_path.is_relative() {
        scene_path.display().to_string()
    } else {
        scene_path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    };
    let text = scene_source(&scene, &shown)
        .with_context(|| format!("exporting the scene {}", scene_path.display()))?;
    match out {
        Some(out) => {
            if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir)
                    .with_context(|| format!("creating {}", dir.display()))?;
            }
            std::fs::write(out, text).with_context(|| format!("writing {}", out.display()))?
        }
        None => crate::report::write_stdout(&text)?,
    }
    Ok(())
}

/// An `f32` as a Rust literal that reads back to the same bits.
fn lit(v: f32) -> String {
    format!("{v:?}")
}

fn material(m: &Material) -> String {
    format!(
        "Material::new({}, {}, {})",
        lit(m.density_kg_m3),
        lit(m.modulus_pa),
        lit(m.poisson)
    )
}

fn range(r: &Range) -> String {
    format!("Range::new({}, {})", lit(r.min), lit(r.max))
}

fn class(out: &mut String, c: &ParticleClass) {
    let speed = match c.speed {
        Speed::Uniform(r) => format!("Speed::Uniform({})", range(&r)),
        Speed::DropHeight(r) => format!("Speed::DropHeight({})", range(&r)),
    };
    let args = format!(
        "ParticleClass::new(\n{0}    {1:?},\n{0}    {2},\n{0}    {3},\n{0}    {4},\n{0})",
        "{indent}",
        c.name.as_str(),
        material(&c.material),
        range(&c.radius_m),
        speed,
    );
    // `ParticleClass::new` gives a prior of 1 and no yield; any other is set on top.
    let mut fields = String::new();
    if c.prior.to_bits() != 1.0f32.to_bits() {
        let _ = writeln!(fields, "            prior: {},", lit(c.prior));
    }
    if let Some(p) = c.yield_pressure_pa {
        let _ = writeln!(fields, "            yield_pressure_pa: Some({}),", lit(p));
    }
    if fields.is_empty() {
        let _ = writeln!(out, "        {},", args.replace("{indent}", "        "));
    } else {
        let _ = write!(
            out,
            "        ParticleClass {{\n{}            ..{}\n        }},\n",
            fields,
            args.replace("{indent}", "            "),
        );
    }
}

/// The list item `Some(RatioMap::new(direction, s_range, ln_force, ln_duration)?),` of a
/// class's table, every literal reading back bit for bit.
fn ratio_map_item(m: &RatioMap) -> String {
    let ((a, b), (s0, s1)) = (m.direction(), m.s_range());
    let array = |v: &[f32]| {
        let items: Vec<String> = v.iter().map(|&x| lit(x)).collect();
        let lines = array_lines(&items, &" ".repeat(16));
        format!("            [\n{}\n            ],\n", lines.join("\n"))
    };
    format!(
        "        Some(RatioMap::new(\n            ({}, {}),\n            \
         ({}, {}),\n{}{}        )?),\n",
        lit(a),
        lit(b),
        lit(s0),
        lit(s1),
        array(m.ln_force()),
        array(m.ln_duration()),
    )
}

fn contact_is_default(c: &ContactCalibration) -> bool {
    let d = Settings::default().contact;
    [
        (c.force_ratio, d.force_ratio),
        (c.duration_ratio, d.duration_ratio),
        (c.shape_ratio, d.shape_ratio),
        (c.skewness, d.skewness),
    ]
    .iter()
    .all(|(a, b)| a.to_bits() == b.to_bits())
        && c.sampled == SampledCalibration::NONE
}

/// The field `name: [a, b, ..],` of f32 literals that read back bit for bit, at `indent`
/// spaces, laid out as rustfmt lays it out: on one line when the array is at most 60 columns
/// wide and the line at most 100; else, when every literal is short (at most 10 characters),
/// literals filled into lines of at most 100 columns; else one literal per line.
fn lit_array_field(name: &str, v: &[f32], indent: usize) -> String {
    let items: Vec<String> = v.iter().map(|&x| lit(x)).collect();
    let pad = " ".repeat(indent);
    let one_line = format!("[{}]", items.join(", "));
    let field = format!("{pad}{name}: {one_line},");
    if one_line.len() <= 60 && field.len() <= 100 {
        return field + "\n";
    }
    let lines = array_lines(&items, &" ".repeat(indent + 4));
    format!("{pad}{name}: [\n{}\n{pad}],\n", lines.join("\n"))
}

/// The lines of a multi-line array of `items`, each starting with `inner`, as rustfmt lays
/// them out: filled to 100 columns when every item is at most 10 characters, else one per line.
fn array_lines(items: &[String], inner: &str) -> Vec<String> {
    if !items.iter().all(|i| i.len() <= 10) {
        return items.iter().map(|item| format!("{inner}{item},")).collect();
    }
    let mut lines = Vec::new();
    let mut line = inner.to_string();
    for item in items {
        if line.len() > inner.len() && line.len() + 1 + item.len() + 1 > 100 {
            lines.push(std::mem::replace(&mut line, inner.to_string()));
        }
        if line.len() > inner.len() {
            line.push(' ');
        }
        let _ = write!(line, "{item},");
    }
    lines.push(line);
    lines
}

/// The sampling correction as a `SampledCalibration` literal, or its `NONE`.
fn sampled_literal(s: &SampledCalibration) -> String {
    if *s == SampledCalibration::NONE {
        return "SampledCalibration::NONE".into();
    }
    let SampledCalibration {
        ln_force,
        ln_duration,
        sigma_ln_force,
        sigma_ln_duration,
    } = s;
    format!(
        "SampledCalibration {{\n{}{}{}{}            }}",
        lit_array_field("ln_force", ln_force, 16),
        lit_array_field("ln_duration", ln_duration, 16),
        lit_array_field("sigma_ln_force", sigma_ln_force, 16),
        lit_array_field("sigma_ln_duration", sigma_ln_duration, 16),
    )
}

/// `pulse_shape: PulseShape { .. },` (a firmware that runs such a scene enables the kernel's
/// `pulse_shape` feature), or nothing for [`PulseShape::NONE`].
fn shape_field(p: &PulseShape) -> String {
    if *p == PulseShape::NONE {
        return String::new();
    }
    format!(
        "        pulse_shape: PulseShape {{\n{}{}            area: {},\n            peak_at: {},\n        }},\n",
        lit_array_field("values", &p.values, 12),
        lit_array_field("slopes", &p.slopes, 12),
        lit(p.area),
        lit(p.peak_at),
    )
}

/// `sampled_phase: SampledPhase { .. },` (a firmware that runs such a scene enables the kernel's
/// `sampled_phase` feature), or nothing for [`SampledPhase::NONE`].
fn phase_field(p: &SampledPhase) -> String {
    if *p == SampledPhase::NONE {
        return String::new();
    }
    let rows = |name: &str, t: &[[f32; PHASE_COLUMNS]; PHASE_ROWS]| {
        let body: Vec<String> = t
            .iter()
            .map(|r| {
                let v: Vec<String> = r.iter().map(|&x| lit(x)).collect();
                format!("                [{}],\n", v.join(", "))
            })
            .collect();
        format!("            {name}: [\n{}            ],\n", body.concat())
    };
    let axes: Vec<String> = p
        .asymmetry
        .iter()
        .map(|[a, b]| format!("                [{}, {}],\n", lit(*a), lit(*b)))
        .collect();
    format!(
        "        sampled_phase: SampledPhase {{\n            asymmetry: [\n{}            ],\n{}{}{}{}        }},\n",
        axes.concat(),
        rows("ln_force", &p.ln_force),
        rows("ln_duration", &p.ln_duration),
        rows("sigma_ln_force", &p.sigma_ln_force),
        rows("sigma_ln_duration", &p.sigma_ln_duration),
    )
}

/// The settings as `Settings { .., ..Settings::default() }` with every field whose bits differ
/// from the default's (host-sim starts from the default too), or `Settings::default()`.
fn settings(out: &mut String, s: &Settings) {
    let mut fields = changed_fields(s);
    if !contact_is_default(&s.contact) {
        fields.push(contact_field(&s.contact));
    }
    let phase = phase_field(&s.sampled_phase);
    if !phase.is_empty() {
        fields.push(phase);
    }
    let shape = shape_field(&s.pulse_shape);
    if !shape.is_empty() {
        fields.push(shape);
    }
    if fields.is_empty() {
        out.push_str("    let settings = Settings::default();\n");
    } else {
        out.push_str("    let settings = Settings {\n");
        for f in fields {
            out.push_str(&f);
        }
        out.push_str("        ..Settings::default()\n    };\n");
    }
}

/// `name: value,` of every number of `s` (all but the contact calibration) whose bits differ
/// from the default's.
fn changed_fields(s: &Settings) -> Vec<String> {
    let d = Settings::default();
    // Destructured in full: a field added to the kernel's settings is a build error here.
    let Settings {
        trigger_sigmas,
        release_sigmas,
        hold_samples,
        baseline_tau_s,
        stuck_samples,
        model_sigma,
        confident_error_rate,
        out_sigmas,
        separability_grid,
        shape_tolerance,
        contact: _,
        spike_fraction,
        skew_tolerance,
        flat_top_ratio,
        sampled_phase: _,
        pulse_shape: _,
    } = *s;
    let mut fields = Vec::new();
    let mut float = |name: &str, v: f32, default: f32| {
        if v.to_bits() != default.to_bits() {
            fields.push(format!("        {name}: {},\n", lit(v)));
        }
    };
    float("trigger_sigmas", trigger_sigmas, d.trigger_sigmas);
    float("release_sigmas", release_sigmas, d.release_sigmas);
    float("baseline_tau_s", baseline_tau_s, d.baseline_tau_s);
    float("model_sigma", model_sigma, d.model_sigma);
    float(
        "confident_error_rate",
        confident_error_rate,
        d.confident_error_rate,
    );
    float("out_sigmas", out_sigmas, d.out_sigmas);
    float("shape_tolerance", shape_tolerance, d.shape_tolerance);
    float("spike_fraction", spike_fraction, d.spike_fraction);
    float("skew_tolerance", skew_tolerance, d.skew_tolerance);
    float("flat_top_ratio", flat_top_ratio, d.flat_top_ratio);
    let mut int = |name: &str, v: u16, default: u16| {
        if v != default {
            fields.push(format!("        {name}: {v},\n"));
        }
    };
    int("hold_samples", hold_samples, d.hold_samples);
    int("stuck_samples", stuck_samples, d.stuck_samples);
    int("separability_grid", separability_grid, d.separability_grid);
    fields
}

/// `contact: ContactCalibration { .. },` with every ratio and the sampling correction.
fn contact_field(contact: &ContactCalibration) -> String {
    let ContactCalibration {
        force_ratio,
        duration_ratio,
        shape_ratio,
        skewness,
        sampled,
    } = *contact;
    format!(
        "        contact: ContactCalibration {{\n            \
                     force_ratio: {},\n            \
                     duration_ratio: {},\n            \
                     shape_ratio: {},\n            \
                     skewness: {},\n            \
                     sampled: {},\n        \
                 }},\n",
        lit(force_ratio),
        lit(duration_ratio),
        lit(shape_ratio),
        lit(skewness),
        sampled_literal(&sampled),
    )
}

/// The Rust source of `scene` (read from the file named `source` in the header): a module
/// with `pub fn scene<M: Backend>() -> Result<Scene<DEFAULT_CLASSES, M>, Error>`. The scene is
/// converted first ([`scene_to_kernel`]), so a file the kernel refuses exports nothing.
pub fn scene_source(scene: &SceneFile, source: &str) -> Result<String, ConvertError> {
    scene_to_kernel(scene)?;
    let cal = SceneCalibration::of(scene).map_err(ConvertError::Calibration)?;
    let settings_k = cal.settings(scene);
    let classes: Vec<ParticleClass> = scene.classes.iter().map(class_to_kernel).collect();
    let maps = ratio_maps_to_kernel(&cal.tables)?;
    let plate = material_to_kernel(&scene.plate.material());
    let dynamics = dynamics_to_kernel(&scene.sensor)?;
    let tables = !maps.is_empty();

    let mut out = String::new();
    header(&mut out, source, &scene.name);
    imports(&mut out, &settings_k, &dynamics, tables);
    let _ = write!(
        out,
        "/// The scene with math backend `M`{}.\n\
         #[inline(never)]\n\
         pub fn scene<M: Backend>() -> Result<Scene<DEFAULT_CLASSES, M>, Error> {{\n    \
             let classes = [\n",
        if dynamics.is_rigid() {
            ""
        } else {
            " (the chain's equaliser designed with `M`)"
        }
    );
    for c in &classes {
        class(&mut out, c);
    }
    out.push_str("    ];\n");
    sensor_chain(&mut out, &scene.sensor, &dynamics);
    settings(&mut out, &settings_k);
    if tables {
        out.push_str("    let maps = [\n");
        for m in maps.iter().flatten() {
            out.push_str(&ratio_map_item(m));
        }
        out.push_str("    ];\n");
    }
    let _ = write!(
        out,
        "    Scene::{}(\n        \
                 {},\n        \
                 &classes,\n        \
                 {}sensor,\n        \
                 settings,\n    \
             )\n\
         }}\n",
        if tables { "with_ratio_maps" } else { "new" },
        material(&plate),
        if tables { "&maps,\n        " } else { "" },
    );
    Ok(out)
}

/// The module's doc header: which file, which scene, how it was made.
fn header(out: &mut String, source: &str, scene_name: &str) {
    let name = if scene_name.is_empty() {
        String::new()
    } else {
        format!(" ({scene_name:?})")
    };
    let _ = write!(
        out,
        "//! The kernel scene of `{source}`{name}, as host-sim builds it from the file.\n\
         //!\n\
         //! Generated by `host-sim export --scene {source}`; do not edit. `fw/stream.sh`\n\
         //! regenerates it, and `fw/stream.sh --check` fails unless it is reproduced byte for\n\
         //! byte.\n\
         \n"
    );
}

/// The `use` lines: the kernel's items the source names, in one list filled to rustfmt's 100
/// columns as it would.
fn imports(out: &mut String, settings: &Settings, dynamics: &ChainDynamics, tables: bool) {
    let mut uses = vec!["Error", "Material", "ParticleClass"];
    if !contact_is_default(&settings.contact) {
        // The calibration literal names its sampling correction (or its `NONE`).
        uses.extend(["ContactCalibration", "SampledCalibration"]);
    }
    if settings.sampled_phase != SampledPhase::NONE {
        uses.push("SampledPhase");
    }
    if settings.pulse_shape != PulseShape::NONE {
        uses.push("PulseShape");
    }
    uses.extend(["Range", "Scene", "SensorChain", "Settings", "Speed"]);
    if !dynamics.is_rigid() {
        uses.push("ChainDynamics");
        if !dynamics.modes().is_empty() {
            uses.push("BeamMode");
        }
        if dynamics.accelerometer().is_some() {
            uses.push("Accelerometer");
        }
        if dynamics.tolerance() != ChainTolerance::IDENTIFIED
            || dynamics.has_accelerometer_tolerance()
        {
            uses.push("ChainTolerance");
        }
    }
    uses.sort_unstable();
    let one_line = format!("use coalshock::{{{}}};", uses.join(", "));
    let mut lines = Vec::new();
    let mut line = String::from("   ");
    for u in uses {
        if line.len() + 1 + u.len() + 1 > 100 {
            lines.push(std::mem::replace(&mut line, String::from("   ")));
        }
        let _ = write!(line, " {u},");
    }
    lines.push(line);
    let list = if one_line.len() <= 100 {
        one_line
    } else {
        format!("use coalshock::{{\n{}\n}};", lines.join("\n"))
    };
    let _ = write!(
        out,
        "use coalshock::math::Backend;\n\
         {}use coalshock::scene::DEFAULT_CLASSES;\n\
         {list}\n\n",
        if tables {
            "use coalshock::ratio_map::RatioMap;\n"
        } else {
            ""
        }
    );
}

/// `let sensor = ..`: the plate's chain, and, unless it is rigid, its dynamics (modes,
/// accelerometer, tolerance) designed with `M`.
fn sensor_chain(out: &mut String, s: &SensorSpec, dynamics: &ChainDynamics) {
    let _ = writeln!(
        out,
        "    let sensor = SensorChain::from_plate({}, {}, {}, {}, {});",
        lit(s.sample_rate_hz as f32),
        lit(s.effective_mass_kg as f32),
        lit(s.counts_per_m_s2 as f32),
        lit(s.noise_rms_counts as f32),
        s.adc_bits,
    );
    if dynamics.is_rigid() {
        return;
    }
    out.push_str("    let dynamics = ChainDynamics::RIGID");
    for m in dynamics.modes() {
        let BeamMode {
            frequency_hz,
            damping_ratio,
            gain,
        } = *m;
        let _ = write!(
            out,
            "\n        .with_mode(BeamMode {{\n            \
                 frequency_hz: {},\n            \
                 damping_ratio: {},\n            \
                 gain: {},\n        \
             }})?",
            lit(frequency_hz),
            lit(damping_ratio),
            lit(gain),
        );
    }
    if let Some(Accelerometer {
        frequency_hz,
        damping_ratio,
    }) = dynamics.accelerometer()
    {
        let _ = write!(
            out,
            "\n        .with_accelerometer(Accelerometer {{\n            \
                 frequency_hz: {},\n            \
                 damping_ratio: {},\n        \
             }})",
            lit(frequency_hz),
            lit(damping_ratio),
        );
    }
    let t = dynamics.tolerance();
    if t != ChainTolerance::IDENTIFIED {
        write_tolerance(out, "with_tolerance", t);
    }
    if dynamics.has_accelerometer_tolerance() {
        write_tolerance(
            out,
            "with_accelerometer_tolerance",
            dynamics.accelerometer_tolerance(),
        );
    }
    out.push_str(";\n    let sensor = sensor.with_dynamics_in::<M>(dynamics)?;\n");
}

/// `.METHOD(ChainTolerance { .. })?` on the dynamics being written.
fn write_tolerance(out: &mut String, method: &str, t: ChainTolerance) {
    let _ = write!(
        out,
        "\n        .{method}(ChainTolerance {{\n            \
             frequency: {},\n            \
             damping: {},\n            \
             gain: {},\n        \
         }})?",
        lit(t.frequency),
        lit(t.damping),
        lit(t.gain),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped() -> Vec<(String, SceneFile)> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .expect("scenes/")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        files.sort();
        assert!(files.len() >= 2, "shipped scenes");
        files
            .iter()
            .map(|p| {
                let name = p.file_name().expect("name").to_string_lossy().into_owned();
                (name, crate::scene::load(p).expect("shipped scene loads"))
            })
            .collect()
    }

    /// Every float literal of the text (a token with a `.` or an exponent after a digit).
    fn float_literals(text: &str) -> Vec<&str> {
        text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '_'))
            .filter(|t| {
                t.trim_start_matches('-')
                    .starts_with(|c: char| c.is_ascii_digit())
                    && (t.contains('.') || t.contains('e'))
            })
            .collect()
    }

    /// For every shipped scene: every f32 the kernel scene is built from appears in the text as
    /// the literal that reads back to its bits (plate, classes, priors, sensor, modes,
    /// accelerometer, every setting of the calibrated settings), and every float literal of the
    /// text reads back to itself.
    #[test]
    fn exported_text_carries_the_exact_bits_of_every_shipped_scene() {
        for (name, file) in shipped() {
            let Ok(kernel) = scene_to_kernel(&file) else {
                continue; // a scene the kernel refuses exports nothing (tested below)
            };
            let text = scene_source(&file, &name).expect("exports");
            for lit_text in float_literals(&text) {
                let v: f32 = lit_text.parse().expect("f32 literal");
                assert_eq!(format!("{v:?}"), lit_text, "{name}: {lit_text}");
            }
            parts_are_written(&name, &file, &kernel, &text);
            settings_are_written(&name, &file, &kernel, &text);
            assert!(text.contains("Settings::default()"), "{name}");
        }
    }

    /// The plate, the host's ratio tables, the classes and the chain of `kernel` in `text`.
    fn parts_are_written(name: &str, file: &SceneFile, kernel: &coalshock::Scene, text: &str) {
        let has = |what: String| {
            assert!(text.contains(&what), "{name}: `{what}` missing in\n{text}");
        };
        has(material(kernel.plate()));
        // The host's tables (the kernel fills a yielding class's map itself).
        let cal = SceneCalibration::of(file).expect("calibration");
        for m in ratio_maps_to_kernel(&cal.tables)
            .expect("tables")
            .iter()
            .flatten()
        {
            has(ratio_map_item(m));
        }
        for c in kernel.classes() {
            if c.prior != 1.0 {
                has(format!("prior: {}", lit(c.prior)));
            }
            if let Some(p) = c.yield_pressure_pa {
                has(format!("yield_pressure_pa: Some({}),", lit(p)));
            }
            has(format!("{:?}", c.name.as_str()));
            has(material(&c.material));
            has(range(&c.radius_m));
            has(match c.speed {
                Speed::Uniform(r) => format!("Speed::Uniform({})", range(&r)),
                Speed::DropHeight(r) => format!("Speed::DropHeight({})", range(&r)),
            });
        }
        let chain = kernel.sensor();
        assert!(text.contains(&format!("from_plate({}, ", lit(chain.sample_rate_hz))));
        let s = &file.sensor;
        let m_over_s = s.effective_mass_kg as f32 / s.counts_per_m_s2 as f32;
        assert_eq!(m_over_s.to_bits(), chain.force_per_count_n.to_bits());
        for m in chain.dynamics.modes() {
            has(format!("frequency_hz: {},", lit(m.frequency_hz)));
            has(format!("damping_ratio: {},", lit(m.damping_ratio)));
            has(format!("gain: {},", lit(m.gain)));
        }
        assert_eq!(
            text.contains("with_dynamics_in::<M>"),
            !chain.dynamics.is_rigid(),
            "{name}"
        );
    }

    /// Every setting of `kernel` in `text` when its bits differ from the default's, and the
    /// contact calibration of the scene file.
    fn settings_are_written(name: &str, file: &SceneFile, kernel: &coalshock::Scene, text: &str) {
        let has = |what: String| {
            assert!(text.contains(&what), "{name}: `{what}` missing in\n{text}");
        };
        // Every setting is written when its bits differ from the default's, else it is the
        // default's (`..Settings::default()`).
        let st = kernel.settings();
        let d = Settings::default();
        for (field, v, dv) in [
            ("trigger_sigmas", st.trigger_sigmas, d.trigger_sigmas),
            ("release_sigmas", st.release_sigmas, d.release_sigmas),
            ("baseline_tau_s", st.baseline_tau_s, d.baseline_tau_s),
            ("model_sigma", st.model_sigma, d.model_sigma),
            (
                "confident_error_rate",
                st.confident_error_rate,
                d.confident_error_rate,
            ),
            ("out_sigmas", st.out_sigmas, d.out_sigmas),
            ("shape_tolerance", st.shape_tolerance, d.shape_tolerance),
            ("spike_fraction", st.spike_fraction, d.spike_fraction),
            ("skew_tolerance", st.skew_tolerance, d.skew_tolerance),
            ("flat_top_ratio", st.flat_top_ratio, d.flat_top_ratio),
        ] {
            let written = format!("{field}: {},", lit(v));
            assert_eq!(
                text.contains(&written),
                v.to_bits() != dv.to_bits(),
                "{name}: {field}"
            );
        }
        for (field, v, dv) in [
            ("hold_samples", st.hold_samples, d.hold_samples),
            ("stuck_samples", st.stuck_samples, d.stuck_samples),
            (
                "separability_grid",
                st.separability_grid,
                d.separability_grid,
            ),
        ] {
            assert_eq!(
                text.contains(&format!("{field}: {v},")),
                v != dv,
                "{name}: {field}"
            );
        }
        // The export writes the scene file's calibration; the kernel adds its chain's
        // residual (`coalshock::chain_residual`) when it builds the scene, on the node too.
        let c = crate::bridge::kernel_scene::calibrated_settings(file)
            .expect("settings")
            .contact;
        if contact_is_default(&c) {
            assert!(!text.contains("ContactCalibration"), "{name}");
        } else {
            // Whatever the literal names is imported.
            assert!(text.contains(" SampledCalibration,"), "{name}");
            for (field, v) in [
                ("force_ratio", c.force_ratio),
                ("duration_ratio", c.duration_ratio),
                ("shape_ratio", c.shape_ratio),
                ("skewness", c.skewness),
            ] {
                has(format!("{field}: {},", lit(v)));
            }
        }
    }

    /// Arrays laid out as rustfmt 1.95 (edition 2024, default settings) lays out the same
    /// fields inside a `SampledCalibration` literal (the expected texts are its output): one
    /// line up to 60 columns of array, short literals filled up to 100 columns, long ones one
    /// per line.
    #[test]
    fn arrays_are_laid_out_as_rustfmt_does() {
        let short = [0.05, 0.01, 0.003, 0.001, 0.001, 0.0007, 0.0002, 0.00011];
        assert_eq!(
            lit_array_field("ln_z", &short, 16),
            "                ln_z: [0.05, 0.01, 0.003, 0.001, 0.001, 0.0007, 0.0002, 0.00011],\n"
        );
        let wide = [
            0.05, 0.01, 0.003, 0.001, 0.001, 0.0007, 0.0002, 0.0001, 0.01,
        ];
        assert_eq!(
            lit_array_field("ln_y", &wide, 16),
            "                ln_y: [\n                    \
             0.05, 0.01, 0.003, 0.001, 0.001, 0.0007, 0.0002, 0.0001, 0.01,\n                ],\n"
        );
        let filled = [
            0.0054962, -0.011278, 0.0038743, 0.0014294, 0.0018145, 0.000712, 0.0002847, 0.0001095,
        ];
        assert_eq!(
            lit_array_field("ln_duration", &filled, 16),
            "                ln_duration: [\n                    \
             0.0054962, -0.011278, 0.0038743, 0.0014294, 0.0018145, 0.000712, 0.0002847,\n                    \
             0.0001095,\n                ],\n"
        );
        let long = [
            0.005496286,
            0.01127803,
            0.00387434,
            0.00142947,
            0.00181459,
            0.00071209,
            0.0002847,
            0.0001095,
        ];
        let rows: String = [
            "0.005496286",
            "0.01127803",
            "0.00387434",
            "0.00142947",
            "0.00181459",
            "0.00071209",
            "0.0002847",
            "0.0001095",
        ]
        .iter()
        .map(|r| format!("                    {r},\n"))
        .collect();
        assert_eq!(
            lit_array_field("ln_force", &long, 16),
            format!("                ln_force: [\n{rows}                ],\n")
        );
    }

    #[test]
    fn a_refused_scene_exports_nothing() {
        let mut s = SceneFile::paper();
        s.settings.confident_error_rate = 0.6;
        assert!(scene_source(&s, "x.toml").is_err());
    }
}
