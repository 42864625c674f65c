//! `indra bake`: the whole state of a render every C frames, written as checkpoints, and how a
//! render starts from the nearest one (`render --checkpoints`) instead of simulating every frame
//! before its first.

use std::path::{Path, PathBuf};

use clap::Args;
use indra::assets::Assets;
use indra::checkpoint::{Checkpoint, Header};
use indra::gpu::GpuOptions;
use indra::offscreen::OffscreenRenderer;

use super::render::RenderSource;
use super::source::LoadedSource;
use super::{FrameSpan, check_timing};

/// The extension of checkpoint files.
const EXTENSION: &str = "ckpt";

/// `indra bake`.
#[derive(Args, Clone)]
pub struct BakeArgs {
    #[command(flatten)]
    pub source: RenderSource,
    /// The frames to write checkpoints in: a range A-B (both included) or a count from 0; a
    /// checkpoint at frame F holds the state before F is drawn.
    #[arg(long, value_parser = FrameSpan::parse)]
    pub frames: FrameSpan,
    /// A checkpoint at every frame of the range that is a multiple of this.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub every: u64,
    /// Folder for the checkpoints, written as <scene>_<frame>.ckpt.
    #[arg(long, default_value = "checkpoints")]
    pub out: PathBuf,
}

/// Steps through the frames (simulation only, nothing drawn) and writes the checkpoints.
pub fn bake(assets: &Assets, gpu: &GpuOptions, args: &BakeArgs) -> Result<(), String> {
    let (first, count) = args.frames.resolve(0)?;
    check_timing(first, count, args.source.dt)?;
    if count == 0 {
        return Err("--frames 0 bakes nothing: give a range A-B".into());
    }
    let last = first + count - 1;
    let frames: Vec<u64> = (first..=last).filter(|f| f.is_multiple_of(args.every)).collect();
    if frames.is_empty() {
        return Err(format!("no frame from {first} to {last} is a multiple of --every {}", args.every));
    }
    let loaded = LoadedSource::load(assets, &args.source, |_, _| last + 1)?;
    std::fs::create_dir_all(&args.out).map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let mut renderer = loaded.renderer(gpu, &args.source, "baking")?;
    loaded.schedule(&mut renderer);
    let bar = indicatif::ProgressBar::new(frames.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} checkpoints  eta {eta}").expect("valid template"),
    );
    let mut sizes = Vec::new();
    for &frame in &frames {
        renderer.seek(frame).map_err(|e| e.to_string())?;
        let checkpoint = renderer.checkpoint(&loaded.controls).map_err(|e| e.to_string())?;
        let path = args.out.join(format!("{}_{frame:06}.{EXTENSION}", loaded.stem));
        sizes.push(checkpoint.write(&path).map_err(|e| e.to_string())?);
        for message in renderer.instance_mut().take_messages() {
            bar.suspend(|| eprintln!("warning: {message}"));
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    for e in renderer.gpu().take_uncaptured_errors() {
        eprintln!("GPU error during the bake: {e}");
    }
    let largest = sizes.iter().copied().max().unwrap_or(0);
    eprintln!(
        "wrote {} checkpoint(s) of frames {}–{} to {} ({} each at most)",
        frames.len(),
        frames[0],
        frames[frames.len() - 1],
        args.out.display(),
        human_bytes(largest)
    );
    Ok(())
}

/// Starts `renderer` (which has drawn nothing) from the checkpoint in `folder` nearest at or
/// before `frame` for the same scene; with none there, it starts from frame 0 as without.
pub fn resume(
    renderer: &mut OffscreenRenderer,
    folder: &Path,
    frame: u64,
    controls: &str,
    other_adapter: bool,
) -> Result<(), String> {
    let wanted = renderer.checkpoint_header(controls);
    let Some((path, header)) = nearest(folder, &wanted.scene, frame)? else {
        eprintln!(
            "no checkpoint of '{}' at or before frame {frame} in {}: simulating from 0",
            wanted.scene,
            folder.display()
        );
        return Ok(());
    };
    if let Some(why) = header.mismatch(&wanted, other_adapter) {
        return Err(format!("{} {why}", path.display()));
    }
    let checkpoint = Checkpoint::read(&path).map_err(|e| e.to_string())?;
    if checkpoint.header != header {
        return Err(format!("{} changed while it was read", path.display()));
    }
    renderer.restore(&checkpoint).map_err(|e| format!("{}: {e}", path.display()))?;
    eprintln!("starting from {} (frame {})", path.display(), header.frame);
    Ok(())
}

/// The checkpoint of `scene` in `folder` with the latest frame at or before `frame`.
fn nearest(folder: &Path, scene: &str, frame: u64) -> Result<Option<(PathBuf, Header)>, String> {
    let entries = std::fs::read_dir(folder).map_err(|e| format!("cannot read {}: {e}", folder.display()))?;
    let mut best: Option<(PathBuf, Header)> = None;
    for entry in entries {
        let path = entry.map_err(|e| format!("cannot read {}: {e}", folder.display()))?.path();
        if path.extension().is_none_or(|e| e != EXTENSION) {
            continue;
        }
        let header = Checkpoint::read_header(&path).map_err(|e| e.to_string())?;
        let better = best.as_ref().is_none_or(|(_, b)| header.frame > b.frame);
        if header.scene == scene && header.frame <= frame && better {
            best = Some((path, header));
        }
    }
    Ok(best)
}

/// Bytes as KiB, MiB or GiB.
fn human_bytes(bytes: u64) -> String {
    match bytes {
        b if b >= 1 << 30 => format!("{:.2} GiB", b as f64 / f64::from(1u32 << 30)),
        b if b >= 1 << 20 => format!("{:.1} MiB", b as f64 / f64::from(1u32 << 20)),
        b => format!("{:.1} KiB", b as f64 / 1024.0),
    }
}
