//! The format of a kernel assembled at build time (`loader/build.rs`, which includes this
//! file too) and the hash of the sources it was assembled from: the runtime takes a
//! prebuilt program only when the sources it would assemble hash the same.
//!
//! Layout, little-endian: the sources' hash (u64), the entry (u32), the image's length
//! (u32) and bytes, the symbol count (u32), then each symbol's name length (u32), name
//! (UTF-8) and value (u32).

/// A kernel program: local-store image, entry point, symbols.
pub type Image = (Vec<u8>, u32, Vec<(String, u32)>);

/// FNV-1a over everything that decides a kernel's assembly: its name, source, defines and
/// include files (the last two in name order, so the order they are given in does not
/// matter).
pub fn sources_hash(
    name: &str,
    source: &str,
    defines: &[(&str, i64)],
    includes: &[(String, String)],
) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes.iter().chain(&[0xff]) {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    eat(name.as_bytes());
    eat(source.as_bytes());
    let mut defines: Vec<_> = defines.to_vec();
    defines.sort();
    for (d, v) in defines {
        eat(d.as_bytes());
        eat(&v.to_le_bytes());
    }
    let mut includes: Vec<&(String, String)> = includes.iter().collect();
    includes.sort();
    for (file, text) in includes {
        eat(file.as_bytes());
        eat(text.as_bytes());
    }
    h
}

pub fn encode(hash: u64, (image, entry, symbols): &Image) -> Vec<u8> {
    let mut out = Vec::with_capacity(image.len() + 64 * symbols.len() + 32);
    out.extend(hash.to_le_bytes());
    out.extend(entry.to_le_bytes());
    out.extend((image.len() as u32).to_le_bytes());
    out.extend(image);
    out.extend((symbols.len() as u32).to_le_bytes());
    for (name, value) in symbols {
        out.extend((name.len() as u32).to_le_bytes());
        out.extend(name.as_bytes());
        out.extend(value.to_le_bytes());
    }
    out
}

/// The hash and program of an encoded kernel; `None` for anything malformed (every length
/// checked against the bytes there are).
pub fn decode(bytes: &[u8]) -> Option<(u64, Image)> {
    let mut rest = bytes;
    let mut take = |n: usize| -> Option<&[u8]> {
        if rest.len() < n {
            return None;
        }
        let (part, after) = rest.split_at(n);
        rest = after;
        Some(part)
    };
    let hash = u64::from_le_bytes(take(8)?.try_into().ok()?);
    let entry = u32::from_le_bytes(take(4)?.try_into().ok()?);
    let len = u32::from_le_bytes(take(4)?.try_into().ok()?) as usize;
    let image = take(len)?.to_vec();
    let count = u32::from_le_bytes(take(4)?.try_into().ok()?) as usize;
    let mut symbols = Vec::with_capacity(count.min(bytes.len() / 8));
    for _ in 0..count {
        let n = u32::from_le_bytes(take(4)?.try_into().ok()?) as usize;
        let name = String::from_utf8(take(n)?.to_vec()).ok()?;
        let value = u32::from_le_bytes(take(4)?.try_into().ok()?);
        symbols.push((name, value));
    }
    rest.is_empty().then_some((hash, (image, entry, symbols)))
}
