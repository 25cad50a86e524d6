//! How the viewer fits a screen: the window's first size (the scene's view plus the
//! panels, within the monitor), the panels' sizes for a window size (the 3D view keeps
//! most of the window), and the text sizes (none under [`MIN_TEXT`] points).
//!
//! Decisions:
//! - The window starts at the size the user left it at ([`super::remembered`]), else at
//!   the monitor's usable part ([`SCREEN_SHARE`]: a small scene gets a larger view, not a
//!   small window that scrolls its panels), and never more than that part ([`usable`]: the monitor less room for a title bar and a task
//!   bar). The scene's size follows the view, as on any resize; a scene too large for
//!   the screen is shown smaller and the status line says so.
//! - The left panel is fixed; the lut 3D panel narrows from [`RIGHT_MAX`] to
//!   [`RIGHT_MIN`] points so that the view keeps [`VIEW_SHARE`] of the window's width;
//!   the sections panel takes a quarter of the height, within [`SECTIONS_MIN`] ..
//!   [`SECTIONS_MAX`]. Every panel scrolls what does not fit (never clips it).

use egui::{FontId, TextStyle, Vec2};

/// Width of the left (controls) panel in points.
pub const LEFT: f32 = 250.0;
/// Widest lut 3D panel (the whole coefficient grid and full-width curves).
pub const RIGHT_MAX: f32 = 430.0;
/// Narrowest lut 3D panel (the grid still fits; curves narrow).
pub const RIGHT_MIN: f32 = 330.0;
/// Share of the window's width the 3D view keeps when the lut 3D panel narrows.
pub const VIEW_SHARE: f32 = 0.45;
/// Tallest sections panel.
pub const SECTIONS_MAX: f32 = 220.0;
/// Shortest sections panel (three sections and their sliders still readable).
pub const SECTIONS_MIN: f32 = 140.0;
/// Share of the window's height the sections panel takes.
pub const SECTIONS_SHARE: f32 = 0.25;
/// The smallest text anywhere in the viewer (points): hints, tick labels, legends.
pub const MIN_TEXT: f32 = 11.0;
/// Smallest 3D view (points) a scene's window is made for, for a 3D-opacity volume
/// (room for the box labels and colour bars around a small volume).
pub const MIN_VOLUME_VIEW: f32 = 420.0;
/// Smallest window height made at start (points).
pub const MIN_HEIGHT: f32 = 480.0;
/// Least share of the monitor's usable part (each side) the window starts with: all of
/// it, so that the panels need not scroll where the screen has room (at three quarters a
/// 1280x1024 screen left 300 points unused while the panels scrolled).
pub const SCREEN_SHARE: f32 = 1.0;

/// The panels' sizes in points (0 for a panel not shown).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Panels {
    /// The controls on the left.
    pub left: f32,
    /// The lut 3D editor on the right.
    pub right: f32,
    /// The sections below the view.
    pub bottom: f32,
}

/// The panels for a window of `window` points, with the lut 3D panel and the sections
/// panel when shown.
pub fn panels(window: Vec2, lut3d: bool, sections: bool) -> Panels {
    let right = if lut3d {
        (window.x - LEFT - VIEW_SHARE * window.x).clamp(RIGHT_MIN, RIGHT_MAX)
    } else {
        0.0
    };
    let bottom = if sections {
        (SECTIONS_SHARE * window.y).clamp(SECTIONS_MIN, SECTIONS_MAX)
    } else {
        0.0
    };
    Panels {
        left: LEFT,
        right,
        bottom,
    }
}

/// The part of a monitor of `monitor` points a window may take: room is left for a
/// title bar and a task bar (8 % of the height) and the window's borders (3 % of the
/// width).
pub fn usable(monitor: Vec2) -> Vec2 {
    Vec2::new((monitor.x * 0.97).floor(), (monitor.y * 0.92).floor())
}

/// The window's first inner size (points) for a scene whose view is `scene` pixels
/// (points at scale 1), on a monitor whose usable part is `usable` (unknown: `None`).
pub fn first_window(scene: [u32; 2], volume: bool, usable: Option<Vec2>) -> Vec2 {
    let min_view = if volume { MIN_VOLUME_VIEW } else { 0.0 };
    let view = Vec2::new(
        (scene[0] as f32).max(min_view),
        (scene[1] as f32).max(min_view),
    );
    let (right, below) = if volume {
        (RIGHT_MAX, SECTIONS_MAX)
    } else {
        (0.0, 0.0)
    };
    let want = Vec2::new(LEFT + view.x + right, (view.y + below).max(MIN_HEIGHT));
    match usable {
        Some(u) => want
            .max(u * SCREEN_SHARE)
            .min(u)
            .max(Vec2::splat(64.0))
            .floor(),
        None => want,
    }
}

