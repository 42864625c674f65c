//! Every codec that is not HAP (H.264, ProRes, VP9, PNG sequences, …) and every camera, through
//! an `ffmpeg` process that writes raw RGBA frames to a pipe — the well-kept decoder, not one of
//! ours, as export already encodes through one.
//!
//! A clip is probed once (`ffprobe`), then decoded in order from wherever it is asked to start:
//! frame k starts a process with an exact seek to k (ffmpeg decodes from the keyframe before
//! and drops what precedes k), and following frames are read on from the same process. So frame
//! k is the same pixels whether a render reaches it by playing or by seeking.

use std::io::Read;
use std::path::Path;
use std::process::{Child, ChildStdout, Command, Stdio};

/// The environment variable naming the `ffmpeg` to run (default: `ffmpeg` on the PATH).
pub const FFMPEG_ENV: &str = "INDRA_FFMPEG";

/// The environment variable naming the `ffprobe` to run (default: `ffprobe` on the PATH).
pub const FFPROBE_ENV: &str = "INDRA_FFPROBE";

/// How far ahead (in frames) a forward jump reads on instead of starting a new process.
const READ_ON_LIMIT: usize = 48;

/// The containers a clip may be (ffmpeg's demuxer names): those that hold their media and name
/// no other file. Playlists (HLS, DASH, concat, ffconcat) are not among them: a `.mov` that is
/// really an HLS playlist made ffmpeg open files outside every allowed folder — FIFOs too.
pub const CLIP_FORMATS: &str = "mov,mp4,matroska,webm,avi,mpegts,mpeg,flv,ivf,gif,apng,yuv4mpegpipe,asf,ogg,mxf,\
     h264,hevc,m4v,mjpeg,image2,png_pipe,jpeg_pipe,webp_pipe,exr_pipe";

/// The input options every clip is opened with: the containers above, and the `file` protocol
/// alone (no network, no pipes, no protocol a name could smuggle in).
pub fn clip_input_guard() -> [&'static str; 4] {
    ["-format_whitelist", CLIP_FORMATS, "-protocol_whitelist", "file"]
}

/// How long a probe may take before it is ended and the clip refused (ffprobe has no timeout
/// of its own, and a file that reads for ever would hold the load for ever).
pub const PROBE_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(10);

/// The ffmpeg (or ffprobe) program to run.
pub fn program(env: &str, default: &str) -> std::ffi::OsString {
    std::env::var_os(env).unwrap_or_else(|| default.into())
}

/// The sentence for a missing ffmpeg or ffprobe.
pub fn not_found(program: &std::ffi::OsStr, e: &std::io::Error) -> String {
    format!(
        "{} was not found ({e}): install ffmpeg (`apt-get install ffmpeg`, or tools/setup-system run) or name it in {FFMPEG_ENV}/{FFPROBE_ENV}",
        program.to_string_lossy()
    )
}

/// `path` as ffmpeg must read it to take it as a file: with the `file:` protocol, so that a name
/// like `-y.mp4` is no option and `mix:clip.mov` no protocol.
pub fn file_arg(path: &Path) -> String {
    format!("file:{}", path.display())
}

/// What ffprobe says about a clip's first video stream.
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    /// Frame size in pixels.
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// Frames per second.
    pub fps: f64,
    /// Frames in the clip.
    pub frames: usize,
    /// The codec's name (`h264`, `prores`, …).
    pub codec: String,
    /// Whether the stream has an alpha channel.
    pub alpha: bool,
}

/// Probes `path` with ffprobe, within [`PROBE_TIMEOUT`].
pub fn probe(path: &Path) -> Result<Probe, String> {
    probe_with(&program(FFPROBE_ENV, "ffprobe"), path, PROBE_TIMEOUT)
}

/// Probes `path` with the program `ffprobe`, ending it after `timeout`.
fn probe_with(ffprobe: &std::ffi::OsStr, path: &Path, timeout: std::time::Duration) -> Result<Probe, String> {
    let child = Command::new(ffprobe)
        .args(["-v", "error"])
        .args(clip_input_guard())
        .args(["-select_streams", "v:0", "-show_entries"])
        .arg("stream=width,height,r_frame_rate,avg_frame_rate,nb_frames,duration,pix_fmt,codec_name:format=duration")
        .args(["-of", "json"])
        .arg(file_arg(path))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| not_found(ffprobe, &e))?;
    let output = output_within(child, timeout)
        .ok_or_else(|| format!("ffprobe gave no answer within {timeout:?}; the file is refused"))?;
    if !output.status.success() {
        let said = String::from_utf8_lossy(&output.stderr);
        let said = said.lines().last().unwrap_or("it could not be read").trim();
        return Err(format!("not a video ffmpeg can read: {said}"));
    }
    parse_probe(&String::from_utf8_lossy(&output.stdout))
}

