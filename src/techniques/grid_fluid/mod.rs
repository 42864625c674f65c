//! A 2-D grid fluid (stable fluids, Stam 1999) stirred by a cursor: the displacement source of
//! chapter 6, whose output texture any node can read (the tessellated surface takes it as its
//! height). The cursor and the `drag` gate are ordinary parameters, so the window's mouse, a
//! TouchOSC XY pad, MIDI, presets and recordings stir it the same way.
//!
//! Per fixed step, as the book's sample orders it: velocity (add the cursor's splat, diffuse,
//! project, self-advect, project), then density (add, diffuse, advect, dissipate). Diffusion and
//! pressure are Jacobi iterations between two slots; the walls are a closed, no-slip box.
//! Fixes of the sample's solver (seed-reference §9 item 22) are listed in the shader.
//!
//! Units: the box is N cells wide; velocities are in cells per second; `viscosity` and `diffusion`
//! keep the sample's numbers (100, 10) in units of 1e-5 box² per second, so that a = dt·ν·N²·1e-5
//! (the sample's a = dt·ν·N² made diffusion pure neighbour averaging).
//!
//! Book: [UGP4 ch.6] (sakota), the displacement source; [UGP1] grid fluid. Shader:
//! `grid_fluid.wgsl`.

mod plan;

pub use plan::{Field, FluidDispatch, Kernel, Planned, step_dispatches};

use std::cell::RefCell;

use crate::checkpoint::{CheckpointError, NodeState};
use crate::gpu::{BindGroupCache, ComputeKernel, Gpu, ShaderError};
use crate::graph::{Extent, FrameGraph, TextureDesc, TextureHandle};
use crate::params::{InputRole, ParamDecl, ParamSet, ParamValue};
use crate::time::FrameTime;

use super::saved::{load_buffer, save_buffer};
use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "grid_fluid",
    chapter: "6: Tessellation & Displacement (displacement source)",
    summary: "a 2-D stable-fluids grid stirred by a cursor; its density is a height map",
    params: Settings::decls,
    inputs: &[],
    shaders: &["grid_fluid.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

/// The output format (density in R, G and B).
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

crate::technique_params! {
    /// What a grid fluid reads each step.
    pub struct Settings {
        /// grid cells per side (restarts the fluid)
        resolution: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(256), Some((16.0, 1024.0)), doc),
        /// where the fluid is stirred: box position, y up
        cursor: [f32; 2] = |n, doc| {
            ParamDecl::new(n, ParamValue::Vec2([0.5, 0.5]), Some((0.0, 1.0)), doc).with_role(InputRole::Pointer)
        },
        /// stir while true (the left mouse button in the window)
        drag: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(false), None, doc).with_role(InputRole::Drag),
        /// velocity diffusion, 1e-5 box²/s
        viscosity: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(100.0), Some((0.0, 5000.0)), doc),
        /// density diffusion, 1e-5 box²/s
        diffusion: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(10.0), Some((0.0, 5000.0)), doc),
        /// how strongly cursor motion pushes the fluid
        velocity_coef: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(4.0), Some((0.0, 50.0)), doc),
        /// density added per second under the cursor
        density_coef: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(6.0), Some((0.0, 100.0)), doc),
        /// source radius, box units
        radius: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.072), Some((0.005, 0.5)), doc),
        /// Jacobi sweeps of the diffusion solves
        sweeps: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(2), Some((1.0, 64.0)), doc),
        /// Jacobi iterations of the pressure solve
        pressure_iterations: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(40), Some((1.0, 400.0)), doc),
        /// density lost per second (0: none)
        dissipation: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.1), Some((0.0, 10.0)), doc),
        /// clear the fluid (R in the window)
        reset: bool = |n, doc| ParamDecl::trigger(n, doc).with_role(InputRole::Key('r')),
    }
}

/// The kernels (one pipeline per entry point) and their two layouts.
struct Kernels {
    by_kind: Vec<ComputeKernel>,
    /// Dispatch uniforms + fields.
    simulate: wgpu::BindGroupLayout,
    /// The same + the output image.
    image: wgpu::BindGroupLayout,
}

/// A grid fluid node.
pub struct GridFluid {
    device: wgpu::Device,
    queue: wgpu::Queue,
    kernels: Kernels,
    /// All fields, N² floats each (see [`Field`]); imported into the graph each frame.
    fields: (wgpu::Buffer, u64, u32),
    /// One 256-byte uniform block per dispatch of the frame, bound at a dynamic offset.
    uniforms: wgpu::Buffer,
    /// Bind groups by (fields id, output texture id or 0, uniform buffer size).
    bind_groups: RefCell<BindGroupCache<(u64, u64, u64)>>,
    /// Dispatches queued by `step`, recorded by the next `add_passes`.
    pending: Vec<Planned>,
    /// The cursor at the previous step, while dragging (its motion is the velocity impulse).
    last_cursor: Option<[f32; 2]>,
}

