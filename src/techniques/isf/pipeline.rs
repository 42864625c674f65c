//! The GPU side of a compiled ISF shader: one bind group layout and pipeline per target format
//! — a compute pipeline writing a storage image where the shader has a compute variant, else a
//! render pipeline drawing the quad.

use std::collections::BTreeMap;

use super::compile::Compiled;
use super::program::{FIRST_TEXTURE_BINDING, SAMPLER_BINDING, UNIFORM_BINDING, storage_binding};
use super::targets::{BYTE_FORMAT, FLOAT_FORMAT};
use crate::gpu::ShaderError;

/// The node's image: linear HDR like every node's.
pub const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The pipelines of one compiled shader.
pub struct Pipelines {
    /// Target format → its bind group layout and pipeline.
    pub by_format: BTreeMap<FormatKey, (wgpu::BindGroupLayout, Pipeline)>,
    pub sampler: wgpu::Sampler,
}

/// How a pass runs: as a compute shader writing a storage image where the shader allows it, or
/// rasterised (a `.vs`, varyings, derivatives).
pub enum Pipeline {
    Compute(wgpu::ComputePipeline),
    Raster(wgpu::RenderPipeline),
}

/// `wgpu::TextureFormat` is not `Ord`: formats by the two this node renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum FormatKey {
    Byte,
    Float,
}

impl FormatKey {
    pub fn of(format: wgpu::TextureFormat) -> Self {
        if format == BYTE_FORMAT { FormatKey::Byte } else { FormatKey::Float }
    }
}

pub fn build_pipelines(device: &wgpu::Device, origin: &str, compiled: &Compiled) -> Result<Pipelines, ShaderError> {
    let compute = compiled.compute.is_some();
    let visibility = if compute { wgpu::ShaderStages::COMPUTE } else { wgpu::ShaderStages::VERTEX_FRAGMENT };
    let mut entries = vec![
        wgpu::BindGroupLayoutEntry {
            binding: UNIFORM_BINDING,
            visibility,
            ty: crate::gpu::block_binding(false, wgpu::BufferSize::new(u64::from(compiled.program.uniforms.size))),
            count: None,
        },
        wgpu::BindGroupLayoutEntry {
            binding: SAMPLER_BINDING,
            visibility,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            count: None,
        },
    ];
    let textures = compiled.program.textures.len();
    entries.extend((0..textures).map(|i| crate::gpu::texture_entry(FIRST_TEXTURE_BINDING + i as u32, visibility)));
    let module = |m: &naga::Module, label: &str| {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(crate::gpu::with_blocks_bound(m.clone()))),
        })
    };
    let by_format = crate::gpu::validated(device, origin, || {
        let mut by_format = BTreeMap::new();
        for (k, format) in [BYTE_FORMAT, FLOAT_FORMAT].into_iter().enumerate() {
            let mut entries = entries.clone();
            if compute {
                entries.push(wgpu::BindGroupLayoutEntry {
                    binding: storage_binding(textures),
                    visibility,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    count: None,
                });
            }
            let layout = device
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("isf"), entries: &entries });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("isf"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = match &compiled.compute {
                Some(variants) => Pipeline::Compute(device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(origin),
                    layout: Some(&pipeline_layout),
                    module: &module(&variants[k], "isf.compute"),
                    entry_point: Some("main"),
                    compilation_options: Default::default(),
                    cache: None,
                })),
                None => Pipeline::Raster(device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(origin),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module(&compiled.vertex, "isf.vs"),
                        entry_point: Some("main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module(&compiled.fragment, "isf.fs"),
                        entry_point: Some("main"),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format,
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: None,
                    multisample: wgpu::MultisampleState::default(),
                    multiview_mask: None,
                    cache: None,
                })),
            };
            by_format.insert(FormatKey::of(format), (layout, pipeline));
        }
        by_format
    })?;
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("isf_sampler"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    Ok(Pipelines { by_format, sampler })
}
