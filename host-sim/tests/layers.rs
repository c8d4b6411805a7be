//! The layers of `host-sim/src` (see the crate's documentation): every `crate::` path in a
//! layer's files, code and docs, names its own layer or one listed before it, never a module
//! through the crate root's re-exports.

use std::path::{Path, PathBuf};

/// The layers, lowest first: the module each is, and the path of its files under `src/`.
const LAYERS: [(&str, &str); 7] = [
    ("physics", "physics"),
    ("scene", "scene.rs"),
    ("sim", "sim"),
    ("bridge", "bridge"),
    ("score", "score"),
    ("report", "report"),
    ("cli", "cli"),
];

/// Every `.rs` file under `dir` (or `dir` itself if it is a file).
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    if dir.is_file() {
        return vec![dir.to_path_buf()];
    }
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        files.extend(rust_files(&entry.unwrap().path()));
    }
    files
}

/// The module names that follow `crate::` in `text` (`crate::physics::laws` gives `physics`).
fn crate_paths(text: &str) -> Vec<&str> {
    text.match_indices("crate::")
        .filter(|(at, _)| !text[..*at].ends_with('$'))
        .map(|(at, m)| {
            let rest = &text[at + m.len()..];
            let end = rest
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(rest.len());
            &rest[..end]
        })
        .collect()
}

#[test]
fn every_layer_imports_only_itself_and_the_layers_before_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut wrong = Vec::new();
    let mut files_seen = 0;
    for (rank, (layer, path)) in LAYERS.iter().enumerate() {
        let mut files = rust_files(&src.join(path));
        if !path.ends_with(".rs") {
            files.push(src.join(format!("{path}.rs")));
        }
        for file in files {
            files_seen += 1;
            let text = std::fs::read_to_string(&file).unwrap();
            for name in crate_paths(&text) {
                match LAYERS.iter().position(|(l, _)| *l == name) {
                    Some(used) if used <= rank => {}
                    Some(_) => {
                        wrong.push(format!("{}: {layer} uses crate::{name}", file.display()))
                    }
                    None => wrong.push(format!(
                        "{}: crate::{name} is not a layer (write its layer's path)",
                        file.display()
                    )),
                }
            }
        }
    }
    assert_eq!(
        files_seen,
        rust_files(&src).len() - 2,
        "every file but lib.rs and main.rs"
    );
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn the_check_sees_a_path_that_climbs() {
    assert_eq!(
        crate_paths("use crate::report::paper; /// [`crate::sim::stream`] $crate::x"),
        ["report", "sim"]
    );
}
