//! A tiny persistent worker pool for deterministic data-parallel loops.
//!
//! # Theory
//!
//! Starting a thread costs tens of microseconds, about as long as one step of the jelly cube,
//! so the workers are started once and then wait for work. Each job is one function
//! `job(part)` for `part = 0, 1, …, parts - 1`. The caller and the workers take parts from a
//! shared counter until none is left; [`Pool::run`] returns when every part is done.
//!
//! ```text
//! caller:   publish job, epoch += 1 ──► take parts, run them ──► close the job,
//!                                                               wait for workers inside ──► return
//! worker:   (spin, then sleep) until epoch changes ──► enter the job (if still open),
//!                                                     take parts, run them ──► leave ──► (spin …)
//! ```
//! Taking parts, rather than giving part `k` to worker `k`, matters on a busy machine: when the
//! operating system has paused a worker, the caller runs that worker's part itself instead of
//! waiting for the worker's next time slice (milliseconds).
//!
//! **Determinism.** The pool decides only *who* runs a part, never *what* a part computes: the
//! caller splits the data into parts by a fixed rule, and each part writes only its own outputs.
//! So the result is the same bit for bit whichever thread runs a part, and even when there is no
//! free worker and the caller runs all parts itself ([`Pool::run`] does that when another thread is
//! already using the pool). No floating-point value is ever combined across threads in an order
//! that depends on timing (no atomics on floats, no "whoever finishes first adds first").
//!
//! **Idle workers use no CPU.** After a job a worker spins for [`SPIN`] (a step of a running
//! simulation usually follows within microseconds, and waking a sleeping thread costs about as
//! much as the step), then parks in the operating system until the next job. A paused
//! simulation therefore costs nothing. (This is not covered by a test: a test that measures
//! CPU time would be a timed test.)
//!
//! **Waking without losing a job** (the "lost wake-up" problem): the worker first announces
//! `sleeping = true`, then looks at the epoch once more, and parks only if it is unchanged; the
//! caller first bumps the epoch, then unparks every worker that announced sleeping. With
//! sequentially consistent atomics at least one of the two sees the other's write, and
//! `std::thread::park` keeps an unpark that arrives before the park, so a job is never missed.
//!
//! References: M. Herlihy, N. Shavit, *The Art of Multiprocessor Programming*, 2nd ed., Morgan
//! Kaufmann 2020, §7 (spin locks and contention) and §8.4 (condition variables and the lost
//! wake-up problem); the Rust standard library documentation of `std::thread::park`.

use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock, TryLockError};
use std::thread::{self, JoinHandle, Thread};
use std::time::{Duration, Instant};

/// How long a worker keeps spinning after a job before it parks (and a caller spins before it
/// starts yielding its time slice while waiting for the workers).
pub const SPIN: Duration = Duration::from_micros(200);

/// At most this many threads (caller included) in the global pool: enough for a 64-core
/// workstation; a pass never uses more parts than its work pays for (see
/// `stencil::MIN_SLOTS_PER_PART`) nor more than `stencil::MAX_PARTS`.
pub const MAX_THREADS: usize = 64;

/// The environment variable that overrides the global pool's size (1 turns threading off).
pub const THREADS_ENV: &str = "SPRINGLAB_THREADS";

/// The global pool's size: `override_` (the value of [`THREADS_ENV`]) when it is a whole number
/// ≥ 1, else the cores the operating system offers this process (`available_parallelism`,
/// which honours CPU affinity and cgroup quotas); at most [`MAX_THREADS`].
#[must_use]
pub fn threads_for(override_: Option<&str>, available: Option<usize>) -> usize {
    override_
        .and_then(|s| s.trim().parse::<usize>().ok())
        .filter(|&n| n >= 1)
        .unwrap_or_else(|| available.unwrap_or(1))
        .clamp(1, MAX_THREADS)
}

