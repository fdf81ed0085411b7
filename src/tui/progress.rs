//! What a student has done, kept between sessions: per lesson, the steps opened, the goals met
//! and the predictions made.
//!
//! The file is `progress.json` in the user's data directory (`directories`: for example
//! `~/.local/share/springlab/` on Linux, `~/Library/Application Support/springlab/` on macOS),
//! or in `$SPRINGLAB_DATA_DIR` when that is set (the tests use it). `springlab --no-save` (a
//! classroom machine) keeps progress in memory only. A file that cannot be read or parsed is
//! treated as empty and replaced on the next save; a save that fails is reported once on the
//! hint line and never stops the app. Lessons are keyed by their file and slug, steps by index.

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

    /// Progress read from `path` (empty when it does not exist or cannot be read), saved there.
    #[must_use]
    pub fn load(path: &Path) -> Progress {
        let lessons = std::fs::read_to_string(path)
            .ok()
            .and_then(|text| serde_json::from_str::<File>(&text).ok())
            .map(|f| f.lessons)
            .unwrap_or_default();
        Progress {
            lessons,
            path: Some(path.to_path_buf()),
            error: None,
        }
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
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir)?;
            }
            let text = serde_json::to_string_pretty(&file).map_err(std::io::Error::other)?;
            let tmp = path.with_extension("json.tmp");
            std::fs::write(&tmp, text)?;
            std::fs::rename(&tmp, &path)
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
