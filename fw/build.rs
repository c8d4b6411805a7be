//! Build script of the firmware: hands the node's memory map to the linker. The map is the
//! repository's top-level `memory.x` (STM32F405 class: 1 MiB flash, 128 KiB RAM), copied to
//! `OUT_DIR`, which goes on this package's link search path; cortex-m-rt's `link.x` includes it.
//! Only the binaries of this package link it: the `coalshock` kernel has no build script, so a
//! firmware that depends on it brings its own `memory.x`.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let source = "../memory.x";
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed={source}");
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let memory = fs::read(source).expect("the node's memory map ../memory.x");
    fs::write(out.join("memory.x"), memory).expect("memory.x copied to OUT_DIR");
    println!("cargo:rustc-link-search={}", out.display());
}