/// A job as the workers see it: the caller's closure with its lifetime erased (see
/// [`Pool::run`] for why that is sound) and the number of parts.
#[derive(Clone, Copy)]
struct Job {
    function: *const (dyn Fn(usize) + Sync + 'static),
    parts: usize,
}

// SAFETY: `function` points to a `Sync` closure, so calling it from another thread is allowed;
// the pointer is only dereferenced while the caller of `Pool::run` keeps the closure alive.
unsafe impl Send for Job {}

/// State shared between the caller and the workers.
struct Shared {
    /// Incremented once per job; a worker looks for a job when it sees a new value.
    epoch: AtomicU64,
    /// The open job, if any. A worker enters it (counted in `running`) while holding this lock;
    /// the caller closes it (sets `None`) under the lock, after which no worker can enter.
    job: Mutex<Option<Job>>,
    /// The next part to take.
    next: AtomicUsize,
    /// Workers inside the current job.
    running: AtomicUsize,
    /// One flag per worker: true while it is (about to be) parked.
    sleeping: Vec<AtomicBool>,
    /// Set when a part run by a worker panicked; the caller re-raises it.
    panicked: AtomicBool,
    /// Set when the pool is dropped: the workers exit.
    shutdown: AtomicBool,
}

/// A fixed set of worker threads that run the parts of one job at a time (see the module docs).
pub struct Pool {
    shared: Arc<Shared>,
    workers: Vec<(Thread, JoinHandle<()>)>,
    /// Held while a job runs; a second caller that finds it taken runs its parts itself.
    submit: Mutex<()>,
    /// How many threads [`Pool::threads`] offers (at most the workers + 1).
    active: AtomicUsize,
}

impl Pool {
    /// A pool with `threads` threads in all: the caller plus `threads - 1` workers.
    ///
    /// # Panics
    /// If a worker thread cannot be started.
    #[must_use]
    pub fn new(threads: usize) -> Pool {
        let count = threads.max(1) - 1;
        let shared = Arc::new(Shared {
            epoch: AtomicU64::new(0),
            job: Mutex::new(None),
            next: AtomicUsize::new(0),
            running: AtomicUsize::new(0),
            sleeping: (0..count).map(|_| AtomicBool::new(false)).collect(),
            panicked: AtomicBool::new(false),
            shutdown: AtomicBool::new(false),
        });
        let workers = (0..count)
            .map(|k| {
                let shared = Arc::clone(&shared);
                let handle = thread::Builder::new()
                    .name(format!("springlab-worker-{}", k + 1))
                    .spawn(move || worker(&shared, k))
                    .expect("start a worker thread");
                (handle.thread().clone(), handle)
            })
            .collect();
        Pool {
            shared,
            workers,
            submit: Mutex::new(()),
            active: AtomicUsize::new(count + 1),
        }
    }

    /// The process-wide pool, started on first use: one thread per core the machine offers,
    /// or the number in the environment variable `SPRINGLAB_THREADS` (see [`threads_for`];
    /// 1 turns threading off). A pass uses only as many of them as its size pays for.
    pub fn global() -> &'static Pool {
        static POOL: OnceLock<Pool> = OnceLock::new();
        POOL.get_or_init(|| {
            let threads = threads_for(
                std::env::var(THREADS_ENV).ok().as_deref(),
                thread::available_parallelism().ok().map(usize::from),
            );
            Pool::new(threads)
        })
    }

    /// Number of threads offered to callers, the caller included (see [`Pool::set_threads`]);
    /// 1 inside [`alone`].
    #[must_use]
    pub fn threads(&self) -> usize {
        if ALONE.with(Cell::get) {
            return 1;
        }
        self.active.load(Ordering::Relaxed)
    }

    /// Offers only `threads` threads from now on (at least 1, at most the number the pool was
    /// started with), for example to compare one thread with two. Results do not change.
    pub fn set_threads(&self, threads: usize) {
        self.active
            .store(threads.clamp(1, self.workers.len() + 1), Ordering::Relaxed);
    }

