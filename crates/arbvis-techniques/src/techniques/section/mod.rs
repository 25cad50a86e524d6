//! `[technique.section]` / `[layer.section]`: an inline, crossline or time (depth) section
//! of a survey, a plane through it coloured by a table; the interpreter's view beside the
//! volume, its horizons and wells (issue 57).
//!
//! # How it works
//! The volume is loaded as 3D opacity loads it (SEG-Y, NIfTI, raw, the synthetic cube, a
//! survey from memory) and the attribute derived; the section's position is read in the
//! survey's own numbers (inline and crossline numbers from the trace headers, time in ms),
//! a fractional sample position blending the two samples either side. The plane is drawn
//! where that position lies in the survey's box, in the same world frame as a 3D-opacity
//! layer of the same volume (each sample at its voxel's centre), so the two line up.
//!
//! **Faithful**: the section's values quantized to 8 bits over the range (`quantize`, as
//! 3D opacity quantizes), filtered by the texture unit, then the table's nearest entry read
//! by a dependent fetch (`programs/section/faithful.*`). **Precise**: the values as floats,
//! interpolated bilinearly in the program from the four nearest samples, and the table
//! interpolated between its entries (`precise.*`); [`reference`] is its f64 twin. A sample
//! without data (NaN) leaves every pixel whose interpolation touches it empty. The section
//! is opaque (the table's colours; its alpha is not used) or translucent by `opacity`;
//! moving it (`inline = 300`) uploads the new plane's samples, not a new renderer.

pub mod prepare;
pub mod reference;
pub mod renderer;

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::error::RenderResult;
use crate::programs::ProgramPair;
use crate::techniques::world::World;
use crate::techniques::{ReferenceView, Renderer, Settings, Technique};
use arbvis_core::colortable::TableSpec;
use arbvis_core::vocab::{Fidelity, FieldError};
use arbvis_data::volume::attributes::Attribute;
use arbvis_data::volume::quantize::Quantization;
use arbvis_data::volume::VolumeSource;
use arbvis_gl::{Gpu, ProgramChoice, ProgramKind};

/// `[technique.section]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SectionScene {
    /// The survey (as 3D opacity's `volume`; a store's planes are read as they are needed).
    pub volume: VolumeSource,
    /// The attribute shown (amplitude = the samples themselves).
    #[serde(default)]
    pub attribute: Attribute,
    /// The value range the table spans (as 3D opacity's `quantize`, and by default as 3D
    /// opacity takes a survey's: its 1st to 99th percentile, so that a section and a
    /// 3D-opacity layer of one survey agree; other volumes their min..max).
    #[serde(default)]
    pub quantize: Quantization,
    /// The colour table (by default `seismic`, red-white-blue).
    #[serde(default = "default_table")]
    pub table: TableSpec,
    /// An inline section at this inline number.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inline: Option<f64>,
    /// A crossline section at this crossline number.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crossline: Option<f64>,
    /// A time slice at this time (ms), between samples as well.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time: Option<f64>,
    /// A depth slice at this depth (a survey in depth; its vertical axis as `time`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth: Option<f64>,
    /// In (0, 1]: below 1 the section is translucent.
    #[serde(default = "one")]
    pub opacity: f64,
}

fn default_table() -> TableSpec {
    TableSpec::builtin("seismic")
}

fn one() -> f64 {
    1.0
}

/// Where a section lies: the volume axis it cuts (0 time/depth, 1 crossline, 2 inline)
/// and the number on that axis, with the key it was given by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cut {
    /// The voxel axis across the plane.
    pub axis: usize,
    /// The survey's number there (inline, crossline, ms or m).
    pub number: f64,
    /// `inline`, `crossline`, `time` or `depth`.
    pub key: &'static str,
}

impl SectionScene {
    /// A section of `volume` at inline `inline`, every other value at its default.
    pub fn inline(volume: VolumeSource, inline: f64) -> SectionScene {
        SectionScene {
            volume,
            attribute: Attribute::default(),
            quantize: Quantization::default(),
            table: default_table(),
            inline: Some(inline),
            crossline: None,
            time: None,
            depth: None,
            opacity: 1.0,
        }
    }

