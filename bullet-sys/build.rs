//! Finds Debian's double-precision Bullet through pkg-config, compiles the C++ shim in `shim/` and
//! generates bindings for the shim's own C header (nothing of Bullet's C++ reaches Rust).

use std::env;
use std::path::PathBuf;

/// Bullet versions (pkg-config `bullet-float64`) on which the parity tests showed bit-identical results
/// with pybullet 3.2.7: Debian's libbullet-dev 3.24+dfsg-2 (bookworm and trixie). Other versions build,
/// with a warning; `bash scripts/test` then says whether parity holds there. See docs/parity.md.
const BIT_EXACT_VERSIONS: &[&str] = &["3.24"];

const INSTALL_HINT: &str =
    "Bullet (double precision) was not found through pkg-config `bullet-float64`.\n\
     Install it with: sudo apt-get install libbullet-dev pkg-config\n\
     (bindgen also needs libclang: sudo apt-get install libclang-dev)";

/// The shim's sources, by concern: the C API with the world and its bodies, URDF import, the skin-friction
/// solver.
const SOURCES: &[&str] = &[
    "shim/snake_shim.cpp",
    "shim/shim_urdf.cpp",
    "shim/shim_skin.cpp",
];

/// The shim's headers: the FFI contract that bindgen reads, and what the sources share.
const HEADERS: &[&str] = &["shim/snake_shim.h", "shim/shim_internal.h"];

fn main() {
    for path in HEADERS.iter().chain(SOURCES) {
        println!("cargo:rerun-if-changed={path}");
    }
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");

    // Double precision is what pybullet is built with; the single-precision `bullet.pc` diverges.
    let bullet = match pkg_config::Config::new()
        .atleast_version("3.24")
        .probe("bullet-float64")
    {
        Ok(lib) => lib,
        Err(err) => {
            eprintln!("{INSTALL_HINT}\n(pkg-config said: {err})");
            panic!("{INSTALL_HINT}");
        }
    };

    if !BIT_EXACT_VERSIONS.contains(&bullet.version.as_str()) {
        println!(
            "cargo:warning=Bullet {} found; bit parity with pybullet 3.2.7 is established for Bullet {} \
             only and unverified on this version (the parity tests in `bash scripts/test` will tell)",
            bullet.version,
            BIT_EXACT_VERSIONS.join(", ")
        );
    }

    let mut build = cc::Build::new();
    build
        .cpp(true)
        // The shim is on the hot path of every step; optimise it even in debug builds.
        .opt_level(2)
        .files(SOURCES)
        .flag_if_supported("-std=c++14")
        // Bit-for-bit agreement with pybullet needs IEEE arithmetic in the exact order written:
        // no contraction into FMA, no fast-math.
        .flag_if_supported("-ffp-contract=off")
        .flag_if_supported("-fno-fast-math")
        .warnings(false);
    for path in &bullet.include_paths {
        build.include(path);
    }
    for (key, value) in &bullet.defines {
        build.define(key, value.as_deref());
    }
    build.compile("snake_shim");

    let bindings = bindgen::Builder::default()
        .header("shim/snake_shim.h")
        .allowlist_function("ss_.*")
        .allowlist_type("ss_.*")
        .allowlist_var("SS_.*")
        .derive_default(true)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()))
        .generate()
        .expect("bindgen could not parse shim/snake_shim.h (is libclang-dev installed?)");
    let out = PathBuf::from(env::var("OUT_DIR").expect("OUT_DIR is set by cargo"));
    bindings
        .write_to_file(out.join("bindings.rs"))
        .expect("could not write bindings.rs");
}
