//! HAP frames (Vidvox's open codec, `Vidvox/hap` `HapVideoDRAFT.md`): sections of S3TC/BPTC
//! texture blocks, Snappy-compressed whole or in chunks. A frame unpacks to the blocks a GPU
//! samples directly (BC1 for Hap, BC3 for Hap Alpha, scaled YCoCg in BC3 for Hap Q, BC7 for
//! Hap7, BC4 for alpha) — the only CPU work is Snappy, chunks of a frame in parallel.
//!
//! Every size is checked before memory is taken for it: a frame's unpacked size must be exactly
//! what its width and height need, so a frame whose size fields lie is an error, never a huge
//! allocation or a read past its end.

/// A block-compressed texture format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BlockFormat {
    /// DXT1: RGB, 8 bytes per 4×4 block.
    Bc1,
    /// DXT5: RGBA, 16 bytes per block.
    Bc3,
    /// RGTC1: one channel, 8 bytes per block.
    Bc4,
    /// BPTC: RGBA, 16 bytes per block.
    Bc7,
}

impl BlockFormat {
    /// Bytes per 4×4 block.
    pub fn block_bytes(self) -> usize {
        match self {
            BlockFormat::Bc1 | BlockFormat::Bc4 => 8,
            BlockFormat::Bc3 | BlockFormat::Bc7 => 16,
        }
    }

    /// Bytes of a `width` × `height` image.
    pub fn image_bytes(self, width: u32, height: u32) -> usize {
        width.div_ceil(4) as usize * height.div_ceil(4) as usize * self.block_bytes()
    }
}

/// What a texture's channels mean.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channels {
    /// Colour, opaque.
    Rgb,
    /// Colour and straight (not premultiplied) alpha.
    Rgba,
    /// HAP Q's scaled YCoCg: Co, Cg, scale, Y in R, G, B, A.
    ScaledYCoCg,
    /// Alpha only, in R.
    Alpha,
}

/// One texture of a frame: its format and blocks, row by row of blocks.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HapTexture {
    /// Block format.
    pub format: BlockFormat,
    /// What the channels mean.
    pub channels: Channels,
    /// The blocks.
    pub blocks: Vec<u8>,
}

/// A decoded frame: a colour texture and, for Hap Q Alpha, a separate alpha texture.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HapFrame {
    /// The colour (or, for Hap Alpha-Only, the alpha) texture.
    pub color: HapTexture,
    /// Hap Q Alpha's BC4 alpha.
    pub alpha: Option<HapTexture>,
}

/// Section types of the decode instructions.
const MULTIPLE_IMAGES: u8 = 0x0D;
const DECODE_INSTRUCTIONS: u8 = 0x01;
const CHUNK_COMPRESSORS: u8 = 0x02;
const CHUNK_SIZES: u8 = 0x03;
const CHUNK_OFFSETS: u8 = 0x04;

/// Unpacks one HAP frame of a `width` × `height` clip.
pub fn decode_frame(bytes: &[u8], width: u32, height: u32) -> Result<HapFrame, String> {
    let (kind, body, _) = section(bytes).ok_or("the HAP frame's header is damaged")?;
    if kind != MULTIPLE_IMAGES {
        return Ok(HapFrame { color: decode_image(kind, body, width, height)?, alpha: None });
    }
    let mut color = None;
    let mut alpha = None;
    let mut rest = body;
    while !rest.is_empty() {
        let (kind, body, next) = section(rest).ok_or("a HAP image section is damaged")?;
        let texture = decode_image(kind, body, width, height)?;
        if texture.channels == Channels::Alpha {
            alpha = Some(texture)
        } else {
            color = Some(texture)
        }
        rest = next;
    }
    match (color, alpha) {
        (Some(color), alpha) => Ok(HapFrame { color, alpha }),
        (None, Some(alpha)) => Ok(HapFrame { color: alpha, alpha: None }),
        (None, None) => Err("the HAP frame holds no image".into()),
    }
}

/// One section: its type, its body and what follows it.
fn section(bytes: &[u8]) -> Option<(u8, &[u8], &[u8])> {
    let head = bytes.get(..4)?;
    let short = u32::from_le_bytes([head[0], head[1], head[2], 0]) as usize;
    let (size, header) =
        if short == 0 { (u32::from_le_bytes(bytes.get(4..8)?.try_into().ok()?) as usize, 8) } else { (short, 4) };
    let end = size.checked_add(header)?;
    Some((head[3], bytes.get(header..end)?, &bytes[end..]))
}

