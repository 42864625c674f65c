//! LTC written by libltc (Debian's libltc-dev, through `tests/timecode/ltcgen.c`), an encoder
//! not written here, read back by indra's decoder frame-exactly at every rate, across the
//! labels drop-frame skips, at 48 and 44.1 kHz, forwards and backwards. Without libltc the
//! tests say they were skipped, except on CI.

use crate::common;
use indra::timecode::ltc::{LtcDecoder, LtcFrame};
use indra::timecode::{Rate, Timecode};
use std::path::PathBuf;
use std::process::Command;

/// libltc's generator and reader (`tests/timecode/ltcgen.c`, `ltcread.c`), built once per
/// run; `None` (skipped) without libltc.
fn libltc() -> Option<(PathBuf, PathBuf)> {
    static BUILT: std::sync::OnceLock<Result<(PathBuf, PathBuf), String>> = std::sync::OnceLock::new();
    let built = BUILT.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("indra-ltcgen-{}", std::process::id()));
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        let build = |name: &str| {
            let exe = dir.join(name);
            let source = format!("{}/tests/timecode/{name}.c", env!("CARGO_MANIFEST_DIR"));
            let out = Command::new("cc")
                .args(["-O2", "-o"])
                .arg(&exe)
                .arg(source)
                .arg("-lltc")
                .output()
                .map_err(|e| format!("no C compiler: {e}"))?;
            if !out.status.success() {
                return Err(format!("libltc's {name} did not build: {}", String::from_utf8_lossy(&out.stderr)));
            }
            Ok(exe)
        };
        Ok((build("ltcgen")?, build("ltcread")?))
    });
    match built {
        Ok(programs) => Some(programs.clone()),
        Err(problem) => {
            assert!(
                std::env::var_os("CI").is_none(),
                "CI runs the LTC tests (tools/setup-system installs libltc-dev): {problem}"
            );
            eprintln!("skipped: {problem}");
            None
        }
    }
}

/// libltc's reader.
pub(crate) fn ltcread() -> Option<PathBuf> {
    libltc().map(|(_, reader)| reader)
}

/// libltc's generator.
pub(crate) fn ltcgen() -> Option<PathBuf> {
    libltc().map(|(generator, _)| generator)
}

/// What libltc writes for `segments` (see tests/timecode/ltcgen.c) at `fps` and
/// `sample_rate`, as samples around zero.
fn libltc_audio(exe: &PathBuf, sample_rate: u32, fps: &str, segments: &[&str]) -> Vec<f32> {
    let out = Command::new(exe).arg(sample_rate.to_string()).arg(fps).args(segments).output().unwrap();
    assert!(out.status.success(), "ltcgen {segments:?}: {}", String::from_utf8_lossy(&out.stderr));
    out.stdout.iter().map(|&b| (f32::from(b) - 128.0) / 128.0).collect()
}

/// Every frame read from `audio`, fed in blocks of 480 samples as an audio callback would.
fn decode(audio: &[f32], sample_rate: u32) -> Vec<LtcFrame> {
    let mut decoder = LtcDecoder::new(sample_rate);
    let mut frames = Vec::new();
    for block in audio.chunks(480) {
        decoder.write(block, &mut frames);
    }
    frames
}

