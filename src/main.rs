//! The `arbvis` command line.
#![forbid(unsafe_code)]

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};

use arbvis::gl::{Backend, Headless, ProgramChoice, TargetFormat};
use arbvis::scene::{parse_size, Fidelity, Scene};

#[derive(Parser)]
#[command(
    name = "arbvis",
    version,
    about = "Programmable-shader-era GPU visualization, faithful and precise"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print the GL driver, its profile, ARB program support and native limits.
    Info {
        /// Offscreen backend to ask.
        #[arg(long, value_enum, default_value_t = Backend::Egl)]
        backend: Backend,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Render a scene offscreen to a PNG.
    Render {
        #[command(flatten)]
        scene: SceneArgs,
        /// Output PNG (written atomically).
        #[arg(short, long)]
        output: PathBuf,
        /// Offscreen backend.
        #[arg(long, value_enum, default_value_t = Backend::Egl)]
        backend: Backend,
        /// Print every GL resource created, with its bytes, and the timings.
        #[arg(long)]
        stats: bool,
    },
    /// Print what the loaders see in a volume file (SEG-Y, NIfTI): format, dimensions,
    /// inline/crossline/sample ranges, sample type, byte order, value statistics.
    Inspect {
        /// A `.sgy`/`.segy` or `.nii`/`.nii.gz` file.
        file: PathBuf,
    },
    /// Open the desktop viewer (winit + glutin + egui).
    #[cfg(feature = "viewer")]
    View {
        #[command(flatten)]
        scene: SceneArgs,
        /// Folder for screenshots (default: current folder).
        #[arg(long, default_value = ".")]
        screenshot_dir: PathBuf,
        /// Run a script of UI actions, one per line (see `arbvis::viewer::script`), then exit.
        #[arg(long)]
        script: Option<PathBuf>,
    },
}

/// Where the scene comes from and what overrides it.
#[derive(Args)]
struct SceneArgs {
    /// Scene file (TOML).
    scene: Option<PathBuf>,
    /// A built-in demo instead of a file (e.g. `quad`).
    #[arg(long, conflicts_with = "scene")]
    demo: Option<String>,
    /// Image size, e.g. 512x512.
    #[arg(long, value_parser = parse_size)]
    size: Option<[u32; 2]>,
    /// Program kind: arb, glsl, or auto (ARB where the driver has it).
    #[arg(long, value_enum)]
    programs: Option<ProgramChoice>,
    /// Faithful (original programs, 8-bit) or precise (corrected, float).
    #[arg(long, value_enum)]
    fidelity: Option<Fidelity>,
    /// Colour target precision (default from fidelity).
    #[arg(long, value_enum)]
    target: Option<TargetFormat>,
}

impl SceneArgs {
    /// The scene and a name for where it came from.
    fn load(&self) -> Result<(Scene, String)> {
        let (mut scene, origin) = match (&self.scene, &self.demo) {
            (Some(path), _) => (Scene::load(path)?, path.display().to_string()),
            (None, Some(name)) => (Scene::demo(name)?, format!("demo:{name}")),
            (None, None) => bail!("name a scene file or --demo NAME"),
        };
        if let Some(s) = self.size {
            scene.size = s;
        }
        if let Some(p) = self.programs {
            scene.programs = p;
        }
        if let Some(f) = self.fidelity {
            scene.fidelity = f;
        }
        if let Some(t) = self.target {
            scene.target = Some(t);
        }
        Ok((scene, origin))
    }
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("arbvis: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Info { backend, json } => {
            let headless = Headless::new(backend)?;
            let caps = headless.gpu().caps();
            if json {
                println!("{}", serde_json_like(caps));
            } else {
                print!("{}", arbvis::info::format_info(backend, caps));
            }
        }
        Command::Render {
            scene,
            output,
            backend,
            stats,
        } => {
            let (scene, origin) = scene.load()?;
            let rendered = arbvis::render::render(&scene, backend)
                .with_context(|| format!("rendering {origin}"))?;
            arbvis::png_io::write_png(
                &output,
                &rendered.image,
                &rendered.png_text(&scene, &origin),
            )?;
            println!(
                "wrote {} ({}x{}, {} programs, {} target, {} on {})",
                output.display(),
                scene.size[0],
                scene.size[1],
                rendered.program_kind.name(),
                scene.target_format().name(),
                rendered.caps.renderer,
                backend.name()
            );
            if stats {
                print!("{}", arbvis::render::format_stats(&rendered.resources));
                println!(
                    "build {:.3} ms, draw {:.3} ms",
                    rendered.build_time.as_secs_f64() * 1e3,
                    rendered.draw_time.as_secs_f64() * 1e3
                );
            }
        }
        Command::Inspect { file } => {
            print!("{}", arbvis::volume::inspect(&file)?);
        }
        #[cfg(feature = "viewer")]
        Command::View {
            scene,
            screenshot_dir,
            script,
        } => {
            let (scene, origin) = scene.load()?;
            let script = match script {
                Some(p) => Some(arbvis::viewer::script::Script::load(&p)?),
                None => None,
            };
            arbvis::viewer::run(arbvis::viewer::ViewerOptions {
                scene,
                origin,
                screenshot_dir,
                script,
            })?;
        }
    }
    Ok(())
}

/// Caps as JSON (flat; no JSON crate needed for this one record).
fn serde_json_like(caps: &arbvis::gl::Caps) -> String {
    toml::to_string(caps)
        .map(|t| {
            let fields: Vec<String> = t
                .lines()
                .filter_map(|l| l.split_once(" = "))
                .map(|(k, v)| format!("\"{k}\": {v}"))
                .collect();
            format!("{{{}}}", fields.join(", "))
        })
        .unwrap_or_default()
}