/// Bytes between uniform blocks (wgpu's minimum uniform offset alignment).
const BLOCK: u64 = 256;

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(GridFluid::new(setup)?))
}

impl GridFluid {
    /// Builds the pipelines and zeroed fields at the resolution asked for.
    pub fn new(setup: &NodeSetup<'_>) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let uniform = wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: crate::gpu::block_binding(true, wgpu::BufferSize::new(size_of::<FluidDispatch>() as u64)),
            count: None,
        };
        let fields = crate::gpu::storage_entry(1, wgpu::ShaderStages::COMPUTE, false);
        let output = wgpu::BindGroupLayoutEntry {
            binding: 2,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: FORMAT,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
            count: None,
        };
        // The simulation kernels never touch the image: they bind no texture, so a simulation-only
        // frame (a seek) needs none.
        let simulate = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("grid_fluid_simulate_layout"),
            entries: &[uniform, fields],
        });
        let image = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("grid_fluid_output_layout"),
            entries: &[uniform, fields, output],
        });
        let (origin, source) = setup.shader_source("grid_fluid.wgsl", &[("d", 0), ("fields", 1), ("output", 2)])?;
        let by_kind = Kernel::ALL
            .iter()
            .map(|k| {
                let layout = if *k == Kernel::WriteOutput { &image } else { &simulate };
                ComputeKernel::new(device, &origin, &source, k.entry(), &[layout])
            })
            .collect::<Result<_, _>>()?;
        let n = Settings::read(setup.params).resolution.clamp(16, 1024) as u32;
        Ok(Self {
            device: device.clone(),
            queue: setup.gpu.queue.clone(),
            kernels: Kernels { by_kind, simulate, image },
            fields: zeroed_fields(device, n),
            uniforms: uniform_blocks(device, 512),
            bind_groups: RefCell::default(),
            pending: Vec::new(),
            last_cursor: None,
        })
    }

    /// The grid side the fields were made for.
    pub fn resolution(&self) -> u32 {
        self.fields.2
    }

    /// Reads one field back (N² floats, row 0 at the bottom; blocking, for tests and tools).
    pub fn read_field(&self, field: Field) -> Vec<f32> {
        let (buffer, _, n) = &self.fields;
        let bytes = u64::from(*n) * u64::from(*n) * 4;
        crate::gpu::read_buffer(&self.device, &self.queue, buffer, field as u64 * bytes, bytes)
            .map(|b| bytemuck::cast_slice(&b).to_vec())
            .unwrap_or_default()
    }

    /// Writes one field (N² floats; for tests that start from a known state).
    pub fn write_field(&self, field: Field, values: &[f32]) {
        let (buffer, _, n) = &self.fields;
        let bytes = u64::from(*n) * u64::from(*n) * 4;
        self.queue.write_buffer(buffer, field as u64 * bytes, bytemuck::cast_slice(values));
    }

    /// (Re)creates zeroed fields if the resolution changed or a reset was asked for.
    fn ensure_fields(&mut self, settings: &Settings) {
        let n = settings.resolution.clamp(16, 1024) as u32;
        if self.resolution() == n && !settings.reset {
            return;
        }
        self.fields = zeroed_fields(&self.device, n);
        self.pending.clear();
        self.last_cursor = None;
    }
}

/// Zeroed fields for an `n`² grid, with their graph resource id.
fn zeroed_fields(device: &wgpu::Device, n: u32) -> (wgpu::Buffer, u64, u32) {
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("grid_fluid_fields"),
        size: u64::from(n) * u64::from(n) * 4 * Field::COUNT as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    (buffer, crate::graph::next_resource_id(), n)
}

/// A uniform buffer of `blocks` dispatch blocks.
fn uniform_blocks(device: &wgpu::Device, blocks: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("grid_fluid_dispatches"),
        size: blocks * BLOCK,
        usage: crate::gpu::BLOCK_USAGE,
        mapped_at_creation: false,
    })
}

impl Technique for GridFluid {
    fn simulates_on_gpu(&self) -> bool {
        true
    }

    fn save_state(&self, gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
        // The cursor of the last step: a drag that goes on past the checkpoint moves from it.
        state.put_option("last_cursor", self.last_cursor);
        save_buffer(gpu, state, "fields", &self.fields.0)
    }

    fn load_state(
        &mut self,
        gpu: &Gpu,
        params: &ParamSet,
        _time: &FrameTime,
        state: &NodeState,
    ) -> Result<(), CheckpointError> {
        self.ensure_fields(&Settings::read(params));
        let cursor = state.get_option::<[f32; 2]>("last_cursor")?;
        self.last_cursor = cursor.filter(|c| c.iter().all(|v| v.is_finite()));
        load_buffer(gpu, state, "fields", &self.fields.0)
    }

