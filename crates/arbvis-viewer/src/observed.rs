//! What a script's runner sees of the viewer between frames (its own file so that the
//! runner and the checks it runs, such as [`super::check`], both read it without
//! importing each other).

use egui::Rect;

use super::widgets::Widgets;
use arbvis_core::camera::Camera;

/// What the runner sees of the viewer between frames.
pub struct Observed<'a> {
    /// The labelled widgets of the last frame.
    pub widgets: &'a mut Widgets,
    /// The 3D picture (points).
    pub view: Rect,
    /// The whole view: the picture and the legends' margin (points).
    pub shown: Rect,
    /// Frames drawn so far.
    pub frames: u64,
    /// The scene's camera.
    pub camera: Camera,
    /// The window's inner size in pixels.
    pub window: [u32; 2],
    /// The window's frame on the screen: x, y, width, height in pixels (when known).
    pub outer: Option<[i32; 4]>,
    /// The monitor's size in pixels (when known).
    pub screen: Option<[u32; 2]>,
    /// egui's scale.
    pub pixels_per_point: f32,
    /// What the overlay placed: labels and legends with their rectangles (points).
    pub overlay: &'a [(String, Rect)],
    /// The 3D view's size in pixels.
    pub view_px: [u32; 2],
    /// An action of the last frame that failed (screenshot not written, ...).
    pub action_error: Option<String>,
    /// The interactive quality's name.
    pub quality: &'static str,
    /// The divisor of each side the next interactive picture is drawn at.
    pub scale: f64,
}
