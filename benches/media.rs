//! Media-in benchmarks (criterion), on clips the local ffmpeg makes: the CPU cost of one HAP
//! frame (read from the sample tables + Snappy, chunked frames in parallel) at 1080p and 4K for
//! Hap, Hap Q and Hap Q in 8 chunks; beside it the CPU fallback's BC decode (texture2ddecoder),
//! and the ffmpeg path's decode rate for 1080p H.264 — the peer a HAP frame is weighed against.
//! Run: `cargo bench --bench media`. The GPU side (upload + BC sampling) is in `indra bench` of
//! a scene with a 4K clip (docs/performance.md).

use std::path::PathBuf;
use std::process::Command;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use indra::media::clip::Clip;
use indra::media::hap;
use indra::media::picture::Picture;

const FRAMES: usize = 12;

/// A clip of ffmpeg's `testsrc2` (moving, detailed: a hard case for Snappy) at `size`, `frames`
/// long at 60 fps.
fn clip(name: &str, size: &str, frames: usize, args: &[&str]) -> PathBuf {
    let dir = std::env::temp_dir().join("indra-bench-media");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    if !path.exists() {
        let out = Command::new("ffmpeg")
            .args(["-v", "error", "-y", "-f", "lavfi", "-i"])
            .arg(format!("testsrc2=size={size}:rate=60:duration={}", frames as f64 / 60.0))
            .args(args)
            .arg(&path)
            .output()
            .expect("ffmpeg runs (apt-get install ffmpeg)");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    path
}

fn hap_frames(c: &mut Criterion) {
    let mut group = c.benchmark_group("hap_frame");
    group.sample_size(20);
    for (size, label) in [("1920x1080", "1080p"), ("3840x2160", "4k")] {
        for (format, chunks) in [("hap", "1"), ("hap_q", "1"), ("hap_q", "8")] {
            let name = format!("{label}_{format}_{chunks}.mov");
            let path = clip(&name, size, FRAMES, &["-c:v", "hap", "-format", format, "-chunks", chunks]);
            let mut clip = Clip::open(&path, 16384, 1 << 30).unwrap();
            let bytes = clip.info().width as u64 * clip.info().height as u64 * 4;
            group.throughput(Throughput::Bytes(bytes));
            let mut i = 0;
            group.bench_function(format!("{label} {format} chunks {chunks}: read + snappy"), |b| {
                b.iter(|| {
                    i = (i + 1) % FRAMES;
                    clip.read(i).unwrap()
                })
            });
            if chunks == "1" {
                let Picture::Hap(frame) = clip.read(0).unwrap() else { unreachable!() };
                let (w, h) = (clip.info().width, clip.info().height);
                group.bench_function(format!("{label} {format}: CPU fallback BC decode"), |b| {
                    b.iter(|| hap::decode_to_bgra(&frame.color, w, h).unwrap())
                });
            }
        }
    }
    group.finish();
}

fn ffmpeg_h264(c: &mut Criterion) {
    const LONG: usize = 240;
    let path = clip("1080p_h264_240.mp4", "1920x1080", LONG, &["-c:v", "libx264", "-pix_fmt", "yuv420p", "-g", "60"]);
    let mut group = c.benchmark_group("ffmpeg_frame");
    group.sample_size(20);
    let mut clip = Clip::open(&path, 16384, 1 << 30).unwrap();
    let mut i = 0;
    // In order through one decoding process, as a clip plays (a new one per pass of the clip).
    group.bench_function("1080p h264: the next frame through the ffmpeg pipe", |b| {
        b.iter(|| {
            i = (i + 1) % LONG;
            clip.read(i).unwrap().bytes()
        })
    });
    group.finish();
}

criterion_group!(benches, hap_frames, ffmpeg_h264);
criterion_main!(benches);
