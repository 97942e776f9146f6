//! Every integration test of `spu-loader` in one test binary: each `.rs` file beside this one is a
//! module of it, so the build links one test binary instead of one per file
//! (`tests/tests/test_files.rs` checks that none is left out).

mod fuzz_regressions;
mod kernels_assemble;
mod spu_refit;
