//! A scene of several layers (`[[layer]]`) drawn in one picture, in one world frame.
//!
//! Each layer is prepared as its technique prepares it, in its own object frame; its
//! technique tells where that frame lies in the world ([`World`]: the data's own
//! coordinates, z up; a layer's `scale` and `offset` move it by hand). The scene's frame
//! is the union of every layer's world box, hidden layers included (hiding a layer never
//! moves the camera), centred and scaled so that its longest side spans [-1, 1]; each
//! layer is drawn through the camera with its [`Placement`] in that frame. Positions are
//! subtracted in f64 before they are scaled, so UTM coordinates keep their millimetres.
//!
//! Compositing, as a 2003 program could: the opaque layers first (opaque surfaces,
//! isosurfaces) with a depth test and depth writes, then the translucent layers in the
//! scene's order, each tested against that depth without writing it
//! (`Gpu::set_occluded`): a translucent volume, cell volume or splat is hidden behind an
//! opaque surface and drawn over it in front. Where an opaque layer is in view, the other
//! layers draw as geometry its depth can hide (`Technique::occludable`: splats as points,
//! not tiles; 3D opacity on precise slices, not the ray caster; cell volumes by projected
//! cells, not the walk or the grid); what still passes over the whole frame (the splats'
//! OIT composite and eye-dome lighting) is not occluded (docs/scenes.md, "Layers").

use arbvis_core::camera::{Camera, Placement};
use glam::{DQuat, DVec3};

use crate::catalog::{LayerInfo, Settings, TechniqueScene};
use crate::error::{RenderError, RenderResult};
use crate::techniques::world::World;
use crate::techniques::{Frame, Params, Renderer, Streaming};
use arbvis_data::volume::Limits;
use arbvis_gl::{Gpu, ProgramKind, Surface};

/// A layered scene's camera where its text writes none: a three-quarter view from the
/// south, 30 degrees above the horizon, the world's z up the screen, the whole frame in
/// view at any rotation.
pub fn default_camera() -> Camera {
    let tilt = DQuat::from_rotation_x(-60f64.to_radians());
    let turn = DQuat::from_rotation_z(-30f64.to_radians());
    Camera {
        rotation: (tilt * turn).normalize().to_array(),
        zoom: 0.9 / 3f64.sqrt(),
        ..Camera::default()
    }
}

/// Each layer's world, moved by its hand placement (`world = scale * data + offset`).
pub fn placed_world(world: World, info: &LayerInfo) -> World {
    World {
        units: world.units * info.scale,
        centre: world.centre * info.scale + DVec3::from_array(info.offset),
        ..world
    }
}

/// The placement of each world in the frame of their union (longest side [-1, 1]).
pub fn placements(worlds: &[World]) -> Vec<Placement> {
    let (lo, hi) = worlds.iter().map(World::bounds).fold(
        (DVec3::INFINITY, DVec3::NEG_INFINITY),
        |(lo, hi), [a, b]| (lo.min(a), hi.max(b)),
    );
    let centre = (lo + hi) / 2.0;
    let longest = (hi - lo).max_element();
    let s = if longest > 0.0 && longest.is_finite() {
        2.0 / longest
    } else {
        1.0
    };
    worlds
        .iter()
        .map(|w| Placement {
            scale: w.units * s,
            rotation: w.rotation,
            offset: (w.centre - centre) * s,
        })
        .collect()
}

/// Most layers a scene holds (each is prepared, placed and drawn: bounded work).
pub const MAX_LAYERS: usize = 4096;

/// One layer as drawn.
struct Drawn {
    placement: Placement,
    /// Its renderer in [`LayeredRenderer::renderers`] (layers with equal parameters share
    /// one: their data are read and uploaded once); None for a hidden layer.
    renderer: Option<usize>,
    /// Drawn in the first pass, with depth.
    opaque: bool,
    /// The layer's name (its legends' titles).
    name: String,
}

