//! Runs computed ahead: a sequential search on one thread, its likely next runs on the others.
//!
//! # Why
//!
//! The studies' searches (advise's halvings of `dt`, its reference chain) decide each run from
//! the ones before it, so they cannot simply be spread over the cores. But their next run is
//! usually predictable (the next halving), and every run is a deterministic function of its
//! key (scene, method, steps): the same numbers whichever thread computes it, and whenever.
//! So the search itself stays exactly as written, one run at a time, and asks [`Ahead::get`]
//! for each run; helper threads compute the runs the search [`Ahead::hint`]s it will want next.
//! A run already computed is taken from the memo, one being computed is waited for, any other
//! is computed by the asking thread. The search therefore takes the same decisions and
//! reports the same numbers as without helpers (and with `SPRINGLAB_THREADS=1` there are none);
//! a guess that turns out unneeded costs only a core that would have waited, and is stopped as
//! soon as it leaves the hints.
//!
//! ```text
//! search:  get(k₀) ─ hint(k₁) ── get(k₁): wait ── hint(k₂) ── get(k₂) …
//! helper:             compute k₁ ───────────────── compute k₂ ───────
//! ```
//!
//! Reference: J. L. Hennessy, D. A. Patterson, *Computer Architecture: A Quantitative
//! Approach*, 6th ed., 2017, §3.6 (speculation: work done before it is known to be needed,
//! committed only when it is, discarded otherwise).

use std::collections::{HashMap, HashSet};
use std::hash::Hash;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};

/// What a computation is told: stop early (return `None`) when this becomes true.
pub type Cancel = AtomicBool;

struct Memo<K, R> {
    done: HashMap<K, R>,
    /// Keys being computed, with the flag that stops a guess nobody wants any more.
    running: HashMap<K, Arc<Cancel>>,
    /// Keys the search has asked for: never cancelled.
    demanded: HashSet<K>,
    /// The search's guesses, most likely first.
    hints: Vec<K>,
    finished: bool,
}

/// The memo of runs shared by the search and its helpers (module docs).
pub struct Ahead<'f, K, R> {
    memo: Mutex<Memo<K, R>>,
    changed: Condvar,
    compute: &'f (dyn Fn(&K, &Cancel) -> Option<R> + Sync),
    /// Helpers start a guess only while this says a core is free.
    idle: &'f (dyn Fn() -> bool + Sync),
    /// Whether there are helpers: then every run steps on its own thread alone
    /// ([`crate::physics::pool::alone`]), since the search and its helpers share the cores.
    shared: bool,
    /// Helpers start a guess only while fewer computations than this run (the search's
    /// included): one per core, so that a long list of hints never oversubscribes the cores.
    slots: usize,
}

