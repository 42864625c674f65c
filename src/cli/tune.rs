//! `indra tune`: times, on the adapter that will run them, the options that change only how fast
//! a node draws, and saves the fastest as what `auto` takes there (`gpu::tuning`).

use std::time::Instant;

use clap::Args;
use indra::assets::Assets;
use indra::gpu::tuning::{AdapterKey, TunedChoice, Tuning, TuningSource};
use indra::gpu::{Gpu, GpuOptions};
use indra::graph::RollingMedian;
use indra::offscreen::OffscreenRenderer;

use super::{load_scene, parse_size};

/// `indra tune`.
#[derive(Args, Clone)]
pub struct TuneArgs {
    /// Output size to measure at: the size the shows will play at.
    #[arg(long, value_parser = parse_size, default_value = "1920x1080")]
    pub size: (u32, u32),
    /// Frames measured per option (after warm-up).
    #[arg(long, default_value_t = 60)]
    pub frames: u64,
    /// Frames rendered before measuring each option.
    #[arg(long, default_value_t = 10)]
    pub warmup: u64,
    /// Measure only this technique's choices (repeatable; default: all).
    #[arg(long, value_name = "TECHNIQUE")]
    pub only: Vec<String>,
    /// Save here instead of this adapter's file in the configuration folder.
    #[arg(long, value_name = "FILE")]
    pub out: Option<std::path::PathBuf>,
}

/// A parameter whose options draw the same image at different speeds, and the bundled scene
/// that represents it (where the technique does its usual work).
struct Tunable {
    technique: &'static str,
    parameter: &'static str,
    options: &'static [&'static str],
    scene: &'static str,
    /// Frame to start at: simulations that grow or settle are measured grown.
    start: u64,
    /// Whether the options need 64-bit atomics (drawing in compute).
    needs_atomics: bool,
}

/// A technique's `rasterizer`, measured in `scene` from frame `start`.
const fn rasterizer(technique: &'static str, scene: &'static str, start: u64) -> Tunable {
    Tunable { technique, parameter: "rasterizer", options: &["compute", "pipeline"], scene, start, needs_atomics: true }
}

/// Everything `auto` can stand for. Msaa is not here: its options draw different images, a
/// choice of look for the performer, not of speed; no kernel has workgroup-size variants.
const TUNABLES: &[Tunable] = &[
    rasterizer("tessellation", "tessellation_fluid", 120),
    rasterizer("space_colonization", "space_colonization_tubes", 200),
    rasterizer("poisson", "poisson_3d", 120),
    rasterizer("cube_field", "star_glow", 0),
    rasterizer("cloth", "cloth", 120),
    Tunable {
        technique: "star_glow",
        parameter: "layout",
        options: &["Auto", "Book", "Fused"],
        scene: "star_glow",
        start: 0,
        needs_atomics: false,
    },
];

