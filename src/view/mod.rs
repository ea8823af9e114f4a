//! `btf view SCENE.toml`: the interactive garment viewer (orbit/zoom/pan, light drag,
//! environment switch and rotation, fabric switch, exposure, effect switches, a panel with
//! frame and pass costs, screenshots), and its headless relatives: the turntable export
//! (`--turntable N -o DIR`) and the interaction-latency benchmark (`--bench N`).
//!
//! - [`state`]: what is shown and what each change recomputes (no window);
//! - [`camera`]: orbit / zoom / pan and the light drag;
//! - [`env`]: the environment list and the hooks into the renderer's environment light;
//! - [`actions`], [`panel`], [`present`], [`app`]: keys, the egui panel, the frame on the
//!   surface, the winit event loop;
//! - [`turntable`]: frames for a product page, and the latency benchmark.

mod actions;
mod app;
mod camera;
mod env;
mod panel;
mod present;
mod state;
mod turntable;

use anyhow::{Context, Result, bail};
use btf_render::Scene;
use std::path::PathBuf;

/// Arguments of `btf view`.
#[derive(clap::Args, Debug, Clone)]
pub struct ViewArgs {
    /// Scene description (TOML).
    pub scene: PathBuf,
    /// Environment map (equirectangular EXR/HDR) offered in the panel; repeatable.
    #[arg(long)]
    pub env: Vec<PathBuf>,
    /// Exposure of each `--env` map's light: `auto` scales it to the horizontal irradiance
    /// of the scene's own environment (so a dim studio and a bright sky light the garment
    /// alike), `fixed` keeps the scene's factor for every map.
    #[arg(long, value_enum, default_value_t = EnvExposure::Auto)]
    pub env_exposure: EnvExposure,
    /// Frame width: of the turntable frames, and of the frame area the window opens with
    /// (the window shows frames at its own size after that). Overrides the scene.
    #[arg(long)]
    pub width: Option<u32>,
    /// Frame height (as `--width`). Overrides the scene.
    #[arg(long)]
    pub height: Option<u32>,
    /// Folder for screenshots (`p` / F12 write `shot-NNNN.png`).
    #[arg(long, default_value = ".")]
    pub shots: PathBuf,
    /// Print one line per rendered frame (change, update and render milliseconds).
    #[arg(long)]
    pub log: bool,
    /// Start with the panel hidden (`h` toggles it).
    #[arg(long)]
    pub no_panel: bool,
    /// Headless: write N frames of a full turn (camera and lights orbit together) to `-o`.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=3600))]
    pub turntable: Option<u32>,
    /// Output folder of `--turntable`.
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: Option<PathBuf>,
    /// Keep turntable frames that already exist (continue an interrupted export).
    #[arg(long)]
    pub resume: bool,
    /// Headless: time N interactions of each kind and print the latency table.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=10000))]
    pub bench: Option<u32>,
}

/// How the viewer lights the garment with a map chosen in the panel.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum EnvExposure {
    /// Same horizontal irradiance as the scene's environment.
    Auto,
    /// The scene's exposure factor for every map.
    Fixed,
}

/// Runs `btf view`.
pub fn run(args: ViewArgs) -> Result<()> {
    let mut scene = Scene::load(&args.scene)?;
    if let Some(w) = args.width {
        scene.output.width = w;
    }
    if let Some(h) = args.height {
        scene.output.height = h;
    }
    scene.validate(&args.scene)?;
    if let Some(n) = args.turntable {
        let Some(out) = &args.output else {
            bail!("--turntable {n} needs an output folder: -o DIR");
        };
        return turntable::export(&args, scene, n, out);
    }
    if let Some(n) = args.bench {
        return turntable::bench(&args, scene, n);
    }
    if args.output.is_some() {
        bail!("-o is the folder of --turntable; screenshots go to --shots DIR");
    }
    // Screenshots only add files under new names (the next free `shot-NNNN.png`), so the
    // folder may hold anything, the scene included.
    std::fs::create_dir_all(&args.shots)
        .with_context(|| format!("cannot create the screenshot folder {}", args.shots.display()))?;
    app::run(args, scene)
}