/// A top-level image section of type `kind`.
fn decode_image(kind: u8, body: &[u8], width: u32, height: u32) -> Result<HapTexture, String> {
    let (format, channels) = match kind & 0x0F {
        0x0B => (BlockFormat::Bc1, Channels::Rgb),
        0x0E => (BlockFormat::Bc3, Channels::Rgba),
        0x0F => (BlockFormat::Bc3, Channels::ScaledYCoCg),
        0x0C => (BlockFormat::Bc7, Channels::Rgba),
        0x01 => (BlockFormat::Bc4, Channels::Alpha),
        _ => return Err(format!("the HAP frame has a texture format this player does not know (0x{kind:02X})")),
    };
    let expected = format.image_bytes(width, height);
    let blocks = match kind >> 4 {
        0x0A => {
            if body.len() != expected {
                return Err(lying(body.len(), expected, width, height));
            }
            body.to_vec()
        }
        0x0B => snappy(body, expected, width, height)?,
        0x0C => chunked(body, expected, width, height)?,
        _ => return Err(format!("the HAP frame names a compressor this player does not know (0x{kind:02X})")),
    };
    Ok(HapTexture { format, channels, blocks })
}

fn lying(got: usize, expected: usize, width: u32, height: u32) -> String {
    format!("a HAP frame unpacks to {got} bytes, but a {width}×{height} frame is {expected}: the file is damaged")
}

/// Snappy-decompresses `body`, which must unpack to exactly `expected` bytes.
fn snappy(body: &[u8], expected: usize, width: u32, height: u32) -> Result<Vec<u8>, String> {
    let mut out = vec![0u8; checked_len(body, expected, width, height)?];
    snap::raw::Decoder::new().decompress(body, &mut out).map_err(|e| format!("a HAP frame is damaged: {e}"))?;
    Ok(out)
}

/// The length `body` says it unpacks to, if that is `expected`.
fn checked_len(body: &[u8], expected: usize, width: u32, height: u32) -> Result<usize, String> {
    let len = snap::raw::decompress_len(body).map_err(|e| format!("a HAP frame is damaged: {e}"))?;
    if len != expected {
        return Err(lying(len, expected, width, height));
    }
    Ok(len)
}

