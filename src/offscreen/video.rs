//! Video files through an `ffmpeg` process: raw RGBA frames are streamed into its standard input,
//! so the video holds exactly the frames the PNG path would write, encoded by a well-kept encoder
//! instead of one of ours.
//!
//! The container follows the file's extension and picks a codec a client can play: H.264 (CRF 18,
//! yuv420p) in `.mp4` and `.mkv`, ProRes 422 HQ in `.mov`, VP9 in `.webm`. Odd sizes are padded by
//! one black row or column (4:2:0 chroma needs even sides). Colours are tagged BT.709.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use super::frame_pipe::FramePipe;

pub use crate::media::ffmpeg::FFMPEG_ENV;

/// What to encode and how.
#[derive(Clone, Debug)]
pub struct VideoSettings {
    /// The file to write; its extension picks the container.
    pub path: PathBuf,
    /// Frame size in pixels (the RGBA rows given to [`VideoWriter::write`]).
    pub size: (u32, u32),
    /// Frames per second (1 / the scene's dt).
    pub fps: f64,
    /// Codec: `h264`, `h265`, `prores`, `vp9`, `av1`, `ffv1`, or any ffmpeg encoder name
    /// (default: the container's, see the module docs).
    pub codec: Option<String>,
    /// Quality: the CRF for H.264/H.265/VP9/AV1 (lower is better), the ProRes profile (0 proxy …
    /// 3 HQ, 4 4444); lossless FFV1 ignores it.
    pub quality: Option<u32>,
    /// A sound track: the audio file and the second of it the first frame shows (a render that
    /// starts at frame n starts n × dt into the file).
    pub audio: Option<(PathBuf, f64)>,
    /// `path` is a network stream's URL (`srt://`, `udp://`, `rtmp://`), not a file: H.264 tuned
    /// for latency (no B-frames, a keyframe a second) in MPEG-TS, or FLV for RTMP.
    pub stream: bool,
    /// For a stream: frames come faster than real time (a render), so ffmpeg paces them to `fps`.
    pub pace: bool,
}

impl VideoSettings {
    /// A network stream to `url` of frames of `size` at `fps`; with `pace`, ffmpeg paces frames
    /// that come faster than real time (a render).
    pub fn stream(url: &str, size: (u32, u32), fps: f64, pace: bool) -> Self {
        Self { path: url.into(), size, fps, codec: None, quality: None, audio: None, stream: true, pace }
    }
}

/// The URL schemes `--stream` sends to, with the container each carries.
pub const STREAM_SCHEMES: &[(&str, &str)] = &[("srt", "mpegts"), ("udp", "mpegts"), ("rtmp", "flv"), ("rtmps", "flv")];

/// Why a video could not be written; each is one sentence for the user.
#[derive(Debug, thiserror::Error)]
pub enum VideoError {
    /// No ffmpeg to run.
    #[error(
        "ffmpeg was not found ({0}): install it (`apt-get install ffmpeg`, or tools/setup-system run) or name it in {FFMPEG_ENV}"
    )]
    NoFfmpeg(String),
    /// The extension names no container we know.
    #[error("{0}: write a video as .mp4, .mov, .webm or .mkv")]
    Container(String),
    /// A codec that does not fit the container, or a quality out of range.
    #[error("{0}")]
    Settings(String),
    /// ffmpeg stopped, or ended with an error.
    #[error("ffmpeg failed writing {path}: {detail}")]
    Ffmpeg {
        /// The video file.
        path: String,
        /// ffmpeg's own last lines, or how it ended.
        detail: String,
    },
}

/// A running encoder; frames go in with [`VideoWriter::write`], [`VideoWriter::finish`] closes
/// the file. Dropping it without `finish` kills ffmpeg (the file is then incomplete).
pub struct VideoWriter {
    pipe: FramePipe,
    settings: VideoSettings,
    frames: u64,
}

