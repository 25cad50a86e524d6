//! A script's `check layout`: every control the panels drew is scrolled into view in
//! turn and must then lie whole inside its panel's visible part and inside the window;
//! the window must lie inside the screen; the overlay's labels must lie apart and inside
//! the 3D picture, its legends apart, inside the view and clear of the picture. Each
//! rectangle is printed (`layout: ...`, points) so a test can assert on the numbers.

use egui::{Pos2, Rect};

use super::observed::Observed;

/// Frames a control may take to scroll whole into view...
const PATIENCE: u32 = 30;

/// ...and time: egui's scrolling is animated over time, so on a loaded machine (the test
/// suite's parallel viewers under Xvfb) 30 frames can pass before it settles.
const PATIENCE_TIME: std::time::Duration = std::time::Duration::from_secs(5);

/// The check in progress.
#[derive(Debug, Default)]
pub struct LayoutCheck {
    started: bool,
    /// Labels still to check (the next is last).
    pending: Vec<String>,
    /// Lines to print at the end.
    lines: Vec<String>,
    /// Frames spent on the current label.
    waited: u32,
    /// When the current label's wait began.
    since: Option<std::time::Instant>,
}

fn rect(r: Rect) -> String {
    format!(
        "{:.1} {:.1} {:.1} {:.1}",
        r.min.x, r.min.y, r.max.x, r.max.y
    )
}

/// What does not fit in the window: a message for the script line that checked.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Misfit(pub String);

impl LayoutCheck {
    /// One frame of the check: `Ok(true)` once done (the lines printed), `Ok(false)` to
    /// go on next frame, `Err` naming what does not fit.
    pub fn step(&mut self, o: &mut Observed<'_>) -> Result<bool, Misfit> {
        let ppp = o.pixels_per_point.max(1e-3);
        let window = Rect::from_min_max(
            Pos2::ZERO,
            Pos2::new(o.window[0] as f32 / ppp, o.window[1] as f32 / ppp),
        );
        if !self.started {
            self.started = true;
            self.pending = o.widgets.labels();
            self.pending.reverse();
            let screen = o
                .screen
                .map_or("unknown".into(), |[w, h]| format!("{w}x{h}"));
            let at = o
                .outer
                .map_or("unknown".into(), |[x, y, w, h]| format!("{x} {y} {w} {h}"));
            self.lines.push(format!(
                "layout: screen {screen}, window {}x{} (outer {at}), {ppp} pixels per point",
                o.window[0], o.window[1]
            ));
            self.lines.push(format!(
                "layout: view {} 3D {}",
                rect(o.shown),
                rect(o.view)
            ));
            if let (Some([sw, sh]), Some([x, y, w, h])) = (o.screen, o.outer) {
                if x < 0 || y < 0 || x + w > sw as i32 || y + h > sh as i32 {
                    return Err(Misfit(format!(
                        "the window ({x}, {y}, {w} x {h} pixels with its frame) is not inside the {sw}x{sh} screen"
                    )));
                }
            }
        }
        while let Some(label) = self.pending.last().cloned() {
            o.widgets.focus = Some(label.clone());
            let whole = o.widgets.get(&label).map(|seen| {
                let fits = seen.visible.expand(0.5).contains_rect(seen.rect)
                    && window.expand(0.5).contains_rect(seen.rect);
                (fits, *seen)
            });
            match whole {
                Some((true, seen)) => {
                    self.lines
                        .push(format!("layout: control {label:?} {}", rect(seen.rect)));
                    self.pending.pop();
                    self.waited = 0;
                    self.since = None;
                }
                _ if self.waited < PATIENCE
                    || self
                        .since
                        .get_or_insert_with(std::time::Instant::now)
                        .elapsed()
                        < PATIENCE_TIME =>
                {
                    self.waited += 1;
                    return Ok(false);
                }
                Some((false, seen)) => {
                    return Err(Misfit(format!(
                    "{label:?} at {} is not whole inside the window ({}): its visible part is {}",
                    rect(seen.rect),
                    rect(window),
                    rect(seen.visible)
                )))
                }
                None => {
                    return Err(Misfit(format!(
                        "{label:?} is no longer drawn (closed or hidden since the check began)"
                    )))
                }
            }
        }
        o.widgets.focus = None;
        // A panel taller than its window shows a scroll bar without being hovered.
        for (name, content, shown, floating) in &o.widgets.scrolls {
            let overflows = *content > *shown + 0.5;
            self.lines.push(format!(
                "layout: scroll {name:?} content {content:.1} shown {shown:.1} {}",
                if overflows { "overflows" } else { "fits" }
            ));
            if overflows && *floating {
                return Err(Misfit(format!(
                    "the {name} overflows ({content:.0} points in {shown:.0}) behind a floating scroll bar, hidden until hovered"
                )));
            }
        }
        let problems = overlay_problems(o.view, o.shown, o.overlay);
        if let Some(p) = problems.first() {
            return Err(Misfit(format!(
                "overlay: {p} ({} problems)",
                problems.len()
            )));
        }
        for (name, r) in o.overlay {
            self.lines
                .push(format!("layout: overlay {name:?} {}", rect(*r)));
        }
        let controls = self
            .lines
            .iter()
            .filter(|l| l.starts_with("layout: control"))
            .count();
        self.lines.push(format!(
            "layout: {controls} controls whole inside the window, {} overlay items apart",
            o.overlay.len()
        ));
        for line in self.lines.drain(..) {
            println!("{line}");
        }
        Ok(true)
    }
}

