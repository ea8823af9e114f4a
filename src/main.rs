//! The `btf` command-line tool: parses arguments into validated configurations and calls
//! the libraries (`btf-core`, `btf-image`, `btf-light`, `datasets`, `btf-capture`,
//! `btf-render`). Glue only: one file per command in [`cmd`], shared arguments in
//! [`args`], report writers in [`report`], the two demos in [`demo`], the viewer in
//! [`view`]. The flag naming scheme every command follows is `docs/cli.md`.

mod args;
mod cmd;
mod demo;
mod guard;
mod progress;
#[cfg(test)]
mod readme_commands;
mod report;
mod scene_yarns;
mod view;

use cmd::{
    capture, compress, demo as demo_cmd, export, import, inspect, knit, reconstruct, relight,
    render, render_sweep, shards, synth, thin,
};

use clap::{CommandFactory, Parser, Subcommand};
use std::process::ExitCode;

/// Capture processing, PCA compression and rendering of bidirectional texture functions.
#[derive(Parser)]
#[command(name = "btf", version, about, propagate_version = true)]
pub(crate) struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the whole pipeline on embedded defaults: synthesise, compress, render, report.
    Demo(demo_cmd::DemoArgs),
    /// Synthesise materials, environments, meshes and raw captures with known ground truth.
    #[command(subcommand)]
    Synth(synth::SynthCmd),
    /// Print what a BTF or eigen store holds.
    Inspect(inspect::InspectArgs),
    /// Compress a BTF store by per-view-slot PCA (or sweep the number of components).
    Compress(compress::CompressArgs),
    /// Reconstruct the texture for one view and one light direction on the CPU.
    Reconstruct(reconstruct::ReconstructArgs),
    /// Process raw captures into normtextures and score them against ground truth.
    #[command(subcommand)]
    Capture(capture::CaptureCmd),
    /// Import Bonn-database BTFs (UBO2003 image folders, UBO2014 `.btf` files).
    #[command(subcommand)]
    Import(import::ImportCmd),
    /// Export data for other tools.
    Export(export::ExportArgs),
    /// Render a scene (TOML) on the GPU.
    Render(render::RenderArgs),
    /// Time the renderer against plain texturing and its read bound over components × modes.
    RenderSweep(render_sweep::RenderSweepArgs),
    /// Render a scene under several environment maps and rotations (batch relighting).
    Relight(relight::RelightArgs),
    /// Which shards, frames or view slots of a sharded job are done, missing or corrupt.
    Status(shards::StatusArgs),
    /// Finish a sharded job once every shard is done (commit the store, merge summaries).
    Finalize(shards::FinalizeArgs),
    /// Knit and yarn: charts, stitch meshes, yarn skeletons, fibers, reference renders.
    #[command(subcommand)]
    Knit(knit::KnitCmd),
    /// Thin semi-transparent cloth: check the slab model against Monte Carlo.
    #[command(subcommand)]
    Thin(thin::ThinCmd),
    /// Inspect a garment interactively (window), or export a turntable (headless).
    View(view::ViewArgs),
    /// Print a shell completion script (e.g. `btf completions bash > /etc/bash_completion.d/btf`).
    Completions(CompletionsArgs),
}

/// Arguments of `btf completions`.
#[derive(clap::Args)]
struct CompletionsArgs {
    /// The shell.
    shell: clap_complete::Shell,
}

/// The completion script of `btf` for `shell`.
fn completions(shell: clap_complete::Shell) -> String {
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "btf", &mut script);
    String::from_utf8_lossy(&script).into_owned()
}

/// Mesa's `VK_LAYER_MESA_device_select` layer, which the Vulkan loader puts in front of
/// every driver, asks Wayland for the session's GPU and, without `XDG_RUNTIME_DIR` (in
/// containers, CI, ssh sessions), has libwayland print `error: XDG_RUNTIME_DIR is invalid or
/// not set` twice per device enumeration — noise that reads like a failure of the command.
/// Without a runtime directory there is no Wayland session whose GPU it could pick, so the
/// layer is switched off (`NODEVICE_SELECT=1`) unless the user set that variable.
#[allow(unsafe_code)]
fn quiet_vulkan_device_select() {
    let runtime_dir = std::env::var_os("XDG_RUNTIME_DIR");
    let no_session = runtime_dir.is_none_or(|d| !std::path::Path::new(&d).is_dir());
    if no_session && std::env::var_os("NODEVICE_SELECT").is_none() {
        // SAFETY: the first statement of `main`, before any thread exists, so nothing can
        // read the environment concurrently.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}

fn main() -> ExitCode {
    quiet_vulkan_device_select();
    // A `BTF_SIMD` this CPU cannot run is refused here, before any kernel would panic on it.
    if let Err(e) = btf_core::simd::Isa::from_env() {
        eprintln!("error: {e}");
        return ExitCode::from(2);
    }
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(a) => demo_cmd::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Compress(a) => compress::run(a),
        Command::Reconstruct(a) => reconstruct::run(a),
        Command::Capture(c) => capture::run(c),
        Command::Import(c) => import::run(c),
        Command::Export(a) => export::run(a),
        Command::Synth(c) => synth::run(c),
        Command::Render(a) => render::run(a),
        Command::RenderSweep(a) => render_sweep::run(a),
        Command::Relight(a) => relight::run(a),
        Command::Status(a) => shards::run_status(a),
        Command::Finalize(a) => shards::run_finalize(a),
        Command::Knit(c) => knit::run(c),
        Command::Thin(c) => thin::run(c),
        Command::View(a) => view::run(a),
        Command::Completions(a) => {
            guard::outln!("{}", completions(a.shell).trim_end());
            Ok(())
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every subcommand, at every depth, as its path of names (`["synth", "material"]`).
    fn subcommands(cmd: &clap::Command, path: Vec<String>, out: &mut Vec<Vec<String>>) {
        for sub in cmd.get_subcommands() {
            let mut p = path.clone();
            p.push(sub.get_name().to_string());
            out.push(p.clone());
            subcommands(sub, p, out);
        }
    }

    #[test]
    fn the_bash_completions_name_every_subcommand() {
        let script = completions(clap_complete::Shell::Bash);
        let mut all = Vec::new();
        subcommands(&Cli::command(), Vec::new(), &mut all);
        assert!(all.len() > 25, "{} subcommands", all.len());
        for path in all {
            // clap_complete's bash script selects each command path by a line
            // `cmd="btf__subcmd__capture__subcmd__registration__subcmd__sweep"`.
            let case = format!("cmd=\"btf__subcmd__{}\"", path.join("__subcmd__"))
                .replace('-', "__subcmd__");
            assert!(script.contains(&case), "the bash script lacks {case}");
        }
    }

    #[test]
    fn the_command_line_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
