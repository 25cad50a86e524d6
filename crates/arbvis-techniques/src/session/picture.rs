//! The session's picture, kept in an offscreen target and redrawn only when what it
//! shows changes (camera, parameters, size, background); a window shows it by a blit
//! each UI frame, an offscreen caller reads it.
//!
//! Decisions:
//! - While the user interacts (a drag, an edit just made) the picture is drawn
//!   *reduced*: the technique's cheaper parameters ([`TechniqueScene::for_interaction`])
//!   into a target of a fraction of the view's pixels, scaled up by the blit. Under
//!   [`InteractiveQuality::Budget`] (the default) that fraction follows the measured
//!   frame times so that a frame takes at most the [`FrameBudget`] (VTK's image sample
//!   distance, `AutoAdjustSampleDistances`), from the whole view down to a tenth of
//!   each side.
//! - When the user is still, the full-quality picture is drawn in parts
//!   ([`crate::techniques::DrawInParts`], runs of slices back to front), as many per UI
//!   frame as fit in the budget's part time; the reduced picture stays until the full
//!   one is complete. The parts leave exactly what one draw would, so the finished
//!   picture is the offscreen render of the scene (screenshots and Python read it).

use std::time::{Duration, Instant};

use crate::error::RenderResult;
use crate::scene::{Scene, TechniqueScene};
use crate::techniques::{Frame, Renderer};
use arbvis_core::camera::Camera;
use arbvis_core::vocab::TargetFormat;
use arbvis_gl::{Gpu, Surface, Target};

/// The most each side of a reduced picture is divided by (VTK's largest image sample
/// distance is 10 too).
pub const MAX_SCALE: f64 = 10.0;

/// How long a frame may take while the camera or a parameter moves, and how much of a
/// still frame goes to drawing full-quality parts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameBudget {
    /// A frame while the user interacts (default 66 ms: 15 frames per second, VTK's
    /// `DesiredUpdateRate`).
    pub interactive: Duration,
    /// Full-quality parts drawn in one UI frame while still (default 40 ms).
    pub parts: Duration,
}

impl Default for FrameBudget {
    fn default() -> FrameBudget {
        FrameBudget {
            interactive: Duration::from_millis(66),
            parts: Duration::from_millis(40),
        }
    }
}

/// How the picture is drawn while the user interacts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InteractiveQuality {
    /// The image scale and the technique's cheaper parameters chosen from measured
    /// frame times to keep each frame within the [`FrameBudget`].
    #[default]
    Budget,
    /// As when still (every frame waits for the whole picture).
    Full,
    /// Half the slices, half the pixels along each side.
    Half,
    /// A quarter of the slices and of the pixels along each side.
    Quarter,
}

impl InteractiveQuality {
    /// Every quality and its name, for panels and scripts.
    pub const ALL: [(InteractiveQuality, &'static str); 4] = [
        (InteractiveQuality::Budget, "budget"),
        (InteractiveQuality::Full, "full"),
        (InteractiveQuality::Half, "half"),
        (InteractiveQuality::Quarter, "quarter"),
    ];

    /// Its name.
    pub fn name(self) -> &'static str {
        InteractiveQuality::ALL
            .iter()
            .find(|(q, _)| *q == self)
            .map_or("budget", |(_, n)| n)
    }

    /// The fixed divisor of each side, or `None` for the budget's.
    fn fixed(self) -> Option<f64> {
        match self {
            InteractiveQuality::Budget => None,
            InteractiveQuality::Full => Some(1.0),
            InteractiveQuality::Half => Some(2.0),
            InteractiveQuality::Quarter => Some(4.0),
        }
    }
}

/// What a picture shows; a new one is drawn when it changes.
#[derive(Debug, Clone, PartialEq)]
pub struct Key {
    /// The camera.
    pub camera: Camera,
    /// View size in pixels.
    pub size: [u32; 2],
    /// Bumped whenever the renderer or its parameters change.
    pub generation: u64,
    /// Clear colour.
    pub background: [f32; 4],
    /// Target precision.
    pub format: TargetFormat,
}

