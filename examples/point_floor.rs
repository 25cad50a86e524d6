//! The floor of a point draw on this driver: N random points (default 570,000) drawn
//! as 1.3-pixel GL_POINTS by a do-nothing GLSL pair into 1600x900 RGBA8 with blending,
//! median of 6 frames (clear + draw + finish). `--sprite` reads `gl_PointCoord` as a
//! splat's fragment program must. What arbvis's splats (README, "Splats") measure against:
//! `cargo run --release --example point_floor -- 570000 --sprite`.
use std::time::Instant;

use arbvis::gl::{
    self, Backend, Blend, DrawCall, Headless, Mesh, Primitive, Program, ProgramKind, ProgramText,
    Surface, Target, TargetFormat,
};

fn main() -> anyhow::Result<()> {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(570_000);
    let sprite = std::env::args().any(|a| a == "--sprite");
    let h = Headless::new(Backend::Egl)?;
    let gpu = h.gpu();
    let mut v = Vec::with_capacity(n * 4);
    let mut s = 1u64;
    for _ in 0..n {
        for c in 0..3 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let x = ((s >> 33) as f32 / (1u64 << 31) as f32) * 1.6 - 0.8;
            v.push(if c == 2 { x * 0.1 } else { x });
        }
        v.push(1.0);
    }
    let mesh = Mesh::new(gpu, "points", &[4], &v)?;
    let vs = ProgramText { name: "v".into(), text: "#version 330\nlayout(location = 0) in vec4 position;\nvoid main() { gl_Position = position; gl_PointSize = 1.3; }\n".into() };
    let fs = ProgramText {
        name: "f".into(),
        text: if sprite {
            "#version 330\nout vec4 c;\nvoid main() { c = vec4(gl_PointCoord, 0.5, 0.5); }\n"
        } else {
            "#version 330\nout vec4 c;\nvoid main() { c = vec4(1.0, 0.5, 0.2, 0.5); }\n"
        }
        .into(),
    };
    let program = Program::new(gpu, ProgramKind::Glsl, &vs, &fs)?;
    let target = Target::create(gpu, 1600, 900, TargetFormat::Rgba8, false)?;
    let mut times = Vec::new();
    for _ in 0..6 {
        let t0 = Instant::now();
        target.clear(gpu, [0.0; 4])?;
        gl::draw(
            gpu,
            Surface::Target(&target),
            &DrawCall {
                blend: Blend::Over,
                primitive: Primitive::Points,
                ..DrawCall::new(&program, &mesh)
            },
        )?;
        gpu.finish();
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    println!("{n} points, sprite {sprite}: median {:.1} ms", times[3]);
    Ok(())
}
