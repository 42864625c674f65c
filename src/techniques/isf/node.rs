//! An ISF node on the GPU: one render pipeline per target format from the compiled stages, a
//! uniform buffer per pass, feedback buffers (persistent targets, ping-ponged so the pass that
//! writes one reads its last frame), imported images, and each frame's passes in the frame graph.

use std::collections::BTreeMap;

mod saved;

use super::compile::Compiled;
use super::header::InputKind;
use super::pipeline::{FormatKey, OUTPUT_FORMAT, Pipeline, Pipelines, build_pipelines};
use super::program::{FIRST_TEXTURE_BINDING, SAMPLER_BINDING, TextureSource, UNIFORM_BINDING, storage_binding};
use super::sound::{AUDIO_WIDTH, AudioTexture};
use super::targets::{BYTE_FORMAT, FLOAT_FORMAT};
use super::{IsfFiles, Settings};
use crate::checkpoint::{CheckpointError, NodeState};
use crate::gpu::{BindGroupCache, DEFAULT_MAX_AGE, Gpu, ShaderError};
use crate::graph::{Extent, FrameGraph, PersistentTexture, PingPong, TextureDesc, TextureHandle};
use crate::params::{AudioSnapshot, ParamSet, ParamValue};
use crate::techniques::image_pass::{self, ImageKernel, ImagePass};
use crate::techniques::{NodeSetup, Technique};
use crate::time::FrameTime;

/// The largest imported image file read.
const IMPORTED_FILE_LIMIT: u64 = 64 << 20;

/// Builds an ISF node from the file its `file` parameter names.
pub fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    let file = Settings::read(setup.params).file;
    let files = IsfFiles::read(setup.assets, file.as_str()).map_err(|message| ShaderError {
        origin: file.as_str().into(),
        line: 1,
        column: 1,
        message,
    })?;
    let compiled = files.compile()?;
    Ok(Box::new(IsfNode::new(setup, &files, compiled)?))
}

/// One pass's GPU state.
struct PassState {
    uniforms: wgpu::Buffer,
    groups: BindGroupCache<Vec<u64>>,
}

/// A persistent target.
struct Feedback {
    buffers: PingPong,
    size: (u32, u32),
    format: wgpu::TextureFormat,
}

/// A live ISF node.
pub struct IsfNode {
    compiled: std::sync::Arc<Compiled>,
    pipelines: Pipelines,
    passes: Vec<PassState>,
    /// Persistent targets by name.
    feedback: BTreeMap<String, Feedback>,
    /// Imported images by name.
    imported: BTreeMap<String, PersistentTexture>,
    /// Sound as textures, by input name: the waveform (`audio`) or spectrum (`audioFFT`), one
    /// row, written each frame from what the audio analysis heard.
    audio: BTreeMap<String, AudioTexture>,
    queue: wgpu::Queue,
    /// What a texture nothing has written yet reads: transparent black.
    black: PersistentTexture,
    present: (ImageKernel, ImagePass),
    /// The parameter positions of the shader's inputs (by name, found once).
    positions: Vec<Option<usize>>,
    /// Per input: the header's default, what a missing parameter reads.
    defaults: Vec<Option<ParamValue>>,
    /// Per input: its offset in the uniform block (a bool's or event's int), found once.
    input_offsets: Vec<Option<u32>>,
    /// Per texture slot: the offset of its size in the uniform block.
    size_offsets: Vec<Option<u32>>,
    device: wgpu::Device,
    id: String,
    messages: Vec<String>,
    /// The last size-expression problem told, so it is told once.
    size_problem: Option<String>,
    /// The pass sizes of the last frame whose sizes were good: what the passes keep while a
    /// live value asks for sizes that cannot be made.
    sizes: Vec<(u32, u32)>,
    /// Per input: whether an event fired in the latest step (triggers are seen in the step they
    /// fire in; the frame drawn after it shows them).
    fired: Vec<bool>,
}

/// The present kernel's (unused) uniform block.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PresentUniforms {
    pad: [u32; 4],
}

