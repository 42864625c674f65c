//! The frame graph on a real device: transient textures are reused within a frame once their
//! last reader has run, steady-state frames create nothing, culled passes never record, and
//! per-pass timestamps arrive when the adapter has them.

use crate::common;

use std::cell::Cell;

use indra::gpu::read_texture_rgba8;
use indra::graph::{FrameGraph, GraphRuntime, TextureDesc};

const FMT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Records a pass that clears `target` to `colour`.
fn clear(ctx: &mut indra::graph::PassContext<'_>, target: indra::graph::TextureHandle, colour: wgpu::Color) {
    let view = ctx.view(target).clone();
    ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("test_clear"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(colour), store: wgpu::StoreOp::Store },
        })],
        ..Default::default()
    });
}

/// a → b → c → out, plus a dead-end pass; returns how many passes recorded.
fn chain_frame(runtime: &mut GraphRuntime, gpu: &indra::gpu::Gpu) -> (indra::graph::FrameOutput, usize) {
    let recorded = Cell::new(0);
    let mut graph = FrameGraph::new((64, 64));
    let [a, b, c] = ["a", "b", "c"].map(|n| graph.create_texture(n, TextureDesc::full(FMT)));
    let dead = graph.create_texture("dead", TextureDesc::full(FMT));
    let out = graph.create_texture("out", TextureDesc::full(FMT));
    let green = wgpu::Color { r: 0.0, g: 1.0, b: 0.0, a: 1.0 };
    // Declared out of order on purpose.
    graph.add_pass("out").read(c).render_target(out).record(|ctx| {
        recorded.set(recorded.get() + 1);
        clear(ctx, out, green);
    });
    graph.add_pass("dead_end").read(a).render_target(dead).record(|ctx| {
        recorded.set(recorded.get() + 100);
        clear(ctx, dead, green);
    });
    for (name, from, to) in [("make_c", Some(b), c), ("make_b", Some(a), b), ("make_a", None, a)] {
        let pass = graph.add_pass(name);
        let pass = if let Some(f) = from { pass.read(f) } else { pass };
        let recorded = &recorded;
        pass.render_target(to).record(move |ctx| {
            recorded.set(recorded.get() + 1);
            clear(ctx, to, wgpu::Color::RED);
        });
    }
    graph.set_output(out);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let output = runtime.execute(&gpu.device, &gpu.queue, graph, &mut encoder).expect("graph compiles");
    gpu.queue.submit([encoder.finish()]);
    runtime.after_submit();
    (output, recorded.get())
}

#[test]
fn transients_are_reused_within_and_across_frames() {
    let gpu = common::gpu();
    let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
    let (first, recorded) = chain_frame(&mut runtime, &gpu);
    assert_eq!(recorded, 4, "the dead-end pass must be culled and never recorded");
    let s = &first.stats;
    assert_eq!((s.passes_declared, s.passes_executed), (5, 4));
    let texture = 64 * 64 * 4;
    // a, b, c, out requested; c reuses a (a's last reader, make_b, has run): 3 allocated.
    assert_eq!(s.transient_bytes_requested, 4 * texture);
    assert_eq!(s.transient_bytes_allocated, 3 * texture);
    assert_eq!(s.textures_created, 3);
    let pixels = read_texture_rgba8(&gpu.device, &gpu.queue, &first.texture).unwrap();
    assert_eq!(&pixels[..4], &[0, 255, 0, 255], "the output pass ran and wrote green");

    let (second, _) = chain_frame(&mut runtime, &gpu);
    assert_eq!(second.stats.textures_created, 0, "a steady-state frame creates no textures");
    assert_eq!(runtime.pool().len(), 3);
    assert_eq!(runtime.pool().bytes(), 3 * texture);
}

#[test]
fn pass_timings_arrive_as_medians_when_supported() {
    let gpu = common::gpu();
    let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
    for _ in 0..8 {
        chain_frame(&mut runtime, &gpu);
        let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
    }
    runtime.drain_timings(&gpu.device);
    let timings = runtime.timings();
    if gpu.has_timestamps() {
        let names: Vec<&str> = timings.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names, ["make_a", "make_b", "make_c", "out"]);
        assert!(timings.iter().all(|t| t.samples >= 4 && t.median_ms >= 0.0 && t.median_ms < 1000.0), "{timings:?}");
        assert!(runtime.frame_gpu_median_ms().is_some());
    } else {
        assert!(timings.is_empty());
    }
}

