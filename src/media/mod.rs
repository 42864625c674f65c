//! Media in: video clips, numbered image sequences, stills, cameras and NDI sources, as pictures
//! a node uploads (and NDI out, the same runtime's other half). Pure CPU and processes — no GPU: HAP clips are read from their QuickTime sample tables and unpacked to
//! texture blocks ([`mov`], [`hap`]); every other codec and every camera comes through an
//! `ffmpeg` process ([`ffmpeg`], [`camera`]); a worker decodes ahead of the show ([`prefetch`]);
//! a [`playhead`] turns the fixed clock into a clip frame, so renders are exact. Tested against
//! ffmpeg-made clips in `tests/suite/media.rs` and through the nodes in their render tests.

pub mod camera;
pub mod clip;
pub mod ffmpeg;
pub mod hap;
pub mod mov;
pub mod ndi;
pub mod picture;
pub mod playhead;
pub mod prefetch;
pub mod sequence;
pub mod still;

/// The most memory one decoded frame may take (RGBA8): 8192 × 8192.
pub const DECODED_LIMIT: u64 = 256 << 20;

/// Refuses a `width` × `height` picture (called `what` in the message: "the video", a file
/// name) larger than `max_side` on a side or `max_bytes` as RGBA8.
pub fn check_size(what: &str, (width, height): (u32, u32), max_side: u32, max_bytes: u64) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("{what} has no size"));
    }
    if width > max_side || height > max_side {
        return Err(format!("{what} is {width}×{height} pixels; this GPU takes at most {max_side} on a side"));
    }
    let bytes = u64::from(width) * u64::from(height) * 4;
    if bytes > max_bytes {
        return Err(format!(
            "{what} is {width}×{height} pixels ({} MiB decoded), more than the {} MiB a picture may take",
            bytes >> 20,
            max_bytes >> 20
        ));
    }
    Ok(())
}
