//! The measurements of issue 19 on a large synthetic survey (never run by the tests;
//! `benches/store/run.sh` drives it):
//!
//! - `generate OUT.sgy NS NX NI`: a seismic-like survey of NI inlines x NX crosslines x NS
//!   samples (reflectors folded over the survey, two normal faults, a Ricker wavelet,
//!   noise; deterministic) written trace by trace with arbvis's SEG-Y writer
//!   ([`arbvis::volume::segy::TraceWriter`], IEEE float), inlines generated in parallel.
//! - `view STORE WxH [precise]`: open-to-first-picture, frames while turning at interactive quality
//!   (half the window's side, 1° a frame), the full-quality picture's time after the turn
//!   stops, the process's peak memory; the same turning frames of the 256³ demo
//!   (`scenes/bench/v3o2-sum-256.toml`, three attributes) at the same size, camera, slice
//!   count and fidelity, interleaved; a picture of the survey.
//!   `precise`: the one-pass ray caster through the page table (the demo then ray casts
//!   too, without jitter, as the page table's ray caster does).
//! - `first STORE WxH`: open to first picture (the viewer's path: streaming, the coarsest
//!   level standing in until finer bricks arrive) and on to the full-quality picture, with
//!   what a remote store (`STORE` a URL) fetched by each: `benches/remote/run.sh`.
//! - `error STORE N`: on a window of N³ voxels at the survey's centre, the f64 reference
//!   integral of the full-resolution data against each LOD policy (RMSE and max, RGB),
//!   faithful and precise.

use std::io::BufWriter;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use arbvis::gl::{Backend, Headless, Surface, Target};
use arbvis::scene::Scene;
use arbvis::techniques::Frame;
use arbvis::volume::segy::{SampleFormat, TraceWriter, WriteOptions};
use arbvis::volume::synthetic::{ricker, SplitMix};
use rayon::prelude::*;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("generate") if args.len() == 5 => {
            let n: Vec<usize> = args[2..5]
                .iter()
                .map(|a| a.parse())
                .collect::<Result<_, _>>()?;
            generate(&args[1], [n[0], n[1], n[2]])
        }
        Some("view") if args.len() == 3 => view(&args[1], &args[2], false),
        Some("view") if args.len() == 4 && args[3] == "precise" => view(&args[1], &args[2], true),
        Some("error") if args.len() == 3 => error(&args[1], args[2].parse()?),
        Some("first") if args.len() == 3 => first(&args[1], &args[2]),
        _ => bail!("usage: store_bench generate OUT.sgy NS NX NI | view STORE WxH [precise] | error STORE N | first STORE WxH"),
    }
}

/// The survey's structure: layers (depth, reflection coefficient), folds, faults.
struct Geology {
    layers: Vec<(f64, f64)>,
    fold: [f64; 4],
    faults: [(f64, f64, f64); 3],
    wavelet: Vec<f64>,
    half: i64,
}

impl Geology {
    fn new(ns: usize) -> Geology {
        let mut rng = SplitMix::new(19);
        let layers = 12 + ns / 5;
        let layers = (0..layers)
            .map(|b| {
                let depth = (b as f64 + 0.5 + 0.7 * (rng.next_f64() - 0.5)) / layers as f64;
                let r = (rng.next_f64() * 2.0 - 1.0).signum() * (0.2 + 0.8 * rng.next_f64());
                (depth, r)
            })
            .collect();
        let fold = [0, 1, 2, 3].map(|_| rng.next_f64() * 6.0);
        let faults = [
            (0.3 + 0.1 * rng.next_f64(), 0.6, 0.04),
            (0.55 + 0.1 * rng.next_f64(), -0.4, -0.03),
            (0.8, 0.2, 0.05),
        ];
        // Ricker of 6 cycles per 100 samples, cut at 1.5 periods.
        let f: f64 = 0.06;
        let half = (1.5 / f).ceil() as i64;
        let wavelet = (-half..=half).map(|t| ricker(t as f64, f)).collect();
        Geology {
            layers,
            fold,
            faults,
            wavelet,
            half,
        }
    }

