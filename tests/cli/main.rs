//! End-to-end tests of the `btf` binary, one module per area, run in temporary folders
//! through the small harness of [`common`] (ripgrep's habit): the commands and their
//! contracts ([`commands`]), synthesis, capture processing, import/export, rendering,
//! relighting, thin cloth, the stores as zarr-python reads them ([`python`]), the demo, the viewer under Xvfb, ARCHITECTURE.md's equation index
//! against the code ([`docs`]), and the hostile suite of issue
//! #26 ([`hostile`]: what a command may never do to files, whatever the input), and
//! sharded jobs of issue #23 ([`shards`]: 4 concurrent shards, one killed; [`dask_jobs`]:
//! the same through the Python driver on Dask).

mod common;

mod capture;
mod commands;
mod dask_jobs;
mod demo;
mod docs;
mod garment;
mod hostile;
mod import_export;
mod knit;
mod knit_motion;
mod knit_sweep;
mod python;
mod relight;
mod render;
mod render_yarns;
mod shards;
mod synth;
mod thin;
mod view;
