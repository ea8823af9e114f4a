//! What an EXR header may claim before a reader allocates for it. The `exr` crate sizes
//! its read buffer for one block (a scan-line group or a tile) from the header — channels ×
//! bytes per sample × tile area or lines per block × width — before it reads that block;
//! a few hundred bytes claiming a 16384² tile or a hundred channels therefore ask for
//! gigabytes (the `raw_image` fuzz target found one: 570 bytes → a 1.4 GB allocation).
//! B44/B44A is refused too (see [`check_header`]). Every EXR reader of the workspace checks
//! each header here first.

/// Largest block (bytes, uncompressed) a header may imply: a 16384-pixel-wide RGBA `f32`
/// image in DWAB's 256-line blocks is 64 MiB; four times that is left for more channels.
pub const MAX_BLOCK_BYTES: usize = 256 << 20;

/// Most channels per layer (an RGBA image has 4; multi-layer renders a few dozen).
pub const MAX_CHANNELS: usize = 64;

/// Refuses a header whose channel count or block size is beyond the limits: `Err` holds
/// the header field at fault and what it claims (the caller adds the file).
pub fn check_header(
    h: &exr::meta::header::Header,
) -> std::result::Result<(), (&'static str, String)> {
    let channels = h.channels.list.len();
    if channels > MAX_CHANNELS {
        return Err(("channels", format!("{channels} channels, more than {MAX_CHANNELS}")));
    }
    let block = h.max_block_byte_size();
    if block > MAX_BLOCK_BYTES {
        let (field, what) = match h.blocks {
            exr::meta::BlockDescription::Tiles(t) => {
                ("tiles", format!("{} × {} pixel tiles", t.tile_size.width(), t.tile_size.height()))
            }
            exr::meta::BlockDescription::ScanLines => (
                "dataWindow",
                format!(
                    "{} pixels wide × {} lines per block",
                    h.layer_size.width(),
                    h.compression.scan_lines_per_block()
                ),
            ),
        };
        return Err((
            field,
            format!(
                "{what} of {channels} channels make {block} bytes per block, more than \
                 {MAX_BLOCK_BYTES}"
            ),
        ));
    }
    // B44/B44A: the `exr` crate's decoder panics on malformed blocks in builds with
    // overflow checks (the raw_image and envmap fuzz targets); lossy 4 × 4-block playback
    // coding is no format for measured or lighting data, so it is refused by name.
    if matches!(
        h.compression,
        exr::compression::Compression::B44 | exr::compression::Compression::B44A
    ) {
        return Err((
            "compression",
            format!(
                "{:?} (lossy playback coding; save as ZIP, PIZ or uncompressed EXR)",
                h.compression
            ),
        ));
    }
    Ok(())
}
