//! The `btf` command-line tool: parses arguments into validated configurations and calls
//! the libraries (`btf-core`, `datasets`, `btf-capture`, `btf-render`). No numerics live here.

mod cmd_capture;
mod cmd_compress;
mod cmd_demo;
mod cmd_export;
mod cmd_import;
mod cmd_inspect;
mod cmd_reconstruct;
mod cmd_relight;
mod cmd_thin;
mod demo_scene;
mod guard;
mod progress;
mod registration_sweep;
mod relight_report;
mod render_cmd;
mod render_sweep;
mod sweep;
mod synth_cmd;
mod thin_demo;
mod thin_demo_material;
mod thin_demo_report;
mod view;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Capture processing, PCA compression and rendering of bidirectional texture functions.
#[derive(Parser)]
#[command(name = "btf", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the whole pipeline on embedded defaults: synthesise, compress, render, report.
    Demo(cmd_demo::DemoArgs),
    /// Synthesise materials, environments, meshes and raw captures with known ground truth.
    #[command(subcommand)]
    Synth(synth_cmd::SynthCmd),
    /// Print what a BTF or eigen store holds.
    Inspect(cmd_inspect::InspectArgs),
    /// Compress a BTF store by per-view-slot PCA (or sweep the number of components).
    Compress(cmd_compress::CompressArgs),
    /// Reconstruct the texture for one view and one light direction on the CPU.
    Reconstruct(cmd_reconstruct::ReconstructArgs),
    /// Process raw captures into normtextures and score them against ground truth.
    #[command(subcommand)]
    Capture(cmd_capture::CaptureCmd),
    /// Import Bonn-database BTFs (UBO2003 image folders, UBO2014 `.btf` files).
    #[command(subcommand)]
    Import(cmd_import::ImportCmd),
    /// Export data for other tools.
    Export(cmd_export::ExportArgs),
    /// Render a scene (TOML) on the GPU.
    Render(render_cmd::RenderArgs),
    /// Time the renderer against plain texturing and its read bound over components × modes.
    RenderSweep(render_sweep::RenderSweepArgs),
    /// Render a scene under several environment maps and rotations (batch relighting).
    Relight(cmd_relight::RelightArgs),
    /// Thin semi-transparent cloth: check the slab model against Monte Carlo.
    #[command(subcommand)]
    Thin(cmd_thin::ThinCmd),
    /// Inspect a garment interactively (window), or export a turntable (headless).
    View(view::ViewArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(a) => cmd_demo::run(a),
        Command::Inspect(a) => cmd_inspect::run(a),
        Command::Compress(a) => cmd_compress::run(a),
        Command::Reconstruct(a) => cmd_reconstruct::run(a),
        Command::Capture(c) => cmd_capture::run(c),
        Command::Import(c) => cmd_import::run(c),
        Command::Export(a) => cmd_export::run(a),
        Command::Synth(c) => synth_cmd::run(c),
        Command::Render(a) => render_cmd::run(a),
        Command::RenderSweep(a) => render_sweep::run(a),
        Command::Relight(a) => cmd_relight::run(a),
        Command::Thin(c) => cmd_thin::run(c),
        Command::View(a) => view::run(a),
    };
    match result {
        Ok(()) => {
            guard::flush_stdout();
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
