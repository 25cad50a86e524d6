//! Labelled widgets: every control the panels draw goes through here, so that a script
//! can find it (its rectangle, whether it is enabled and visible), scroll it into view,
//! learn whether a click took effect, and hand it a value (`set`).
//!
//! Decisions: a widget's rectangle is recorded clipped to what its scroll area shows (a
//! click on a hidden part would land elsewhere); the widget a script is about to use is
//! scrolled into view by the widget itself; a `set` is applied by the widget's own code,
//! which checks the value (range, integer, option name) as an edit would, and records the
//! outcome for the script to read on the next frame.

use std::collections::{HashMap, HashSet};

use egui::{Rect, Response, Ui};

/// Where a widget was drawn this frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seen {
    /// The whole widget (points).
    pub rect: Rect,
    /// The part that is visible (empty when scrolled out).
    pub visible: Rect,
    /// Whether it takes input.
    pub enabled: bool,
}

/// A value a script hands to a widget, and what became of it.
#[derive(Debug, Clone, PartialEq)]
pub struct SetRequest {
    /// The widget's label.
    pub label: String,
    /// The value as written.
    pub value: String,
    /// `None` until the widget took it; then applied or why not.
    pub outcome: Option<SetOutcome>,
}

/// What a widget did with a script's value.
#[derive(Debug, Clone, PartialEq)]
pub enum SetOutcome {
    /// It took the value.
    Applied,
    /// It refused it, saying why.
    Refused(String),
}

impl SetOutcome {
    /// Applied where `result` is `Ok`, else refused with the error's message.
    pub fn of<T, E: std::fmt::Display>(result: &Result<T, E>) -> SetOutcome {
        match result {
            Ok(_) => SetOutcome::Applied,
            Err(e) => SetOutcome::Refused(e.to_string()),
        }
    }
}

/// The registry, rebuilt every frame.
#[derive(Debug, Default)]
pub struct Widgets {
    seen: HashMap<String, Seen>,
    texts: HashMap<String, String>,
    /// Labels whose widget responded (clicked, changed, edited) since the script last
    /// cleared them.
    pub hits: HashSet<String>,
    /// The label a script is about to use: scrolled into view when drawn.
    pub focus: Option<String>,
    /// A pending `set`.
    pub set: Option<SetRequest>,
    /// The scrolled panels of the last frame: name, content and shown height (points),
    /// and whether their scroll bar floats (hidden until hovered).
    pub scrolls: Vec<(String, f32, f32, bool)>,
}

impl Widgets {
    /// Forget last frame's rectangles (hits, focus and set persist).
    pub fn begin_frame(&mut self) {
        self.seen.clear();
        self.texts.clear();
        self.scrolls.clear();
    }

    /// Note a panel's scroll area after it was drawn (for `check layout`).
    pub fn note_scroll<R>(
        &mut self,
        ui: &Ui,
        name: &str,
        out: &egui::scroll_area::ScrollAreaOutput<R>,
    ) {
        self.scrolls.push((
            name.to_string(),
            out.content_size.y,
            out.inner_rect.height(),
            ui.style().spacing.scroll.floating,
        ));
    }

    /// The text a [`Widgets::text`] label showed last frame (a script's `print`).
    pub fn text_of(&self, label: &str) -> Option<&str> {
        self.texts.get(label).map(String::as_str)
    }

    /// A small text line, recorded as `label` with what it says (for `print`).
    pub fn text(&mut self, ui: &mut Ui, label: &str, text: &str) {
        let r = ui.label(egui::RichText::new(text).small());
        self.record(ui, label, r.rect, true);
        self.texts.insert(label.to_string(), text.to_string());
    }

    /// A small text line whose text `print` can read as `label`, outside the layout check
    /// (status lines that grow and shrink as the renderer reports).
    pub fn status_text(&mut self, ui: &mut Ui, label: &str, text: &str) {
        ui.label(egui::RichText::new(text).small());
        self.texts.insert(label.to_string(), text.to_string());
    }

    /// Where `label` was drawn last.
    pub fn get(&self, label: &str) -> Option<&Seen> {
        self.seen.get(label)
    }

    /// Every label drawn, sorted (for errors).
    pub fn labels(&self) -> Vec<String> {
        let mut v: Vec<String> = self.seen.keys().cloned().collect();
        v.sort();
        v
    }

    /// Record `response` under `label`; returns whether it responded this frame.
    pub fn add(&mut self, ui: &Ui, label: &str, response: &Response) -> bool {
        self.record(ui, label, response.rect, response.enabled());
        if self.focus.as_deref() == Some(label) && !ui.clip_rect().contains_rect(response.rect) {
            // At once: egui's animated scroll moves a few points a frame, too slow for a
            // script's patience in a short window.
            response.scroll_to_me_animation(
                Some(egui::Align::Center),
                egui::style::ScrollAnimation::none(),
            );
        }
        let hit = response.clicked()
            || response.changed()
            || response.secondary_clicked()
            || response.double_clicked();
        if hit {
            self.hit(label);
        }
        hit
    }

    /// Record a rectangle under `label` without a response (custom widgets).
    pub fn record(&mut self, ui: &Ui, label: &str, rect: Rect, enabled: bool) {
        let visible = rect.intersect(ui.clip_rect());
        let visible = if visible.is_positive() {
            visible
        } else {
            Rect::NOTHING
        };
        self.seen.insert(
            label.to_string(),
            Seen {
                rect,
                visible,
                enabled,
            },
        );
    }

    /// Note that `label`'s widget did something.
    pub fn hit(&mut self, label: &str) {
        self.hits.insert(label.to_string());
    }

