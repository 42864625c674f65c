//! Still images (PNG, JPEG) decoded to RGBA8 within bounds: a tiny file claiming a huge image is
//! refused from its header, before any pixel is decoded.

use std::io::Cursor;

use image::ImageDecoder;

/// Decodes `bytes` (named `name` in messages) if the image's header says it fits a texture of at
/// most `max_side` a side and `max_bytes` as RGBA8.
pub fn decode_bounded(bytes: &[u8], name: &str, max_side: u32, max_bytes: u64) -> Result<image::RgbaImage, String> {
    let failed = |e: image::ImageError| format!("cannot read {name}: {e}");
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read {name}: {e}"))?;
    // A backstop: the checks below refuse first, with a sentence that says why.
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(2 * max_bytes);
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(failed)?;
    super::check_size(name, decoder.dimensions(), max_side, max_bytes)?;
    Ok(image::DynamicImage::from_decoder(decoder).map_err(failed)?.to_rgba8())
}
