//! The cloth's GPU state at one resolution: three particle buffers that rotate through the roles
//! previous / current / next (so no step copies), normals, the NaN flag, and the plan of one
//! frame's dispatches with their bind groups made ahead of time.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};

use super::ClothUniforms;
use crate::checkpoint::{CheckpointError, NodeState};
use crate::gpu::{BindGroupCache, Gpu};
use crate::graph::{BufferHandle, FrameGraph};
use crate::techniques::saved::{load_buffer, save_buffer};

/// (uniform slot, previous, current, next): which buffers a simulation dispatch binds.
pub type Key = (usize, usize, usize, usize);

/// Which simulation kernel a dispatch runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// One explicit Verlet substep.
    Verlet,
    /// One XPBD small step (prediction and one Jacobi projection).
    Xpbd,
}

/// One dispatch of a frame's simulation.
#[derive(Clone, Copy, Debug)]
pub struct Dispatch {
    /// The kernel.
    pub kernel: Kernel,
    /// Its bind group.
    pub key: Key,
}

/// Watches the NaN flag without stalling: copy after a frame's simulation, map during a later
/// step, read when mapped.
pub struct NanWatch {
    stage: AtomicU8,
    ready: Arc<AtomicBool>,
}

const IDLE: u8 = 0;
const COPIED: u8 = 1;
const MAPPING: u8 = 2;

impl NanWatch {
    fn new() -> Self {
        Self { stage: AtomicU8::new(IDLE), ready: Arc::new(AtomicBool::new(false)) }
    }

    /// Records the copy of the flag, unless a read is still under way.
    pub fn after_check(&self, encoder: &mut wgpu::CommandEncoder, status: &wgpu::Buffer, readback: &wgpu::Buffer) {
        if self.stage.load(Ordering::Acquire) == IDLE {
            encoder.copy_buffer_to_buffer(status, 0, readback, 0, 4);
            self.stage.store(COPIED, Ordering::Release);
        }
    }

    /// Advances the read; true when a finished read found the flag set.
    pub fn poll(&self, readback: &wgpu::Buffer) -> bool {
        match self.stage.load(Ordering::Acquire) {
            COPIED => {
                let ready = self.ready.clone();
                readback.slice(..).map_async(wgpu::MapMode::Read, move |r| ready.store(r.is_ok(), Ordering::Release));
                self.stage.store(MAPPING, Ordering::Release);
                false
            }
            MAPPING if self.ready.load(Ordering::Acquire) => {
                let flagged = readback.slice(..).get_mapped_range().map(|v| v.iter().any(|&b| b != 0)).unwrap_or(false);
                readback.unmap();
                self.ready.store(false, Ordering::Release);
                self.stage.store(IDLE, Ordering::Release);
                flagged
            }
            _ => false,
        }
    }
}

/// Buffers and bookkeeping for one resolution and pin mode.
pub struct State {
    /// Particles per side.
    pub res: u32,
    /// Pin mode index.
    pub pin: u32,
    particles: [wgpu::Buffer; 3],
    ids: [u64; 3],
    /// Index of the previous-positions buffer.
    pub prev: usize,
    /// Index of the current-positions buffer.
    pub cur: usize,
    /// Vertex normals.
    pub normals: wgpu::Buffer,
    /// Its graph id.
    pub normals_id: u64,
    /// The NaN flag.
    pub status: wgpu::Buffer,
    /// Where the flag is read back.
    pub status_readback: wgpu::Buffer,
    /// Simulation bind groups by key.
    pub bind_groups: BindGroupCache<Key>,
    /// The NaN watch.
    pub nan: NanWatch,
    /// Surface triangle indices (particle numbers).
    pub surface_indices: wgpu::Buffer,
    /// Number of surface indices.
    pub surface_count: u32,
    /// Spring line indices and the ranges of the three kinds (made on first debug draw).
    pub lines: Option<(wgpu::Buffer, [std::ops::Range<u32>; 3])>,
    /// Draw bind groups by current-buffer index.
    pub draw_groups: BindGroupCache<usize>,
}

