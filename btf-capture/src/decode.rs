//! Bounded image decoding for every image a user hands this crate (raw captures, UBO2003
//! folders and zips): the size a header claims is read and checked against
//! [`MAX_PIXELS`] before any pixel is allocated, EXR pixels go into rows allocated as they
//! are decoded ([`btf_core::memory::LazyRows`]) so a tiny file claiming a huge image costs
//! nothing, and the `image` crate's allocation limit is reported with the file and field.

use crate::{Error, Result};
use btf_core::memory::LazyRows;
use std::io::{BufRead, Read, Seek};

/// Largest image accepted, in pixels: 16384², the largest camera `capture.toml` allows.
pub const MAX_PIXELS: u64 = 1 << 28;

/// Largest decoded image (bytes) a PNG/TIFF/… header may ask for: a 16-bit RGBA image of
/// 8192 × 8192 pixels.
pub const MAX_DECODED_BYTES: u64 = 512 << 20;

/// Most pixels a compressed image may claim per byte of file (see [`decode_image`]).
pub const MAX_PIXELS_PER_BYTE: u64 = 4096;

/// Refuses an empty image or one beyond [`MAX_PIXELS`]; `field` names the header field.
pub fn check_pixels(file: &str, field: &str, w: u64, h: u64) -> Result<()> {
    if w == 0 || h == 0 || w.saturating_mul(h) > MAX_PIXELS {
        return Err(Error::limit(
            file,
            field,
            format!("{w} x {h} pixels is empty or more than {MAX_PIXELS}"),
        ));
    }
    Ok(())
}

/// The size of every layer of an EXR from its header, each checked with [`check_pixels`].
fn exr_layer_sizes<R: Read + Seek>(src: R, file: &str) -> Result<Vec<(usize, usize)>> {
    let meta = exr::meta::MetaData::read_from_buffered(src, false)
        .map_err(|e| Error::Image { file: file.into(), what: e.to_string() })?;
    let sizes: Vec<(usize, usize)> =
        meta.headers.iter().map(|h| (h.layer_size.width(), h.layer_size.height())).collect();
    if sizes.is_empty() {
        return Err(Error::invalid(file, "header", "no layer"));
    }
    for &(w, h) in &sizes {
        check_pixels(file, "dataWindow", w as u64, h as u64)?;
    }
    for h in &meta.headers {
        btf_image::exr_limits::check_header(h)
            .map_err(|(field, what)| Error::limit(file, field, what))?;
    }
    Ok(sizes)
}

/// The size of the first layer of an EXR, from its header alone.
pub fn exr_dimensions<R: Read + Seek>(src: R, file: &str) -> Result<(usize, usize)> {
    Ok(exr_layer_sizes(src, file)?[0])
}

