//! A program image ready to load into a context, and every check that keeps a run from
//! misusing its input: an ELF whose segments leave local store or overlap, an empty file,
//! a text file handed over as a raw image. Each is refused here, before anything runs.

use crate::elf::read_elf;
use crate::ppe::start::LS_SIZE;
use std::fmt;
use std::path::Path;

/// Why a program cannot be loaded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadError(pub String);

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for LoadError {}

/// The largest program file [`Program::from_file`] reads: far more than local store holds,
/// so that ELF files with symbols and debug sections fit.
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// A program's local-store contents, entry point and symbols.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Program {
    /// `(local-store address, bytes)`, each inside local store, none overlapping.
    pub segments: Vec<(u32, Vec<u8>)>,
    /// Where it starts.
    pub entry: u32,
    /// Its symbols: `(name, value)` (none for a raw image).
    pub symbols: Vec<(String, u32)>,
    /// For a program with overlays: the whole ELF file, which the loader puts in main
    /// memory for the overlay manager to DMA the overlays from (as libspe2 does), and
    /// where `_EAR_` is, which receives its effective address.
    pub overlay_image: Option<(Vec<u8>, u32)>,
}

impl Program {
    /// An SPU ELF executable, its segments checked against local store and each other.
    pub fn from_elf(bytes: &[u8]) -> Result<Program, LoadError> {
        if bytes.is_empty() {
            return Err(LoadError("an empty file: nothing to run".into()));
        }
        let elf = read_elf(bytes).map_err(LoadError)?;
        // e_type: only an executable has its addresses settled; an object's are not.
        match bytes.get(16..18).map(|t| u16::from_be_bytes([t[0], t[1]])) {
            Some(2) => {}
            Some(1) => {
                return Err(LoadError(
                    "a relocatable object, not an SPU program: link it first (spu ld OBJ.o \
                     -o PROG)"
                        .into(),
                ))
            }
            other => {
                return Err(LoadError(format!(
                    "ELF type {} is not an executable (ET_EXEC)",
                    other.unwrap_or(0)
                )))
            }
        }
        let mut spans: Vec<(u64, u64)> = Vec::new();
        for (addr, data) in &elf.segments {
            let (start, end) = (*addr as u64, *addr as u64 + data.len() as u64);
            if end > LS_SIZE as u64 {
                return Err(LoadError(format!(
                    "segment at {addr:#x} of {} bytes lies outside local store (0..{LS_SIZE:#x})",
                    data.len()
                )));
            }
            if let Some((s, e)) = spans.iter().find(|(s, e)| start < *e && *s < end) {
                return Err(LoadError(format!(
                    "segment at {start:#x}..{end:#x} overlaps the segment at {s:#x}..{e:#x}"
                )));
            }
            spans.push((start, end));
        }
        if elf.entry >= LS_SIZE {
            return Err(LoadError(format!(
                "entry point {:#x} lies outside local store (0..{LS_SIZE:#x})",
                elf.entry
            )));
        }
        let overlay_image = match elf.overlays {
            0 => None,
            _ => match elf.symbols.iter().find(|s| s.0 == "_EAR_") {
                Some(&(_, ear)) if ear <= LS_SIZE - 16 => Some((bytes.to_vec(), ear)),
                _ => {
                    return Err(LoadError(
                        "overlay segments, but no `_EAR_' in local store for the overlay                          manager to find the image by (link it with spu ld -T)"
                            .into(),
                    ))
                }
            },
        };
        Ok(Program {
            segments: elf.segments,
            entry: elf.entry,
            symbols: elf.symbols,
            overlay_image,
        })
    }

    /// A raw local-store image loaded at 0 and started at 0. Refused: an empty one, one
    /// larger than local store, and one that looks like text (a source, not machine code).
    pub fn from_raw(bytes: &[u8]) -> Result<Program, LoadError> {
        if bytes.is_empty() {
            return Err(LoadError("an empty file: nothing to run".into()));
        }
        if bytes.len() > LS_SIZE as usize {
            return Err(LoadError(format!(
                "{} bytes do not fit the 256 KiB local store",
                bytes.len()
            )));
        }
        if looks_like_text(bytes) {
            return Err(LoadError(
                "a text file, not an SPU program: assemble it first, or name it .s".into(),
            ));
        }
        Ok(Program {
            segments: vec![(0, bytes.to_vec())],
            entry: 0,
            symbols: Vec::new(),
            overlay_image: None,
        })
    }

    /// An ELF executable (by its magic number) or else a raw image.
    pub fn from_bytes(bytes: &[u8]) -> Result<Program, LoadError> {
        if bytes.starts_with(b"\x7fELF") {
            Program::from_elf(bytes)
        } else {
            Program::from_raw(bytes)
        }
    }

    /// The file at `path`, as [`Program::from_bytes`] reads it; a name that says it is a
    /// source (`.asm`, `.S`) is refused before reading. Errors name the file.
    pub fn from_file(path: &Path) -> Result<Program, LoadError> {
        let name = path.display();
        if path
            .extension()
            .is_some_and(|e| e == "asm" || e == "S" || e == "s")
        {
            return Err(LoadError(format!(
                "{name}: an assembly source, not an SPU program: assemble it first, or name \
                 it .s"
            )));
        }
        let bytes = read_limited(path, MAX_FILE_BYTES)?;
        Program::from_bytes(&bytes).map_err(|e| LoadError(format!("{name}: {e}")))
    }

    /// Where the program's code and data end: the first byte above every segment.
    pub fn end(&self) -> u32 {
        self.segments
            .iter()
            .map(|(a, d)| a + d.len() as u32)
            .max()
            .unwrap_or(0)
    }
}

/// Reads a file of at most `limit` bytes (checked while reading, so a file that grows or a
/// device that never ends cannot exhaust memory).
fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, LoadError> {
    use std::io::Read;
    let name = path.display();
    let file = std::fs::File::open(path).map_err(|e| LoadError(format!("{name}: {e}")))?;
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| LoadError(format!("{name}: {e}")))?;
    if bytes.len() as u64 > limit {
        return Err(LoadError(format!(
            "{name}: larger than the {limit}-byte limit for a program"
        )));
    }
    Ok(bytes)
}

/// Whether `bytes` read as text: UTF-8 without NULs or control characters other than
/// whitespace. SPU machine code almost always holds a zero byte (`stop`, `il`, small
/// immediates), so a program is not mistaken for text.
pub fn looks_like_text(bytes: &[u8]) -> bool {
    std::str::from_utf8(bytes).is_ok_and(|text| {
        text.chars()
            .all(|c| !c.is_control() || matches!(c, '\n' | '\r' | '\t' | '\x0c'))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_refused_and_code_is_not() {
        let err = Program::from_raw(b"start:\n\tstop 0x2000\n").unwrap_err();
        assert_eq!(
            err.0,
            "a text file, not an SPU program: assemble it first, or name it .s"
        );
        // `stop 0x2000`: 00 00 20 00.
        let p = Program::from_raw(&[0, 0, 0x20, 0]).unwrap();
        assert_eq!(p.segments, vec![(0, vec![0, 0, 0x20, 0])]);
        assert_eq!(p.end(), 4);
    }

    #[test]
    fn empty_and_oversized_images_are_refused() {
        assert_eq!(
            Program::from_bytes(&[]).unwrap_err().0,
            "an empty file: nothing to run"
        );
        assert_eq!(
            Program::from_raw(&vec![0; 0x40001]).unwrap_err().0,
            "262145 bytes do not fit the 256 KiB local store"
        );
    }
}