fn storage(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

impl State {
    /// Triangles of the compute draw: the surface's, then the sphere's 32 × 16 × 2 if drawn.
    pub fn triangles(&self, sphere: bool) -> u32 {
        self.surface_count / 3 + if sphere { 32 * 16 * 2 } else { 0 }
    }

    /// Buffers for `res` × `res` particles, drawn as the triangles of `surface` (the renderer's
    /// index buffer and its count).
    pub fn new(device: &wgpu::Device, res: u32, pin: u32, surface: (wgpu::Buffer, u32)) -> Self {
        let bytes = u64::from(res * res) * 16;
        let particles = std::array::from_fn(|i| storage(device, &format!("cloth_particles_{i}"), bytes));
        let status = storage(device, "cloth_status", 4);
        let status_readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cloth_status_readback"),
            size: 4,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let (surface_indices, surface_count) = surface;
        Self {
            res,
            pin,
            particles,
            ids: std::array::from_fn(|_| crate::graph::next_resource_id()),
            prev: 0,
            cur: 1,
            normals: storage(device, "cloth_normals", bytes),
            normals_id: crate::graph::next_resource_id(),
            status,
            status_readback,
            bind_groups: BindGroupCache::default(),
            nan: NanWatch::new(),
            surface_indices,
            surface_count,
            lines: None,
            draw_groups: BindGroupCache::default(),
        }
    }

    /// The particle buffers.
    pub fn particles(&self) -> &[wgpu::Buffer; 3] {
        &self.particles
    }

    /// Puts every particle at `pose` with zero velocity and clears the NaN flag.
    pub fn reset(&mut self, queue: &wgpu::Queue, pose: &[[f32; 4]]) {
        for i in [self.prev, self.cur] {
            queue.write_buffer(&self.particles[i], 0, bytemuck::cast_slice(pose));
        }
        // The rest pose is flat, facing +z: the normals the first step's wind pushes along.
        let flat: Vec<[f32; 4]> = vec![[0.0, 0.0, 1.0, 0.0]; pose.len()];
        queue.write_buffer(&self.normals, 0, bytemuck::cast_slice(&flat));
        queue.write_buffer(&self.status, 0, &[0; 4]);
    }

    /// Saves the particles (all three buffers and their roles), the normals and the NaN flag.
    pub fn save(&self, gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
        state.put_pod("roles", &[self.prev as u32, self.cur as u32]);
        for (i, buffer) in self.particles.iter().enumerate() {
            save_buffer(gpu, state, &format!("particles{i}"), buffer)?;
        }
        save_buffer(gpu, state, "normals", &self.normals)?;
        save_buffer(gpu, state, "status", &self.status)
    }

    /// Puts back what [`State::save`] wrote, into buffers of the same resolution.
    pub fn load(&mut self, gpu: &Gpu, state: &NodeState) -> Result<(), CheckpointError> {
        let roles = state.get_pod::<u32>("roles")?;
        match roles[..] {
            [prev, cur] if prev != cur && prev < 3 && cur < 3 => (self.prev, self.cur) = (prev as usize, cur as usize),
            _ => return Err(state.error("roles", format!("{roles:?} are not two of the three buffers"))),
        }
        for (i, buffer) in self.particles.iter().enumerate() {
            load_buffer(gpu, state, &format!("particles{i}"), buffer)?;
        }
        load_buffer(gpu, state, "normals", &self.normals)?;
        load_buffer(gpu, state, "status", &self.status)
    }

    /// The lowest buffer index not among `used`.
    fn free(used: &[usize]) -> usize {
        (0..3).find(|i| !used.contains(i)).expect("three buffers, at most two in use")
    }

    /// Plans one frame: `substeps` substeps for each queued step, rotating buffer roles, with
    /// every bind group created now. Leaves `prev`/`cur` as they will be after the frame.
    pub fn plan(
        &mut self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        uniforms: &[wgpu::Buffer],
        steps: &[ClothUniforms],
        substeps: u32,
    ) -> Vec<Dispatch> {
        self.bind_groups.begin_frame();
        self.draw_groups.begin_frame();
        let mut out = Vec::new();
        for (slot, u) in steps.iter().enumerate() {
            for _ in 0..substeps {
                let kernel = if u.solver == 0 { Kernel::Verlet } else { Kernel::Xpbd };
                let next = Self::free(&[self.prev, self.cur]);
                out.push(Dispatch { kernel, key: (slot, self.prev, self.cur, next) });
                (self.prev, self.cur) = (self.cur, next);
            }
        }
        let keys: Vec<Key> = out.iter().map(|d| d.key).chain([self.normals_key()]).collect();
        for key in keys {
            self.bind_group(device, layout, uniforms, key);
        }
        out
    }

    /// The key the normals pass binds (current positions; the other roles are placeholders).
    pub fn normals_key(&self) -> Key {
        (0, self.prev, self.cur, Self::free(&[self.prev, self.cur]))
    }

    fn bind_group(
        &mut self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        uniforms: &[wgpu::Buffer],
        key: Key,
    ) {
        let (slot, prev, cur, next) = key;
        let particles = &self.particles;
        let (status, normals) = (&self.status, &self.normals);
        self.bind_groups.get_or_create(key, || {
            let entries: Vec<wgpu::BindGroupEntry> = [
                uniforms[slot].as_entire_binding(),
                particles[prev].as_entire_binding(),
                particles[cur].as_entire_binding(),
                particles[next].as_entire_binding(),
                status.as_entire_binding(),
                normals.as_entire_binding(),
            ]
            .into_iter()
            .enumerate()
            .map(|(binding, resource)| wgpu::BindGroupEntry { binding: binding as u32, resource })
            .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("cloth_sim_bind_group"),
                layout,
                entries: &entries,
            })
        });
    }

    /// Imports the particle buffers into this frame's graph.
    pub fn import(&self, graph: &mut FrameGraph<'_>) -> [BufferHandle; 3] {
        std::array::from_fn(|i| graph.import_buffer(format!("cloth/particles{i}"), &self.particles[i], self.ids[i]))
    }

    /// Copies the current positions to the CPU (blocking).
    pub fn read_positions(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Vec<[f32; 4]> {
        self.read(device, queue, self.cur)
    }

    /// Copies the previous positions to the CPU (blocking).
    pub fn read_previous(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Vec<[f32; 4]> {
        self.read(device, queue, self.prev)
    }

    /// Copies the normals to the CPU (blocking).
    pub fn read_normals(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Vec<[f32; 4]> {
        Self::read_all(device, queue, &self.normals, self.res)
    }

    fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue, which: usize) -> Vec<[f32; 4]> {
        Self::read_all(device, queue, &self.particles[which], self.res)
    }

    fn read_all(device: &wgpu::Device, queue: &wgpu::Queue, buffer: &wgpu::Buffer, res: u32) -> Vec<[f32; 4]> {
        let size = u64::from(res * res) * 16;
        crate::gpu::read_buffer(device, queue, buffer, 0, size)
            .map(|bytes| bytemuck::cast_slice(&bytes).to_vec())
            .unwrap_or_default()
    }
}
