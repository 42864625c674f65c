//! LTC written by libltc (Debian's libltc-dev, through `tests/timecode/ltcgen.c`), an encoder
//! not written here, read back by indra's decoder frame-exactly at every rate, across the
//! labels drop-frame skips, at 48 and 44.1 kHz, forwards and backwards. Without libltc the
//! tests say they were skipped, except on CI.

use indra::timecode::ltc::{LtcDecoder, LtcFrame};
use indra::timecode::{Rate, Timecode};
use std::path::PathBuf;
use std::process::Command;

/// libltc's generator, built once per run; `None` (skipped) without libltc.
fn ltcgen() -> Option<PathBuf> {
    static BUILT: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();
    let built = BUILT.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("indra-ltcgen-{}", std::process::id()));
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        let exe = dir.join("ltcgen");
        let source = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/timecode/ltcgen.c");
        let out = Command::new("cc")
            .args(["-O2", "-o"])
            .arg(&exe)
            .arg(source)
            .arg("-lltc")
            .output()
            .map_err(|e| format!("no C compiler: {e}"))?;
        if !out.status.success() {
            return Err(format!("libltc's generator did not build: {}", String::from_utf8_lossy(&out.stderr)));
        }
        Ok(exe)
    });
    match built {
        Ok(exe) => Some(exe.clone()),
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

/// What libltc writes for `count` frames from `first` at `fps`, at `sample_rate`, as samples
/// around zero.
fn libltc_audio(exe: &PathBuf, sample_rate: u32, fps: &str, first: &str, count: u32, reverse: bool) -> Vec<f32> {
    let mut args = vec![sample_rate.to_string(), fps.to_string(), first.to_string(), count.to_string()];
    if reverse {
        args.push("reverse".into());
    }
    let out = Command::new(exe).args(&args).output().unwrap();
    assert!(out.status.success(), "ltcgen {args:?}: {}", String::from_utf8_lossy(&out.stderr));
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
            let frames = decode(&libltc_audio(&exe, sample_rate, fps, first, 100, false), sample_rate);
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
    let frames = decode(&libltc_audio(&exe, 48_000, "25", "10:00:02:00", 60, true), 48_000);
    assert!(frames.len() >= 58, "{} of 60 frames read", frames.len());
    assert!(frames.iter().all(|f| f.reverse && f.rate == rate), "{frames:?}");
    let counts: Vec<u64> = frames.iter().map(|f| rate.count(f.timecode).unwrap()).collect();
    assert!(counts.windows(2).all(|w| w[1] + 1 == w[0]), "not counting down: {counts:?}");
}
