//! Every integration test of `spu-tests` in one test binary: each `.rs` file beside this one is a
//! module of it, so the build links one test binary instead of one per file
//! (`tests/tests/test_files.rs` checks that none is left out).

mod asm_files;
mod asm_kernels;
mod core_events;
mod core_mfc;
mod core_robustness;
mod core_semantics;
mod core_snapshots;
mod engines_differential;
mod frame_cycles;
mod gnu_differential;
mod gnu_ld_differential;
mod golden_forms;
mod isa_extensions;
mod kernel_caches;
mod kernel_modules;
mod memory_model;
mod reflect_module;
mod runtime_frames;
mod sched_timing;
mod shade_module;
mod shaded_frames;
mod shadow_module;
mod shared_scenes;
mod test_files;
mod timing_extremes;
mod timing_memo_core;
mod timing_model;
mod timing_speed;
mod timing_static;