/// Measures every tunable choice and saves the winners for this adapter.
pub fn tune(assets: &Assets, gpu: &GpuOptions, args: &TuneArgs) -> Result<(), String> {
    if args.frames == 0 || args.frames > 100_000 || args.warmup > 100_000 {
        return Err("--frames takes 1 to 100000 frames and --warmup at most 100000".into());
    }
    if let Some(unknown) = args.only.iter().find(|t| !TUNABLES.iter().any(|c| &c.technique == t)) {
        let known: Vec<&str> = TUNABLES.iter().map(|c| c.technique).collect();
        return Err(format!("nothing of '{unknown}' is tuned (techniques with choices: {})", known.join(", ")));
    }
    // Measured against the built-in defaults: an option `Auto` is then the rule it stands for
    // untuned, never an earlier tuning.
    let device =
        Gpu::headless(&GpuOptions { tuning: TuningSource::Defaults, ..gpu.clone() }).map_err(|e| e.to_string())?;
    let info = device.adapter.get_info();
    let key = AdapterKey::of(&info);
    let path = match &args.out {
        Some(path) => path.clone(),
        None => Tuning::path_for(&key).ok_or("no configuration folder (set HOME, or give --out FILE)")?,
    };
    // A CPU adapter (lavapipe) draws on the cores that step and record the frame, and its
    // timestamps leave out the work it does at submit: what a frame costs there is its wall time.
    let cpu_adapter = info.device_type == wgpu::DeviceType::Cpu;
    let gpu_clock = device.has_timestamps() && !cpu_adapter;
    let clock = if gpu_clock { "GPU" } else { "wall" };
    say!("adapter    {}", device.adapter_label());
    say!(
        "size       {}x{}   {} frames an option (+{} warm-up), {clock} median",
        args.size.0,
        args.size.1,
        args.frames,
        args.warmup
    );
    let assets = &assets.rendering_at(Some(args.size));
    let atomics = device.device.features().contains(indra::techniques::splat_draw::FEATURES);
    let mut tuning = Tuning { key: Some(key), clock: clock.into(), choices: Vec::new() };
    for tunable in TUNABLES.iter().filter(|t| args.only.is_empty() || args.only.iter().any(|o| o == t.technique)) {
        let name = format!("{}.{}", tunable.technique, tunable.parameter);
        if tunable.needs_atomics && !atomics {
            say!("{name:<30} pipeline only (no 64-bit atomics on this adapter: nothing to choose)");
            continue;
        }
        let mut figures = Vec::new();
        for option in tunable.options {
            let ms = measure(assets, &device, tunable, option, args, gpu_clock)
                .map_err(|e| format!("{name}={option}: {e}"))?;
            figures.push((option.to_string(), ms));
        }
        let fastest = figures.iter().min_by(|a, b| a.1.total_cmp(&b.1)).map(|f| f.0.clone()).unwrap_or_default();
        let told: Vec<String> = figures.iter().map(|(o, ms)| format!("{o} {ms:.3} ms")).collect();
        say!("{name:<30} {fastest:<10} ({})", told.join(", "));
        tuning.choices.push(TunedChoice {
            technique: tunable.technique.into(),
            parameter: tunable.parameter.into(),
            chosen: fastest,
            scene: tunable.scene.into(),
            size: args.size,
            figures,
        });
    }
    tuning.save(&path)?;
    say!("saved      {}", path.display());
    Ok(())
}

/// The median frame of `tunable`'s scene (from `assets`, which render at `args.size`) with every
/// node of its technique set to `option`: GPU time (`gpu_clock`) or wall time.
fn measure(
    assets: &Assets,
    device: &Gpu,
    tunable: &Tunable,
    option: &str,
    args: &TuneArgs,
    gpu_clock: bool,
) -> Result<f64, String> {
    let mut scene = load_scene(assets, tunable.scene).map_err(|e| e.to_string())?;
    let ids: Vec<String> =
        scene.nodes.iter().filter(|n| n.technique.name == tunable.technique).map(|n| n.id.clone()).collect();
    if ids.is_empty() {
        return Err(format!("scene '{}' has no {} node", tunable.scene, tunable.technique));
    }
    for id in ids {
        scene.set_from_str(&format!("{id}.{}={option}", tunable.parameter))?;
    }
    scene.check_texture_budget(args.size)?;
    let mut renderer = OffscreenRenderer::new(device.clone(), assets, scene, Some(args.size), None, None)
        .map_err(|e| e.to_string())?;
    renderer.seek(tunable.start).map_err(|e| e.to_string())?;
    for _ in 0..args.warmup {
        renderer.render_only().map_err(|e| e.to_string())?;
    }
    renderer.restart_timings();
    let mut walls = RollingMedian::new(args.frames as usize);
    for _ in 0..args.frames {
        let began = Instant::now();
        renderer.render_only().map_err(|e| e.to_string())?;
        if let Some(index) = renderer.last_submission() {
            renderer.wait_for(index);
        }
        walls.push(began.elapsed().as_secs_f64() * 1e3);
    }
    renderer.finish_timings();
    let gpu = renderer.runtime().frame_gpu_median_ms().filter(|_| gpu_clock);
    Ok(gpu.or_else(|| walls.median()).unwrap_or(f64::INFINITY))
}
