//! What a rasterising pass costs on this GPU before it draws anything: the clear, the
//! multisample resolve and the depth buffer of a full-frame target, against the same bytes written
//! by a compute pass. The account behind the raster nodes' figures in docs/performance.md.
//!
//! `cargo run --release --example raster_floor [-- WIDTH HEIGHT]` (default 3840×2160) prints the
//! median GPU time of each variant, timed by timestamps written around it in the encoder.

use indra::gpu::{BackendChoice, Gpu, GpuOptions, read_buffer};

/// Frames timed per variant (after a few warm-up frames).
const REPEATS: usize = 60;
const COLOR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

const FULLSCREEN: &str = "
@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(p * 2.0 - 1.0, 0.5, 1.0);
}
@fragment fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(fract(p.xy * 0.01), 0.5, 1.0);
}
";

const COMPUTE_FILL: &str = "
@group(0) @binding(0) var output: texture_storage_2d<rgba16float, write>;
@compute @workgroup_size(8, 8, 1)
fn fill(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(output);
    if (id.x < size.x && id.y < size.y) {
        textureStore(output, id.xy, vec4<f32>(fract(vec2<f32>(id.xy) * 0.01), 0.5, 1.0));
    }
}
";

const COMPUTE_RESOLVE: &str = "
@group(0) @binding(0) var samples: texture_multisampled_2d<f32>;
@group(0) @binding(1) var output: texture_storage_2d<rgba16float, write>;
@compute @workgroup_size(8, 8, 1)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(output);
    if (id.x < size.x && id.y < size.y) {
        var sum = vec4<f32>(0.0);
        for (var s = 0; s < 4; s++) { sum += textureLoad(samples, id.xy, s); }
        textureStore(output, id.xy, sum * 0.25);
    }
}
";

/// One variant: its name and what it records.
struct Variant {
    name: &'static str,
    samples: u32,
    depth: bool,
    draw: bool,
    resolve: bool,
}

fn main() -> Result<(), String> {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<u32>().map_err(|e| e.to_string()));
    let width = args.next().unwrap_or(Ok(3840))?;
    let height = args.next().unwrap_or(Ok(2160))?;
    let gpu = Gpu::headless(&GpuOptions { backend: BackendChoice::Vulkan, ..GpuOptions::default() })
        .map_err(|e| e.to_string())?;
    if !gpu.device.features().contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS) {
        return Err(format!("{} has no timestamps inside encoders", gpu.adapter_label()));
    }
    println!("adapter: {}  size: {width}x{height}", gpu.adapter_label());
    let floor = Floor::new(&gpu, width, height);
    let mut variants = Vec::new();
    for samples in [1, 4] {
        for (depth, draw) in [(false, false), (true, false), (false, true), (true, true)] {
            let name = match (depth, draw) {
                (false, false) => "clear",
                (true, false) => "clear + depth",
                (false, true) => "clear + full-frame draw",
                (true, true) => "clear + depth + full-frame draw",
            };
            variants.push(Variant { name, samples, depth, draw, resolve: true });
        }
    }
    variants.push(Variant {
        name: "clear, stored (no resolve)",
        samples: 4,
        depth: false,
        draw: false,
        resolve: false,
    });
    for v in &variants {
        let ms = floor.median(&gpu, |encoder| floor.record_raster(encoder, v))?;
        let how = if v.samples > 1 && v.resolve { ", resolved" } else { "" };
        println!("{:<55} {ms:.3} ms", format!("raster {}x {}{how}", v.samples, v.name));
    }
    let ms = floor.median(&gpu, |encoder| {
        floor.record_raster(encoder, &Variant { name: "", samples: 4, depth: false, draw: false, resolve: false });
        floor.record_compute_resolve(encoder);
    })?;
    println!("{:<55} {ms:.3} ms", "raster 4x clear, stored + compute resolve");
    let ms = floor.median(&gpu, |e| floor.record_fill(e))?;
    println!("{:<55} {ms:.3} ms", "compute fill (1x, the same bytes as the 1x clear)");
    Ok(())
}

/// The targets and pipelines of the experiment.
struct Floor {
    single_view: wgpu::TextureView,
    multi_view: wgpu::TextureView,
    depth_views: [wgpu::TextureView; 2],
    draws: [wgpu::RenderPipeline; 4],
    fill: (wgpu::ComputePipeline, wgpu::BindGroup),
    resolve: (wgpu::ComputePipeline, wgpu::BindGroup),
    size: (u32, u32),
    queries: wgpu::QuerySet,
    stamps: wgpu::Buffer,
}

