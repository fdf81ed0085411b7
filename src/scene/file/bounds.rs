//! Limits on a TOML text's structure, checked before it is parsed.
//!
//! A TOML reader builds a tree of every value in the text before the scene's own checks can see
//! it; each value costs tens of bytes there, so a 16 MB file of `x = [[],[],…]` (5 million empty
//! arrays) would need more than a gigabyte. [`check`] scans the text once, in constant memory,
//! and refuses it at the first place where it has more than [`MAX_VALUES`] values or nests more
//! than [`MAX_DEPTH`] arrays and inline tables. It counts the characters that start or separate
//! values outside strings and comments (`=`, `,`, `[`, `{`): every value of the tree needs at
//! least one of them, so the tree has at most that many values (plus one).

/// The most values (counted as in the module docs) a scene or lesson file may hold: about
/// 80 000 explicit particles with their springs, and a parse tree well under 100 MB.
pub const MAX_VALUES: usize = 500_000;

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

/// Checks `text` against [`MAX_VALUES`] and [`MAX_DEPTH`].
///
/// # Errors
/// The offset of the first value past a limit, and which limit.
pub fn check(text: &str) -> Result<(), TooLarge> {
    check_with(text, MAX_VALUES, MAX_DEPTH)
}

/// [`check`] with other limits.
///
/// # Errors
/// As [`check`].
pub fn check_with(text: &str, max_values: usize, max_depth: usize) -> Result<(), TooLarge> {
    let bytes = text.as_bytes();
    let mut values = 0usize;
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
            b'=' | b',' => values += 1,
            b'[' | b'{' => {
                values += 1;
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
            b']' | b'}' => depth = depth.saturating_sub(1),
            // A table header `[a]` or `[[a]]` opens at the start of a line and closes on it, so
            // depth comes back to 0 at its end like an array's.
            _ => {}
        }
        if values > max_values {
            return Err(TooLarge {
                offset: i,
                message: format!(
                    "more than {max_values} values (numbers, arrays, tables); a scene or lesson \
                     file holds at most {max_values}"
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

    #[test]
    fn counts_values_outside_strings_and_comments() {
        // `=`, `[`, `,`, `,`: 4 values.
        assert_eq!(check_with("a = [1, 2, 3]", 4, 4), Ok(()));
        // One more `,`: 5.
        assert!(check_with("a = [1, 2, 3, 4]", 4, 4).is_err());
        // Separators in strings and comments are not values.
        assert_eq!(
            check_with("a = \"[,,,,]\" # ,,,,,,\nb = '{{{'", 2, 1),
            Ok(())
        );
        assert_eq!(check_with("a = \"\"\"x\",\"\n,,,\"\"\"", 1, 1), Ok(()));
        assert_eq!(check_with("a = '''x','\n,,,'''", 1, 1), Ok(()));
        assert_eq!(check_with(r#"a = "\",,,,""#, 1, 1), Ok(()));
    }

    #[test]
    fn refuses_at_the_value_past_the_limit() {
        let text = format!("x = [{}]", "[],".repeat(10));
        let e = check_with(&text, 8, 4).expect_err("too many");
        // `=` (1) at byte 2, the list's `[` (2) at 4, then `[` at 5, 8, 11, 14 and `,` at 7,
        // 10, 13: the 9th value is the `[` at byte 14.
        assert_eq!(e.offset, 14);
        let deep = format!("x = {}", "[".repeat(20));
        let e = check_with(&deep, 100, 16).expect_err("too deep");
        assert_eq!(e.offset, 4 + 16);
        // Table headers do not nest.
        let headers = "[[particles]]\nmass = 1\n".repeat(40);
        assert_eq!(check_with(&headers, 1000, 2), Ok(()));
    }
}
