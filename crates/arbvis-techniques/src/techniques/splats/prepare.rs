//! CPU preparation of the splats (no GL): per-point colour, property value, normal and
//! visibility, the vertex data the programs take, and CPU mirrors of the programs' colour
//! and alpha formulas (the seed's as written, and the corrected ones) for the reference.

use std::path::Path;

use glam::DVec3;

use super::normals::{estimate_cloud, DEFAULT_K};
use super::scene::{ColourMode, Kernel, Mode, SplatsScene};
use crate::error::RenderResult;
use arbvis_core::vocab::Fidelity;
use arbvis_core::vocab::FieldError;
use arbvis_data::points::section::{facies_colour, PALETTE};
use arbvis_data::points::{PointCloud, FACIES, FAULT, LAYER, UNDEFINED_FACIES};

/// Floats per vertex: position 3, colour 3, property value 1, normal 3, size scale 1 (a
/// COPC point's spacing over the deepest drawn level's; the precise programs multiply the
/// splat size by it, the seed's ignore it).
pub const VERTEX_COMPONENTS: [usize; 5] = [3, 3, 1, 3, 1];
/// Sum of [`VERTEX_COMPONENTS`].
pub const FLOATS_PER_VERTEX: usize = 11;

/// The gradient scale's two end colours. The seed shows its gradient (Figure 3) but not
/// the values of `colorA` and `colorB`; these are ours: deep blue to warm yellow.
pub const COLOR_A: [f64; 3] = [0.05, 0.10, 0.45];
/// See [`COLOR_A`].
pub const COLOR_B: [f64; 3] = [1.0, 0.85, 0.25];

/// Layer colours: the first 8 of [`arbvis_data::points::section::PALETTE`] (layer ids 0..7 in
/// the seed's sections; ids wrap around beyond).
pub const LAYERS_IN_PALETTE: i32 = 8;

/// A cloud ready to draw.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// Positions in object space ([-1, 1]³, the cloud's own rescaling).
    pub positions: Vec<[f32; 3]>,
    /// Base colour per point (before lighting, before the property gradient).
    pub colours: Vec<[f32; 3]>,
    /// The property per point (NaN where absent).
    pub values: Vec<f32>,
    /// The property's smallest and largest finite value.
    pub range: [f64; 2],
    /// Unit normals (zero without lighting).
    pub normals: Vec<[f32; 3]>,
    /// Drawn at all (hidden layers and undefined facies are not).
    pub visible: Vec<bool>,
    /// Normal estimation fallbacks (too few or coincident neighbours).
    pub normal_fallbacks: usize,
}

/// Load the scene's cloud (relative paths from `base`) and prepare it; returns the
/// cloud too (a renderer keeps it to re-prepare after edits without reloading).
pub fn prepare(scene: &SplatsScene, base: &Path) -> RenderResult<(PointCloud, Prepared)> {
    let (cloud, prepared, _) = prepare_for(scene, base, None)?;
    Ok((cloud, prepared))
}

/// What [`prepare_for`] makes: the cloud, its preparation and a COPC cut's account.
pub type PreparedCloud = (
    PointCloud,
    Prepared,
    Option<arbvis_data::points::copc_lod::Loaded>,
);

/// [`prepare`], a COPC cloud's nodes chosen for `view`; with what a COPC cut holds.
pub fn prepare_for(
    scene: &SplatsScene,
    base: &Path,
    view: Option<&arbvis_data::points::copc_lod::View>,
) -> RenderResult<PreparedCloud> {
    let (cloud, note) = scene.cloud.load_for(base, view)?;
    if let Some(warning) = missing_colour(scene, &cloud) {
        eprintln!("arbvis: warning: {warning}");
    }
    let normals = normals_for(&cloud, scene);
    let prepared = from_cloud(&cloud, scene, normals)?;
    Ok((cloud, prepared, note))
}