    /// The trace at (x, y) in [0, 1)², noise from `seed`.
    fn trace(&self, x: f64, y: f64, seed: u64, out: &mut [f32]) {
        let ns = out.len();
        let f = &self.fold;
        let mut shift = 0.06 * (f[0] + 9.0 * x).sin() * (f[1] + 7.0 * y).cos()
            + 0.03 * (f[2] + 23.0 * x + 11.0 * y).sin()
            + 0.08 * x
            - 0.05 * y;
        for &(at, slope, throw) in &self.faults {
            if x + slope * (y - 0.5) > at {
                shift += throw;
            }
        }
        out.iter_mut().for_each(|v| *v = 0.0);
        for (n, &(depth, r)) in self.layers.iter().enumerate() {
            // Deeper layers fold more; each one thins a little across the survey.
            let s =
                (depth + shift * (0.5 + depth) + 0.01 * (n as f64 * 0.7 + f[3] + 3.0 * y).sin())
                    * ns as f64;
            // Sub-sample placement: the spike split between the two nearest samples.
            let s0 = s.floor();
            for (at, weight) in [(s0 as i64, 1.0 - (s - s0)), (s0 as i64 + 1, s - s0)] {
                for (w, &a) in self.wavelet.iter().enumerate() {
                    let i = at + w as i64 - self.half;
                    if (0..ns as i64).contains(&i) {
                        out[i as usize] += (r * weight * a) as f32;
                    }
                }
            }
        }
        let mut rng = SplitMix::new(seed);
        for v in out.iter_mut() {
            *v += (0.04 * (rng.next_f64() * 2.0 - 1.0)) as f32;
        }
    }
}

