//! The ELF reader never panics or over-allocates, whatever the bytes, and what it returns
//! can be loaded into an SPU and disassembled as `spu run` and `spu dis` do.
#![no_main]
use libfuzzer_sys::fuzz_target;

thread_local! {
    static SPU: std::cell::RefCell<spu_isa::machine::Spu> =
        std::cell::RefCell::new(spu_isa::machine::Spu::new(0));
}

fuzz_target!(|data: &[u8]| {
    if let Ok(elf) = spu_spe::elf::read_elf(data) {
        let segments: Vec<(u32, &[u8])> = elf
            .segments
            .iter()
            .map(|(a, d)| (*a, d.as_slice()))
            .collect();
        // One SPU for every input: building one per input costs more than the rest.
        SPU.with(|spu| spu.borrow_mut().load_segments(&segments, elf.entry));
        let symbols = spu_isa::disasm::SymbolTable::new(
            elf.symbols.iter().map(|(n, a)| (*a, n.clone())).collect(),
        );
        for (_, addr, bytes, code) in &elf.sections {
            if *code {
                let _ = spu_isa::disasm::listing(bytes, *addr, &symbols);
            }
        }
    }
});
