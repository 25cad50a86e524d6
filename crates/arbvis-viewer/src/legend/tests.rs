use super::*;

/// Text as a font of this size measures it, about: 0.55 em per character, 1.25 em tall.
fn measure(t: &str, size: f32) -> Vec2 {
    Vec2::new(0.55 * size * t.chars().count() as f32, 1.25 * size)
}

fn bar(title: &str, lo: &str, hi: &str) -> Legend {
    Legend::Bar {
        title: title.into(),
        texture: TextureId::default(),
        lo: lo.into(),
        hi: hi.into(),
    }
}

fn key(title: &str, n: usize) -> Legend {
    Legend::Key {
        title: title.into(),
        entries: (0..n)
            .map(|i| {
                (
                    Color32::from_rgb((i * 12) as u8, 100, 50),
                    format!("layer {i}"),
                )
            })
            .collect(),
    }
}

/// Every text inside the margin, no two texts or legend boxes overlapping.
fn assert_tidy(l: &LegendLayout, view: Rect) {
    let picture = l.picture(view);
    let margin = match l.side {
        Side::Right => Rect::from_min_max(Pos2::new(picture.right(), view.top()), view.max),
        Side::Top => Rect::from_min_max(view.min, Pos2::new(view.right(), picture.top())),
    };
    assert!(
        !margin.intersects(picture.shrink(0.01)),
        "{margin:?} {picture:?}"
    );
    for t in &l.texts {
        assert!(
            margin.expand(0.01).contains_rect(t.rect),
            "{:?} at {:?} leaves {margin:?}",
            t.text,
            t.rect
        );
    }
    for (i, a) in l.texts.iter().enumerate() {
        for b in &l.texts[i + 1..] {
            assert!(
                !a.rect.intersects(b.rect),
                "{:?} {:?} overlaps {:?} {:?}",
                a.text,
                a.rect,
                b.text,
                b.rect
            );
        }
    }
    for (i, (a, ra)) in l.boxes.iter().enumerate() {
        assert!(
            margin.expand(0.01).contains_rect(*ra),
            "{a} leaves the margin"
        );
        for (b, rb) in &l.boxes[i + 1..] {
            assert!(!ra.intersects(*rb), "{a} overlaps {b}");
        }
    }
}

fn bars() -> [Legend; 3] {
    [
        bar("primary: amplitude", "-1.3258", "1.2306"),
        bar("secondary: envelope", "0.0028", "1.5352"),
        bar("tertiary: cosine-phase", "-1", "1"),
    ]
}

#[test]
fn three_colour_bars_stack_in_their_margin() {
    let view = Rect::from_min_size(Pos2::new(250.0, 0.0), Vec2::new(700.0, 500.0));
    let legends = bars();
    let l = layout(view, &legends, Ink::on([0.0; 4]), &measure);
    // At the right, the picture keeps 538 x 500; along the top (one row of three, 61
    // tall) it would keep 700 x 439.
    assert_eq!(l.side, Side::Right);
    // The widest text is "tertiary: cosine-phase", 22 characters of 6.6 points = 145.2,
    // plus two paddings: 162 (rounded up).
    assert_eq!(l.size, 162.0);
    assert_eq!(l.boxes.len(), 3);
    assert_eq!(l.texts.len(), 9, "a title and two values per bar");
    assert_eq!(
        l.marks
            .iter()
            .filter(|m| matches!(m, Mark::Image(..)))
            .count(),
        3
    );
    assert_tidy(&l, view);
    // The range's values sit under the bar's two ends.
    let bar_rect = match &l.marks[1] {
        Mark::Image(r, _) => *r,
        m => panic!("{m:?}"),
    };
    let hi = l.texts.iter().find(|t| t.text == "1.2306").unwrap();
    assert_eq!(hi.rect.right(), bar_rect.right());
    assert!(hi.rect.top() >= bar_rect.bottom());
}

#[test]
fn a_tall_view_puts_its_bars_on_top() {
    // The view beside a narrow window's lut 3D panel: 300 x 480.
    let view = Rect::from_min_size(Pos2::new(250.0, 0.0), Vec2::new(300.0, 480.0));
    let l = layout(view, &bars(), Ink::on([0.0; 4]), &measure);
    // At the right (105 points, 35 % of 300) the picture would keep 195 x 480; on top,
    // two rows (primary and secondary side by side, 120 and 126 points wide, tertiary's
    // 146 below) of 45 points each take 8 + 45 + 8 + 45 + 8 = 114 and leave 300 x 366.
    assert_eq!((l.side, l.size), (Side::Top, 114.0));
    assert_eq!(l.picture(view).height(), 366.0);
    assert_eq!(l.boxes.len(), 3);
    assert_tidy(&l, view);
}

#[test]
fn long_texts_are_cut_and_long_keys_say_what_is_left_out() {
    // A narrow view: the margin is 35 % of 200 points; the title is cut with "…".
    let view = Rect::from_min_size(Pos2::new(0.0, 0.0), Vec2::new(200.0, 150.0));
    let legends = [key("isovalues of a scalar with a very long name", 20)];
    let l = layout(view, &legends, Ink::on([1.0; 4]), &measure);
    assert_eq!(l.size, 70.0);
    assert!(l.texts[0].text.ends_with('…'), "{:?}", l.texts[0].text);
    // 150 points hold the title and some of the 20 entries, then "… N more".
    let last = &l.texts.last().unwrap().text;
    // (Entries are cut too, "lay…": count their swatches.)
    let shown = l
        .marks
        .iter()
        .filter(|m| matches!(m, Mark::Fill(..)))
        .count();
    assert!((3..20).contains(&shown), "{shown}");
    // "… 15 more", itself cut to the 54 points inside the margin.
    assert!(last.starts_with(&format!("… {} m", 20 - shown)), "{last:?}");
    assert_tidy(&l, view);
    // No legends: no margin.
    assert_eq!(layout(view, &[], Ink::on([1.0; 4]), &measure).size, 0.0);
}

#[test]
fn class_names_follow_asprs() {
    assert_eq!(class_name(2), "2 ground");
    assert_eq!(class_name(9), "9 water");
    assert_eq!(class_name(42), "class 42");
}
