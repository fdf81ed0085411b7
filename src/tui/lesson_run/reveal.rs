//! What the lesson screen shows of a step with a prediction before and after the student's
//! answer (the step's `hide` in its front matter): the title, text, try items, goal and plots
//! that would give the answer away wait for it.

use crate::lesson::Plot;

use super::LessonRun;

impl LessonRun {
    /// True once the step's prediction is answered (always, for a step without one).
    #[must_use]
    pub fn answered(&self) -> bool {
        !self.awaiting_prediction()
    }

    /// The step's title as shown now: a neutral one until the prediction is answered, when
    /// the step's own title says the answer.
    #[must_use]
    pub fn shown_title(&self) -> &str {
        let step = self.step();
        match &step.hide.title {
            Some(t) if !self.answered() => t,
            _ => &step.title,
        }
    }

    /// The step's text (numbers filled in) as shown now: up to what the step hides until the
    /// prediction is answered.
    #[must_use]
    pub fn shown_text(&self) -> &str {
        if self.answered() {
            &self.text
        } else {
            self.step().hide.text_before(&self.text)
        }
    }

    /// True when part of the text waits for the prediction's answer.
    #[must_use]
    pub fn text_held_back(&self) -> bool {
        self.shown_text().len() < self.text.len()
    }

    /// True when try item `i` (0-based) is shown now.
    #[must_use]
    pub fn try_shown(&self, i: usize) -> bool {
        self.answered() || !self.step().hide.try_items.contains(&i)
    }

    /// True when the goal's text is shown now.
    #[must_use]
    pub fn goal_shown(&self) -> bool {
        self.answered() || !self.step().hide.goal
    }

    /// True when the status line shows the method's limit now (dt·ω, the limit, "stable
    /// below"): not before the answer on a step that hides it.
    #[must_use]
    pub fn limit_shown(&self) -> bool {
        self.answered() || !self.step().hide.limit
    }

    /// The step's plots shown now.
    #[must_use]
    pub fn shown_plots(&self) -> Vec<Plot> {
        let step = self.step();
        step.plots
            .iter()
            .copied()
            .filter(|p| self.answered() || !step.hide.plots.contains(p))
            .collect()
    }
}
