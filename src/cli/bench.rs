//! `indra bench`: per-pass GPU medians, frame times and a show's switches.

use std::time::Instant;

use clap::Args;
use indra::assets::Assets;
use indra::gpu::{Gpu, GpuOptions};
use indra::offscreen::OffscreenRenderer;

use super::{MAX_START, SceneEdits, check_timing, parse_size, scene_with_edits, with_scene_folder};

/// `indra bench`.
#[derive(Args, Clone)]
pub struct BenchArgs {
    /// Scene name (from scenes/) or path to a .ron file.
    pub scene: String,
    /// Output size WxH.
    #[arg(long, value_parser = parse_size, default_value = "1920x1080")]
    pub size: (u32, u32),
    /// Frames to measure (after warm-up).
    #[arg(long, default_value_t = 100)]
    pub frames: u64,
    /// Frames rendered before measuring.
    #[arg(long, default_value_t = 10)]
    pub warmup: u64,
    /// Seek to this frame first (simulations run every step before it, undrawn), e.g. to
    /// measure a cloth that has settled rather than one at rest.
    #[arg(long, default_value_t = 0)]
    pub start: u64,
    #[command(flatten)]
    pub edits: SceneEdits,
    /// Hold tracks still (measure one parameter set, not an animation).
    #[arg(long)]
    pub no_animation: bool,
    /// For a show with a cue list: GO every this many seconds of the fixed clock, and report
    /// the worst frame at a switch against the median frame.
    #[arg(long, value_name = "SECONDS")]
    pub cue_every: Option<f64>,
    /// For a show: add an effect to layer 1 every this many seconds and remove it the next time,
    /// each built ahead on a worker thread as a live show does, and report the worst frame at an
    /// edit against the frames after it.
    #[arg(long, value_name = "SECONDS", conflicts_with = "cue_every")]
    pub fx_every: Option<f64>,
    /// The effect `--fx-every` adds.
    #[arg(long, default_value = "shaders/isf/Kaleidoscope.fs")]
    pub fx: String,
    /// Every frame waits for its files and clip frames, as `render` does (default: as live, a
    /// frame whose clip frame is not decoded yet shows an older one): the frame time then
    /// includes decoding that does not keep up.
    #[arg(long)]
    pub wait_for_media: bool,
    /// Keep one frame in flight, as the window does (it records the next frame while the GPU
    /// draws this one): the wall time is then the interval between frames, not each frame's
    /// full latency.
    #[arg(long)]
    pub pipelined: bool,
    /// Sample this DMX patch's fixtures in every frame (its pass is timed as `dmx/pixel_map`;
    /// nothing is sent).
    #[arg(long, value_name = "PATCH")]
    pub dmx_patch: Option<std::path::PathBuf>,
}

