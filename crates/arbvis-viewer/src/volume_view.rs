//! The 3D view's picture, kept in an offscreen target and redrawn only when what it shows
//! changes (camera, parameters, size, background); the window shows it by a blit each UI
//! frame, so the panels stay responsive while the volume waits.
//!
//! Decisions:
//! - While the user interacts (a drag, an edit in the last [`SETTLE`]) the volume is drawn
//!   at the *interactive quality*: a fraction of the slices into a target of a fraction of
//!   the view's pixels, scaled up by the blit. When the user is still, the full-quality
//!   picture is drawn in parts ([`Renderer::draw_part`], runs of slices back to front), as
//!   many per UI frame as fit in [`FRAME_BUDGET`]; the last picture stays on screen until
//!   the new one is complete. The parts leave exactly what one draw would, so the finished
//!   picture is the offscreen render of the scene (screenshots read it).
//! - The full picture has the scene's target format (RGBA8 faithful, RGBA32F precise) and
//!   is cleared to the scene's background, as `arbvis render` does.

use std::time::{Duration, Instant};

use crate::camera::Camera;
use crate::gl::{Gpu, Surface, Target};
use crate::scene::{Scene, TechniqueScene};
use crate::techniques::{Frame, Renderer};
use crate::vocab::TargetFormat;

/// How long after the last edit the view counts as still.
pub const SETTLE: Duration = Duration::from_millis(250);
/// Time given to full-quality parts in one UI frame.
pub const FRAME_BUDGET: Duration = Duration::from_millis(40);

/// How the volume is drawn while the user interacts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InteractiveQuality {
    /// As when still (every frame waits for the whole volume).
    Full,
    /// Half the slices, half the pixels along each side.
    #[default]
    Half,
    /// A quarter of the slices and of the pixels along each side.
    Quarter,
}

impl InteractiveQuality {
    /// Every quality and its name, for the panel and scripts.
    pub const ALL: [(InteractiveQuality, &'static str); 3] = [
        (InteractiveQuality::Full, "full"),
        (InteractiveQuality::Half, "half"),
        (InteractiveQuality::Quarter, "quarter"),
    ];

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            InteractiveQuality::Full => "full",
            InteractiveQuality::Half => "half",
            InteractiveQuality::Quarter => "quarter",
        }
    }

    fn divisor(self) -> u32 {
        match self {
            InteractiveQuality::Full => 1,
            InteractiveQuality::Half => 2,
            InteractiveQuality::Quarter => 4,
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
    /// Bumped whenever the renderer's parameters change.
    pub generation: u64,
    /// Clear colour.
    pub background: [f32; 4],
    /// Target precision.
    pub format: TargetFormat,
}

impl Key {
    /// The key of `scene` drawn at `size` after `generation` parameter changes.
    pub fn of(scene: &Scene, size: [u32; 2], generation: u64) -> Key {
        Key {
            camera: scene.camera,
            size,
            generation,
            background: scene.background,
            format: scene.target_format(),
        }
    }

    fn frame(&self, divisor: u32) -> Frame {
        Frame {
            camera: self.camera,
            width: (self.size[0] / divisor).max(1),
            height: (self.size[1] / divisor).max(1),
        }
    }
}

struct Picture {
    target: Target,
    key: Key,
    full: bool,
}

struct Building {
    picture: Picture,
    next: usize,
    parts: usize,
    spent: Duration,
}

/// What [`VolumeView::update`] left to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pending {
    /// The picture on screen is the full-quality one of the current key.
    Done,
    /// A full-quality picture is being drawn: draw another frame soon.
    Building,
    /// A reduced picture is shown: refine once the user is still.
    Refine,
}

/// The kept picture and the one being drawn.
#[derive(Default)]
pub struct VolumeView {
    shown: Option<Picture>,
    building: Option<Building>,
    /// Milliseconds the last full-quality picture took (all its parts).
    pub full_ms: f64,
    /// Milliseconds the last interactive picture took.
    pub interactive_ms: f64,
    /// Parts the last full-quality picture was drawn in.
    pub parts: usize,
}

fn fresh_target(
    gpu: &Gpu,
    old: Option<Picture>,
    w: u32,
    h: u32,
    format: TargetFormat,
    depth: bool,
) -> anyhow::Result<Target> {
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

impl VolumeView {
    /// Draw the full-quality picture again (a streaming renderer has more data for it).
    pub fn refine(&mut self) {
        if let Some(p) = &mut self.shown {
            p.full = false;
        }
    }

    /// Bring the picture up to date with `key`: at `quality` while `interacting`, else
    /// in full-quality parts within the frame budget (`sync` draws them all now).
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        gpu: &Gpu,
        renderer: &mut dyn Renderer,
        technique: &TechniqueScene,
        key: &Key,
        interacting: bool,
        quality: InteractiveQuality,
        sync: bool,
    ) -> anyhow::Result<Pending> {
        let shown_full = self.shown.as_ref().is_some_and(|p| p.full && p.key == *key);
        if shown_full {
            self.building = None;
            return Ok(Pending::Done);
        }
        // At full interactive quality every frame waits for the whole volume.
        let sync = sync || (interacting && quality == InteractiveQuality::Full);
        let shown_current = self.shown.as_ref().is_some_and(|p| p.key == *key);
        if (interacting || self.shown.is_none()) && quality != InteractiveQuality::Full && !sync {
            if !shown_current {
                self.draw_reduced(gpu, renderer, technique, key, quality)?;
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
        technique: &TechniqueScene,
        key: &Key,
        quality: InteractiveQuality,
    ) -> anyhow::Result<()> {
        let t0 = Instant::now();
        let d = quality.divisor();
        let frame = key.frame(d);
        let target = fresh_target(
            gpu,
            self.shown.take(),
            frame.width,
            frame.height,
            key.format,
            renderer.needs_depth(),
        )?;
        target.clear(gpu, key.background)?;
        renderer.update(gpu, technique.for_interaction(d).params())?;
        let drawn = renderer.draw(gpu, Surface::Target(&target), &frame);
        renderer.update(gpu, technique.params())?;
        drawn?;
        gpu.finish();
        self.interactive_ms = t0.elapsed().as_secs_f64() * 1e3;
        self.shown = Some(Picture {
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
    ) -> anyhow::Result<Pending> {
        let frame = key.frame(1);
        if self.building.as_ref().is_none_or(|b| b.picture.key != *key) {
            let old = self.building.take().map(|b| b.picture);
            let target = fresh_target(
                gpu,
                old,
                frame.width,
                frame.height,
                key.format,
                renderer.needs_depth(),
            )?;
            target.clear(gpu, key.background)?;
            // Parts of about a frame budget each, from the last full picture's time.
            let budget = FRAME_BUDGET.as_secs_f64() * 1e3;
            let parts = if sync {
                1
            } else {
                ((self.full_ms / budget).ceil() as usize).clamp(1, 64)
            };
            self.building = Some(Building {
                picture: Picture {
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
            if !sync && t0.elapsed() >= FRAME_BUDGET {
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
    pub fn full_picture(&self, key: &Key) -> Option<&Target> {
        self.shown
            .as_ref()
            .filter(|p| p.full && p.key == *key)
            .map(|p| &p.target)
    }

    /// Show the picture in the window's `viewport` (`[x, y, w, h]`, GL pixels).
    pub fn show(&self, gpu: &Gpu, viewport: [i32; 4]) -> anyhow::Result<()> {
        if let Some(p) = &self.shown {
            p.target.blit_to_window(gpu, viewport)?;
        }
        Ok(())
    }
}
