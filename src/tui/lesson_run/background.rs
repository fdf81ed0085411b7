//! Work computed off the drawing thread, the newest request winning: one worker thread per kind
//! of work computes the newest request when it is free (requests that came in between are
//! skipped) and the run takes the result when it polls. The bodies' spectra (ω_max by power
//! iteration and the damped theory's modes: a key that changes stiffness, damping, drag or pins
//! asks for them; on the cloth one computation takes about a third of a second) and, in the
//! event loop, what a newly opened step computes (its text's numbers, its study charts, its
//! spectra) go through it, so the keys, `q` and Ctrl-C are answered meanwhile.
//! [`Latest::settle`] waits for the newest result (tests, and the public key API, see
//! `App::handle_key`), so what a test reads after a key is always up to date.

use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Condvar, Mutex, PoisonError};

use super::Limit;
use super::memo::{self, Memo};
use crate::physics::{Method, MethodParams, Model, State};
use crate::study::theory::{self, Spectrum};

/// Per body: its spectrum at its initial state (`None` when no spring moves a free particle).
pub type Bodies = Vec<Option<Spectrum>>;

/// What the worker and the run share.
struct Shared<Q> {
    slot: Mutex<Slot<Q>>,
    /// Wakes the worker.
    wake: Condvar,
}

/// The worker's mailbox.
struct Slot<Q> {
    /// The newest request not yet taken (its number and input); `None` after it is taken.
    request: Option<(u64, Q)>,
    /// The run is gone: the worker ends.
    closed: bool,
}

/// A worker computing `work` on the newest request, and the newest result asked for.
pub struct Latest<Q: Send + 'static, A: Send + 'static> {
    shared: Arc<Shared<Q>>,
    /// Results from the worker (request number, result).
    results: Option<Receiver<(u64, A)>>,
    /// The number of the newest request.
    asked: u64,
    /// The number of the result held by the run.
    have: u64,
    /// What the worker computes.
    work: fn(Q) -> A,
    /// The worker thread's name.
    name: &'static str,
}

/// The spectra's worker.
pub type Spectra = Latest<Vec<(Model, State)>, Bodies>;

/// The methods and method settings of the bodies, and their spectra.
pub type LimitInputs = (Vec<(Method, MethodParams)>, Arc<Bodies>);

/// The limit's worker.
pub type Limits = Latest<LimitInputs, Option<(Limit, f64)>>;

impl Default for Limits {
    fn default() -> Self {
        Latest::new("springlab-limit", |(methods, spectra)| {
            limit_of(&methods, &spectra)
        })
    }
}

/// The stability limit of the bodies' methods over their spectra, the most restrictive body
/// deciding, and the largest ω_max (rad/s); `None` when no body has a spectrum.
#[must_use]
pub fn limit_of(
    methods: &[(Method, MethodParams)],
    spectra: &[Option<Spectrum>],
) -> Option<(Limit, f64)> {
    let mut limit: Option<Limit> = None;
    let mut omega = 0.0f64;
    for ((method, params), spectrum) in methods.iter().zip(spectra) {
        let Some(spectrum) = spectrum else { continue };
        omega = omega.max(spectrum.omega_max);
        let l = theory::limit(*method, params, spectrum);
        let this = match (l.stability, l.dt) {
            ("conditional", Some(dt)) => Limit::Below(dt),
            ("none", _) => Limit::Never,
            ("unconditional", _) => Limit::Always,
            _ => Limit::NotCovered,
        };
        // The most restrictive body decides.
        let rank = |l: &Limit| match l {
            Limit::Never => 0,
            Limit::Below(_) => 1,
            Limit::NotCovered => 2,
            Limit::Always => 3,
        };
        limit = Some(match limit {
            None => this,
            Some(Limit::Below(a)) if matches!(this, Limit::Below(b) if b < a) => this,
            Some(prev) if rank(&this) < rank(&prev) => this,
            Some(prev) => prev,
        });
    }
    limit.map(|l| (l, omega))
}

impl Default for Spectra {
    fn default() -> Self {
        Latest::new("springlab-spectra", |bodies| compute(&bodies))
    }
}

impl<Q: Send + 'static, A: Send + 'static> Clone for Latest<Q, A> {
    /// A clone starts without a worker and without pending requests (a clone of a run has its
    /// own results from then on).
    fn clone(&self) -> Self {
        Latest::new(self.name, self.work)
    }
}

impl<Q: Send + 'static, A: Send + 'static> std::fmt::Debug for Latest<Q, A> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct(self.name)
            .field("asked", &self.asked)
            .field("have", &self.have)
            .finish_non_exhaustive()
    }
}

impl<Q: Send + 'static, A: Send + 'static> Drop for Latest<Q, A> {
    fn drop(&mut self) {
        // The worker ends when its results cannot be delivered: drop the receiver, wake it.
        self.results = None;
        let mut slot = self
            .shared
            .slot
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        slot.request = None;
        slot.closed = true;
        drop(slot);
        self.shared.wake.notify_all();
    }
}