/// What a scene's `colour` needs and the cloud lacks (its points are then drawn grey):
/// the warning naming the key, or `None` when the cloud has it.
pub fn missing_colour(scene: &SplatsScene, cloud: &PointCloud) -> Option<String> {
    let (word, lacks) = match scene.colour {
        ColourMode::Rgb if cloud.rgb.is_none() => (
            "rgb",
            "no colours (RGB: LAS point formats 2, 3, 5, 7, 8 and 10 have them, 6 has not; PLY red, green, blue)",
        ),
        ColourMode::Intensity if cloud.ints("intensity").is_none() => ("intensity", "no intensity"),
        ColourMode::Classification if cloud.ints("classification").is_none() => {
            ("classification", "no classification")
        }
        ColourMode::Facies if cloud.ints(FACIES).is_none() => ("facies", "no facies column"),
        ColourMode::Layer if cloud.ints(LAYER).is_none() => ("layer", "no layer column"),
        _ => return None,
    };
    Some(format!(
        "technique.splats.colour = \"{word}\": the cloud has {lacks}, so its points are drawn grey; colour = \"elevation\" colours any cloud"
    ))
}

/// [`prepare_for`] in stages (a COPC cloud: [`arbvis_data::points::copc_load`]'s; any other
/// cloud in one): `each` gets each stage prepared and whether it is the whole cut, and
/// returns false to stop.
pub fn prepare_in_stages(
    scene: &SplatsScene,
    base: &Path,
    view: &arbvis_data::points::copc_lod::View,
    stages: arbvis_data::points::copc_load::Stages,
    mut each: impl FnMut(
        (
            PointCloud,
            Prepared,
            Option<arbvis_data::points::copc_lod::Loaded>,
        ),
        bool,
    ) -> bool,
) -> RenderResult<()> {
    let arbvis_data::points::PointSource::Copc(spec) = &scene.cloud else {
        each(prepare_for(scene, base, Some(view))?, true);
        return Ok(());
    };
    let mut failed = None;
    let mut warned = false;
    arbvis_data::points::copc_load::load_in_stages(
        spec,
        base,
        Some(view),
        stages,
        |cloud, loaded, whole| {
            if !std::mem::replace(&mut warned, true) {
                if let Some(warning) = missing_colour(scene, &cloud) {
                    eprintln!("arbvis: warning: {warning}");
                }
            }
            let normals = normals_for(&cloud, scene);
            match from_cloud(&cloud, scene, normals) {
                Ok(prepared) => each((cloud, prepared, Some(loaded)), whole),
                Err(e) => {
                    failed = Some(e);
                    false
                }
            }
        },
    )?;
    failed.map_or(Ok(()), Err)
}

/// Normals of a scene's cloud (k nearest neighbours, PCA, per layer) and the count of
/// fallbacks, when the scene lights its surface; `None` otherwise.
pub fn normals_for(cloud: &PointCloud, scene: &SplatsScene) -> Option<(Vec<[f32; 3]>, usize)> {
    if !(scene.lighting && scene.mode == Mode::Surface) {
        return None;
    }
    let k = if scene.normals_k == 0 {
        DEFAULT_K
    } else {
        scene.normals_k
    };
    let report = estimate_cloud(cloud, k, true);
    let fallbacks = report.collinear + report.coincident + report.too_few;
    Some((report.normals, fallbacks))
}

fn byte_colour(c: [u8; 3]) -> [f32; 3] {
    c.map(|v| v as f32 / 255.0)
}

