//! Runs a [`Script`] frame by frame: each step is a few frames of injected egui events
//! (press, move, release) or a request to the viewer (resize, idle, measure), and is
//! checked to have taken effect before the next begins. Errors name the script line.

use std::time::Instant;

use anyhow::anyhow;
use egui::{Event, Modifiers, PointerButton, Pos2};

use super::check::LayoutCheck;
pub use super::observed::Observed;
use super::script::{Action, MeasureMode, Script, Step};
use arbvis_core::camera::Camera;

/// Frames a step may wait for its widget to appear or take effect.
const PATIENCE: u32 = 30;

mod actions;

/// What the script asks of this frame.
#[derive(Debug, Clone, PartialEq)]
pub enum ScriptStep {
    /// Inject these events and draw.
    Events(Vec<Event>),
    /// Draw no frame for the script before this instant.
    Idle(Instant),
    /// Draw a frame in this measuring mode.
    Measure(MeasureMode),
    /// Resize the window to this many pixels, then draw.
    Resize(u32, u32),
    /// Draw, and write the whole window as a picture after painting.
    WindowShot,
    /// Close the viewer.
    Quit,
}

/// Runs a script.
#[derive(Default)]
pub struct ScriptRunner {
    origin: String,
    steps: Vec<Step>,
    index: usize,
    phase: u32,
    frames_in_step: u32,
    /// Where the current pointer action presses (points).
    point: Pos2,
    camera: Option<Camera>,
    frames_at: u64,
    started: Option<Instant>,
    deadline: Option<Instant>,
    last_click: Option<Instant>,
    layout: Option<LayoutCheck>,
    /// The rectangle the current step's widget had last frame: a pointer action waits
    /// until it is the same two frames running, so that a layout still settling (a
    /// panel growing after a click) cannot move the widget under the pointer.
    aimed_at: Option<egui::Rect>,
}

pub(super) fn press(pos: Pos2, button: PointerButton, pressed: bool) -> Event {
    Event::PointerButton {
        pos,
        button,
        pressed,
        modifiers: Modifiers::NONE,
    }
}

impl ScriptRunner {
    /// A runner for `script`.
    pub fn new(script: &Script) -> ScriptRunner {
        ScriptRunner {
            origin: script.origin.clone(),
            steps: script.steps.clone(),
            ..ScriptRunner::default()
        }
    }

    fn error(&self, step: &Step, message: impl std::fmt::Display) -> anyhow::Error {
        anyhow!(
            "script {} line {} ({}): {message}",
            self.origin,
            step.line,
            step.text
        )
    }

    fn next(&mut self) {
        self.index += 1;
        self.phase = 0;
        self.frames_in_step = 0;
        self.camera = None;
        self.started = None;
        self.deadline = None;
        self.layout = None;
        self.aimed_at = None;
    }

    /// Find `label` on screen and the point at `at` (fractions; centre when `None`):
    /// `Ok(None)` while it is still being looked for or scrolled into view.
    fn locate(
        &mut self,
        step: &Step,
        o: &mut Observed<'_>,
        label: &str,
        at: Option<(f32, f32)>,
    ) -> anyhow::Result<Option<Pos2>> {
        o.widgets.focus = Some(label.to_string());
        let late = self.frames_in_step > PATIENCE;
        let Some(seen) = o.widgets.get(label).copied() else {
            return if late {
                Err(self.error(
                    step,
                    format!(
                        "no widget labelled {label:?}; widgets: {:?}",
                        o.widgets.labels()
                    ),
                ))
            } else {
                Ok(None)
            };
        };
        if !seen.enabled {
            return Err(self.error(step, format!("{label:?} is disabled")));
        }
        let r = seen.rect;
        if self.aimed_at.replace(r) != Some(r) && !late {
            return Ok(None);
        }
        let (fx, fy) = at.unwrap_or((0.5, 0.5));
        let p = Pos2::new(r.left() + fx * r.width(), r.top() + fy * r.height());
        // Points exactly on the far edges count as inside.
        if seen.visible.expand(0.01).contains(p) {
            Ok(Some(p))
        } else if late {
            Err(self.error(step, format!("{label:?} cannot be scrolled into view")))
        } else {
            Ok(None)
        }
    }

    /// The script's wish for the next frame.
    pub fn step(&mut self, o: &mut Observed<'_>) -> anyhow::Result<ScriptStep> {
        let Some(step) = self.steps.get(self.index).cloned() else {
            return Ok(ScriptStep::Quit);
        };
        if let Some(e) = o.action_error.take() {
            return Err(self.error(&step, e));
        }
        self.frames_in_step += 1;
        let mut events = Vec::new();
        let outcome = match &step.action {
            Action::Wait(n) => Outcome::done_if(self.frames_in_step > *n),
            Action::Quit => Outcome::Now(ScriptStep::Quit),
            Action::Click { label, at, kind } => {
                self.click(&step, o, (label, *at, *kind), &mut events)?
            }
            Action::DragOn { label, at, by } => {
                self.drag_on(&step, o, (label, *at, *by), &mut events)?
            }
            Action::Drag(dx, dy) => self.drag(&step, o, egui::vec2(*dx, *dy), &mut events)?,
            Action::Scroll(dy) => self.scroll(&step, o, *dy, &mut events)?,
            Action::Set { label, value } => self.set(&step, o, label, value)?,
            Action::Key(name) => self.key(&step, o, name, &mut events)?,
            Action::Resize(w, h) => self.resize(&step, o, [*w, *h])?,
            Action::Idle(ms) => self.idle(&step, o, *ms),
            Action::Print(label) => self.print(&step, o, label)?,
            Action::CheckLayout => {
                let check = self.layout.get_or_insert_with(LayoutCheck::default);
                match check.step(o) {
                    Ok(finished) => Outcome::done_if(finished),
                    Err(e) => return Err(self.error(&step, e.to_string())),
                }
            }
            Action::WindowShot => {
                if self.phase == 0 {
                    self.phase = 1;
                    Outcome::Now(ScriptStep::WindowShot)
                } else {
                    Outcome::Done
                }
            }
            Action::Measure(n, mode) => self.measure(&step, o, *n, *mode),
        };
        match outcome {
            Outcome::Now(wish) => return Ok(wish),
            Outcome::Done => self.next(),
            Outcome::Pending => {}
        }
        Ok(ScriptStep::Events(events))
    }
}

/// What a step came to this frame.
pub(super) enum Outcome {
    /// Still going: the frame's events are injected and the step goes on next frame.
    Pending,
    /// Finished: the frame's events are injected and the next step starts.
    Done,
    /// This wish instead of events; the step goes on next frame.
    Now(ScriptStep),
}

impl Outcome {
    fn done_if(done: bool) -> Outcome {
        if done {
            Outcome::Done
        } else {
            Outcome::Pending
        }
    }
}
