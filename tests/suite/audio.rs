//! Sound as a control source: analysis of a synthetic beat (onsets, bands, tempo), renders that
//! hear a WAV file exactly (twice the same bytes, sought or played), the file as a video's sound
//! track, and bad files as one sentence.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{indra, text};

use indra::control::audio::{AudioFile, analyse_file};

const RATE: u32 = 48_000;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("indra-audio-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `seconds` of a 120 bpm beat: a 60 Hz kick of 80 ms every half second over faint 6 kHz hiss,
/// as 16-bit stereo (the channels are mixed on reading).
fn write_beat(path: &Path, seconds: f32) {
    let spec =
        hound::WavSpec { channels: 2, sample_rate: RATE, bits_per_sample: 16, sample_format: hound::SampleFormat::Int };
    let mut w = hound::WavWriter::create(path, spec).unwrap();
    for i in 0..(seconds * RATE as f32) as usize {
        let t = i as f32 / RATE as f32;
        let in_beat = t % 0.5;
        let kick =
            if in_beat < 0.08 { 0.8 * (std::f32::consts::TAU * 60.0 * t).sin() * (1.0 - in_beat / 0.08) } else { 0.0 };
        let hiss = 0.01 * (std::f32::consts::TAU * 6000.0 * t).sin();
        let s = ((kick + hiss) * 32767.0) as i16;
        w.write_sample(s).unwrap();
        w.write_sample(s).unwrap();
    }
    w.finalize().unwrap();
}

#[test]
fn a_beat_gives_onsets_on_the_beat_bass_in_the_low_band_and_its_tempo() {
    let dir = temp_dir("analysis");
    let path = dir.join("beat.wav");
    write_beat(&path, 10.0);
    let file = AudioFile::open(&path).unwrap();
    assert_eq!(file.rate, RATE);
    assert!((file.seconds() - 10.0).abs() < 1e-3);
    let frames = analyse_file(&file, 600, 1.0 / 60.0);
    let mut onsets = Vec::new();
    for (f, frame) in (0u64..).zip(&frames) {
        if frame.onset {
            onsets.push(f);
        }
        if f % 30 == 2 {
            assert!(
                frame.low > frame.high + 0.3,
                "frame {f}: the kick is bass (low {}, high {})",
                frame.low,
                frame.high
            );
        }
    }
    // A kick every 30 frames, found within a frame of where it starts.
    assert!((19..=20).contains(&onsets.len()), "{onsets:?}");
    for f in &onsets {
        assert!(f % 30 <= 1 || f % 30 == 29, "onset at frame {f}: {onsets:?}");
    }
    let bpm = frames.last().unwrap().bpm.expect("a tempo after 10 s");
    assert!((bpm - 120.0).abs() < 1.0, "{bpm}");
}

#[test]
fn a_render_hears_the_file_exactly_played_or_sought_and_carries_it_as_sound() {
    let dir = temp_dir("render");
    let wav = dir.join("beat.wav");
    write_beat(&wav, 2.0);
    let render = |out: &str, start: &str, frames: &str, audio: bool| {
        let out = dir.join(out);
        let mut args = vec!["render", "kleinian_star_glow", "--size", "64x36", "--start", start, "--frames", frames];
        args.extend(["--out", out.to_str().unwrap()]);
        if audio {
            args.extend(["--audio", wav.to_str().unwrap()]);
        }
        let o = indra(&args);
        assert!(o.status.success(), "{}", text(&o));
        out
    };
    let (a, b) = (render("a", "0", "31", true), render("b", "0", "31", true));
    let sought = render("c", "30", "1", true);
    let silent = render("d", "0", "31", false);
    let png = |dir: &Path, f: u32| std::fs::read(dir.join(format!("kleinian_star_glow_{f:05}.png"))).unwrap();
    for f in [0, 15, 30] {
        assert_eq!(png(&a, f), png(&b, f), "frame {f}: two renders hear the same");
    }
    assert_eq!(png(&a, 30), png(&sought, 30), "frame 30 sought hears what playing hears");
    assert_ne!(png(&a, 30), png(&silent, 30), "the kick moves the glow and the zoom");

    let video = dir.join("clip.mp4");
    let o = indra(&[
        "render",
        "kleinian_star_glow",
        "--size",
        "64x36",
        "--frames",
        "30",
        "--start",
        "15",
        "--audio",
        wav.to_str().unwrap(),
        "--video",
        video.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let probe = Command::new("ffprobe")
        .args(["-v", "error", "-show_entries", "stream=codec_type,codec_name,duration", "-of", "csv=p=0"])
        .arg(&video)
        .output()
        .expect("ffprobe runs");
    let streams = String::from_utf8_lossy(&probe.stdout);
    let audio = streams.lines().find(|l| l.contains("audio")).unwrap_or_else(|| panic!("no sound track: {streams}"));
    assert!(audio.starts_with("aac"), "{audio}");
    let duration: f64 = audio.rsplit(',').next().unwrap().parse().unwrap();
    assert!((duration - 0.5).abs() < 0.06, "the sound lasts as long as the 30 frames: {duration}");
}

#[test]
fn a_bad_audio_file_is_one_sentence() {
    let dir = temp_dir("bad");
    let not_wav = dir.join("song.wav");
    std::fs::write(&not_wav, b"ID3 this is an mp3, really").unwrap();
    for (path, said) in [
        (not_wav, "is neither a WAV file nor audio ffmpeg can decode"),
        (dir.join("missing.wav"), "cannot read audio file"),
    ] {
        let o = indra(&["render", "kleinian_star_glow", "--size", "32x32", "--audio", path.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        assert!(text(&o).contains(said) && !text(&o).contains("panicked"), "{}", text(&o));
    }
}

#[test]
fn other_formats_are_decoded_by_ffmpeg_to_the_same_sound() {
    let dir = temp_dir("formats");
    let wav = dir.join("beat.wav");
    write_beat(&wav, 6.0);
    let reference = AudioFile::open(&wav).unwrap();
    for ext in ["flac", "mp3", "ogg"] {
        let encoded = dir.join(format!("beat.{ext}"));
        let made = Command::new("ffmpeg").args(["-v", "error", "-y", "-i"]).arg(&wav).arg(&encoded).status().unwrap();
        assert!(made.success(), "ffmpeg could not make {ext}");
        let file = AudioFile::open(&encoded).unwrap_or_else(|e| panic!("{ext}: {e}"));
        assert_eq!(file.rate, RATE, "{ext}");
        // Lossy codecs add a little padding at the start; the length stays within 0.1 s.
        assert!((file.seconds() - 6.0).abs() < 0.1, "{ext}: {} s", file.seconds());
        if ext == "flac" {
            let worst = file.samples.iter().zip(&reference.samples).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
            assert!(worst < 1e-4, "flac is lossless: off by {worst}");
        }
        let frames = analyse_file(&file, 360, 1.0 / 60.0);
        let bpm = frames.last().unwrap().bpm.expect("a tempo after 6 s");
        assert!((bpm - 120.0).abs() < 1.0, "{ext}: {bpm}");
    }
}

#[test]
fn the_bundled_loop_has_its_tempo_and_drives_kleinian_audio_to_its_goldens() {
    let wav = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/audio/demo-beat.wav");
    let file = AudioFile::open(Path::new(wav)).unwrap();
    let frames = analyse_file(&file, 480, 1.0 / 60.0);
    assert!((frames[479].bpm.expect("a tempo after 8 s") - 120.0).abs() < 1.0);
    // Once the tempo is heard: a beat every 30 frames, on the kicks.
    let beats: Vec<usize> = (300..480).filter(|&f| frames[f].beat).collect();
    assert_eq!(beats.len(), 6, "{beats:?}");
    assert!(beats.iter().all(|f| f % 30 <= 2 || f % 30 >= 28), "within 2 frames of the kicks: {beats:?}");

    let dir = temp_dir("golden");
    let size = (192, 108);
    for frame in [45u32, 100] {
        let start = frame.to_string();
        let o = indra(&[
            "render",
            "kleinian_audio",
            "--size",
            "192x108",
            "--start",
            &start,
            "--frames",
            "1",
            "--audio",
            wav,
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", text(&o));
        let png = image::open(dir.join(format!("kleinian_audio_{frame:05}.png"))).unwrap().to_rgba8();
        common::golden(0.01, 0.3).check(&format!("kleinian_audio_f{frame:04}"), size, png.as_raw()).unwrap();
    }
}
