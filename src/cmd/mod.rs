//! One module per subcommand of `btf`: its arguments (clap) and its `run`.

pub mod capture;
pub mod compress;
pub mod demo;
pub mod export;
pub mod garment;
pub mod import;
pub mod inspect;
pub mod knit;
pub mod knit_animate;
pub mod knit_compare;
pub mod knit_compare_report;
pub mod knit_deform;
pub mod knit_deform_drape;
pub mod knit_lumislice;
pub mod knit_render;
pub mod knit_strips;
pub mod knit_sweep;
pub mod knit_sweep_report;
pub mod reconstruct;
pub mod registration_sweep;
pub mod relight;
pub mod render;
pub mod render_sweep;
pub mod shards;
pub mod synth;
pub mod thin;