    /// Runs `job(0)`, `job(1)`, …, `job(parts - 1)`, in parallel where workers are free, and
    /// returns when all have finished. Each part runs exactly once, on the caller's thread or a
    /// worker's; all of them run on the caller's thread when another thread is using the pool
    /// — the same results, because a part's work never depends on who runs it.
    ///
    /// # Panics
    /// If a part panics (after all parts have finished).
    pub fn run(&self, parts: usize, job: &(dyn Fn(usize) + Sync)) {
        let sequential = || (0..parts).for_each(job);
        if parts <= 1 || self.workers.is_empty() || ALONE.with(Cell::get) {
            return sequential();
        }
        let _guard = match self.submit.try_lock() {
            Ok(guard) => guard,
            Err(TryLockError::Poisoned(poisoned)) => poisoned.into_inner(),
            // Another thread's job is running: do ours here rather than wait.
            Err(TryLockError::WouldBlock) => return sequential(),
        };
        let shared = &*self.shared;
        // SAFETY: only the lifetime is changed. A worker dereferences the pointer only between
        // entering the job (under the `job` lock, while it is open) and leaving it
        // (`running -= 1`), and `Finish` below does not let this function return (or unwind)
        // before the job is closed and no worker is inside, so `job` outlives every use.
        let function: *const (dyn Fn(usize) + Sync + 'static) = unsafe {
            std::mem::transmute::<*const (dyn Fn(usize) + Sync + '_), _>(std::ptr::from_ref(job))
        };
        {
            let mut open = lock(&shared.job);
            shared.next.store(0, Ordering::SeqCst);
            // A worker's panic in an earlier job whose caller panicked too (and so never looked
            // at the flag) belongs to that job, not this one.
            shared.panicked.store(false, Ordering::SeqCst);
            *open = Some(Job { function, parts });
        }
        shared.epoch.fetch_add(1, Ordering::SeqCst);
        for ((thread, _), sleeping) in self.workers.iter().zip(&shared.sleeping) {
            if sleeping.load(Ordering::SeqCst) {
                thread.unpark();
            }
        }
        {
            // Closes the job and waits for the workers inside, even if a part panics here.
            let _finish = Finish { shared };
            take_parts(shared, job, parts);
        }
        if shared.panicked.swap(false, Ordering::SeqCst) {
            panic!("a worker thread panicked");
        }
    }
}

thread_local! {
    /// Set inside [`alone`]: this thread's jobs run on this thread only.
    static ALONE: Cell<bool> = const { Cell::new(false) };
}

/// Runs `f` with every job this thread gives the pool run on this thread alone, and
/// [`Pool::threads`] answering 1 here, so passes are split as for one thread. For work that runs
/// beside a simulation using the pool (`springlab lesson N --homework`'s comparison): no worker
/// is woken, none spins after each of its small jobs on a core the simulation and the student's
/// program need. The results are the same bit for bit (module docs).
pub fn alone<R>(f: impl FnOnce() -> R) -> R {
    struct Restore(bool);
    impl Drop for Restore {
        fn drop(&mut self) {
            ALONE.with(|a| a.set(self.0));
        }
    }
    let _restore = Restore(ALONE.with(|a| a.replace(true)));
    f()
}

/// What became of a job of [`independent`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JobEvent {
    /// The job started.
    Started,
    /// The job ended (its result is kept).
    Finished,
}

/// Runs `job(0)`, …, `job(count - 1)` on up to `threads` scoped threads and returns their
/// results in index order; `event(i, …)` is called on the calling thread as job `i` starts and
/// as it ends (a terminal's progress).
///
/// For independent runs (the levels of a study, a verification beside its confirmation):
/// heaviest first by `weight` (largest-processing-time first, so that the longest job does not
/// start last), each job taken from a shared counter by the next free thread. A job's result
/// depends only on its index, never on the thread that runs it, so the results are the same
/// bit for bit for any `threads`; with one thread the jobs run on the caller in index order.
/// With more than one thread each job steps on its thread [`alone`] (the same bits): the jobs
/// already keep the cores busy, and a pool worker woken for one job's small passes, spinning
/// after each, would only take time from the job beside it.
///
/// Reference: R. L. Graham, "Bounds on multiprocessing timing anomalies", *SIAM J. Appl.
/// Math.* 17 (1969) 416–429 (largest processing time first).
///
/// # Panics
/// If a job panics.
pub fn independent<R: Send>(
    count: usize,
    threads: usize,
    weight: impl Fn(usize) -> f64,
    job: impl Fn(usize) -> R + Sync,
    mut event: impl FnMut(usize, JobEvent),
) -> Vec<R> {
    let threads = threads.clamp(1, count.max(1));
    if threads == 1 {
        return (0..count)
            .map(|i| {
                event(i, JobEvent::Started);
                let r = job(i);
                event(i, JobEvent::Finished);
                r
            })
            .collect();
    }
    let mut order: Vec<usize> = (0..count).collect();
    order.sort_by(|&a, &b| weight(b).total_cmp(&weight(a)).then(a.cmp(&b)));
    let next = AtomicUsize::new(0);
    let mut results: Vec<Option<R>> = (0..count).map(|_| None).collect();
    thread::scope(|scope| {
        let (tx, rx) = std::sync::mpsc::channel::<(usize, Option<R>)>();
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, order, job) = (&next, &order, &job);
            scope.spawn(move || {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&i) = order.get(k) else { break };
                    if tx.send((i, None)).is_err() || tx.send((i, Some(alone(|| job(i))))).is_err()
                    {
                        break;
                    }
                }
            });
        }
        drop(tx);
        // Ends when every thread has finished (or one panicked: the scope then panics too).
        for (i, result) in rx {
            match result {
                None => event(i, JobEvent::Started),
                Some(r) => {
                    results[i] = Some(r);
                    event(i, JobEvent::Finished);
                }
            }
        }
    });
    results
        .into_iter()
        .map(|r| r.expect("every job ran (a panic would have ended the scope)"))
        .collect()
}

