//! Running checks safely: each on its own thread, with a time limit, panics caught and silenced.
//!
//! # How one check runs
//!
//! 1. A worker thread is started with a shared handle to the student's implementation.
//! 2. The thread marks itself as a grading thread (a thread-local flag) and calls the check inside
//!    [`std::panic::catch_unwind`]. A process-wide panic hook, installed once, prints nothing for
//!    grading threads and records the message and location instead; other threads keep the hook
//!    that was there before, so grading never hides the panics of the program around it.
//! 3. The thread's deadline is the start plus the time limit; calls to a student's program
//!    ([`super::remote::Remote`]) wait at most until then. The runner waits on a channel for at
//!    most the limit plus a short grace. A result is a pass, a failed case (the check's points
//!    are lost) or a number that is not finite; a panic arrives as its message; a call to the
//!    student's program that got no answer arrives as its [`CallFailure`]; no answer in time is
//!    a timeout.
//! 4. Each of these costs the check in progress only: checks of the same item that passed keep
//!    their points, and the item's later checks run (after a time-out they are skipped, since
//!    they would wait the limit again). The item's status and reason name what happened.
//!
//! With the student's code in its own process (`springlab grade`), a check never needs to be
//! abandoned: the program is killed at the deadline. Homework graded in this process (the
//! library calls, used by springlab's own tests) cannot be stopped on a timeout (Rust has no safe
//! way to kill a thread): the thread is abandoned and keeps a core busy until the process exits.

use std::any::Any;
use std::cell::{Cell, RefCell};
use std::panic::{self, AssertUnwindSafe};
use std::sync::{Arc, Mutex, Once, mpsc};
use std::thread;
use std::time::{Duration, Instant};

use super::remote::CallFailure;
use super::report::{
    CheckOutcome, CheckReport, Feedback, ItemReport, ItemStatus, NotGraded, Report,
};

/// Settings of a grading run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Longest time one check may take before its item scores zero.
    pub time_limit: Duration,
    /// Seed of the random cases; the same seed gives the same cases and the same report.
    pub seed: u64,
}

/// The default seed of the random cases.
pub const DEFAULT_SEED: u64 = 0x5EED_2020_0425;

/// The default time limit of one check, generous for debug builds on a loaded machine: every
/// check of the reference takes milliseconds.
pub const DEFAULT_TIME_LIMIT: Duration = Duration::from_secs(10);

impl Default for Options {
    fn default() -> Options {
        Options {
            time_limit: DEFAULT_TIME_LIMIT,
            seed: DEFAULT_SEED,
        }
    }
}

/// Why a check did not pass.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Failure {
    /// A case disagreed with the reference: the check's points are lost.
    Wrong(Feedback),
    /// The student returned NaN or ±∞: the item scores zero.
    NotFinite(Feedback),
}

/// What a check returns.
pub(crate) type CheckResult = Result<(), Failure>;

/// Context handed to every check.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ctx {
    /// Seed of the random cases (each check mixes in its own constant).
    pub seed: u64,
}

/// One check of an item: a name, its points and the function that runs it.
pub(crate) struct CheckSpec<H> {
    pub name: &'static str,
    pub points: f64,
    pub run: fn(&H, &Ctx) -> CheckResult,
}

/// One rubric item.
pub(crate) struct ItemSpec<H> {
    pub id: &'static str,
    pub category: &'static str,
    pub name: &'static str,
    pub checks: Vec<CheckSpec<H>>,
}

impl<H> ItemSpec<H> {
    /// The item's points: the sum of its checks'.
    pub fn max_points(&self) -> f64 {
        self.checks.iter().map(|c| c.points).sum()
    }
}

/// A whole rubric.
pub(crate) struct Rubric<H> {
    pub assignment: &'static str,
    pub title: &'static str,
    pub course_max: f64,
    pub not_graded: Vec<NotGraded>,
    pub items: Vec<ItemSpec<H>>,
}

thread_local! {
    /// True on a grading worker thread: its panics are recorded, not printed.
    static GRADING: Cell<bool> = const { Cell::new(false) };
    /// The last panic's "message at file:line:col" on this thread.
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
    /// The case a check is running on this thread, shared with the runner so that a panic or a
    /// timeout can report it.
    static CASE: RefCell<Option<Arc<Mutex<String>>>> = const { RefCell::new(None) };
}

