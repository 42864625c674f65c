//! A clip file as numbered frames: HAP `.mov` files read straight from their sample tables (any
//! frame is one seek, one read and Snappy), everything else through ffmpeg.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use super::ffmpeg::FfmpegClip;
use super::hap::{self, BlockFormat, HapFrame};
use super::mov::{self, VideoTrack};
use super::picture::Picture;
use super::sequence::ImageSequence;

/// What a clip is.
#[derive(Clone, Debug, PartialEq)]
pub struct ClipInfo {
    /// Frame size in pixels.
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// Frames in the clip.
    pub frames: usize,
    /// Frames per second (average).
    pub fps: f64,
    /// The codec, for messages and the panel (`Hap1`, `HapY`, `h264`, …).
    pub codec: String,
    /// Whether the clip carries alpha.
    pub alpha: bool,
    /// Whether any frame is a random access (HAP); otherwise frames decode best in order.
    pub random_access: bool,
}

impl ClipInfo {
    /// The clip's length in seconds.
    pub fn duration(&self) -> f64 {
        if self.fps > 0.0 { self.frames as f64 / self.fps } else { 0.0 }
    }
}

/// A clip's frames, by index.
pub enum Clip {
    /// A HAP track of a QuickTime file.
    Hap(HapClip),
    /// Anything ffmpeg decodes.
    Ffmpeg(FfmpegClip),
    /// Numbered stills at a given frame rate.
    Sequence(ImageSequence, f64),
}

impl Clip {
    /// Opens `path`: a QuickTime/MP4 file whose video is HAP is read directly, anything else
    /// through ffmpeg. Frames larger than `max_side` on a side or `max_bytes` decoded are
    /// refused here, before any is read.
    pub fn open(path: &Path, max_side: u32, max_bytes: u64) -> Result<Clip, String> {
        if let Some(clip) = HapClip::open(path, max_side, max_bytes)? {
            return Ok(Clip::Hap(clip));
        }
        Ok(Clip::Ffmpeg(FfmpegClip::open(path, max_side, max_bytes)?))
    }

    /// The frames of `folder` whose names match `pattern` (`take_%04d.png`), at `fps`.
    pub fn open_sequence(
        folder: &Path,
        pattern: &str,
        fps: f64,
        max_side: u32,
        max_bytes: u64,
    ) -> Result<Clip, String> {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(format!("{fps} frames per second is no frame rate"));
        }
        Ok(Clip::Sequence(ImageSequence::open(folder, pattern, max_side, max_bytes)?, fps))
    }

    /// What the clip is.
    pub fn info(&self) -> ClipInfo {
        match self {
            Clip::Hap(c) => c.info(),
            Clip::Ffmpeg(c) => {
                let p = c.probe();
                ClipInfo {
                    width: p.width,
                    height: p.height,
                    frames: p.frames,
                    fps: p.fps,
                    codec: p.codec.clone(),
                    alpha: p.alpha,
                    random_access: false,
                }
            }
            Clip::Sequence(sequence, fps) => ClipInfo {
                width: sequence.size().0,
                height: sequence.size().1,
                frames: sequence.len(),
                fps: *fps,
                codec: "image sequence".into(),
                alpha: sequence.alpha(),
                random_access: true,
            },
        }
    }

    /// Frame `index` (0-based, below `info().frames`).
    pub fn read(&mut self, index: usize) -> Result<Picture, String> {
        match self {
            Clip::Hap(c) => c.read(index).map(Picture::Hap),
            Clip::Ffmpeg(c) => c.read(index).map(Picture::Rgba),
            Clip::Sequence(s, _) => s.read(index),
        }
    }
}

/// A HAP clip: the open file and its sample tables.
pub struct HapClip {
    file: File,
    track: VideoTrack,
}

/// The HAP four-character codes and whether each has alpha.
const HAP_CODECS: &[(&[u8; 4], bool)] =
    &[(b"Hap1", false), (b"Hap5", true), (b"HapY", false), (b"HapM", true), (b"HapA", true), (b"Hap7", true)];

impl HapClip {
    /// Opens `path` if it is a QuickTime/MP4 file with a HAP video track (`None` when it is
    /// some other file, for ffmpeg to try).
    pub fn open(path: &Path, max_side: u32, max_bytes: u64) -> Result<Option<HapClip>, String> {
        let mut file = crate::files::open_regular(path).map_err(|e| e.to_string())?;
        let len = file.metadata().map_err(|e| e.to_string())?.len();
        let mut magic = [0u8; 8];
        if file.read_exact(&mut magic).is_err() || !is_quicktime(&magic) {
            return Ok(None);
        }
        let track = mov::read_video_track(&mut file, len).map_err(|e| format!("{}: {e}", path.display()))?;
        if !HAP_CODECS.iter().any(|(code, _)| **code == track.codec) {
            return Ok(None);
        }
        super::check_size("the video", (track.width, track.height), max_side, max_bytes)?;
        if track.samples.is_empty() {
            return Err(format!("{}: the clip has no frames", path.display()));
        }
        Ok(Some(HapClip { file, track }))
    }

    /// What the clip is.
    pub fn info(&self) -> ClipInfo {
        let alpha = HAP_CODECS.iter().any(|(code, alpha)| **code == self.track.codec && *alpha);
        ClipInfo {
            width: self.track.width,
            height: self.track.height,
            frames: self.track.samples.len(),
            fps: self.track.fps(),
            codec: self.track.codec_name(),
            alpha,
            random_access: true,
        }
    }

    /// The sample tables.
    pub fn track(&self) -> &VideoTrack {
        &self.track
    }

    /// Frame `index`'s texture blocks.
    pub fn read(&mut self, index: usize) -> Result<HapFrame, String> {
        let sample = *self.track.samples.get(index).ok_or_else(|| format!("the clip has no frame {index}"))?;
        let (w, h) = (self.track.width, self.track.height);
        // A frame never needs more than its raw blocks (BC3 plus BC4 for Hap Q Alpha) and headers.
        let largest = BlockFormat::Bc3.image_bytes(w, h) + BlockFormat::Bc4.image_bytes(w, h) + (64 << 10);
        if sample.size as usize > largest {
            return Err(format!("frame {index} claims {} bytes, more than a {w}×{h} HAP frame can be", sample.size));
        }
        let mut bytes = vec![0u8; sample.size as usize];
        self.file
            .seek(SeekFrom::Start(sample.offset))
            .and_then(|_| self.file.read_exact(&mut bytes))
            .map_err(|e| format!("cannot read frame {index}: {e} (was the file truncated?)"))?;
        hap::decode_frame(&bytes, w, h).map_err(|e| format!("frame {index}: {e}"))
    }
}

/// Whether `head` starts a QuickTime/MP4 file (its first atom is one those files begin with).
fn is_quicktime(head: &[u8; 8]) -> bool {
    [b"ftyp", b"moov", b"mdat", b"wide", b"free", b"skip", b"pnot"].iter().any(|k| head[4..8] == k[..])
}