/// The spectra of `bodies` (model and initial state each), as the status line uses them.
#[must_use]
pub fn compute(bodies: &[(Model, State)]) -> Bodies {
    bodies
        .iter()
        .map(|(model, initial)| {
            SPECTRA.get_or(memo::key(&(model, initial)), || {
                let omega = crate::study::omega_max(model, initial).omega;
                (omega > 0.0 && omega.is_finite()).then(|| theory::spectrum(model, initial, omega))
            })
        })
        .collect()
}

/// The last bodies' spectra ([`super::memo`]): `R`, a step opened again or a coefficient
/// pressed back and forth finds its spectrum at once.
static SPECTRA: Memo<Option<Spectrum>> = Memo::new(memo::KEPT);

impl<Q: Send + 'static, A: Send + 'static> Latest<Q, A> {
    /// A worker (started at the first request) named `name` that computes `work`.
    pub fn new(name: &'static str, work: fn(Q) -> A) -> Self {
        Latest {
            shared: Arc::new(Shared {
                slot: Mutex::new(Slot {
                    request: None,
                    closed: false,
                }),
                wake: Condvar::new(),
            }),
            results: None,
            asked: 0,
            have: 0,
            work,
            name,
        }
    }

    /// Asks for `work` on `bodies`; an older request not yet started is dropped.
    pub fn request(&mut self, bodies: Q) {
        self.asked += 1;
        if self.results.is_none() {
            let (send, receive) = mpsc::channel();
            let shared = Arc::clone(&self.shared);
            let work = self.work;
            let spawned = std::thread::Builder::new()
                .name(self.name.into())
                .spawn(move || worker(&shared, &send, work));
            if spawned.is_err() {
                // No thread: the run computes on demand ([`Spectra::settle`]).
                self.shared
                    .slot
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .request = Some((self.asked, bodies));
                return;
            }
            self.results = Some(receive);
        }
        self.shared
            .slot
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .request = Some((self.asked, bodies));
        self.shared.wake.notify_one();
    }

    /// True while the newest request has no result yet.
    #[must_use]
    pub fn pending(&self) -> bool {
        self.have < self.asked
    }

    /// The newest result that arrived, if it is newer than the one held.
    pub fn poll(&mut self) -> Option<A> {
        let mut newest = None;
        if let Some(rx) = &self.results {
            while let Ok((n, bodies)) = rx.try_recv() {
                if n > self.have {
                    self.have = n;
                    newest = Some(bodies);
                }
            }
        }
        newest
    }

    /// Waits for the result of the newest request (computing it here when no worker runs or
    /// it is still waiting in the slot); `None` when nothing is pending.
    pub fn settle(&mut self) -> Option<A> {
        if !self.pending() {
            return self.poll();
        }
        // Still in the slot: take it and compute it on this thread.
        let waiting = self
            .shared
            .slot
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .request
            .take();
        if let Some((n, bodies)) = waiting
            && n == self.asked
        {
            self.have = n;
            return Some((self.work)(bodies));
        }
        // The worker has it: wait for its answer.
        let mut newest = None;
        while self.pending() {
            let Some(rx) = &self.results else { break };
            match rx.recv() {
                Ok((n, bodies)) if n > self.have => {
                    self.have = n;
                    newest = Some(bodies);
                }
                Ok(_) => {}
                Err(_) => break,
            }
        }
        newest
    }
}

/// The nice value of the app's worker threads (0 is the drawing thread's, 19 the lowest).
pub const WORKER_NICE: i32 = 10;

/// Lowers the calling thread's priority to [`WORKER_NICE`] (on Linux the nice value belongs to
/// the thread). The workers compute what the screen shows next (spectra, a step's numbers,
/// exports): on a loaded machine they must not take the CPU from the drawing thread, which
/// answers the keys (`q` among them). Where the system refuses, nothing changes.
pub fn lower_priority() {
    #[cfg(target_os = "linux")]
    {
        let _ = rustix::process::setpriority_process(Some(rustix::thread::gettid()), WORKER_NICE);
    }
}

/// The worker: takes the newest request, computes it, sends it back; ends when the run is gone.
fn worker<Q, A>(shared: &Shared<Q>, results: &Sender<(u64, A)>, work: fn(Q) -> A) {
    lower_priority();
    loop {
        let request = {
            let mut slot = shared.slot.lock().unwrap_or_else(PoisonError::into_inner);
            loop {
                if slot.closed {
                    return;
                }
                if let Some(r) = slot.request.take() {
                    break r;
                }
                slot = shared
                    .wake
                    .wait(slot)
                    .unwrap_or_else(PoisonError::into_inner);
            }
        };
        let (n, bodies) = request;
        if results.send((n, work(bodies))).is_err() {
            return;
        }
    }
}
