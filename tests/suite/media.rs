//! Clips made by the local ffmpeg, read by indra's own HAP reader and through its ffmpeg path,
//! against ffmpeg's own decode: same frames, same pixels (within BC tolerance), any order.

use crate::common::clips::{COUNTER_SIZE, counter_source, ffmpeg_frames, make_clip, read_counter};
use indra::media::clip::Clip;
use indra::media::hap::{self, Channels};
use indra::media::picture::Picture;

const LIMIT: u64 = indra::media::DECODED_LIMIT;

/// HAP Q's scaled YCoCg to RGB, as `video.wgsl` does it, on 8-bit values.
fn ycocg(p: [u8; 4]) -> [f32; 3] {
    let [r, g, b, a] = p.map(|c| f32::from(c) / 255.0);
    let scale = b * (255.0 / 8.0) + 1.0;
    let (co, cg) = ((r - 128.0 / 255.0) / scale, (g - 128.0 / 255.0) / scale);
    [a + co - cg, a + cg, a - co - cg]
}

/// The RGBA8 pixels of `picture` as the CPU fallback decodes them (straight alpha).
fn cpu_rgba(picture: &Picture, size: (u32, u32)) -> Vec<[u8; 4]> {
    let Picture::Hap(frame) = picture else { panic!("a HAP clip gives HAP frames") };
    let bgra = hap::decode_to_bgra(&frame.color, size.0, size.1).unwrap();
    let alpha = frame.alpha.as_ref().map(|a| hap::decode_to_bgra(a, size.0, size.1).unwrap());
    bgra.iter()
        .enumerate()
        .map(|(i, &p)| {
            let [b, g, r, a] = p.to_le_bytes();
            let mut rgba = match frame.color.channels {
                Channels::ScaledYCoCg => {
                    let c = ycocg([r, g, b, a]).map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8);
                    [c[0], c[1], c[2], 255]
                }
                Channels::Alpha => [255, 255, 255, r],
                _ => [r, g, b, a],
            };
            if let Some(alpha) = &alpha {
                rgba[3] = alpha[i].to_le_bytes()[2];
            }
            rgba
        })
        .collect()
}

/// Mean and largest channel difference between two RGBA images (colour only where opaque
/// enough to see, and alpha everywhere).
fn difference(ours: &[[u8; 4]], theirs: &[u8]) -> (f64, u8) {
    let mut sum = 0u64;
    let mut max = 0u8;
    let mut n = 0u64;
    for (p, q) in ours.iter().zip(theirs.chunks_exact(4)) {
        let channels = if q[3] > 32 { 0..4 } else { 3..4 };
        for c in channels {
            let d = p[c].abs_diff(q[c]);
            sum += u64::from(d);
            max = max.max(d);
            n += 1;
        }
    }
    (sum as f64 / n.max(1) as f64, max)
}

#[test]
fn hap_hap_alpha_and_hap_q_decode_to_ffmpegs_pixels() {
    let size = (72, 40);
    let source = "testsrc=size=72x40:rate=25:duration=0.4,format=rgba,geq=r='r(X,Y)':g='g(X,Y)':b='b(X,Y)':a='X*255/W'";
    let clips = [
        ("hap.mov", vec!["-c:v", "hap", "-format", "hap"], "Hap1", false),
        ("hap_alpha.mov", vec!["-c:v", "hap", "-format", "hap_alpha"], "Hap5", true),
        ("hap_q.mov", vec!["-c:v", "hap", "-format", "hap_q"], "HapY", false),
        ("hap_q_chunks.mov", vec!["-c:v", "hap", "-format", "hap_q", "-chunks", "4"], "HapY", false),
        ("hap_raw.mov", vec!["-c:v", "hap", "-format", "hap", "-compressor", "none"], "Hap1", false),
    ];
    for (name, args, codec, alpha) in clips {
        let path = make_clip(name, source, &args);
        let mut clip = Clip::open(&path, 16384, LIMIT).unwrap();
        let info = clip.info();
        assert_eq!((info.codec.as_str(), info.width, info.height, info.frames, info.alpha), (codec, 72, 40, 10, alpha));
        assert!(info.random_access && (info.fps - 25.0).abs() < 1e-9, "{name}: {info:?}");
        let reference = ffmpeg_frames(&path, size);
        assert_eq!(reference.len(), 10, "{name}");
        // Out of order: every frame is a random access.
        for index in [7, 0, 9, 3] {
            let ours = cpu_rgba(&clip.read(index).unwrap(), size);
            let (mean, max) = difference(&ours, &reference[index]);
            // BC decoders may round block interpolation by a step or two; YCoCg adds a little.
            assert!(mean < 1.0 && max <= 6, "{name} frame {index}: mean {mean:.3}, max {max}");
        }
    }
}

