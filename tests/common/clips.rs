//! Clips made by the local ffmpeg for the media tests: HAP, HAP Alpha, HAP Q, H.264, ProRes, from
//! ffmpeg's test sources — including a frame counter burnt in as bars, read back from pixels.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The counter clip's size: 8 bars of 8 pixels, bit i of the frame number in bar i.
pub const COUNTER_SIZE: (u32, u32) = (64, 16);

/// The folder the clips of this test process are made in.
pub fn clip_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("indra-clips-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// ffmpeg's lavfi source for a counter clip of `seconds` at `rate`: frame n shows n in binary.
pub fn counter_source(rate: u32, seconds: f64) -> String {
    let (w, h) = COUNTER_SIZE;
    let bit = "if(bitand(N\\,pow(2\\,floor(X/8)))\\,255\\,0)";
    format!("nullsrc=size={w}x{h}:rate={rate}:duration={seconds},format=rgb24,geq=r={bit}:g={bit}:b={bit}")
}

/// Makes `name` in [`clip_dir`] from lavfi `source` with `args` (codec settings), once per
/// process; returns its path.
pub fn make_clip(name: &str, source: &str, args: &[&str]) -> PathBuf {
    let path = clip_dir().join(name);
    if path.exists() {
        return path;
    }
    let partial =
        clip_dir().join(format!("partial-{}-{name}", std::thread::current().name().unwrap_or("t").replace("::", "-")));
    let out = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-f", "lavfi", "-i", source])
        .args(args)
        .arg(&partial)
        .output()
        .expect("ffmpeg runs (apt-get install ffmpeg)");
    assert!(out.status.success(), "ffmpeg made no {name}: {}", String::from_utf8_lossy(&out.stderr));
    std::fs::rename(&partial, &path).unwrap();
    path
}

/// Every frame of `path` as ffmpeg itself decodes it, RGBA, `size` each.
pub fn ffmpeg_frames(path: &Path, size: (u32, u32)) -> Vec<Vec<u8>> {
    let out = Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(path)
        .args(["-f", "rawvideo", "-pix_fmt", "rgba", "-"])
        .output()
        .expect("ffmpeg runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    out.stdout.chunks_exact((size.0 * size.1 * 4) as usize).map(<[u8]>::to_vec).collect()
}

/// The number a counter frame shows (`rgba` rows of [`COUNTER_SIZE`] width, row `y`).
pub fn read_counter(rgba: &[u8], y: u32) -> usize {
    let row = (y * COUNTER_SIZE.0 * 4) as usize;
    (0..8).filter(|i| rgba[row + ((i * 8 + 4) * 4) as usize] > 128).map(|i| 1 << i).sum()
}
