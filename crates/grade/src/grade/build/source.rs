//! Where a submission's code is, reading it (bounded, regular files only) and naming a build
//! by its contents.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

/// At most this many bytes of source are copied from one submission.
const MAX_SOURCE_BYTES: u64 = 8 << 20;
/// At most this many files.
const MAX_SOURCE_FILES: usize = 2000;

/// Where a submission's code is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Submission {
    /// The directory given.
    pub dir: PathBuf,
    /// The directory holding `lib.rs`.
    pub src: PathBuf,
}

/// Finds the code of the submission in `dir`: `dir/src/lib.rs`, `dir/lib.rs`, or the one
/// `src/lib.rs` in the folders below (an upload of a whole crate folder, up to three levels
/// down; hidden folders and `target` are not searched).
///
/// # Errors
/// A sentence saying what was looked for, or that several crates were found.
pub fn locate(dir: &Path) -> Result<Submission, String> {
    let found = |src: PathBuf| Submission {
        dir: dir.to_path_buf(),
        src,
    };
    if dir.join("src").join("lib.rs").is_file() {
        return Ok(found(dir.join("src")));
    }
    if dir.join("lib.rs").is_file() {
        return Ok(found(dir.to_path_buf()));
    }
    let mut level = vec![dir.to_path_buf()];
    for _ in 0..3 {
        let mut next = Vec::new();
        for parent in &level {
            let Ok(entries) = std::fs::read_dir(parent) else {
                if parent == dir {
                    return Err(format!("cannot read {}", dir.display()));
                }
                continue;
            };
            for entry in entries.filter_map(Result::ok) {
                let name = entry.file_name().to_string_lossy().into_owned();
                // symlink_metadata: links are not followed.
                let is_dir = std::fs::symlink_metadata(entry.path()).is_ok_and(|m| m.is_dir());
                if is_dir && !name.starts_with('.') && name != "target" && name != "src" {
                    next.push(entry.path());
                }
            }
        }
        let mut crates: Vec<PathBuf> = next
            .iter()
            .map(|d| d.join("src"))
            .filter(|src| src.join("lib.rs").is_file())
            .collect();
        crates.sort();
        match crates.len() {
            0 => {}
            1 => return Ok(found(crates.remove(0))),
            n => {
                return Err(format!(
                    "{n} crates in {}: {}; grade them one by one",
                    dir.display(),
                    crates
                        .iter()
                        .map(|c| c.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
        }
        level = next;
    }
    Err(format!(
        "no src/lib.rs in {} (nor lib.rs, nor up to three folders down)",
        dir.display()
    ))
}

/// A source tree read into memory: relative paths (with `/`) and contents, sorted.
pub(super) fn read_tree(src: &Path) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut files = Vec::new();
    let mut total = 0u64;
    let mut stack = vec![(src.to_path_buf(), String::new())];
    while let Some((dir, prefix)) = stack.pop() {
        let entries = std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        for entry in entries.filter_map(Result::ok) {
            let name = entry.file_name().to_string_lossy().into_owned();
            let relative = if prefix.is_empty() {
                name.clone()
            } else {
                format!("{prefix}/{name}")
            };
            // symlink_metadata: a link is neither followed nor copied.
            let Ok(meta) = std::fs::symlink_metadata(entry.path()) else {
                continue;
            };
            if meta.is_dir() {
                if name != "target" && !name.starts_with('.') {
                    stack.push((entry.path(), relative));
                }
            } else if meta.is_file() {
                total += meta.len();
                if total > MAX_SOURCE_BYTES || files.len() >= MAX_SOURCE_FILES {
                    return Err(format!(
                        "{} holds more than {} MiB or {MAX_SOURCE_FILES} files",
                        src.display(),
                        MAX_SOURCE_BYTES >> 20
                    ));
                }
                let bytes = std::fs::read(entry.path()).map_err(|e| format!("{relative}: {e}"))?;
                files.push((relative, bytes));
            }
        }
    }
    files.sort();
    Ok(files)
}

/// A 128-bit digest, as 32 hex digits, of everything that goes into a build.
pub(super) fn digest(parts: &[&[u8]]) -> String {
    let mut out = String::new();
    for salt in [0x5350_4c41_u64, 0x4247_5244_u64] {
        let mut h = DefaultHasher::new();
        salt.hash(&mut h);
        for p in parts {
            p.hash(&mut h);
        }
        out.push_str(&format!("{:016x}", h.finish()));
    }
    out
}
