//! How a COPC cut arrives in the viewer's stages, against the same cut loaded whole: the
//! scene's first view is loaded (its nodes decoded into the process's cache), then the
//! camera zooms in by a factor and the new view's cut is loaded, each stage printed with
//! the time since the camera stopped.
//!
//! `cargo run --release --example copc_stages -- SCENE ZOOM BUDGET [whole]`
//! (docs/benchmarks.md: the 200 M-point outcrop at 1600x900).

use std::time::Instant;

use arbvis::catalog::TechniqueScene;
use arbvis::points::copc_load::{load, load_in_stages, Stages};
use arbvis::points::copc_lod::View;
use arbvis::points::PointSource;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: copc_stages SCENE ZOOM BUDGET [whole]");
        std::process::exit(2);
    }
    let scene = arbvis::scene::Scene::load(std::path::Path::new(&args[1])).expect("the scene");
    let zoom: f64 = args[2].parse().expect("ZOOM: a number");
    let TechniqueScene::Splats(p) = &scene.technique else {
        panic!("a splats scene")
    };
    let PointSource::Copc(spec) = &p.cloud else {
        panic!("a COPC cloud")
    };
    let mut spec = spec.clone();
    spec.points = args[3].parse().expect("BUDGET: a point count");
    let stages = if args.get(4).is_some_and(|a| a == "whole") {
        Stages::WHOLE
    } else {
        Stages::viewer()
    };
    let size = [1600, 900];
    let mut camera = scene.camera;
    let start = Instant::now();
    load(&spec, &scene.base, Some(&View::of(&camera, size))).expect("the first view");
    println!("first view: {:.3} s", start.elapsed().as_secs_f64());
    camera.zoom *= zoom;
    let view = View::of(&camera, size);
    let start = Instant::now();
    load_in_stages(
        &spec,
        &scene.base,
        Some(&view),
        stages,
        |cloud, loaded, whole| {
            println!(
                "{:.3} s: {} points in {} nodes{}",
                start.elapsed().as_secs_f64(),
                cloud.len(),
                loaded.nodes.len(),
                if whole { ", the whole cut" } else { "" }
            );
            true
        },
    )
    .expect("the zoomed view");
}
