//! The command line and the files refuse what they cannot do, by the field's name and (in a
//! scene) the class's: counts beyond their bound, ranges that are not two numbers, values the
//! kernel's f32 cannot hold, an unknown material, and a stream whose samples do not match its
//! truth file. Each case runs the `host-sim` binary or the file reader on the bad input.
//! A reader that closes standard output early ends the command quietly with exit code 141
//! (128 + SIGPIPE), without a panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use host_sim::generate::generate;
use host_sim::hertz64::Material64;
use host_sim::kernel_scene::scene_to_kernel;
use host_sim::scene::{MaterialName, MaterialSpec, SceneFile};
use host_sim::stream::StreamOptions;
use host_sim::stream_file::{read_stream, stream_paths, write_stream};

fn temp_dir(tag: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("host-sim-cli-inputs-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Runs `host-sim args`: (exit code, stdout, stderr).
fn host_sim(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("runs host-sim");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Refused with exit code `code` and every needle in standard error.
fn refused(args: &[&str], code: i32, needles: &[&str]) {
    let (rc, _, err) = host_sim(args);
    assert_eq!(rc, code, "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: {n:?} not in {err}");
    }
}

#[test]
fn counts_beyond_their_bound_are_refused_with_it() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/paper.toml");
    let scene = scene.to_str().expect("utf8 path");
    let huge = ["1000000000000", "18446744073709551615"];
    for n in huge {
        refused(
            &["evaluate", "--scene", scene, "--n", n],
            2,
            &["--n", "from 1 to 10000000", "impacts per class"],
        );
        refused(
            &["evaluate", "--scene", scene, "--n", "5", "--bayes-draws", n],
            2,
            &["--bayes-draws", "from 1 to 100000000"],
        );
        refused(
            &["stream", "--n", n, "--out", "unused"],
            2,
            &["--n", "from 1 to 10000000"],
        );
        refused(
            &["caving", "--scene", scene, "--rounds", n],
            2,
            &["--rounds", "from 1 to 100000"],
        );
        refused(
            &["caving", "--scene", scene, "--post-impacts", n],
            2,
            &["--post-impacts", "from 1 to 1000000"],
        );
    }
    refused(
        &["evaluate", "--scene", scene, "--n", "0"],
        2,
        &["--n", "from 1"],
    );
}

#[test]
fn a_refused_scene_names_the_field_without_a_backtrace() {
    let dir = temp_dir("field-named");
    let path = dir.join("scene.toml");
    let text = paper_with("radius_m = [0.015, 0.04]", "radius_m = [0.015, 0.03, 0.04]");
    std::fs::write(&path, text).expect("write scene");
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args([
            "evaluate",
            "--scene",
            path.to_str().expect("utf8"),
            "--n",
            "5",
        ])
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("runs host-sim");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("radius_m must be exactly two numbers"),
        "{err}"
    );
    assert!(
        !err.contains("Stack backtrace") && !err.contains("panicked"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The paper scene's text with `from` replaced by `to` once.
fn paper_with(from: &str, to: &str) -> String {
    let text = SceneFile::paper().to_toml_string().expect("serialize");
    assert!(text.contains(from), "{from} not in {text}");
    text.replacen(from, to, 1)
}

/// `evaluate` on the scene `text` is refused with every needle in its message.
fn scene_refused(tag: &str, text: &str, needles: &[&str]) {
    let dir = temp_dir(tag);
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).expect("write scene");
    refused(
        &[
            "evaluate",
            "--scene",
            path.to_str().expect("utf8"),
            "--n",
            "5",
        ],
        1,
        needles,
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ranges_must_be_exactly_two_numbers() {
    let good = "radius_m = [0.015, 0.04]";
    for (tag, bad, found) in [
        ("three", "radius_m = [0.015, 0.03, 0.04]", "got 3 values"),
        ("four", "radius_m = [0.015, 0.04, \"x\", 7]", "got 4 values"),
        ("text", "radius_m = [0.015, \"x\"]", "[0.015, \"x\"]"),
    ] {
        scene_refused(
            tag,
            &paper_with(good, bad),
            &["class \"coal\"", "radius_m", "exactly two numbers", found],
        );
    }
    let speed = paper_with("speed_m_s = [1.0, 5.0]", "speed_m_s = [1.0]");
    scene_refused(
        "speed",
        &speed,
        &["class \"coal\"", "speed_m_s", "got 1 values"],
    );
    // Integers are numbers.
    let ints = paper_with("speed_m_s = [1.0, 5.0]", "speed_m_s = [1, 5]");
    let s = SceneFile::from_toml_str(&ints).expect("integers are numbers");
    assert_eq!(s, SceneFile::paper());
}

#[test]
fn values_beyond_the_kernels_f32_name_the_class_and_the_reason() {
    let prior = paper_with("prior = 1.0", "prior = 1e-300");
    scene_refused(
        "prior",
        &prior,
        &[
            "classes[0].prior",
            "class \"coal\"",
            "underflows the kernel's f32",
        ],
    );
    let text = SceneFile::paper().to_toml_string().expect("serialize");
    let gangue = text
        .rfind("material = \"sandstone\"")
        .expect("gangue material");
    let modulus = format!(
        "{}material = {{ density_kg_m3 = 2487.0, modulus_pa = 1e40, poisson = 0.123 }}{}",
        &text[..gangue],
        &text[gangue + "material = \"sandstone\"".len()..]
    );
    scene_refused(
        "modulus",
        &modulus,
        &[
            "classes[1].material.modulus_pa",
            "class \"gangue\"",
            "overflows the kernel's f32 arithmetic",
        ],
    );
    // The host's bound is the kernel's: just inside it both accept, just outside both refuse.
    for (value, inside) in [(0.9e30, true), (1.1e30, false)] {
        let mut s = SceneFile::paper();
        s.classes[1].material = MaterialSpec::Custom(Material64 {
            modulus_pa: value,
            ..Material64::SANDSTONE
        });
        assert_eq!(s.validate().is_ok(), inside, "host, E = {value}");
        assert_eq!(scene_to_kernel(&s).is_ok(), inside, "kernel, E = {value}");
    }
    for (value, inside) in [(1.1e-30, true), (0.9e-30, false)] {
        let mut s = SceneFile::paper();
        s.classes[0].prior = value;
        assert_eq!(s.validate().is_ok(), inside, "host, prior = {value}");
        assert_eq!(
            scene_to_kernel(&s).is_ok(),
            inside,
            "kernel, prior = {value}"
        );
    }
    // A derived quantity the kernel cannot carry names the class too.
    let tiny = paper_with("radius_m = [0.015, 0.04]", "radius_m = [1e-30, 1e-29]");
    scene_refused(
        "tiny",
        &tiny,
        &[
            "classes[0].radius_m and speed",
            "class \"coal\"",
            "sphere mass",
        ],
    );
}

#[test]
fn impact_takes_every_material_scene_files_take() {
    for m in MaterialName::ALL {
        let (rc, out, err) = host_sim(&[
            "impact",
            "--material",
            m.name(),
            "--radius",
            "0.03",
            "--speed",
            "2",
        ]);
        assert_eq!(rc, 0, "{}: {err}", m.name());
        // The row's density is the scene table's: the mass column is 4/3 pi rho R^3.
        let row: Vec<&str> = out.lines().nth(1).expect("row").split(',').collect();
        let head: Vec<&str> = out.lines().next().expect("header").split(',').collect();
        let col = head
            .iter()
            .position(|h| *h == "mass_kg")
            .expect("mass column");
        let mass: f64 = row[col].parse().expect("mass");
        let want = 4.0 / 3.0 * std::f64::consts::PI * m.material().density_kg_m3 * 0.03f64.powi(3);
        assert!(
            (mass / want - 1.0).abs() < 1e-12,
            "{}: {mass} {want}",
            m.name()
        );
    }
    refused(
        &[
            "impact",
            "--material",
            "granite",
            "--radius",
            "0.03",
            "--speed",
            "2",
        ],
        1,
        &["unknown material", "roof_sandstone", "sandy_mudstone"],
    );
}

#[test]
fn a_stream_must_be_as_long_as_its_truth_says() {
    let dir = temp_dir("stream");
    let scene = SceneFile::paper();
    let stream = generate(&scene, 5, 3, &StreamOptions::default()).expect("stream");
    assert!(stream.gaps.is_empty(), "a stream without gaps");
    let out = dir.join("run");
    write_stream(&stream, &out).expect("write");
    read_stream(&out).expect("the stream as written reads back");
    let (bin, _) = stream_paths(&out);
    let bytes = std::fs::read(&bin).expect("bin");

    std::fs::write(&bin, &bytes[..bytes.len() - 200]).expect("truncate");
    let e = read_stream(&out).expect_err("truncated").to_string();
    assert!(e.contains(".bin") && e.contains("truncated"), "{e}");
    assert!(
        e.contains(&format!("{}", stream.samples.len() - 100)),
        "{e}"
    );

    let mut doubled = bytes.clone();
    doubled.extend_from_slice(&bytes);
    std::fs::write(&bin, &doubled).expect("double");
    let e = read_stream(&out).expect_err("doubled").to_string();
    assert!(
        e.contains(".bin") && e.contains("longer than the stream"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `[sensor] accelerometer_tolerance` is refused without an accelerometer stage and outside
/// `[0, 0.5)`, by its field's name.
#[test]
fn an_accelerometer_tolerance_needs_an_accelerometer_and_a_relative_error() {
    let sensor = "[sensor]\n";
    let without = paper_with(
        sensor,
        "[sensor]\naccelerometer_tolerance = { frequency = 0.005, damping = 0.01 }\n",
    );
    scene_refused(
        "no-band",
        &without,
        &["sensor.accelerometer_tolerance", "no accelerometer stage"],
    );
    let band = "[sensor]\naccelerometer = { frequency_hz = 40000.0, damping_ratio = 0.05 }\n";
    let too_wide = paper_with(
        sensor,
        &format!("{band}accelerometer_tolerance = {{ frequency = 0.005, damping = 0.7 }}\n"),
    );
    scene_refused(
        "too-wide",
        &too_wide,
        &["sensor.accelerometer_tolerance.damping", "[0, 0.5)", "0.7"],
    );
}

/// `evaluate` whose standard output is a pipe closed by its reader before anything is written
/// (as `host-sim evaluate ... | head -0` does) ends quietly with exit code 141, what a shell
/// reports for a process SIGPIPE ended, without a panic on the broken pipe (which aborted
/// it before).
#[test]
fn a_reader_that_closes_standard_output_early_ends_the_command_quietly() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/paper.toml");
    let scene = scene.to_str().expect("utf8 path");
    let mut child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["evaluate", "--scene", scene, "--n", "50", "--seed", "1"])
        .env("RUST_BACKTRACE", "0")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs host-sim");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("waits for host-sim");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(out.status.code(), Some(141), "{err}");
    assert!(!err.contains("Error"), "{err}");
}