/// Prepare a cloud in memory, with normals from [`normals_for`] (zeros when `None`).
pub fn from_cloud(
    cloud: &PointCloud,
    scene: &SplatsScene,
    normals: Option<(Vec<[f32; 3]>, usize)>,
) -> RenderResult<Prepared> {
    let n = cloud.len();
    let layers = cloud.ints(LAYER);
    let facies = cloud.ints(FACIES);
    let faults = cloud.ints(FAULT);
    let values: Vec<f32> = match cloud.attribute(&scene.property) {
        Some(a) => match &a.values {
            arbvis_data::points::Values::Float(v) => v.clone(),
            arbvis_data::points::Values::Int(v) => v.iter().map(|&x| x as f32).collect(),
        },
        None if scene.colour == ColourMode::Property || scene.mode == Mode::Volume => {
            let names: Vec<&str> = cloud.attributes.iter().map(|a| a.name.as_str()).collect();
            return Err(FieldError::new(
                "property",
                format!(
                    "the cloud has no attribute {:?} (it has: {})",
                    scene.property,
                    names.join(", ")
                ),
            )
            .into());
        }
        None => vec![f32::NAN; n],
    };
    let range = values
        .iter()
        .filter(|v| v.is_finite())
        .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], &v| {
            [lo.min(v as f64), hi.max(v as f64)]
        });
    let range = if range[0] <= range[1] {
        range
    } else {
        [0.0, 0.0]
    };
    let grey = [0.6f32; 3];
    // LAS stores colour in 16 bits, but many writers put 8-bit values there (autzen's
    // largest is 236): scale by 255 when nothing exceeds it, as PDAL and CloudCompare do.
    // Over the frame's z (a COPC file's, so that every cut colours a point alike).
    let elevation_range = [cloud.frame[0][2], cloud.frame[1][2]];
    let rgb_scale = match &cloud.rgb {
        Some(rgb) if rgb.iter().flatten().all(|&v| v <= 255) => 255.0,
        _ => 65535.0,
    };
    let colours: Vec<[f32; 3]> = (0..n)
        .map(|i| {
            let base = match scene.colour {
                ColourMode::Facies => facies.map_or(grey, |f| byte_colour(facies_colour(f[i]))),
                ColourMode::Layer => layers.map_or(grey, |l| {
                    byte_colour(PALETTE[l[i].rem_euclid(LAYERS_IN_PALETTE) as usize])
                }),
                ColourMode::Rgb => cloud
                    .rgb
                    .as_ref()
                    .map_or(grey, |rgb| rgb[i].map(|v| v as f32 / rgb_scale)),
                ColourMode::Intensity => cloud.ints("intensity").map_or(grey, |v| {
                    let max = cloud
                        .attribute("intensity")
                        .map_or(1.0, |a| a.stats.max.max(1.0));
                    [(v[i] as f64 / max) as f32; 3]
                }),
                ColourMode::Classification => cloud
                    .ints("classification")
                    .map_or(grey, |c| byte_colour(class_colour(c[i]))),
                ColourMode::Elevation => {
                    let z = cloud.origin[2] + cloud.scale * cloud.positions[i][2] as f64;
                    gradient_scale(z, elevation_range, Fidelity::Precise).map(|c| c as f32)
                }
                ColourMode::Property => grey,
            };
            match faults {
                Some(f) if scene.faults_white && f[i] >= 0 => [1.0; 3],
                _ => base,
            }
        })
        .collect();
    let classes = cloud.ints("classification");
    let visible: Vec<bool> = (0..n)
        .map(|i| {
            let hidden_layer = layers.is_some_and(|l| scene.hide_layers.contains(&l[i]));
            let hidden_class = classes.is_some_and(|c| scene.hide_classes.contains(&c[i]));
            let undefined =
                scene.hide_undefined && facies.is_some_and(|f| f[i] == UNDEFINED_FACIES);
            !(hidden_layer || hidden_class || undefined)
        })
        .collect();
    let (normals, normal_fallbacks) = match normals {
        Some((v, f)) if v.len() == n => (v, f),
        _ => (vec![[0.0; 3]; n], 0),
    };
    Ok(Prepared {
        positions: cloud.positions.clone(),
        colours,
        values,
        range,
        normals,
        visible,
        normal_fallbacks,
    })
}

/// LAS classification colours (ASPRS classes of LAS 1.4 table 17; others grey).
pub fn class_colour(class: i32) -> [u8; 3] {
    match class {
        1 => [200, 200, 200],
        2 => [166, 118, 29],
        3 => [161, 217, 155],
        4 => [65, 171, 93],
        5 => [0, 109, 44],
        6 => [222, 45, 38],
        7 => [255, 0, 255],
        9 => [49, 130, 189],
        10 => [120, 80, 140],
        11 => [90, 90, 90],
        13..=16 => [255, 200, 0],
        17 => [140, 110, 180],
        18 => [255, 120, 160],
        _ => [160, 160, 160],
    }
}

impl Prepared {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True for an empty cloud.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The vertex data of the points in `order` (all points when `None`), each point's
    /// size scaled by `scales` (1 where it has none).
    pub fn vertices(&self, order: Option<&[u32]>, scales: &[f32]) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.len() * FLOATS_PER_VERTEX);
        let mut push = |i: usize| {
            out.extend_from_slice(&self.positions[i]);
            out.extend_from_slice(&self.colours[i]);
            out.push(self.values[i]);
            out.extend_from_slice(&self.normals[i]);
            out.push(scales.get(i).copied().unwrap_or(1.0));
        };
        match order {
            Some(o) => o.iter().for_each(|&i| push(i as usize)),
            None => (0..self.len()).for_each(push),
        }
        out
    }
}

