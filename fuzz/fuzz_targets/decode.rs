//! Decoding and disassembling any word never panics, and a decoded word re-encodes to the
//! bits its form uses.
#![no_main]
use libfuzzer_sys::fuzz_target;
use spu_isa::codec::{decode, encode, operand_values, primary_form_of};
use spu_isa::disasm::{instruction_text, NoSymbols};

fuzz_target!(|data: &[u8]| {
    for chunk in data.chunks_exact(8) {
        let word = u32::from_be_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]);
        let pc = u32::from_be_bytes([chunk[4], chunk[5], chunk[6], chunk[7]]) & 0x3fffc;
        let inst = decode(word);
        let text = instruction_text(word, pc, &NoSymbols);
        assert!(!text.is_empty());
        if let Some(form) = primary_form_of(inst) {
            let again = encode(form, &operand_values(form, word, pc), pc);
            // Every bit the re-encoding sets was set in the word.
            assert_eq!(again & !word, 0, "{word:#010x} -> {again:#010x}");
        }
    }
});
