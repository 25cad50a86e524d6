//! A synthetic geological section, since ReconMS's `.dat` files are not public: a
//! filled 2.5D slab of points, as ReconMS's particle method produces (points throughout
//! the volume, not only on surfaces), with the seed's six attributes.
//!
//! How it is built (metres, z up, the surface at z = 0):
//! - **Box**: x 0..12,000 along the section, y 0..1,500 across it, z -4,000..0. Points are
//!   uniform in the box; point `i` draws from its own SplitMix64 stream seeded by
//!   `(seed, i)`, so the cloud is the same for a seed whatever the thread count.
//! - **Layers** 0 (bottom, oldest) .. 7 (top) between folded interfaces: interface `k`
//!   lies near `-4000 + 500 k`, folded by two long sine waves (amplitude fading upwards,
//!   as folds grown during deposition) and a small wave of its own; the spacing keeps
//!   interfaces from ever crossing.
//! - **Faults**: 2 or 3 normal faults (from the seed) striking along y, dipping 55-70°,
//!   each lowering its hanging wall by a throw of 150-400 m. Layers are looked up at the
//!   point's depth before faulting, so interfaces are offset across each fault. Points
//!   within 20 m of a fault plane get its id (0, 1, 2), others -1.
//! - **Facies** per layer from a set of six (1 sandstone, 2 shale, 3 limestone,
//!   4 siltstone, 5 conglomerate, 6 marl): a dominant one, a secondary one in lateral
//!   channel-like bodies and thin interbeds; four ellipsoidal patches are undefined
//!   (-999).
//! - **Porosity**: a base per facies (0.0015 shale .. 0.009 conglomerate) that falls
//!   with depth, times noise, plus a damage-zone term that decays away from each fault
//!   (up to +0.03 on the plane): mostly within 0.0-0.020 and densest in 0.0-0.012, as
//!   the seed reports, and highest along faults as its figure 15 shows.
//! - **Amplitude**: a synthetic seismic trace: Ricker wavelets at the interfaces (at
//!   their pre-fault depth) weighted by reflection coefficients of the layers'
//!   dominant facies, a weak ripple from the thin interbeds, and noise; about -0.4..0.3.
//! - **Joint dip** (degrees, 0..90): near-vertical joints in brittle facies, lower in
//!   shale and marl, tilted with the bedding, and close to the fault dip within 150 m of
//!   a fault.
//!
//! [`facies_colour`] gives the facies colours. ReconMS's own dictionary (the seed imported
//! it) is not public, so these follow the usual lithology conventions instead (sandstone
//! yellow, shale green-grey, limestone blue, ...); -999 is grey.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::progress::Progress;
use super::{
    CloudParts, PointCloud, PointsError, Values, AMPLITUDE, FACIES, FAULT, JOINT_DIP, LAYER,
    POROSITY, UNDEFINED_FACIES,
};

/// Most points the generator makes (benchmarks go to 10-20 M).
pub const MAX_SECTION_POINTS: usize = 20_000_000;

/// The generated section as a scene names it: `{ section = { points = 570000, seed = 1 } }`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SectionSpec {
    /// Number of points (the seed's cloud had about 570,000).
    pub points: usize,
    /// Random seed: the same seed gives the same cloud.
    pub seed: u64,
}

impl Default for SectionSpec {
    fn default() -> Self {
        SectionSpec {
            points: 570_000,
            seed: 1,
        }
    }
}

/// Size of the section box (x, y, z extents) in metres; z runs from -4000 to 0.
pub const BOX: [f64; 3] = [12_000.0, 1_500.0, 4_000.0];

/// Number of layers.
pub const LAYERS: i32 = 8;

/// Half-width of the band around a fault plane whose points carry the fault's id.
pub const FAULT_HALF_WIDTH: f64 = 20.0;