/// The renderer of a layered scene: its layers' renderers, each placed in the frame.
pub struct LayeredRenderer {
    layers: Vec<Drawn>,
    renderers: Vec<Box<dyn Renderer>>,
}

/// `error` named as layer `index`'s.
fn in_layer(index: usize, info: &LayerInfo, error: RenderError) -> RenderError {
    RenderError::Layer {
        index,
        name: match info.name.as_str() {
            "" => "unnamed".into(),
            n => n.into(),
        },
        source: Box::new(error),
    }
}

/// The renderer of a scene's `layers`: its one technique's (a plain one-layer scene), or
/// a [`LayeredRenderer`].
pub fn build_any(
    gpu: &Gpu,
    layers: &[(&LayerInfo, &TechniqueScene)],
    settings: &Settings<'_>,
    kind: ProgramKind,
) -> RenderResult<Box<dyn Renderer>> {
    match layers {
        [(info, technique)] if **info == LayerInfo::default() => {
            crate::catalog::build(gpu, technique, settings, kind)
        }
        _ => Ok(Box::new(build(gpu, layers, settings, kind)?)),
    }
}

/// Prepare every distinct layer once (layers of equal parameters share their data), place
/// them in one frame, build the renderers the visible ones need.
pub fn build(
    gpu: &Gpu,
    layers: &[(&LayerInfo, &TechniqueScene)],
    settings: &Settings<'_>,
    kind: ProgramKind,
) -> RenderResult<LayeredRenderer> {
    let limits = Limits::for_max_side(gpu.caps().max_3d_texture_size);
    // With an opaque layer in view, the others draw as geometry its depth can hide.
    let occluding = layers.iter().any(|(i, t)| i.visible && t.draws_opaque());
    let owned: Vec<(&LayerInfo, TechniqueScene)> = layers
        .iter()
        .map(|(info, t)| match occluding && !t.draws_opaque() {
            true => (*info, t.occludable()),
            false => (*info, (*t).clone()),
        })
        .collect();
    let layers: Vec<(&LayerInfo, &TechniqueScene)> = owned.iter().map(|(i, t)| (*i, t)).collect();
    let layers = layers.as_slice();
    // Each layer's distinct technique: the first layer with equal parameters.
    let first: Vec<usize> = (0..layers.len())
        .map(|i| (0..i).find(|&j| layers[j].1 == layers[i].1).unwrap_or(i))
        .collect();
    let mut prepared: Vec<Option<crate::catalog::PreparedData>> = Vec::new();
    // Each layer's world as its data give it, before its hand placement.
    let mut own: Vec<World> = Vec::with_capacity(layers.len());
    for (index, (info, technique)) in layers.iter().enumerate() {
        if first[index] == index {
            let data = crate::catalog::prepare(technique, settings, &limits)
                .map_err(|e| in_layer(index, info, e))?;
            let world = crate::catalog::world(technique, &data).ok_or_else(|| {
                let why = RenderError::Unplaced(format!(
                    "a {} layer has no place in a world frame yet (a layered scene takes surfaces, lines, sections, clouds, meshes, volumes and whole survey stores, not a window of a store or the quad)",
                    technique.name()
                ));
                in_layer(index, info, why)
            })?;
            own.push(world);
            prepared.push(Some(data));
        } else {
            own.push(own[first[index]]);
            prepared.push(None);
        }
    }
    let worlds: Vec<World> = own
        .into_iter()
        .zip(layers)
        .map(|(world, (info, _))| placed_world(world, info))
        .collect();
    let placements = placements(&worlds);
    colour_across(layers, &first, &worlds, &mut prepared)?;
    // A renderer for each distinct technique some visible layer draws.
    let wanted = |i: usize| (0..layers.len()).any(|l| first[l] == i && layers[l].0.visible);
    let mut renderers = Vec::new();
    let mut slot = vec![None; layers.len()];
    for (index, data) in prepared.into_iter().enumerate() {
        let (info, technique) = layers[index];
        if let Some(data) = data.filter(|_| wanted(index)) {
            let renderer = crate::catalog::renderer(technique, gpu, settings, kind, data)
                .map_err(|e| in_layer(index, info, e))?;
            slot[index] = Some(renderers.len());
            renderers.push(renderer);
        }
    }
    let layers = layers
        .iter()
        .enumerate()
        .map(|(index, (info, _))| {
            let renderer = slot[first[index]].filter(|_| info.visible);
            Drawn {
                placement: placements[index],
                opaque: renderer.is_some_and(|r| renderers[r].opaque()),
                name: info.name.clone(),
                renderer,
            }
        })
        .collect();
    Ok(LayeredRenderer { layers, renderers })
}

