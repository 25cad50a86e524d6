//! Issue acceptance: the seed's v3o2 sum program, uploaded byte for byte, with a 3D RGB
//! texture on unit 0 and colour tables on units 2-4, gives a hand-computed pixel exactly,
//! on EGL and on OSMesa.

use crate::common;

use arbvis::gl::{
    draw, Backend, DrawCall, Extent, Filter, Mesh, Program, ProgramKind, Surface, Target,
    TargetFormat, TexelData, TexelFormat, Texture,
};
use arbvis::programs;
use arbvis::techniques::quad::quad_vertices;
use common::headless;

/// The sum program as the seed prints it, one C literal per line, joined as C joins them.
const SEED_SUM_LINES: [&str; 15] = [
    "!!ARBfp1.0",
    "TEMP rgba_frag;",
    "TEMP lut1;",
    "TEMP lut2;",
    "TEMP lut3;",
    "TEMP temp;",
    "TEX rgba_frag, fragment.texcoord[0], texture[0], 3D;",
    "TEX lut1, rgba_frag.g, texture[2], 2D;",
    "TEX lut2, rgba_frag.b, texture[3], 2D;",
    "TEX lut3, rgba_frag.r, texture[4], 2D;",
    "MUL temp, program.local[1], lut1;",
    "MAD temp, program.local[2], lut2, temp;",
    "MAD temp, program.local[3], lut3, temp;",
    "MUL result.color, temp, 0.3333;",
    "END",
];

#[test]
fn stored_sum_program_is_the_seed_joined_with_no_separator() {
    let joined: String = SEED_SUM_LINES.concat();
    assert_eq!(programs::OPACITY3D_SUM_ARBFP.text, joined);
    assert_eq!(joined.len(), 376);
}

/// A 256-entry RGBA8 table, 256x1 2D texture, with entry `k` set to `value` and every
/// other entry to `other`.
fn table(value_at: u8, value: [u8; 4], other: [u8; 4]) -> Vec<u8> {
    (0..256u32)
        .flat_map(|k| if k == value_at as u32 { value } else { other })
        .collect()
}

fn hand_computed_sum_pixel(backend: Backend) {
    let h = headless(backend);
    let gpu = h.gpu();
    // A 2x2x2 volume, every voxel (R, G, B) = (tertiary 30, primary 200, secondary 90):
    // whatever the interpolation, the fetched texel is exactly these bytes.
    let voxel = [30u8, 200, 90];
    let volume: Vec<u8> = voxel.repeat(8);
    let vol = Texture::new(
        gpu,
        "volume",
        Extent::D3(2, 2, 2),
        TexelFormat::Rgb8,
        Filter::Nearest,
        TexelData::U8(&volume),
    )
    .unwrap();
    // Tables: the entry the program reads holds the value; all others are decoys, so a
    // wrong channel or a wrong index shows. With NEAREST, coordinate k/255 on 256 texels
    // lands on texel floor(k/255*256) = k for k < 255.
    let t1 = table(200, [200, 40, 0, 255], [7, 7, 7, 7]);
    let t2 = table(90, [0, 160, 80, 128], [9, 9, 9, 9]);
    let t3 = table(30, [100, 0, 250, 64], [11, 11, 11, 11]);
    let lut = |d: &[u8], n| {
        Texture::new(
            gpu,
            n,
            Extent::D2(256, 1),
            TexelFormat::Rgba8,
            Filter::Nearest,
            TexelData::U8(d),
        )
        .unwrap()
    };
    let (lut1, lut2, lut3) = (lut(&t1, "lut1"), lut(&t2, "lut2"), lut(&t3, "lut3"));

    // Upload the seed's bytes, not the embedded file, so the test checks the seed itself.
    let fragment = arbvis::gl::ProgramText {
        name: "seed/sum".into(),
        text: SEED_SUM_LINES.concat().into(),
    };
    let program =
        Program::new(gpu, ProgramKind::Arb, &programs::TRANSFORM_ARBVP, &fragment).unwrap();
    program.set_transform(gpu, glam::DMat4::IDENTITY).unwrap();
    let c1 = [1.0, 0.5, 0.25, 1.0];
    let c2 = [0.5, 1.0, 0.0, 0.5];
    let c3 = [0.0, 0.25, 1.0, 1.0];
    program.set_local(gpu, 1, c1).unwrap();
    program.set_local(gpu, 2, c2).unwrap();
    program.set_local(gpu, 3, c3).unwrap();

    let mesh = Mesh::new(gpu, "quad", &[4, 4], &quad_vertices()).unwrap();
    let target = Target::new(gpu, 8, 8, TargetFormat::Rgba8).unwrap();
    draw(
        gpu,
        Surface::Target(&target),
        &DrawCall {
            textures: &[(0, &vol), (2, &lut1), (3, &lut2), (4, &lut3)],
            primitive: Default::default(),
            ..DrawCall::new(&program, &mesh)
        },
    )
    .unwrap();
    let image = target.read(gpu).unwrap();

    // By hand: temp = c1*lut1 + c2*lut2 + c3*lut3, result = temp * 0.3333, stored as
    // round(255 * result). Tables in 0..1 are byte/255.
    //   R: (1*200 + 0.5*0 + 0*100)/255 * 0.3333 = 0.261412 -> 66.66 -> 67
    //   G: (0.5*40 + 1*160 + 0.25*0)/255 * 0.3333 = 0.235271 -> 59.99 -> 60
    //   B: (0.25*0 + 0*80 + 1*250)/255 * 0.3333 = 0.326765 -> 83.33 -> 83
    //   A: (1*255 + 0.5*128 + 1*64)/255 * 0.3333 = 0.500597 -> 127.65 -> 128
    // Each lies at least 0.15 level from a rounding boundary, so the result is exact
    // whatever the driver's internal float precision.
    let expected = [67u8, 60, 83, 128];
    let mut by_formula = [0u8; 4];
    for ch in 0..4 {
        let lut_v = |t: &[u8], k: u8| t[k as usize * 4 + ch] as f64 / 255.0;
        let v =
            (c1[ch] * lut_v(&t1, 200) + c2[ch] * lut_v(&t2, 90) + c3[ch] * lut_v(&t3, 30)) * 0.3333;
        by_formula[ch] = (v * 255.0).round() as u8;
    }
    assert_eq!(
        by_formula, expected,
        "the hand computation and its formula agree"
    );
    for (x, y) in [(0, 0), (3, 4), (7, 7)] {
        common::assert_pixel_u8(
            &image,
            x,
            y,
            expected,
            &format!("v3o2 sum on {}", backend.name()),
        );
    }
}

#[test]
fn sum_program_hand_computed_pixel_egl() {
    hand_computed_sum_pixel(Backend::Egl);
}

#[test]
fn sum_program_hand_computed_pixel_osmesa() {
    hand_computed_sum_pixel(Backend::Osmesa);
}