/// Renders `frames` frames and prints per-pass GPU medians and frame time.
pub fn bench(assets: &Assets, gpu: &GpuOptions, args: &BenchArgs) -> Result<(), String> {
    if args.frames == 0 {
        return Err("--frames 0 measures nothing; bench at least one frame".into());
    }
    if args.frames <= MAX_START && args.frames.saturating_add(args.warmup) > MAX_START {
        return Err(format!("--warmup {} and --frames {} together pass {MAX_START} frames", args.warmup, args.frames));
    }
    check_timing(args.start, args.frames, None)?;
    let assets = &with_scene_folder(assets, &args.scene).rendering_at(Some(args.size));
    let scene = scene_with_edits(assets, &args.scene, &args.edits)?;
    scene.check_texture_budget(args.size)?;
    let cue_steps = match args.cue_every {
        None => None,
        Some(s) if s.is_finite() && s > 0.0 && scene.show.as_ref().is_some_and(|show| !show.cues.is_empty()) => {
            Some(((s / f64::from(scene.dt)).round() as u64).max(1))
        }
        Some(_) => return Err("--cue-every takes a positive number of seconds and a show with a cue list".into()),
    };
    let fx_steps = match args.fx_every {
        None => None,
        Some(s) if s.is_finite() && s > 0.0 && scene.show.is_some() => {
            Some(((s / f64::from(scene.dt)).round() as u64).max(1))
        }
        Some(_) => return Err("--fx-every takes a positive number of seconds and a show".into()),
    };
    // Measured as it plays live: clips prepare on worker threads, files load in the background —
    // or, with --wait-for-media, each frame waiting for its files and clip frames as a render
    // does, so the wall time includes any decoding that does not keep up.
    let wait = if args.wait_for_media { indra::files::LoadWait::Finish } else { indra::files::LoadWait::Background };
    let assets = &assets.with_load_wait(wait);
    let device = Gpu::headless(gpu).map_err(|e| e.to_string())?;
    let adapter = device.adapter_label();
    let timestamps = device.has_timestamps();
    let tuning = device.tuning.summary();
    let name = scene.name.clone();
    let mut renderer =
        OffscreenRenderer::new(device, assets, scene, Some(args.size), None, None).map_err(|e| e.to_string())?;
    renderer.instance_mut().animate = !args.no_animation;
    let mut dmx_line = None;
    if let Some(path) = &args.dmx_patch {
        let layout = indra::dmx::Layout::new(indra::dmx::Patch::load(path)?)?;
        if !layout.boxes.is_empty() {
            let map = indra::dmx::PixelMap::new(&renderer.gpu().device, &layout.boxes).map_err(|e| e.to_string())?;
            renderer.set_pixel_map(map, layout.patch.image)?;
        }
        dmx_line = Some(format!("dmx        {} LEDs in {} universes", layout.boxes.len(), layout.universes().len()));
    }
    renderer.seek(args.start).map_err(|e| e.to_string())?;
    for _ in 0..args.warmup {
        renderer.render_only().map_err(|e| e.to_string())?;
    }
    renderer.restart_timings();
    let mut record = match fx_steps {
        Some(n) => super::bench_record::FrameRecord::new(n).calling_them("edit", "edits"),
        None => super::bench_record::FrameRecord::new(cue_steps.unwrap_or(1)),
    };
    let mut edits = fx_steps.map(|every| super::bench_fx::EffectToggle::new(&mut renderer, &args.fx, every));
    let mut switch_passes = super::bench_switch::SwitchPasses::default();
    let mut last = Instant::now();
    let mut stats = None;
    let mut in_flight = None;
    for i in 0..args.frames {
        let mut go = cue_steps.is_some_and(|n| i > 0 && i % n == 0);
        if go {
            let frame = renderer.next_frame();
            renderer.schedule(frame, vec![indra::params::ControlEvent::Show(indra::params::ShowCommand::CueGo)]);
        }
        if let Some(edits) = &mut edits {
            go = edits.before_frame(&mut renderer, i)?;
        }
        let (time, s) = renderer.render_only().map_err(|e| e.to_string())?;
        // Stepping, recording and submitting a frame: the CPU's share of its wall time.
        let recorded = Instant::now();
        // Waiting for this frame makes wall time its full latency; waiting for the one before
        // (pipelined) makes it the interval between frames with one in flight, as live.
        let newest = renderer.last_submission();
        let wait_for = if args.pipelined { std::mem::replace(&mut in_flight, newest) } else { newest };
        if let Some(index) = wait_for {
            renderer.wait_for(index);
        }
        let now = Instant::now();
        let ms = |from: Instant, to: Instant| (to - from).as_secs_f64() * 1e3;
        record.push(ms(last, now), ms(last, recorded), go.then_some(time.frame));
        if !args.pipelined {
            let latest = renderer.runtime().latest_frame_timings();
            switch_passes.push(i, latest, go.then(|| ms(last, now)));
        }
        last = now;
        stats = Some(s);
    }
    renderer.finish_timings();
    if let Some(edits) = edits {
        edits.finish();
    }
    let wall_median = record.wall_median();
    say!("scene      {name}");
    say!("adapter    {adapter}");
    say!("tuning     {tuning}");
    say!(
        "size       {}x{}   frames {} (+{} warm-up) from frame {}",
        args.size.0,
        args.size.1,
        args.frames,
        args.warmup,
        args.start
    );
    for s in &args.edits.sets {
        say!("set        {s}");
    }
    if let Some(line) = dmx_line {
        say!("{line}");
    }
    if timestamps {
        say!("{:<28} {:>12} {:>8}", "pass", "GPU median", "samples");
        for t in renderer.runtime().timings() {
            say!("{:<28} {:>9.3} ms {:>8}", t.name, t.median_ms, t.samples);
        }
        // Per technique: the sum of its passes' medians (the book layout has up to ~100 passes).
        let mut totals: std::collections::BTreeMap<String, (f64, usize)> = Default::default();
        for t in renderer.runtime().timings() {
            let technique = t.name.split('/').next().unwrap_or(&t.name).to_string();
            let entry = totals.entry(technique).or_default();
            entry.0 += t.median_ms;
            entry.1 += 1;
        }
        for (technique, (ms, passes)) in totals {
            say!("{:<28} {:>9.3} ms  ({passes} passes)", format!("total {technique}"), ms);
        }
        if let Some(ms) = renderer.runtime().frame_gpu_median_ms() {
            say!("{:<28} {:>9.3} ms", "all passes (GPU)", ms);
        }
        if let Some(ms) = renderer.runtime().frame_gpu_span_median_ms() {
            say!("{:<28} {:>9.3} ms", "first pass to last (GPU)", ms);
        }
    } else {
        say!("(this adapter has no TIMESTAMP_QUERY_INSIDE_ENCODERS: wall-clock only)");
    }
    say!("{:<28} {:>9.3} ms", "step + record (CPU median)", record.cpu_median());
    let wall_label = if args.pipelined { "frame interval (median)" } else { "frame wall time (median)" };
    say!("{:<28} {:>9.3} ms  ({:.1} fps)", wall_label, wall_median, 1e3 / wall_median.max(1e-9));
    for line in record.switch_report().into_iter().chain(switch_passes.report()) {
        say!("{line}");
    }
    for line in renderer.instance_mut().bench_reports() {
        say!("node       {line}");
    }
    if let Some(s) = stats {
        say!(
            "graph      passes {}/{} executed, transient {} KiB requested / {} KiB allocated, compile {:.1} µs",
            s.passes_executed,
            s.passes_declared,
            s.transient_bytes_requested / 1024,
            s.transient_bytes_allocated / 1024,
            s.compile_time.as_secs_f64() * 1e6
        );
    }
    Ok(())
}