/// The layers of `new` whose parameters differ from `old`'s and that can take them in
/// place (through [`Renderer::update_layer`]), each as its renderer was built to take it;
/// None where the scene must be built again: a layer added, removed, moved, shown, hidden
/// or placed, one whose data or place change ([`TechniqueScene::keeps_place`]), one turned
/// opaque or translucent, or one that gives or takes colours.
pub fn changes_in_place(
    old: &[(&LayerInfo, &TechniqueScene)],
    new: &[(&LayerInfo, &TechniqueScene)],
) -> Option<Vec<(usize, TechniqueScene)>> {
    if old.len() != new.len() || old.iter().zip(new).any(|(a, b)| a.0 != b.0) {
        return None;
    }
    let occluding = |layers: &[(&LayerInfo, &TechniqueScene)]| {
        layers.iter().any(|(i, t)| i.visible && t.draws_opaque())
    };
    let occluding = match (occluding(old), occluding(new)) {
        (a, b) if a == b => b,
        _ => return None,
    };
    let mut changes = Vec::new();
    for (index, ((info, was), (_, is))) in old.iter().zip(new).enumerate() {
        if was == is {
            continue;
        }
        let gives = new
            .iter()
            .any(|(_, t)| crate::catalog::colour_source(t) == Some(info.name.as_str()));
        let takes = crate::catalog::colour_source(was).is_some()
            || crate::catalog::colour_source(is).is_some();
        if gives || takes || !was.keeps_place(is) || was.draws_opaque() != is.draws_opaque() {
            return None;
        }
        changes.push((
            index,
            match occluding && !is.draws_opaque() {
                true => is.occludable(),
                false => (*is).clone(),
            },
        ));
    }
    Some(changes)
}

/// Layers coloured by another (`colour_from`): each of their points takes the colour the
/// named layer shows where it lies in the world.
fn colour_across(
    layers: &[(&LayerInfo, &TechniqueScene)],
    first: &[usize],
    worlds: &[World],
    prepared: &mut [Option<crate::catalog::PreparedData>],
) -> RenderResult<()> {
    for (index, (info, technique)) in layers.iter().enumerate() {
        let Some(source) = crate::catalog::colour_source(technique) else {
            continue;
        };
        if first[index] != index {
            continue;
        }
        let named = layers.iter().position(|(i, _)| i.name == source);
        let from = named.filter(|&s| s != index).ok_or_else(|| {
            let why = RenderError::Unplaced(format!(
                "colour_from names layer {source:?}, which is not another layer of the scene"
            ));
            in_layer(index, info, why)
        })?;
        let Some(Some(data)) = prepared.get(index) else {
            continue;
        };
        let points: Vec<DVec3> = crate::catalog::coloured_points(technique, data)
            .into_iter()
            .map(|p| worlds[from].to_object(worlds[index].to_world(p)))
            .collect();
        let Some(Some(source_data)) = prepared.get(first[from]) else {
            continue;
        };
        let colours =
            crate::catalog::colours_at(layers[from].1, source_data, &points).ok_or_else(|| {
                let why = RenderError::Unplaced(format!(
                    "layer {source:?} ({}) has no colours to give",
                    layers[from].1.name()
                ));
                in_layer(index, info, why)
            })?;
        if let Some(Some(data)) = prepared.get_mut(index) {
            crate::catalog::take_colours(technique, data, &colours);
        }
    }
    Ok(())
}

