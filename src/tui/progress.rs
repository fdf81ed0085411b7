//! What a student has done, kept between sessions: per lesson, the steps opened, the goals met
//! and the predictions made.
//!
//! The file is `progress.json` in the user's data directory (`directories`: for example
//! `~/.local/share/springlab/` on Linux, `~/Library/Application Support/springlab/` on macOS),
//! or in `$SPRINGLAB_DATA_DIR` when that is set (the tests use it). `springlab --no-save` (a
//! classroom machine) keeps progress in memory only. Lessons are keyed by their file and slug,
//! steps by index.
//!
//! Progress is never lost:
//! - the file is read field by field: a lesson record or a field of one that does not parse is
//!   left out, and the others are kept;
//! - a file that cannot be read, is not JSON, or has a part that was left out is kept: renamed
//!   aside to `progress.json.unreadable-YYYYMMDDTHHMMSSZ` (UTC) before anything is saved, and
//!   the app says so once ([`Progress::notice`]); what could be read is saved at once;
//! - something at the path that is not a regular file (a directory, a FIFO, a device) is not read,
//!   moved or written: progress is then kept in memory only, and the app says so;
//! - a save writes a temporary file with a unique name (`O_EXCL`) beside the file and renames it
//!   over it ([`crate::output::AtomicFile`]): a link or a file left at a fixed temporary name is
//!   never written through, and a failed save (a full disk) leaves the old file and no temporary
//!   file. A save that fails is reported once on the hint line and never stops the app.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// The environment variable that moves the progress file's directory.
pub const DATA_DIR_VAR: &str = "SPRINGLAB_DATA_DIR";

/// One lesson's record.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LessonProgress {
    /// Per step: opened.
    #[serde(default)]
    pub visited: Vec<bool>,
    /// Per step: its goal was met.
    #[serde(default)]
    pub met: Vec<bool>,
    /// Per step: the option predicted (0-based).
    #[serde(default)]
    pub answers: Vec<Option<usize>>,
}

/// Every lesson's record and where it is saved.
#[derive(Clone, Debug, Default)]
pub struct Progress {
    /// Keyed by [`Progress::key`].
    lessons: BTreeMap<String, LessonProgress>,
    /// The file; `None` keeps everything in memory.
    path: Option<PathBuf>,
    /// The last save's error, if any.
    error: Option<String>,
    /// What the student must be told about the file as it was found, once.
    notice: Option<String>,
}

#[derive(Serialize, Deserialize)]
struct File {
    version: u32,
    lessons: BTreeMap<String, LessonProgress>,
}

impl Progress {
    /// Progress kept in memory only (`--no-save`, tests).
    #[must_use]
    pub fn in_memory() -> Progress {
        Progress::default()
    }

    /// The default file: `$SPRINGLAB_DATA_DIR/progress.json`, else the user's data directory.
    #[must_use]
    pub fn default_path() -> Option<PathBuf> {
        if let Some(dir) = std::env::var_os(DATA_DIR_VAR).filter(|d| !d.is_empty()) {
            return Some(PathBuf::from(dir).join("progress.json"));
        }
        directories::ProjectDirs::from("", "", "springlab")
            .map(|d| d.data_dir().join("progress.json"))
    }

