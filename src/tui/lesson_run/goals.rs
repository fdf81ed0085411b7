//! After each step: the history, the goal's verdict and the prediction's reveal; what the
//! student did (met goals, visited steps, predictions) as the progress file keeps it.

use crate::lesson::GoalKind;
use crate::physics::diverge;

use super::LessonRun;

impl LessonRun {
    /// Each step's body goes to `handover` (the attached homework's reference), or nowhere.
    pub fn set_handover(&mut self, handover: Option<crate::grade::live::Handover>) {
        self.handover = handover;
    }

    /// One step, then the history, the goal and the divergence check; true when it diverged.
    pub(super) fn step_once(&mut self) -> bool {
        let diverged = self.sim.step().is_some() || self.sim.diverged.is_some();
        if let Some(handover) = self.handover.as_ref().filter(|_| !diverged) {
            handover.offer(&self.sim, self.generation);
        }
        if diverged {
            // The diverging sample is drawn too (the plot ends where the status line says).
            self.history
                .record_divergence(&self.sim, self.oscillator.as_ref());
        } else {
            self.history.record(&self.sim, self.oscillator.as_ref());
            self.observed.record(&self.sim);
        }
        self.check_goal(diverged);
        if diverged {
            self.running = false;
        }
        diverged
    }

    fn check_goal(&mut self, diverged: bool) {
        let time = self
            .sim
            .diverged
            .as_ref()
            .map_or(self.sim.time(), |d| d.time);
        self.check_prediction(diverged, time);
        if self.goal.is_some() {
            return;
        }
        let Some(goal) = &self.lesson.steps[self.step].goal else {
            return;
        };
        let speed = if goal.kind == GoalKind::Settle && !diverged {
            self.body_speed(goal.body)
        } else {
            0.0
        };
        self.goal = goal.check(&mut self.goal_progress, time, speed, diverged);
        if self.goal == Some(true) && !self.met[self.step] {
            self.met[self.step] = true;
            self.progress_changed = true;
        }
    }

    /// The largest particle speed of body `body` (1-based), or of every body (m/s).
    fn body_speed(&self, body: Option<usize>) -> f64 {
        self.sim
            .states()
            .enumerate()
            .filter(|(i, _)| body.is_none_or(|b| b == i + 1))
            .map(|(_, s)| diverge::max_speed(s))
            .fold(0.0f64, f64::max)
    }

    /// After an answer, a run that diverged or passed the longest option's time reveals the
    /// prediction's answer beside what this run did.
    fn check_prediction(&mut self, diverged: bool, time: f64) {
        if self.revealed.is_some() {
            return;
        }
        let Some(chosen) = self.answer() else { return };
        let Some(p) = &self.lesson.steps[self.step].predict else {
            return;
        };
        let horizon = p
            .options
            .iter()
            .map(|o| o.claim.time + crate::lesson::SETTLE_HOLD)
            .fold(0.0, f64::max);
        if !diverged && time < horizon {
            return;
        }
        let per_body = p
            .options
            .iter()
            .all(|o| o.claim.kind == crate::lesson::GoalKind::Settle && o.claim.body.is_some());
        let what = if diverged {
            format!("this run blew up at t = {} s", super::plots::number(time))
        } else if per_body {
            // Options about different bodies of one run: say what each body did in this one.
            let bodies: Vec<String> = p
                .options
                .iter()
                .map(|o| {
                    let v = self.body_speed(o.claim.body);
                    let state = if v < o.claim.speed {
                        "at rest"
                    } else {
                        "still moving"
                    };
                    format!(
                        "{} {state} (max |v| {} m/s)",
                        o.text,
                        super::plots::number(v)
                    )
                })
                .collect();
            format!(
                "at t = {} s in this run: {}",
                super::plots::number(time),
                bodies.join(", ")
            )
        } else {
            format!("this run kept going for {} s", super::plots::number(time))
        };
        let right = &p.options[p.answer];
        let verdict = if chosen == p.answer {
            "✓ you predicted it".to_string()
        } else {
            format!("✗ you predicted {}) {}", chosen + 1, p.options[chosen].text)
        };
        self.revealed = Some(format!(
            "{what}. Answer: {}) {}. {verdict}.",
            p.answer + 1,
            right.text
        ));
        // On a small screen the answer and its explanation open the text (lesson_view): show
        // them from their first line.
        self.text_scroll = 0;
    }
}

/// What the student did, as the progress file keeps it.
impl LessonRun {
    /// Restores what the student did before (met goals, visited steps, predictions), for
    /// example from the progress file; lengths that do not match the lesson are cut or padded.
    pub fn restore(&mut self, met: &[bool], visited: &[bool], answers: &[Option<usize>]) {
        let n = self.lesson.steps.len();
        for i in 0..n {
            self.met[i] |= met.get(i).copied().unwrap_or(false);
            self.visited[i] |= visited.get(i).copied().unwrap_or(false);
            if self.answers[i].is_none() {
                self.answers[i] = answers.get(i).copied().flatten().filter(|&a| {
                    self.lesson.steps[i]
                        .predict
                        .as_ref()
                        .is_some_and(|p| a < p.options.len())
                });
            }
        }
    }

    /// Per step: its goal was met.
    #[must_use]
    pub fn met_goals(&self) -> &[bool] {
        &self.met
    }

    /// Per step: the student opened it.
    #[must_use]
    pub fn visited_steps(&self) -> &[bool] {
        &self.visited
    }

    /// Per step: the option predicted (0-based).
    #[must_use]
    pub fn answers(&self) -> &[Option<usize>] {
        &self.answers
    }

    /// True once since the last call when met goals, visits or answers changed.
    pub fn take_progress_changed(&mut self) -> bool {
        std::mem::take(&mut self.progress_changed)
    }
}
