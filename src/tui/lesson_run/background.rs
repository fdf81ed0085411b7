//! The bodies' spectra (ω_max by power iteration and the damped theory's modes) computed off
//! the drawing thread: a key that changes stiffness, damping, drag or pins asks for them, one
//! worker thread computes the newest request when it is free (requests that came in between are
//! skipped: the latest wins), and the run takes the result when it polls. On the cloth one
//! computation takes about a third of a second; the keys, `q` and Ctrl-C are answered
//! meanwhile. [`Spectra::settle`] waits for the newest result (tests, and the public key API,
//! see `App::handle_key`), so what a test reads after a key is always up to date.

use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Condvar, Mutex, PoisonError};

use crate::physics::{Model, State};
use crate::study::theory::{self, Spectrum};

/// Per body: its spectrum at its initial state (`None` when no spring moves a free particle).
pub type Bodies = Vec<Option<Spectrum>>;

/// One request: its number and the bodies' models and initial states.
type Request = (u64, Vec<(Model, State)>);

/// What the worker and the run share.
#[derive(Default)]
struct Shared {
    slot: Mutex<Slot>,
    /// Wakes the worker.
    wake: Condvar,
}

/// The worker's mailbox.
#[derive(Default)]
struct Slot {
    /// The newest request not yet taken; `None` after it is taken.
    request: Option<Request>,
    /// The run is gone: the worker ends.
    closed: bool,
}

/// The spectra's worker and the newest result asked for.
pub struct Spectra {
    shared: Arc<Shared>,
    /// Results from the worker (request number, spectra).
    results: Option<Receiver<(u64, Bodies)>>,
    /// The number of the newest request.
    asked: u64,
    /// The number of the result held by the run.
    have: u64,
}

impl Default for Spectra {
    fn default() -> Self {
        Spectra {
            shared: Arc::new(Shared::default()),
            results: None,
            asked: 0,
            have: 0,
        }
    }
}

impl Clone for Spectra {
    /// A clone starts without a worker and without pending requests (a clone of a run has its
    /// own results from then on).
    fn clone(&self) -> Self {
        Spectra::default()
    }
}

impl std::fmt::Debug for Spectra {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Spectra")
            .field("asked", &self.asked)
            .field("have", &self.have)
            .finish_non_exhaustive()
    }
}

impl Drop for Spectra {
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
            let omega = crate::study::omega_max(model, initial).omega;
            (omega > 0.0 && omega.is_finite()).then(|| theory::spectrum(model, initial, omega))
        })
        .collect()
}

impl Spectra {
    /// Asks for the spectra of `bodies`; an older request not yet started is dropped.
    pub fn request(&mut self, bodies: Vec<(Model, State)>) {
        self.asked += 1;
        if self.results.is_none() {
            let (send, receive) = mpsc::channel();
            let shared = Arc::clone(&self.shared);
            let spawned = std::thread::Builder::new()
                .name("springlab-spectra".into())
                .spawn(move || worker(&shared, &send));
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
    pub fn poll(&mut self) -> Option<Bodies> {
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
    pub fn settle(&mut self) -> Option<Bodies> {
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
            return Some(compute(&bodies));
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

/// The worker: takes the newest request, computes it, sends it back; ends when the run is gone.
fn worker(shared: &Shared, results: &Sender<(u64, Bodies)>) {
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
        if results.send((n, compute(&bodies))).is_err() {
            return;
        }
    }
}