/// What is wrong with the overlay's items (`label ...`, `legend ...`, `legend text ...`):
/// labels outside the 3D picture `view` or overlapping another label; legends outside
/// the whole `shown` view, over the picture, or overlapping another legend.
pub fn overlay_problems(view: Rect, shown: Rect, items: &[(String, Rect)]) -> Vec<String> {
    let inside = |outer: Rect, r: Rect| outer.expand(0.5).contains_rect(r);
    let mut out = Vec::new();
    let of = |kind: &str| -> Vec<&(String, Rect)> {
        items
            .iter()
            .filter(|(n, _)| {
                n.starts_with(kind) && !(kind == "legend " && n.starts_with("legend text "))
            })
            .collect()
    };
    let labels = of("label ");
    let legends = of("legend ");
    for (n, r) in &labels {
        if !inside(view, *r) {
            out.push(format!(
                "{n:?} at {} leaves the 3D picture {}",
                rect(*r),
                rect(view)
            ));
        }
    }
    for (n, r) in of("legend text ").iter().chain(&legends) {
        if !inside(shown, *r) {
            out.push(format!(
                "{n:?} at {} leaves the view {}",
                rect(*r),
                rect(shown)
            ));
        }
        if r.intersects(view) && r.intersect(view).area() > 0.0 {
            out.push(format!(
                "{n:?} at {} lies over the 3D picture {}",
                rect(*r),
                rect(view)
            ));
        }
    }
    for group in [&labels, &legends] {
        for (i, (a, ra)) in group.iter().enumerate() {
            for (b, rb) in &group[i + 1..] {
                if ra.intersects(*rb) {
                    out.push(format!(
                        "{a:?} at {} overlaps {b:?} at {}",
                        rect(*ra),
                        rect(*rb)
                    ));
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(x0: f32, y0: f32, x1: f32, y1: f32) -> Rect {
        Rect::from_min_max(Pos2::new(x0, y0), Pos2::new(x1, y1))
    }

    #[test]
    fn overlay_problems_are_named() {
        let view = r(0.0, 0.0, 300.0, 200.0);
        let shown = r(0.0, 0.0, 400.0, 200.0);
        let good = vec![
            ("label 0".to_string(), r(10.0, 10.0, 20.0, 22.0)),
            ("label 0".to_string(), r(30.0, 10.0, 40.0, 22.0)),
            ("legend facies".to_string(), r(308.0, 8.0, 392.0, 80.0)),
            ("legend text facies".to_string(), r(308.0, 8.0, 350.0, 20.0)),
            ("legend layers".to_string(), r(308.0, 92.0, 392.0, 150.0)),
        ];
        assert_eq!(overlay_problems(view, shown, &good), Vec::<String>::new());
        let mut bad = good.clone();
        bad.push(("label 63".into(), r(15.0, 15.0, 30.0, 27.0))); // over the first 0
        bad.push(("label sample".into(), r(290.0, 50.0, 330.0, 62.0))); // cut by the margin
        bad.push(("legend key".into(), r(250.0, 160.0, 320.0, 190.0))); // over the picture
        let p = overlay_problems(view, shown, &bad);
        assert_eq!(p.len(), 4, "{p:#?}");
        assert!(p[0].contains("\"label sample\"") && p[0].contains("leaves the 3D picture"));
        assert!(p[1].contains("\"legend key\"") && p[1].contains("over the 3D picture"));
        assert!(p[2].contains("\"label 0\"") && p[2].contains("overlaps \"label 63\""));
        // The second 0 touches the 63 at x = 30: touching counts.
        assert!(p[3].starts_with("\"label 0\" at 30.0") && p[3].contains("overlaps \"label 63\""));
    }
}