impl Floor {
    fn new(gpu: &Gpu, width: u32, height: u32) -> Self {
        let device = &gpu.device;
        let texture = |label, format, samples, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let single =
            texture("single", COLOR, 1, attach | wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_DST);
        let multi = texture("multi", COLOR, 4, attach | wgpu::TextureUsages::TEXTURE_BINDING);
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let depth_views = [view(&texture("depth1", DEPTH, 1, attach)), view(&texture("depth4", DEPTH, 4, attach))];
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("fullscreen"),
            source: wgpu::ShaderSource::Wgsl(FULLSCREEN.into()),
        });
        let draw = |samples: u32, depth: bool| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("fullscreen"),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: depth.then(|| wgpu::DepthStencilState {
                    format: DEPTH,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: wgpu::MultisampleState { count: samples, ..Default::default() },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs"),
                    compilation_options: Default::default(),
                    targets: &[Some(COLOR.into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let draws = [draw(1, false), draw(1, true), draw(4, false), draw(4, true)];
        let single_view = view(&single);
        let multi_view = view(&multi);
        // Explicit layouts: a derived one would ask for a filterable multisampled texture.
        let storage_out = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: COLOR,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
            count: None,
        };
        let samples_in = wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: true,
            },
            count: None,
        };
        let compute = |source: &str, entry: &str, views: &[&wgpu::TextureView]| {
            let entries: &[wgpu::BindGroupLayoutEntry] =
                if views.len() == 1 { &[storage_out(0)] } else { &[samples_in, storage_out(1)] };
            let group_layout =
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(entry), entries });
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(entry),
                bind_group_layouts: &[Some(&group_layout)],
                immediate_size: 0,
            });
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(entry),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            });
            let entries: Vec<_> = views
                .iter()
                .enumerate()
                .map(|(i, v)| wgpu::BindGroupEntry {
                    binding: i as u32,
                    resource: wgpu::BindingResource::TextureView(v),
                })
                .collect();
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(entry),
                layout: &group_layout,
                entries: &entries,
            });
            (pipeline, group)
        };
        let fill = compute(COMPUTE_FILL, "fill", &[&single_view]);
        let resolve = compute(COMPUTE_RESOLVE, "resolve", &[&multi_view, &single_view]);
        let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("floor"),
            ty: wgpu::QueryType::Timestamp,
            count: 2,
        });
        let stamps = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("floor_stamps"),
            size: 16,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Self { single_view, multi_view, depth_views, draws, fill, resolve, size: (width, height), queries, stamps }
    }

    /// One render pass as a raster node records it.
    fn record_raster(&self, encoder: &mut wgpu::CommandEncoder, v: &Variant) {
        let multi = v.samples > 1;
        let (view, resolve_target) = match (multi, v.resolve) {
            (true, true) => (&self.multi_view, Some(&self.single_view)),
            (true, false) => (&self.multi_view, None),
            (false, _) => (&self.single_view, None),
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(v.name),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: if resolve_target.is_some() { wgpu::StoreOp::Discard } else { wgpu::StoreOp::Store },
                },
            })],
            depth_stencil_attachment: v.depth.then(|| wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth_views[usize::from(multi)],
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        if v.draw {
            pass.set_pipeline(&self.draws[usize::from(multi) * 2 + usize::from(v.depth)]);
            pass.draw(0..3, 0..1);
        }
    }

    fn record_compute(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (pipeline, group): &(wgpu::ComputePipeline, wgpu::BindGroup),
    ) {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(self.size.0.div_ceil(8), self.size.1.div_ceil(8), 1);
    }

    fn record_fill(&self, encoder: &mut wgpu::CommandEncoder) {
        self.record_compute(encoder, &self.fill);
    }

    fn record_compute_resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        self.record_compute(encoder, &self.resolve);
    }

    /// The median milliseconds between timestamps written before and after `record`.
    fn median(&self, gpu: &Gpu, record: impl Fn(&mut wgpu::CommandEncoder)) -> Result<f64, String> {
        let period = f64::from(gpu.queue.get_timestamp_period()) * 1e-6;
        let mut samples = Vec::with_capacity(REPEATS);
        let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        for repeat in 0..REPEATS + 5 {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            encoder.write_timestamp(&self.queries, 0);
            record(&mut encoder);
            encoder.write_timestamp(&self.queries, 1);
            encoder.resolve_query_set(&self.queries, 0..2, &self.stamps, 0);
            gpu.queue.submit([encoder.finish()]);
            let stamps = read_buffer(&gpu.device, &gpu.queue, &self.stamps, 0, 16).map_err(|e| e.to_string())?;
            let stamps: &[u64] = bytemuck::cast_slice(&stamps);
            if repeat >= 5 {
                samples.push(stamps[1].saturating_sub(stamps[0]) as f64 * period);
            }
        }
        if let Some(error) = pollster::block_on(scope.pop()) {
            return Err(error.to_string());
        }
        samples.sort_by(f64::total_cmp);
        Ok(samples[samples.len() / 2])
    }
}
