//! Eye-dome lighting (`edl`, issue 28 item 4): on two fronto-parallel planes of points, the
//! far one half hidden by the near one, seen orthographically: with `edl = 1` every pixel
//! of a flat stretch and of the background keeps its colour exactly (no neighbour is
//! nearer), the far plane's pixels beside the near plane's edge darken (their neighbours
//! are nearer: log2(2.25 / 1.75) each), and the near plane's edge does not; for tiles and
//! for points. Faithful or ARB with `edl` is refused naming the key.

use std::fmt::Write as _;

use arbvis::gl::Backend;
use arbvis::render::render_on;
use arbvis::scene::Scene;

use crate::common::{headless, temp_dir};

/// A PLY of two planes: z = 0 over [-1, 1]² (grey 200) and z = 0.5 over [-1, -0.0] x
/// [-1, 1] (grey 120), 2 points per 0.033.
fn two_planes() -> String {
    let mut rows = String::new();
    let n = 61;
    let mut count = 0;
    for (z, grey, x_max) in [(0.0, 200, 1.0), (0.5, 120, 0.0)] {
        for i in 0..n {
            for j in 0..n {
                let x = -1.0 + 2.0 * i as f64 / (n - 1) as f64;
                let y = -1.0 + 2.0 * j as f64 / (n - 1) as f64;
                if x <= x_max {
                    writeln!(rows, "{x} {y} {z} {grey} {grey} {grey}").unwrap();
                    count += 1;
                }
            }
        }
    }
    format!(
        "ply\nformat ascii 1.0\nelement vertex {count}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n{rows}"
    )
}

fn scene(dir: &std::path::Path, draw: &str, edl: f64) -> Scene {
    let text = format!(
        "size = [120, 120]\nfidelity = \"precise\"\nprograms = \"glsl\"\nbackground = [0.0, 0.0, 1.0, 1.0]\n[camera]\nzoom = 0.9\n[technique.splats]\ncloud = {{ ply = \"planes.ply\" }}\ncolour = \"rgb\"\npoint_size = 4.0\nkernel = \"smoothstep\"\ndraw = \"{draw}\"\nedl = {edl}\n"
    );
    let mut s = Scene::parse(&text, "edl.toml").unwrap();
    s.base = dir.to_path_buf();
    s
}

#[test]
fn eye_dome_lighting_darkens_what_lies_behind_an_edge_only() {
    let dir = temp_dir("splats-edl");
    std::fs::write(dir.join("planes.ply"), two_planes()).unwrap();
    let h = headless(Backend::Egl);
    for draw in ["tiles", "points"] {
        let plain = render_on(&h, &scene(&dir, draw, 0.0)).unwrap().image;
        let lit = render_on(&h, &scene(&dir, draw, 1.0)).unwrap().image;
        let px = |img: &arbvis::image::Image, x: u32, y: u32| {
            let k = 4 * (y * img.width + x) as usize;
            [img.data[k], img.data[k + 1], img.data[k + 2]]
        };
        let (mut same, mut darker, mut darker_near) = (0, 0, 0);
        for y in 20..100 {
            for x in 4..116 {
                let (a, b) = (px(&plain, x, y), px(&lit, x, y));
                if a == b {
                    same += 1;
                    continue;
                }
                assert!(
                    b[0] < a[0],
                    "{draw} ({x}, {y}): {a:?} -> {b:?} is not darker"
                );
                darker += 1;
                // The near plane (grey 120, the left half) keeps its edge.
                if (a[0] - 120.0 / 255.0).abs() < 0.02 {
                    darker_near += 1;
                }
            }
        }
        // The darkened pixels: a band a few pixels wide beside the edge, on the far
        // plane; everything else (flat planes, background) exactly as without it.
        assert!(
            (80..=80 * 6).contains(&darker),
            "{draw}: {darker} darker, {same} same"
        );
        assert_eq!(darker_near, 0, "{draw}");
        // Far from the edge nothing changes: the middle of each plane.
        for (x, y) in [(20, 60), (100, 60)] {
            assert_eq!(px(&plain, x, y), px(&lit, x, y), "{draw} ({x}, {y})");
        }
    }
    // Refused where it cannot be drawn, naming the key.
    let mut faithful = scene(&dir, "points", 1.0);
    faithful.fidelity = arbvis::scene::Fidelity::Faithful;
    let e = render_on(&h, &faithful).err().unwrap().to_string();
    assert!(e.contains("edl") && e.contains("precise"), "{e}");
}
