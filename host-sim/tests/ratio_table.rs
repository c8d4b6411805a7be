//! The Adams fixed-`c_max` ratio tables against direct integration at points off the table.

use host_sim::ratio_table::{class_residual, class_table, direct, needs_tables};
use host_sim::scene::load;

fn scene_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenes")
        .join(name)
}

#[test]
fn explore() {
    let scene = load(scene_path("paper_adams_fixed.toml")).expect("scene");
    assert!(needs_tables(&scene));
    for c in 0..scene.classes.len() {
        let t = class_table(&scene, c).expect("table");
        println!(
            "class {c} s {:?}\n F {:?}\n t {:?}",
            t.s_range, t.ln_force, t.ln_duration
        );
        println!("residual {:?}", class_residual(&scene, c, &t).expect("res"));
        for (r, u) in [
            (0.015, 1.0),
            (0.015, 5.0),
            (0.04, 1.0),
            (0.04, 5.0),
            (0.0245, 3.0),
        ] {
            let d = direct(&scene, c, r, u).unwrap();
            let (tf, tt) = t.at(r.ln(), f64::ln(u));
            println!(
                "R {r} u {u}: direct F {:.4} t {:.4} table F {:.4} t {:.4}",
                d.force.ln(),
                d.duration.ln(),
                tf,
                tt
            );
        }
    }
}