#[test]
fn gpu_validation_errors_are_collected_not_panics() {
    let gpu = common::gpu();
    // A zero-sized texture is a validation error raised outside any error scope.
    let _ = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("invalid"),
        size: wgpu::Extent3d { width: 0, height: 0, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: FMT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let errors = gpu.take_uncaptured_errors();
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(gpu.take_uncaptured_errors().is_empty(), "taking clears the list");
}

#[test]
fn broken_shader_fails_with_location_and_device_survives() {
    let gpu = common::gpu();
    let layout =
        gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("empty"), entries: &[] });
    let broken = "@compute @workgroup_size(8, 8, 1)\nfn main() {\n    let x: f32 = 1u;\n}\n";
    let err = indra::gpu::ComputeKernel::new(&gpu.device, "broken.wgsl", broken, "main", &[&layout])
        .err()
        .expect("must fail");
    assert_eq!(err.line, 3, "{err}");
    let ok = "@compute @workgroup_size(8, 4, 1)\nfn main() {}\n";
    let kernel =
        indra::gpu::ComputeKernel::new(&gpu.device, "ok.wgsl", ok, "main", &[&layout]).expect("valid shader builds");
    assert_eq!(kernel.workgroups([17, 9, 1]), [3, 3, 1], "dispatch sizes come from the shader's workgroup size");
    assert!(gpu.take_uncaptured_errors().is_empty());
}

#[test]
fn persistent_ping_pong_state_is_written_even_if_nothing_reads_it() {
    let gpu = common::gpu();
    let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
    let mut state = indra::graph::PingPong::new(&gpu.device, "test.state", (8, 8), FMT);
    for (step, colour) in [(0, wgpu::Color::RED), (1, wgpu::Color::BLUE)] {
        let mut graph = FrameGraph::new((8, 8));
        let (write, history) = state.write_and_history();
        let next = graph.import_texture("state.next", write);
        let _prev = graph.import_texture("state.prev", history);
        let out = graph.create_texture("out", TextureDesc::full(FMT));
        // Writes only persistent state: must not be culled although the output never reads it.
        graph.add_pass("simulate").render_target(next).record(move |ctx| clear(ctx, next, colour));
        graph.add_pass("show").render_target(out).record(move |ctx| clear(ctx, out, wgpu::Color::BLACK));
        graph.set_output(out);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let frame = runtime.execute(&gpu.device, &gpu.queue, graph, &mut encoder).unwrap();
        gpu.queue.submit([encoder.finish()]);
        assert_eq!(frame.stats.passes_executed, 2, "step {step}");
        state.swap();
    }
    // After two steps the current state holds the second write, the other the first.
    let current = read_texture_rgba8(&gpu.device, &gpu.queue, &state.current().texture).unwrap();
    assert_eq!(&current[..4], &[0, 0, 255, 255]);
    let (other, _) = state.write_and_history();
    assert_eq!(&read_texture_rgba8(&gpu.device, &gpu.queue, &other.texture).unwrap()[..4], &[255, 0, 0, 255]);
}

/// A frame in which `buffers` compute steps each write a transient buffer of 1 KiB that the next
/// reads, into an output image.
fn buffer_frame(runtime: &mut GraphRuntime, gpu: &indra::gpu::Gpu, buffers: usize) {
    let mut graph = FrameGraph::new((8, 8));
    let out = graph.create_texture("out", TextureDesc::full(wgpu::TextureFormat::Rgba8Unorm));
    let mut last = None;
    for i in 0..buffers {
        let b = graph.create_buffer(format!("b{i}"), 1024);
        let pass = graph.add_pass(format!("write{i}")).write_buffer(b);
        let pass = if let Some(previous) = last { pass.read_buffer(previous) } else { pass };
        pass.record(move |ctx| {
            let buffer = ctx.buffer(b).clone();
            ctx.encoder.clear_buffer(&buffer, 0, None);
        });
        last = Some(b);
    }
    let pass = graph.add_pass("out").render_target(out);
    let pass = if let Some(previous) = last { pass.read_buffer(previous) } else { pass };
    pass.record(move |ctx| clear(ctx, out, wgpu::Color::GREEN));
    graph.set_output(out);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    runtime.execute(&gpu.device, &gpu.queue, graph, &mut encoder).expect("graph compiles");
    gpu.queue.submit([encoder.finish()]);
    runtime.after_submit();
}

#[test]
fn transient_buffers_are_shared_in_turn_and_dropped_when_idle_unless_held() {
    let gpu = common::gpu();
    for hold in [false, true] {
        let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
        runtime.hold_transients(hold);
        buffer_frame(&mut runtime, &gpu, 4);
        // b0 → b1 → b2 → b3: each buffer is free once the step after it has read it, so two
        // take turns.
        assert_eq!(runtime.buffer_pool().bytes(), 2 * 1024, "four buffers in turn need two");
        for _ in 0..130 {
            buffer_frame(&mut runtime, &gpu, 0);
        }
        let kept = if hold { 2 * 1024 } else { 0 };
        assert_eq!(runtime.buffer_pool().bytes(), kept, "idle buffers after two seconds (hold {hold})");
    }
}