    /// The cuts the parameters name (exactly one in a valid scene).
    pub fn cuts(&self) -> Vec<Cut> {
        [
            (self.time, 0, "time"),
            (self.depth, 0, "depth"),
            (self.crossline, 1, "crossline"),
            (self.inline, 2, "inline"),
        ]
        .into_iter()
        .filter_map(|(n, axis, key)| n.map(|number| Cut { axis, number, key }))
        .collect()
    }

    /// The one cut of a valid scene.
    pub fn cut(&self) -> Result<Cut, FieldError> {
        match self.cuts()[..] {
            [c] => Ok(c),
            _ => Err(FieldError::new(
                "inline",
                "a section is at one of inline = N, crossline = N, time = MS or depth = M",
            )),
        }
    }
}

impl Technique for SectionScene {
    const NAME: &'static str = "section";
    const DEMOS: &'static [(&'static str, &'static str)] =
        &[crate::techniques::demo!("section-inline")];

    fn validate(&self, _: Fidelity, _: ProgramChoice) -> Result<(), FieldError> {
        let cut = self.cut()?;
        if !cut.number.is_finite() {
            return Err(FieldError::new(
                cut.key,
                format!("{}: a number", cut.number),
            ));
        }
        if !(self.opacity > 0.0 && self.opacity <= 1.0) {
            return Err(FieldError::new(
                "opacity",
                format!("{}: above 0 and at most 1", self.opacity),
            ));
        }
        self.table.validate().map_err(|e| e.within("table"))
    }

    fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut PathBuf)) {
        let kind = self.volume.kind();
        if let Some(p) = self.volume.path_mut() {
            f(&format!("volume.{kind}"), p);
        }
        if let Some(p) = self.table.file.as_mut() {
            f("table.file", p);
        }
    }

    fn program_pairs() -> Vec<ProgramPair> {
        renderer::program_pairs()
    }

    fn draws_opaque(&self) -> bool {
        self.opacity >= 1.0
    }

    /// Another cut, table, range or opacity of the same survey's attribute.
    fn keeps_place(&self, new: &Self) -> bool {
        self.volume == new.volume && self.attribute == new.attribute
    }

    type Prepared = prepare::Prepared;

    fn prepare(
        &self,
        settings: &Settings<'_>,
        limits: &arbvis_data::volume::Limits,
    ) -> RenderResult<prepare::Prepared> {
        Technique::validate(self, settings.fidelity, settings.programs)?;
        prepare::prepare(self, settings.base, limits)
    }

    fn renderer(
        &self,
        gpu: &Gpu,
        settings: &Settings<'_>,
        kind: ProgramKind,
        prepared: prepare::Prepared,
    ) -> RenderResult<Box<dyn Renderer>> {
        Ok(Box::new(
            renderer::SectionRenderer::new(gpu, kind, settings.fidelity, self, prepared)?
                .with_base(settings.base),
        ))
    }

    /// The plane's value at each pixel centre's hit, interpolated and coloured as the
    /// precise programs do, in f64.
    fn reference(
        &self,
        prepared: &prepare::Prepared,
        view: &ReferenceView<'_>,
    ) -> Option<arbvis_core::image::Image> {
        Some(reference::reference(
            prepared,
            self.opacity,
            &view.camera,
            view.size,
            view.background,
        ))
    }

    fn world(&self, prepared: &prepare::Prepared) -> Option<World> {
        Some(prepared.world)
    }

    /// A survey's section, as 3D opacity defaults a survey: seen from its three-quarter
    /// view, its range the 1st to 99th percentile (so a section and a 3D-opacity layer of
    /// one survey show one value in one colour).
    fn unwritten_defaults(
        &mut self,
        written: &dyn Fn(&str) -> bool,
        camera: &mut arbvis_core::camera::Camera,
        _: &mut Fidelity,
    ) {
        if self.volume.data_kind() != arbvis_data::sniff::DataKind::Survey {
            return;
        }
        if !written("camera") {
            *camera = crate::techniques::opacity3d::survey_camera();
        }
        // A store's percentiles are not computed: its min-max.
        let store = matches!(self.volume, VolumeSource::Store(_));
        if !store && !written("technique.section.quantize") {
            self.quantize = Quantization::Percentile([1.0, 99.0]);
        }
    }

    /// A survey seen as 3D opacity sees it.
    fn default_camera(&self) -> Option<arbvis_core::camera::Camera> {
        (self.volume.data_kind() == arbvis_data::sniff::DataKind::Survey)
            .then(crate::techniques::opacity3d::survey_camera)
    }
}
