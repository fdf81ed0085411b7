//! Where a submission's code is, reading it (bounded, regular files only) and naming a build
//! by its contents.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

use crate::grade::untrusted::shown_path;

/// At most this many bytes of source are copied from one submission.
const MAX_SOURCE_BYTES: u64 = 8 << 20;
/// At most this many files.
const MAX_SOURCE_FILES: usize = 2000;

/// Where a submission's code is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Submission {
    /// The directory given.
    pub dir: PathBuf,
    /// The directory holding `lib.rs`, or the lone `lib.rs` given.
    pub src: PathBuf,
}

/// Finds the code of the submission in `dir`: `dir` itself when it is a file named `lib.rs`,
/// `dir/src/lib.rs`, `dir/lib.rs`, or the one
/// `src/lib.rs` in the folders below (an upload of a whole crate folder, up to three levels
/// down; hidden folders and `target` are not searched). Nothing inside `dir` is reached through
/// a symbolic link: the grader reads the submission with its own rights (root on Gradescope),
/// so a link named `src` or `lib.rs` could hand it any file of the machine; such a link is an
/// error that says so.
///
/// # Errors
/// A sentence saying what was looked for, that a link was found, or that several crates were
/// found.
pub fn locate(dir: &Path) -> Result<Submission, String> {
    let found = |src: PathBuf| Submission {
        dir: dir.to_path_buf(),
        src,
    };
    // A lone `lib.rs` (the path given is the file itself).
    if dir.file_name().is_some_and(|n| n == "lib.rs")
        && std::fs::symlink_metadata(dir).is_ok_and(|m| m.is_file())
    {
        return Ok(found(dir.to_path_buf()));
    }
    if has_lib(&dir.join("src"))? {
        return Ok(found(dir.join("src")));
    }
    if has_lib(dir)? {
        return Ok(found(dir.to_path_buf()));
    }
    let mut level = vec![dir.to_path_buf()];
    for _ in 0..3 {
        let mut next = Vec::new();
        for parent in &level {
            let Ok(entries) = std::fs::read_dir(parent) else {
                if parent == dir {
                    return Err(format!("cannot read {}", shown_path(dir)));
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
        let mut crates = Vec::new();
        for d in &next {
            let src = d.join("src");
            if has_lib(&src)? {
                crates.push(src);
            }
        }
        crates.sort();
        match crates.len() {
            0 => {}
            1 => return Ok(found(crates.remove(0))),
            n => {
                return Err(format!(
                    "{n} crates in {}: {}; grade them one by one",
                    shown_path(dir),
                    crates
                        .iter()
                        .map(|c| shown_path(c))
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
        }
        level = next;
    }
    Err(format!(
        "no src/lib.rs in {} (nor lib.rs, nor up to three folders down)",
        shown_path(dir)
    ))
}

/// True when `folder/lib.rs` is a regular file and `folder` a real folder; false when either
/// is missing.
///
/// # Errors
/// When either is a symbolic link (a link is never followed).
fn has_lib(folder: &Path) -> Result<bool, String> {
    let lib = folder.join("lib.rs");
    let mut is_file = false;
    for path in [folder, lib.as_path()] {
        match std::fs::symlink_metadata(path) {
            Ok(m) if m.file_type().is_symlink() => return Err(link_refused(path)),
            Ok(m) => is_file = m.is_file(),
            Err(_) => return Ok(false),
        }
    }
    Ok(is_file)
}

fn link_refused(path: &Path) -> String {
    format!(
        "{} is a symbolic link: links are not graded (the grader copies regular files only); \
         put the files themselves in the submission",
        shown_path(path)
    )
}

/// The contents of the regular file `path` of a submission, at most `limit` bytes: opened
/// without following a link and without waiting on a FIFO or a device, checked to be a
/// regular file once open (so nothing can swap it for a link in between).
///
/// # Errors
/// A sentence naming the file: a link, not a regular file, larger than `limit`, or the system's
/// error.
pub fn read_regular(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    use std::io::Read;
    use std::os::unix::fs::OpenOptionsExt;
    let shown = shown_path(path);
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(nix::libc::O_NOFOLLOW | nix::libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| {
            if e.raw_os_error() == Some(nix::libc::ELOOP) {
                link_refused(path)
            } else {
                format!("{shown}: {e}")
            }
        })?;
    let meta = file.metadata().map_err(|e| format!("{shown}: {e}"))?;
    if !meta.is_file() {
        return Err(format!("{shown} is not a regular file"));
    }
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("{shown}: {e}"))?;
    if bytes.len() as u64 > limit {
        return Err(format!("{shown} is larger than {limit} bytes"));
    }
    Ok(bytes)
}

/// A source tree read into memory: relative paths (with `/`) and contents, sorted. Regular
/// files only: a symbolic link, a FIFO, a socket or a device is an error, unless its name is
/// hidden (an editor's lock file `.#lib.rs` is a link), when it is left out.
pub(super) fn read_tree(src: &Path) -> Result<Vec<(String, Vec<u8>)>, String> {
    if std::fs::symlink_metadata(src).is_ok_and(|m| m.is_file()) {
        // A lone lib.rs.
        return Ok(vec![(
            "lib.rs".to_string(),
            read_regular(src, MAX_SOURCE_BYTES)?,
        )]);
    }
    let mut files = Vec::new();
    let mut total = 0u64;
    if std::fs::symlink_metadata(src).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(link_refused(src));
    }
    let mut stack = vec![(src.to_path_buf(), String::new())];
    while let Some((dir, prefix)) = stack.pop() {
        let entries = std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", shown_path(&dir)))?;
        for entry in entries.filter_map(Result::ok) {
            let name = entry.file_name().to_string_lossy().into_owned();
            let relative = if prefix.is_empty() {
                name.clone()
            } else {
                format!("{prefix}/{name}")
            };
            // symlink_metadata: a link is never followed.
            let Ok(meta) = std::fs::symlink_metadata(entry.path()) else {
                continue;
            };
            let special = !meta.is_dir() && !meta.is_file();
            if special && name.starts_with('.') {
                continue;
            }
            if meta.file_type().is_symlink() {
                return Err(link_refused(&entry.path()));
            }
            if meta.is_dir() {
                if name != "target" && !name.starts_with('.') {
                    stack.push((entry.path(), relative));
                }
            } else if meta.is_file() {
                total += meta.len();
                if total > MAX_SOURCE_BYTES || files.len() >= MAX_SOURCE_FILES {
                    return Err(format!(
                        "{} holds more than {} MiB or {MAX_SOURCE_FILES} files",
                        shown_path(src),
                        MAX_SOURCE_BYTES >> 20
                    ));
                }
                let bytes = read_regular(&entry.path(), MAX_SOURCE_BYTES)?;
                total += (bytes.len() as u64).saturating_sub(meta.len());
                files.push((relative, bytes));
            } else {
                return Err(format!(
                    "{} is not a regular file (a FIFO, socket or device)",
                    shown_path(&entry.path())
                ));
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::symlink;

    /// A submission folder with `files` (relative path, contents) in a fresh temporary folder;
    /// a victim folder beside it holds a lib.rs of its own.
    fn submission(files: &[(&str, &str)]) -> (tempfile::TempDir, PathBuf, PathBuf) {
        let root = tempfile::tempdir().expect("tempdir");
        let sub = root.path().join("sub");
        let victim = root.path().join("victim");
        std::fs::create_dir_all(&sub).expect("sub");
        std::fs::create_dir_all(&victim).expect("victim");
        std::fs::write(
            victim.join("lib.rs"),
            "pub const SECRET: &str = \"hunter2\";",
        )
        .expect("w");
        for (path, text) in files {
            let p = sub.join(path);
            std::fs::create_dir_all(p.parent().expect("parent")).expect("mkdir");
            std::fs::write(p, text).expect("write");
        }
        (root, sub, victim)
    }

    fn refused(result: Result<Submission, String>, link: &Path) {
        let why = result.expect_err("a link must not be followed");
        assert_eq!(
            why,
            format!(
                "{} is a symbolic link: links are not graded (the grader copies regular files \
                 only); put the files themselves in the submission",
                link.display()
            )
        );
    }

    #[test]
    fn a_src_folder_that_is_a_link_is_refused_at_every_depth() {
        let (_root, sub, victim) = submission(&[]);
        symlink(&victim, sub.join("src")).expect("link");
        refused(locate(&sub), &sub.join("src"));

        let (_root, sub, victim) = submission(&[("readme.txt", "")]);
        std::fs::create_dir_all(sub.join("crate")).expect("mkdir");
        symlink(&victim, sub.join("crate/src")).expect("link");
        refused(locate(&sub), &sub.join("crate/src"));
    }

    #[test]
    fn a_lib_rs_that_is_a_link_is_refused() {
        let (_root, sub, victim) = submission(&[("src/main.rs", "fn main() {}")]);
        symlink(victim.join("lib.rs"), sub.join("src/lib.rs")).expect("link");
        refused(locate(&sub), &sub.join("src/lib.rs"));

        let (_root, sub, victim) = submission(&[]);
        symlink(victim.join("lib.rs"), sub.join("lib.rs")).expect("link");
        refused(locate(&sub), &sub.join("lib.rs"));
    }

    #[test]
    fn a_link_or_fifo_inside_src_is_refused_and_a_hidden_link_left_out() {
        let (_root, sub, victim) = submission(&[("src/lib.rs", "mod a;"), ("src/a.rs", "")]);
        symlink(victim.join("lib.rs"), sub.join("src/.#lib.rs")).expect("link");
        let found = locate(&sub).expect("found");
        let files = read_tree(&found.src).expect("a hidden link is left out");
        let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["a.rs", "lib.rs"]);

        symlink(victim.join("lib.rs"), sub.join("src/b.rs")).expect("link");
        let why = read_tree(&found.src).expect_err("a link is refused");
        assert!(why.starts_with(&format!(
            "{} is a symbolic link",
            sub.join("src/b.rs").display()
        )));
        std::fs::remove_file(sub.join("src/b.rs")).expect("rm");

        nix::unistd::mkfifo(&sub.join("src/pipe.rs"), nix::sys::stat::Mode::S_IRWXU)
            .expect("mkfifo");
        let why = read_tree(&found.src).expect_err("a FIFO is refused, not waited on");
        assert_eq!(
            why,
            format!(
                "{} is not a regular file (a FIFO, socket or device)",
                sub.join("src/pipe.rs").display()
            )
        );
    }

    #[test]
    fn read_regular_refuses_links_fifos_and_oversized_files() {
        let (_root, sub, victim) = submission(&[("big.txt", "0123456789")]);
        assert_eq!(
            read_regular(&sub.join("big.txt"), 10).expect("10 bytes"),
            b"0123456789"
        );
        assert_eq!(
            read_regular(&sub.join("big.txt"), 9),
            Err(format!(
                "{} is larger than 9 bytes",
                sub.join("big.txt").display()
            ))
        );
        symlink(victim.join("lib.rs"), sub.join("Cargo.toml")).expect("link");
        assert!(
            read_regular(&sub.join("Cargo.toml"), 1 << 20)
                .is_err_and(|e| e.contains("is a symbolic link"))
        );
        nix::unistd::mkfifo(&sub.join("fifo"), nix::sys::stat::Mode::S_IRWXU).expect("mkfifo");
        assert_eq!(
            read_regular(&sub.join("fifo"), 1 << 20),
            Err(format!(
                "{} is not a regular file",
                sub.join("fifo").display()
            ))
        );
    }

    #[test]
    fn control_characters_in_folder_names_are_escaped_in_messages() {
        let (_root, sub, _victim) = submission(&[
            ("a/src/lib.rs", ""),
            ("\u{1b}[2J\u{1b}[Hscore 35 of 35/src/lib.rs", ""),
        ]);
        let why = locate(&sub).expect_err("two crates");
        assert!(!why.contains('\u{1b}'), "{why}");
        assert!(
            why.contains("\\u{1b}[2J\\u{1b}[Hscore 35 of 35/src"),
            "{why}"
        );
    }
}
