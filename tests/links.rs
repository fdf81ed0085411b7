//! Every reference inside the repository points at a file that exists.
//!
//! Two kinds of reference are checked, both resolved against the files on disk:
//! - the relative links of every Markdown file (`[text](path)`, `![alt](path)` and reference
//!   definitions `[label]: path`), resolved from the Markdown file's folder; a `#fragment` is
//!   dropped, web addresses (`scheme:`) and in-page anchors are not files;
//! - in the doc comments (`//!`, `///`) of `src/` and `crates/`, every path-like mention of a
//!   `.md`, `.rs`, `.toml` or `.png` file whose first folder is a top-level entry of the
//!   repository (for example `docs/course.md`, `crates/render/src/render/paint.rs`), resolved
//!   from the repository root, and
//!   every bare upper-case Markdown name (`ARCHITECTURE.md`), resolved from the root too.
//!   Paths that start elsewhere (`DIR/src/lib.rs`, a student's crate; `dir/frame_00042.png`, an
//!   output) name files outside the repository and are left alone.
//!
//! A failure lists every broken reference as `file:line: missing path`.

use std::fs;
use std::path::{Path, PathBuf};

/// Folders never searched: build output, version control and hidden folders.
fn skipped(name: &str) -> bool {
    name.starts_with('.') || name.starts_with("target")
}

/// All files under `dir` (recursively) whose name ends with `suffix`, sorted.
fn files_with_suffix(dir: &Path, suffix: &str, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.filter_map(Result::ok).collect();
    entries.sort_by_key(fs::DirEntry::file_name);
    for entry in entries {
        let name = entry.file_name().to_string_lossy().into_owned();
        let path = entry.path();
        if path.is_dir() {
            if !skipped(&name) {
                files_with_suffix(&path, suffix, out);
            }
        } else if name.ends_with(suffix) {
            out.push(path);
        }
    }
}

/// The link targets of one line of Markdown: inline links and images, and reference
/// definitions.
fn markdown_targets(line: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let trimmed = line.trim_start();
    if trimmed.starts_with('[')
        && let Some(end) = trimmed.find("]:")
    {
        let rest = trimmed[end + 2..].trim();
        if let Some(target) = rest.split_whitespace().next() {
            targets.push(target.trim_matches(['<', '>']).to_string());
        }
    }
    let mut rest = line;
    while let Some(at) = rest.find("](") {
        let after = &rest[at + 2..];
        let Some(close) = after.find(')') else {
            break;
        };
        let inside = after[..close].trim();
        let target = inside.split_whitespace().next().unwrap_or("");
        targets.push(target.trim_matches(['<', '>']).to_string());
        rest = &after[close..];
    }
    targets
}

/// True for a link that names a file of the repository (not a web address, mail or anchor).
fn is_relative_link(target: &str) -> bool {
    !target.is_empty()
        && !target.starts_with('#')
        && !target.starts_with('/')
        && !target.contains("://")
        && !target.starts_with("mailto:")
}

/// The path-like tokens of one doc-comment line that name `.md`, `.rs`, `.toml` or `.png` files.
fn path_tokens(line: &str) -> Vec<&str> {
    let is_path_char = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '/' | '-');
    line.split(|c: char| !is_path_char(c))
        .map(|token| token.trim_end_matches('.'))
        .filter(|token| {
            [".md", ".rs", ".toml", ".png"]
                .iter()
                .any(|ext| token.len() > ext.len() && token.ends_with(ext))
        })
        .collect()
}

/// Whether a doc-comment token claims to be a file of this repository, and if so its path
/// relative to the root.
fn repository_path<'a>(root: &Path, token: &'a str) -> Option<&'a str> {
    let token = token.strip_prefix("./").unwrap_or(token);
    if token.starts_with('/') || token.starts_with("..") {
        return None;
    }
    match token.split_once('/') {
        Some((first, _)) => root.join(first).exists().then_some(token),
        None => {
            let stem = token.strip_suffix(".md")?;
            let upper = stem
                .chars()
                .all(|c| c.is_ascii_uppercase() || c == '_' || c == '-');
            upper.then_some(token)
        }
    }
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn relative(root: &Path, path: &Path) -> String {
    path.strip_prefix(root)
        .unwrap_or(path)
        .display()
        .to_string()
}

