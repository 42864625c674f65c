//! The bandwidth a plain copy kernel achieves on this GPU: the calibration the cloth's
//! per-substep figure is read against (perf-anchors.md asks for it before any bandwidth claim).
//!
//! `cargo run --release --example copy_bandwidth [-- PARTICLES]` copies PARTICLES vec4<f32>
//! (default 1024², the cloth_1024 grid) from one buffer to another, 16 dispatches per compute
//! pass as the cloth's substeps run, and as one large copy of 128 MiB (the smallest storage binding limit common GPUs guarantee); it prints the median
//! time per dispatch and the bytes moved per second (read + write).

use indra::gpu::{BackendChoice, ComputeKernel, Gpu, GpuOptions, read_buffer, storage_entry, uniform_buffer};

const COPY: &str = "
@group(0) @binding(0) var<uniform> count: vec4<u32>;
@group(0) @binding(1) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> dst: array<vec4<f32>>;

@compute @workgroup_size(256, 1, 1)
fn copy(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.y * groups.x * 256u + id.x;
    if (i < count.x) {
        dst[i] = src[i];
    }
}
";

/// Dispatches per pass, as the cloth runs its substeps.
const DISPATCHES: u32 = 16;
/// Passes timed for each size.
const REPEATS: usize = 200;

fn main() -> Result<(), String> {
    let particles: u32 = std::env::args().nth(1).map_or(Ok(1 << 20), |a| a.parse()).map_err(|e| format!("{e}"))?;
    let gpu = Gpu::headless(&GpuOptions { backend: BackendChoice::Vulkan, ..GpuOptions::default() })
        .map_err(|e| e.to_string())?;
    if !gpu.device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
        return Err(format!("{} has no timestamp queries", gpu.adapter_label()));
    }
    println!("adapter: {}", gpu.adapter_label());
    for (label, count, dispatches) in [("cloth grid", particles, DISPATCHES), ("128 MiB", 1 << 23, 1)] {
        let per_dispatch = median_copy(&gpu, count, dispatches)?;
        let bytes = 2.0 * 16.0 * f64::from(count);
        println!(
            "{label}: {count} vec4 per dispatch, {dispatches} dispatches per pass: median {:.2} µs per dispatch, {:.0} GB/s (read + write)",
            per_dispatch * 1e6,
            bytes / per_dispatch / 1e9
        );
    }
    Ok(())
}

/// Median seconds per dispatch of copying `count` vec4 with `dispatches` dispatches per pass.
fn median_copy(gpu: &Gpu, count: u32, dispatches: u32) -> Result<f64, String> {
    let device = &gpu.device;
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("copy"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            storage_entry(1, wgpu::ShaderStages::COMPUTE, true),
            storage_entry(2, wgpu::ShaderStages::COMPUTE, false),
        ],
    });
    let kernel = ComputeKernel::new(device, "copy.wgsl", COPY, "copy", &[&layout]).map_err(|e| e.to_string())?;
    let size = u64::from(count) * 16;
    let buffer = |label| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    };
    let (a, b) = (buffer("copy_a"), buffer("copy_b"));
    let uniforms = uniform_buffer::<[u32; 4]>(device, "copy_count");
    gpu.queue.write_buffer(&uniforms, 0, bytemuck::cast_slice(&[count, 0, 0, 0]));
    let group = |src: &wgpu::Buffer, dst: &wgpu::Buffer| {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("copy"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: src.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: dst.as_entire_binding() },
            ],
        })
    };
    // Alternate directions, as the cloth's buffers rotate, so every dispatch depends on the last.
    let groups = [group(&a, &b), group(&b, &a)];
    let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("copy_times"),
        ty: wgpu::QueryType::Timestamp,
        count: 2,
    });
    let resolve = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("copy_resolve"),
        size: 16,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let threads = [count.min(65535 * 256), count.div_ceil(65535 * 256), 1];
    let period = f64::from(gpu.queue.get_timestamp_period()) * 1e-9;
    let mut samples = Vec::with_capacity(REPEATS);
    for repeat in 0..REPEATS + 5 {
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("copy"),
                timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                    query_set: &queries,
                    beginning_of_pass_write_index: Some(0),
                    end_of_pass_write_index: Some(1),
                }),
            });
            for d in 0..dispatches {
                kernel.dispatch(&mut pass, &[&groups[d as usize % 2]], threads);
            }
        }
        encoder.resolve_query_set(&queries, 0..2, &resolve, 0);
        gpu.queue.submit([encoder.finish()]);
        let stamps = read_buffer(device, &gpu.queue, &resolve, 0, 16).map_err(|e| e.to_string())?;
        let stamps: &[u64] = bytemuck::cast_slice(&stamps);
        // The first few passes warm caches and clocks.
        if repeat >= 5 {
            samples.push(stamps[1].saturating_sub(stamps[0]) as f64 * period / f64::from(dispatches));
        }
    }
    samples.sort_by(f64::total_cmp);
    Ok(samples[samples.len() / 2])
}
