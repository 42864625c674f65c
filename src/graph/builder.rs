//! Declaring a frame: virtual resources and the passes that read and write them.

use super::resource::{BufferHandle, PersistentTexture, TextureDesc, TextureHandle};

/// How a pass touches a resource; decides both the dependency and the inferred usage flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Access {
    /// Sampled or loaded in a shader.
    Read,
    /// Written as a storage texture/buffer (compute).
    Write,
    /// Written as a colour attachment.
    RenderTarget,
}

/// A resource reference inside a pass declaration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Resource {
    Texture(u32),
    Buffer(u32),
}

pub(crate) enum TextureOrigin {
    Transient(TextureDesc),
    Imported(wgpu::Texture, wgpu::TextureView, u64),
}

pub(crate) struct VirtualTexture {
    pub name: String,
    pub origin: TextureOrigin,
}

pub(crate) enum BufferOrigin {
    Transient { size: u64 },
    Imported(wgpu::Buffer, u64),
}

pub(crate) struct VirtualBuffer {
    pub name: String,
    pub origin: BufferOrigin,
}

/// The work of one pass, run at execute time with its resources resolved.
pub(crate) type RecordFn<'r> = Box<dyn FnOnce(&mut PassContext<'_>) + 'r>;

pub(crate) struct PassDecl<'r> {
    pub name: String,
    pub accesses: Vec<(Resource, Access)>,
    pub side_effect: bool,
    pub record: Option<RecordFn<'r>>,
}

/// One frame's declarations. Passes may be added in any order; [`super::compile`] sorts them.
pub struct FrameGraph<'r> {
    pub(crate) output_size: (u32, u32),
    pub(crate) textures: Vec<VirtualTexture>,
    pub(crate) buffers: Vec<VirtualBuffer>,
    pub(crate) passes: Vec<PassDecl<'r>>,
    pub(crate) output: Option<TextureHandle>,
    /// More textures the frame shows (other windows), kept like the output.
    pub(crate) extra_outputs: Vec<TextureHandle>,
    /// A frame that only advances simulations (a seek): it has no output, and only passes that
    /// write persistent state (imports) or have side effects, with what they depend on, run.
    pub(crate) simulation_only: bool,
}

impl<'r> FrameGraph<'r> {
    /// An empty graph for a frame whose output is `output_size` texels.
    pub fn new(output_size: (u32, u32)) -> Self {
        Self {
            output_size,
            textures: Vec::new(),
            buffers: Vec::new(),
            passes: Vec::new(),
            output: None,
            extra_outputs: Vec::new(),
            simulation_only: false,
        }
    }

    /// A graph for a frame that is stepped but not shown (frames skipped by a seek). Nodes add
    /// their passes as usual; compiling keeps only the work that changes persistent resources,
    /// so a stateful node's simulation runs exactly as in a drawn frame, and drawing is culled.
    pub fn simulation_only(output_size: (u32, u32)) -> Self {
        Self { simulation_only: true, ..Self::new(output_size) }
    }

    /// Whether this frame is only stepped, not shown (see [`FrameGraph::simulation_only`]).
    pub fn is_simulation_only(&self) -> bool {
        self.simulation_only
    }

    /// The frame's output size.
    pub fn output_size(&self) -> (u32, u32) {
        self.output_size
    }

    /// Declares a texture that lives only within this frame; the pool provides it.
    pub fn create_texture(&mut self, name: impl Into<String>, desc: TextureDesc) -> TextureHandle {
        self.textures.push(VirtualTexture { name: name.into(), origin: TextureOrigin::Transient(desc) });
        TextureHandle(self.textures.len() as u32 - 1)
    }

    /// The attachments of a rasterising pass named `name`: the single-sample `format` image that
    /// downstream nodes read, a multisampled colour target resolved into it when `samples` > 1,
    /// and a depth buffer of `depth` format (same sample count) if asked for.
    pub fn create_raster_targets(
        &mut self,
        name: &str,
        format: wgpu::TextureFormat,
        depth: Option<wgpu::TextureFormat>,
        samples: u32,
    ) -> RasterTargets {
        let color = self.create_texture(format!("{name}/image"), TextureDesc::full(format));
        let msaa = (samples > 1)
            .then(|| self.create_texture(format!("{name}/msaa"), TextureDesc::full(format).multisampled(samples)));
        let depth =
            depth.map(|d| self.create_texture(format!("{name}/depth"), TextureDesc::full(d).multisampled(samples)));
        RasterTargets { color, msaa, depth }
    }

    /// Brings a node-owned texture into the graph. Passes that write it are never culled.
    pub fn import_texture(&mut self, name: impl Into<String>, texture: &PersistentTexture) -> TextureHandle {
        let origin = TextureOrigin::Imported(texture.texture.clone(), texture.view.clone(), texture.id);
        self.textures.push(VirtualTexture { name: name.into(), origin });
        TextureHandle(self.textures.len() as u32 - 1)
    }

    /// Declares a storage buffer that lives only within this frame.
    pub fn create_buffer(&mut self, name: impl Into<String>, size: u64) -> BufferHandle {
        self.buffers.push(VirtualBuffer { name: name.into(), origin: BufferOrigin::Transient { size } });
        BufferHandle(self.buffers.len() as u32 - 1)
    }