/// GLSL's `smoothstep`.
pub fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The normalized property: the seed's `value / (max - min)` (faithful, without
/// subtracting the minimum, NaN or infinite when the range is empty) or `(value - min) /
/// (max - min)` clamped, 0 for an empty range (precise).
pub fn normalized(value: f64, [min, max]: [f64; 2], fidelity: Fidelity) -> f64 {
    match fidelity {
        Fidelity::Faithful => value / (max - min),
        Fidelity::Precise => {
            if max > min && value.is_finite() {
                ((value - min) / (max - min)).clamp(0.0, 1.0)
            } else {
                0.0
            }
        }
    }
}

/// The seed's `gradient_scale` (CPU mirror): `mix(colorA, colorB, pct)` with
/// `pct = (smoothstep(0, 1, n), sin(n π), sqrt(n))` of the normalized value.
pub fn gradient_scale(value: f64, range: [f64; 2], fidelity: Fidelity) -> [f64; 3] {
    let n = normalized(value, range, fidelity);
    let pct = [
        smoothstep(0.0, 1.0, n),
        (n * std::f64::consts::PI).sin(),
        n.powf(0.5),
    ];
    std::array::from_fn(|c| COLOR_A[c] * (1.0 - pct[c]) + COLOR_B[c] * pct[c])
}

/// Volume mode's transfer function (CPU mirror): `smoothstep(0, 1, n)` for values in
/// `threshold ± range`, else 0.
pub fn transfer(value: f64, range: [f64; 2], scene: &SplatsScene, fidelity: Fidelity) -> f64 {
    let v = scene.volume;
    let inside = value >= v.threshold - v.range && value <= v.threshold + v.range;
    if inside {
        smoothstep(0.0, 1.0, normalized(value, range, fidelity))
    } else {
        0.0
    }
}

/// The footprint alpha at `n_dist` (0 centre, 1 rim) for a scene and fidelity.
pub fn footprint(scene: &SplatsScene, fidelity: Fidelity) -> super::reference::Footprint {
    use super::reference::Footprint;
    match (scene.kernel, fidelity) {
        (Kernel::Smoothstep, Fidelity::Faithful) => Footprint::SeedSmoothstep,
        (Kernel::Gaussian, Fidelity::Faithful) => Footprint::SeedGaussian {
            width: scene.gauss_width,
        },
        (Kernel::Smoothstep, Fidelity::Precise) => Footprint::Smoothstep,
        (Kernel::Gaussian, Fidelity::Precise) => Footprint::Gaussian {
            width: scene.gauss_width,
        },
    }
}

/// Phong terms of the headlight: ambient, diffuse, specular weight, shininess.
pub const PHONG: [f64; 4] = [0.25, 0.75, 0.25, 32.0];

/// A lit colour (CPU mirror of the programs): Phong with a light at the eye (the view
/// direction for orthographic views), the normal turned toward the viewer.
pub fn lit(colour: [f64; 3], normal: DVec3, to_viewer: DVec3) -> [f64; 3] {
    let v = to_viewer.normalize_or_zero();
    let n = if normal.dot(v) < 0.0 { -normal } else { normal };
    let diffuse = n.dot(v).max(0.0);
    let r = 2.0 * n.dot(v) * n - v;
    let specular = r.dot(v).max(0.0).powf(PHONG[3]);
    colour.map(|c| c * (PHONG[0] + PHONG[1] * diffuse) + PHONG[2] * specular)
}

/// Each point's RGBA as the programs compute it before the footprint (CPU mirror, for
/// the reference): base or gradient colour, lighting, volume transfer alpha.
pub fn point_rgba(
    prepared: &Prepared,
    scene: &SplatsScene,
    fidelity: Fidelity,
    eye: Option<DVec3>,
    view_dir: DVec3,
) -> Vec<[f64; 4]> {
    (0..prepared.len())
        .map(|i| rgba_of(prepared, scene, fidelity, eye, view_dir, i))
        .collect()
}

