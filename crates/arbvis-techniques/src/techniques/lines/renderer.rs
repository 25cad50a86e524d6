//! The lines' GL state: their tubes or ribbons drawn by a surface's renderer, shaped again
//! when the view changes where their shape follows it; new parameters read the lines
//! again (files of lines and logs are small).

use std::path::{Path, PathBuf};

use glam::DMat4;

use super::shape::PreparedLines;
use super::{prepare, LinesScene, Width};
use crate::error::RenderResult;
use crate::techniques::surface::renderer::SurfaceRenderer;
use crate::techniques::{Frame, Params, Renderer};
use arbvis_core::vocab::Fidelity;
use arbvis_gl::{Gpu, ProgramKind, Surface};

/// The lines as a surface's renderer draws them; new parameters read the lines again.
pub struct LinesRenderer {
    tubes: SurfaceRenderer,
    fidelity: Fidelity,
    params: LinesScene,
    base: PathBuf,
    /// The lines, to be shaped for each view where their shape follows it.
    prepared: PreparedLines,
    /// The view-projection and size the uploaded shape was made for.
    shaped_for: Option<(DMat4, [u32; 2])>,
}

impl LinesRenderer {
    /// The tubes `prepared` holds, drawn with programs of `kind`; `base` for new files.
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &LinesScene,
        base: &Path,
        prepared: PreparedLines,
    ) -> RenderResult<LinesRenderer> {
        // A shape for a first view; one that follows the view is made again at the draw.
        let first = prepared.shaped(params.shape(), &Default::default(), [64, 64]);
        Ok(LinesRenderer {
            tubes: SurfaceRenderer::new(gpu, kind, fidelity, &params.as_surface(), first)?,
            fidelity,
            params: params.clone(),
            base: base.to_path_buf(),
            prepared,
            shaped_for: None,
        })
    }
}

impl Renderer for LinesRenderer {
    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        if !self.params.shape().fixed() {
            let size = [frame.width, frame.height];
            let view = (frame.camera.view_projection(frame.aspect()), size);
            if self.shaped_for != Some(view) {
                let shaped = self
                    .prepared
                    .shaped(self.params.shape(), &frame.camera, size);
                self.tubes.replace(gpu, shaped)?;
                self.shaped_for = Some(view);
            }
        }
        self.tubes.draw(gpu, surface, frame)
    }

    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()> {
        let params = params.get::<LinesScene>()?;
        if *params != self.params {
            let prepared = prepare(params, &self.base)?;
            let first = prepared.shaped(params.shape(), &Default::default(), [64, 64]);
            let kind = self.tubes.program_kind();
            self.tubes =
                SurfaceRenderer::new(gpu, kind, self.fidelity, &params.as_surface(), first)?;
            self.params = params.clone();
            self.prepared = prepared;
            self.shaped_for = None;
        }
        Ok(())
    }

    fn program_kind(&self) -> ProgramKind {
        self.tubes.program_kind()
    }

    fn needs_depth(&self) -> bool {
        true
    }

    fn opaque(&self) -> bool {
        true
    }

    /// The table over the values' range, or the tubes' colour as a key.
    fn annotations(&self) -> crate::techniques::annotations::Annotations {
        use crate::techniques::annotations::{rgb8, Annotations, Legend};
        let legend = match self.prepared.legend.clone() {
            ([low, high], Some(colours)) => Legend::Bar {
                title: match &self.params.well {
                    Some(_) => "log".into(),
                    None => "value".into(),
                },
                colours,
                low,
                high,
            },
            (_, None) => {
                let [r, g, b] = self.params.colour;
                Legend::Keys {
                    title: "lines".into(),
                    keys: vec![(
                        rgb8([r, g, b, 1.0]),
                        match self.params.width() {
                            Width::Metres(w) => format!("{w} m across"),
                            Width::Pixels(w) => format!("{w} pixels across"),
                        },
                    )],
                }
            }
        };
        Annotations {
            legends: vec![legend],
            axes: None,
        }
    }
}