/// The viewer's text styles: egui's, with every size raised to at least [`MIN_TEXT`]
/// (egui's `Small`, used for hints and status lines, is 9 points) and weak text (hints)
/// a lighter grey, readable on the panels' dark background.
pub fn style(ctx: &egui::Context) {
    ctx.all_styles_mut(|style| {
        for font in style.text_styles.values_mut() {
            font.size = font.size.max(MIN_TEXT);
        }
        style.visuals.weak_text_color = Some(egui::Color32::from_gray(160));
        // Scroll bars drawn whenever a panel's content overflows, not only on hover: a
        // floating bar hides that "Save tables" lies below the window's edge.
        style.spacing.scroll = egui::style::ScrollStyle::solid();
    });
}

/// The font of overlay text of `size` points (never under [`MIN_TEXT`]).
pub fn overlay_font(size: f32) -> FontId {
    FontId::proportional(size.max(MIN_TEXT))
}

/// The smallest text size of `ctx`'s style (for checks).
pub fn smallest_text(ctx: &egui::Context) -> f32 {
    ctx.global_style()
        .text_styles
        .iter()
        .filter(|(s, _)| !matches!(s, TextStyle::Name(_)))
        .map(|(_, f)| f.size)
        .fold(f32::INFINITY, f32::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_view_keeps_most_of_the_window() {
        // 1024x768, 1280x1024 and 1920x1080 screens, usable parts as `usable` gives.
        for (screen, right, bottom) in [
            // 993 - 250 - 0.45 * 993 = 296 -> the narrowest lut 3D panel.
            ([1024.0, 768.0], RIGHT_MIN, 176.0),
            // 1241 - 250 - 558 = 432 -> the widest.
            ([1280.0, 1024.0], RIGHT_MAX, SECTIONS_MAX),
            ([1920.0, 1080.0], RIGHT_MAX, SECTIONS_MAX),
        ] {
            let w = usable(Vec2::from(screen));
            let p = panels(w, true, true);
            assert_eq!((p.right, p.bottom.floor()), (right, bottom), "{screen:?}");
            let view = Vec2::new(w.x - p.left - p.right, w.y - p.bottom);
            // The view is the largest region: wider than the two side panels each, at
            // least 40 % of the width (the narrowest panels on a 1024 screen leave
            // 413 of 993) and 70 % of the height (the sections take a quarter at most).
            assert!(
                view.x >= 0.4 * w.x && view.x > p.right,
                "{screen:?}: {view:?}"
            );
            assert!(view.y >= 0.7 * w.y, "{screen:?}: {view:?}");
        }
        // Without the lut 3D panel the view has three quarters of a 1024 screen.
        let w = usable(Vec2::new(1024.0, 768.0));
        assert!(w.x - panels(w, false, false).left >= 0.74 * w.x);
    }

    #[test]
    fn the_first_window_fits_the_screen() {
        // The splats demo asks for a 1600x900 view: on a 1280x1024 screen the window is
        // the usable part, not 1850 wide.
        let u = usable(Vec2::new(1280.0, 1024.0));
        assert_eq!(u, Vec2::new(1241.0, 942.0));
        let w = first_window([1600, 900], false, Some(u));
        assert_eq!(w, u);
        // A small scene gets the whole usable part too, not 410x480 of scrolling panels.
        let w = first_window([160, 160], false, Some(u));
        assert_eq!(w, u);
        // Without a monitor the scene's size is kept (the view is 160x160).
        let w = first_window([160, 160], false, None);
        assert_eq!(w, Vec2::new(LEFT + 160.0, MIN_HEIGHT));
        // A volume gets room for its labels and both panels, within a 1024x768 screen.
        let small = usable(Vec2::new(1024.0, 768.0));
        assert_eq!(
            first_window([160, 160], true, None),
            Vec2::new(1100.0, 640.0)
        );
        assert_eq!(
            first_window([160, 160], true, Some(small)),
            Vec2::new(993.0, 706.0)
        );
        // On a 1920x1080 screen: all of its usable 1862x993.
        let big = usable(Vec2::new(1920.0, 1080.0));
        assert_eq!(
            first_window([160, 160], true, Some(big)),
            Vec2::new(1862.0, 993.0)
        );
    }

    #[test]
    fn no_text_is_smaller_than_the_minimum() {
        let ctx = egui::Context::default();
        // egui's own Small is under the minimum before the viewer's style.
        assert!(smallest_text(&ctx) < MIN_TEXT);
        style(&ctx);
        assert_eq!(smallest_text(&ctx), MIN_TEXT);
        assert_eq!(overlay_font(8.0).size, MIN_TEXT);
    }
}