/// Point `i`'s RGBA (see [`point_rgba`]).
pub fn rgba_of(
    prepared: &Prepared,
    scene: &SplatsScene,
    fidelity: Fidelity,
    eye: Option<DVec3>,
    view_dir: DVec3,
    i: usize,
) -> [f64; 4] {
    let value = prepared.values[i] as f64;
    let mut c = match scene.colour {
        ColourMode::Property => gradient_scale(value, prepared.range, fidelity),
        _ => prepared.colours[i].map(f64::from),
    };
    if scene.lighting && scene.mode == Mode::Surface {
        let p = DVec3::from_array(prepared.positions[i].map(f64::from));
        let to_viewer = eye.map_or(-view_dir, |e| e - p);
        let n = DVec3::from_array(prepared.normals[i].map(f64::from));
        c = lit(c, n, to_viewer);
    }
    let a = match scene.mode {
        Mode::Surface => 1.0,
        Mode::Volume => transfer(value, prepared.range, scene, fidelity),
    };
    let a = if prepared.visible[i] { a } else { 0.0 };
    [c[0], c[1], c[2], a]
}

/// The point size that closes a COPC cut's gaps in `view`: splats twice the deepest
/// level's spacing across (`spacing`, frame units), as the seed sizes them (`pointSize /
/// distance * factor`: a length at eye distance d covers `length * P[1][1] * h / 2 / d`
/// pixels, so the distance cancels in perspective), or the scene's own when larger.
pub fn point_size_for_spacing(
    scene: &SplatsScene,
    view: &arbvis_data::points::copc_lod::View,
    spacing: f64,
) -> f64 {
    let covering =
        2.0 * spacing * view.projection_y * 0.5 * view.size[1] as f64 / scene.factor.max(1e-9);
    scene.point_size.max(covering)
}

