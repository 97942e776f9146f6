//! The structure of an SPU ELF file checked the way GNU readelf reads it: the header, the
//! section and program header tables and every section's bytes lie inside the file, and
//! the indices between them are in range. Objects are checked as they are written (a
//! broken one is an error, never an output), and the tests run it on every object and
//! executable they produce.

/// Everything wrong with the layout of 32-bit big-endian ELF `data` (empty when sound).
pub fn layout_errors(data: &[u8]) -> Vec<String> {
    let mut errors = Vec::new();
    if data.len() < 52 || &data[..4] != b"\x7fELF" {
        return vec!["not an ELF file (no 52-byte ELF header)".into()];
    }
    if data[4] != 1 || data[5] != 2 {
        return vec!["not 32-bit big-endian ELF".into()];
    }
    let half = |at: usize| u16::from_be_bytes([data[at], data[at + 1]]) as u64;
    let word =
        |at: usize| u32::from_be_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]]) as u64;
    let len = data.len() as u64;
    let (phoff, shoff) = (word(28), word(32));
    let (phentsize, phnum) = (half(42), half(44));
    let (shentsize, shnum, shstrndx) = (half(46), half(48), half(50));
    if phnum > 0 {
        if phentsize != 32 {
            errors.push(format!("program header size {phentsize}, not 32"));
        } else if phoff + phnum * 32 > len {
            errors.push(format!(
                "program headers ({} bytes at {phoff:#x}) extend past the end of the file ({len} bytes)",
                phnum * 32
            ));
        } else {
            for i in 0..phnum {
                let at = (phoff + i * 32) as usize;
                let (offset, filesz) = (word(at + 4), word(at + 16));
                if offset + filesz > len {
                    errors.push(format!(
                        "segment {i} ({filesz} bytes at {offset:#x}) extends past the end of the file"
                    ));
                }
            }
        }
    }
    if shnum == 0 {
        return errors;
    }
    if shentsize != 40 {
        errors.push(format!("section header size {shentsize}, not 40"));
        return errors;
    }
    if shoff + shnum * 40 > len {
        errors.push(format!(
            "section headers ({} bytes at {shoff:#x}) extend past the end of the file ({len} bytes)",
            shnum * 40
        ));
        return errors;
    }
    if shstrndx >= shnum {
        errors.push(format!(
            "section name table index {shstrndx} of {shnum} sections"
        ));
    }
    for i in 1..shnum {
        let at = (shoff + i * 40) as usize;
        let (ty, offset, size, link) = (word(at + 4), word(at + 16), word(at + 20), word(at + 24));
        const SHT_NOBITS: u64 = 8;
        if ty != SHT_NOBITS && offset + size > len {
            errors.push(format!(
                "section {i} ({size} bytes at {offset:#x}) extends past the end of the file ({len} bytes)"
            ));
        }
        if ty == SHT_NOBITS && offset > len {
            errors.push(format!(
                "NOBITS section {i} at {offset:#x} is past the end of the file"
            ));
        }
        if link >= shnum {
            errors.push(format!("section {i} links to section {link} of {shnum}"));
        }
        // Relocation sections name their symbol table and the section they apply to.
        if ty == 4 || ty == 9 {
            let info = word(at + 28);
            if info == 0 || info >= shnum {
                errors.push(format!(
                    "relocation section {i} applies to section {info} of {shnum}"
                ));
            }
        }
    }
    errors
}

#[cfg(test)]
mod tests {
    use super::layout_errors;

    #[test]
    fn a_truncated_file_is_reported() {
        let src = ".section .bss\n.align 4\nbuf: .space 64\n";
        let (obj, _) = crate::assemble_object(src, "t.s", &Default::default()).unwrap();
        let elf = obj.to_elf().unwrap();
        assert_eq!(layout_errors(&elf), Vec::<String>::new());
        let cut = &elf[..elf.len() - 1];
        assert_eq!(layout_errors(cut).len(), 1, "{:?}", layout_errors(cut));
    }
}
