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
    // A byte scan: every character that matters is ASCII, and no byte of a multi-byte
    // character is, so the slices copied always end on character boundaries.
    let b = s.as_bytes();
    let mut out = String::with_capacity(s.len());
    let (mut start, mut i) = (0, 0);
    let mut in_str = false;
    while i < b.len() {
        let c = b[i];
        if in_str {
            match c {
                // An escape takes the next character with it (`\"` does not end the string).
                b'\\' => i += 1,
                b'"' => in_str = false,
                _ => {}
            }
            i += 1;
            continue;
        }
        match c {
            b'"' => in_str = true,
            b'#' => {
                out.push_str(&s[start..i]);
                return (out, Some(&s[i + 1..]));
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                out.push_str(&s[start..i]);
                out.push(' ');
                i = match s[i + 2..].find("*/") {
                    Some(k) => i + 2 + k + 2,
                    None => b.len(),
                };
                start = i;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    out.push_str(&s[start..]);
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
    if !text.contains("/*") {
        return text.to_string();
    }
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
    let (mut file, mut next) = (file.to_string(), 1);
    let mut lines = Vec::new();
    for l in text.lines() {
        lines.push(Line {
            text: l.to_string(),
            file: file.clone(),
            line: next,
        });
        next += 1;
        if let Some((number, name)) = line_marker(l) {
            (file, next) = (name, number);
        }
    }
    lines
}

/// A C preprocessor line marker, `# N "FILE" [FLAGS]` from the first column: the number
/// and name the next line has (app.c hands it to read.c's `s_linefile`). As gas 2.40
/// does, a number with a leading zero or past `INT_MAX`, or one without a file name, is
/// an ordinary comment.
fn line_marker(text: &str) -> Option<(usize, String)> {
    let rest = text.strip_prefix("# ")?;
    let digits = rest.len() - rest.trim_start_matches(|c: char| c.is_ascii_digit()).len();
    let number: i32 = rest[..digits]
        .parse()
        .ok()
        .filter(|_| !rest.starts_with('0'))?;
    let name = rest[digits..].trim_start().strip_prefix('"')?;
    let name = &name[..name.find('"')?];
    Some((number as usize, name.to_string()))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comments_end_where_gas_ends_them() {
        assert_eq!(
            split_comment(r##" .ascii "a#b\"#c" # note"##),
            (r##" .ascii "a#b\"#c" "##.to_string(), Some(" note"))
        );
        assert_eq!(
            split_comment("ai $3, $3, 1 /* one */ # more"),
            ("ai $3, $3, 1   ".to_string(), Some(" more"))
        );
        // An unclosed `/*` runs to the end of the line; `/*/` does not close it.
        assert_eq!(
            split_comment("il $3, 1 /*/ x"),
            ("il $3, 1  ".to_string(), None)
        );
        // Characters past ASCII (bytes as gas reads them) pass through.
        assert_eq!(
            split_comment(".ascii \"é\\é#\" #é"),
            (".ascii \"é\\é#\" ".to_string(), Some("é"))
        );
        assert_eq!(strip_comment("/**/nop"), " nop");
        assert_eq!(first_word("  .IRP\tR, 1 # x"), ".irp");
    }

    #[test]
    fn block_comments_keep_lines_and_columns() {
        let text = "a /* x\n y */ b\n\"/*\" c # /*\nd";
        assert_eq!(
            blank_block_comments(text),
            "a     \n      b\n\"/*\" c # /*\nd"
        );
    }
}
