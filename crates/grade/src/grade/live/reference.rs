//! The reference's side of the comparison: springlab's own answers stepping the body on a
//! thread of their own ([`reference_steps`]), or on the worker's in turn ([`Steps::Here`]), and
//! taking the lesson's steps where the hand-over is trusted (`handover.rs`).

use std::sync::atomic::Ordering;
use std::sync::mpsc::{Receiver, SyncSender};
use std::thread;
use std::time::Duration;

use super::body::{Snapshot, Track};
use super::handover::{Handover, RECHECK, VERIFY, same_bits};
use super::{Homework, Setup, Shared};

/// The reference's thread: steps springlab's answers beside the worker (on the other core), up
/// to the app's clock, and hands each step's body over through `steps` (bounded: it waits when
/// the worker is [`REFERENCE_AHEAD`](super::REFERENCE_AHEAD) steps behind). A step the lesson's simulation took of the
/// same body is taken from `handover` instead of computed again, once trusted
/// (`live/handover.rs`). Ends when the worker stops listening, at `stop`, or at the horizon.
pub(super) fn reference_steps(
    setup: &Setup,
    shared: &Shared,
    horizon: u64,
    steps: &SyncSender<Snapshot>,
    handover: Option<&Handover>,
) {
    let reference = Homework::reference(setup.assignment);
    let mut theirs = Track::new(setup, 1);
    let mut step = 0u64;
    // Steps computed both ways with the same bits.
    let mut verified = 0u64;
    while step < horizon && !shared.stop.load(Ordering::Relaxed) {
        if step >= shared.target.load(Ordering::Relaxed) {
            thread::park_timeout(Duration::from_millis(20));
            continue;
        }
        step += 1;
        match handover.and_then(|h| Some((h, h.take(step)?))) {
            Some((h, lesson)) if verified >= VERIFY && !step.is_multiple_of(RECHECK) => {
                let used = theirs.set_lattice(&lesson.x, &lesson.v);
                if !used {
                    theirs.step(&reference, setup, 1);
                }
                h.recycle(lesson, used);
            }
            Some((h, lesson)) => {
                theirs.step(&reference, setup, 1);
                if same_bits(&theirs.positions(), &lesson.x)
                    && same_bits(&theirs.raw_velocities(), &lesson.v)
                {
                    verified += 1;
                    h.recycle(lesson, false);
                } else {
                    h.end();
                }
            }
            None => theirs.step(&reference, setup, 1),
        }
        if steps.send(Snapshot::of(&theirs, setup)).is_err() {
            break;
        }
    }
}

/// Where the worker takes the reference's steps from.
pub(super) enum Steps {
    /// The reference's thread ([`reference_steps`]).
    Thread(Receiver<Snapshot>),
    /// This thread, in turn (no second thread could be started).
    Here(Box<Track>),
}

impl Steps {
    /// The reference body after its next step; `None` when its thread ended.
    pub(super) fn next(&mut self, setup: &Setup) -> Option<Snapshot> {
        match self {
            Steps::Thread(steps) => steps.recv().ok(),
            Steps::Here(track) => {
                track.step(&Homework::reference(setup.assignment), setup, 1);
                Some(Snapshot::of(track, setup))
            }
        }
    }
}