impl Key {
    /// The key of `scene` after `generation` changes of its renderer, cleared to
    /// `background`.
    pub fn of(scene: &Scene, generation: u64, background: [f32; 4]) -> Key {
        Key {
            camera: scene.camera,
            size: scene.size,
            generation,
            background,
            format: scene.target_format(),
        }
    }

    /// The frame at 1/`scale` of each side (at least a pixel).
    fn frame(&self, scale: f64) -> Frame {
        let side = |n: u32| ((n as f64 / scale).round() as u32).clamp(1, n.max(1));
        Frame {
            camera: self.camera,
            width: side(self.size[0]),
            height: side(self.size[1]),
        }
    }
}

struct Drawn {
    target: Target,
    key: Key,
    full: bool,
}

struct Building {
    picture: Drawn,
    next: usize,
    parts: usize,
    spent: Duration,
}

/// What [`Picture::update`] left to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pending {
    /// The picture is the full-quality one of the current key.
    Done,
    /// A full-quality picture is being drawn: draw another frame soon.
    Building,
    /// A reduced picture is shown: refine once the user is still.
    Refine,
}

/// The kept picture, the one being drawn, and the measured times that size the next.
pub struct Picture {
    shown: Option<Drawn>,
    building: Option<Building>,
    /// Milliseconds the last full-quality picture took (all its parts).
    pub full_ms: f64,
    /// Milliseconds the last reduced picture took.
    pub interactive_ms: f64,
    /// Parts the last full-quality picture was drawn in.
    pub parts: usize,
    /// The divisor of each side the next reduced picture is drawn at (under the budget:
    /// the last one's, adapted to its time).
    pub scale: f64,
    /// The budget the frames are held to.
    pub budget: FrameBudget,
}

impl Default for Picture {
    fn default() -> Picture {
        Picture {
            shown: None,
            building: None,
            full_ms: 0.0,
            interactive_ms: 0.0,
            parts: 0,
            // Before any measure: half of each side, as the viewer always drew.
            scale: 2.0,
            budget: FrameBudget::default(),
        }
    }
}

fn fresh_target(
    gpu: &Gpu,
    old: Option<Drawn>,
    frame: &Frame,
    format: TargetFormat,
    depth: bool,
) -> RenderResult<Target> {
    let (w, h) = (frame.width, frame.height);
    Ok(match old {
        Some(p)
            if p.target.width() == w
                && p.target.height() == h
                && p.target.format() == format
                && p.target.has_depth() == depth =>
        {
            p.target
        }
        _ => Target::create(gpu, w, h, format, depth)?,
    })
}

/// The divisor of each side that brings a reduced frame measured at `ms` when drawn at
/// `scale` within `budget_ms`: its cost taken to follow the pixel count (1/scale²; the
/// technique's cheaper parameters only make it cheaper), aiming at 80 % of the budget,
/// moving at most a factor of 2 a frame (one slow frame does not halve the picture
/// twice), within 1..=[`MAX_SCALE`].
pub fn next_scale(scale: f64, ms: f64, budget_ms: f64) -> f64 {
    if !(ms.is_finite() && ms > 0.0 && budget_ms > 0.0) {
        return scale.clamp(1.0, MAX_SCALE);
    }
    let wanted = scale * (ms / (0.8 * budget_ms)).sqrt();
    wanted.clamp(scale / 2.0, scale * 2.0).clamp(1.0, MAX_SCALE)
}

