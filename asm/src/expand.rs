//! The text side of gas's `macro.c`, shared by the assembler's macros and repetitions and
//! by `spu sched`'s `.irp`: arguments as gas reads them, `\name` substitution, the values
//! of an `.irp`/`.irpc`, and where a block ends. What a statement means is the assembler's
//! (`gas::macros`); here is only how the text is taken apart and put together.

use crate::expr::{is_ident, is_ident_start};
use crate::lex::split_top;

/// A macro or `.irp` argument as gas's `get_any_string` takes it: a double-quoted
/// argument is its text without the quotes (so it may hold commas and spaces).
pub(crate) fn macro_argument(arg: &str) -> String {
    if let Some(inner) = one_string(arg) {
        return inner.to_string();
    }
    // `name="value"` for a keyword argument.
    if let Some((name, value)) = arg.split_once('=') {
        let v = value.trim();
        if v.len() >= 2
            && v.starts_with('"')
            && v.ends_with('"')
            && !v[1..v.len() - 1].contains('"')
        {
            return format!("{name}={}", &v[1..v.len() - 1]);
        }
    }
    arg.to_string()
}

/// The inside of `arg` when it is one quoted string, its escapes kept (macro.c
/// `getstring`: a `"` after an odd run of backslashes does not end it).
fn one_string(arg: &str) -> Option<&str> {
    let body = arg.strip_prefix('"')?;
    let mut backslashes = 0;
    for (k, c) in body.char_indices() {
        match c {
            '\\' => backslashes += 1,
            '"' if backslashes % 2 == 0 => return (k + 1 == body.len()).then(|| &body[..k]),
            _ => backslashes = 0,
        }
    }
    None
}

/// Replaces `\name` (and `\@` with the macro counter) in a macro or repetition body.
pub(crate) fn substitute(text: &str, vars: &[(String, String)], counter: Option<&str>) -> String {
    let mut out = String::new();
    let b = text.as_bytes();
    let mut i = 0;
    let mut in_string = false;
    while i < b.len() {
        if in_string && b[i] == b'\\' && matches!(b.get(i + 1), Some(b'"' | b'\\')) {
            out.push_str(&text[i..i + 2]);
            i += 2;
            continue;
        }
        if b[i] == b'"' {
            in_string = !in_string;
        } else if !in_string && b[i] == b'\'' {
            // A character constant (`'c`, `'\c'`): gas's input scrubber (app.c) has
            // turned it into a number before any macro sees it, so nothing in it is a
            // parameter, and a quote in it opens no string.
            let len = if b.get(i + 1) == Some(&b'\\') { 3 } else { 2 };
            let end = (i + len).min(b.len());
            let end = (end..=b.len())
                .find(|&e| text.is_char_boundary(e))
                .unwrap_or(b.len());
            out.push_str(&text[i..end]);
            i = end;
            continue;
        }
        if b[i] == b'&' {
            // macro.c macro_expand_body: `&name` or `&name&` is the parameter too, in a
            // string as well; `&` before anything else stays.
            let start = i + 1;
            let mut end = start;
            while end < b.len() && is_ident(b[end] as char) && b[end] != b'.' && b[end] != b'$' {
                end += 1;
            }
            let found = vars
                .iter()
                .find(|(n, _)| end > start && n == &text[start..end]);
            if let Some((_, v)) = found {
                out.push_str(v);
                i = end + (b.get(end) == Some(&b'&')) as usize;
                continue;
            }
        }
        if b[i] == b'\\' {
            if let Some(c) = counter {
                if b.get(i + 1) == Some(&b'@') {
                    out.push_str(c);
                    i += 2;
                    continue;
                }
            }
            let start = i + 1;
            let mut end = start;
            while end < b.len() && is_ident(b[end] as char) && b[end] != b'.' && b[end] != b'$' {
                end += 1;
            }
            let name = &text[start..end];
            // macro.c's get_apost_token: an apostrophe right after the name ends it and
            // is dropped, whether or not the name is a parameter.
            let apostrophe = !name.is_empty() && b.get(end) == Some(&b'\'');
            if let Some((_, v)) = vars.iter().find(|(n, _)| n == name) {
                out.push_str(v);
                i = end + apostrophe as usize;
                // `\()` separates a parameter from following text (gas's rule); a bare
                // `()` is taken as well, as the assembler always has.
                if text[i..].starts_with("\\()") {
                    i += 3;
                } else if text[i..].starts_with("()") {
                    i += 2;
                }
                continue;
            }
            if apostrophe {
                out.push_str(&text[i..end]);
                i = end + 1;
                continue;
            }
        }
        let c = text[i..].chars().next().unwrap_or(' ');
        out.push(c);
        i += c.len_utf8().max(1);
    }
    out
}