/// Records the case about to be handed to the student's code, so that a panic (or a timeout)
/// can say which input caused it.
pub(crate) fn set_case(input: &str) {
    CASE.with(|c| {
        if let Some(shared) = c.borrow().as_ref()
            && let Ok(mut text) = shared.lock()
        {
            text.clear();
            text.push_str(input);
        }
    });
}

/// The case last recorded by a check's thread (empty when none, or when its lock is poisoned or
/// busy).
fn recorded_case(shared: &Mutex<String>) -> String {
    shared.try_lock().map(|t| t.clone()).unwrap_or_default()
}

static HOOK: Once = Once::new();

/// Installs, once per process, the hook that keeps grading threads quiet (module docs).
fn install_quiet_hook() {
    HOOK.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if GRADING.with(Cell::get) {
                let location = info
                    .location()
                    .map(|l| format!(" at {}:{}:{}", l.file(), l.line(), l.column()))
                    .unwrap_or_default();
                let message = payload_text(info.payload());
                LAST_PANIC.with(|p| *p.borrow_mut() = Some(format!("{message}{location}")));
            } else {
                previous(info);
            }
        }));
    });
}

fn payload_text(payload: &dyn Any) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}

/// How one isolated run ended.
enum Verdict {
    Done(CheckResult),
    /// The panic's message and the case it happened on.
    Panicked(String, String),
    /// No answer within the limit, on the case last recorded.
    TimedOut(String),
    /// The student's program ended during the check: how, and the case.
    Crashed(String, String),
    /// The student's program answered something unreadable: why, and the case.
    Malformed(String, String),
    NoThread(String),
}

thread_local! {
    /// When the check running on this thread must be done (the remote program's calls wait at
    /// most until then).
    static DEADLINE: Cell<Option<Instant>> = const { Cell::new(None) };
}

/// The deadline of the check running on this thread, if any.
pub(crate) fn check_deadline() -> Option<Instant> {
    DEADLINE.with(Cell::get)
}

/// Time a check thread gets beyond its limit before the runner stops waiting: the student's
/// program is already stopped at the limit; this covers the grader's own work after it.
const GRACE: Duration = Duration::from_secs(2);

fn run_isolated<H: Send + Sync + 'static>(
    hw: &Arc<H>,
    check: fn(&H, &Ctx) -> CheckResult,
    ctx: Ctx,
    limit: Duration,
) -> Verdict {
    install_quiet_hook();
    let (tx, rx) = mpsc::channel();
    let case = Arc::new(Mutex::new(String::new()));
    let case_in_thread = Arc::clone(&case);
    let hw = Arc::clone(hw);
    let deadline = Instant::now() + limit;
    let spawned = thread::Builder::new()
        .name("springlab-grade-check".to_string())
        .spawn(move || {
            GRADING.with(|g| g.set(true));
            DEADLINE.with(|d| d.set(Some(deadline)));
            CASE.with(|c| *c.borrow_mut() = Some(case_in_thread));
            let result = panic::catch_unwind(AssertUnwindSafe(|| check(&hw, &ctx)));
            let outcome = match result {
                Ok(r) => Outcome::Returned(r),
                Err(payload) => match payload.downcast::<CallFailure>() {
                    Ok(failure) => Outcome::Remote(*failure),
                    Err(payload) => Outcome::Panicked(
                        LAST_PANIC
                            .with(|p| p.borrow_mut().take())
                            .unwrap_or_else(|| payload_text(payload.as_ref())),
                    ),
                },
            };
            // The receiver is gone when the check timed out: nothing to do.
            let _ = tx.send(outcome);
        });
    if let Err(e) = spawned {
        return Verdict::NoThread(e.to_string());
    }
    let in_case = || recorded_case(&case);
    match rx.recv_timeout(limit + GRACE) {
        Ok(Outcome::Returned(result)) => Verdict::Done(result),
        Ok(Outcome::Panicked(message)) => Verdict::Panicked(message, in_case()),
        Ok(Outcome::Remote(CallFailure::Panicked(message))) => {
            Verdict::Panicked(message, in_case())
        }
        Ok(Outcome::Remote(CallFailure::TimedOut)) => Verdict::TimedOut(in_case()),
        Ok(Outcome::Remote(CallFailure::Crashed(how))) => Verdict::Crashed(how, in_case()),
        Ok(Outcome::Remote(CallFailure::NotStarted(why))) => Verdict::Crashed(
            format!("the homework program could not be started: {why}"),
            in_case(),
        ),
        Ok(Outcome::Remote(CallFailure::Malformed(why))) => Verdict::Malformed(why, in_case()),
        Err(mpsc::RecvTimeoutError::Timeout) => Verdict::TimedOut(in_case()),
        Err(mpsc::RecvTimeoutError::Disconnected) => Verdict::Panicked(
            "the check's thread ended without an answer".to_string(),
            String::new(),
        ),
    }
}