    fn step(&mut self, params: &ParamSet, time: &FrameTime) {
        let settings = Settings::read(params);
        self.ensure_fields(&settings);
        let n = self.resolution();
        let cursor = settings.cursor;
        let dragging = settings.drag;
        // The cursor's motion since the last step, only while dragging (a press does not jump).
        let motion = match (dragging, self.last_cursor) {
            (true, Some(last)) => [cursor[0] - last[0], cursor[1] - last[1]],
            _ => [0.0, 0.0],
        };
        self.last_cursor = dragging.then_some(cursor);
        self.pending.extend(step_dispatches(n, &settings, time.dt, dragging.then_some((cursor, motion))));
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        _time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        self.ensure_fields(&Settings::read(params));
        let n = self.resolution();
        let mut dispatches = std::mem::take(&mut self.pending);
        dispatches.push(FluidDispatch::output(n));
        let blocks = dispatches.len() as u64;
        if self.uniforms.size() < blocks * BLOCK {
            self.uniforms = uniform_blocks(&self.device, blocks.next_power_of_two());
        }
        let mut bytes = vec![0u8; (blocks * BLOCK) as usize];
        for (i, d) in dispatches.iter().enumerate() {
            let at = i * BLOCK as usize;
            bytes[at..at + size_of::<FluidDispatch>()].copy_from_slice(bytemuck::bytes_of(&d.1));
        }
        self.queue.write_buffer(&self.uniforms, 0, &bytes);
        self.bind_groups.get_mut().begin_frame();

        let this: &'r GridFluid = self;
        let (buffer, buffer_id, _) = &this.fields;
        let fields = graph.import_buffer("grid_fluid/fields", buffer, *buffer_id);
        let output = graph.create_texture(
            "grid_fluid/density",
            TextureDesc { extent: Extent::Absolute(n, n), format: FORMAT, layers: None, samples: 1 },
        );
        let (simulate, last) = dispatches.split_at(dispatches.len() - 1);
        let (simulate, last) = (simulate.to_vec(), last[0]);
        let steps = simulate.len() as u32;
        graph.add_pass("grid_fluid/simulate").write_buffer(fields).record(move |ctx| {
            let group = this.bind_group(ctx, fields, None);
            let mut pass = ctx.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("grid_fluid/simulate"),
                timestamp_writes: None,
            });
            for (i, d) in simulate.iter().enumerate() {
                this.dispatch(&mut pass, &group, i as u32, d.0, n);
            }
        });
        graph.add_pass("grid_fluid/output").read_buffer(fields).write(output).record(move |ctx| {
            let group = this.bind_group(ctx, fields, Some(output));
            let mut pass = ctx.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("grid_fluid/output"),
                timestamp_writes: None,
            });
            this.dispatch(&mut pass, &group, steps, last.0, n);
        });
        output
    }
}

impl GridFluid {
    /// The bind group of the dispatch uniforms and the fields, and of `output` if given.
    fn bind_group(
        &self,
        ctx: &crate::graph::PassContext<'_>,
        fields: crate::graph::BufferHandle,
        output: Option<TextureHandle>,
    ) -> wgpu::BindGroup {
        let key = (ctx.buffer_id(fields), output.map_or(0, |t| ctx.texture_id(t)), self.uniforms.size());
        let mut cache = self.bind_groups.borrow_mut();
        cache
            .get_or_create(key, || {
                let mut entries = vec![
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &self.uniforms,
                            offset: 0,
                            size: wgpu::BufferSize::new(size_of::<FluidDispatch>() as u64),
                        }),
                    },
                    wgpu::BindGroupEntry { binding: 1, resource: ctx.buffer(fields).as_entire_binding() },
                ];
                if let Some(t) = output {
                    entries.push(wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(ctx.view(t)),
                    });
                }
                let layout = if output.is_some() { &self.kernels.image } else { &self.kernels.simulate };
                self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("grid_fluid_bind_group"),
                    layout,
                    entries: &entries,
                })
            })
            .clone()
    }

    fn dispatch(&self, pass: &mut wgpu::ComputePass<'_>, group: &wgpu::BindGroup, block: u32, kernel: Kernel, n: u32) {
        let k = &self.kernels.by_kind[kernel as usize];
        pass.set_pipeline(&k.pipeline);
        pass.set_bind_group(0, group, &[block * BLOCK as u32]);
        let [x, y, z] = k.workgroups([n, n, 1]);
        pass.dispatch_workgroups(x, y, z);
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod render_tests;