impl IsfNode {
    fn new(setup: &NodeSetup<'_>, files: &IsfFiles, compiled: Compiled) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let origin = files.fs.0.as_str();
        let pipelines = build_pipelines(device, origin, &compiled)?;
        let passes = (0..compiled.header.passes.len())
            .map(|i| PassState {
                uniforms: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&format!("{}/pass{i}/uniforms", setup.id)),
                    size: u64::from(compiled.program.uniforms.size),
                    usage: crate::gpu::BLOCK_USAGE,
                    mapped_at_creation: false,
                }),
                groups: BindGroupCache::new(DEFAULT_MAX_AGE),
            })
            .collect();
        let black = PersistentTexture::new(device, "isf/black", (1, 1), BYTE_FORMAT);
        let (present_origin, present_source) = setup.shader_source("isf_present.wgsl", &image_pass::bindings(1))?;
        let kernel = ImageKernel::new(
            device,
            (&present_origin, &present_source),
            "isf_present",
            1,
            size_of::<PresentUniforms>() as u64,
        )?;
        let present_pass = ImagePass::new(device, &kernel);
        let positions = compiled.header.inputs.iter().map(|i| setup.params.index(&i.name)).collect();
        let defaults = compiled.header.inputs.iter().map(|i| i.decl().map(|d| d.default)).collect();
        let layout = &compiled.program.uniforms;
        let input_offsets = compiled
            .header
            .inputs
            .iter()
            .map(|i| match i.kind {
                InputKind::Bool { .. } | InputKind::Event => layout.offset(&format!("_isf_b_{}", i.name)),
                _ => layout.offset(&i.name),
            })
            .collect();
        let size_offsets =
            compiled.program.textures.iter().map(|t| layout.offset(&format!("_isf_size_{}", t.name))).collect();
        let audio = compiled
            .header
            .inputs
            .iter()
            .filter_map(|i| {
                let (max, spectrum) = match i.kind {
                    InputKind::Audio { max } => (max, false),
                    InputKind::AudioFft { max } => (max, true),
                    _ => return None,
                };
                let width = max.unwrap_or(AUDIO_WIDTH).clamp(1, 4096);
                let label = format!("{}/{}", setup.id, i.name);
                Some((i.name.clone(), AudioTexture::new(device, &setup.gpu.queue, &label, width, spectrum)))
            })
            .collect();
        let mut node = Self {
            audio,
            queue: setup.gpu.queue.clone(),
            imported: BTreeMap::new(),
            feedback: BTreeMap::new(),
            compiled: std::sync::Arc::new(compiled),
            pipelines,
            passes,
            black,
            present: (kernel, present_pass),
            positions,
            defaults,
            input_offsets,
            size_offsets,
            device: device.clone(),
            id: setup.id.to_string(),
            messages: Vec::new(),
            size_problem: None,
            sizes: Vec::new(),
            fired: Vec::new(),
        };
        node.fired = vec![false; node.compiled.header.inputs.len()];
        let fail = |message: String| ShaderError { origin: origin.to_string(), line: 1, column: 1, message };
        // A block past the device's limit would fail validation every frame: refuse it here.
        let block = u64::from(node.compiled.program.uniforms.size);
        let limit = device.limits().max_uniform_buffer_binding_size;
        if block > limit {
            return Err(fail(format!("the inputs need a {block}-byte uniform block; this GPU binds at most {limit}")));
        }
        // Sizes that fail with the defaults, or targets too large together, fail the node (a
        // located error; a reload keeps the last good version).
        node.sizes = node.pass_sizes(setup.params, setup.output_size).map_err(fail)?;
        node.import_images(setup, files)?;
        Ok(node)
    }

    /// Reads, decodes and uploads the `IMPORTED` images (paths relative to the shader).
    fn import_images(&mut self, setup: &NodeSetup<'_>, files: &IsfFiles) -> Result<(), ShaderError> {
        for (name, path) in &self.compiled.header.imported {
            let beside = files.path.as_ref().and_then(|p| p.parent()).map(|d| d.join(path));
            let located = beside.as_ref().map_or(path.clone(), |p| p.display().to_string());
            let failed = |message: String| ShaderError { origin: files.fs.0.clone(), line: 1, column: 1, message };
            let bytes = setup
                .assets
                .read_file(&located, IMPORTED_FILE_LIMIT, None)
                .map_err(|e| failed(format!("IMPORTED '{name}': {e}")))?;
            let max_side = setup.gpu.device.limits().max_texture_dimension_2d;
            let still = crate::media::still::decode(&bytes.bytes, &bytes.origin, max_side, 256 << 20)
                .map_err(|e| failed(format!("IMPORTED '{name}': {e}")))?;
            let crate::media::picture::Picture::Rgba(pixels) = still.picture else {
                return Err(failed(format!("IMPORTED '{name}': only 8-bit images (PNG, JPEG) are imported")));
            };
            let texture = PersistentTexture::new(&self.device, &format!("isf/{name}"), still.size, BYTE_FORMAT);
            setup.gpu.queue.write_texture(
                texture.texture.as_image_copy(),
                &pixels,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * still.size.0),
                    rows_per_image: Some(still.size.1),
                },
                texture.texture.size(),
            );
            self.imported.insert(name.clone(), texture);
        }
        Ok(())
    }

    /// The value of input `k` now: the node's parameter, or the header's default where the
    /// parameter is missing (a file changed under a running scene).
    fn input_value(&self, k: usize, params: &ParamSet) -> Option<ParamValue> {
        let value = self.positions[k].map(|p| params.value_at(p));
        let default = self.defaults[k];
        match value {
            Some(v) if default.is_some_and(|d| d.ty() == v.ty()) => Some(v),
            _ => default,
        }
    }

    /// Every pass's size: its expressions over `$WIDTH`, `$HEIGHT` and the inputs, or the render
    /// size; refused past the device's side or the node's target bytes.
    fn pass_sizes(&self, params: &ParamSet, output: (u32, u32)) -> Result<Vec<(u32, u32)>, String> {
        let var = |name: &str| -> Option<f64> {
            match name {
                "WIDTH" => Some(f64::from(output.0)),
                "HEIGHT" => Some(f64::from(output.1)),
                _ => {
                    let k = self.compiled.header.inputs.iter().position(|i| i.name == name)?;
                    self.compiled.header.inputs[k].number(self.input_value(k, params)?)
                }
            }
        };
        let max_side = self.device.limits().max_texture_dimension_2d;
        super::targets::pass_sizes(&self.compiled.header.passes, output, max_side, &var)
    }

    /// The uniform block's bytes for one pass.
    fn uniform_bytes(&self, params: &ParamSet, time: &FrameTime, pass: PassUniforms<'_>) -> Vec<u8> {
        let layout = &self.compiled.program.uniforms;
        let mut bytes = vec![0u8; layout.size as usize];
        let mut put_at = |offset: Option<u32>, values: &[f32], int: bool| {
            let Some(offset) = offset else { return };
            for (i, v) in values.iter().enumerate() {
                let at = offset as usize + 4 * i;
                let word = if int { (*v as i32).to_le_bytes() } else { v.to_le_bytes() };
                bytes[at..at + 4].copy_from_slice(&word);
            }
        };
        let mut put = |name: &str, values: &[f32], int: bool| put_at(layout.offset(name), values, int);
        let date = Settings::read(params).date;
        put("PASSINDEX", &[pass.index as f32], true);
        put("FRAMEINDEX", &[time.frame as f32], true);
        put("TIME", &[time.seconds as f32], false);
        put("TIMEDELTA", &[time.dt], false);
        put("RENDERSIZE", &[pass.size.0 as f32, pass.size.1 as f32], false);
        put("_isf_final", &[f32::from(u8::from(pass.is_final))], true);
        put("DATE", &[date[0], date[1], date[2], ((f64::from(date[3]) + time.seconds) % 86_400.0) as f32], false);
        for (k, input) in self.compiled.header.inputs.iter().enumerate() {
            let Some(value) = self.input_value(k, params) else { continue };
            let offset = self.input_offsets[k];
            match (&input.kind, value) {
                // Events as this step saw them; longs, bools as the numbers the shader takes.
                (InputKind::Event, _) => put_at(offset, &[f32::from(u8::from(self.fired[k]))], true),
                (InputKind::Long { .. } | InputKind::Bool { .. }, v) => {
                    put_at(offset, &[input.number(v).unwrap_or(0.0) as f32], true);
                }
                (_, v) => put_at(offset, &v.components(), false),
            }
        }
        for (offset, size) in self.size_offsets.iter().zip(pass.texture_sizes) {
            put_at(*offset, &[size.0 as f32, size.1 as f32], false);
        }
        bytes
    }

    /// The persistent target `name` at `size` and `format`, made (or remade, cleared) to fit.
    fn feedback(&mut self, name: &str, size: (u32, u32), format: wgpu::TextureFormat) -> &mut Feedback {
        let fits = self.feedback.get(name).is_some_and(|f| f.size == size && f.format == format);
        if !fits {
            let buffers = PingPong::new(&self.device, &format!("{}/{name}", self.id), size, format);
            self.feedback.insert(name.to_string(), Feedback { buffers, size, format });
        }
        self.feedback.get_mut(name).expect("made above")
    }
}

