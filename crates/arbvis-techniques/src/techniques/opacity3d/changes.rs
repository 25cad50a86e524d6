//! What an edit of a 3D opacity scene asks of its renderer, read off one key per GL
//! resource: the key holds the parameters the resource is made from, and a resource is
//! made again exactly when its key differs. No GL; the renderer's `update` acts on it.

use super::{Combine, Interpolation, Opacity3dScene};
use crate::techniques::clip::ClipSpec;
use arbvis_core::colortable::TableSpec;
use arbvis_data::volume::attributes::Attribute;
use arbvis_data::volume::quantize::Quantization;
use arbvis_data::volume::VolumeSource;
use arbvis_gl::Filter;

/// What each attribute's data are read and quantized from.
type AttributeData = Option<(VolumeSource, Attribute, Quantization)>;

/// The parameters each resource is made from.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneKey {
    /// The prepared data (the volume read, derived and quantized; its texture):
    /// each attribute's source, attribute and quantization, the volume's filter and the
    /// interpolation.
    data: ([AttributeData; 3], Filter, Interpolation),
    /// The colour tables' textures: each attribute's table, their filter, and the
    /// combination (a product's neutral table).
    tables: ([Option<TableSpec>; 3], Filter, Combine),
    /// The clip's textures.
    clip: Option<ClipSpec>,
    /// The program's variant: the combination, the ray caster's skipping, jitter and
    /// pre-integration, the tables' filter and the interpolation.
    program: (Combine, Option<(bool, bool, bool)>, Filter, Interpolation),
}

impl SceneKey {
    /// The key of `scene`.
    pub fn of(scene: &Opacity3dScene) -> SceneKey {
        let attributes = scene.attributes();
        SceneKey {
            data: (
                attributes.map(|a| a.map(|a| (a.volume.clone(), a.attribute, a.quantize))),
                scene.volume_filter,
                scene.interpolation,
            ),
            tables: (
                attributes.map(|a| a.map(|a| a.table.clone())),
                scene.table_filter,
                scene.combine,
            ),
            clip: scene.clip.clone(),
            program: (
                scene.combine,
                scene
                    .raycast
                    .map(|r| (r.brick > 0, r.jitter, r.preintegrate)),
                scene.table_filter,
                scene.interpolation,
            ),
        }
    }
}

/// Which resources an edit from one scene to another makes again (the coefficients, the
/// slice count and the ray caster's step settings are sent every update; the bricks'
/// occupancy and the step table are remade every update).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Changes {
    /// The data are prepared again (and the renderer made anew).
    pub data: bool,
    /// The tables are rebuilt.
    pub tables: bool,
    /// The clip is built again.
    pub clip: bool,
    /// The program is made again.
    pub program: bool,
}

impl Changes {
    /// What changes from `old` to `new`.
    pub fn between(old: &Opacity3dScene, new: &Opacity3dScene) -> Changes {
        let (old, new) = (SceneKey::of(old), SceneKey::of(new));
        Changes {
            data: old.data != new.data,
            tables: old.tables != new.tables,
            clip: old.clip != new.clip,
            program: old.program != new.program,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use arbvis_core::colortable::TableSpec;

    fn scene() -> Opacity3dScene {
        let text = r#"
            [primary]
            volume = { synthetic = { size = [9, 7, 5] } }
            coefficients = [0.3, 0.2, 0.1, 0.7]
            table = { builtin = "seismic" }
            [secondary]
            volume = { synthetic = { size = [9, 7, 5] } }
            attribute = "envelope"
            table = { builtin = "viridis" }
        "#;
        toml::from_str(text).unwrap()
    }

    /// An edit's name, the edit, and what it remakes.
    type Case = (&'static str, fn(&mut Opacity3dScene), Changes);

    #[test]
    fn each_edit_remakes_what_is_made_from_it_and_nothing_else() {
        let base = scene();
        let same = Changes::default();
        let cases: [Case; 7] = [
            ("a coefficient", |s| s.primary.coefficients[2] = 0.9, same),
            ("the slice count", |s| s.slices += 17, same),
            (
                "a table",
                |s| s.primary.table = TableSpec::builtin("magma"),
                Changes {
                    tables: true,
                    ..same
                },
            ),
            (
                "the tables' filter",
                |s| s.table_filter = Filter::Nearest,
                Changes {
                    tables: true,
                    program: true,
                    ..same
                },
            ),
            (
                "the combination",
                |s| s.combine = Combine::Product,
                Changes {
                    tables: true,
                    program: true,
                    ..same
                },
            ),
            (
                "an attribute",
                |s| s.secondary.as_mut().unwrap().attribute = Attribute::Amplitude,
                Changes { data: true, ..same },
            ),
            (
                "the volume's filter",
                |s| s.volume_filter = Filter::Nearest,
                Changes { data: true, ..same },
            ),
        ];
        for (what, edit, expected) in cases {
            let mut edited = base.clone();
            edit(&mut edited);
            assert_eq!(Changes::between(&base, &edited), expected, "{what}");
        }
        assert_eq!(Changes::between(&base, &base), same);
    }
}