    /// Brings a node-owned buffer into the graph. Passes that write it are never culled.
    pub fn import_buffer(&mut self, name: impl Into<String>, buffer: &wgpu::Buffer, id: u64) -> BufferHandle {
        self.buffers.push(VirtualBuffer { name: name.into(), origin: BufferOrigin::Imported(buffer.clone(), id) });
        BufferHandle(self.buffers.len() as u32 - 1)
    }

    /// Marks the texture the frame presents; passes that do not contribute to it are culled.
    pub fn set_output(&mut self, texture: TextureHandle) {
        if self.simulation_only {
            return;
        }
        self.output = Some(texture);
    }

    /// Marks one more texture the frame shows (another window): it and the passes it needs
    /// are kept, and it comes back in [`super::FrameOutput::extras`], in the order added.
    pub fn add_extra_output(&mut self, texture: TextureHandle) {
        if !self.simulation_only {
            self.extra_outputs.push(texture);
        }
    }

    /// The texture set as output, if any.
    pub fn output(&self) -> Option<TextureHandle> {
        self.output
    }

    /// Extra output `n` (from 0, in the order added), if any.
    pub fn extra_output(&self, n: usize) -> Option<TextureHandle> {
        self.extra_outputs.get(n).copied()
    }

    /// Starts declaring a pass named `name` (use `<technique>/<pass>`; it labels timings too).
    pub fn add_pass(&mut self, name: impl Into<String>) -> PassBuilder<'_, 'r> {
        PassBuilder {
            graph: self,
            decl: PassDecl { name: name.into(), accesses: Vec::new(), side_effect: false, record: None },
        }
    }

    /// The resolved size of a texture declared in this graph.
    pub fn texture_size(&self, texture: TextureHandle) -> (u32, u32) {
        match &self.textures[texture.0 as usize].origin {
            TextureOrigin::Transient(desc) => desc.extent.resolve(self.output_size),
            TextureOrigin::Imported(t, _, _) => (t.width(), t.height()),
        }
    }

    /// The format of a texture declared in this graph.
    pub fn texture_format(&self, texture: TextureHandle) -> wgpu::TextureFormat {
        match &self.textures[texture.0 as usize].origin {
            TextureOrigin::Transient(desc) => desc.format,
            TextureOrigin::Imported(t, _, _) => t.format(),
        }
    }
}

/// Declares one pass's accesses, then its recording closure.
pub struct PassBuilder<'g, 'r> {
    graph: &'g mut FrameGraph<'r>,
    decl: PassDecl<'r>,
}

impl<'r> PassBuilder<'_, 'r> {
    /// The pass samples or loads `texture`.
    pub fn read(mut self, texture: TextureHandle) -> Self {
        self.decl.accesses.push((Resource::Texture(texture.0), Access::Read));
        self
    }

    /// The pass writes `texture` as a storage texture.
    pub fn write(mut self, texture: TextureHandle) -> Self {
        self.decl.accesses.push((Resource::Texture(texture.0), Access::Write));
        self
    }

    /// The pass renders into `texture` as a colour attachment.
    pub fn render_target(mut self, texture: TextureHandle) -> Self {
        self.decl.accesses.push((Resource::Texture(texture.0), Access::RenderTarget));
        self
    }

    /// The pass draws into `targets` (each of them a render target).
    pub fn draws_into(mut self, targets: &RasterTargets) -> Self {
        for t in [Some(targets.color), targets.msaa, targets.depth].into_iter().flatten() {
            self = self.render_target(t);
        }
        self
    }

    /// The pass reads `buffer` (storage or uniform).
    pub fn read_buffer(mut self, buffer: BufferHandle) -> Self {
        self.decl.accesses.push((Resource::Buffer(buffer.0), Access::Read));
        self
    }

    /// The pass writes `buffer` as storage.
    pub fn write_buffer(mut self, buffer: BufferHandle) -> Self {
        self.decl.accesses.push((Resource::Buffer(buffer.0), Access::Write));
        self
    }

    /// Keeps the pass even if nothing it writes reaches the output (e.g. it writes a readback).
    pub fn side_effect(mut self) -> Self {
        self.decl.side_effect = true;
        self
    }

    /// Finishes the declaration with the closure that records its GPU work.
    pub fn record(mut self, record: impl FnOnce(&mut PassContext<'_>) + 'r) {
        self.decl.record = Some(Box::new(record));
        self.graph.passes.push(self.decl);
    }
}

/// The attachments of a rasterising pass (see [`FrameGraph::create_raster_targets`]).
#[derive(Clone, Copy, Debug)]
pub struct RasterTargets {
    /// The single-sample image downstream nodes read.
    pub color: TextureHandle,
    /// The multisampled colour target resolved into `color` (none at one sample).
    pub msaa: Option<TextureHandle>,
    /// The depth buffer, if any.
    pub depth: Option<TextureHandle>,
}

/// A resolved texture as a pass sees it.
#[derive(Clone)]
pub(crate) struct ResolvedTexture {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    pub id: u64,
}