/// A frame in chunks (`Consult decode instructions`): each chunk is compressed on its own and
/// unpacks to the next stretch of blocks; chunks are decompressed on parallel threads.
fn chunked(body: &[u8], expected: usize, width: u32, height: u32) -> Result<Vec<u8>, String> {
    let damaged = || "a HAP frame's decode instructions are damaged".to_string();
    let (kind, instructions, data) = section(body).ok_or_else(damaged)?;
    if kind != DECODE_INSTRUCTIONS {
        return Err(damaged());
    }
    let (mut compressors, mut sizes, mut offsets) = (None, None, None);
    let mut rest = instructions;
    while !rest.is_empty() {
        let (kind, table, next) = section(rest).ok_or_else(damaged)?;
        match kind {
            CHUNK_COMPRESSORS => compressors = Some(table),
            CHUNK_SIZES => sizes = Some(le32s(table)),
            CHUNK_OFFSETS => offsets = Some(le32s(table)),
            _ => {} // unknown sections are skipped, as the format asks
        }
        rest = next;
    }
    let (Some(compressors), Some(sizes)) = (compressors, sizes) else { return Err(damaged()) };
    if sizes.len() != compressors.len() || offsets.as_ref().is_some_and(|o| o.len() != sizes.len()) {
        return Err(damaged());
    }
    // Each chunk's input and where its output goes, all checked before any is decompressed.
    let mut jobs = Vec::with_capacity(sizes.len());
    let (mut at, mut out_at) = (0usize, 0usize);
    for (i, (&compressor, &size)) in compressors.iter().zip(&sizes).enumerate() {
        let start = offsets.as_ref().map_or(at, |o| o[i] as usize);
        let input = start.checked_add(size as usize).and_then(|end| data.get(start..end)).ok_or_else(damaged)?;
        at = start + size as usize;
        let len = match compressor {
            0x0A => input.len(),
            0x0B => snap::raw::decompress_len(input).map_err(|e| format!("a HAP chunk is damaged: {e}"))?,
            _ => return Err(format!("a HAP chunk names a compressor this player does not know (0x{compressor:02X})")),
        };
        jobs.push((compressor, input, out_at, len));
        out_at = out_at.checked_add(len).ok_or_else(damaged)?;
        if out_at > expected {
            return Err(lying(out_at, expected, width, height));
        }
    }
    if out_at != expected {
        return Err(lying(out_at, expected, width, height));
    }
    let mut out = vec![0u8; expected];
    let mut pieces = Vec::with_capacity(jobs.len());
    let mut remaining = out.as_mut_slice();
    for &(compressor, input, _, len) in &jobs {
        let (piece, rest) = remaining.split_at_mut(len);
        pieces.push((compressor, input, piece));
        remaining = rest;
    }
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(pieces.len()).max(1);
    let per_thread = pieces.len().div_ceil(threads);
    let results: Vec<Result<(), String>> = std::thread::scope(|scope| {
        let handles: Vec<_> = pieces
            .chunks_mut(per_thread)
            .map(|group| {
                scope.spawn(move || {
                    for (compressor, input, piece) in group.iter_mut() {
                        if *compressor == 0x0A {
                            piece.copy_from_slice(input);
                        } else {
                            snap::raw::Decoder::new()
                                .decompress(input, piece)
                                .map_err(|e| format!("a HAP chunk is damaged: {e}"))?;
                        }
                    }
                    Ok(())
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap_or_else(|_| Err("a HAP chunk failed".into()))).collect()
    });
    results.into_iter().collect::<Result<(), String>>()?;
    Ok(out)
}

fn le32s(table: &[u8]) -> Vec<u32> {
    table.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().unwrap())).collect()
}

/// Decodes `texture` to BGRA8 pixels on the CPU (adapters without BC texture support); each
/// `u32` is B, G, R, A in memory order.
pub fn decode_to_bgra(texture: &HapTexture, width: u32, height: u32) -> Result<Vec<u32>, String> {
    let (w, h) = (width as usize, height as usize);
    let mut image = vec![0u32; w * h];
    let blocks = &texture.blocks;
    match texture.format {
        BlockFormat::Bc1 => texture2ddecoder::decode_bc1(blocks, w, h, &mut image),
        BlockFormat::Bc3 => texture2ddecoder::decode_bc3(blocks, w, h, &mut image),
        BlockFormat::Bc4 => texture2ddecoder::decode_bc4(blocks, w, h, &mut image),
        BlockFormat::Bc7 => texture2ddecoder::decode_bc7(blocks, w, h, &mut image),
    }
    .map_err(|e| format!("cannot decode a HAP texture: {e}"))?;
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(size: usize, kind: u8) -> Vec<u8> {
        if size < 1 << 24 {
            let mut h = (size as u32).to_le_bytes()[..3].to_vec();
            h.push(kind);
            h
        } else {
            let mut h = vec![0, 0, 0, kind];
            h.extend((size as u32).to_le_bytes());
            h
        }
    }

    #[test]
    fn uncompressed_and_snappy_frames_unpack_to_their_blocks() {
        let blocks: Vec<u8> = (0..BlockFormat::Bc1.image_bytes(8, 8)).map(|i| i as u8).collect();
        let mut raw = header(blocks.len(), 0xAB);
        raw.extend(&blocks);
        assert_eq!(decode_frame(&raw, 8, 8).unwrap().color.blocks, blocks);
        let packed = snap::raw::Encoder::new().compress_vec(&blocks).unwrap();
        let mut snappy = header(packed.len(), 0xBB);
        snappy.extend(&packed);
        let frame = decode_frame(&snappy, 8, 8).unwrap();
        assert_eq!((frame.color.format, frame.color.channels), (BlockFormat::Bc1, Channels::Rgb));
        assert_eq!(frame.color.blocks, blocks);
    }

    #[test]
    fn hap_q_alpha_is_two_images_in_one_section() {
        // Hap Q Alpha (HapM): scaled YCoCg in BC3 and alpha in BC4, in a multiple-image section.
        let color: Vec<u8> = (0..BlockFormat::Bc3.image_bytes(8, 4)).map(|i| i as u8).collect();
        let alpha: Vec<u8> = (0..BlockFormat::Bc4.image_bytes(8, 4)).map(|i| 200 - i as u8).collect();
        let mut images = header(alpha.len(), 0xA1);
        images.extend(&alpha);
        let packed = snap::raw::Encoder::new().compress_vec(&color).unwrap();
        images.extend(header(packed.len(), 0xBF));
        images.extend(&packed);
        let mut frame = header(images.len(), MULTIPLE_IMAGES);
        frame.extend(images);
        let decoded = decode_frame(&frame, 8, 4).unwrap();
        assert_eq!((decoded.color.channels, decoded.color.blocks.clone()), (Channels::ScaledYCoCg, color));
        let a = decoded.alpha.expect("the alpha image");
        assert_eq!((a.format, a.channels, a.blocks), (BlockFormat::Bc4, Channels::Alpha, alpha));
    }

    #[test]
    fn a_frame_whose_sizes_lie_is_an_error() {
        // Snappy data claiming 4 GiB for an 8×8 frame: refused before anything is allocated.
        let mut claim = vec![0xff, 0xff, 0xff, 0xff, 0x0f];
        claim.extend([0u8; 8]);
        let mut frame = header(claim.len(), 0xBB);
        frame.extend(&claim);
        let e = decode_frame(&frame, 8, 8).unwrap_err();
        assert!(e.contains("8×8") && e.contains("damaged"), "{e}");
        // A section claiming more bytes than the frame has.
        let mut short = header(1000, 0xAB);
        short.extend([0u8; 10]);
        assert!(decode_frame(&short, 8, 8).unwrap_err().contains("header"));
        // Raw blocks for a smaller frame than the clip's.
        let mut small = header(16, 0xAB);
        small.extend([0u8; 16]);
        assert!(decode_frame(&small, 8, 8).unwrap_err().contains("16 bytes"));
        // An unknown format and garbage.
        let mut odd = header(32, 0xA7);
        odd.extend([0u8; 32]);
        assert!(decode_frame(&odd, 8, 8).unwrap_err().contains("0xA7"));
        assert!(decode_frame(&[1, 2], 8, 8).is_err());
    }

    #[test]
    fn chunks_unpack_in_order_with_or_without_offsets_and_lies_are_caught() {
        let blocks: Vec<u8> = (0..BlockFormat::Bc3.image_bytes(16, 8)).map(|i| (i * 7) as u8).collect();
        let halves: Vec<Vec<u8>> =
            blocks.chunks(blocks.len() / 2).map(|c| snap::raw::Encoder::new().compress_vec(c).unwrap()).collect();
        let build = |offsets: bool, sizes: [u32; 2]| {
            let mut tables = header(2, CHUNK_COMPRESSORS);
            tables.extend([0x0B, 0x0B]);
            tables.extend(header(8, CHUNK_SIZES));
            tables.extend(sizes.iter().flat_map(|s| s.to_le_bytes()));
            if offsets {
                // Stored second chunk first: offsets say where each is.
                tables.extend(header(8, CHUNK_OFFSETS));
                tables.extend((halves[1].len() as u32).to_le_bytes());
                tables.extend(0u32.to_le_bytes());
            }
            let mut body = header(tables.len(), DECODE_INSTRUCTIONS);
            body.extend(tables);
            if offsets {
                body.extend(&halves[1]);
                body.extend(&halves[0]);
            } else {
                body.extend(&halves[0]);
                body.extend(&halves[1]);
            }
            let mut frame = header(body.len(), 0xCF);
            frame.extend(body);
            frame
        };
        let sizes = [halves[0].len() as u32, halves[1].len() as u32];
        for offsets in [false, true] {
            let frame = decode_frame(&build(offsets, sizes), 16, 8).unwrap();
            assert_eq!(frame.color.channels, Channels::ScaledYCoCg);
            assert_eq!(frame.color.blocks, blocks, "offsets: {offsets}");
        }
        assert!(decode_frame(&build(false, [sizes[0], 1 << 30]), 16, 8).unwrap_err().contains("damaged"));
        assert!(decode_frame(&build(false, sizes), 16, 16).is_err(), "too few blocks for the clip's size");
    }
}
