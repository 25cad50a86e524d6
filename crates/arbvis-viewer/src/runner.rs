//! Runs a [`Script`] frame by frame: each step is a few frames of injected egui events
//! (press, move, release) or a request to the viewer (resize, idle, measure), and is
//! checked to have taken effect before the next begins. Errors name the script line.

use std::time::{Duration, Instant};

use anyhow::anyhow;
use egui::{Event, Modifiers, PointerButton, Pos2};

use super::check::LayoutCheck;
pub use super::observed::Observed;
use super::script::{Action, ClickKind, MeasureMode, Script, Step};
use super::widgets::SetRequest;
use crate::camera::Camera;

/// Frames a step may wait for its widget to appear or take effect.
const PATIENCE: u32 = 30;

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

fn press(pos: Pos2, button: PointerButton, pressed: bool) -> Event {
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
        let mut done = false;
        match &step.action {
            Action::Wait(n) => done = self.frames_in_step > *n,
            Action::Quit => return Ok(ScriptStep::Quit),
            Action::Click { label, at, kind } => {
                let button = match kind {
                    ClickKind::Secondary => PointerButton::Secondary,
                    _ => PointerButton::Primary,
                };
                let presses = if *kind == ClickKind::Double { 2 } else { 1 };
                // egui counts a click soon after the last as its double (or triple).
                let recent = self
                    .last_click
                    .is_some_and(|t| t.elapsed() < Duration::from_millis(400));
                if self.phase == 0 && !(presses == 2 && recent) {
                    if let Some(p) = self.locate(&step, o, label, *at)? {
                        o.widgets.hits.clear();
                        self.point = p;
                        self.last_click = Some(Instant::now());
                        events.push(Event::PointerMoved(p));
                        events.push(press(p, button, true));
                        self.phase = 1;
                        if presses == 2 {
                            // A double click in one frame: egui times clicks by frame, and
                            // a slow frame between them would make two single clicks.
                            events.push(press(p, button, false));
                            events.push(press(p, button, true));
                            events.push(press(p, button, false));
                            self.phase = 2;
                        }
                    }
                } else if self.phase == 0 {
                } else if self.phase < 2 {
                    events.push(press(self.point, button, self.phase.is_multiple_of(2)));
                    self.phase += 1;
                } else {
                    o.widgets.focus = None;
                    if !o.widgets.hits.contains(label) {
                        return Err(
                            self.error(&step, format!("the click on {label:?} did nothing"))
                        );
                    }
                    done = true;
                }
            }
            Action::DragOn { label, at, by } => {
                let d = egui::vec2(by.0, by.1);
                match self.phase {
                    0 => {
                        if let Some(p) = self.locate(&step, o, label, Some(*at))? {
                            o.widgets.hits.clear();
                            self.point = p;
                            events.push(Event::PointerMoved(p));
                            events.push(press(p, PointerButton::Primary, true));
                            self.phase = 1;
                        }
                    }
                    1 | 2 => {
                        let f = self.phase as f32 / 2.0;
                        events.push(Event::PointerMoved(self.point + d * f));
                        self.phase += 1;
                    }
                    3 => {
                        events.push(press(self.point + d, PointerButton::Primary, false));
                        self.phase += 1;
                    }
                    _ => {
                        o.widgets.focus = None;
                        if !o.widgets.hits.contains(label) {
                            return Err(
                                self.error(&step, format!("the drag on {label:?} did nothing"))
                            );
                        }
                        done = true;
                    }
                }
            }
            Action::Drag(dx, dy) => {
                let c = o.view.center();
                let d = egui::vec2(*dx, *dy);
                match self.phase {
                    0 => {
                        self.camera = Some(o.camera);
                        events.push(Event::PointerMoved(c));
                        events.push(press(c, PointerButton::Primary, true));
                    }
                    1 => events.push(Event::PointerMoved(c + d * 0.5)),
                    2 => events.push(Event::PointerMoved(c + d)),
                    3 => events.push(press(c + d, PointerButton::Primary, false)),
                    _ => {
                        if d != egui::Vec2::ZERO && self.camera == Some(o.camera) {
                            return Err(self.error(&step, "the drag did not turn the camera"));
                        }
                        done = true;
                    }
                }
                self.phase += 1;
            }
            Action::Scroll(dy) => {
                if self.phase == 0 {
                    self.camera = Some(o.camera);
                    let c = o.view.center();
                    events.push(Event::PointerMoved(c));
                    events.push(Event::MouseWheel {
                        unit: egui::MouseWheelUnit::Point,
                        delta: egui::vec2(0.0, *dy),
                        phase: egui::TouchPhase::Move,
                        source: egui::MouseWheelSource::Wheel,
                        modifiers: Modifiers::NONE,
                    });
                    self.phase = 1;
                } else if self.camera.is_some_and(|c| c.zoom != o.camera.zoom) {
                    // Let egui's smooth scrolling finish.
                    done = self.frames_in_step > 20;
                } else if self.frames_in_step > PATIENCE {
                    return Err(self.error(&step, "the scroll did not zoom"));
                }
            }
            Action::Set { label, value } => {
                if self.phase == 0 {
                    o.widgets.focus = Some(label.clone());
                    o.widgets.set = Some(SetRequest {
                        label: label.clone(),
                        value: value.clone(),
                        outcome: None,
                    });
                    self.phase = 1;
                } else {
                    match o.widgets.set.as_ref().and_then(|s| s.outcome.clone()) {
                        Some(Ok(())) => done = true,
                        Some(Err(e)) => return Err(self.error(&step, e)),
                        None if self.frames_in_step > PATIENCE => {
                            return Err(self.error(
                                &step,
                                format!(
                                    "no widget labelled {label:?} took the value; widgets: {:?}",
                                    o.widgets.labels()
                                ),
                            ))
                        }
                        None => {}
                    }
                    if done {
                        o.widgets.set = None;
                        o.widgets.focus = None;
                    }
                }
            }
            Action::Key(name) => {
                let key = egui::Key::from_name(name)
                    .ok_or_else(|| self.error(&step, format!("no key {name:?}")))?;
                let event = |pressed| Event::Key {
                    key,
                    physical_key: None,
                    pressed,
                    repeat: false,
                    modifiers: Modifiers::NONE,
                };
                match self.phase {
                    0 => {
                        o.widgets.hits.clear();
                        events.push(event(true));
                    }
                    1 => events.push(event(false)),
                    _ => {
                        if !o.widgets.hits.contains(&format!("key {name}")) {
                            return Err(self.error(
                                &step,
                                format!("key {name} did nothing (shortcuts: Home, F12)"),
                            ));
                        }
                        done = true;
                    }
                }
                self.phase += 1;
            }
            Action::Resize(w, h) => {
                if self.phase == 0 {
                    self.phase = 1;
                    return Ok(ScriptStep::Resize(*w, *h));
                }
                if o.window == [*w, *h] {
                    done = true;
                } else if self.frames_in_step > PATIENCE {
                    return Err(self.error(
                        &step,
                        format!("the window is {}x{}, not {w}x{h}", o.window[0], o.window[1]),
                    ));
                }
            }
            Action::Idle(ms) => {
                let now = Instant::now();
                let deadline = *self.deadline.get_or_insert_with(|| {
                    self.frames_at = o.frames;
                    now + Duration::from_millis(*ms)
                });
                if now < deadline {
                    return Ok(ScriptStep::Idle(deadline));
                }
                let drawn = o.frames.saturating_sub(self.frames_at + 1);
                println!(
                    "idle: {drawn} frames drawn in {ms} ms (script line {})",
                    step.line
                );
                done = true;
            }
            Action::Print(label) => match o.widgets.text_of(label) {
                Some(text) => {
                    println!("print {label}: {text} (script line {})", step.line);
                    done = true;
                }
                None if self.frames_in_step > PATIENCE => {
                    return Err(self.error(&step, format!("no text labelled {label:?}")))
                }
                None => {}
            },
            Action::CheckLayout => {
                let check = self.layout.get_or_insert_with(LayoutCheck::default);
                match check.step(o) {
                    Ok(finished) => done = finished,
                    Err(e) => return Err(self.error(&step, e)),
                }
            }
            Action::WindowShot => {
                if self.phase == 0 {
                    self.phase = 1;
                    return Ok(ScriptStep::WindowShot);
                }
                done = true;
            }
            Action::Measure(n, mode) => {
                let now = Instant::now();
                let t0 = *self.started.get_or_insert(now);
                if self.frames_in_step > *n {
                    let ms = now.duration_since(t0).as_secs_f64() * 1e3 / *n as f64;
                    println!(
                        "measure {}: {n} frames, {ms:.1} ms per frame ({:.2} fps), view {}x{}, window {}x{}, interactive quality {} (script line {})",
                        mode.name(),
                        1e3 / ms.max(1e-9),
                        o.view_px[0],
                        o.view_px[1],
                        o.window[0],
                        o.window[1],
                        o.quality,
                        step.line
                    );
                    done = true;
                } else {
                    return Ok(ScriptStep::Measure(*mode));
                }
            }
        }
        if done {
            self.next();
        }
        Ok(ScriptStep::Events(events))
    }
}
