//! Build script: hands `memory.x` (the node's memory map, STM32F405 class) to the linker for
//! bare-metal (firmware) builds only. Host builds (tests, benches, host-sim) get nothing from
//! it.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=memory.x");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let out = match env::var_os("OUT_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => return,
    };
    let source = "memory.x";
    let memory = match fs::read(source) {
        Ok(bytes) => bytes,
        Err(e) => {
            println!("cargo:warning={source} not readable: {e}");
            return;
        }
    };
    if let Err(e) = fs::write(out.join("memory.x"), memory) {
        println!("cargo:warning=cannot copy memory.x to OUT_DIR: {e}");
        return;
    }
    println!("cargo:rustc-link-search={}", out.display());
}