/// What a pass's closure gets: the encoder and its declared resources, resolved.
pub struct PassContext<'a> {
    /// The device (for bind groups; pipelines are made ahead of time).
    pub device: &'a wgpu::Device,
    /// The queue (for uniform uploads).
    pub queue: &'a wgpu::Queue,
    /// The frame's one command encoder.
    pub encoder: &'a mut wgpu::CommandEncoder,
    pub(crate) textures: &'a [Option<ResolvedTexture>],
    pub(crate) buffers: &'a [Option<(wgpu::Buffer, u64)>],
    pub(crate) pass_name: &'a str,
}

impl PassContext<'_> {
    fn resolved(&self, texture: TextureHandle) -> &ResolvedTexture {
        self.textures[texture.0 as usize]
            .as_ref()
            .unwrap_or_else(|| panic!("pass '{}' used a texture it did not declare", self.pass_name))
    }

    /// The view of a declared texture.
    pub fn view(&self, texture: TextureHandle) -> &wgpu::TextureView {
        &self.resolved(texture).view
    }

    /// The GPU texture behind a declared handle.
    pub fn texture(&self, texture: TextureHandle) -> &wgpu::Texture {
        &self.resolved(texture).texture
    }

    /// A stable id of the physical texture, for caching bind groups.
    pub fn texture_id(&self, texture: TextureHandle) -> u64 {
        self.resolved(texture).id
    }

    /// A declared buffer.
    pub fn buffer(&self, buffer: BufferHandle) -> &wgpu::Buffer {
        &self.buffers[buffer.0 as usize]
            .as_ref()
            .unwrap_or_else(|| panic!("pass '{}' used a buffer it did not declare", self.pass_name))
            .0
    }

    /// A stable id of the physical buffer, for caching bind groups.
    pub fn buffer_id(&self, buffer: BufferHandle) -> u64 {
        self.buffers[buffer.0 as usize].as_ref().map(|b| b.1).unwrap_or(0)
    }

    /// A declared buffer (a shared handle, so the context is free for the encoder) and its id:
    /// a buffer the graph lends may differ from frame to frame.
    pub fn buffer_and_id(&self, buffer: BufferHandle) -> (wgpu::Buffer, u64) {
        (self.buffer(buffer).clone(), self.buffer_id(buffer))
    }

    /// Begins a render pass into `targets` that clears to `clear` and ends resolved into the image.
    pub fn begin_draw(&mut self, targets: &RasterTargets, clear: wgpu::Color) -> wgpu::RenderPass<'_> {
        self.begin_resolved_pass(targets.color, targets.msaa, targets.depth, clear)
    }

    /// Begins a render pass that clears `color` (and a depth buffer to 1.0, discarded after the
    /// pass): the usual start of a rasterising technique.
    pub fn begin_color_depth_pass(
        &mut self,
        color: TextureHandle,
        depth: TextureHandle,
        clear: wgpu::Color,
    ) -> wgpu::RenderPass<'_> {
        self.begin_resolved_pass(color, None, Some(depth), clear)
    }

    /// Begins a render pass that clears `color`, without depth.
    pub fn begin_color_pass(&mut self, color: TextureHandle, clear: wgpu::Color) -> wgpu::RenderPass<'_> {
        self.begin_resolved_pass(color, None, None, clear)
    }

    /// Begins a render pass that clears `msaa` (a multisampled target, if given) and resolves it
    /// into `color` at the end — or clears and draws `color` directly — with an optional depth
    /// buffer (of the same sample count) cleared to 1.0 and discarded after the pass.
    pub fn begin_resolved_pass(
        &mut self,
        color: TextureHandle,
        msaa: Option<TextureHandle>,
        depth: Option<TextureHandle>,
        clear: wgpu::Color,
    ) -> wgpu::RenderPass<'_> {
        let color_view = self.view(color).clone();
        let msaa_view = msaa.map(|m| self.view(m).clone());
        let depth_view = depth.map(|d| self.view(d).clone());
        resolved_pass(self.encoder, self.pass_name, &color_view, msaa_view.as_ref(), depth_view.as_ref(), clear)
    }

    /// This pass's name, for labels.
    pub fn name(&self) -> &str {
        self.pass_name
    }
}

/// Begins a render pass that clears `msaa` (if given) and resolves it into `output` at the end —
/// or clears and draws `output` directly — with an optional depth attachment (of the same sample
/// count) cleared to 1.0 and discarded after the pass.
fn resolved_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    output: &wgpu::TextureView,
    msaa: Option<&wgpu::TextureView>,
    depth: Option<&wgpu::TextureView>,
    clear: wgpu::Color,
) -> wgpu::RenderPass<'e> {
    let (view, resolve_target) = match msaa {
        Some(samples) => (samples, Some(output)),
        None => (output, None),
    };
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(clear),
                store: if resolve_target.is_some() { wgpu::StoreOp::Discard } else { wgpu::StoreOp::Store },
            },
        })],
        depth_stencil_attachment: depth.map(|view| wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
            stencil_ops: None,
        }),
        ..Default::default()
    })
}