/// The output of `child` once it exits, read as it comes (so a full pipe never stalls it), or
/// `None` when it runs past `timeout` (it is then killed). Each pipe keeps its first 1 MiB.
fn output_within(mut child: Child, timeout: std::time::Duration) -> Option<std::process::Output> {
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(pipe) = pipe {
                let mut pipe = pipe.take(1 << 20);
                let _ = pipe.read_to_end(&mut bytes);
            }
            bytes
        })
    };
    let stdout = drain(child.stdout.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    let stderr = drain(child.stderr.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    let deadline = std::time::Instant::now() + timeout;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if std::time::Instant::now() < deadline => {
                std::thread::sleep(std::time::Duration::from_millis(10))
            }
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                return None;
            }
        }
    };
    Some(std::process::Output { status, stdout: stdout.join().ok()?, stderr: stderr.join().ok()? })
}

/// Reads ffprobe's JSON.
fn parse_probe(json: &str) -> Result<Probe, String> {
    let value: serde_json::Value =
        serde_json::from_str(json).map_err(|e| format!("ffprobe said something unreadable: {e}"))?;
    let stream = value["streams"].get(0).ok_or("the file has no video stream")?;
    let number = |v: &serde_json::Value| v.as_str().and_then(|s| s.parse::<f64>().ok()).or_else(|| v.as_f64());
    let rate = |v: &serde_json::Value| {
        let text = v.as_str()?;
        let (n, d) = text.split_once('/').unwrap_or((text, "1"));
        let (n, d) = (n.parse::<f64>().ok()?, d.parse::<f64>().ok()?);
        (n > 0.0 && d > 0.0).then(|| n / d)
    };
    let width = stream["width"].as_u64().unwrap_or(0) as u32;
    let height = stream["height"].as_u64().unwrap_or(0) as u32;
    if width == 0 || height == 0 {
        return Err("the video stream has no frame size".into());
    }
    let fps = rate(&stream["avg_frame_rate"])
        .or_else(|| rate(&stream["r_frame_rate"]))
        .ok_or("the video has no frame rate")?;
    let duration = number(&stream["duration"]).or_else(|| number(&value["format"]["duration"]));
    let frames = stream["nb_frames"]
        .as_str()
        .and_then(|n| n.parse::<usize>().ok())
        .filter(|&n| n > 0)
        .or_else(|| duration.map(|d| (d * fps).round().max(1.0) as usize))
        .ok_or("the video's length is unknown")?;
    let pix_fmt = stream["pix_fmt"].as_str().unwrap_or("");
    let alpha = ["yuva", "rgba", "bgra", "argb", "abgr", "gbrap", "ya"].iter().any(|p| pix_fmt.starts_with(p));
    Ok(Probe { width, height, fps, frames, codec: stream["codec_name"].as_str().unwrap_or("?").to_string(), alpha })
}

/// A running ffmpeg writing RGBA frames of a fixed size to its standard output.
pub struct RawPipe {
    child: Child,
    stdout: ChildStdout,
    frame_bytes: usize,
    stderr: Option<std::thread::JoinHandle<String>>,
}

