//! Progress bars for long work (hidden when standard error is not a terminal or when
//! `BTF_NO_PROGRESS` is set, so logs and tests stay clean).

use anyhow::{Context, Result};
use btf_core::compress::{CompressParams, CompressReport, compress};
use btf_core::store::BtfStore;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::Path;

/// A bar of `len` steps labelled `what`.
pub fn bar(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    if !enabled() {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    pb.set_style(
        ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta})")
            .expect("static template")
            .progress_chars("=> "),
    );
    pb.set_message(what.to_owned());
    pb
}

/// Runs `work` with a bar labelled `what` that it moves by calling `progress(done, total)`
/// (the total is learnt from the first call); the bar is cleared afterwards.
pub fn counted<T>(what: &str, work: impl FnOnce(&dyn Fn(usize, usize)) -> T) -> T {
    let pb = bar(0, what);
    let out = work(&|done, total| {
        pb.set_length(total as u64);
        pb.set_position(done as u64);
    });
    pb.finish_and_clear();
    out
}

/// A testing aid for the kill-and-restart tests of sharded jobs (issue #23): with
/// `BTF_TEST_UNIT_DELAY_MS=N` set, every finished unit of a shard (a frame, a view slot)
/// is followed by a pause of N ms, so that a test can kill a shard in the middle of its
/// work at a point it observes. Never set in normal use.
pub fn unit_delay() {
    static DELAY: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    let ms = *DELAY.get_or_init(|| {
        std::env::var("BTF_TEST_UNIT_DELAY_MS").ok().and_then(|v| v.parse().ok()).unwrap_or(0)
    });
    if ms > 0 {
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
}

/// True when progress bars should be drawn.
pub fn enabled() -> bool {
    std::env::var_os("BTF_NO_PROGRESS").is_none()
        && std::io::IsTerminal::is_terminal(&std::io::stderr())
}

/// Compresses with a progress bar.
pub fn compress_with_progress(
    input: &BtfStore,
    output: &Path,
    params: CompressParams,
) -> Result<CompressReport> {
    let pb = bar(input.meta().n_views() as u64, "compress");
    let r = compress(input, output, params, &|| pb.inc(1)).with_context(|| {
        format!("compressing {} into {}", input.path().display(), output.display())
    })?;
    pb.finish_and_clear();
    Ok(r)
}
