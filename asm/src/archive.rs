//! Static libraries (`.a`): the GNU `ar` format that `spu ar` writes and `spu ld` searches,
//! so that SPU objects can be shipped and linked as the Cell SDK's libraries were.
//!
//! The layout is GNU ar's: the magic `!<arch>\n`, then members, each a 60-byte header
//! (name, date, uid, gid, mode, size in ASCII, then "`\n") followed by its contents padded
//! to an even length with `\n`. The first member, named `/`, is the symbol index: a
//! big-endian count, one big-endian file offset (of a member's header) per symbol, then
//! the symbols' names, NUL-terminated. A member named `//` holds the names longer than 15
//! bytes, each ended by "/\n"; such a member's name is `/` and the decimal offset of its
//! name there. Short names end with `/`. Headers are written as GNU ar's deterministic
//! mode (`D`, the default of current binutils) writes them: date, uid and gid 0, mode 644.

use crate::object::{Object, SymSection};

/// The archive's magic.
pub const MAGIC: &[u8; 8] = b"!<arch>\n";
const HEADER: usize = 60;

/// One object of an archive.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Member {
    /// Its file name (without directories).
    pub name: String,
    pub data: Vec<u8>,
}

/// An archive: its members in order and its symbol index.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Archive {
    pub members: Vec<Member>,
    /// (symbol, index in `members` of the member that defines it), in index order.
    pub index: Vec<(String, usize)>,
}

/// Whether `bytes` start as an archive does.
pub fn is_archive(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
}

/// The symbols a member defines for the index, as GNU ar lists them: the global and weak
/// symbols defined in a section, absolute or common, in the member's symbol-table order.
/// A member that is not an SPU object defines none (GNU ar keeps such members too).
pub fn defined_symbols(member: &Member) -> Vec<String> {
    match Object::from_elf(&member.name, &member.data) {
        Ok(o) => o
            .symbols
            .iter()
            .filter(|s| s.global && s.section != SymSection::Undefined && !s.name.is_empty())
            .map(|s| s.name.clone())
            .collect(),
        Err(_) => Vec::new(),
    }
}

impl Archive {
    /// An archive of `members` with the index GNU ar builds for them.
    pub fn new(members: Vec<Member>) -> Archive {
        let mut a = Archive {
            members,
            index: Vec::new(),
        };
        a.rebuild_index();
        a
    }

    /// Rebuilds the symbol index from the members (`ar s`).
    pub fn rebuild_index(&mut self) {
        self.index = self
            .members
            .iter()
            .enumerate()
            .flat_map(|(i, m)| defined_symbols(m).into_iter().map(move |s| (s, i)))
            .collect();
    }

    /// Adds `member`, replacing a member of the same name in place (`ar r`).
    pub fn replace(&mut self, member: Member) {
        match self.members.iter_mut().find(|m| m.name == member.name) {
            Some(m) => *m = member,
            None => self.members.push(member),
        }
    }