/// `.irp VAR, A, B, ...` (each value an argument as `macro_argument` takes it) or `.irpc
/// VAR, CHARS` (each character a value): the variable and its values, in order.
pub(crate) fn irp_values(irpc: bool, args: &str) -> (String, Vec<String>) {
    let parts = split_top(args, ',');
    let var = parts
        .first()
        .map(|s| s.trim().to_string())
        .unwrap_or_default();
    let values: Vec<String> = if !irpc {
        parts[1..]
            .iter()
            .map(|s| macro_argument(s.trim()))
            .collect()
    } else {
        parts
            .get(1)
            .map(|s| s.trim().chars().map(|c| c.to_string()).collect())
            .unwrap_or_default()
    };
    (var, values)
}

/// The index of the line that closes a `.macro`/`.rept`/`.irp`/`.irpc` block whose body
/// starts at `start` (nested blocks counted), given each line's directive word; `None`
/// when the block is never closed.
pub(crate) fn block_end<T>(
    lines: &[T],
    start: usize,
    word: impl Fn(&T) -> String,
) -> Option<usize> {
    let mut depth = 1;
    for (i, line) in lines.iter().enumerate().skip(start) {
        match word(line).as_str() {
            ".macro" | ".rept" | ".irp" | ".irpc" => depth += 1,
            ".endm" | ".endr" => {
                depth -= 1;
                if depth == 0 {
                    return Some(i);
                }
            }
            _ => {}
        }
    }
    None
}

/// `.altmacro` arguments (macro.c in alternate mode): split at commas outside `<...>`,
/// quotes and parentheses; `<text>` is `text` with `!` quoting the next character. An
/// argument starting `%` is returned with its `%` for the caller to evaluate.
pub(crate) fn alt_arguments(args: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let (mut angle, mut paren, mut quote) = (0usize, 0usize, false);
    let mut chars = args.chars();
    while let Some(c) = chars.next() {
        match c {
            // macro.c getstring: `!` takes the next character as it is, in `<...>`
            // and in a quoted string alike.
            '!' if angle > 0 || quote => {
                if let Some(n) = chars.next() {
                    cur.push(n);
                }
                continue;
            }
            '"' if angle == 0 => quote = !quote,
            '<' if !quote => {
                angle += 1;
                if angle == 1 {
                    continue;
                }
            }
            '>' if !quote && angle > 0 => {
                angle -= 1;
                if angle == 0 {
                    continue;
                }
            }
            '(' if !quote && angle == 0 => paren += 1,
            ')' if !quote && angle == 0 => paren = paren.saturating_sub(1),
            ',' if !quote && angle == 0 && paren == 0 => {
                out.push(cur.trim().to_string());
                cur.clear();
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    if !cur.trim().is_empty() || !out.is_empty() {
        out.push(cur.trim().to_string());
    }
    out
}

/// Replaces whole identifiers that name a parameter (`.altmacro` bodies may name them
/// without a backslash), outside double-quoted strings.
pub(crate) fn substitute_bare(text: &str, vars: &[(String, String)]) -> String {
    let mut out = String::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    let mut quote = false;
    while i < chars.len() {
        let c = chars[i];
        if c == '"' {
            quote = !quote;
        }
        let starts = !quote
            && is_ident_start(c)
            && (i == 0 || !(is_ident(chars[i - 1]) || chars[i - 1] == '\\'));
        if starts {
            let mut end = i + 1;
            while end < chars.len() && is_ident(chars[end]) {
                end += 1;
            }
            let word: String = chars[i..end].iter().collect();
            match vars.iter().find(|(n, _)| *n == word) {
                Some((_, v)) => out.push_str(v),
                None => out.push_str(&word),
            }
            i = end;
            continue;
        }
        out.push(c);
        i += 1;
    }
    out
}