/// Facies ids, names and colours (sRGB); see the module doc for their origin.
pub const FACIES_TABLE: [(i32, &str, [u8; 3]); 7] = [
    (UNDEFINED_FACIES, "undefined", [128, 128, 128]),
    (1, "sandstone", [238, 214, 110]),
    (2, "shale", [112, 138, 104]),
    (3, "limestone", [110, 160, 215]),
    (4, "siltstone", [196, 160, 112]),
    (5, "conglomerate", [226, 140, 64]),
    (6, "marl", [176, 204, 178]),
];

/// Twelve distinct colours (ColorBrewer's Set3), for ids without colours of their own.
pub const PALETTE: [[u8; 3]; 12] = [
    [141, 211, 199],
    [255, 255, 179],
    [190, 186, 218],
    [251, 128, 114],
    [128, 177, 211],
    [253, 180, 98],
    [179, 222, 105],
    [252, 205, 229],
    [217, 217, 217],
    [188, 128, 189],
    [204, 235, 197],
    [255, 237, 111],
];

/// Colour of facies `id`: from [`FACIES_TABLE`], or for ids it lacks a colour of
/// [`PALETTE`] picked by the id (so files with other ids still show them).
pub fn facies_colour(id: i32) -> [u8; 3] {
    if let Some((_, _, rgb)) = FACIES_TABLE.iter().find(|(f, _, _)| *f == id) {
        return *rgb;
    }
    PALETTE[id.rem_euclid(PALETTE.len() as i32) as usize]
}