impl Pool {
    /// Calls `body(start, a_part, b_part)` for `parts` (at most 8) contiguous, equally long
    /// pieces of `a` and `b` (which must be equally long), where `start` is the index of the
    /// piece's first element; in parallel where workers are free. Every element is in exactly
    /// one piece, so a `body` that treats each element on its own gives the same result for
    /// any `parts`.
    ///
    /// # Panics
    /// If `a` and `b` differ in length, or a call of `body` panics.
    pub fn for_each_part<A: Send, B: Send>(
        &self,
        a: &mut [A],
        b: &mut [B],
        parts: usize,
        body: impl Fn(usize, &mut [A], &mut [B]) + Sync,
    ) {
        const MAX: usize = 8;
        assert_eq!(a.len(), b.len(), "equally long slices");
        let parts = parts.clamp(1, MAX);
        let n = a.len();
        if parts == 1 {
            return body(0, a, b);
        }
        let start = |k: usize| n * k / parts;
        let (mut rest_a, mut rest_b) = (a, b);
        let pieces: [Mutex<(&mut [A], &mut [B])>; MAX] = std::array::from_fn(|k| {
            let len = if k < parts {
                start(k + 1) - start(k)
            } else {
                0
            };
            let (mine_a, others_a) = std::mem::take(&mut rest_a).split_at_mut(len);
            let (mine_b, others_b) = std::mem::take(&mut rest_b).split_at_mut(len);
            (rest_a, rest_b) = (others_a, others_b);
            Mutex::new((mine_a, mine_b))
        });
        self.run(parts, &|k| {
            let mut piece = lock(&pieces[k]);
            let (a, b) = &mut *piece;
            body(start(k), a, b);
        });
    }
}

impl Drop for Pool {
    fn drop(&mut self) {
        self.shared.shutdown.store(true, Ordering::SeqCst);
        for (thread, handle) in self.workers.drain(..) {
            thread.unpark();
            let _ = handle.join();
        }
    }
}

/// Runs parts from the shared counter until none is left.
fn take_parts(shared: &Shared, job: &(dyn Fn(usize) + Sync), parts: usize) {
    loop {
        let part = shared.next.fetch_add(1, Ordering::SeqCst);
        if part >= parts {
            return;
        }
        job(part);
    }
}

/// Closes the current job, then blocks (spinning, then yielding) until no worker is inside.
struct Finish<'a> {
    shared: &'a Shared,
}

