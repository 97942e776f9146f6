//! Every integration test of `spu-asm` in one test binary: each `.rs` file beside this one is a
//! module of it, so the build links one test binary instead of one per file
//! (`tests/tests/test_files.rs` checks that none is left out).

mod debug_line;
mod eh_frame;
mod gas_elf;
mod gnu_compat;
mod gnu_generic;
mod gnu_objects;
mod gnu_quirks;
mod never_panics;
mod objects_and_limits;
mod pcrel_differences;
mod sched;