#[test]
fn libltc_code_is_read_frame_exactly_at_every_rate_and_across_dropped_labels() {
    let Some(exe) = ltcgen() else { return };
    // Starts a little before a minute that drop-frame skips labels in (00:00:59 → 00:01:00:02)
    // and before a tenth minute, which it does not (00:09:59 → 00:10:00:00).
    for (fps, rate) in [("24", Rate::Fps24), ("25", Rate::Fps25), ("29.97", Rate::Fps2997Drop), ("30", Rate::Fps30)] {
        for (first, sample_rate) in [("00:00:59:10", 48_000), ("00:09:59:10", 44_100)] {
            let start = rate.count(Timecode::parse(first).unwrap()).unwrap();
            let frames = decode(&libltc_audio(&exe, sample_rate, fps, &[&format!("{first}+100")]), sample_rate);
            assert!(frames.len() >= 97, "{rate} at {sample_rate} Hz: {} of 100 frames read", frames.len());
            let length = f64::from(sample_rate) / rate.fps();
            for frame in &frames {
                let n = rate.count(frame.timecode).unwrap() - start;
                assert!(frame.rate == rate && !frame.reverse, "{rate}: read as {frame:?}");
                // The frame ends where frame n + 1 begins, as libltc laid them out (its samples
                // are rounded to whole ones, with the remainder carried).
                let end = (n + 1) as f64 * length;
                assert!(
                    (frame.end - end).abs() < 1.5,
                    "{rate} at {sample_rate} Hz: {} ends at {:.2}, not {end:.2}",
                    frame.timecode,
                    frame.end
                );
            }
            let counts: Vec<u64> = frames.iter().map(|f| rate.count(f.timecode).unwrap()).collect();
            assert!(counts.windows(2).all(|w| w[1] == w[0] + 1), "{rate}: frames skipped or repeated: {counts:?}");
            // The last frame's last edge is the next frame's first, which never comes.
            assert_eq!(*counts.last().unwrap(), start + 98, "{rate}: the last frame read");
            if rate.is_drop() && first == "00:00:59:10" {
                let labels: Vec<String> = frames.iter().map(|f| f.timecode.to_string()).collect();
                let at = labels.iter().position(|l| l == "00:00:59:29").unwrap();
                assert_eq!(labels[at + 1], "00:01:00:02", "the two labels drop-frame skips");
            }
        }
    }
}

#[test]
fn libltc_code_played_backwards_is_read_as_reversed() {
    let Some(exe) = ltcgen() else { return };
    let rate = Rate::Fps25;
    let frames = decode(&libltc_audio(&exe, 48_000, "25", &["10:00:02:00-60"]), 48_000);
    assert!(frames.len() >= 58, "{} of 60 frames read", frames.len());
    assert!(frames.iter().all(|f| f.reverse && f.rate == rate), "{frames:?}");
    let counts: Vec<u64> = frames.iter().map(|f| rate.count(f.timecode).unwrap()).collect();
    assert!(counts.windows(2).all(|w| w[1] + 1 == w[0]), "not counting down: {counts:?}");
}

/// The SHA-256 of each frame a render wrote, by frame number, from its manifest.
fn frame_sums(folder: &std::path::Path) -> std::collections::BTreeMap<u64, String> {
    let manifest = std::fs::read_dir(folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "sha256"))
        .expect("a manifest");
    std::fs::read_to_string(manifest)
        .unwrap()
        .lines()
        .map(|line| {
            let (sum, name) = line.split_once("  ").unwrap();
            let digits: String = name.trim_end_matches(".png").chars().rev().take_while(char::is_ascii_digit).collect();
            (digits.chars().rev().collect::<String>().parse().unwrap(), sum.to_string())
        })
        .collect()
}

/// The frame a scene at 50 frames a second shows at `t` seconds, chasing 25 fps code from
/// 01:00:00:00 with a freewheel of `freewheel` seconds, having heard `heard`: (label as a frame
/// count, the second the frame ended). Said again here, apart from indra's chase, from what the
/// chase is meant to do.
fn chased_frame(heard: &[(u64, f64)], t: f64, freewheel: f64) -> u64 {
    let start = 3600 * 25;
    let Some(&(label, end)) = heard.iter().rev().find(|(_, end)| *end <= t + 1e-6) else { return 0 };
    let since = (t - end).clamp(0.0, freewheel);
    let seconds = (label as f64 + 1.0 - start as f64) / 25.0 + since;
    (seconds * 50.0 + 1e-3).floor().max(0.0) as u64
}