#[test]
fn frames_are_exact_by_index_through_hap_and_ffmpeg_in_any_order() {
    let source = counter_source(25, 4.0);
    let hap = make_clip("counter_hap.mov", &source, &["-c:v", "hap"]);
    let h264 =
        make_clip("counter_h264.mp4", &source, &["-c:v", "libx264", "-g", "30", "-pix_fmt", "yuv444p", "-crf", "10"]);
    let prores = make_clip("counter_prores.mov", &source, &["-c:v", "prores_ks", "-profile:v", "4444"]);
    for path in [hap, h264, prores] {
        let mut clip = Clip::open(&path, 16384, LIMIT).unwrap();
        assert_eq!(clip.info().frames, 100, "{}", path.display());
        // In order, a jump forward, a jump back before the last keyframe, one past a keyframe.
        for index in [0, 1, 2, 40, 41, 5, 31, 99, 98] {
            let picture = clip.read(index).unwrap();
            let rgba: Vec<u8> = match &picture {
                Picture::Rgba(p) => p.clone(),
                Picture::Hap(_) => cpu_rgba(&picture, COUNTER_SIZE).into_iter().flatten().collect(),
                Picture::LinearHalf(_) => panic!("a movie decodes to 8-bit RGBA"),
            };
            assert_eq!(read_counter(&rgba, 8), index, "{} frame {index}", path.display());
        }
    }
}

#[test]
fn truncated_lying_and_non_video_files_are_clean_errors() {
    let good = make_clip("counter_hap_for_damage.mov", &counter_source(25, 1.0), &["-c:v", "hap"]);
    let bytes = std::fs::read(&good).unwrap();
    let dir = crate::common::clips::clip_dir();

    // Cut in the middle of the frames (ffmpeg writes the index last: it is gone too).
    let cut = dir.join("cut.mov");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = Clip::open(&cut, 16384, LIMIT).err().expect("a truncated clip is refused");
    assert!(e.contains("truncated") || e.contains("not a video"), "{e}");

    // The index kept but the frames' data shortened: a frame ends past the end of the file.
    let mut moov_first = bytes.clone();
    let moov = bytes.windows(4).position(|w| w == b"moov").unwrap() - 4;
    let index = bytes[moov..].to_vec();
    moov_first.truncate(moov);
    let mdat_cut = moov_first.len() - 200;
    let mut shortened = moov_first[..mdat_cut].to_vec();
    shortened.extend(&index);
    let short = dir.join("short.mov");
    std::fs::write(&short, &shortened).unwrap();
    let e = Clip::open(&short, 16384, LIMIT).err().expect("a clip whose frames lie past its end is refused");
    assert!(e.contains("truncated"), "{e}");

    // A frame whose size field lies: the first frame's section claims more than it has.
    let mut lying = bytes.clone();
    let first =
        u32::from_be_bytes(bytes[bytes.windows(4).position(|w| w == b"stco").unwrap() + 12..][..4].try_into().unwrap())
            as usize;
    lying[first..first + 3].copy_from_slice(&[0xff, 0xff, 0x0f]);
    let liar = dir.join("liar.mov");
    std::fs::write(&liar, &lying).unwrap();
    let mut clip = Clip::open(&liar, 16384, LIMIT).unwrap();
    let e = clip.read(0).unwrap_err();
    assert!(e.contains("frame 0") && (e.contains("damaged") || e.contains("header")), "{e}");
    assert!(clip.read(1).is_ok(), "the other frames still play");

    let text = dir.join("notes.mov");
    std::fs::write(&text, "these are my notes, not a video").unwrap();
    let e = Clip::open(&text, 16384, LIMIT).err().unwrap();
    assert!(e.contains("not a video"), "{e}");
    assert!(Clip::open(&dir.join("missing.mov"), 16384, LIMIT).is_err());

    // Larger than the device takes: refused before a frame is read.
    let e = Clip::open(&good, 32, LIMIT).err().unwrap();
    assert!(e.contains("64×16") && e.contains("at most 32"), "{e}");
}

#[test]
fn a_playlist_saved_as_a_clip_opens_nothing_it_names() {
    // An H.264 clip outside the folder of the "clip" that names it, and a FIFO beside it.
    let outside = make_clip("outside_h264.mp4", &counter_source(25, 0.4), &["-c:v", "libx264", "-pix_fmt", "yuv420p"]);
    let dir = crate::common::clips::clip_dir().join("playlists");
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("never-written.fifo");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
    assert!(made.success());
    for (name, target) in [("hls.mov", outside.clone()), ("fifo.mov", fifo.clone())] {
        let playlist = dir.join(name);
        std::fs::write(
            &playlist,
            format!("#EXTM3U\n#EXT-X-TARGETDURATION:1\n#EXTINF:1,\n{}\n#EXT-X-ENDLIST\n", target.display()),
        )
        .unwrap();
        // ffmpeg reads HLS by content, whatever the name: it opened the file (or blocked on the
        // FIFO for ever). Only containers that name no other file are taken.
        let started = std::time::Instant::now();
        let e = Clip::open(&playlist, 16384, LIMIT).err().unwrap_or_else(|| panic!("{name} was played"));
        assert!(e.contains("not a video"), "{name}: {e}");
        assert!(started.elapsed() < std::time::Duration::from_secs(10), "{name} held the probe");
    }
    // The same clip named directly still plays.
    assert!(Clip::open(&outside, 16384, LIMIT).is_ok());
}
