use super::*;
use crate::fit_zoom;
use arbvis_core::camera::Projection;
use arbvis_data::volume::axes::{span, Numbers};

/// Text as a font of this size measures it, about: 0.55 em per character, 1.25 em tall.
fn measure(t: &str, size: f32) -> Vec2 {
    Vec2::new(0.55 * size * t.chars().count() as f32, 1.25 * size)
}

/// F3's axes: 75 samples at 4 ms, crosslines 875..892, inlines 111..133.
fn seismic() -> [Axis; 3] {
    [
        Axis {
            name: "time (ms)".into(),
            len: 75,
            numbers: Numbers::Linear {
                start: 0.0,
                step: 4.0,
            },
        },
        Axis {
            name: "crossline".into(),
            len: 18,
            numbers: Numbers::Listed((875..893).map(f64::from).collect()),
        },
        Axis {
            name: "inline".into(),
            len: 23,
            numbers: Numbers::Listed((111..134).map(f64::from).collect()),
        },
    ]
}

/// Three spans that all start at 0 (so `0` labels meet at a corner).
fn from_zero() -> [Axis; 3] {
    [
        span("x (m)", 0.0, 12_000.0),
        span("y (m)", 0.0, 1_500.0),
        span("sample", 0.0, 63.0),
    ]
}

/// Rotations spread over the sphere from a fixed generator (no special angles).
fn rotations(n: usize) -> Vec<[f64; 4]> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..n)
        .map(|_| {
            let q = glam::DQuat::from_xyzw(next(), next(), next(), next()).normalize();
            q.to_array()
        })
        .collect()
}

/// Every text inside `area` and no two within [`GAP`] of each other.
fn assert_apart_and_inside(layout: &BoxLayout, area: Rect, case: &str) {
    for t in &layout.texts {
        assert!(
            area.expand(0.01).contains_rect(t.rect),
            "{case}: {:?} at {:?} leaves {area:?}",
            t.text,
            t.rect
        );
    }
    for (i, a) in layout.texts.iter().enumerate() {
        for b in &layout.texts[i + 1..] {
            let gap = if a.text == b.text { SAME_TEXT_GAP } else { GAP };
            assert!(
                !a.rect.expand(gap - 0.01).intersects(b.rect),
                "{case}: {:?} at {:?} touches {:?} at {:?}",
                a.text,
                a.rect,
                b.text,
                b.rect
            );
        }
    }
}

#[test]
fn labels_stay_inside_and_apart_at_any_rotation() {
    let ink = Ink::on([0.0, 0.0, 0.0, 1.0]);
    let mut cases = 0;
    let mut names_missing = 0;
    let mut ticks_dropped = 0;
    for (w, h) in [(600.0, 500.0), (300.0, 260.0), (900.0, 300.0)] {
        let area = Rect::from_min_size(Pos2::new(250.0, 0.0), Vec2::new(w, h));
        for (axes, half) in [
            (seismic(), DVec3::new(1.0, 0.45, 0.7)),
            (from_zero(), DVec3::new(1.0, 0.125, 0.33)),
        ] {
            for projection in [Projection::Orthographic, Projection::Perspective] {
                for rotation in rotations(150) {
                    let mut camera = Camera {
                        projection,
                        rotation,
                        ..Camera::default()
                    };
                    camera.zoom = fit_zoom(&camera, half);
                    let p = Projector::new(&camera, area);
                    let layout = layout_box(&p, area, half, &axes, [None; 3], ink, &measure);
                    let case = format!("{w}x{h} {projection:?} {rotation:?}");
                    assert_apart_and_inside(&layout, area, &case);
                    cases += 1;
                    // Names: one per axis seen along an edge of 24 points or more.
                    let corners: Vec<Pos2> = (0..8).map(|i| p.project(corner(half, i))).collect();
                    let plans = plan_axes(&corners, p.project(DVec3::ZERO), half, &axes, &p);
                    let names = layout
                        .texts
                        .iter()
                        .filter(|t| axes.iter().any(|a| a.name == t.text))
                        .count();
                    names_missing += plans.len() - names;
                    let ticks: usize = plans.iter().map(|p| p.ticks.len()).sum();
                    ticks_dropped += ticks - (layout.texts.len() - names);
                }
            }
        }
    }
    assert_eq!(cases, 1800);
    // Crowded views (300x260 with F3's five-digit crosslines) drop labels rather than
    // overlap them: the check above would fail otherwise. Axis names come first, so
    // they are almost never lost (measured: 0 of 1800 x about 2.7 axes).
    assert_eq!(names_missing, 0);
    assert!(
        ticks_dropped > 0,
        "no case crowded the ticks: the test would not see overlaps"
    );
}

#[test]
fn a_label_is_moved_inside_whole() {
    let area = Rect::from_min_max(Pos2::new(0.0, 0.0), Pos2::new(100.0, 50.0));
    // "sample" anchored at the right edge: moved left until it ends at the edge.
    let r = Rect::from_min_size(Pos2::new(95.0, 10.0), Vec2::new(40.0, 12.0));
    assert_eq!(
        moved_inside(r, area),
        Rect::from_min_size(Pos2::new(60.0, 10.0), Vec2::new(40.0, 12.0))
    );
    // Above the top and left of the left edge.
    let r = Rect::from_min_size(Pos2::new(-5.0, -3.0), Vec2::new(10.0, 10.0));
    assert_eq!(moved_inside(r, area).min, Pos2::new(0.0, 0.0));
    // Wider than the area: its start stays in.
    let r = Rect::from_min_size(Pos2::new(30.0, 10.0), Vec2::new(150.0, 10.0));
    assert_eq!(moved_inside(r, area).min, Pos2::new(0.0, 10.0));
}

#[test]
fn ink_contrasts_with_the_background() {
    let dark = Ink::on([0.0, 0.0, 0.0, 1.0]);
    let light = Ink::on([1.0, 1.0, 1.0, 1.0]);
    // Text luminance at least 200 levels from the background's.
    assert!(dark.text.r() >= 200 && light.text.r() <= 55);
    // A mid grey counts by its luminance: green weighs most.
    assert_eq!(Ink::on([0.2, 0.8, 0.2, 1.0]), light);
    assert_eq!(Ink::on([0.8, 0.2, 0.8, 1.0]), dark);
}
