//! GNU as source syntax below the statement level, the assembler's and `spu sched`'s one
//! reading of it (gas's `input-scrub.c` and the lexing half of `read.c`): comments (`#` to
//! the end of a line, `/* */` across lines, neither inside a string), strings and their
//! escapes, splitting at top-level separators, and source files read as gas reads them
//! (each byte one character).

/// A source line, with where it came from (for diagnostics).
#[derive(Clone, Debug)]
pub(crate) struct Line {
    pub text: String,
    pub file: String,
    pub line: usize,
}

/// Splits a line at its comment: the code, with single-line `/* */` comments blanked to a
/// space, and the text after a `#` that starts a comment. A `#` or `/*` inside a string is
/// string, not comment.
pub(crate) fn split_comment(s: &str) -> (String, Option<&str>) {
    let mut out = String::new();
    let mut chars = s.char_indices().peekable();
    let mut in_str = false;
    while let Some((i, c)) = chars.next() {
        if in_str {
            out.push(c);
            if c == '\\' {
                if let Some((_, n)) = chars.next() {
                    out.push(n);
                }
            } else if c == '"' {
                in_str = false;
            }
            continue;
        }
        match c {
            '"' => {
                in_str = true;
                out.push(c);
            }
            '#' => return (out, Some(&s[i + 1..])),
            '/' if chars.peek().map(|p| p.1) == Some('*') => {
                chars.next();
                let mut prev = ' ';
                for (_, d) in chars.by_ref() {
                    if prev == '*' && d == '/' {
                        break;
                    }
                    prev = d;
                }
                out.push(' ');
            }
            _ => out.push(c),
        }
    }
    (out, None)
}

/// Removes comments: `#` to end of line (outside strings) and `/* */` (single line).
pub(crate) fn strip_comment(s: &str) -> String {
    split_comment(s).0
}

/// Splits on `sep` at nesting depth 0 (parentheses) outside strings.
pub(crate) fn split_top(s: &str, sep: char) -> Vec<String> {
    let mut parts = Vec::new();
    let mut depth = 0i32;
    let mut cur = String::new();
    let mut in_str = false;
    for c in s.chars() {
        if in_str {
            cur.push(c);
            if c == '"' {
                in_str = false;
            }
            continue;
        }
        match c {
            '"' => {
                in_str = true;
                cur.push(c)
            }
            '(' | '[' => {
                depth += 1;
                cur.push(c)
            }
            ')' | ']' => {
                depth -= 1;
                cur.push(c)
            }
            c if c == sep && depth == 0 => parts.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    parts.push(cur);
    parts
}

/// The bytes of a double-quoted string with gas's escapes; `None` if it is not one.
pub(crate) fn unquote(s: &str) -> Option<Vec<u8>> {
    let inner = s.strip_prefix('"')?.strip_suffix('"')?;
    let mut out = Vec::new();
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        if c != '\\' {
            // Source characters are bytes (see `bytes_as_text`).
            out.push(c as u32 as u8);
            continue;
        }
        match chars.next()? {
            'n' => out.push(b'\n'),
            't' => out.push(b'\t'),
            'r' => out.push(b'\r'),
            'b' => out.push(8),
            'f' => out.push(12),
            '\\' => out.push(b'\\'),
            '"' => out.push(b'"'),
            // \xHH...: hex digits, the low byte kept (as GNU as does).
            'x' | 'X' => {
                let mut v: u32 = 0;
                while let Some(d) = chars.peek().and_then(|c| c.to_digit(16)) {
                    v = v.wrapping_mul(16).wrapping_add(d);
                    chars.next();
                }
                out.push(v as u8);
            }
            // \NNN: up to three octal digits.
            d @ '0'..='7' => {
                let mut v = d.to_digit(8).unwrap_or(0);
                for _ in 0..2 {
                    match chars.peek().and_then(|c| c.to_digit(8)) {
                        Some(n) => {
                            v = v * 8 + n;
                            chars.next();
                        }
                        None => break,
                    }
                }
                out.push(v as u8);
            }
            other => out.push(other as u8),
        }
    }
    Some(out)
}

/// A line's first word, lower-cased, comments removed: what names a directive or an
/// instruction (ended by white space or a comma).
pub(crate) fn first_word(text: &str) -> String {
    strip_comment(text)
        .trim()
        .split(|c: char| c.is_whitespace() || c == ',')
        .next()
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Blanks `/* */` comments (which may span lines) with spaces, keeping every newline so
/// line and column numbers stay those of the source. Strings and `#` comments are skipped.
pub(crate) fn blank_block_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    let (mut in_block, mut in_str, mut in_line_comment) = (false, false, false);
    while let Some(c) = chars.next() {
        if c == '\n' {
            in_str = false;
            in_line_comment = false;
            out.push(c);
            continue;
        }
        if in_block {
            if c == '*' && chars.peek() == Some(&'/') {
                chars.next();
                in_block = false;
                out.push_str("  ");
            } else {
                out.push(if c == '\t' { '\t' } else { ' ' });
            }
            continue;
        }
        if in_line_comment {
            out.push(c);
            continue;
        }
        if in_str {
            out.push(c);
            if c == '\\' {
                if let Some(&n) = chars.peek() {
                    if n != '\n' {
                        out.push(n);
                        chars.next();
                    }
                }
            } else if c == '"' {
                in_str = false;
            }
            continue;
        }
        match c {
            '"' => in_str = true,
            '#' => in_line_comment = true,
            '/' if chars.peek() == Some(&'*') => {
                chars.next();
                in_block = true;
                out.push_str("  ");
                continue;
            }
            _ => {}
        }
        out.push(c);
    }
    out
}

/// A source's lines, `/* */` comments blanked (line and column numbers unchanged).
pub(crate) fn to_lines(text: &str, file: &str) -> Vec<Line> {
    let text = blank_block_comments(text);
    text.lines()
        .enumerate()
        .map(|(i, l)| Line {
            text: l.to_string(),
            file: file.to_string(),
            line: i + 1,
        })
        .collect()
}

/// Source text as gas reads it: bytes, each one character (so Latin-1 and UTF-8 text in
/// comments and strings pass through byte for byte).
pub(crate) fn bytes_as_text(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| b as char).collect()
}

/// A line of byte-characters back as text for a diagnostic (UTF-8 if it is, else Latin-1).
pub(crate) fn display_text(text: &str) -> String {
    let bytes: Vec<u8> = text.chars().map(|c| c as u32 as u8).collect();
    String::from_utf8(bytes).unwrap_or_else(|_| text.to_string())
}

/// The most bytes a source or included file may have.
pub const MAX_SOURCE: u64 = 64 << 20;

/// Reads a source file with a size limit.
pub(crate) fn read_source(path: &std::path::Path) -> Result<String, String> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    file.take(MAX_SOURCE + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > MAX_SOURCE {
        return Err(format!("larger than {} MiB", MAX_SOURCE >> 20));
    }
    Ok(bytes_as_text(&bytes))
}