/// SplitMix64 (Steele, Lea, Flood 2014): small, fast, and enough for test data.
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from `seed`.
    pub fn new(seed: u64) -> SplitMix64 {
        SplitMix64(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
}

struct Fault {
    /// x of the trace at the surface (z = 0), at y = 0.
    x0: f64,
    /// Trace shift per metre of y (a slightly oblique strike).
    skew: f64,
    /// +1: dips towards +x; -1: towards -x.
    dir: f64,
    /// Dip angle in radians.
    dip: f64,
    throw: f64,
}

impl Fault {
    /// Signed distance from the plane, positive on the hanging-wall side.
    fn distance(&self, x: f64, y: f64, z: f64) -> f64 {
        let trace = self.x0 + self.skew * y + self.dir * (-z) / self.dip.tan();
        (x - trace) * self.dir * self.dip.sin()
    }
}

struct Patch {
    centre: [f64; 3],
    radii: [f64; 3],
}

/// Everything drawn once from the seed.
struct Model {
    faults: Vec<Fault>,
    patches: Vec<Patch>,
    fold_phase: [f64; 3],
    /// Sine and cosine of each interface's wave phase.
    wave_phase: [(f64, f64); 8],
    /// Dominant, secondary and interbed facies of each layer.
    facies: [[i32; 3]; 8],
    channel_phase: [[f64; 2]; 8],
    /// Reflection coefficient at the base of each layer (from the dominant facies).
    reflection: [f64; 8],
}

/// Layer facies: dominant, secondary, thin interbeds (bottom layer first).
const LAYER_FACIES: [[i32; 3]; 8] = [
    [3, 6, 2],
    [2, 4, 1],
    [1, 5, 2],
    [6, 3, 2],
    [2, 1, 4],
    [1, 2, 5],
    [4, 2, 1],
    [5, 1, 2],
];

impl Model {
    fn new(seed: u64) -> Model {
        let mut rng = SplitMix64::new(seed ^ 0x5EC7_1011);
        let count = 2 + (rng.next_u64() % 2) as usize;
        let faults = (0..count)
            .map(|j| {
                // Spread traces over the section, one per slot, jittered.
                let slot = BOX[0] / count as f64;
                Fault {
                    x0: slot * (j as f64 + 0.5) + rng.range(-0.2, 0.2) * slot,
                    skew: rng.range(-0.3, 0.3),
                    dir: if (j + (seed as usize & 1)).is_multiple_of(2) {
                        1.0
                    } else {
                        -1.0
                    },
                    dip: rng.range(55.0, 70.0).to_radians(),
                    throw: rng.range(150.0, 400.0),
                }
            })
            .collect();
        let patches = (0..4)
            .map(|_| Patch {
                centre: [
                    rng.range(0.0, BOX[0]),
                    rng.range(0.0, BOX[1]),
                    rng.range(-BOX[2], 0.0),
                ],
                radii: [
                    rng.range(500.0, 1100.0),
                    rng.range(400.0, 900.0),
                    rng.range(120.0, 260.0),
                ],
            })
            .collect();
        let tau = std::f64::consts::TAU;
        Model {
            faults,
            patches,
            fold_phase: std::array::from_fn(|_| rng.range(0.0, tau)),
            wave_phase: std::array::from_fn(|_| rng.range(0.0, tau).sin_cos()),
            facies: LAYER_FACIES,
            channel_phase: std::array::from_fn(|_| [rng.range(0.0, tau), rng.range(0.0, tau)]),
            reflection: std::array::from_fn(|k| {
                let (below, above) = (LAYER_FACIES[k.max(1) - 1][0], LAYER_FACIES[k][0]);
                (impedance(above) - impedance(below)) / (impedance(above) + impedance(below))
            }),
        }
    }

    /// Depths of the interfaces at (x, y): `[k]` is the base of layer `k`. Each is the
    /// common fold, fading upwards, plus a wave of its own phase (expanded as
    /// `sin(a + p) = sin a cos p + cos a sin p` so one sine and cosine serve all).
    fn interfaces(&self, x: f64, y: f64) -> [f64; 8] {
        let tau = std::f64::consts::TAU;
        let fold = 330.0 * (tau * x / 7_000.0 + self.fold_phase[0]).sin()
            + 110.0 * (tau * x / 2_300.0 + self.fold_phase[1]).sin()
            + 50.0 * (tau * y / 3_000.0 + self.fold_phase[2]).sin();
        let (sin, cos) = (tau * x / 900.0).sin_cos();
        std::array::from_fn(|k| {
            let (sp, cp) = self.wave_phase[k];
            let wave = 25.0 * (sin * cp + cos * sp);
            -BOX[2] + 500.0 * k as f64 + fold * (1.0 - k as f64 / 12.0) + wave
        })
    }

    /// Slope of the folding at (x, y) under interface `k`, in degrees.
    fn bedding_dip(&self, k: usize, x: f64) -> f64 {
        let tau = std::f64::consts::TAU;
        let d = 330.0 * tau / 7_000.0 * (tau * x / 7_000.0 + self.fold_phase[0]).cos()
            + 110.0 * tau / 2_300.0 * (tau * x / 2_300.0 + self.fold_phase[1]).cos();
        (d * (1.0 - k as f64 / 12.0)).abs().atan().to_degrees()
    }
}

/// One generated point.
struct Sample {
    position: [f64; 3],
    layer: i32,
    facies: i32,
    fault: i32,
    porosity: f32,
    amplitude: f32,
    joint_dip: f32,
}

fn ricker(t: f64) -> f64 {
    let a = (std::f64::consts::PI * t).powi(2);
    (1.0 - 2.0 * a) * (-a).exp()
}

/// Acoustic impedance of a facies (arbitrary units), for reflection coefficients.
fn impedance(facies: i32) -> f64 {
    match facies {
        1 => 7.0,
        2 => 6.2,
        3 => 10.5,
        4 => 6.8,
        5 => 7.6,
        _ => 8.4,
    }
}

fn sample(model: &Model, seed: u64, i: u64) -> Sample {
    let mut rng = SplitMix64::new(seed.wrapping_mul(0xA24B_AED4_963E_E407) ^ i);
    rng.next_u64();
    let (x, y, z) = (
        rng.range(0.0, BOX[0]),
        rng.range(0.0, BOX[1]),
        rng.range(-BOX[2], 0.0),
    );
    // Depth before faulting, and the nearest fault.
    let mut z0 = z;
    let mut nearest: Option<(usize, f64)> = None;
    for (j, f) in model.faults.iter().enumerate() {
        let d = f.distance(x, y, z);
        if d > 0.0 {
            z0 += f.throw;
        }
        if nearest.is_none_or(|(_, n)| d.abs() < n.abs()) {
            nearest = Some((j, d));
        }
    }
    let interfaces = model.interfaces(x, y);
    let layer = (1..8).take_while(|&k| z0 >= interfaces[k]).count();
    let fault_distance = nearest.map_or(f64::INFINITY, |(_, d)| d.abs());
    let fault = match nearest {
        Some((j, d)) if d.abs() <= FAULT_HALF_WIDTH => j as i32,
        _ => -1,
    };
    // Facies: channels of the secondary facies, thin interbeds, undefined patches.
    let [dominant, secondary, interbed] = model.facies[layer];
    let tau = std::f64::consts::TAU;
    let [p0, p1] = model.channel_phase[layer];
    let channel = (tau * x / 1_700.0 + p0).sin() * (tau * y / 1_300.0 + p1).sin()
        + 0.4 * (tau * x / 430.0 + p1).sin();
    let base = interfaces[layer];
    let bed = (tau * (z0 - base) / 55.0).sin();
    let mut facies = if channel > 0.75 {
        secondary
    } else if bed > 0.93 {
        interbed
    } else {
        dominant
    };
    let rock = facies;
    if model.patches.iter().any(|p| {
        (0..3)
            .map(|a| ((([x, y, z][a]) - p.centre[a]) / p.radii[a]).powi(2))
            .sum::<f64>()
            < 1.0
    }) {
        facies = UNDEFINED_FACIES;
    }
    // Porosity: facies base, compaction with depth, noise, fault damage zone.
    let base_porosity = match rock {
        1 => 0.0080,
        2 => 0.0015,
        3 => 0.0040,
        4 => 0.0030,
        5 => 0.0090,
        _ => 0.0055,
    };
    let compaction = (z / 5_000.0).exp();
    let noise = 0.35 + 1.3 * rng.next_f64();
    let damage = 0.03 * (-fault_distance / 60.0).exp() * (0.6 + 0.8 * rng.next_f64());
    let porosity = base_porosity * compaction * noise + damage;
    // Amplitude: Ricker wavelets at the pre-fault interfaces.
    let mut amplitude = 0.0;
    for (r, z) in model.reflection.iter().zip(interfaces).skip(1) {
        amplitude += 1.6 * r * ricker((z0 - z) / 120.0);
    }
    amplitude += 0.04 * bed + 0.02 * (rng.next_f64() - 0.5);
    // Joint dip: steep in brittle rock, following faults near them.
    let bedding = model.bedding_dip(layer, x);
    let mut dip = match rock {
        2 | 6 => 35.0 + 15.0 * rng.next_f64(),
        _ => 90.0 - bedding - 12.0 * rng.next_f64(),
    };
    if let Some((j, d)) = nearest {
        let w = (-d.abs() / 150.0).exp();
        let fault_dip = model.faults[j].dip.to_degrees() + 6.0 * (rng.next_f64() - 0.5);
        dip = w * fault_dip + (1.0 - w) * dip;
    }
    Sample {
        position: [x, y, z],
        layer: layer as i32,
        facies,
        fault,
        porosity: porosity as f32,
        amplitude: amplitude as f32,
        joint_dip: dip.clamp(0.0, 90.0) as f32,
    }
}

/// Generate the section of `spec` (1 to [`MAX_SECTION_POINTS`] points).
pub fn generate(spec: &SectionSpec) -> Result<PointCloud, PointsError> {
    let n = spec.points;
    if n == 0 || n > MAX_SECTION_POINTS {
        return Err(PointsError::Invalid(format!(
            "section: points = {n}: the generator makes 1 to {MAX_SECTION_POINTS} points"
        )));
    }
    // The samples and the columns made from them are held together, then the cloud.
    let each = std::mem::size_of::<Sample>() as u64;
    let estimate = arbvis_core::budget::times(n as u64, 2 * each)
        .max(super::footprint(n as u64, 6, false, false));
    arbvis_core::budget::check(format!("the section of {n} points"), estimate)
        .map_err(|e| PointsError::Invalid(format!("section: points = {n}: {e}")))?;
    let model = Model::new(spec.seed);
    let progress = Progress::new(n as u64, "generating the section");
    const BLOCK: usize = 1 << 15;
    let blocks: Vec<Vec<Sample>> = (0..n.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            let range = b * BLOCK..((b + 1) * BLOCK).min(n);
            progress.inc(range.len() as u64);
            range.map(|i| sample(&model, spec.seed, i as u64)).collect()
        })
        .collect();
    drop(progress);
    let mut positions = Vec::with_capacity(n);
    let mut ints: [Vec<i32>; 3] = std::array::from_fn(|_| Vec::with_capacity(n));
    let mut floats: [Vec<f32>; 3] = std::array::from_fn(|_| Vec::with_capacity(n));
    for s in blocks.into_iter().flatten() {
        positions.push(s.position);
        ints[0].push(s.layer);
        ints[1].push(s.facies);
        ints[2].push(s.fault);
        floats[0].push(s.porosity);
        floats[1].push(s.amplitude);
        floats[2].push(s.joint_dip);
    }
    let [layer, facies, fault] = ints;
    let [porosity, amplitude, joint_dip] = floats;
    let attributes = vec![
        (LAYER.to_string(), Values::Int(layer)),
        (FACIES.to_string(), Values::Int(facies)),
        (FAULT.to_string(), Values::Int(fault)),
        (POROSITY.to_string(), Values::Float(porosity)),
        (AMPLITUDE.to_string(), Values::Float(amplitude)),
        (JOINT_DIP.to_string(), Values::Float(joint_dip)),
    ];
    PointCloud::from_parts(CloudParts {
        positions,
        attributes,
        rgb: None,
        normals: None,
    })
    .map_err(|m| PointsError::Invalid(format!("section: {m}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn section(points: usize, seed: u64) -> PointCloud {
        generate(&SectionSpec { points, seed }).unwrap()
    }

    #[test]
    fn counts_ranges_and_ids() {
        let c = section(100_000, 1);
        assert_eq!(c.len(), 100_000);
        for a in &c.attributes {
            assert_eq!(a.values.len(), 100_000, "{}", a.name);
            assert_eq!(a.stats.non_finite, 0, "{}", a.name);
        }
        let layer = c.ints(LAYER).unwrap();
        assert!(layer.iter().all(|l| (0..LAYERS).contains(l)));
        for l in 0..LAYERS {
            let n = layer.iter().filter(|&&x| x == l).count();
            assert!(n > 5_000, "layer {l} has {n} points");
        }
        let facies = c.ints(FACIES).unwrap();
        let undefined = facies.iter().filter(|&&f| f == UNDEFINED_FACIES).count();
        assert!(
            (1_000..20_000).contains(&undefined),
            "{undefined} undefined facies"
        );
        assert!(facies
            .iter()
            .all(|f| FACIES_TABLE.iter().any(|(id, _, _)| id == f)));
        for id in 1..=6 {
            assert!(facies.contains(&id), "facies {id} missing");
        }
        let fault = c.ints(FAULT).unwrap();
        let faults = fault.iter().copied().max().unwrap() + 1;
        assert!((2..=3).contains(&faults));
        assert!(fault.iter().all(|&f| f >= -1 && f < faults));
        for j in 0..faults {
            let n = fault.iter().filter(|&&f| f == j).count();
            assert!((150..1_500).contains(&n), "fault {j}: {n} points");
        }
        // The box, rescaled: x is the longest side and spans [-1, 1].
        assert!(c.bounds[0][0] >= 0.0 && c.bounds[1][0] <= BOX[0]);
        assert!(c.bounds[0][2] >= -BOX[2] && c.bounds[1][2] <= 0.0);
        assert!((c.scale - BOX[0] / 2.0).abs() < 5.0, "{}", c.scale);
        assert!(c.positions.iter().flatten().all(|v| v.abs() <= 1.0));
        let dip = c.attribute(JOINT_DIP).unwrap().stats;
        assert!(dip.min >= 0.0 && dip.max <= 90.0);
        let amp = c.attribute(AMPLITUDE).unwrap().stats;
        assert!(amp.min < -0.1 && amp.max > 0.1, "{amp:?}");
    }

    #[test]
    fn porosity_as_the_seed_reports_and_highest_along_faults() {
        let c = section(200_000, 3);
        let por = c.floats(POROSITY).unwrap();
        let n = por.len() as f64;
        let within =
            |lo: f32, hi: f32| por.iter().filter(|&&p| p >= lo && p <= hi).count() as f64 / n;
        assert!(por.iter().all(|&p| p >= 0.0));
        let to_020 = within(0.0, 0.020);
        let to_012 = within(0.0, 0.012);
        assert!(to_020 > 0.97, "{to_020} within 0-0.020");
        assert!(to_012 > 0.9, "{to_012} within 0-0.012");
        // Densest in 0-0.012: more points per unit of porosity than in 0.012-0.020.
        assert!(to_012 / 0.012 > 5.0 * (to_020 - to_012) / 0.008);
        // Along faults (fault id >= 0) porosity is several times the rest.
        let fault = c.ints(FAULT).unwrap();
        let mean = |on: bool| {
            let v: Vec<f64> = por
                .iter()
                .zip(fault)
                .filter(|(_, &f)| (f >= 0) == on)
                .map(|(&p, _)| p as f64)
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        let (on, off) = (mean(true), mean(false));
        assert!(on > 4.0 * off, "on faults {on}, elsewhere {off}");
        assert!(c.attribute(POROSITY).unwrap().stats.max > 0.02);
    }

    #[test]
    fn deterministic_per_seed_and_thread_count() {
        let a = section(40_000, 7);
        let b = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| section(40_000, 7));
        assert_eq!(a, b);
        let c = section(40_000, 8);
        assert_ne!(a.positions, c.positions);
        // A prefix of a bigger cloud is the smaller cloud (per-point streams).
        let d = section(50_000, 7);
        assert_eq!(a.ints(FACIES).unwrap(), &d.ints(FACIES).unwrap()[..40_000]);
    }

    #[test]
    fn layers_are_stacked_bottom_up() {
        let c = section(50_000, 2);
        let layer = c.ints(LAYER).unwrap();
        let mut mean_z = [0.0f64; 8];
        let mut count = [0usize; 8];
        for (i, &l) in layer.iter().enumerate() {
            let l = l as usize;
            mean_z[l] += c.original(i).unwrap()[2];
            count[l] += 1;
        }
        let mean: Vec<f64> = (0..8).map(|l| mean_z[l] / count[l] as f64).collect();
        assert!(mean.windows(2).all(|w| w[0] < w[1]), "{mean:?}");
    }

    #[test]
    fn absurd_sizes_are_refused() {
        for points in [0, MAX_SECTION_POINTS + 1, usize::MAX] {
            let e = generate(&SectionSpec { points, seed: 1 }).unwrap_err();
            assert!(e.to_string().contains("1 to 20000000 points"), "{e}");
        }
        assert_eq!(section(1, 1).len(), 1);
    }

    #[test]
    fn scene_syntax() {
        let s: SectionSpec = toml::from_str("points = 1000").unwrap();
        assert_eq!(
            s,
            SectionSpec {
                points: 1000,
                seed: 1
            }
        );
        assert_eq!(toml::from_str::<SectionSpec>("").unwrap().points, 570_000);
        assert!(toml::from_str::<SectionSpec>("point = 3").is_err());
    }

    #[test]
    fn facies_colours() {
        assert_eq!(facies_colour(UNDEFINED_FACIES), [128, 128, 128]);
        assert_eq!(facies_colour(3), [110, 160, 215]);
        assert_eq!(facies_colour(40), facies_colour(40));
        assert_ne!(facies_colour(40), facies_colour(41));
        let _ = facies_colour(i32::MIN);
    }
}