impl RawPipe {
    /// Starts ffmpeg with `input` arguments (everything up to and including `-i …`), converting
    /// the first video stream to `width` × `height` RGBA.
    pub fn start(input: &[String], width: u32, height: u32) -> Result<Self, String> {
        let ffmpeg = program(FFMPEG_ENV, "ffmpeg");
        let mut child = Command::new(&ffmpeg)
            .args(["-v", "error", "-nostdin"])
            .args(input)
            .args(["-map", "0:v:0", "-fps_mode", "passthrough", "-an"])
            // Scaling only when the stream is not that size already (a camera that changed mode).
            .args(["-vf", &format!("scale={width}:{height}:flags=bicubic"), "-f", "rawvideo", "-pix_fmt", "rgba", "-"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| not_found(&ffmpeg, &e))?;
        let stdout = child.stdout.take().ok_or("ffmpeg gave no output pipe")?;
        let stderr = child.stderr.take().map(|pipe| {
            std::thread::spawn(move || {
                let mut text = String::new();
                let _ = pipe.take(64 << 10).read_to_string(&mut text);
                text
            })
        });
        Ok(Self { child, stdout, frame_bytes: width as usize * height as usize * 4, stderr })
    }

    /// The next frame, or why there is none (the stream ended, ffmpeg failed).
    pub fn next_frame(&mut self) -> Result<Vec<u8>, String> {
        let mut frame = vec![0u8; self.frame_bytes];
        match self.stdout.read_exact(&mut frame) {
            Ok(()) => Ok(frame),
            Err(_) => {
                let _ = self.child.kill();
                let _ = self.child.wait();
                let said = self.stderr.take().and_then(|h| h.join().ok()).unwrap_or_default();
                let said = said.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("").trim().to_string();
                Err(if said.is_empty() { "the video ended early".into() } else { format!("ffmpeg: {said}") })
            }
        }
    }
}

impl Drop for RawPipe {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A clip decoded by ffmpeg, read in order with exact seeks where order breaks.
pub struct FfmpegClip {
    path: std::path::PathBuf,
    probe: Probe,
    /// The running decoder and the index of the frame it gives next.
    pipe: Option<(RawPipe, usize)>,
}

impl FfmpegClip {
    /// Probes `path` and checks its frames fit `max_side` and `max_bytes`.
    pub fn open(path: &Path, max_side: u32, max_bytes: u64) -> Result<Self, String> {
        let probe = probe(path)?;
        super::check_size("the video", (probe.width, probe.height), max_side, max_bytes)?;
        Ok(Self { path: path.to_path_buf(), probe, pipe: None })
    }

    /// What ffprobe said.
    pub fn probe(&self) -> &Probe {
        &self.probe
    }

    /// Frame `index`'s RGBA pixels (straight alpha): read on from the running decoder when it
    /// is at or a little before `index`, otherwise from a new one that seeks there exactly.
    pub fn read(&mut self, index: usize) -> Result<Vec<u8>, String> {
        let reusable = matches!(&self.pipe, Some((_, next)) if *next <= index && index - *next <= READ_ON_LIMIT);
        if !reusable {
            // Half a frame before frame `index`: ffmpeg's exact seek then starts at it, whatever
            // the rounding of its timestamps.
            let seconds = (index as f64 - 0.5).max(0.0) / self.probe.fps;
            let mut input = Vec::new();
            if index > 0 {
                input.extend(["-ss".to_string(), format!("{seconds:.6}")]);
            }
            input.extend(clip_input_guard().map(String::from));
            input.extend(["-i".to_string(), file_arg(&self.path)]);
            self.pipe = Some((RawPipe::start(&input, self.probe.width, self.probe.height)?, index));
        }
        let (pipe, next) = self.pipe.as_mut().expect("started above");
        while *next < index {
            pipe.next_frame()?;
            *next += 1;
        }
        let frame = pipe.next_frame();
        *next += 1;
        if frame.is_err() {
            self.pipe = None;
        }
        frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probe_output_is_read_with_or_without_a_frame_count() {
        let json = r#"{"streams":[{"codec_name":"prores","width":64,"height":36,"pix_fmt":"yuva444p12le",
            "r_frame_rate":"30000/1001","avg_frame_rate":"30000/1001","duration":"2.002000"}],
            "format":{"duration":"2.002"}}"#;
        let p = parse_probe(json).unwrap();
        assert_eq!((p.width, p.height, p.frames, p.alpha), (64, 36, 60, true));
        assert!((p.fps - 29.97).abs() < 0.01);
        let counted = r#"{"streams":[{"codec_name":"h264","width":8,"height":8,"pix_fmt":"yuv420p",
            "avg_frame_rate":"0/0","r_frame_rate":"25/1","nb_frames":"7"}]}"#;
        let p = parse_probe(counted).unwrap();
        assert_eq!((p.frames, p.fps, p.alpha), (7, 25.0, false));
        assert!(parse_probe(r#"{"streams":[]}"#).unwrap_err().contains("no video"));
        assert!(parse_probe("nonsense").is_err());
    }

    #[test]
    fn a_probe_that_never_answers_is_ended_and_the_file_refused() {
        let dir = std::env::temp_dir().join(format!("indra-probe-timeout-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let stuck = dir.join("ffprobe");
        std::fs::write(&stuck, "#!/bin/sh\nexec sleep 30\n").unwrap();
        #[cfg(unix)]
        std::fs::set_permissions(&stuck, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
        let started = std::time::Instant::now();
        let e =
            probe_with(stuck.as_os_str(), &dir.join("clip.mov"), std::time::Duration::from_millis(500)).unwrap_err();
        assert!(e.contains("no answer within"), "{e}");
        assert!(started.elapsed() < std::time::Duration::from_secs(5), "the probe was waited for");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