/// What a check thread sends back.
enum Outcome {
    Returned(CheckResult),
    Panicked(String),
    Remote(CallFailure),
}

/// Runs every check of `rubric` against `hw` and collects the report.
pub(crate) fn grade<H: Send + Sync + 'static>(
    rubric: Rubric<H>,
    hw: H,
    options: &Options,
) -> Report {
    let start = Instant::now();
    let hw = Arc::new(hw);
    let ctx = Ctx { seed: options.seed };
    let mut items = Vec::with_capacity(rubric.items.len());
    for item in &rubric.items {
        items.push(grade_item(item, &hw, ctx, options.time_limit));
    }
    finish(&rubric, items, options, start.elapsed().as_secs_f64())
}

/// A failed check's feedback for a run that gave no answer.
fn no_answer(case: String, expected: String, got: String, hint: &str) -> Option<Feedback> {
    Some(Feedback {
        input: case,
        expected,
        got,
        hint: hint.to_string(),
    })
}

/// Runs the checks of one item. A check that passes keeps its points whatever happens later; a
/// wrong answer, a non-finite number, a panic, a crash of the student's program or an
/// unreadable answer cost the check in progress, and the item's other checks still run (a new
/// program answers them after a crash). A time-out costs the check in progress and skips the
/// item's remaining checks, which would most likely wait the whole limit again. The item's
/// status names the first such event and its reason says what happened.
fn grade_item<H: Send + Sync + 'static>(
    item: &ItemSpec<H>,
    hw: &Arc<H>,
    ctx: Ctx,
    limit: Duration,
) -> ItemReport {
    let mut checks = Vec::with_capacity(item.checks.len());
    let mut fatal: Option<(ItemStatus, String)> = None;
    let mut skip_rest = false;
    let ms = limit.as_millis();
    for check in &item.checks {
        if skip_rest {
            checks.push(CheckReport {
                name: check.name.to_string(),
                score: 0.0,
                max_score: check.points,
                outcome: CheckOutcome::NotRun,
                feedback: None,
            });
            continue;
        }
        let name = check.name;
        let mut first = |status: ItemStatus, reason: String| {
            if fatal.is_none() {
                fatal = Some((status, reason));
            }
        };
        let (outcome, feedback) = match run_isolated(hw, check.run, ctx, limit) {
            Verdict::Done(Ok(())) => (CheckOutcome::Passed, None),
            Verdict::Done(Err(Failure::Wrong(f))) => (CheckOutcome::Failed, Some(f)),
            Verdict::Done(Err(Failure::NotFinite(f))) => {
                first(
                    ItemStatus::NotFinite,
                    format!(
                        "\"{name}\" produced a number that is not finite (NaN or infinite): that \
                         check scores 0"
                    ),
                );
                (CheckOutcome::Failed, Some(f))
            }
            Verdict::Panicked(message, case) => {
                first(
                    ItemStatus::Panicked,
                    format!("\"{name}\" panicked: {message}; that check scores 0"),
                );
                (
                    CheckOutcome::Failed,
                    no_answer(
                        case,
                        "an answer".to_string(),
                        format!("a panic: {message}"),
                        "call the function with this input from a test of your own and run it \
                         with RUST_BACKTRACE=1; a panic is never worth points",
                    ),
                )
            }
            Verdict::Crashed(how, case) => {
                first(
                    ItemStatus::Crashed,
                    format!(
                        "the homework program ended during \"{name}\": {how}; that check scores \
                         0 and a new program answers the rest"
                    ),
                );
                (
                    CheckOutcome::Failed,
                    no_answer(
                        case,
                        "an answer".to_string(),
                        format!("no answer: {how}"),
                        "a homework method must return: no process::exit, no abort, no endless \
                         recursion, no unbounded allocation",
                    ),
                )
            }
            Verdict::Malformed(why, case) => {
                first(
                    ItemStatus::Malformed,
                    format!("\"{name}\" got an answer the grader cannot read: {why}"),
                );
                (
                    CheckOutcome::Failed,
                    no_answer(
                        case,
                        "an answer of the method's type".to_string(),
                        format!("an unreadable answer: {why}"),
                        "return what the method's signature says, of a size that fits the input",
                    ),
                )
            }
            Verdict::TimedOut(case) => {
                skip_rest = true;
                first(
                    ItemStatus::TimedOut,
                    format!(
                        "\"{name}\" did not finish within {ms} ms: that check scores 0 and the \
                         item's remaining checks were not run"
                    ),
                );
                (
                    CheckOutcome::Failed,
                    no_answer(
                        case,
                        format!("an answer within {ms} ms"),
                        "no answer".to_string(),
                        "look for a loop whose condition never changes, or one far longer than \
                         the system (every check takes milliseconds)",
                    ),
                )
            }
            Verdict::NoThread(e) => {
                first(
                    ItemStatus::NotRun,
                    format!("could not start a thread for \"{name}\": {e}"),
                );
                (CheckOutcome::NotRun, None)
            }
        };
        checks.push(CheckReport {
            name: check.name.to_string(),
            score: if outcome == CheckOutcome::Passed {
                check.points
            } else {
                0.0
            },
            max_score: check.points,
            outcome,
            feedback,
        });
    }
    let max_score = item.max_points();
    let score: f64 = checks.iter().map(|c| c.score).sum();
    let (status, reason) = match fatal {
        Some((status, reason)) => (status, Some(reason)),
        None if score == max_score => (ItemStatus::Full, None),
        None if score == 0.0 => (ItemStatus::Zero, None),
        None => (ItemStatus::Partial, None),
    };
    ItemReport {
        id: item.id.to_string(),
        category: item.category.to_string(),
        name: item.name.to_string(),
        score,
        max_score,
        status,
        reason,
        checks,
    }
}

