//! Finds the references the differential tests compare with, so that a test whose
//! reference is absent shows as ignored, saying why, instead of passing without comparing
//! anything (`#[cfg_attr(not(has_binutils), ignore = "...")]`):
//!
//! - `cfg(has_binutils)` and `SPU_ELF_AS` (its path): GNU as for SPU, where
//!   `scripts/build-spu-binutils.sh` installs it (`$SPU_BINUTILS/bin`,
//!   `~/.local/spu-binutils/bin`) or on `PATH` (`tests/gnu_differential.rs`);
//! - `cfg(has_ld_spu_testsuite)` and `SPU_LD_TESTSUITE_DIR`: binutils' own
//!   `ld/testsuite/ld-spu` sources, which the script installs beside it
//!   (`share/spu-binutils-testsuite/ld-spu`) or `SPU_LD_TESTSUITE` names
//!   (`tests/gnu_ld_differential.rs`);
//! - `cfg(has_gas_testsuite)` and `SPU_GAS_TESTSUITE_ROOT`: gas's own testsuite
//!   directories (`gas/testsuite/gas/{all,elf,macros}`), which the script installs
//!   beside it (`share/spu-binutils-testsuite/gas`) or `SPU_GAS_TESTSUITE_ROOT` names
//!   (`tests/gnu_differential.rs`);
//! - `cfg(has_shared_scenes)`: the scene files beside the repository,
//!   `<repo>/../shared/scenes`, where `spu_loader::scene::shared_scenes_dir` looks
//!   (`tests/shared_scenes.rs`). Only whether the directory is there is looked at; nothing
//!   of it is read by the build.
//!
//! All are looked for again when `SPU_BINUTILS`, `SPU_LD_TESTSUITE`,
//! `SPU_GAS_TESTSUITE_ROOT`, `HOME` or `PATH` changes or the program
//! found changes; a reference that appears otherwise is seen after
//! `cargo clean -p spu-tests`.

use std::path::{Path, PathBuf};

fn main() {
    println!("cargo::rustc-check-cfg=cfg(has_binutils)");
    println!("cargo::rustc-check-cfg=cfg(has_ld_spu_testsuite)");
    println!("cargo::rustc-check-cfg=cfg(has_shared_scenes)");
    println!("cargo::rustc-check-cfg=cfg(has_gas_testsuite)");
    for var in [
        "SPU_BINUTILS",
        "SPU_LD_TESTSUITE",
        "SPU_GAS_TESTSUITE_ROOT",
        "HOME",
        "PATH",
    ] {
        println!("cargo::rerun-if-env-changed={var}");
    }
    println!("cargo::rerun-if-changed=build.rs");
    let mut dirs: Vec<PathBuf> = Vec::new();
    if let Some(p) = std::env::var_os("SPU_BINUTILS") {
        dirs.push(Path::new(&p).join("bin"));
    }
    if let Some(h) = std::env::var_os("HOME") {
        dirs.push(Path::new(&h).join(".local/spu-binutils/bin"));
    }
    if let Some(path) = std::env::var_os("PATH") {
        dirs.extend(std::env::split_paths(&path));
    }
    if let Some(gas) = dirs
        .into_iter()
        .map(|d| d.join("spu-elf-as"))
        .find(|p| p.is_file())
    {
        println!("cargo::rerun-if-changed={}", gas.display());
        println!("cargo::rustc-cfg=has_binutils");
        println!("cargo::rustc-env=SPU_ELF_AS={}", gas.display());
        let installed = gas
            .parent()
            .and_then(Path::parent)
            .map(|prefix| prefix.join("share/spu-binutils-testsuite"))
            .unwrap_or_default();
        let gas_suite = std::env::var_os("SPU_GAS_TESTSUITE_ROOT")
            .map(PathBuf::from)
            .unwrap_or(installed.join("gas"));
        if gas_suite.join("all").is_dir() {
            println!("cargo::rerun-if-changed={}", gas_suite.display());
            println!("cargo::rustc-cfg=has_gas_testsuite");
            println!(
                "cargo::rustc-env=SPU_GAS_TESTSUITE_ROOT={}",
                gas_suite.display()
            );
        }
        let beside = installed.join("ld-spu");
        let suite = std::env::var_os("SPU_LD_TESTSUITE")
            .map(PathBuf::from)
            .unwrap_or(beside);
        if suite.is_dir() {
            println!("cargo::rerun-if-changed={}", suite.display());
            println!("cargo::rustc-cfg=has_ld_spu_testsuite");
            println!("cargo::rustc-env=SPU_LD_TESTSUITE_DIR={}", suite.display());
        }
    }
    let manifest = std::env::var_os("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR");
    if Path::new(&manifest).join("../../shared/scenes").is_dir() {
        println!("cargo::rustc-cfg=has_shared_scenes");
    }
}
