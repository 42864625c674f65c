//! A numbered image sequence as a clip: `shots/take_%04d.png` names every file of that folder
//! whose name is the prefix, a number and the suffix, in the order of their numbers (gaps are
//! skipped, not shown black), played at a frame rate the node gives (PNG, JPEG or OpenEXR). Frames are read and decoded
//! like stills, each under the file rules and size bounds, and must all be the first one's size.

use std::path::{Path, PathBuf};

use super::picture::Picture;
use super::still::{Still, decode};

/// The largest file one frame may be.
pub const FRAME_FILE_LIMIT: u64 = 256 << 20;

/// Whether a file name is a sequence pattern (`%d`, `%04d`).
pub fn is_pattern(name: &str) -> bool {
    split_pattern(name).is_some()
}

/// The text before and after a pattern's `%d` / `%0Nd`.
fn split_pattern(name: &str) -> Option<(&str, &str)> {
    let at = name.find('%')?;
    let rest = &name[at + 1..];
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    rest[digits..].strip_prefix('d').map(|suffix| (&name[..at], suffix))
}

/// An image sequence's frames.
pub struct ImageSequence {
    frames: Vec<PathBuf>,
    width: u32,
    height: u32,
    alpha: bool,
    max_side: u32,
    max_bytes: u64,
}

impl ImageSequence {
    /// The frames in `folder` matching file-name `pattern`; the first is decoded to learn the size.
    pub fn open(folder: &Path, pattern: &str, max_side: u32, max_bytes: u64) -> Result<Self, String> {
        let (prefix, suffix) =
            split_pattern(pattern).ok_or_else(|| format!("'{pattern}' has no %d or %04d for the frame number"))?;
        let entries = std::fs::read_dir(folder).map_err(|e| format!("cannot read {}: {e}", folder.display()))?;
        let mut numbered: Vec<(u64, PathBuf)> = entries
            .flatten()
            .filter_map(|entry| {
                let name = entry.file_name().to_string_lossy().into_owned();
                let number = name.strip_prefix(prefix)?.strip_suffix(suffix)?;
                let n = (!number.is_empty() && number.bytes().all(|b| b.is_ascii_digit()))
                    .then(|| number.parse::<u64>().ok())??;
                Some((n, entry.path()))
            })
            .collect();
        numbered.sort();
        let frames: Vec<PathBuf> = numbered.into_iter().map(|(_, p)| p).collect();
        if frames.is_empty() {
            return Err(format!("no files match {pattern} in {}", folder.display()));
        }
        let mut sequence = Self { frames, width: 0, height: 0, alpha: false, max_side, max_bytes };
        let first = sequence.decode(&sequence.frames[0])?;
        (sequence.width, sequence.height) = first.size;
        sequence.alpha = match &first.picture {
            Picture::Rgba(p) => p.chunks_exact(4).any(|p| p[3] < 255),
            Picture::LinearHalf(p) => p.chunks_exact(4).any(|p| half::f16::from_bits(p[3]).to_f32() < 1.0),
            Picture::Hap(_) => false,
        };
        Ok(sequence)
    }

    /// Frames in the sequence.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether it has no frames (never, once opened).
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The frame size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Whether the first frame has any transparent pixel.
    pub fn alpha(&self) -> bool {
        self.alpha
    }

    fn decode(&self, path: &Path) -> Result<Still, String> {
        let bytes = crate::files::read_limited(path, FRAME_FILE_LIMIT).map_err(|e| e.to_string())?;
        let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
        decode(&bytes, &name, self.max_side, self.max_bytes)
    }

    /// Frame `index`'s pixels.
    pub fn read(&self, index: usize) -> Result<Picture, String> {
        let path = self.frames.get(index).ok_or_else(|| format!("the sequence has no frame {index}"))?;
        let still = self.decode(path)?;
        if still.size != (self.width, self.height) {
            let (w, h) = still.size;
            return Err(format!("{} is {w}×{h}, not the sequence's {}×{}", path.display(), self.width, self.height));
        }
        Ok(still.picture)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_name_numbered_files() {
        assert_eq!(split_pattern("take_%04d.png"), Some(("take_", ".png")));
        assert_eq!(split_pattern("%d.jpg"), Some(("", ".jpg")));
        assert!(!is_pattern("still.png") && !is_pattern("100%.png") && !is_pattern("%s.png"));
    }
}