fn finish<H>(
    rubric: &Rubric<H>,
    items: Vec<ItemReport>,
    options: &Options,
    seconds: f64,
) -> Report {
    Report {
        assignment: rubric.assignment.to_string(),
        title: rubric.title.to_string(),
        score: items.iter().map(|i| i.score).sum(),
        max_score: items.iter().map(|i| i.max_score).sum(),
        course_max_score: rubric.course_max,
        not_graded: rubric.not_graded.clone(),
        items,
        seed: options.seed,
        time_limit_ms: u64::try_from(options.time_limit.as_millis()).unwrap_or(u64::MAX),
        seconds,
        sandbox: None,
    }
}

/// A report in which nothing ran (the crate did not build, or the grading process crashed or
/// hung): every item scores zero and carries `reason`.
pub(crate) fn not_run<H>(rubric: &Rubric<H>, reason: &str, options: &Options) -> Report {
    let items = rubric
        .items
        .iter()
        .map(|item| ItemReport {
            id: item.id.to_string(),
            category: item.category.to_string(),
            name: item.name.to_string(),
            score: 0.0,
            max_score: item.max_points(),
            status: ItemStatus::NotRun,
            reason: Some(reason.to_string()),
            checks: item
                .checks
                .iter()
                .map(|c| CheckReport {
                    name: c.name.to_string(),
                    score: 0.0,
                    max_score: c.points,
                    outcome: CheckOutcome::NotRun,
                    feedback: None,
                })
                .collect(),
        })
        .collect();
    finish(rubric, items, options, 0.0)
}
