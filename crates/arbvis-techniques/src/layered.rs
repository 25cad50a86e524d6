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
//! opaque surface and drawn over it in front. Passes that cover the whole frame (precise
//! splats' tiles and OIT composite, precise cell volumes' walk) are not occluded yet: in
//! a layered scene those techniques draw over opaque layers (docs/scenes.md, "Layers").

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

/// One layer as drawn.
struct Drawn {
    placement: Placement,
    /// None for a hidden layer (prepared for its place in the frame, never built).
    renderer: Option<Box<dyn Renderer>>,
    /// Drawn in the first pass, with depth.
    opaque: bool,
    /// The layer's name (its legends' titles).
    name: String,
}

/// The renderer of a layered scene: its layers' renderers, each placed in the frame.
pub struct LayeredRenderer {
    layers: Vec<Drawn>,
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

/// Prepare every layer, place them in one frame, build the visible ones' renderers.
pub fn build(
    gpu: &Gpu,
    layers: &[(&LayerInfo, &TechniqueScene)],
    settings: &Settings<'_>,
    kind: ProgramKind,
) -> RenderResult<LayeredRenderer> {
    let limits = Limits::for_max_side(gpu.caps().max_3d_texture_size);
    let mut prepared = Vec::with_capacity(layers.len());
    let mut worlds = Vec::with_capacity(layers.len());
    for (index, (info, technique)) in layers.iter().enumerate() {
        let data = crate::catalog::prepare(technique, settings, &limits)
            .map_err(|e| in_layer(index, info, e))?;
        let world = crate::catalog::world(technique, &data).ok_or_else(|| {
            let why = RenderError::Unplaced(format!(
                "a {} layer has no place in a world frame yet (a layered scene takes surfaces, clouds, meshes and volumes read whole, not survey stores or the quad)",
                technique.name()
            ));
            in_layer(index, info, why)
        })?;
        worlds.push(placed_world(world, info));
        prepared.push(data);
    }
    let placements = placements(&worlds);
    let mut drawn = Vec::with_capacity(layers.len());
    for (index, ((info, technique), data)) in layers.iter().zip(prepared).enumerate() {
        let renderer = match info.visible {
            true => Some(
                crate::catalog::renderer(technique, gpu, settings, kind, data)
                    .map_err(|e| in_layer(index, info, e))?,
            ),
            false => None,
        };
        drawn.push(Drawn {
            placement: placements[index],
            opaque: renderer.as_ref().is_some_and(|r| r.opaque()),
            name: info.name.clone(),
            renderer,
        });
    }
    Ok(LayeredRenderer { layers: drawn })
}

impl LayeredRenderer {
    /// The visible layers in drawing order: opaque first, then translucent, each in the
    /// scene's order.
    fn in_order(&mut self) -> impl Iterator<Item = (Placement, bool, &mut Box<dyn Renderer>)> {
        let (opaque, translucent): (Vec<_>, Vec<_>) =
            self.layers.iter_mut().partition(|d| d.opaque);
        opaque
            .into_iter()
            .chain(translucent)
            .filter_map(|d| Some((d.placement, d.opaque, d.renderer.as_mut()?)))
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
        for (placement, opaque, renderer) in self.in_order() {
            gpu.set_occluded(!opaque);
            result = renderer.draw(gpu, surface, &placed(frame, placement));
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
        match self.layers.first_mut().and_then(|d| d.renderer.as_mut()) {
            Some(r) => r.update(gpu, params),
            None => Ok(()),
        }
    }

    fn program_kind(&self) -> ProgramKind {
        self.layers
            .iter()
            .find_map(|d| d.renderer.as_ref())
            .map_or(ProgramKind::Glsl, |r| r.program_kind())
    }

    /// Every visible layer's legends, each titled with its layer's name; no axes (each
    /// layer's are its own frame's).
    fn annotations(&self) -> crate::techniques::annotations::Annotations {
        use crate::techniques::annotations::{Annotations, Legend};
        let mut legends = Vec::new();
        for d in &self.layers {
            let Some(r) = d.renderer.as_ref() else {
                continue;
            };
            for mut legend in r.annotations().legends {
                let (Legend::Bar { title, .. } | Legend::Keys { title, .. }) = &mut legend;
                if !d.name.is_empty() {
                    *title = format!("{}: {title}", d.name);
                }
                legends.push(legend);
            }
        }
        Annotations {
            legends,
            axes: None,
        }
    }

    fn needs_depth(&self) -> bool {
        self.layers
            .iter()
            .filter_map(|d| d.renderer.as_ref())
            .any(|r| r.needs_depth())
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
        for d in &mut self.layers {
            if let Some(r) = d.renderer.as_mut() {
                r.set_streaming(streaming);
            }
        }
    }

    fn pending(&self) -> bool {
        self.layers
            .iter()
            .filter_map(|d| d.renderer.as_ref())
            .any(|r| r.pending())
    }

    fn settle(&mut self, gpu: &Gpu, camera: &Camera, size: [u32; 2]) -> RenderResult<bool> {
        let mut arrived = false;
        for d in &mut self.layers {
            if let Some(r) = d.renderer.as_mut() {
                let camera = Camera {
                    placement: d.placement,
                    ..*camera
                };
                arrived |= r.settle(gpu, &camera, size)?;
            }
        }
        Ok(arrived)
    }
}
