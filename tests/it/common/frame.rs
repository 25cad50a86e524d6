//! The harness the picture tests draw through: one frame of a renderer, seen by a camera,
//! onto a cleared target of a named size and format, read back as an image (and its
//! depth where asked). A test names what differs (size, format, background) and nothing
//! else; comparing goes through [`super::assert_close`], [`super::assert_snapshot`] and
//! each technique's own scores, with their named tolerances.

use arbvis::camera::Camera;
use arbvis::gl::{Gpu, Surface, Target, TargetFormat};
use arbvis::image::Image;
use arbvis::scene::Fidelity;
use arbvis::techniques::{Frame, Renderer};

/// How a frame is taken: the target's size and format, whether it has a depth buffer,
/// and the colour it is cleared to.
#[derive(Debug, Clone, Copy)]
pub struct Shot {
    /// Width and height in pixels.
    pub size: [u32; 2],
    /// The target's texel format.
    pub format: TargetFormat,
    /// A depth buffer (opaque geometry with a depth test).
    pub depth: bool,
    /// The clear colour.
    pub background: [f32; 4],
}

impl Shot {
    /// A `size` target of `format`, no depth, cleared to transparent black.
    pub fn new(size: [u32; 2], format: TargetFormat) -> Shot {
        Shot {
            size,
            format,
            depth: false,
            background: [0.0; 4],
        }
    }

    /// A `size` target in the format `fidelity` draws into: RGBA8 faithful (the era's
    /// framebuffer), RGBA32F precise.
    pub fn for_fidelity(size: [u32; 2], fidelity: Fidelity) -> Shot {
        let format = match fidelity {
            Fidelity::Faithful => TargetFormat::Rgba8,
            Fidelity::Precise => TargetFormat::Rgba32f,
        };
        Shot::new(size, format)
    }

    /// The same, with a depth buffer.
    pub fn with_depth(self) -> Shot {
        Shot {
            depth: true,
            ..self
        }
    }

    /// The same, cleared to `background`.
    pub fn on(self, background: [f32; 4]) -> Shot {
        Shot { background, ..self }
    }

    /// A fresh target of this shot.
    pub fn target(&self, gpu: &Gpu) -> Target {
        let [w, h] = self.size;
        match self.depth {
            true => Target::with_depth(gpu, w, h, self.format),
            false => Target::new(gpu, w, h, self.format),
        }
        .unwrap()
    }

    /// The frame `camera` sees at this shot's size.
    pub fn frame(&self, camera: &Camera) -> Frame {
        Frame {
            camera: *camera,
            width: self.size[0],
            height: self.size[1],
        }
    }

    /// `r`'s picture of `camera` on a fresh target.
    pub fn draw(&self, gpu: &Gpu, r: &mut dyn Renderer, camera: &Camera) -> Image {
        self.draw_on(gpu, r, &self.target(gpu), camera)
    }

    /// `r`'s picture of `camera` on `target` (of this shot), cleared first.
    pub fn draw_on(
        &self,
        gpu: &Gpu,
        r: &mut dyn Renderer,
        target: &Target,
        camera: &Camera,
    ) -> Image {
        target.clear(gpu, self.background).unwrap();
        r.draw(gpu, Surface::Target(target), &self.frame(camera))
            .unwrap();
        target.read(gpu).unwrap()
    }

    /// [`Shot::draw`] with the depth buffer read back too (a shot with depth).
    pub fn draw_with_depth(
        &self,
        gpu: &Gpu,
        r: &mut dyn Renderer,
        camera: &Camera,
    ) -> (Image, Vec<f32>) {
        let target = self.target(gpu);
        let image = self.draw_on(gpu, r, &target, camera);
        let depth = target.read_depth(gpu).unwrap().expect("a shot with depth");
        (image, depth)
    }
}
