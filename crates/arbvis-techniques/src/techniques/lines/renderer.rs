//! The lines' GL state: their tubes drawn by a surface's renderer; new parameters read the
//! lines again (files of lines and logs are small).

use std::path::{Path, PathBuf};

use super::{prepare, LinesScene};
use crate::error::RenderResult;
use crate::techniques::surface::prepare::Prepared;
use crate::techniques::surface::renderer::SurfaceRenderer;
use crate::techniques::{Frame, Params, Renderer};
use arbvis_core::vocab::Fidelity;
use arbvis_gl::{Gpu, ProgramKind, Surface};

/// The tubes as a surface's renderer draws them; new parameters read the lines again.
pub struct LinesRenderer {
    tubes: SurfaceRenderer,
    fidelity: Fidelity,
    params: LinesScene,
    base: PathBuf,
}

impl LinesRenderer {
    /// The tubes `prepared` holds, drawn with programs of `kind`; `base` for new files.
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &LinesScene,
        base: &Path,
        prepared: Prepared,
    ) -> RenderResult<LinesRenderer> {
        Ok(LinesRenderer {
            tubes: SurfaceRenderer::new(gpu, kind, fidelity, &params.as_surface(), prepared)?,
            fidelity,
            params: params.clone(),
            base: base.to_path_buf(),
        })
    }
}

impl Renderer for LinesRenderer {
    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        self.tubes.draw(gpu, surface, frame)
    }

    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()> {
        let params = params.get::<LinesScene>()?;
        if *params != self.params {
            let prepared = prepare(params, &self.base)?;
            let kind = self.tubes.program_kind();
            self.tubes =
                SurfaceRenderer::new(gpu, kind, self.fidelity, &params.as_surface(), prepared)?;
            self.params = params.clone();
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
        let legend = match self.tubes.prepared().elevation.clone() {
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
                        format!("radius {} m", self.params.radius),
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
