//! Still images decoded within bounds — a tiny file claiming a huge image is refused from its
//! header, before any pixel is decoded. PNG and JPEG come as 8-bit sRGB-encoded RGBA; OpenEXR as
//! linear half floats, values above 1 kept (HDR).

use std::io::Cursor;

use image::ImageDecoder;

use super::picture::Picture;

/// A decoded still.
#[derive(Clone, Debug)]
pub struct Still {
    /// Size in pixels.
    pub size: (u32, u32),
    /// Its pixels: [`Picture::Rgba`] or, for OpenEXR, [`Picture::LinearHalf`].
    pub picture: Picture,
}

/// Decodes `bytes` (named `name` in messages) if the image's header says it fits a texture of at
/// most `max_side` a side and `max_bytes` as RGBA8.
pub fn decode(bytes: &[u8], name: &str, max_side: u32, max_bytes: u64) -> Result<Still, String> {
    let failed = |e: image::ImageError| format!("cannot read {name}: {e}");
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read {name}: {e}"))?;
    let exr = reader.format() == Some(image::ImageFormat::OpenExr);
    // A backstop: the check below refuses first, with a sentence that says why.
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(4 * max_bytes);
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(failed)?;
    let size = decoder.dimensions();
    super::check_size(name, size, max_side, max_bytes)?;
    let image = image::DynamicImage::from_decoder(decoder).map_err(failed)?;
    let picture = if exr {
        Picture::LinearHalf(
            image.to_rgba32f().into_raw().into_iter().map(|v| half::f16::from_f32(v).to_bits()).collect(),
        )
    } else {
        Picture::Rgba(image.to_rgba8().into_raw())
    };
    Ok(Still { size, picture })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn openexr_keeps_linear_values_above_one_and_png_stays_8_bit() {
        let hdr = image::Rgba32FImage::from_pixel(4, 2, image::Rgba([2.5, 0.25, 0.0, 1.0]));
        let mut exr = Vec::new();
        image::DynamicImage::ImageRgba32F(hdr)
            .write_to(&mut Cursor::new(&mut exr), image::ImageFormat::OpenExr)
            .unwrap();
        let still = decode(&exr, "hdr.exr", 16384, 1 << 20).unwrap();
        let Picture::LinearHalf(texels) = &still.picture else { panic!("EXR decodes to half floats") };
        assert_eq!(still.size, (4, 2));
        let first: Vec<f32> = texels[..4].iter().map(|&b| half::f16::from_bits(b).to_f32()).collect();
        assert_eq!(first, [2.5, 0.25, 0.0, 1.0]);
        let mut png = Vec::new();
        image::DynamicImage::ImageRgba8(image::RgbaImage::new(3, 3))
            .write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        assert!(matches!(decode(&png, "a.png", 16384, 1 << 20).unwrap().picture, Picture::Rgba(_)));
        assert!(decode(&exr, "hdr.exr", 3, 1 << 20).unwrap_err().contains("at most 3"));
    }
}