/// Every layer's renderer takes its cheaper parameters for an image of 1/`scale` of each
/// side ([`TechniqueScene::for_interaction`]), or its own again (`None`): a one-layer
/// renderer through `update`, a layered one layer by layer through `update_layer` (a
/// renderer two layers share keeps its parameters).
fn reduce(
    gpu: &Gpu,
    renderer: &mut dyn Renderer,
    layers: &[&TechniqueScene],
    scale: Option<f64>,
) -> RenderResult<()> {
    let params = |t: &TechniqueScene| match scale {
        Some(s) => t.for_interaction(s),
        None => t.clone(),
    };
    match layers {
        [one] => renderer.update(gpu, params(one).params()),
        _ => {
            for (index, layer) in layers.iter().enumerate() {
                renderer.update_layer(gpu, index, params(layer).params())?;
            }
            Ok(())
        }
    }
}

impl Picture {
    /// Draw the full-quality picture again (a streaming renderer has more data for it).
    pub fn refine(&mut self) {
        if let Some(p) = &mut self.shown {
            p.full = false;
        }
    }

    /// Bring the picture of the scene's `layers` (one for a one-layer scene) up to date
    /// with `key`: reduced at `quality` while `interacting`, else in full-quality parts
    /// within the budget (`sync` draws them all now).
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        gpu: &Gpu,
        renderer: &mut dyn Renderer,
        layers: &[&TechniqueScene],
        key: &Key,
        interacting: bool,
        quality: InteractiveQuality,
        sync: bool,
    ) -> RenderResult<Pending> {
        let shown_full = self.shown.as_ref().is_some_and(|p| p.full && p.key == *key);
        if shown_full {
            self.building = None;
            return Ok(Pending::Done);
        }
        // At full interactive quality every frame waits for the whole picture.
        let sync = sync || (interacting && quality == InteractiveQuality::Full);
        let shown_current = self.shown.as_ref().is_some_and(|p| p.key == *key);
        if (interacting || self.shown.is_none()) && quality != InteractiveQuality::Full && !sync {
            if !shown_current {
                self.draw_reduced(gpu, renderer, layers, key, quality)?;
            }
            if interacting {
                self.building = None;
                return Ok(Pending::Refine);
            }
        }
        self.build(gpu, renderer, key, sync)
    }

    fn draw_reduced(
        &mut self,
        gpu: &Gpu,
        renderer: &mut dyn Renderer,
        layers: &[&TechniqueScene],
        key: &Key,
        quality: InteractiveQuality,
    ) -> RenderResult<()> {
        let scale = quality.fixed().unwrap_or(self.scale);
        let t0 = Instant::now();
        let frame = key.frame(scale);
        let target = fresh_target(
            gpu,
            self.shown.take(),
            &frame,
            key.format,
            renderer.needs_depth(),
        )?;
        target.clear(gpu, key.background)?;
        reduce(gpu, renderer, layers, Some(scale))?;
        let drawn = renderer.draw(gpu, Surface::Target(&target), &frame);
        reduce(gpu, renderer, layers, None)?;
        drawn?;
        gpu.finish();
        self.interactive_ms = t0.elapsed().as_secs_f64() * 1e3;
        self.scale = match quality {
            InteractiveQuality::Budget => next_scale(
                scale,
                self.interactive_ms,
                self.budget.interactive.as_secs_f64() * 1e3,
            ),
            _ => scale,
        };
        self.shown = Some(Drawn {
            target,
            key: key.clone(),
            full: false,
        });
        Ok(())
    }

    fn build(
        &mut self,
        gpu: &Gpu,
        renderer: &mut dyn Renderer,
        key: &Key,
        sync: bool,
    ) -> RenderResult<Pending> {
        let frame = key.frame(1.0);
        let budget = self.budget.parts;
        if self.building.as_ref().is_none_or(|b| b.picture.key != *key) {
            // A picture drawn whole now reuses the shown one's target (nothing is shown
            // meanwhile); one drawn in parts leaves it on screen until done.
            let old = match sync {
                true => self
                    .building
                    .take()
                    .map(|b| b.picture)
                    .or(self.shown.take()),
                false => self.building.take().map(|b| b.picture),
            };
            let target = fresh_target(gpu, old, &frame, key.format, renderer.needs_depth())?;
            target.clear(gpu, key.background)?;
            // Parts of about a frame's part time each, from the last full picture's time.
            let parts = if sync {
                1
            } else {
                ((self.full_ms / (budget.as_secs_f64() * 1e3)).ceil() as usize).clamp(1, 64)
            };
            self.building = Some(Building {
                picture: Drawn {
                    target,
                    key: key.clone(),
                    full: true,
                },
                next: 0,
                parts,
                spent: Duration::ZERO,
            });
        }
        let Some(b) = self.building.as_mut() else {
            return Ok(Pending::Done);
        };
        let t0 = Instant::now();
        while b.next < b.parts {
            renderer.draw_part(
                gpu,
                Surface::Target(&b.picture.target),
                &frame,
                b.next,
                b.parts,
            )?;
            gpu.finish();
            b.next += 1;
            if !sync && t0.elapsed() >= budget {
                break;
            }
        }
        b.spent += t0.elapsed();
        if b.next < b.parts {
            return Ok(Pending::Building);
        }
        if let Some(done) = self.building.take() {
            self.full_ms = done.spent.as_secs_f64() * 1e3;
            self.parts = done.parts;
            self.shown = Some(done.picture);
        }
        Ok(Pending::Done)
    }

    /// Forget the pictures (the next update draws afresh).
    pub fn invalidate(&mut self) {
        self.shown = None;
        self.building = None;
    }

    /// The full-quality picture of `key`, if it is the one shown.
    pub fn full(&self, key: &Key) -> Option<&Target> {
        self.shown
            .as_ref()
            .filter(|p| p.full && p.key == *key)
            .map(|p| &p.target)
    }

    /// The picture shown (full or reduced), if any.
    pub fn shown(&self) -> Option<&Target> {
        self.shown.as_ref().map(|p| &p.target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scale_brings_a_slow_frame_into_the_budget_and_a_fast_one_back_to_full() {
        let budget = 66.0;
        // A technique whose frame costs 400 ms at full size, following the pixel count:
        // the scale settles where the frame fits, from either side, within a few frames.
        let cost = |s: f64| 400.0 / (s * s);
        for start in [1.0, 2.0, 10.0] {
            let mut s = start;
            for _ in 0..8 {
                s = next_scale(s, cost(s), budget);
            }
            let ms = cost(s);
            // 80 % of the budget is the aim; the last step may leave it within 1 %.
            assert!(
                (ms - 0.8 * budget).abs() < 0.01 * budget,
                "start {start}: {s} {ms}"
            );
        }
        // A cheap frame goes back to full size and stays there.
        assert_eq!(next_scale(3.0, 1.0, budget), 1.5);
        assert_eq!(next_scale(1.0, 1.0, budget), 1.0);
        // A frame far over the budget: at most twice the divisor a frame, never past 10.
        assert_eq!(next_scale(2.0, 10_000.0, budget), 4.0);
        assert_eq!(next_scale(8.0, 10_000.0, budget), MAX_SCALE);
        // No measure (a zero or a NaN time) keeps the scale.
        assert_eq!(next_scale(3.0, 0.0, budget), 3.0);
        assert_eq!(next_scale(3.0, f64::NAN, budget), 3.0);
    }

    #[test]
    fn a_reduced_frame_keeps_at_least_a_pixel_and_never_grows() {
        let key = Key {
            camera: Camera::default(),
            size: [7, 1],
            generation: 0,
            background: [0.0; 4],
            format: TargetFormat::Rgba8,
        };
        let f = key.frame(MAX_SCALE);
        assert_eq!([f.width, f.height], [1, 1]);
        let f = key.frame(1.0);
        assert_eq!([f.width, f.height], [7, 1]);
        let f = key.frame(2.0);
        // 3.5 rounds to 4.
        assert_eq!([f.width, f.height], [4, 1]);
    }
}