impl Drop for Finish<'_> {
    fn drop(&mut self) {
        *lock(&self.shared.job) = None;
        let start = Instant::now();
        while self.shared.running.load(Ordering::Acquire) > 0 {
            if start.elapsed() < SPIN {
                std::hint::spin_loop();
            } else {
                // A worker was descheduled in the middle of a part (a busy machine): let it
                // have our core.
                thread::yield_now();
            }
        }
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The loop of worker `k`.
fn worker(shared: &Shared, k: usize) {
    let mut seen = 0;
    loop {
        // Wait for a new epoch: spin for a while, then sleep.
        let start = Instant::now();
        loop {
            if shared.shutdown.load(Ordering::SeqCst) {
                return;
            }
            let epoch = shared.epoch.load(Ordering::Acquire);
            if epoch != seen {
                seen = epoch;
                break;
            }
            if start.elapsed() < SPIN {
                std::hint::spin_loop();
            } else {
                shared.sleeping[k].store(true, Ordering::SeqCst);
                if shared.epoch.load(Ordering::SeqCst) == seen
                    && !shared.shutdown.load(Ordering::SeqCst)
                {
                    thread::park();
                }
                shared.sleeping[k].store(false, Ordering::SeqCst);
            }
        }
        // Enter the job if it is still open (a late worker finds it closed, or a newer one).
        let job = {
            let open = lock(&shared.job);
            if open.is_some() {
                shared.running.fetch_add(1, Ordering::SeqCst);
            }
            *open
        };
        if let Some(job) = job {
            // SAFETY: the caller of `Pool::run` keeps the closure alive until the job is closed
            // and `running` is back to zero (see `Pool::run`), and the closure is `Sync`.
            let function = unsafe { &*job.function };
            if catch_unwind(AssertUnwindSafe(|| take_parts(shared, function, job.parts))).is_err() {
                shared.panicked.store(true, Ordering::SeqCst);
            }
            shared.running.fetch_sub(1, Ordering::Release);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicU32;

    #[test]
    fn independent_jobs_return_in_index_order_for_any_thread_count() {
        // Job i sums 1..=i the long way: its result is i (i + 1) / 2 whoever runs it.
        let job = |i: usize| (1..=i as u64).sum::<u64>();
        for threads in 1..=4 {
            let mut seen = Vec::new();
            let out = super::independent(
                9,
                threads,
                |i| (i % 4) as f64,
                job,
                |i, e| {
                    seen.push((i, e));
                },
            );
            let want: Vec<u64> = (0..9u64).map(|i| i * (i + 1) / 2).collect();
            assert_eq!(out, want, "{threads} threads");
            // Each job starts once and then ends once.
            for i in 0..9 {
                let events: Vec<JobEvent> = (seen.iter())
                    .filter(|(j, _)| *j == i)
                    .map(|&(_, e)| e)
                    .collect();
                assert_eq!(events, [JobEvent::Started, JobEvent::Finished], "job {i}");
            }
        }
    }

    #[test]
    fn every_part_runs_exactly_once() {
        let pool = Pool::new(2);
        for parts in 0..6 {
            let counts: Vec<AtomicU32> = (0..parts).map(|_| AtomicU32::new(0)).collect();
            pool.run(parts, &|k| {
                counts[k].fetch_add(1, Ordering::SeqCst);
            });
            assert!(counts.iter().all(|c| c.load(Ordering::SeqCst) == 1));
        }
    }

    #[test]
    fn for_each_part_visits_every_element_once_with_its_index() {
        let pool = Pool::new(2);
        for parts in 1..=5 {
            let mut a: Vec<usize> = vec![0; 37];
            let mut b: Vec<usize> = vec![0; 37];
            pool.for_each_part(&mut a, &mut b, parts, |start, a, b| {
                for (i, (a, b)) in a.iter_mut().zip(b.iter_mut()).enumerate() {
                    *a += start + i;
                    *b += 1;
                }
            });
            assert_eq!(a, (0..37).collect::<Vec<_>>());
            assert!(b.iter().all(|&b| b == 1));
        }
    }

    #[test]
    fn a_parked_worker_wakes_up() {
        let pool = Pool::new(2);
        let count = AtomicU32::new(0);
        for _ in 0..3 {
            // Long enough for the worker to stop spinning and park.
            thread::sleep(SPIN * 5);
            pool.run(2, &|_| {
                count.fetch_add(1, Ordering::SeqCst);
            });
        }
        assert_eq!(count.load(Ordering::SeqCst), 6);
    }

    #[test]
    fn a_panicking_part_is_reported_to_the_caller() {
        let pool = Pool::new(2);
        let result = catch_unwind(AssertUnwindSafe(|| {
            pool.run(2, &|k| assert!(k != 1, "part 1 fails"));
        }));
        assert!(result.is_err());
        // The pool still works afterwards.
        let count = AtomicU32::new(0);
        pool.run(2, &|_| {
            count.fetch_add(1, Ordering::SeqCst);
        });
        assert_eq!(count.load(Ordering::SeqCst), 2);
    }

    #[test]
    fn a_panic_belongs_to_its_own_job() {
        let pool = Pool::new(2);
        for _ in 0..20 {
            // Every part panics, the caller's too: the caller unwinds without looking at the
            // workers' flag.
            let result = catch_unwind(AssertUnwindSafe(|| {
                pool.run(2, &|_| panic!("every part fails"));
            }));
            assert!(result.is_err());
            // The next job has no panic, and must not report one.
            pool.run(2, &|_| {});
        }
    }
}
