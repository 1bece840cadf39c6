//! `include/bushing.h` is what cbindgen makes of the sources today:
//! regenerated and compared byte for byte (`BUSHING_BLESS=1` writes it).

use std::path::Path;

#[test]
fn the_committed_header_is_cbindgens_output() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let mut made = Vec::new();
    cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen reads the crate")
        .write(&mut made);
    let path = dir.join("include/bushing.h");
    if std::env::var_os("BUSHING_BLESS").is_some() {
        std::fs::write(&path, &made).expect("header written");
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    assert!(
        committed == made,
        "include/bushing.h is not cbindgen's output: regenerate it with \
         BUSHING_BLESS=1 cargo test -p bushing-c --test header"
    );
}
