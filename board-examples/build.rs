//! Links the firmware binaries with cortex-m-rt's `link.x` and the workspace
//! memory map when building for a bare-metal target, and the rig loop with
//! defmt's `defmt.x`.
use std::{env, fs, path::PathBuf};

fn main() {
    if env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("none") {
        let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
        fs::copy("../memory.x", out.join("memory.x")).expect("memory.x at the workspace root");
        println!("cargo:rustc-link-search={}", out.display());
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
        // The defmt table (format strings), kept out of the image: the
        // host reads it from the ELF to decode the log.
        println!("cargo:rustc-link-arg-bin=rig-loop=-Tdefmt.x");
    }
    println!("cargo:rerun-if-changed=../memory.x");
}
