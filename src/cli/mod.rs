//! What each CLI command does, on top of the library: one module per command, and here the
//! argument types and checks they share. Every failure is one sentence for the user; nothing
//! here panics on bad input.

use clap::Args;
use indra::assets::Assets;
use indra::scene::{Scene, load_scene};

/// Prints a line to stdout, ignoring a closed pipe (`indra list | head` must not panic).
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

mod assemble;
mod bake;
mod bench;
mod bench_fx;
mod bench_record;
mod bench_switch;
mod chase;
mod check;
mod list;
mod ltc_out;
mod render;
mod render_dmx;
mod run;
mod source;
mod triangulate;
mod tune;

pub use assemble::{AssembleArgs, assemble};
pub use bake::{BakeArgs, bake};
pub use bench::{BenchArgs, bench};
pub use check::check;
pub use list::{list, list_cameras, list_ndi};
pub use render::{RenderArgs, render};
use render_dmx::RenderDmx;
pub use run::{RunArgs, run};

pub use triangulate::{TriangulateArgs, triangulate};
pub use tune::{TuneArgs, tune};

/// The scene `indra` opens with no arguments.
pub const DEFAULT_SCENE: &str = "kleinian";

fn parse_msaa(text: &str) -> Result<u32, String> {
    match text.trim().parse::<u32>() {
        Ok(n @ (1 | 2 | 4 | 8)) => Ok(n),
        _ => Err(format!("'{text}' is not a sample count: use 1, 2, 4 or 8")),
    }
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(|| format!("'{text}' is not WxH (e.g. 1920x1080)"))?;
    let parse = |s: &str| s.trim().parse::<u32>().ok().filter(|v| (1..=16384).contains(v));
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("'{text}' is not WxH with sides from 1 to 16384")),
    }
}

/// `--frames`: a count from `--start`, or a range of frame numbers with both ends included.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameSpan {
    /// This many frames.
    Count(u64),
    /// Frames A to B.
    Range(u64, u64),
}

impl FrameSpan {
    fn parse(text: &str) -> Result<Self, String> {
        let number = |s: &str| {
            s.trim().parse::<u64>().map_err(|_| format!("'{text}' is not a frame count (120) or range (600-699)"))
        };
        match text.split_once('-') {
            None => Ok(FrameSpan::Count(number(text)?)),
            Some((a, b)) => match (number(a)?, number(b)?) {
                (a, b) if a <= b => Ok(FrameSpan::Range(a, b)),
                (a, b) => Err(format!("the range {a}-{b} ends before it starts")),
            },
        }
    }

    /// A range as Open Job Description writes a contiguous chunk: `A-B`, `A,B` (two frames) or
    /// `A` (one frame).
    fn parse_chunk(text: &str) -> Result<Self, String> {
        let bad = || format!("'{text}' is not a range of frames (600-699, 600,601 or 600)");
        let number = |s: &str| s.trim().parse::<u64>().map_err(|_| bad());
        let (a, b) = match text.split_once(['-', ',']) {
            None => (number(text)?, number(text)?),
            Some((a, b)) => (number(a)?, number(b)?),
        };
        let two = text.contains(',');
        if a > b || (two && b != a + 1) {
            return Err(bad());
        }
        Ok(FrameSpan::Range(a, b))
    }

    /// The first frame and how many, given `--start`.
    fn resolve(self, start: u64) -> Result<(u64, u64), String> {
        match self {
            FrameSpan::Count(n) => Ok((start, n)),
            FrameSpan::Range(a, b) if start == 0 => Ok((a, b - a + 1)),
            FrameSpan::Range(a, b) => Err(format!("--frames {a}-{b} names its first frame: leave out --start {start}")),
        }
    }
}

/// Most steps a render or bench may seek through (≈ 190 days at 60 fps): beyond it a seek
/// would run for hours, so it is refused with a sentence instead.
const MAX_START: u64 = 1_000_000_000;

/// Checks `--start`, `--frames` and `--dt`: one sentence for each bad value.
fn check_timing(start: u64, frames: u64, dt: Option<f32>) -> Result<(), String> {
    if start > MAX_START {
        return Err(format!("--start {start} is past {MAX_START} steps; split the render or lower it"));
    }
    if frames > MAX_START {
        return Err(format!("--frames {frames} is more than {MAX_START}; render in parts"));
    }
    if let Some(dt) = dt.filter(|dt| !(dt.is_finite() && *dt > 0.0 && *dt <= 1.0)) {
        return Err(format!("--dt {dt} must be a number of seconds in (0, 1], e.g. 0.0166667"));
    }
    Ok(())
}

/// `assets` with the folder of scene file `name` (if it is a path to a file) open to the files
/// its parameters name: a scene kept beside its warp files and images works from any folder.
fn with_scene_folder(assets: &Assets, name: &str) -> Assets {
    let path = std::path::Path::new(name);
    match path.parent() {
        Some(folder) if path.is_file() => {
            assets.allowing(if folder.as_os_str().is_empty() { std::path::Path::new(".") } else { folder })
        }
        _ => assets.clone(),
    }
}

/// The edits every command that plays a scene takes from the command line: `--set` and `--msaa`.
#[derive(Args, Clone)]
pub struct SceneEdits {
    /// Set a parameter (repeatable): node.param=value — 0.5, true, an option name, a vector as
    /// 1,0.3,0.1 or (1.0,0.3,0.1), one component as node.param.x=0.5.
    #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
    pub sets: Vec<String>,
    /// Samples per pixel of rasterising nodes, 1, 2, 4 or 8 (default: the scene's, normally 4);
    /// lowered to what the adapter supports.
    #[arg(long, value_parser = parse_msaa)]
    pub msaa: Option<u32>,
}

impl SceneEdits {
    /// Applies the `--set` assignments and `--msaa` to a loaded scene (the texture budget is
    /// checked at the size it renders at, by the caller).
    fn apply(&self, mut scene: Scene) -> Result<Scene, String> {
        for assignment in &self.sets {
            scene.set_from_str(assignment)?;
        }
        if let Some(samples) = self.msaa {
            scene.msaa = samples;
        }
        Ok(scene)
    }
}

/// A DMX file a command uses: `flag` (`--dmx-out`, `--dmx-in`), else the file `named` in scene
/// `scene` (`dmx:`, `dmx_in:`), found as the scene's other files are (beside it, or under the
/// project's folders); `what` names it in the message.
fn dmx_file(
    assets: &Assets,
    flag: Option<&std::path::Path>,
    named: Option<&str>,
    scene: &str,
    what: &str,
) -> Result<Option<std::path::PathBuf>, String> {
    match (flag, named) {
        (Some(path), _) => Ok(Some(path.to_path_buf())),
        (None, Some(name)) => {
            assets.locate_file(name).map(Some).map_err(|e| format!("'{scene}' names the {what} {name}: {e}"))
        }
        (None, None) => Ok(None),
    }
}

/// Loads a scene and applies the command line's edits to it.
fn scene_with_edits(assets: &Assets, name: &str, edits: &SceneEdits) -> Result<Scene, String> {
    edits.apply(load_scene(assets, name).map_err(|e| e.to_string())?)
}