/// The codec's ffmpeg arguments: encoder, pixel format and quality.
fn codec_args(codec: &str, quality: Option<u32>) -> Result<Vec<String>, VideoError> {
    let crf = |default: u32, max: u32, encoder: &str, pix: &str| -> Result<Vec<String>, VideoError> {
        let q = quality.unwrap_or(default);
        if q > max {
            return Err(VideoError::Settings(format!("--quality {q} is past {max}, the worst CRF of {codec}")));
        }
        let mut args = vec!["-c:v".into(), encoder.into(), "-pix_fmt".into(), pix.into(), "-crf".into(), q.to_string()];
        if encoder == "libvpx-vp9" || encoder == "libaom-av1" {
            // Constant quality for VP9/AV1 needs the bitrate cap switched off.
            args.extend(["-b:v".into(), "0".into()]);
        }
        Ok(args)
    };
    match codec {
        "h264" | "libx264" => crf(18, 51, "libx264", "yuv420p"),
        "h265" | "hevc" | "libx265" => crf(20, 51, "libx265", "yuv420p"),
        "vp9" | "libvpx-vp9" => crf(30, 63, "libvpx-vp9", "yuv420p"),
        "av1" | "libaom-av1" => crf(30, 63, "libaom-av1", "yuv420p"),
        "prores" | "prores_ks" => {
            let profile = quality.unwrap_or(3);
            if profile > 4 {
                return Err(VideoError::Settings(format!(
                    "--quality {profile} is no ProRes profile: 0 proxy, 1 LT, 2 standard, 3 HQ, 4 4444"
                )));
            }
            let pix = if profile == 4 { "yuva444p10le" } else { "yuv422p10le" };
            Ok(["-c:v", "prores_ks", "-profile:v", &profile.to_string(), "-pix_fmt", pix].map(String::from).to_vec())
        }
        "ffv1" => Ok(["-c:v", "ffv1", "-level", "3", "-pix_fmt", "bgr0"].map(String::from).to_vec()),
        // HAP, the VJ codec (every frame a keyframe, decoded on the GPU): indra plays it back
        // frame-exact, so a scene can be rendered to a clip for a show. Sides must be multiples
        // of 4 (ffmpeg's encoder refuses others).
        "hap" | "hap_alpha" | "hap_q" => {
            Ok(["-c:v", "hap", "-format", codec, "-pix_fmt", "rgba"].map(String::from).to_vec())
        }
        other => {
            let mut args = vec!["-c:v".into(), other.into(), "-pix_fmt".into(), "yuv420p".into()];
            if let Some(q) = quality {
                args.extend(["-q:v".into(), q.to_string()]);
            }
            Ok(args)
        }
    }
}

/// The container's default codec, from the file's extension.
fn default_codec(path: &Path) -> Result<&'static str, VideoError> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "mp4" | "mkv" => Ok("h264"),
        "mov" => Ok("prores"),
        "webm" => Ok("vp9"),
        _ => Err(VideoError::Container(path.display().to_string())),
    }
}

/// `fps` as the exact fraction ffmpeg should use: whole rates stay whole, NTSC rates become
/// n·1000/1001, anything else is kept to a thousandth. A dt of 0.0166667 is 60, not 59.99988.
pub fn frame_rate(fps: f64) -> String {
    let whole = fps.round();
    if (fps - whole).abs() < 1e-5 * fps && whole >= 1.0 {
        return format!("{whole}");
    }
    let ntsc = (fps * 1.001).round();
    if (fps - ntsc * 1000.0 / 1001.0).abs() < 1e-4 * fps {
        return format!("{}/1001", ntsc * 1000.0);
    }
    format!("{}/1000", (fps * 1000.0).round().max(1.0))
}

/// Asks `program` whether it has `encoder` (`ffmpeg -h encoder=NAME` names it when it does).
fn check_encoder(program: &std::ffi::OsStr, encoder: &str) -> Result<(), VideoError> {
    let output = Command::new(program)
        .args(["-hide_banner", "-h", &format!("encoder={encoder}")])
        .stdin(Stdio::null())
        .output()
        .map_err(|e| VideoError::NoFfmpeg(format!("{}: {e}", program.to_string_lossy())))?;
    let text = String::from_utf8_lossy(&output.stdout);
    if text.contains(&format!("Encoder {encoder} ")) {
        Ok(())
    } else {
        Err(VideoError::Settings(format!(
            "this ffmpeg has no encoder '{encoder}' (`ffmpeg -encoders` lists those it has)"
        )))
    }
}

impl VideoSettings {
    /// The size of the encoded picture: odd sides grow by one (padded black), as 4:2:0 needs.
    pub fn encoded_size(&self) -> (u32, u32) {
        (self.size.0.next_multiple_of(2), self.size.1.next_multiple_of(2))
    }

