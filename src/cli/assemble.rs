//! Manifests of rendered frames, and `indra assemble`: the frames of a chunked render checked
//! against their manifests (none missing, none twice, none changed) and made into one video.
//!
//! A render to PNGs writes `<stem>_<first>-<last>.sha256` beside its frames, in the format
//! `sha256sum` writes and checks (`sha256sum -c` verifies a folder without indra). A chunk that
//! is killed writes no manifest; run again, it writes its frames and manifest anew.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::Args;
use indra::offscreen::{VideoSettings, VideoWriter};

/// The extension of manifests.
const EXTENSION: &str = "sha256";

/// The file name of frame `frame` of a render of `stem`.
pub fn frame_file(stem: &str, frame: u64) -> String {
    format!("{stem}_{frame:05}.png")
}

/// The sums of the frames one render wrote.
#[derive(Default)]
pub struct Manifest {
    /// (frame, file name, SHA-256 hex), in the order written.
    frames: Vec<(u64, String, String)>,
}

impl Manifest {
    /// Adds frame `frame`, written as `name` with the bytes `png`.
    pub fn add(&mut self, frame: u64, name: &str, png: &[u8]) {
        self.frames.push((frame, name.to_string(), indra::checkpoint::sha256_hex(png)));
    }

    /// Writes the manifest into `folder` (atomically) and returns its path; none for no frames.
    pub fn write(&self, folder: &Path, stem: &str) -> Result<Option<PathBuf>, String> {
        let (Some(first), Some(last)) = (self.frames.first(), self.frames.last()) else { return Ok(None) };
        let path = folder.join(format!("{stem}_{:05}-{:05}.{EXTENSION}", first.0, last.0));
        let text: String = self.frames.iter().map(|(_, name, sum)| format!("{sum}  {name}\n")).collect();
        indra::atomic_file::write(&path, text.as_bytes())
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        Ok(Some(path))
    }
}

/// `indra assemble`.
#[derive(Args, Clone)]
pub struct AssembleArgs {
    /// The folder the chunks rendered into (their PNGs and .sha256 manifests).
    pub folder: PathBuf,
    /// The video to write (.mov: ProRes 422 HQ; .mp4 and .mkv: H.264; .webm: VP9).
    #[arg(long, value_name = "FILE")]
    pub video: PathBuf,
    /// Frames per second (the scene's 1/dt; indra's scenes step at 60).
    #[arg(long, default_value_t = 60.0)]
    pub fps: f64,
    /// Video codec, as for `render --codec`.
    #[arg(long)]
    pub codec: Option<String>,
    /// Video quality, as for `render --quality`.
    #[arg(long)]
    pub quality: Option<u32>,
}

/// One frame a manifest lists.
struct Listed {
    name: String,
    sum: String,
    manifest: PathBuf,
}

/// Checks every manifest in the folder and muxes the frames they list, in order, into a video.
pub fn assemble(args: &AssembleArgs) -> Result<(), String> {
    let frames = read_manifests(&args.folder)?;
    let (Some((&first, _)), Some((&last, _))) = (frames.first_key_value(), frames.last_key_value()) else {
        return Err(format!("{} holds no .{EXTENSION} manifest: render into it first", args.folder.display()));
    };
    let missing: Vec<u64> = (first..=last).filter(|f| !frames.contains_key(f)).take(10).collect();
    if !missing.is_empty() {
        return Err(format!("frames {first}–{last}: frame(s) {missing:?} are in no manifest (a chunk did not finish)"));
    }
    let mut video: Option<VideoWriter> = None;
    let bar = indicatif::ProgressBar::new(frames.len() as u64);
    for (frame, listed) in &frames {
        let path = args.folder.join(&listed.name);
        let bytes = std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        if indra::checkpoint::sha256_hex(&bytes) != listed.sum {
            return Err(format!(
                "{} is not the frame {} lists (changed or cut short)",
                path.display(),
                listed.manifest.display()
            ));
        }
        let image = image::load_from_memory(&bytes).map_err(|e| format!("{}: {e}", path.display()))?.to_rgba8();
        let size = image.dimensions();
        let writer = match &mut video {
            Some(writer) => writer,
            None => video.insert(start_video(args, size)?),
        };
        if writer.settings().size != size {
            return Err(format!(
                "frame {frame} is {}x{}, the frames before it {:?}",
                size.0,
                size.1,
                writer.settings().size
            ));
        }
        writer.write(image.as_raw()).map_err(|e| e.to_string())?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    video.expect("at least one frame").finish().map_err(|e| e.to_string())?;
    eprintln!("checked {} frame(s), {first}–{last}, and wrote {}", frames.len(), args.video.display());
    Ok(())
}

fn start_video(args: &AssembleArgs, size: (u32, u32)) -> Result<VideoWriter, String> {
    let settings = VideoSettings {
        path: args.video.clone(),
        size,
        fps: args.fps,
        codec: args.codec.clone(),
        quality: args.quality,
        audio: None,
        stream: false,
        pace: false,
    };
    VideoWriter::start(settings).map_err(|e| e.to_string())
}

/// Every frame the manifests in `folder` list, by frame number; a frame listed twice, or a line
/// that is not `<sum>  <stem>_<frame>.png`, is an error naming its manifest.
fn read_manifests(folder: &Path) -> Result<BTreeMap<u64, Listed>, String> {
    let entries = std::fs::read_dir(folder).map_err(|e| format!("cannot read {}: {e}", folder.display()))?;
    let mut manifests: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == EXTENSION))
        .collect();
    manifests.sort();
    let mut frames: BTreeMap<u64, Listed> = BTreeMap::new();
    let mut stems = std::collections::BTreeSet::new();
    for manifest in manifests {
        let text =
            std::fs::read_to_string(&manifest).map_err(|e| format!("cannot read {}: {e}", manifest.display()))?;
        for (n, line) in text.lines().enumerate() {
            let bad = || format!("{}:{}: not '<sha256>  <scene>_<frame>.png'", manifest.display(), n + 1);
            let (sum, name) = line.split_once("  ").ok_or_else(bad)?;
            let (stem, frame) = name.strip_suffix(".png").and_then(|s| s.rsplit_once('_')).ok_or_else(bad)?;
            let frame: u64 = frame.parse().map_err(|_| bad())?;
            if sum.len() != 64 || !sum.bytes().all(|b| b.is_ascii_hexdigit()) || name.contains(['/', '\\']) {
                return Err(bad());
            }
            stems.insert(stem.to_string());
            let listed = Listed { name: name.to_string(), sum: sum.to_string(), manifest: manifest.clone() };
            if let Some(before) = frames.insert(frame, listed) {
                return Err(format!(
                    "frame {frame} is in {} and in {}: two chunks overlap",
                    before.manifest.display(),
                    manifest.display()
                ));
            }
        }
    }
    if stems.len() > 1 {
        return Err(format!("{} holds frames of {stems:?}: assemble one render per folder", folder.display()));
    }
    Ok(frames)
}
