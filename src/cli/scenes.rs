//! `springlab scenes`: the built-in catalogue with every parameter.

use std::io::Write;

use crate::scene::BUILTIN;

/// Prints each scene on one line, then its parameters with unit, default and range.
///
/// # Errors
/// Only when standard output cannot be written.
pub fn list() -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    for def in BUILTIN {
        writeln!(out, "{:<14} {}", def.name, def.summary)?;
        for p in (def.params)() {
            let unit = if p.unit.is_empty() {
                String::new()
            } else {
                format!(" {}", p.unit)
            };
            writeln!(
                out,
                "    {:<16} = {}{unit:<8}  {} ({})",
                p.name,
                p.default,
                p.doc,
                p.expected()
            )?;
        }
    }
    Ok(())
}