#[test]
fn a_render_chasing_ltc_shows_the_frame_the_code_says_seeking_on_jumps_and_freewheeling() {
    let Some(exe) = ltcgen() else { return };
    let dir = std::env::temp_dir().join(format!("indra-chase-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // 25 fps code a desk might send: a pre-roll before the timeline's start, 2 s of show, a
    // jump back, a second of silence, and the code again further on.
    let segments = ["00:59:59:13+12", "01:00:00:00+50", "01:00:00:10+25", "silence+25", "01:00:03:00+25"];
    let code = libltc_audio(&exe, 48_000, "25", &segments);
    // On the right channel of a stereo file, music (a tone) on the left.
    let wav = dir.join("show.wav");
    let spec = hound::WavSpec {
        channels: 2,
        sample_rate: 48_000,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut writer = hound::WavWriter::create(&wav, spec).unwrap();
    for (i, sample) in code.iter().enumerate() {
        let tone = 0.5 * (i as f32 * 440.0 * std::f32::consts::TAU / 48_000.0).sin();
        writer.write_sample((tone * 32767.0) as i16).unwrap();
        writer.write_sample((sample * 32767.0) as i16).unwrap();
    }
    writer.finalize().unwrap();
    // Where each code frame ends (1920 samples a frame), and its label.
    let mut frames: Vec<(u64, f64)> = Vec::new();
    let mut at = 0u64;
    let mut resumed = 0;
    for segment in segments {
        let (label, count) = segment.split_once('+').unwrap();
        let count: u64 = count.parse().unwrap();
        if label == "silence" {
            resumed = frames.len();
        } else {
            let first = Rate::Fps25.count(Timecode::parse(label).unwrap()).unwrap();
            frames.extend((0..count).map(|i| (first + i, (at + i + 1) as f64 * 0.04)));
        }
        at += count;
    }
    // A decoder that lost the signal loses the first frame after it too, or not (the level the
    // code comes back at decides): both are right.
    let lost = [frames[..resumed].to_vec(), frames[resumed + 1..].to_vec()].concat();
    let outputs = (at * 2) as usize;
    let last = format!("0-{}", outputs - 1);
    let chased = dir.join("chased");
    let (wav, chased_dir) = (wav.to_str().unwrap(), chased.to_str().unwrap());
    let chase = ["--ltc", wav, "--ltc-channel", "2", "--ltc-start", "01:00:00:00", "--freewheel", "0.5"];
    let scene = ["render", "isf_feedback", "--dt", "0.02", "--size", "64x36"];
    let ran = common::indra(&[&scene[..], &chase, &["--frames", &last, "--out", chased_dir]].concat());
    assert!(ran.status.success(), "{}", common::text(&ran));
    assert!(common::text(&ran).contains("the code jumped back"), "{}", common::text(&ran));
    let plain = dir.join("plain");
    let ran = common::indra(&[&scene[..], &["--frames", "0-200", "--out", plain.to_str().unwrap()]].concat());
    assert!(ran.status.success(), "{}", common::text(&ran));
    let (chased, plain) = (frame_sums(&chased), frame_sums(&plain));
    let distinct: std::collections::BTreeSet<&String> = plain.values().collect();
    assert!(distinct.len() > 150, "the picture moves: {} distinct frames of 201", distinct.len());
    let dt = f64::from(0.02f32);
    let mut shown = Vec::new();
    for k in 0..outputs as u64 {
        let t = k as f64 * dt;
        let wanted = [chased_frame(&frames, t, 0.5), chased_frame(&lost, t, 0.5)];
        let got = &chased[&k];
        assert!(
            wanted.iter().any(|w| plain.get(w) == Some(got)),
            "output {k} ({t:.2} s) is not frame {} of the timeline{}",
            wanted[0],
            if wanted[0] == wanted[1] { String::new() } else { format!(" or {}", wanted[1]) }
        );
        shown.push(wanted[0]);
    }
    // What the code asked for, in outline: the start, the jump back, the freewheel's hold, the
    // jump ahead.
    assert_eq!((shown[0], shown[24], shown[26], shown[30]), (0, 0, 2, 6));
    assert!(shown[124] > 95 && shown[128] < 30, "{:?}", &shown[120..130]);
    assert_eq!((shown[199], shown[205], shown[220]), (95, 95, 95), "held after the freewheel");
    assert!(shown[outputs - 1] > 190);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// What libltc's decoder reads in 48 kHz samples at `fps` (its nominal rate): each frame's
/// label and the sample its last transition is at.
fn libltc_read(reader: &PathBuf, samples: &[i16], fps: &str) -> Vec<(Timecode, u64)> {
    use std::io::Write;
    let bytes: Vec<u8> = samples.iter().flat_map(|s| s.to_le_bytes()).collect();
    let mut child = Command::new(reader)
        .args(["48000", fps])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(&bytes).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|line| {
            let fields: Vec<&str> = line.split(' ').collect();
            assert_eq!(fields[3], "0", "read as reversed: {line}");
            (Timecode::parse(fields[0]).unwrap(), fields[2].parse().unwrap())
        })
        .collect()
}

/// The samples of a mono 16-bit 48 kHz WAV.
fn wav_samples(wav: &std::path::Path) -> Vec<i16> {
    let mut file = hound::WavReader::open(wav).unwrap();
    let spec = file.spec();
    assert_eq!((spec.channels, spec.sample_rate, spec.bits_per_sample), (1, 48_000, 16));
    file.samples::<i16>().map(Result::unwrap).collect()
}

#[test]
fn ltc_a_render_writes_is_read_by_libltc_frame_exactly_and_chased_back_to_the_same_frames() {
    let Some((_, reader)) = libltc() else { return };
    let dir = std::env::temp_dir().join(format!("indra-ltc-out-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // Frames 30–179 at 50 frames a second (0.6–3.6 s), the timeline's first frame labelled
    // 00:00:58:00: the code crosses the minute, where drop-frame skips two labels.
    let scene = ["render", "isf_feedback", "--dt", "0.02", "--size", "64x36"];
    let dt = f64::from(0.02f32);
    let (from, to) = (30.0 * dt, 180.0 * dt);
    for (rate, fps) in [(Rate::Fps2997Drop, "29.97"), (Rate::Fps24, "24")] {
        let wav = dir.join(format!("{fps}.wav"));
        let written = dir.join(format!("written-{fps}"));
        let out = ["--frames", "30-179", "--out", written.to_str().unwrap(), "--ltc-start", "00:00:58:00"];
        let code = ["--ltc-out", wav.to_str().unwrap(), "--ltc-rate", if fps == "24" { "24" } else { "29.97df" }];
        let ran = common::indra(&[&scene[..], &out, &code].concat());
        assert!(ran.status.success(), "{}", common::text(&ran));
        let start = rate.count(Timecode::parse("00:00:58:00").unwrap()).unwrap();
        let read = libltc_read(&reader, &wav_samples(&wav), fps);
        // Every whole frame of the span is read (the one cut at each end may not be), its
        // label the next, and its end where the timeline's time puts it, within 3 samples (libltc
        // reads the ends of its own encoder's frames up to 3 samples early: 1 at 25 and 30 fps,
        // 2 at 29.97, 3 at 24).
        let whole = ((to - from) * rate.fps()).floor() as usize;
        assert!(read.len() + 1 >= whole, "{rate}: {} of {whole} frames read", read.len());
        let counts: Vec<u64> = read.iter().map(|(label, _)| rate.count(*label).unwrap()).collect();
        assert!(counts.windows(2).all(|w| w[1] == w[0] + 1), "{rate}: {read:?}");
        for (count, (label, end)) in counts.iter().zip(&read) {
            let due = ((*count + 1 - start) as f64 / rate.fps() - from) * 48_000.0;
            assert!((*end as f64 - due).abs() <= 3.0, "{rate}: {label} ends at sample {end}, not {due:.1}");
        }
        if rate == Rate::Fps2997Drop {
            let labels: Vec<String> = read.iter().map(|(label, _)| label.to_string()).collect();
            let minute = labels.iter().position(|l| l == "00:00:59:29").expect("the last label of minute 0");
            assert_eq!(labels[minute + 1], "00:01:00:02", "drop-frame skips 00 and 01");
        }
    }
    // Chased back, frame by frame, output k (k × dt into the file) is frame 30 + k once the
    // first whole code frame is heard, and the first frame before.
    let wav = dir.join("29.97.wav");
    let chased = dir.join("chased");
    let chase = ["--ltc", wav.to_str().unwrap(), "--ltc-start", "00:00:58:00", "--frames", "0-149"];
    let ran = common::indra(&[&scene[..], &chase, &["--out", chased.to_str().unwrap()]].concat());
    assert!(ran.status.success(), "{}", common::text(&ran));
    let (chased, written) = (frame_sums(&chased), frame_sums(&dir.join("written-29.97")));
    let heard = libltc_read(&reader, &wav_samples(&wav), "29.97")[0].1 as f64 / 48_000.0;
    let plain_zero = {
        let zero = dir.join("zero");
        let ran = common::indra(&[&scene[..], &["--frames", "0-0", "--out", zero.to_str().unwrap()]].concat());
        assert!(ran.status.success(), "{}", common::text(&ran));
        frame_sums(&zero)[&0].clone()
    };
    for k in 0..150u64 {
        let t = k as f64 * dt;
        let got = &chased[&k];
        if t > heard + 0.001 {
            assert_eq!(got, &written[&(30 + k)], "output {k} ({t:.2} s) is not frame {}", 30 + k);
        } else if t < heard - 0.001 {
            assert_eq!(got, &plain_zero, "output {k} ({t:.2} s), before any code, is not frame 0");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
