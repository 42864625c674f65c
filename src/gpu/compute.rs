//! A compute pipeline built from validated WGSL, which knows its workgroup size from naga's
//! reflection so that callers dispatch thread counts, never workgroup counts.

use super::shader::{ShaderError, compile_wgsl};

/// A compute pipeline and the `@workgroup_size` of its entry point.
pub struct ComputeKernel {
    /// The pipeline.
    pub pipeline: wgpu::ComputePipeline,
    /// `@workgroup_size` read from the shader.
    pub workgroup_size: [u32; 3],
}

impl ComputeKernel {
    /// Validates `source`, builds the pipeline for `entry` with `layouts`, inside an error scope.
    pub fn new(
        device: &wgpu::Device,
        origin: &str,
        source: &str,
        entry: &str,
        layouts: &[&wgpu::BindGroupLayout],
    ) -> Result<Self, ShaderError> {
        let (shader, module) = compile_wgsl(device, origin, source)?;
        let workgroup_size =
            module.entry_points.iter().find(|e| e.name == entry).map(|e| e.workgroup_size).ok_or_else(|| {
                ShaderError {
                    origin: origin.into(),
                    line: 1,
                    column: 1,
                    message: format!("no compute entry point named '{entry}'"),
                }
            })?;
        let bind_group_layouts: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(|l| Some(*l)).collect();
        let pipeline = super::validated(device, origin, || {
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(origin),
                bind_group_layouts: &bind_group_layouts,
                immediate_size: 0,
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&layout),
                module: &shader,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        })?;
        Ok(Self { pipeline, workgroup_size })
    }

    /// Workgroups to cover `threads` invocations on each axis.
    pub fn workgroups(&self, threads: [u32; 3]) -> [u32; 3] {
        std::array::from_fn(|i| threads[i].div_ceil(self.workgroup_size[i].max(1)))
    }

    /// Records a dispatch covering `threads` with `bind_groups` bound in order.
    pub fn dispatch(&self, pass: &mut wgpu::ComputePass<'_>, bind_groups: &[&wgpu::BindGroup], threads: [u32; 3]) {
        pass.set_pipeline(&self.pipeline);
        for (i, group) in bind_groups.iter().enumerate() {
            pass.set_bind_group(i as u32, *group, &[]);
        }
        let [x, y, z] = self.workgroups(threads);
        pass.dispatch_workgroups(x, y, z);
    }
}
