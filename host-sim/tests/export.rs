//! The node's scenes (`fw/replay/src/scenes/`) are what `host-sim export` writes from the
//! shipped scene files, and compiled they build the kernel scene host-sim builds from each
//! file (`fw/stream.sh --check` and the `node_replay` example check the same in CI).

use coalshock::math::DefaultBackend;
use host_sim::export::scene_source;
use host_sim::kernel_scene::scene_to_kernel;

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn node_scenes_are_the_exported_scene_files() {
    for name in ["paper", "piezo_chain", "paper_yield"] {
        let file = host_sim::scene::load(root().join(format!("scenes/{name}.toml"))).unwrap();
        let text = scene_source(&file, &format!("scenes/{name}.toml")).unwrap();
        let shipped =
            std::fs::read_to_string(root().join(format!("fw/replay/src/scenes/{name}.rs")))
                .unwrap();
        assert_eq!(
            text, shipped,
            "fw/replay/src/scenes/{name}.rs: run fw/stream.sh"
        );
    }
}

#[test]
fn compiled_node_scenes_equal_host_sim_scenes() {
    let load = |name: &str| {
        let file = host_sim::scene::load(root().join(format!("scenes/{name}.toml"))).unwrap();
        scene_to_kernel(&file).unwrap()
    };
    assert_eq!(
        coalshock_replay::scenes::paper::scene::<DefaultBackend>().unwrap(),
        load("paper")
    );
    assert_eq!(
        coalshock_replay::scenes::piezo_chain::scene::<DefaultBackend>().unwrap(),
        load("piezo_chain")
    );
    assert_eq!(
        coalshock_replay::scenes::paper_yield::scene::<DefaultBackend>().unwrap(),
        load("paper_yield")
    );
}

/// `export --out DIR/x.rs` creates a missing `DIR`, as `stream --out` does, and writes there
/// what it would print (its header names the scene by the file name of an absolute path).
#[test]
fn export_creates_the_output_directory() {
    let dir = std::env::temp_dir().join(format!("coalshock-export-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.join("nested").join("paper.rs");
    let scene = root().join("scenes/paper.toml");
    host_sim::export::run(&scene, Some(&out)).unwrap();
    let written = std::fs::read_to_string(&out).unwrap();
    let file = host_sim::scene::load(&scene).unwrap();
    assert_eq!(written, scene_source(&file, "paper.toml").unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}
