//! The assembler never panics, whatever the source: it assembles or reports diagnostics.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(source) = std::str::from_utf8(data) {
        let _ = spu_asm::assemble(source, "fuzz.s", &spu_asm::Options::default());
    }
});