impl<K: Clone + Eq + Hash + Send, R: Clone + Send> Ahead<'_, K, R> {
    fn lock(&self) -> MutexGuard<'_, Memo<K, R>> {
        self.memo.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The result for `key`: from the memo, from a helper computing it, or computed here.
    pub fn get(&self, key: &K) -> R {
        let mut memo = self.lock();
        memo.demanded.insert(key.clone());
        loop {
            if let Some(r) = memo.done.get(key) {
                return r.clone();
            }
            match memo.running.get(key) {
                Some(cancel) => {
                    // Wanted now: a guess being computed must finish.
                    cancel.store(false, Ordering::SeqCst);
                    memo = self
                        .changed
                        .wait(memo)
                        .unwrap_or_else(PoisonError::into_inner);
                }
                None => break,
            }
        }
        let never = Arc::new(Cancel::new(false));
        memo.running.insert(key.clone(), Arc::clone(&never));
        drop(memo);
        let result = loop {
            // A demanded computation is never cancelled, so it always gives a result.
            if let Some(r) = self.compute_here(key, &never) {
                break r;
            }
            never.store(false, Ordering::SeqCst);
        };
        let mut memo = self.lock();
        memo.running.remove(key);
        memo.done.insert(key.clone(), result.clone());
        self.changed.notify_all();
        result
    }

    /// The result for `key` when it has been computed, without computing or waiting for it.
    pub fn peek(&self, key: &K) -> Option<R> {
        self.lock().done.get(key).cloned()
    }

    /// The runs the search will probably ask for next, most likely first; replaces the last
    /// hints and stops the guesses no longer among them.
    pub fn hint(&self, keys: Vec<K>) {
        let mut memo = self.lock();
        for (key, cancel) in &memo.running {
            if !keys.contains(key) && !memo.demanded.contains(key) {
                cancel.store(true, Ordering::SeqCst);
            }
        }
        memo.hints = keys;
        self.changed.notify_all();
    }

    /// A helper's loop: compute the first hinted key nobody has computed or started, until
    /// [`Ahead::finish`].
    fn help(&self) {
        loop {
            let mut memo = self.lock();
            let (key, cancel) = loop {
                if memo.finished {
                    return;
                }
                let next = memo
                    .hints
                    .iter()
                    .find(|k| !memo.done.contains_key(*k) && !memo.running.contains_key(*k))
                    .cloned();
                if let Some(key) = next {
                    if memo.running.len() < self.slots && (self.idle)() {
                        let cancel = Arc::new(Cancel::new(false));
                        memo.running.insert(key.clone(), Arc::clone(&cancel));
                        break (key, cancel);
                    }
                    // No core free yet: look again soon (a computation that ends notifies).
                    memo = self
                        .changed
                        .wait_timeout(memo, IDLE_POLL)
                        .unwrap_or_else(PoisonError::into_inner)
                        .0;
                    continue;
                }
                memo = self
                    .changed
                    .wait(memo)
                    .unwrap_or_else(PoisonError::into_inner);
            };
            drop(memo);
            // A guess that panics is dropped like a cancelled one: the search, asking for it,
            // computes it itself and meets the same panic on its own thread.
            let result = catch_unwind(AssertUnwindSafe(|| self.compute_here(&key, &cancel)))
                .ok()
                .flatten();
            let mut memo = self.lock();
            memo.running.remove(&key);
            if let Some(r) = result {
                memo.done.insert(key, r);
            }
            self.changed.notify_all();
        }
    }

    /// One computation on this thread; with helpers, its simulation steps without the global
    /// pool's workers (the same bits either way): the search and each helper already keep a
    /// core busy, and a pool worker woken for their small passes, spinning after each, would
    /// only take time from them.
    fn compute_here(&self, key: &K, cancel: &Cancel) -> Option<R> {
        if self.shared {
            crate::physics::pool::alone(|| (self.compute)(key, cancel))
        } else {
            (self.compute)(key, cancel)
        }
    }

    /// Stops every helper (their guesses are cancelled).
    fn finish(&self) {
        let mut memo = self.lock();
        memo.finished = true;
        memo.hints.clear();
        for cancel in memo.running.values() {
            cancel.store(true, Ordering::SeqCst);
        }
        self.changed.notify_all();
    }
}

/// Stops the helpers when the search ends, also when it panics.
struct Finish<'a, 'f, K: Clone + Eq + Hash + Send, R: Clone + Send>(&'a Ahead<'f, K, R>);

impl<K: Clone + Eq + Hash + Send, R: Clone + Send> Drop for Finish<'_, '_, K, R> {
    fn drop(&mut self) {
        self.0.finish();
    }
}

/// How often a helper waiting for a free core looks again.
const IDLE_POLL: std::time::Duration = std::time::Duration::from_millis(20);