    /// Progress read from `path` and saved there (module docs: what cannot be read is kept
    /// aside and said once by [`Progress::notice`]).
    #[must_use]
    pub fn load(path: &Path) -> Progress {
        let mut progress = Progress {
            lessons: BTreeMap::new(),
            path: Some(path.to_path_buf()),
            error: None,
            notice: None,
        };
        let found = match std::fs::metadata(path) {
            // Nothing there yet (a missing directory included): the first save makes it.
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
                ) =>
            {
                return progress;
            }
            Err(e) => Err(e.to_string()),
            Ok(m) if !m.is_file() => {
                progress.path = None;
                progress.notice = Some(format!(
                    "{} is not a regular file: progress is kept in memory only this time",
                    path.display()
                ));
                return progress;
            }
            Ok(_) => read_limited(path).map_err(|e| e.to_string()),
        };
        let (lessons, problems) = match found {
            Ok(bytes) => parse(&bytes),
            Err(e) => (BTreeMap::new(), vec![format!("cannot read it ({e})")]),
        };
        progress.lessons = lessons;
        if problems.is_empty() {
            return progress;
        }
        let what = problems.join("; ");
        match keep_aside(path) {
            Ok(aside) => {
                let kept = progress.lessons.len();
                progress.notice = Some(format!(
                    "progress file {}: {what}; the file is kept as {}{}",
                    path.display(),
                    aside.display(),
                    if kept > 0 {
                        format!(" and the progress of {kept} lesson(s) that could be read goes on")
                    } else {
                        " and a new one is started".to_string()
                    }
                ));
                if kept > 0
                    && let Some(e) = progress.save()
                {
                    progress.notice = Some(format!("{}; {e}", progress.notice.unwrap_or_default()));
                }
            }
            Err(e) => {
                progress.path = None;
                progress.notice = Some(format!(
                    "progress file {}: {what}; it cannot be moved aside ({e}), so it is left as \
                     it is and progress is kept in memory only this time",
                    path.display()
                ));
            }
        }
        progress
    }

    /// What the student must be told about the progress file as it was found (kept aside,
    /// partly unreadable, not a file), if anything; shown once when the app starts.
    #[must_use]
    pub fn notice(&self) -> Option<&str> {
        self.notice.as_deref()
    }

    /// The file progress is saved to, if any.
    #[must_use]
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// The key of a lesson: its slug, with the file's directory for lessons not built in.
    #[must_use]
    pub fn key(source: &str, slug: &str) -> String {
        match Path::new(source).parent() {
            Some(dir) if !source.starts_with("lessons/") => format!("{}#{slug}", dir.display()),
            _ => slug.to_string(),
        }
    }

    /// The record of lesson `key`.
    #[must_use]
    pub fn lesson(&self, key: &str) -> Option<&LessonProgress> {
        self.lessons.get(key)
    }

    /// Replaces the record of lesson `key` and saves; returns the save's error, if it failed
    /// (only the first failure is returned).
    pub fn update(&mut self, key: &str, record: LessonProgress) -> Option<String> {
        if self.lessons.get(key) == Some(&record) {
            return None;
        }
        self.lessons.insert(key.to_string(), record);
        self.save()
    }

    fn save(&mut self) -> Option<String> {
        let path = self.path.clone()?;
        let file = File {
            version: 1,
            lessons: self.lessons.clone(),
        };
        let result = (|| -> std::io::Result<()> {
            if let Some(dir) = path.parent()
                && !dir.as_os_str().is_empty()
            {
                std::fs::create_dir_all(dir)?;
            }
            let text = serde_json::to_string_pretty(&file).map_err(std::io::Error::other)?;
            crate::output::write(&path, text.as_bytes())
        })();
        match result {
            Ok(()) => None,
            Err(e) if self.error.is_none() => {
                let m = format!("progress not saved to {}: {e}", path.display());
                self.error = Some(m.clone());
                Some(m)
            }
            Err(_) => None,
        }
    }

    /// Steps done of a lesson of `steps` steps with `goals` (per step: has a goal) and
    /// `predictions` (per step: has one): a step is done when opened, its goal (if any) met and
    /// its prediction (if any) answered.
    #[must_use]
    pub fn done(&self, key: &str, goals: &[bool], predictions: &[bool]) -> usize {
        self.steps_done(key, goals, predictions)
            .iter()
            .filter(|d| **d)
            .count()
    }

    /// Per step of the lesson: done (as in [`Progress::done`]).
    #[must_use]
    pub fn steps_done(&self, key: &str, goals: &[bool], predictions: &[bool]) -> Vec<bool> {
        let Some(r) = self.lessons.get(key) else {
            return vec![false; goals.len()];
        };
        (0..goals.len())
            .map(|i| {
                r.visited.get(i).copied().unwrap_or(false)
                    && (!goals[i] || r.met.get(i).copied().unwrap_or(false))
                    && (!predictions[i] || r.answers.get(i).copied().flatten().is_some())
            })
            .collect()
    }
}

/// The most bytes read from a progress file (a real one is a few kilobytes).
const MAX_BYTES: u64 = 16 << 20;

