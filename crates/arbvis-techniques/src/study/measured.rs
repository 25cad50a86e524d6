//! One setting measured by `arbvis bench`: its frame times and its error against the
//! reference, as the bench and its breakdown probes both report it.

use serde::Serialize;

use arbvis_core::vocab::TargetFormat;
use arbvis_gl::ProgramKind;

/// One setting measured.
#[derive(Debug, Clone, Serialize)]
pub struct Measured {
    /// The setting's name.
    pub name: String,
    /// Technique name.
    pub technique: String,
    /// `faithful` or `precise`.
    pub fidelity: String,
    /// `slicing` or `raycast` (3D opacity), else empty.
    pub path: String,
    /// Slice count (slicing).
    pub slices: Option<usize>,
    /// Steps per voxel (ray caster).
    pub steps_per_voxel: Option<f64>,
    /// `arb` or `glsl`.
    pub programs: String,
    /// Colour target.
    pub target: String,
    /// The first frame (program variants compiled, meshes built), ms.
    pub first_ms: f64,
    /// Every timed frame, ms, in the order taken.
    pub frames_ms: Vec<f64>,
    /// Median of `frames_ms`.
    pub median_ms: f64,
    /// Smallest of `frames_ms`.
    pub min_ms: f64,
    /// Largest of `frames_ms`.
    pub max_ms: f64,
    /// RMSE over RGB against the reference.
    pub rmse: Option<f64>,
    /// Largest RGB difference from the reference.
    pub max_abs: Option<f64>,
}

impl Measured {
    /// A setting named `name` whose first frame took `first` ms, nothing else known yet
    /// (frames, medians and errors are filled in as they are measured).
    pub(super) fn untimed(name: String, first: f64) -> Measured {
        Measured {
            name,
            technique: String::new(),
            fidelity: String::new(),
            path: String::new(),
            slices: None,
            steps_per_voxel: None,
            programs: String::new(),
            target: String::new(),
            first_ms: first,
            frames_ms: Vec::new(),
            median_ms: f64::NAN,
            min_ms: f64::NAN,
            max_ms: f64::NAN,
            rmse: None,
            max_abs: None,
        }
    }

    /// A probe of [`super::breakdown`] (GLSL, on `slices` slices).
    pub fn probe(name: String, target: TargetFormat, slices: usize, first: f64) -> Measured {
        Measured {
            technique: "opacity3d".into(),
            path: "probe".into(),
            slices: Some(slices),
            programs: ProgramKind::Glsl.name().into(),
            target: target.name().into(),
            ..Measured::untimed(name, first)
        }
    }
}
