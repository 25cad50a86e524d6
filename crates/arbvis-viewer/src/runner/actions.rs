//! One script action a frame at a time: each pushes the frame's events (pointer, keys)
//! and says whether its step is done, checking that the action took effect (a click that
//! hit nothing, a drag that did not turn the camera, is the script's error at its line).

use std::time::{Duration, Instant};

use egui::{Event, Modifiers, PointerButton};

use super::{press, Observed, Outcome, ScriptRunner, ScriptStep, PATIENCE};
use crate::script::{ClickKind, MeasureMode, Step};
use crate::widgets::{SetOutcome, SetRequest};

impl ScriptRunner {
    /// `click`, `click-at`, `right-click-at`, `double-click-at`: press and release on the
    /// widget (a double click in one frame), then check that it was hit.
    pub(super) fn click(
        &mut self,
        step: &Step,
        o: &mut Observed<'_>,
        (label, at, kind): (&str, Option<(f32, f32)>, ClickKind),
        events: &mut Vec<Event>,
    ) -> anyhow::Result<Outcome> {
        let button = match kind {
            ClickKind::Secondary => PointerButton::Secondary,
            _ => PointerButton::Primary,
        };
        let presses = if kind == ClickKind::Double { 2 } else { 1 };
        // egui counts a click soon after the last as its double (or triple).
        let recent = self
            .last_click
            .is_some_and(|t| t.elapsed() < Duration::from_millis(400));
        if self.phase == 0 && !(presses == 2 && recent) {
            if let Some(p) = self.locate(step, o, label, at)? {
                o.widgets.hits.clear();
                self.point = p;
                self.last_click = Some(Instant::now());
                events.push(Event::PointerMoved(p));
                events.push(press(p, button, true));
                self.phase = 1;
                if presses == 2 {
                    // A double click in one frame: egui times clicks by frame, and a slow
                    // frame between them would make two single clicks.
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
                return Err(self.error(step, format!("the click on {label:?} did nothing")));
            }
            return Ok(Outcome::Done);
        }
        Ok(Outcome::Pending)
    }

    /// `drag-on`: press on the widget, move by `by` in two frames, release, then check
    /// that it was hit.
    pub(super) fn drag_on(
        &mut self,
        step: &Step,
        o: &mut Observed<'_>,
        (label, at, by): (&str, (f32, f32), (f32, f32)),
        events: &mut Vec<Event>,
    ) -> anyhow::Result<Outcome> {
        let d = egui::vec2(by.0, by.1);
        match self.phase {
            0 => {
                if let Some(p) = self.locate(step, o, label, Some(at))? {
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
                    return Err(self.error(step, format!("the drag on {label:?} did nothing")));
                }
                return Ok(Outcome::Done);
            }
        }
        Ok(Outcome::Pending)
    }

    /// `drag`: across the 3D view from its centre by `d`, then check that the camera
    /// turned.
    pub(super) fn drag(
        &mut self,
        step: &Step,
        o: &mut Observed<'_>,
        d: egui::Vec2,
        events: &mut Vec<Event>,
    ) -> anyhow::Result<Outcome> {
        let c = o.view.center();
        let mut outcome = Outcome::Pending;
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
                    return Err(self.error(step, "the drag did not turn the camera"));
                }
                outcome = Outcome::Done;
            }
        }
        self.phase += 1;
        Ok(outcome)
    }

    /// `scroll`: over the 3D view, then wait for egui's smooth scrolling to finish
    /// zooming.
    pub(super) fn scroll(
        &mut self,
        step: &Step,
        o: &mut Observed<'_>,
        dy: f32,
        events: &mut Vec<Event>,
    ) -> anyhow::Result<Outcome> {
        if self.phase == 0 {
            self.camera = Some(o.camera);
            let c = o.view.center();
            events.push(Event::PointerMoved(c));
            events.push(Event::MouseWheel {
                unit: egui::MouseWheelUnit::Point,
                delta: egui::vec2(0.0, dy),
                phase: egui::TouchPhase::Move,
                source: egui::MouseWheelSource::Wheel,
                modifiers: Modifiers::NONE,
            });
            self.phase = 1;
        } else if self.camera.is_some_and(|c| c.zoom != o.camera.zoom) {
            // Let egui's smooth scrolling finish.
            return Ok(Outcome::done_if(self.frames_in_step > 20));
        } else if self.frames_in_step > PATIENCE {
            return Err(self.error(step, "the scroll did not zoom"));
        }
        Ok(Outcome::Pending)
    }

    /// `set`: ask the widget labelled `label` to take `value`, then wait for its answer.
    pub(super) fn set(
        &mut self,
        step: &Step,
        o: &mut Observed<'_>,
        label: &str,
        value: &str,
    ) -> anyhow::Result<Outcome> {
        if self.phase == 0 {
            o.widgets.focus = Some(label.to_string());
            o.widgets.set = Some(SetRequest {
                label: label.to_string(),
                value: value.to_string(),
                outcome: None,
            });
            self.phase = 1;
            return Ok(Outcome::Pending);
        }
        match o.widgets.set.as_ref().and_then(|s| s.outcome.clone()) {
            Some(SetOutcome::Applied) => {
                o.widgets.set = None;
                o.widgets.focus = None;
                Ok(Outcome::Done)
            }
            Some(SetOutcome::Refused(e)) => Err(self.error(step, e)),
            None if self.frames_in_step > PATIENCE => Err(self.error(
                step,
                format!(
                    "no widget labelled {label:?} took the value; widgets: {:?}",
                    o.widgets.labels()
                ),
            )),
            None => Ok(Outcome::Pending),
        }
    }

    /// `key`: press and release, then check that a shortcut took it.
    pub(super) fn key(
        &mut self,
        step: &Step,
        o: &mut Observed<'_>,
        name: &str,
        events: &mut Vec<Event>,
    ) -> anyhow::Result<Outcome> {
        let key = egui::Key::from_name(name)
            .ok_or_else(|| self.error(step, format!("no key {name:?}")))?;
        let event = |pressed| Event::Key {
            key,
            physical_key: None,
            pressed,
            repeat: false,
            modifiers: Modifiers::NONE,
        };
        let mut outcome = Outcome::Pending;
        match self.phase {
            0 => {
                o.widgets.hits.clear();
                events.push(event(true));
            }
            1 => events.push(event(false)),
            _ => {
                if !o.widgets.hits.contains(&format!("key {name}")) {
                    return Err(self.error(
                        step,
                        format!("key {name} did nothing (shortcuts: Home, F12)"),
                    ));
                }
                outcome = Outcome::Done;
            }
        }
        self.phase += 1;
        Ok(outcome)
    }

    /// `resize`: ask for the window size, then wait until the window has it.
    pub(super) fn resize(
        &mut self,
        step: &Step,
        o: &Observed<'_>,
        [w, h]: [u32; 2],
    ) -> anyhow::Result<Outcome> {
        if self.phase == 0 {
            self.phase = 1;
            return Ok(Outcome::Now(ScriptStep::Resize(w, h)));
        }
        if o.window == [w, h] {
            Ok(Outcome::Done)
        } else if self.frames_in_step > PATIENCE {
            Err(self.error(
                step,
                format!("the window is {}x{}, not {w}x{h}", o.window[0], o.window[1]),
            ))
        } else {
            Ok(Outcome::Pending)
        }
    }

    /// `idle`: draw nothing for `ms`, then print the frames drawn meanwhile.
    pub(super) fn idle(&mut self, step: &Step, o: &Observed<'_>, ms: u64) -> Outcome {
        let now = Instant::now();
        let deadline = *self.deadline.get_or_insert_with(|| {
            self.frames_at = o.frames;
            now + Duration::from_millis(ms)
        });
        if now < deadline {
            return Outcome::Now(ScriptStep::Idle(deadline));
        }
        let drawn = o.frames.saturating_sub(self.frames_at + 1);
        println!(
            "idle: {drawn} frames drawn in {ms} ms (script line {})",
            step.line
        );
        Outcome::Done
    }

    /// `print`: the text of the line labelled `label`, once it is on screen.
    pub(super) fn print(
        &mut self,
        step: &Step,
        o: &Observed<'_>,
        label: &str,
    ) -> anyhow::Result<Outcome> {
        match o.widgets.text_of(label) {
            Some(text) => {
                println!("print {label}: {text} (script line {})", step.line);
                Ok(Outcome::Done)
            }
            None if self.frames_in_step > PATIENCE => {
                Err(self.error(step, format!("no text labelled {label:?}")))
            }
            None => Ok(Outcome::Pending),
        }
    }

    /// `measure`: draw `n` frames in `mode`, then print the frame rate.
    pub(super) fn measure(
        &mut self,
        step: &Step,
        o: &Observed<'_>,
        n: u32,
        mode: MeasureMode,
    ) -> Outcome {
        let now = Instant::now();
        let t0 = *self.started.get_or_insert(now);
        if self.frames_in_step <= n {
            return Outcome::Now(ScriptStep::Measure(mode));
        }
        let ms = now.duration_since(t0).as_secs_f64() * 1e3 / n as f64;
        println!(
            "measure {}: {n} frames, {ms:.1} ms per frame ({:.2} fps), view {}x{}, window {}x{}, interactive quality {} (scale 1/{:.1}) (script line {})",
            mode.name(),
            1e3 / ms.max(1e-9),
            o.view_px[0],
            o.view_px[1],
            o.window[0],
            o.window[1],
            o.quality,
            o.scale,
            step.line
        );
        Outcome::Done
    }
}