    /// The full ffmpeg command line after the program name.
    pub fn ffmpeg_args(&self) -> Result<Vec<String>, VideoError> {
        // A video goes to a file: `http://…` or `rtmp://…` would make ffmpeg stream to the
        // network from an option meant for a file name. Streams are asked for by name.
        let named = self.path.display().to_string();
        let stream_format = if self.stream {
            let scheme = named.split_once("://").map(|(s, _)| s.to_ascii_lowercase()).unwrap_or_default();
            let format = STREAM_SCHEMES.iter().find(|(s, _)| *s == scheme).map(|(_, f)| *f);
            Some(format.ok_or_else(|| {
                VideoError::Settings(format!(
                    "'{named}': a stream goes to srt://HOST:PORT, udp://HOST:PORT or rtmp://…"
                ))
            })?)
        } else {
            None
        };
        if named.contains("://") && !self.stream {
            return Err(VideoError::Settings(format!("'{named}' is a URL; video and audio options take file names")));
        }
        let container = if self.stream { "h264" } else { default_codec(&self.path)? };
        let codec = self.codec.as_deref().unwrap_or(container);
        if !(self.fps.is_finite() && self.fps > 0.0) {
            return Err(VideoError::Settings(format!("{} frames per second is no frame rate", self.fps)));
        }
        let (w, h) = self.size;
        let mut args: Vec<String> = [
            "-hide_banner",
            "-nostdin",
            "-loglevel",
            "error",
            "-y",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgba",
            "-s",
            &format!("{w}x{h}"),
            "-framerate",
            &frame_rate(self.fps),
            "-i",
            "pipe:0",
        ]
        .map(String::from)
        .to_vec();
        if self.stream && self.pace {
            // A stream goes out in real time: frames a render makes faster than that are paced
            // (a receiver, like a screen, takes them at the frame rate; a burst is lost). Not for
            // the live show, whose frames come in real time: pacing them again costs ≈ 90 ms.
            args.insert(args.iter().position(|a| a == "-f").unwrap_or(0), "-re".into());
        }
        if let Some((file, offset)) = &self.audio {
            args.extend(["-ss".into(), format!("{offset:.6}"), "-i".into(), ffmpeg_file(file)]);
            args.extend(["-map".into(), "0:v".into(), "-map".into(), "1:a".into()]);
            let ext = self.path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
            let audio_codec: &[&str] = match ext.as_str() {
                "mov" => &["-c:a", "pcm_s16le"],
                "webm" => &["-c:a", "libopus", "-b:a", "160k"],
                _ => &["-c:a", "aac", "-b:a", "192k"],
            };
            args.extend(audio_codec.iter().map(|s| s.to_string()));
            // The video decides the length; the sound stops with the last frame.
            args.push("-shortest".into());
        }
        // Pad odd sides (4:2:0 needs even ones; HAP's 4×4 blocks, multiples of 4) and convert
        // with the BT.709 matrix players assume for HD, instead of swscale's BT.601 default.
        let side = if codec.starts_with("hap") { 4 } else { 2 };
        args.extend([
            "-vf".into(),
            format!("pad=ceil(iw/{side})*{side}:ceil(ih/{side})*{side},scale=out_color_matrix=bt709:out_range=tv"),
            "-colorspace".into(),
            "bt709".into(),
            "-color_primaries".into(),
            "bt709".into(),
            "-color_trc".into(),
            "bt709".into(),
        ]);
        args.extend(codec_args(codec, self.quality)?);
        if let Some(format) = stream_format {
            // Latency over size: the fastest preset, no look-ahead or B-frames, a keyframe a
            // second so a receiver that joins late starts within one.
            let keyframes = (self.fps.round() as u32).max(1).to_string();
            args.extend(
                ["-preset", "ultrafast", "-tune", "zerolatency", "-bf", "0", "-g", &keyframes, "-f", format]
                    .map(String::from),
            );
            args.push(named);
            return Ok(args);
        }
        if matches!(self.path.extension().and_then(|e| e.to_str()), Some("mp4" | "mov")) {
            // The index at the front: the file plays while it still downloads.
            args.extend(["-movflags".into(), "+faststart".into()]);
        }
        args.push(ffmpeg_file(&self.path));
        Ok(args)
    }
}

use crate::media::ffmpeg::file_arg as ffmpeg_file;

