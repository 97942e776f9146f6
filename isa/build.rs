//! Decides once whether this build has the block compiler: the `jit` feature on a host
//! Cranelift generates code for (x86_64, aarch64). The sources test `cfg(block_compiler)`.

fn main() {
    println!("cargo::rustc-check-cfg=cfg(block_compiler)");
    let arch = std::env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    let jit = std::env::var_os("CARGO_FEATURE_JIT").is_some();
    if jit && matches!(arch.as_str(), "x86_64" | "aarch64") {
        println!("cargo::rustc-cfg=block_compiler");
    }
}
