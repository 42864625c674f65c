//! Colour and depth attachments a node draws into at 1–8 samples per pixel, resolved into the
//! single-sample texture the frame graph hands downstream — so post effects and readback never
//! see a multisampled image, and thin geometry does not shimmer.

/// A node's own draw attachments for one output size and sample count.
pub struct DrawTargets {
    label: &'static str,
    color_format: wgpu::TextureFormat,
    depth_format: Option<wgpu::TextureFormat>,
    size: (u32, u32),
    samples: u32,
    /// The multisampled colour attachment (none at one sample: the output is drawn directly).
    color: Option<wgpu::TextureView>,
    depth: Option<wgpu::TextureView>,
}

impl DrawTargets {
    /// Targets of `color_format` (and `depth_format`, if any); made by the first [`Self::ensure`].
    pub fn new(
        label: &'static str,
        color_format: wgpu::TextureFormat,
        depth_format: Option<wgpu::TextureFormat>,
    ) -> Self {
        Self { label, color_format, depth_format, size: (0, 0), samples: 0, color: None, depth: None }
    }

    /// (Re)creates the attachments if the size or sample count changed.
    pub fn ensure(&mut self, device: &wgpu::Device, size: (u32, u32), samples: u32) {
        if self.size == size && self.samples == samples {
            return;
        }
        let make = |format| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(self.label),
                    size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: samples,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        self.color = (samples > 1).then(|| make(self.color_format));
        self.depth = self.depth_format.map(make);
        (self.size, self.samples) = (size, samples);
    }

    /// The size of the current attachments.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Samples per pixel of the current attachments.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Begins a pass that clears to `clear` and ends resolved (or drawn directly) into `output`.
    pub fn begin_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        output: &wgpu::TextureView,
        clear: wgpu::Color,
    ) -> wgpu::RenderPass<'e> {
        begin_resolved_pass(encoder, self.label, output, self.color.as_ref(), self.depth.as_ref(), clear)
    }
}

/// Begins a render pass that clears `msaa` (if given) and resolves it into `output` at the end —
/// or clears and draws `output` directly — with an optional depth attachment (of the same sample
/// count) cleared to 1.0 and discarded after the pass.
pub fn begin_resolved_pass<'e>(
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