impl LayeredRenderer {
    /// The visible layers in drawing order (opaque first, then translucent, each in the
    /// scene's order): placement, opacity and renderer index.
    fn in_order(&self) -> Vec<(Placement, bool, usize)> {
        let visible = |opaque: bool| {
            self.layers
                .iter()
                .filter(move |d| d.opaque == opaque)
                .filter_map(|d| Some((d.placement, d.opaque, d.renderer?)))
        };
        visible(true).chain(visible(false)).collect()
    }

    /// The distinct renderers that draw.
    fn drawn(&self) -> impl Iterator<Item = &Box<dyn Renderer>> {
        self.renderers.iter()
    }
}

/// `frame` with its camera placing a layer.
fn placed(frame: &Frame, placement: Placement) -> Frame {
    let mut frame = *frame;
    frame.camera.placement = placement;
    frame
}

impl Renderer for LayeredRenderer {
    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        let mut result = Ok(());
        for (placement, opaque, r) in self.in_order() {
            gpu.set_occluded(!opaque);
            result = self.renderers[r].draw(gpu, surface, &placed(frame, placement));
            if result.is_err() {
                break;
            }
        }
        gpu.set_occluded(false);
        result
    }

    /// The first layer's parameters (what the session's one-technique editors change);
    /// a change to any other layer rebuilds the scene's renderer.
    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()> {
        match self.layers.first().and_then(|d| d.renderer) {
            Some(r) => self.renderers[r].update(gpu, params),
            None => Ok(()),
        }
    }

    /// Layer `index`'s renderer takes `params`, unless another layer draws with it too; a
    /// hidden layer draws nothing to change.
    fn update_layer(&mut self, gpu: &Gpu, index: usize, params: Params<'_>) -> RenderResult<bool> {
        let Some(drawn) = self.layers.get(index) else {
            return Ok(false);
        };
        let Some(r) = drawn.renderer else {
            return Ok(true);
        };
        if self.layers.iter().filter(|d| d.renderer == Some(r)).count() > 1 {
            return Ok(false);
        }
        let name = drawn.name.clone();
        self.renderers[r]
            .update(gpu, params)
            .map_err(|e| RenderError::Layer {
                index,
                name: match name.as_str() {
                    "" => "unnamed".into(),
                    n => n.into(),
                },
                source: Box::new(e),
            })?;
        Ok(true)
    }

    fn program_kind(&self) -> ProgramKind {
        self.drawn()
            .next()
            .map_or(ProgramKind::Glsl, |r| r.program_kind())
    }

    /// Every visible layer's legends, each titled with its layer's name; the axes of the
    /// first visible layer that has them (a survey's inline, crossline and time), placed
    /// as that layer is.
    fn annotations(&self) -> crate::techniques::annotations::Annotations {
        use crate::techniques::annotations::{Annotations, Legend};
        let mut legends = Vec::new();
        let mut axes = None;
        for d in &self.layers {
            let Some(r) = d.renderer else {
                continue;
            };
            let own = self.renderers[r].annotations();
            if axes.is_none() {
                axes = own.axes.map(|mut b| {
                    b.placement = d.placement;
                    b
                });
            }
            for mut legend in own.legends {
                let (Legend::Bar { title, .. } | Legend::Keys { title, .. }) = &mut legend;
                if !d.name.is_empty() {
                    *title = format!("{}: {title}", d.name);
                }
                legends.push(legend);
            }
        }
        Annotations { legends, axes }
    }

    fn needs_depth(&self) -> bool {
        self.drawn().any(|r| r.needs_depth())
    }

    /// Each visible layer's line, named.
    fn status(&self) -> Option<String> {
        let lines: Vec<String> = self
            .layers
            .iter()
            .filter_map(|d| {
                let line = self.renderers[d.renderer?].status()?;
                Some(match d.name.as_str() {
                    "" => line,
                    name => format!("{name}: {line}"),
                })
            })
            .collect();
        (!lines.is_empty()).then(|| lines.join("; "))
    }

    fn streaming(&self) -> Option<&dyn Streaming> {
        Some(self)
    }

    fn streaming_mut(&mut self) -> Option<&mut dyn Streaming> {
        Some(self)
    }
}