    /// Reads an archive; `name` is for messages. Every size and offset is checked.
    pub fn read(name: &str, bytes: &[u8]) -> Result<Archive, String> {
        if !is_archive(bytes) {
            return Err(format!("{name}: not an archive (no !<arch> magic)"));
        }
        let mut pos = MAGIC.len();
        let mut raw_index: Option<&[u8]> = None;
        let mut long_names: &[u8] = &[];
        let mut members = Vec::new();
        // Header offset of each member, to resolve the index.
        let mut offsets = Vec::new();
        while pos < bytes.len() {
            if bytes.len() - pos < HEADER {
                return Err(format!(
                    "{name}: truncated member header at offset {pos} ({} bytes left)",
                    bytes.len() - pos
                ));
            }
            let h = &bytes[pos..pos + HEADER];
            if &h[58..60] != b"`\n" {
                return Err(format!("{name}: bad member header at offset {pos}"));
            }
            let size_field = std::str::from_utf8(&h[48..58]).unwrap_or("").trim();
            let size: usize = size_field
                .parse()
                .map_err(|_| format!("{name}: bad member size {size_field:?} at offset {pos}"))?;
            let start = pos + HEADER;
            if size > bytes.len() - start {
                return Err(format!(
                    "{name}: member at offset {pos} claims {size} bytes, past the end of the \
                     archive ({} bytes left)",
                    bytes.len() - start
                ));
            }
            let data = &bytes[start..start + size];
            let raw_name = std::str::from_utf8(&h[..16])
                .map_err(|_| format!("{name}: member name at offset {pos} is not text"))?
                .trim_end();
            match raw_name {
                "/" if members.is_empty() && raw_index.is_none() => raw_index = Some(data),
                "//" => long_names = data,
                _ => {
                    let member_name = if let Some(n) = raw_name.strip_suffix('/') {
                        n.to_string()
                    } else if let Some(off) = raw_name.strip_prefix('/') {
                        long_name(long_names, off)
                            .ok_or_else(|| format!("{name}: bad long name {raw_name:?}"))?
                    } else {
                        raw_name.to_string()
                    };
                    offsets.push(pos);
                    members.push(Member {
                        name: member_name,
                        data: data.to_vec(),
                    });
                }
            }
            pos = start + size + (size & 1);
        }
        let mut index = Vec::new();
        if let Some(raw) = raw_index {
            let bad = |why: &str| format!("{name}: bad symbol index: {why}");
            if raw.len() < 4 {
                return Err(bad("shorter than its count"));
            }
            let count = u32::from_be_bytes(raw[..4].try_into().unwrap()) as usize;
            let names_at = count
                .checked_mul(4)
                .and_then(|n| n.checked_add(4))
                .filter(|&n| n <= raw.len())
                .ok_or_else(|| bad(&format!("{count} symbols do not fit its size")))?;
            let mut names = raw[names_at..].split(|&b| b == 0);
            for k in 0..count {
                let off = u32::from_be_bytes(raw[4 + 4 * k..8 + 4 * k].try_into().unwrap());
                let member = offsets
                    .iter()
                    .position(|&o| o == off as usize)
                    .ok_or_else(|| bad(&format!("offset {off} is not a member's header")))?;
                let sym = names
                    .next()
                    .filter(|s| !s.is_empty())
                    .ok_or_else(|| bad(&format!("{count} symbols but fewer names")))?;
                let sym = String::from_utf8(sym.to_vec()).map_err(|_| bad("a name not text"))?;
                index.push((sym, member));
            }
        }
        Ok(Archive { members, index })
    }

    /// The archive in GNU ar's format (deterministic headers, index first, long names next).
    pub fn write(&self) -> Vec<u8> {
        let mut long = Vec::new();
        let mut names = Vec::new();
        for m in &self.members {
            if m.name.len() > 15 || m.name.contains('/') || m.name.contains(' ') {
                names.push(format!("/{}", long.len()));
                long.extend(m.name.as_bytes());
                long.extend(b"/\n");
            } else {
                names.push(format!("{}/", m.name));
            }
        }
        let padded = |n: usize| n + (n & 1);
        let index_size =
            4 + 4 * self.index.len() + self.index.iter().map(|s| s.0.len() + 1).sum::<usize>();
        let mut at = MAGIC.len();
        if !self.index.is_empty() {
            at += HEADER + padded(index_size);
        }
        if !long.is_empty() {
            at += HEADER + padded(long.len());
        }
        let mut offsets = Vec::new();
        for m in &self.members {
            offsets.push(at as u32);
            at += HEADER + padded(m.data.len());
        }
        let mut out = MAGIC.to_vec();
        if !self.index.is_empty() {
            let mut raw = (self.index.len() as u32).to_be_bytes().to_vec();
            for (_, m) in &self.index {
                raw.extend(offsets[*m].to_be_bytes());
            }
            for (s, _) in &self.index {
                raw.extend(s.as_bytes());
                raw.push(0);
            }
            push_member(&mut out, "/", "0", &raw);
        }
        if !long.is_empty() {
            push_member(&mut out, "//", "", &long);
        }
        for (m, n) in self.members.iter().zip(&names) {
            push_member(&mut out, n, "644", &m.data);
        }
        out
    }
}