/// The file's bytes, at most [`MAX_BYTES`].
fn read_limited(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(MAX_BYTES + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_BYTES {
        return Err(std::io::Error::other(format!(
            "larger than {} MiB",
            MAX_BYTES >> 20
        )));
    }
    Ok(bytes)
}

/// The lessons that could be read, and what could not (empty when the whole file was read).
fn parse(bytes: &[u8]) -> (BTreeMap<String, LessonProgress>, Vec<String>) {
    let mut lessons = BTreeMap::new();
    let mut problems = Vec::new();
    let value: serde_json::Value = match serde_json::from_slice(bytes) {
        Ok(v) => v,
        Err(e) => return (lessons, vec![format!("it is not valid JSON ({e})")]),
    };
    let Some(records) = value.get("lessons").and_then(serde_json::Value::as_object) else {
        return (
            lessons,
            vec!["it has no `lessons` object (not a springlab progress file)".to_string()],
        );
    };
    if value.get("version").and_then(serde_json::Value::as_u64) != Some(1) {
        problems.push("its `version` is not 1".to_string());
    }
    for (key, record) in records {
        let Some(fields) = record.as_object() else {
            problems.push(format!("lesson `{}` is not an object", excerpt(key)));
            continue;
        };
        let mut lesson = LessonProgress::default();
        let mut bad = Vec::new();
        for (name, value) in fields {
            let ok = match name.as_str() {
                "visited" => serde_json::from_value(value.clone()).map(|v| lesson.visited = v),
                "met" => serde_json::from_value(value.clone()).map(|v| lesson.met = v),
                "answers" => serde_json::from_value(value.clone()).map(|v| lesson.answers = v),
                // A field of a later version: not ours to judge.
                _ => Ok(()),
            };
            if ok.is_err() {
                bad.push(format!("`{name}`"));
            }
        }
        if !bad.is_empty() {
            problems.push(format!(
                "lesson `{}`: {} could not be read",
                excerpt(key),
                bad.join(", ")
            ));
        }
        lessons.insert(key.clone(), lesson);
    }
    (lessons, problems)
}

/// At most 60 characters of `text`, for a message.
fn excerpt(text: &str) -> String {
    match text.char_indices().nth(60) {
        Some((at, _)) => format!("{}…", &text[..at]),
        None => text.to_string(),
    }
}

/// Renames `path` to `path.unreadable-YYYYMMDDTHHMMSSZ` (a free name: `-2`, `-3`, … added when
/// taken); returns the new path.
fn keep_aside(path: &Path) -> std::io::Result<PathBuf> {
    let seconds = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let stamp = utc_stamp(seconds);
    let name = path.file_name().map_or_else(
        || "progress.json".into(),
        |n| n.to_string_lossy().into_owned(),
    );
    for n in 1..=100 {
        let suffix = if n == 1 {
            String::new()
        } else {
            format!("-{n}")
        };
        let aside = path.with_file_name(format!("{name}.unreadable-{stamp}{suffix}"));
        if std::fs::symlink_metadata(&aside).is_err() {
            std::fs::rename(path, &aside)?;
            return Ok(aside);
        }
    }
    Err(std::io::Error::other("no free name to keep it under"))
}

/// `YYYYMMDDTHHMMSSZ` of a time in seconds since 1970-01-01 UTC (proleptic Gregorian calendar;
/// days to a civil date by H. Hinnant's `civil_from_days`,
/// <https://howardhinnant.github.io/date_algorithms.html>).
fn utc_stamp(seconds: u64) -> String {
    let days = (seconds / 86_400) as i64;
    let rest = seconds % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}{month:02}{day:02}T{:02}{:02}{:02}Z",
        rest / 3600,
        rest / 60 % 60,
        rest % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_stamps_of_known_instants() {
        assert_eq!(utc_stamp(0), "19700101T000000Z");
        // 2000-02-29 12:34:56 UTC (a leap day) = 951 827 696 s.
        assert_eq!(utc_stamp(951_827_696), "20000229T123456Z");
        // 2026-11-26 23:45:00 UTC = 1 795 736 700 s.
        assert_eq!(utc_stamp(1_795_736_700), "20261126T234500Z");
    }

    #[test]
    fn one_bad_field_keeps_the_rest() {
        let text = br#"{"version":1,"lessons":{
            "rope":{"visited":[true,true],"met":"yes","answers":[1]},
            "hooke":{"visited":[true],"met":[true],"answers":[]},
            "odd":[1,2]}}"#;
        let (lessons, problems) = parse(text);
        assert_eq!(lessons["rope"].visited, [true, true]);
        assert!(lessons["rope"].met.is_empty());
        assert_eq!(lessons["rope"].answers, [Some(1)]);
        assert_eq!(lessons["hooke"].met, [true]);
        assert!(!lessons.contains_key("odd"));
        assert_eq!(problems.len(), 2, "{problems:?}");
        assert!(problems[0].contains("`met`") || problems[1].contains("`met`"));
    }
}