impl Streaming for LayeredRenderer {
    fn set_streaming(&mut self, streaming: bool) {
        for r in &mut self.renderers {
            r.set_streaming(streaming);
        }
    }

    fn pending(&self) -> bool {
        self.drawn().any(|r| r.pending())
    }

    fn settle(&mut self, gpu: &Gpu, camera: &Camera, size: [u32; 2]) -> RenderResult<bool> {
        let mut arrived = false;
        // A shared renderer settles for the first layer that draws it.
        for (placement, _, r) in self.in_order() {
            let camera = Camera {
                placement,
                ..*camera
            };
            arrived |= self.renderers[r].settle(gpu, &camera, size)?;
        }
        Ok(arrived)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn world_at(centre: DVec3, units: f64) -> World {
        World {
            half: DVec3::new(1.0, 0.5, 0.25),
            units,
            rotation: DQuat::IDENTITY,
            centre,
        }
    }

    /// Layers in UTM coordinates a millimetre apart stay a millimetre apart in the
    /// frame: positions are subtracted in f64 before they are scaled.
    #[test]
    fn utm_layers_keep_their_millimetres() {
        let utm = DVec3::new(635_123.456, 6_123_456.789, -1234.5);
        for shift in [1e-3, 2.5e-3, -7e-3] {
            let worlds = [
                world_at(utm, 600.0),
                world_at(utm + DVec3::new(shift, 0.0, -shift), 600.0),
            ];
            let p = placements(&worlds);
            // The frame's longest side is 1200 m: 2 / 1200 scene units per metre.
            let s = 2.0 / (1200.0 + shift.abs());
            let apart = p[1].offset - p[0].offset;
            // f64 rounding of 6e6 is 1e-9 m: far below the millimetre.
            assert!((apart.x - shift * s).abs() < 1e-11 * s * 1e3, "{apart}");
            assert!((apart.z + shift * s).abs() < 1e-11 * s * 1e3, "{apart}");
        }
    }

    /// One layer alone sits at the frame's centre at the scale its technique framed it
    /// (its longest side [-1, 1]): the identity placement, whatever its coordinates.
    #[test]
    fn one_layer_is_placed_as_it_frames_itself() {
        for (centre, units) in [
            (DVec3::new(635_000.0, 848_000.0, -400.0), 71.5),
            (DVec3::new(-3.0, 0.25, 9.0), 0.013),
        ] {
            let p = placements(&[world_at(centre, units)])[0];
            assert!((p.scale - 1.0).abs() < 1e-12);
            assert!(p.offset.length() < 1e-9, "{:?}", p.offset);
        }
    }

    /// A hand placement scales the data's coordinates and then moves them.
    #[test]
    fn scale_then_offset() {
        let w = world_at(DVec3::new(10.0, 20.0, 30.0), 5.0);
        let info = LayerInfo {
            scale: 2.0,
            offset: [1.0, -1.0, 0.5],
            ..LayerInfo::default()
        };
        let placed = placed_world(w, &info);
        assert_eq!(placed.units, 10.0);
        assert_eq!(placed.centre, DVec3::new(21.0, 39.0, 60.5));
        // A data point at object (1, 0, 0) lies at 2 * (15, 20, 30) + offset.
        assert_eq!(placed.to_world(DVec3::X), DVec3::new(31.0, 39.0, 60.5));
    }
}