    /// The value a pending `set` hands to `label`, once.
    pub fn take_set(&mut self, label: &str) -> Option<String> {
        match &self.set {
            Some(s) if s.label == label && s.outcome.is_none() => Some(s.value.clone()),
            _ => None,
        }
    }

    /// Record what became of the pending `set`.
    pub fn set_outcome(&mut self, outcome: SetOutcome) {
        if let Some(s) = &mut self.set {
            s.outcome = Some(outcome);
        }
    }

    /// A slider over `range` labelled `text`, recorded as `label`; takes `set` values
    /// (numbers in the range; whole numbers for integer values).
    pub fn slider<N: egui::emath::Numeric>(
        &mut self,
        ui: &mut Ui,
        label: &str,
        value: &mut N,
        range: std::ops::RangeInclusive<N>,
        text: &str,
        logarithmic: bool,
    ) -> bool {
        let set = self.numeric_set(label, &range, ui.is_enabled());
        if let Some(v) = set {
            *value = v;
        }
        let r = ui.add(
            egui::Slider::new(value, range)
                .logarithmic(logarithmic)
                .text(text),
        );
        self.add(ui, label, &r) || set.is_some()
    }

    /// A number box over `range`, recorded as `label`; takes `set` values.
    pub fn drag_value(
        &mut self,
        ui: &mut Ui,
        label: &str,
        value: &mut f64,
        range: std::ops::RangeInclusive<f64>,
        speed: f64,
    ) -> bool {
        let set = self.numeric_set(label, &range, ui.is_enabled());
        if let Some(v) = set {
            *value = v;
        }
        let r = ui.add(
            egui::DragValue::new(value)
                .range(range)
                .speed(speed)
                .max_decimals(3),
        );
        let r = r.on_hover_text(label);
        self.add(ui, label, &r) || set.is_some()
    }

    fn numeric_set<N: egui::emath::Numeric>(
        &mut self,
        label: &str,
        range: &std::ops::RangeInclusive<N>,
        enabled: bool,
    ) -> Option<N> {
        let text = self.take_set(label)?;
        let (lo, hi) = (range.start().to_f64(), range.end().to_f64());
        let outcome = match text.parse::<f64>() {
            _ if !enabled => Err(format!("{label} is disabled")),
            Ok(v) if !(lo..=hi).contains(&v) => Err(format!("{label}: {v} is outside {lo}..={hi}")),
            Ok(v) if N::INTEGRAL && v.fract() != 0.0 => {
                Err(format!("{label}: {v} is not a whole number"))
            }
            Ok(v) => Ok(v),
            Err(_) => Err(format!("{label} takes a number, got {text:?}")),
        };
        let value = outcome.as_ref().ok().map(|&v| N::from_f64(v));
        self.set_outcome(SetOutcome::of(&outcome));
        if value.is_some() {
            self.hit(label);
        }
        value
    }

    /// A check box, recorded as `label`; takes `set true` / `set false`.
    pub fn checkbox(&mut self, ui: &mut Ui, label: &str, value: &mut bool, text: &str) -> bool {
        let mut set = false;
        if let Some(v) = self.take_set(label) {
            let outcome = match v.as_str() {
                _ if !ui.is_enabled() => Err(format!("{label} is disabled")),
                "true" => Ok(true),
                "false" => Ok(false),
                other => Err(format!("{label} takes true or false, got {other:?}")),
            };
            if let Ok(b) = outcome {
                *value = b;
                set = true;
                self.hit(label);
            }
            self.set_outcome(SetOutcome::of(&outcome));
        }
        let r = ui.checkbox(value, text);
        self.add(ui, label, &r) || set
    }

    /// A drop-down choice among `options` (value, name), recorded as `label`; takes
    /// `set` values by option name.
    pub fn choice<T: PartialEq + Clone>(
        &mut self,
        ui: &mut Ui,
        label: &str,
        value: &mut T,
        options: &[(T, &str)],
        width: f32,
    ) -> bool {
        let mut changed = false;
        if let Some(v) = self.take_set(label) {
            let found = options.iter().find(|(_, n)| *n == v);
            let outcome = match found {
                _ if !ui.is_enabled() => Err(format!("{label} is disabled")),
                Some((o, _)) => {
                    *value = o.clone();
                    changed = true;
                    self.hit(label);
                    Ok(())
                }
                None => Err(format!(
                    "{label} has no option {v:?}; options: {}",
                    options
                        .iter()
                        .map(|(_, n)| *n)
                        .collect::<Vec<_>>()
                        .join(", ")
                )),
            };
            self.set_outcome(SetOutcome::of(&outcome));
        }
        let current = options
            .iter()
            .find(|(o, _)| o == value)
            .map_or("(other)", |(_, n)| *n);
        let r = egui::ComboBox::from_id_salt(label)
            .selected_text(current)
            .width(width)
            .show_ui(ui, |ui| {
                for (o, name) in options {
                    if ui.selectable_label(o == value, *name).clicked() && o != value {
                        *value = o.clone();
                        changed = true;
                    }
                }
            });
        let r = r.response.on_hover_text(label);
        self.add(ui, label, &r);
        if changed {
            self.hit(label);
        }
        changed
    }

    /// A radio button for `option` of `value`, recorded as `label`.
    pub fn radio<T: PartialEq>(
        &mut self,
        ui: &mut Ui,
        label: &str,
        value: &mut T,
        option: T,
    ) -> bool {
        let r = ui.radio_value(value, option, label);
        self.add(ui, label, &r) && r.changed()
    }

    /// A button, recorded under its text; returns whether it was clicked.
    pub fn button(&mut self, ui: &mut Ui, text: &str) -> bool {
        let r = ui.button(text);
        self.add(ui, text, &r);
        r.clicked()
    }
}