fn generate(path: &str, [ns, nx, ni]: [usize; 3]) -> Result<()> {
    let t0 = Instant::now();
    let g = Geology::new(ns);
    let o = WriteOptions {
        format: SampleFormat::IeeeFloat,
        big_endian: true,
        revision: 1,
        first_inline: 1000,
        first_crossline: 500,
        interval_us: 4000,
    };
    let file = std::fs::File::create(path).with_context(|| path.to_string())?;
    let mut w = TraceWriter::new(BufWriter::with_capacity(8 << 20, file), o, ns)?;
    // Eight inlines at a time in parallel, written in order.
    let batch = 8;
    let mut k = 0;
    while k < ni {
        let ks: Vec<usize> = (k..(k + batch).min(ni)).collect();
        let traces: Vec<Vec<Vec<f32>>> = ks
            .par_iter()
            .map(|&kk| {
                (0..nx)
                    .map(|j| {
                        let mut t = vec![0f32; ns];
                        g.trace(
                            j as f64 / nx as f64,
                            kk as f64 / ni as f64,
                            (kk * nx + j) as u64,
                            &mut t,
                        );
                        t
                    })
                    .collect()
            })
            .collect();
        for (kk, line) in ks.iter().zip(traces) {
            for (j, t) in line.iter().enumerate() {
                w.trace(*kk, j, t)?;
            }
        }
        k += batch;
        if k % 256 < batch {
            eprintln!("{k}/{ni} inlines, {:.0} s", t0.elapsed().as_secs_f64());
        }
    }
    w.finish()?;
    let bytes = std::fs::metadata(path)?.len();
    println!(
        "generated {path}: {ns} samples x {nx} crosslines x {ni} inlines, {:.2} GB in {:.1} s",
        bytes as f64 / 1e9,
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn store_scene(store: &str, size: [u32; 2], extra: &str) -> Result<Scene> {
    let text = format!(
        r#"size = [{}, {}]
background = [0.0, 0.0, 0.0, 1.0]
[camera]
rotation = [0.2241, -0.3696, 0.0747, 0.8986]
[technique.opacity3d]
slices = 256
[technique.opacity3d.primary]
volume = {{ store = "{store}" }}
attribute = "amplitude"
table = {{ builtin = "seismic", alpha = [[0.0, 0.8], [0.4, 0.0], [0.6, 0.0], [1.0, 0.8]] }}
[technique.opacity3d.store]
{extra}
"#,
        size[0], size[1]
    );
    Ok(Scene::parse(&text, "store_bench")?)
}

/// `scene` drawn precisely: GLSL, the point-sampling ray caster without jitter (the page
/// table's ray caster has none).
fn make_precise(scene: &mut Scene) {
    scene.fidelity = arbvis::vocab::Fidelity::Precise;
    scene.programs = arbvis::gl::ProgramChoice::Glsl;
    if let arbvis::scene::TechniqueScene::Opacity3d(p) = &mut scene.technique {
        p.raycast = Some(arbvis::techniques::opacity3d::Raycast {
            jitter: false,
            bake: false,
            ..Default::default()
        });
    }
}

fn parse_size(s: &str) -> Result<[u32; 2]> {
    let (w, h) = s.split_once('x').context("size WxH")?;
    Ok([w.parse()?, h.parse()?])
}

fn turned(scene: &Scene, degrees: f64) -> arbvis::camera::Camera {
    let mut c = scene.camera;
    let q = glam::DQuat::from_rotation_y(degrees.to_radians()) * c.quat();
    c.rotation = q.to_array();
    c
}

fn first(store: &str, size: &str) -> Result<()> {
    let size = parse_size(size)?;
    let h = Headless::new(Backend::Egl)?;
    let gpu = h.gpu();
    let scene = store_scene(store, size, "gpu_memory = \"512M\"")?;
    let target = Target::create(gpu, size[0], size[1], scene.target_format(), false)?;
    let frame = Frame {
        camera: scene.camera,
        width: size[0],
        height: size[1],
    };
    let t0 = Instant::now();
    let mut r = arbvis::render::build(gpu, &scene, scene.programs.resolve(gpu))?;
    r.set_streaming(true);
    let mut first = None;
    for frames in 1.. {
        target.clear(gpu, scene.clear_colour())?;
        r.draw(gpu, Surface::Target(&target), &frame)?;
        gpu.finish();
        let status = r.status().unwrap_or_default();
        let f = arbvis::fetch::stats();
        if first.is_none() && !status.contains("; 0 drawn") {
            first = Some(());
            println!(
                "first picture: {:.3} s, {frames} frames; {status}; fetched {} requests, {} bytes",
                t0.elapsed().as_secs_f64(),
                f.requests,
                f.bytes
            );
        }
        if first.is_some() && !status.contains("loading") {
            println!(
                "full picture: {:.3} s, {frames} frames; {status}; fetched {} requests, {} bytes",
                t0.elapsed().as_secs_f64(),
                f.requests,
                f.bytes
            );
            break;
        }
        if t0.elapsed().as_secs() > 600 {
            bail!("no full picture in 10 minutes: {status}");
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    Ok(())
}

fn view(store: &str, size: &str, precise: bool) -> Result<()> {
    let size = parse_size(size)?;
    let half = [size[0] / 2, size[1] / 2];
    let h = Headless::new(Backend::Egl)?;
    let gpu = h.gpu();
    let mut scene = store_scene(store, size, "gpu_memory = \"512M\"")?;
    if precise {
        make_precise(&mut scene);
    }
    println!("fidelity: {:?}", scene.fidelity);
    let kind = scene.programs.resolve(gpu);
    let target = Target::create(gpu, size[0], size[1], scene.target_format(), false)?;
    let small = Target::create(gpu, half[0], half[1], scene.target_format(), false)?;
    // Open to first picture: open, build, stream until a frame draws some brick.
    let t0 = Instant::now();
    let mut r = arbvis::render::build(gpu, &scene, kind)?;
    r.set_streaming(true);
    let mut frames = 0;
    loop {
        target.clear(gpu, scene.clear_colour())?;
        let frame = Frame {
            camera: scene.camera,
            width: size[0],
            height: size[1],
        };
        r.draw(gpu, Surface::Target(&target), &frame)?;
        gpu.finish();
        frames += 1;
        let status = r.status().unwrap_or_default();
        if !status.contains("; 0 drawn") {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let first = t0.elapsed().as_secs_f64();
    println!("open to first picture: {:.3} s ({frames} frames)", first);
    // Turning at interactive quality (half the side), 1° a frame, interleaved with the
    // 256³ demo at the same size.
    // Today's 256³ demo (scenes/bench/v3o2-sum-256.toml: three attributes, sum) at the
    // store scene's window, camera and slice count, at the same fidelity.
    let mut demo = Scene::load(std::path::Path::new("scenes/bench/v3o2-sum-256.toml"))?;
    demo.size = half;
    demo.camera = scene.camera;
    demo.fidelity = arbvis::vocab::Fidelity::Faithful;
    if let (
        arbvis::scene::TechniqueScene::Opacity3d(d),
        arbvis::scene::TechniqueScene::Opacity3d(s),
    ) = (&mut demo.technique, &scene.technique)
    {
        d.slices = s.slices;
    }
    if precise {
        make_precise(&mut demo);
    }
    let mut dr = arbvis::render::build(gpu, &demo, demo.programs.resolve(gpu))?;
    let (mut store_ms, mut demo_ms) = (Vec::new(), Vec::new());
    for step in 0..40 {
        let camera = turned(&scene, step as f64);
        let frame = Frame {
            camera,
            width: half[0],
            height: half[1],
        };
        let t = Instant::now();
        small.clear(gpu, scene.clear_colour())?;
        r.draw(gpu, Surface::Target(&small), &frame)?;
        gpu.finish();
        store_ms.push(t.elapsed().as_secs_f64() * 1e3);
        let dframe = Frame {
            camera: turned(&demo, step as f64),
            width: half[0],
            height: half[1],
        };
        let t = Instant::now();
        small.clear(gpu, demo.clear_colour())?;
        dr.draw(gpu, Surface::Target(&small), &dframe)?;
        gpu.finish();
        demo_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (s, d) = (median(&mut store_ms), median(&mut demo_ms));
    println!(
        "turning at {}x{} (interactive, half of {}x{}): store {s:.1} ms, 256³ demo (v3o2-sum-256) {d:.1} ms, ratio {:.2}",
        half[0], half[1], size[0], size[1], s / d
    );
    println!("{}", r.status().unwrap_or_default());
    // The camera stops: full-size frames until nothing is pending.
    let camera = turned(&scene, 40.0);
    let frame = Frame {
        camera,
        width: size[0],
        height: size[1],
    };
    let t = Instant::now();
    let mut frames = 0;
    loop {
        target.clear(gpu, scene.clear_colour())?;
        r.draw(gpu, Surface::Target(&target), &frame)?;
        gpu.finish();
        frames += 1;
        // Two minutes at most: a store without levels larger than the GPU budget never
        // holds the whole picture at once (offscreen `render` draws it in batches).
        if !r.pending() || frames > 5000 || t.elapsed().as_secs() > 120 {
            break;
        }
    }
    println!(
        "full quality after the camera stops: {:.2} s ({frames} frames){}",
        t.elapsed().as_secs_f64(),
        if r.pending() {
            ", NOT REACHED: bricks still wanted"
        } else {
            ""
        }
    );
    println!("{}", r.status().unwrap_or_default());
    let image = target.read(gpu)?;
    let mut picture_scene = scene.clone();
    picture_scene.camera = camera;
    let out =
        std::path::Path::new(store).with_extension(if precise { "precise.png" } else { "png" });
    arbvis::png_io::write_png(&out, &picture_scene.picture(&image), &[])?;
    println!("picture: {}", out.display());
    println!("peak memory while viewing: {:.0} MB", peak_rss_mb());
    Ok(())
}

fn error(store: &str, n: usize) -> Result<()> {
    use arbvis::techniques::opacity3d::prepare::from_volumes;
    use arbvis::techniques::opacity3d::reference::reference;
    use arbvis::volume::quantize::Quantization;
    let s = arbvis::store::Store::open(std::path::Path::new(store))?;
    let d = s.meta.dims;
    let lo: [usize; 3] = std::array::from_fn(|a| d[a].saturating_sub(n) / 2);
    let hi: [usize; 3] = std::array::from_fn(|a| (lo[a] + n).min(d[a]));
    let window = s.window(0, lo, hi)?;
    let am = &s.meta.attributes[0];
    let range = Quantization::Range([am.min.unwrap_or(0.0), am.max.unwrap_or(1.0)]);
    let size = [256u32, 256];
    let extra = format!("window = [{lo:?}, {hi:?}]\ngpu_memory = \"1G\"\n");
    let base = store_scene(store, size, &extra)?;
    let arbvis::scene::TechniqueScene::Opacity3d(params) = &base.technique else {
        unreachable!()
    };
    let mut params = params.clone();
    params.primary.quantize = range;
    let table = params
        .primary
        .table
        .build(std::path::Path::new("."))
        .map_err(anyhow::Error::msg)?;
    let prepared =
        from_volumes([Some((&window, range, table)), None, None]).map_err(anyhow::Error::msg)?;
    let t = Instant::now();
    let reference = reference(
        &prepared,
        &params,
        &base.camera,
        size,
        [0.0, 0.0, 0.0, 1.0],
        4.0,
    );
    println!(
        "window {lo:?}..{hi:?}: reference in {:.1} s",
        t.elapsed().as_secs_f64()
    );
    if let Some(codec) = s.lossy() {
        println!(
            "the reference is of the decoded values: the survey was compressed lossily ({codec})"
        );
    }
    let h = Headless::new(Backend::Egl)?;
    let policies = [
        ("level 0", "level = 0"),
        ("level 1", "level = 1"),
        ("level 2", "level = 2"),
        ("full quality (1 px)", "pixels = 1.0"),
        ("interactive (2 px)", "pixels = 2.0"),
        ("interactive (4 px)", "pixels = 4.0"),
    ];
    for (precise, (name, policy)) in [false, true]
        .into_iter()
        .flat_map(|p| policies.iter().map(move |x| (p, x)))
    {
        let mut scene = store_scene(store, size, &format!("{extra}{policy}\n"))?;
        if precise {
            make_precise(&mut scene);
        }
        let name = format!("{} {name}", if precise { "precise" } else { "faithful" });
        if let arbvis::scene::TechniqueScene::Opacity3d(p) = &mut scene.technique {
            p.primary.quantize = range;
        }
        let t = Instant::now();
        let r = arbvis::render::render_on(&h, &scene)?;
        let (mut sq, mut max, mut count) = (0.0f64, 0.0f64, 0usize);
        for y in 0..size[1] {
            for x in 0..size[0] {
                let a = r.image.pixel_u8(x, y);
                let b = reference.pixel_u8(x, y);
                for c in 0..3 {
                    let e = (a[c] as f64 - b[c] as f64).abs() / 255.0;
                    sq += e * e;
                    max = max.max(e);
                    count += 1;
                }
            }
        }
        println!(
            "{name}: RMSE {:.4}, max {:.3} ({:.2} s; {})",
            (sq / count as f64).sqrt(),
            max,
            t.elapsed().as_secs_f64(),
            r.status.unwrap_or_default()
        );
    }
    Ok(())
}