/// An ASPRS classification code's name.
pub fn class_name(code: i32) -> String {
    let name = match code {
        0 => "never classified",
        1 => "unclassified",
        2 => "ground",
        3 => "low vegetation",
        4 => "medium vegetation",
        5 => "high vegetation",
        6 => "building",
        7 => "low point (noise)",
        8 => "model key point",
        9 => "water",
        10 => "rail",
        11 => "road surface",
        13 => "wire guard",
        14 => "wire conductor",
        15 => "transmission tower",
        16 => "wire connector",
        17 => "bridge deck",
        18 => "high noise",
        _ => return format!("class {code}"),
    };
    format!("{code} {name}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use arbvis_data::points::section::{generate, SectionSpec};
    use arbvis_data::points::PointSource;

    fn scene() -> SplatsScene {
        toml::from_str::<SplatsScene>("cloud = { section = { points = 2000, seed = 5 } }").unwrap()
    }

    #[test]
    fn colours_visibility_and_values_follow_the_scene() {
        let cloud = generate(&SectionSpec {
            points: 2000,
            seed: 5,
        })
        .unwrap();
        let mut s = scene();
        // A classification filter on a cloud without classes hides nothing.
        s.hide_classes = vec![0, 1, 2];
        s.hide_layers = vec![0, 3];
        s.hide_undefined = true;
        s.faults_white = true;
        let p = from_cloud(&cloud, &s, None).unwrap();
        let layers = cloud.ints(LAYER).unwrap();
        let facies = cloud.ints(FACIES).unwrap();
        let faults = cloud.ints(FAULT).unwrap();
        for i in 0..p.len() {
            let hidden = [0, 3].contains(&layers[i]) || facies[i] == UNDEFINED_FACIES;
            assert_eq!(p.visible[i], !hidden);
            if faults[i] >= 0 {
                assert_eq!(p.colours[i], [1.0; 3]);
            } else {
                assert_eq!(p.colours[i], byte_colour(facies_colour(facies[i])));
            }
        }
        assert!(p.range[0] >= 0.0 && p.range[1] > p.range[0]);
        assert_eq!(p.vertices(None, &[]).len(), 2000 * FLOATS_PER_VERTEX);
        assert!(matches!(s.cloud, PointSource::Section(_)));
    }

    #[test]
    fn eight_bit_colours_in_sixteen_bit_fields_are_scaled_by_255() {
        let mut cloud = generate(&SectionSpec { points: 3, seed: 5 }).unwrap();
        let mut s = scene();
        s.colour = ColourMode::Rgb;
        cloud.rgb = Some(vec![[255, 0, 51], [0, 0, 0], [236, 84, 102]]);
        let p = from_cloud(&cloud, &s, None).unwrap();
        assert_eq!(p.colours[0], [1.0, 0.0, 0.2]);
        cloud.rgb = Some(vec![[65535, 0, 13107], [256, 0, 0], [0, 0, 0]]);
        let p = from_cloud(&cloud, &s, None).unwrap();
        assert_eq!(p.colours[0], [1.0, 0.0, 0.2]);
    }

    #[test]
    fn the_seeds_gradient_quirk_and_its_correction() {
        // Range [0.5, 1]: the seed divides 0.75 by 0.5 (1.5, beyond the scale); the
        // precise scale puts it in the middle.
        let range = [0.5, 1.0];
        assert_eq!(normalized(0.75, range, Fidelity::Faithful), 1.5);
        assert_eq!(normalized(0.75, range, Fidelity::Precise), 0.5);
        assert!(normalized(0.3, [0.3, 0.3], Fidelity::Faithful).is_infinite());
        assert_eq!(normalized(0.3, [0.3, 0.3], Fidelity::Precise), 0.0);
        let mid = gradient_scale(0.75, range, Fidelity::Precise);
        assert!(
            (mid[1] - COLOR_B[1]).abs() < 1e-12,
            "sin(pi/2) = 1: green at colorB"
        );
    }

    #[test]
    fn lighting_faces_the_viewer() {
        let c = [0.5, 0.5, 0.5];
        let toward = lit(c, DVec3::Z, DVec3::Z);
        let away = lit(c, -DVec3::Z, DVec3::Z);
        assert_eq!(toward, away, "a normal facing away is flipped");
        let grazing = lit(c, DVec3::X, DVec3::Z);
        assert!(grazing[0] < toward[0]);
    }

    /// `hide_classes` hides the points of those LAS classes and no others.
    #[test]
    fn hidden_classes_are_not_drawn() {
        use arbvis_data::points::{CloudParts, Values};
        let classes: Vec<i32> = (0..50).map(|i| [1, 2, 5, 7, 2][i % 5]).collect();
        let cloud = PointCloud::from_parts(CloudParts {
            positions: (0..50)
                .map(|i| [i as f64, (i * 7 % 11) as f64, 0.5])
                .collect(),
            attributes: vec![("classification".into(), Values::Int(classes.clone()))],
            rgb: None,
            normals: None,
        })
        .unwrap();
        let mut s = scene();
        s.colour = ColourMode::Classification;
        s.hide_classes = vec![2, 7];
        let p = from_cloud(&cloud, &s, None).unwrap();
        for (i, c) in classes.iter().enumerate() {
            assert_eq!(p.visible[i], ![2, 7].contains(c), "point {i}, class {c}");
        }
        assert_eq!(p.colours[2], byte_colour(class_colour(5)));
    }

    /// Elevation colours each point by its own z in the file's units through the
    /// gradient, over the cloud's z range: the lowest at the gradient's start, the
    /// highest at its end, one in between where its height puts it (within f32 rounding
    /// of the positions: 1e-5 of the range).
    #[test]
    fn elevation_follows_each_points_height() {
        use arbvis_data::points::CloudParts;
        // Uneven heights far from the origin (a lidar tile's), x and y unrelated to z.
        let z: Vec<f64> = (0..40)
            .map(|i| 312.5 + ((i * 37) % 23) as f64 * 1.7)
            .collect();
        let cloud = PointCloud::from_parts(CloudParts {
            positions: (0..40)
                .map(|i| [635_000.0 + (i * 13 % 7) as f64, 848_000.0 + i as f64, z[i]])
                .collect(),
            attributes: vec![],
            rgb: None,
            normals: None,
        })
        .unwrap();
        let mut s = scene();
        s.colour = ColourMode::Elevation;
        let p = from_cloud(&cloud, &s, None).unwrap();
        let (lo, hi) = (312.5, 312.5 + 22.0 * 1.7);
        for (i, &zi) in z.iter().enumerate() {
            let want = gradient_scale(zi, [lo, hi], Fidelity::Precise);
            let near = gradient_scale(zi + 1e-5 * (hi - lo), [lo, hi], Fidelity::Precise);
            for c in 0..3 {
                let tolerance = (near[c] - want[c]).abs().max(1e-6);
                assert!(
                    (p.colours[i][c] as f64 - want[c]).abs() <= tolerance,
                    "point {i} (z {zi}) channel {c}: {:?} vs {want:?}",
                    p.colours[i]
                );
            }
        }
    }
}
