//! Work a step repeats each time it opens (`n` and `p` back and forth, `R`, a test opening the
//! same step for every option of its prediction): its text's numbers and study charts and the
//! bodies' spectra. Each is a function of its inputs alone, so it is kept here under a hash of
//! the inputs' whole contents (every field and every number to the last bit, through `Debug`),
//! the last [`KEPT`] of each kind for the whole process: opening a step again finds them at once.

use std::collections::VecDeque;
use std::fmt::{Debug, Write};
use std::hash::{DefaultHasher, Hasher};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// A hash of `value`'s `Debug` text (numbers as the shortest text that reads back to the same
/// bits), fed to the hasher as it is written: a jelly's scene prints megabytes.
#[must_use]
pub fn key(value: &impl Debug) -> u64 {
    struct Feed(DefaultHasher);
    impl Write for Feed {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            self.0.write(s.as_bytes());
            Ok(())
        }
    }
    let mut feed = Feed(DefaultHasher::new());
    // Writing into the hasher cannot fail.
    let _ = write!(feed, "{value:?}");
    feed.0.finish()
}

/// How many results of each kind the app's memos keep: more than every body of every step of
/// the built-in lessons (tested), so that a student going through every lesson and back, or
/// a test suite opening every step several times, computes each once. The largest kept
/// result, a dense spectrum, is a few tens of kilobytes.
pub const KEPT: usize = 128;

/// The last `capacity` results of one kind, by [`key`].
pub struct Memo<V> {
    entries: Mutex<VecDeque<(u64, V)>>,
    capacity: usize,
}

impl<V: Clone> Memo<V> {
    /// An empty memo keeping at most `capacity` results.
    #[must_use]
    pub const fn new(capacity: usize) -> Self {
        Memo {
            entries: Mutex::new(VecDeque::new()),
            capacity,
        }
    }

    /// The result kept under `key`, or `compute`'s, then kept (the oldest leaves when full).
    /// The lock is not held while computing: two threads asking at once both compute.
    pub fn get_or(&self, key: u64, compute: impl FnOnce() -> V) -> V {
        if let Some((_, v)) = self.lock().iter().find(|(k, _)| *k == key) {
            return v.clone();
        }
        let v = compute();
        let mut entries = self.lock();
        if !entries.iter().any(|(k, _)| *k == key) {
            if entries.len() >= self.capacity {
                entries.pop_front();
            }
            entries.push_back((key, v.clone()));
        }
        v
    }

    fn lock(&self) -> MutexGuard<'_, VecDeque<(u64, V)>> {
        self.entries.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_result_is_computed_once_per_content_and_the_oldest_leaves() {
        let memo = Memo::new(2);
        let calls = std::cell::Cell::new(0);
        let get = |x: f64| {
            memo.get_or(key(&x), || {
                calls.set(calls.get() + 1);
                x * 2.0
            })
        };
        assert_eq!(get(1.0), 2.0);
        assert_eq!(get(1.0), 2.0);
        // -0.0 and 0.0 print differently: two contents.
        assert_eq!(get(0.0), 0.0);
        assert_eq!(get(-0.0), -0.0);
        // 1.0 was the oldest of three: it left.
        assert_eq!(get(1.0), 2.0);
        assert_eq!(calls.get(), 4);
        assert_ne!(key(&0.1), key(&(0.1 + f64::EPSILON)));
    }

    #[test]
    fn the_memos_keep_every_body_of_every_built_in_step() {
        let mut bodies = 0;
        for lesson in crate::lesson::builtin() {
            for step in lesson.expect("a built-in lesson loads").steps {
                bodies += step
                    .build_scene()
                    .expect("a built-in step builds")
                    .bodies
                    .len();
            }
        }
        assert!(bodies > 30, "{bodies} bodies");
        assert!(KEPT >= bodies, "{KEPT} kept for {bodies} bodies");
    }
}
