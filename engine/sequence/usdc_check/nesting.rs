//! The nesting depth of a `.usda` text. openusd's parser recurses once per level of braces,
//! brackets and parentheses (prims, dictionaries, metadata, arrays), so that a text nested a
//! few thousand deep overflows the stack: an abort, which no caller can catch.

/// The deepest nesting of `{`, `[` and `(` in `text` outside comments, strings, asset paths and
/// path references, each delimited as openusd's lexer delimits them. The scan stops at a
/// string left open: the lexer fails there, and the parser reads nothing after it.
pub fn depth(text: &str) -> usize {
    let bytes = text.as_bytes();
    let (mut depth, mut deepest, mut at) = (0usize, 0, 0);
    while let Some(&first) = bytes.get(at) {
        let rest = &bytes[at..];
        let length = match first {
            b'{' | b'[' | b'(' => {
                depth += 1;
                deepest = deepest.max(depth);
                Some(1)
            }
            b'}' | b']' | b')' => {
                depth = depth.saturating_sub(1);
                Some(1)
            }
            b'#' => Some(rest.iter().position(|&b| b == b'\n' || b == b'\r').unwrap_or(rest.len())),
            b'/' if rest.starts_with(b"/*") => closed(rest, 2, b"*/"),
            // A triple-quoted string or asset path when it is closed, else a single one.
            b'"' | b'\'' | b'@' => {
                let triple = [first; 3];
                let long = if rest.starts_with(&triple) { closed(rest, 3, &triple) } else { None };
                long.or_else(|| quoted(rest))
            }
            b'<' => closed(rest, 1, b">"),
            _ => Some(1),
        };
        match length {
            Some(length) => at += length,
            None => break,
        }
    }
    deepest
}

/// The length of the construct at the start of `rest` whose first `open` bytes open it and the
/// first `close` after them ends it; None when nothing closes it.
fn closed(rest: &[u8], open: usize, close: &[u8]) -> Option<usize> {
    let after = rest.get(open..)?;
    after.windows(close.len()).position(|w| w == close).map(|p| open + p + close.len())
}

/// The length of the string (`"` or `'`, with backslash escapes) or asset path (`@`, without)
/// at the start of `rest`; None when nothing closes it or an escape runs into a line end.
fn quoted(rest: &[u8]) -> Option<usize> {
    let quote = rest[0];
    let mut at = 1;
    loop {
        match *rest.get(at)? {
            b if b == quote => return Some(at + 1),
            b'\\' if quote != b'@' => {
                if matches!(rest.get(at + 1), None | Some(b'\n')) {
                    return None;
                }
                at += 2;
            }
            _ => at += 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::depth;

    #[test]
    fn brackets_count_outside_comments_strings_assets_and_paths() {
        assert_eq!(depth("def X { dictionary d = { int[] a = [(1, 2)] } }"), 4);
        let hidden =
            "# ((( \n/* [[[ */ \"{{{\\\" {\" '[[' \"\"\"\n(((\"\"\" @((( @ @@@ {{@ @@@ </A{v=x}>";
        assert_eq!(depth(hidden), 0);
        // Closers inside a string do not lower the depth.
        assert_eq!(depth("{ { \"}}}}\" { } }"), 3);
        // An empty string then a one-character string, not an unclosed triple quote.
        assert_eq!(depth("\"\"\"a\" ("), 1);
        // A comment ends at a lone carriage return.
        assert_eq!(depth("# a\r((("), 3);
    }

    #[test]
    fn the_scan_stops_where_the_lexer_would_fail() {
        assert_eq!(depth("( \"open ((((("), 1);
        assert_eq!(depth("( \"escape \\\n\" ((("), 1);
        assert_eq!(depth(&"{".repeat(10_000)), 10_000);
    }
}