impl VideoWriter {
    /// Starts ffmpeg writing `settings.path` (its folder is created). A missing ffmpeg, or one
    /// without the encoder, fails here rather than after the frames were rendered.
    pub fn start(settings: VideoSettings) -> Result<Self, VideoError> {
        let args = settings.ffmpeg_args()?;
        let program = std::env::var_os(FFMPEG_ENV).unwrap_or_else(|| "ffmpeg".into());
        let encoder = args.iter().skip_while(|a| *a != "-c:v").nth(1).cloned().unwrap_or_default();
        check_encoder(&program, &encoder)?;
        if let Some(folder) = settings.path.parent().filter(|p| !p.as_os_str().is_empty() && !settings.stream) {
            std::fs::create_dir_all(folder).map_err(|e| VideoError::Ffmpeg {
                path: settings.path.display().to_string(),
                detail: format!("cannot create {}: {e}", folder.display()),
            })?;
        }
        let pipe = FramePipe::spawn(&program, &args)
            .map_err(|e| VideoError::NoFfmpeg(format!("{}: {e}", program.to_string_lossy())))?;
        Ok(Self { pipe, settings, frames: 0 })
    }

    /// Frames written so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// The settings it was started with.
    pub fn settings(&self) -> &VideoSettings {
        &self.settings
    }

    /// Appends one frame: `rgba` is width × height × 4 bytes, top row first.
    pub fn write(&mut self, rgba: &[u8]) -> Result<(), VideoError> {
        let (w, h) = self.settings.size;
        let expected = w as usize * h as usize * 4;
        if rgba.len() != expected {
            return Err(VideoError::Settings(format!(
                "a frame of {} bytes does not fit the video's {w}x{h} ({expected} bytes)",
                rgba.len()
            )));
        }
        // ffmpeg quit (bad codec, full disk): its own words say why better than a broken pipe.
        self.pipe.write(rgba).map_err(|detail| self.failure(detail))?;
        self.frames += 1;
        Ok(())
    }

    /// Closes the input and waits for ffmpeg to finish the file; returns the frames written.
    pub fn finish(mut self) -> Result<u64, VideoError> {
        self.pipe.finish().map_err(|detail| self.failure(detail))?;
        Ok(self.frames)
    }

    /// An error naming the file, with ffmpeg's last words.
    fn failure(&self, detail: String) -> VideoError {
        VideoError::Ffmpeg { path: self.settings.path.display().to_string(), detail }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(path: &str) -> VideoSettings {
        VideoSettings {
            path: path.into(),
            size: (64, 48),
            fps: 60.0,
            codec: None,
            quality: None,
            audio: None,
            stream: false,
            pace: false,
        }
    }

    #[test]
    fn frame_rates_are_exact_fractions() {
        assert_eq!(frame_rate(1.0 / 0.0166667), "60");
        assert_eq!(frame_rate(30.0), "30");
        assert_eq!(frame_rate(30000.0 / 1001.0), "30000/1001");
        assert_eq!(frame_rate(24000.0 / 1001.0), "24000/1001");
        assert_eq!(frame_rate(12.5), "12500/1000");
    }

    #[test]
    fn containers_pick_their_codec_and_unknown_ones_are_refused() {
        let args = |p: &str| settings(p).ffmpeg_args().map(|a| a.join(" "));
        assert!(args("a.mp4").unwrap().contains("-c:v libx264 -pix_fmt yuv420p -crf 18"));
        assert!(args("a.mkv").unwrap().contains("libx264"));
        assert!(args("a.mov").unwrap().contains("-c:v prores_ks -profile:v 3"));
        assert!(args("a.webm").unwrap().contains("libvpx-vp9"));
        assert!(args("A.MP4").unwrap().ends_with(" file:A.MP4"));
        assert!(args("-y.mp4").unwrap().ends_with(" file:-y.mp4"), "a name like an option is a file");
        assert!(args("http://example.com/live.mp4").is_err(), "a URL is no file name");
        let mut with_sound = settings("a.mp4");
        with_sound.audio = Some(("mix:final.wav".into(), 0.0));
        assert!(with_sound.ffmpeg_args().unwrap().join(" ").contains("-i file:mix:final.wav"));
        let e = args("a.gif").unwrap_err().to_string();
        assert!(e.contains(".mp4, .mov, .webm or .mkv"), "{e}");
    }

    #[test]
    fn quality_out_of_range_is_one_sentence() {
        let mut s = settings("a.mp4");
        s.quality = Some(60);
        assert!(s.ffmpeg_args().unwrap_err().to_string().contains("past 51"));
        let mut s = settings("a.mov");
        s.quality = Some(7);
        assert!(s.ffmpeg_args().unwrap_err().to_string().contains("no ProRes profile"));
        s.fps = f64::NAN;
        assert!(s.ffmpeg_args().is_err());
    }
}
