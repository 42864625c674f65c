//! The `indra` command line: parsing, and the process's allocator settings; each command's work
//! is in `cli`.

mod cli;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use indra::gpu::BackendChoice;
use indra::gpu::tuning::TuningSource;

/// Limits glibc to two malloc arenas. By default each thread that allocates while the others
/// hold theirs gets an arena of its own, up to eight per core, and a show's clip builds, reloads
/// and the driver's threads each fragment one: on a loaded two-core machine a show under
/// trigger floods rose ~150 MiB an hour with the default and stayed flat with two (tests/soak;
/// frame times within noise, docs/performance-notes.md). Set before any thread starts.
fn fewer_malloc_arenas() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes glibc's allocator settings; no other thread runs yet.
    unsafe {
        libc::mallopt(libc::M_ARENA_MAX, 2);
    }
}

/// indra — real-time visual-art engine (Unity Graphics Programming vol.4 techniques on wgpu).
#[derive(Parser)]
#[command(name = "indra", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    gpu: GpuArgs,
    /// Folder holding `shaders/` and `scenes/` (default: $INDRA_ROOT, the current folder, or
    /// the source tree; built-in copies otherwise).
    #[arg(long, global = true)]
    root: Option<PathBuf>,
    /// A folder whose files parameters may name (warp files, images, models), besides the root
    /// and the scene's own folder; repeatable. `/` opens every file the process can read.
    #[arg(long = "allow-path", value_name = "FOLDER", global = true)]
    allow_paths: Vec<PathBuf>,
    /// List this machine's cameras (V4L2 devices) for a `camera` node's `device`, and exit.
    #[arg(long)]
    list_cameras: bool,
    /// List the NDI sources seen on the network within two seconds, for an `ndi` node's
    /// `source`, and exit (needs the NDI runtime: see the README's NDI section).
    #[arg(long)]
    list_ndi: bool,
}

/// Options that pick the GPU.
#[derive(Args, Clone)]
struct GpuArgs {
    /// Graphics API.
    #[arg(long, global = true, value_enum, default_value_t = BackendChoice::Auto)]
    backend: BackendChoice,
    /// Use the adapter whose name contains this text (e.g. llvmpipe, H100).
    #[arg(long, global = true)]
    adapter: Option<String>,
    /// What parameters set to `auto` take: `saved` (what `indra tune` measured on this adapter;
    /// the default of run and bench), `off` (the built-in defaults; the default of render and
    /// bake, so that rendered bytes never hang on a measurement), or a tuning file.
    #[arg(long, global = true, value_name = "saved|off|FILE")]
    tuning: Option<String>,
}

#[derive(Subcommand)]
enum Command {
    /// Open a scene in a window with live controls (default: the kleinian scene).
    Run(Box<cli::RunArgs>),
    /// Render frames off-screen to a PNG sequence (with a manifest of SHA-256 sums) or a video.
    Render(Box<cli::RenderArgs>),
    /// Step through frames without drawing and write checkpoints of the whole state, so a
    /// render can start anywhere (`render --checkpoints`) without simulating what comes before.
    Bake(Box<cli::BakeArgs>),
    /// Check the frames of a chunked render against their manifests and make one video.
    Assemble(cli::AssembleArgs),
    /// Validate every scene and shader (or the given files); non-zero exit on any error.
    Check {
        /// Scene (.ron) or shader (.wgsl) files; all known ones when empty.
        files: Vec<PathBuf>,
    },
    /// List scenes and their parameters.
    List,
    /// Render off-screen and print per-pass GPU medians and frame time.
    Bench(cli::BenchArgs),
    /// Triangulate rings from a JSON or SVG file; print triangle count, area deviation and time.
    Triangulate(cli::TriangulateArgs),
    /// Measure, on this adapter, the options that only change how fast a node draws (the
    /// rasterizer, StarGlow's layout), and save the fastest as what `auto` takes here.
    Tune(cli::TuneArgs),
}

fn main() -> ExitCode {
    fewer_malloc_arenas();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn,indra=info,wgpu_hal=off")).init();
    let cli = Cli::parse();
    let mut assets = match cli.root {
        Some(root) => indra::assets::Assets::new(Some(root)),
        None => indra::assets::Assets::discover(),
    };
    for folder in &cli.allow_paths {
        assets = assets.allowing(folder);
    }
    let live = matches!(cli.command, None | Some(Command::Run(_) | Command::Bench(_)));
    let tuning = match cli.gpu.tuning.as_deref() {
        None if live => TuningSource::Saved,
        None | Some("off") => TuningSource::Defaults,
        Some("saved") => TuningSource::Saved,
        Some(file) => TuningSource::File(file.into()),
    };
    let gpu = indra::gpu::GpuOptions { backend: cli.gpu.backend, adapter: cli.gpu.adapter, tuning };
    let result = match cli.command {
        _ if cli.list_cameras => cli::list_cameras(),
        _ if cli.list_ndi => cli::list_ndi(),
        None => cli::run(&assets, &gpu, &cli::RunArgs::default()),
        Some(Command::Run(args)) => cli::run(&assets, &gpu, &args),
        Some(Command::Render(args)) => cli::render(&assets, &gpu, &args),
        Some(Command::Bake(args)) => cli::bake(&assets, &gpu, &args),
        Some(Command::Assemble(args)) => cli::assemble(&args),
        Some(Command::Check { files }) => cli::check(&assets, &files),
        Some(Command::List) => cli::list(&assets),
        Some(Command::Bench(args)) => cli::bench(&assets, &gpu, &args),
        Some(Command::Triangulate(args)) => cli::triangulate(&args),
        Some(Command::Tune(args)) => cli::tune(&assets, &gpu, &args),
    };
    // Worker threads end, and GPU objects let go of off the render thread are released, before
    // the driver unloads (a clip still building at exit is a few seconds at most).
    indra::gpu::wait_for_drops(std::time::Duration::from_secs(20));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}