/// Runs `search` with `helpers` helper threads computing its hinted runs with `compute`
/// (`compute(key, cancel)`: the result, or `None` when `cancel` became true). With no helper
/// the search computes every run itself, one after another.
pub fn with_helpers<K, R, T>(
    helpers: usize,
    compute: &(dyn Fn(&K, &Cancel) -> Option<R> + Sync),
    search: impl FnOnce(&Ahead<'_, K, R>) -> T,
) -> T
where
    K: Clone + Eq + Hash + Send,
    R: Clone + Send,
{
    with_helpers_when(helpers, compute, &|| true, search)
}

/// [`with_helpers`] whose helpers start a guess only while `idle()` (a core is free: the
/// stability study's other searches leave one).
pub fn with_helpers_when<K, R, T>(
    helpers: usize,
    compute: &(dyn Fn(&K, &Cancel) -> Option<R> + Sync),
    idle: &(dyn Fn() -> bool + Sync),
    search: impl FnOnce(&Ahead<'_, K, R>) -> T,
) -> T
where
    K: Clone + Eq + Hash + Send,
    R: Clone + Send,
{
    run_with(helpers, usize::MAX, compute, idle, search)
}

/// [`with_helpers`] for a search that hints many runs at once (advise: the next halving, the
/// verification, the next methods' and models' first runs): `cores` helpers, but at most `cores`
/// computations at a time, the search's own included, each helper taking the first hint nobody
/// has started, so the cores stay busy with the likeliest runs and are never oversubscribed.
/// With `cores < 2` the search computes every run itself.
pub fn with_cores<K, R, T>(
    cores: usize,
    compute: &(dyn Fn(&K, &Cancel) -> Option<R> + Sync),
    search: impl FnOnce(&Ahead<'_, K, R>) -> T,
) -> T
where
    K: Clone + Eq + Hash + Send,
    R: Clone + Send,
{
    let helpers = if cores < 2 { 0 } else { cores };
    run_with(helpers, cores.max(1), compute, &|| true, search)
}

fn run_with<K, R, T>(
    helpers: usize,
    slots: usize,
    compute: &(dyn Fn(&K, &Cancel) -> Option<R> + Sync),
    idle: &(dyn Fn() -> bool + Sync),
    search: impl FnOnce(&Ahead<'_, K, R>) -> T,
) -> T
where
    K: Clone + Eq + Hash + Send,
    R: Clone + Send,
{
    let ahead = Ahead {
        memo: Mutex::new(Memo {
            done: HashMap::new(),
            running: HashMap::new(),
            demanded: HashSet::new(),
            hints: Vec::new(),
            finished: false,
        }),
        changed: Condvar::new(),
        compute,
        idle,
        shared: helpers > 0,
        slots,
    };
    std::thread::scope(|scope| {
        for _ in 0..helpers {
            scope.spawn(|| ahead.help());
        }
        let _finish = Finish(&ahead);
        search(&ahead)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    /// A search that doubles its key until a condition, with hints of the next key: the same
    /// answers with and without helpers, every demanded key computed exactly once.
    #[test]
    fn a_search_gets_the_same_results_with_and_without_helpers() {
        for helpers in [0, 1, 3] {
            let computed = AtomicUsize::new(0);
            let compute = |k: &u64, cancel: &Cancel| {
                let mut acc = *k;
                for i in 0..10_000u64 {
                    if i % 1000 == 0 && cancel.load(Ordering::SeqCst) {
                        return None;
                    }
                    acc = acc.wrapping_mul(6364136223846793005).wrapping_add(i);
                }
                computed.fetch_add(1, Ordering::SeqCst);
                Some(acc)
            };
            let results = with_helpers(helpers, &compute, |ahead| {
                let mut out = Vec::new();
                let mut k = 1u64;
                while k < 1 << 12 {
                    ahead.hint(vec![2 * k, 4 * k]);
                    out.push(ahead.get(&k));
                    k *= 2;
                }
                out
            });
            let expected: Vec<u64> = (0..12)
                .map(|e| {
                    let mut acc = 1u64 << e;
                    for i in 0..10_000u64 {
                        acc = acc.wrapping_mul(6364136223846793005).wrapping_add(i);
                    }
                    acc
                })
                .collect();
            assert_eq!(results, expected, "{helpers} helpers");
            assert!(computed.load(Ordering::SeqCst) >= 12);
        }
    }

    /// While the search computes a run itself, with `with_cores(2)` only one helper computes
    /// beside it, however many runs are hinted; the answers are those of the search alone.
    #[test]
    fn with_cores_keeps_to_its_cores() {
        use std::time::{Duration, Instant};
        let busy = AtomicUsize::new(0);
        let most = AtomicUsize::new(0);
        let spin = |d: Duration, mut each: Box<dyn FnMut(Duration) + '_>| {
            let start = Instant::now();
            while start.elapsed() < d {
                each(start.elapsed());
                std::hint::spin_loop();
            }
        };
        let compute = |k: &u64, _: &Cancel| {
            busy.fetch_add(1, Ordering::SeqCst);
            if *k == 0 {
                // The search's own run: after its first 40 ms (the guesses helpers may have
                // started before it began are over), count the computations beside it.
                spin(
                    Duration::from_millis(120),
                    Box::new(|t| {
                        if t > Duration::from_millis(40) {
                            most.fetch_max(busy.load(Ordering::SeqCst), Ordering::SeqCst);
                        }
                    }),
                );
            } else {
                spin(Duration::from_millis(1), Box::new(|_| {}));
            }
            busy.fetch_sub(1, Ordering::SeqCst);
            Some(k * k)
        };
        let search = |ahead: &Ahead<'_, u64, u64>| {
            // Many short runs hinted, then a long one not hinted: the search computes it.
            ahead.hint((1..1000).collect());
            let mut out = vec![ahead.get(&0)];
            out.extend((1..5).map(|k| ahead.get(&k)));
            out
        };
        let alone = with_cores(1, &compute, search);
        assert_eq!(alone, vec![0, 1, 4, 9, 16]);
        most.store(0, Ordering::SeqCst);
        assert_eq!(with_cores(2, &compute, search), alone);
        let most = most.load(Ordering::SeqCst);
        assert!(most <= 2, "{most} computations at once on two cores");
    }
}