/// References checked so far and the broken ones, as `file:line: missing target`.
#[derive(Default)]
struct Findings {
    checked: usize,
    broken: Vec<String>,
}

impl Findings {
    /// Counts the reference `target` on line `index` (0-based) of `file`; records it when the
    /// file it names does not exist.
    fn check(&mut self, root: &Path, file: &Path, index: usize, target: &str, exists: bool) {
        self.checked += 1;
        if !exists {
            self.broken.push(format!(
                "{}:{}: missing {target}",
                relative(root, file),
                index + 1
            ));
        }
    }
}

/// Broken links in every Markdown file of the repository, as `file:line: missing target`.
fn broken_markdown_links(root: &Path) -> (usize, Vec<String>) {
    let mut files = Vec::new();
    files_with_suffix(root, ".md", &mut files);
    let mut found = Findings::default();
    for file in &files {
        let text = fs::read_to_string(file).expect("Markdown files are UTF-8");
        let dir = file.parent().expect("a file has a folder");
        let mut in_code = false;
        for (index, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("```") {
                in_code = !in_code;
                continue;
            }
            if in_code {
                continue;
            }
            for target in markdown_targets(line) {
                if !is_relative_link(&target) {
                    continue;
                }
                let path = target.split('#').next().unwrap_or("");
                if path.is_empty() {
                    continue;
                }
                found.check(root, file, index, &target, dir.join(path).exists());
            }
        }
    }
    (found.checked, found.broken)
}

/// Broken file references in the doc comments of `src/` and `crates/`, as `file:line: missing path`.
fn broken_doc_references(root: &Path) -> (usize, Vec<String>) {
    let mut files = Vec::new();
    files_with_suffix(&root.join("src"), ".rs", &mut files);
    files_with_suffix(&root.join("crates"), ".rs", &mut files);
    let mut found = Findings::default();
    for file in &files {
        let text = fs::read_to_string(file).expect("sources are UTF-8");
        for (index, line) in text.lines().enumerate() {
            let trimmed = line.trim_start();
            if !(trimmed.starts_with("//!") || trimmed.starts_with("///")) {
                continue;
            }
            for token in path_tokens(trimmed) {
                let Some(path) = repository_path(root, token) else {
                    continue;
                };
                found.check(root, file, index, path, root.join(path).exists());
            }
        }
    }
    (found.checked, found.broken)
}

#[test]
fn every_markdown_link_points_at_a_file() {
    let (checked, broken) = broken_markdown_links(&root());
    assert!(
        checked > 0,
        "found no relative link at all; is the scan broken?"
    );
    assert!(
        broken.is_empty(),
        "Markdown links to missing files:\n{}",
        broken.join("\n")
    );
}

#[test]
fn every_file_named_in_a_doc_comment_exists() {
    let (checked, broken) = broken_doc_references(&root());
    assert!(
        checked >= 10,
        "found only {checked} file references in doc comments; is the scan broken?"
    );
    assert!(
        broken.is_empty(),
        "doc comments in src/ and crates/ name missing files:\n{}",
        broken.join("\n")
    );
}

#[test]
fn the_scanners_find_what_they_should() {
    assert_eq!(
        markdown_targets("see [a](docs/a.md#x) and ![b](<img/b.png> \"t\") or [c](https://x.org)"),
        ["docs/a.md#x", "img/b.png", "https://x.org"]
    );
    assert_eq!(markdown_targets("[label]: ../x.md \"title\""), ["../x.md"]);
    assert_eq!(
        path_tokens("//! see `docs/course.md` §2, src/render.rs. and out.png, not foo.rsx"),
        ["docs/course.md", "src/render.rs", "out.png"]
    );
    let root = root();
    assert_eq!(repository_path(&root, "docs/x.md"), Some("docs/x.md"));
    assert_eq!(repository_path(&root, "DIR/src/lib.rs"), None);
    assert_eq!(repository_path(&root, "NOWHERE.md"), Some("NOWHERE.md"));
    assert_eq!(repository_path(&root, "out.png"), None);
    assert!(!root.join("NOWHERE.md").exists());
}