/// What differs between the passes of a frame.
struct PassUniforms<'a> {
    index: usize,
    size: (u32, u32),
    is_final: bool,
    /// Each texture slot's size, in slot order.
    texture_sizes: &'a [(u32, u32)],
}

impl Technique for IsfNode {
    fn simulates_on_gpu(&self) -> bool {
        // Feedback buffers are state: a sought frame must have run every pass before it.
        self.compiled.header.passes.iter().any(|p| p.persistent)
    }

    fn step(&mut self, params: &ParamSet, _time: &FrameTime) {
        // This step's events only: a frame reached by seeking shows what playing shows.
        for k in 0..self.compiled.header.inputs.len() {
            self.fired[k] = matches!(self.input_value(k, params), Some(ParamValue::Trigger(true)));
        }
    }

    fn hear(&mut self, audio: &AudioSnapshot) {
        for texture in self.audio.values() {
            texture.write(&self.queue, audio);
        }
    }

    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn save_state(&self, gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
        saved::save(self, gpu, state)
    }

    fn load_state(&mut self, gpu: &Gpu, _: &ParamSet, _: &FrameTime, state: &NodeState) -> Result<(), CheckpointError> {
        saved::load(self, gpu, state)
    }

    fn status(&self) -> Option<String> {
        let h = &self.compiled.header;
        let role = format!("{:?}", h.role()).to_lowercase();
        Some(format!(
            "ISF {role}, {} pass(es){}",
            h.passes.len(),
            if h.credit.is_empty() { String::new() } else { format!(" — {}", h.credit) }
        ))
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        inputs: &[TextureHandle],
    ) -> TextureHandle {
        let output = graph.output_size();
        // The compiled shader is shared, not copied, while the node's state changes below.
        let compiled = std::sync::Arc::clone(&self.compiled);
        let header_passes = &compiled.header.passes;
        // Sizes first: bad sizes (an input driven out of range) keep the last good ones, told once.
        let sizes = match self.pass_sizes(params, output) {
            Ok(sizes) => {
                self.sizes.clone_from(&sizes);
                sizes
            }
            Err(problem) => {
                if self.size_problem.as_ref() != Some(&problem) {
                    self.messages.push(format!("{}: {problem}; the passes keep their sizes", self.id));
                    self.size_problem = Some(problem);
                }
                self.sizes.clone()
            }
        };
        // Persistent targets, (re)made to their size; both halves imported.
        let mut feedback_handles: BTreeMap<String, [TextureHandle; 2]> = BTreeMap::new();
        for (pass, size) in header_passes.iter().zip(&sizes) {
            let Some(target) = pass.target.as_ref().filter(|_| pass.persistent) else { continue };
            if feedback_handles.contains_key(target) {
                continue;
            }
            let format = if pass.float { FLOAT_FORMAT } else { BYTE_FORMAT };
            let id = self.id.clone();
            let f = self.feedback(target, *size, format);
            let (write, history) = f.buffers.write_and_history();
            let write = graph.import_texture(format!("{id}/{target}.next"), write);
            let history = graph.import_texture(format!("{id}/{target}"), history);
            feedback_handles.insert(target.clone(), [history, write]);
        }
        let black = graph.import_texture(format!("{}/black", self.id), &self.black);
        // What each texture slot reads now: (handle, size).
        let slots = &compiled.program.textures;
        let mut node_inputs = inputs.iter();
        let mut current: Vec<Option<(TextureHandle, (u32, u32))>> = Vec::with_capacity(slots.len());
        for slot in slots {
            current.push(match slot.source {
                TextureSource::Node => node_inputs.next().map(|&h| (h, graph.texture_size(h))),
                TextureSource::Target => feedback_handles.get(&slot.name).map(|h| {
                    let f = &self.feedback[&slot.name];
                    (h[0], f.size)
                }),
                TextureSource::Imported => self.imported.get(&slot.name).map(|t| {
                    let size = (t.texture.width(), t.texture.height());
                    (graph.import_texture(format!("{}/{}", self.id, slot.name), t), size)
                }),
                TextureSource::Audio | TextureSource::AudioFft => self.audio.get(&slot.name).map(|a| {
                    let size = (a.texture.texture.width(), 1);
                    (graph.import_texture(format!("{}/{}", self.id, slot.name), &a.texture), size)
                }),
            });
        }
        let slot_of = |name: &str| slots.iter().position(|s| s.name == name);
        let target_sizes: BTreeMap<String, (u32, u32)> =
            header_passes.iter().zip(&sizes).filter_map(|(p, size)| Some((p.target.clone()?, *size))).collect();
        // Uniforms per pass, built before the passes borrow the node.
        let mut plans = Vec::with_capacity(header_passes.len());
        let mut written: BTreeMap<String, usize> = BTreeMap::new();
        let last = header_passes.len() - 1;
        for (i, (pass, &size)) in header_passes.iter().zip(&sizes).enumerate() {
            let to_output = i == last && pass.target.is_none();
            // A target nothing wrote yet reads black but has its own size (IMG_SIZE).
            let bound: Vec<(TextureHandle, (u32, u32))> = current
                .iter()
                .zip(slots)
                .map(|(c, slot)| c.unwrap_or((black, target_sizes.get(&slot.name).copied().unwrap_or((1, 1)))))
                .collect();
            let texture_sizes: Vec<(u32, u32)> = bound.iter().map(|b| b.1).collect();
            let bytes = self.uniform_bytes(
                params,
                time,
                PassUniforms { index: i, size, is_final: to_output, texture_sizes: &texture_sizes },
            );
            let (dest, format) = match &pass.target {
                _ if to_output => (
                    graph.create_texture(format!("{}/image", self.id), TextureDesc::full(OUTPUT_FORMAT)),
                    OUTPUT_FORMAT,
                ),
                Some(target) if pass.persistent => {
                    let writes = written.entry(target.clone()).or_insert(0);
                    let handles = feedback_handles[target];
                    // Ping-pong: the first write of a frame goes to the other half, a second
                    // write back to the first, and so on.
                    let dest = handles[1 - *writes % 2];
                    *writes += 1;
                    (dest, if pass.float { FLOAT_FORMAT } else { BYTE_FORMAT })
                }
                Some(target) => {
                    let format = if pass.float { FLOAT_FORMAT } else { BYTE_FORMAT };
                    let desc =
                        TextureDesc { extent: Extent::Absolute(size.0, size.1), format, layers: None, samples: 1 };
                    (graph.create_texture(format!("{}/{target}", self.id), desc), format)
                }
                None => {
                    // A pass without a target before the last: it renders into a scratch image
                    // that nothing reads (as in GL hosts); still drawn, for its side effects.
                    let desc = TextureDesc {
                        extent: Extent::Absolute(size.0, size.1),
                        format: BYTE_FORMAT,
                        layers: None,
                        samples: 1,
                    };
                    (graph.create_texture(format!("{}/pass{i}", self.id), desc), BYTE_FORMAT)
                }
            };
            if let Some(k) = pass.target.as_ref().and_then(|t| slot_of(t)).filter(|_| !to_output) {
                current[k] = Some((dest, size));
            }
            plans.push((bound.into_iter().map(|b| b.0).collect::<Vec<_>>(), dest, format, bytes, size));
        }
        self.fired.iter_mut().for_each(|f| *f = false);
        // Feedback halves swap once per write this frame.
        for (target, writes) in &written {
            if writes % 2 == 1
                && let Some(f) = self.feedback.get_mut(target)
            {
                f.buffers.swap();
            }
        }
        let last_target = header_passes[last].target.as_ref();
        let covers_target = self.compiled.program.covers_target;
        let Self { pipelines, passes, present, id, .. } = self;
        let pipelines = &*pipelines;
        let mut image = None;
        for (i, ((bound, dest, format, bytes, size), state)) in plans.into_iter().zip(passes.iter_mut()).enumerate() {
            let mut builder = graph.add_pass(format!("{id}/pass{i}"));
            let mut read = bound.clone();
            read.sort_by_key(|h| h.0);
            read.dedup();
            for h in read {
                builder = builder.read(h);
            }
            if header_passes[i].persistent {
                builder = builder.side_effect();
            }
            let (layout, pipeline) = &pipelines.by_format[&FormatKey::of(format)];
            let builder = match pipeline {
                Pipeline::Compute(_) => builder.write(dest),
                Pipeline::Raster(_) => builder.render_target(dest),
            };
            builder.record(move |ctx| {
                ctx.queue.write_buffer(&state.uniforms, 0, &bytes);
                state.groups.begin_frame();
                let mut key: Vec<u64> = bound.iter().map(|&h| ctx.texture_id(h)).collect();
                key.push(ctx.texture_id(dest));
                let group = state
                    .groups
                    .get_or_create(key, || {
                        let mut entries = vec![
                            wgpu::BindGroupEntry {
                                binding: UNIFORM_BINDING,
                                resource: state.uniforms.as_entire_binding(),
                            },
                            wgpu::BindGroupEntry {
                                binding: SAMPLER_BINDING,
                                resource: wgpu::BindingResource::Sampler(&pipelines.sampler),
                            },
                        ];
                        for (k, &h) in bound.iter().enumerate() {
                            entries.push(wgpu::BindGroupEntry {
                                binding: FIRST_TEXTURE_BINDING + k as u32,
                                resource: wgpu::BindingResource::TextureView(ctx.view(h)),
                            });
                        }
                        if matches!(pipeline, Pipeline::Compute(_)) {
                            entries.push(wgpu::BindGroupEntry {
                                binding: storage_binding(bound.len()),
                                resource: wgpu::BindingResource::TextureView(ctx.view(dest)),
                            });
                        }
                        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                            label: Some("isf"),
                            layout,
                            entries: &entries,
                        })
                    })
                    .clone();
                match pipeline {
                    Pipeline::Compute(pipeline) => {
                        let mut cp = ctx.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                            label: Some("isf"),
                            timestamp_writes: None,
                        });
                        cp.set_pipeline(pipeline);
                        cp.set_bind_group(0, &group, &[]);
                        cp.dispatch_workgroups(size.0.div_ceil(8), size.1.div_ceil(8), 1);
                    }
                    Pipeline::Raster(pipeline) => {
                        // Cleared first, as GL hosts do, where a .vs moves the quad off some
                        // pixels; a quad over everything needs no clear (on the H200 the clear
                        // costs as much as the draw).
                        let load = if covers_target {
                            wgpu::LoadOp::Load
                        } else {
                            wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
                        };
                        let view = ctx.view(dest).clone();
                        let mut rp = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                            label: Some("isf"),
                            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                                view: &view,
                                depth_slice: None,
                                resolve_target: None,
                                ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
                            })],
                            depth_stencil_attachment: None,
                            timestamp_writes: None,
                            occlusion_query_set: None,
                            multiview_mask: None,
                        });
                        rp.set_pipeline(pipeline);
                        rp.set_bind_group(0, &group, &[]);
                        rp.draw(0..6, 0..1);
                    }
                }
            });
            if i == last && last_target.is_none() {
                image = Some(dest);
            }
        }
        if let Some(target) = last_target {
            // The last pass wrote a buffer: the node's image is that buffer, made linear.
            let k = slots.iter().position(|s| &s.name == target).expect("every target has a slot");
            let (source, _) = current[k].unwrap_or((black, (1, 1)));
            let (kernel, pass) = present;
            image =
                Some(pass.declare(graph, &format!("{id}/present"), kernel, PresentUniforms { pad: [0; 4] }, &[source]));
        }
        image.expect("the last pass makes the image")
    }
}
