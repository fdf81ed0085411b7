//! Limits on a TOML text's structure, checked before it is parsed.
//!
//! A TOML reader builds a tree of every value in the text before the scene's own checks can see
//! it; each value costs 100 to 900 bytes there, so a 16 MB file of `x = [[],[],…]` (5 million
//! empty arrays) needed more than a gigabyte. [`check`] scans the text once, in constant memory,
//! and refuses it at the first place where the tree would need more than [`MAX_TREE_BYTES`] or
//! nests more than [`MAX_DEPTH`] arrays and inline tables. It prices the characters that start
//! or separate values outside strings and comments: every value of the tree needs at least one
//! of them, and each is priced above what the `toml` crate's tree was measured to take per
//! value (peak resident memory over a file of 250 000 of them, springlab's own 6 MB deducted):
//!
//! | character | what it makes | priced (bytes) | measured (bytes) |
//! |---|---|---|---|
//! | `=` | a key and its value | [`KEY_BYTES`] = 500 | 360 (`a0 = 1` lines) |
//! | `[` | an array, or the table of a `[header]` | [`TABLE_BYTES`] = 700 | 140 (`[]`), 360 (`[t0]`) |
//! | `{` | an inline table | [`TABLE_BYTES`] = 700 | 180 (`{}`), 640 (`{a={b={}}}`, per table) |
//! | `,` | an array element | [`ELEMENT_BYTES`] = 150 | 140 (30-byte strings) |
//!
//! A particle (`[[particles]]`, `position = [x, y, z]`, `mass = m`) is priced 3 400 bytes and
//! measured 2 700, so a file may list about 19 000 explicit particles (a `[[ropes]]` block builds
//! any number from a few values); `--force` lifts the limit with the file size.

/// Priced bytes of a key and its value (`=`).
pub const KEY_BYTES: usize = 500;
/// Priced bytes of an array or a table (`[`, `{`).
pub const TABLE_BYTES: usize = 700;
/// Priced bytes of an array element (`,`).
pub const ELEMENT_BYTES: usize = 150;

/// The most bytes the TOML reader's tree of a scene or lesson file may be priced at: with the
/// file's text (at most 16 MiB) and springlab itself, reading any file stays under 100 MB.
pub const MAX_TREE_BYTES: usize = 64 << 20;

/// The deepest nesting of arrays and inline tables (a vector in an inline table in an array is
/// depth 3).
pub const MAX_DEPTH: usize = 16;

/// Where and why a text is refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TooLarge {
    /// Byte offset of the value that crossed the limit.
    pub offset: usize,
    /// What was exceeded.
    pub message: String,
}

/// Checks `text` against [`MAX_TREE_BYTES`] and [`MAX_DEPTH`].
///
/// # Errors
/// The offset of the first value past a limit, and which limit.
pub fn check(text: &str) -> Result<(), TooLarge> {
    check_with(text, MAX_TREE_BYTES, MAX_DEPTH)
}

/// [`check`] with other limits: at most `max_bytes` priced bytes, `max_depth` levels.
///
/// # Errors
/// As [`check`].
pub fn check_with(text: &str, max_bytes: usize, max_depth: usize) -> Result<(), TooLarge> {
    let bytes = text.as_bytes();
    let mut priced = 0usize;
    let mut depth = 0usize;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'#' => {
                // A comment runs to the end of the line.
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            quote @ (b'"' | b'\'') => {
                i = skip_string(bytes, i, quote);
                continue;
            }
            b'=' => priced += KEY_BYTES,
            b',' => priced += ELEMENT_BYTES,
            b'[' | b'{' => {
                priced += TABLE_BYTES;
                depth += 1;
                if depth > max_depth {
                    return Err(TooLarge {
                        offset: i,
                        message: format!(
                            "arrays and inline tables nested more than {max_depth} deep"
                        ),
                    });
                }
            }
            // A table header `[a]` or `[[a]]` opens and closes on its line, so depth comes back
            // to 0 at its end like an array's.
            b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        if priced > max_bytes {
            return Err(TooLarge {
                offset: i,
                message: format!(
                    "too many values: reading the file up to here would need more than {} MB \
                     (150 to 700 bytes per key, table or array element); use --force to read \
                     it anyway",
                    max_bytes >> 20
                ),
            });
        }
        i += 1;
    }
    Ok(())
}

/// The index just past the string that opens at `start` with `quote` (`"` or `'`, single or
/// triple); the end of the text when it is not closed (the TOML reader then says so).
fn skip_string(bytes: &[u8], start: usize, quote: u8) -> usize {
    let triple = bytes.get(start..start + 3) == Some(&[quote, quote, quote][..]);
    let mut i = start + if triple { 3 } else { 1 };
    while i < bytes.len() {
        let b = bytes[i];
        if b == b'\\' && quote == b'"' {
            i += 2;
            continue;
        }
        if b == quote {
            if !triple {
                return i + 1;
            }
            if bytes.get(i..i + 3) == Some(&[quote, quote, quote][..]) {
                // Up to two more quotes may end the content (`""""` ends with one in it).
                let mut end = i + 3;
                while end < bytes.len() && bytes[end] == quote && end < i + 5 {
                    end += 1;
                }
                return end;
            }
        }
        if b == b'\n' && !triple {
            // An unclosed one-line string: the reader reports it.
            return i;
        }
        i += 1;
    }
    bytes.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The priced bytes of `=` ×k, `[` or `{` ×t, `,` ×e.
    fn price(k: usize, t: usize, e: usize) -> usize {
        k * KEY_BYTES + t * TABLE_BYTES + e * ELEMENT_BYTES
    }

    #[test]
    fn prices_values_outside_strings_and_comments() {
        // `=`, `[`, `,`, `,`.
        let three = price(1, 1, 2);
        assert_eq!(check_with("a = [1, 2, 3]", three, 4), Ok(()));
        // One more `,`.
        assert!(check_with("a = [1, 2, 3, 4]", three, 4).is_err());
        // Separators in strings and comments are not values.
        let two_keys = price(2, 0, 0);
        assert_eq!(
            check_with("a = \"[,,,,]\" # ,,,,,,\nb = '{{{'", two_keys, 1),
            Ok(())
        );
        let one_key = price(1, 0, 0);
        assert_eq!(
            check_with("a = \"\"\"x\",\"\n,,,\"\"\"", one_key, 1),
            Ok(())
        );
        assert_eq!(check_with("a = '''x','\n,,,'''", one_key, 1), Ok(()));
        assert_eq!(check_with(r#"a = "\",,,,""#, one_key, 1), Ok(()));
    }

    #[test]
    fn refuses_at_the_value_past_the_limit() {
        let text = format!("x = [{}]", "[],".repeat(10));
        // `=` at byte 2, the list's `[` at 4, then `[` at 5, 8, 11, 14 and `,` at 7, 10, 13:
        // up to byte 13 that is 1 key, 4 arrays and 3 elements; the `[` at 14 is past.
        let e = check_with(&text, price(1, 4, 3), 4).expect_err("too many");
        assert_eq!(e.offset, 14);
        let deep = format!("x = {}", "[".repeat(20));
        let e = check_with(&deep, usize::MAX, 16).expect_err("too deep");
        assert_eq!(e.offset, 4 + 16);
        // Table headers do not nest.
        let headers = "[[particles]]\nmass = 1\n".repeat(40);
        assert_eq!(check_with(&headers, usize::MAX, 2), Ok(()));
    }
}