/// The name at `off` (decimal) in the long-names member, ended by "/\n".
fn long_name(table: &[u8], off: &str) -> Option<String> {
    let off: usize = off.parse().ok()?;
    let rest = table.get(off..)?;
    let end = rest.windows(2).position(|w| w == b"/\n")?;
    String::from_utf8(rest[..end].to_vec()).ok()
}

/// Appends one member: header (GNU ar's fields; the long-names member has no date, ids or
/// mode) then contents, padded to an even length.
fn push_member(out: &mut Vec<u8>, name: &str, mode: &str, data: &[u8]) {
    let plain = name != "//";
    let num = |v: &'static str| if plain { v } else { "" };
    let header = format!(
        "{name:<16}{:<12}{:<6}{:<6}{mode:<8}{:<10}`\n",
        num("0"),
        num("0"),
        num("0"),
        data.len()
    );
    out.extend(header.as_bytes());
    out.extend(data);
    if data.len() % 2 == 1 {
        out.push(b'\n');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Archive {
        Archive {
            members: vec![
                Member {
                    name: "a.o".into(),
                    data: b"abc".to_vec(),
                },
                Member {
                    name: "a_rather_long_member_name.o".into(),
                    data: b"defg".to_vec(),
                },
            ],
            index: vec![("f".into(), 0), ("g".into(), 1), ("h".into(), 1)],
        }
    }

    #[test]
    fn round_trip_with_long_names_and_index() {
        let a = sample();
        let bytes = a.write();
        assert_eq!(Archive::read("t.a", &bytes).unwrap(), a);
        // The index's offsets are the members' header offsets: 8 + index (60 + 4 + 12 + 6)
        // + long names (60 + 30) = 180 for the first member.
        assert_eq!(&bytes[8 + 60 + 4..8 + 60 + 8], &180u32.to_be_bytes());
        assert_eq!(&bytes[180..196], b"a.o/            ");
        assert_eq!(&bytes[180 + 40..180 + 60], b"644     3         `\n");
        // Odd contents are padded with a newline.
        assert_eq!(bytes[180 + 63], b'\n');
        assert_eq!(&bytes[180 + 64..180 + 68], b"/0  ");
    }

    #[test]
    fn truncated_and_oversized_members_and_bad_indexes_are_errors() {
        let bytes = sample().write();
        let e = Archive::read("t.a", &bytes[..bytes.len() - 2]).unwrap_err();
        assert!(e.contains("past the end of the archive"), "{e}");
        let e = Archive::read("t.a", &bytes[..bytes.len() - 64 - 5]).unwrap_err();
        assert!(e.contains("truncated member header"), "{e}");
        let mut bad = bytes.clone();
        bad[8 + 60 + 4..8 + 60 + 8].copy_from_slice(&7u32.to_be_bytes());
        let e = Archive::read("t.a", &bad).unwrap_err();
        assert_eq!(
            e,
            "t.a: bad symbol index: offset 7 is not a member's header"
        );
        let mut bad = bytes.clone();
        bad[8 + 60..8 + 64].copy_from_slice(&1000u32.to_be_bytes());
        let e = Archive::read("t.a", &bad).unwrap_err();
        assert_eq!(e, "t.a: bad symbol index: 1000 symbols do not fit its size");
        assert!(Archive::read("t.a", b"!<arch>").is_err());
        assert_eq!(Archive::read("t.a", MAGIC).unwrap(), Archive::default());
    }
}