/// Reads the first RGB(A) layer of an EXR (largest resolution level) as row-major RGB,
/// after checking every layer's claimed size; `open` gives the source from its start (it
/// is called twice: header, then pixels).
pub fn read_exr_rgb<R: Read + Seek + Send>(
    open: impl Fn() -> Result<R>,
    file: &str,
) -> Result<(usize, usize, Vec<[f32; 3]>)> {
    use exr::prelude::{ReadChannels as _, ReadLayers as _};
    exr_layer_sizes(open()?, file)?;
    let img = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res, _| LazyRows::<[f32; 3]>::new(res.width(), res.height()),
            |rows: &mut LazyRows<[f32; 3]>,
             pos: exr::math::Vec2<usize>,
             (r, g, b, _a): (f32, f32, f32, f32)| {
                rows.set(pos.x(), pos.y(), [r, g, b]);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(open()?)
        .map_err(|e| Error::Image { file: file.into(), what: e.to_string() })?;
    let size = img.layer_data.size;
    let px = img.layer_data.channel_data.pixels.into_vec().map_err(|y| {
        Error::invalid(file, "pixels", format!("row {y} of {} is missing", size.height()))
    })?;
    Ok((size.width(), size.height(), px))
}

/// Decodes a PNG/JPEG/TIFF/BMP/HDR image through `image` (its default limits: 512 MiB per
/// allocation), checking the header's size with [`check_pixels`] first.
pub fn decode_image<R: BufRead + Seek>(
    reader: image::ImageReader<R>,
    file: &str,
    file_len: u64,
) -> Result<image::DynamicImage> {
    use image::ImageDecoder;
    let img_err = |e: image::ImageError| match e {
        image::ImageError::Limits(l) => Error::limit(file, "width x height", l.to_string()),
        other => Error::Image { file: file.into(), what: other.to_string() },
    };
    let dec = reader.into_decoder().map_err(img_err)?;
    let (w, h) = dec.dimensions();
    check_pixels(file, "width x height", w as u64, h as u64)?;
    // The decoder allocates the whole image before reading a pixel; the `image` crate's
    // own 512 MiB limit is not applied on this path (the raw_image fuzz target: 73 bytes of
    // PNG claiming a 16-bit image asked for 1.6 GB).
    // A compressed image cannot hold more than a few hundred pixels per byte (deflate
    // tops out near 1032:1, a flat JPEG block near 64 pixels in a few bits): more is a
    // forged or truncated header whose decoder would fill gigabytes with nothing (the
    // ubo2003_image fuzz target: 219 bytes of JPEG claiming 13 800² pixels).
    let pixels = w as u64 * h as u64;
    if pixels > MAX_PIXELS_PER_BYTE * file_len + (1 << 20) {
        return Err(Error::limit(
            file,
            "width x height",
            format!(
                "{w} x {h} pixels claimed by a file of {file_len} bytes (more than \
                 {MAX_PIXELS_PER_BYTE} pixels per byte): the header is forged or the file cut short"
            ),
        ));
    }
    let bytes = dec.total_bytes();
    if bytes > MAX_DECODED_BYTES {
        return Err(Error::limit(
            file,
            "width x height",
            format!(
                "{w} x {h} pixels of {:?} decode to {bytes} bytes, more than {MAX_DECODED_BYTES}",
                dec.color_type()
            ),
        ));
    }
    image::DynamicImage::from_decoder(dec).map_err(|e| match e {
        image::ImageError::Limits(l) => Error::limit(
            file,
            "width x height",
            format!("{w} x {h} pixels: {l} (the decoder allocates at most 512 MiB)"),
        ),
        other => Error::Image { file: file.into(), what: other.to_string() },
    })
}

/// Crafted headers claiming huge images, for the tests of this crate's readers.
#[cfg(test)]
pub(crate) mod crafted {
    /// A valid 2×2 RGB EXR whose `dataWindow` is patched to claim `w × h` pixels.
    pub fn exr_claiming(w: i32, h: i32) -> Vec<u8> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.exr");
        exr::prelude::write_rgb_file(&p, 2, 2, |_, _| (1f32, 1f32, 1f32)).unwrap();
        let mut b = std::fs::read(&p).unwrap();
        let key = b"dataWindow\0box2i\0";
        let at = b.windows(key.len()).position(|s| s == key).unwrap() + key.len() + 4;
        b[at + 8..at + 12].copy_from_slice(&(w - 1).to_le_bytes());
        b[at + 12..at + 16].copy_from_slice(&(h - 1).to_le_bytes());
        b
    }

    fn crc32(bytes: &[u8]) -> u32 {
        let mut c = !0u32;
        for &b in bytes {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
            }
        }
        !c
    }

    /// A PNG (8-bit RGB) whose IHDR claims `w × h` pixels, with an empty IDAT.
    pub fn png_claiming(w: u32, h: u32) -> Vec<u8> {
        png_claiming_as(w, h, 8, 2)
    }

    /// [`png_claiming`] with another bit depth and colour type (6 = RGBA).
    pub fn png_claiming_as(w: u32, h: u32, bits: u8, colour: u8) -> Vec<u8> {
        let mut chunk = b"IHDR".to_vec();
        chunk.extend_from_slice(&w.to_be_bytes());
        chunk.extend_from_slice(&h.to_be_bytes());
        chunk.extend_from_slice(&[bits, colour, 0, 0, 0]);
        let mut b = b"\x89PNG\r\n\x1a\n".to_vec();
        b.extend_from_slice(&13u32.to_be_bytes());
        b.extend_from_slice(&chunk);
        b.extend_from_slice(&crc32(&chunk).to_be_bytes());
        for tag in [b"IDAT", b"IEND"] {
            b.extend_from_slice(&0u32.to_be_bytes());
            b.extend_from_slice(tag);
            b.extend_from_slice(&crc32(tag).to_be_bytes());
        }
        b
    }

    /// A Radiance `.hdr` header claiming `w × h` pixels, and no data.
    pub fn hdr_claiming(w: u32, h: u32) -> Vec<u8> {
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n").into_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::crafted::*;
    use super::*;
    use std::io::Cursor;

    #[test]
    fn huge_claims_are_refused_before_decoding_naming_file_and_field() {
        let exr = exr_claiming(100_000, 100_000);
        let e = read_exr_rgb(|| Ok(Cursor::new(&exr[..])), "big.exr").unwrap_err();
        assert!(matches!(e, Error::Limit { .. }), "{e}");
        let e = e.to_string();
        assert!(e.contains("big.exr") && e.contains("dataWindow") && e.contains("100000"), "{e}");
        let e = exr_dimensions(Cursor::new(&exr[..]), "big.exr").unwrap_err().to_string();
        assert!(e.contains("big.exr") && e.contains("dataWindow"), "{e}");
        for (bytes, name) in [
            (png_claiming(100_000, 100_000), "big.png"),
            (hdr_claiming(100_000, 100_000), "big.hdr"),
        ] {
            let rd =
                image::ImageReader::new(Cursor::new(&bytes[..])).with_guessed_format().unwrap();
            let e = decode_image(rd, name, bytes.len() as u64).unwrap_err();
            assert!(matches!(e, Error::Limit { .. }), "{name}: {e}");
            let e = e.to_string();
            assert!(e.contains(name) && e.contains("width x height"), "{e}");
        }
    }

    #[test]
    fn a_claim_within_the_limit_costs_what_the_file_holds() {
        // 16384 × 16384 is allowed (the largest camera), but the file holds 2 rows of data:
        // refused as truncated, without allocating the 3 GiB the header claims.
        let exr = exr_claiming(16384, 16384);
        let e = read_exr_rgb(|| Ok(Cursor::new(&exr[..])), "short.exr").unwrap_err().to_string();
        assert!(e.contains("short.exr"), "{e}");
        let png = png_claiming(16384, 16384);
        let rd = image::ImageReader::new(Cursor::new(&png[..])).with_guessed_format().unwrap();
        assert!(
            decode_image(rd, "short.png", png.len() as u64)
                .unwrap_err()
                .to_string()
                .contains("short.png")
        );
    }
}
