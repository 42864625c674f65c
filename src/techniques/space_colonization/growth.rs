//! The growth state on the GPU and the dispatches of a growth step (see the shader's header):
//! buffers, bind groups, the grid's cell buffers (resized when the reach changes), and the list
//! of dispatches a frame records — so that `add_passes` only replays it.

use super::cloud::{Attraction, Cloud, Node};
use super::params::{GridLayout, GrowthUniforms, MAX_CELLS, PoseUniforms};
use crate::checkpoint::{CheckpointError, NodeState};
use crate::gpu::{ComputeKernel, Gpu, PrefixSum, ScanTarget, ShaderError, storage_entry, uniform_entry};
use crate::techniques::NodeSetup;
use crate::techniques::saved::{load_buffer, save_buffer};

/// Bytes between uniform blocks (wgpu's minimum uniform offset alignment).
pub const BLOCK: u64 = 256;
/// i32s per node in the direction sums (Σx, Σy, Σz, count, first attraction).
const ACCUM: u64 = 5;
/// Bytes of the indirect arguments: node dispatch (3), draw (4), indexed draw (5), the next
/// step's growth work over nodes, attractions and slots (3 each; zero once the pool is full), and
/// this step's grid rebuild and remove (3 each; zero if the pool was full before it).
const ARGS_BYTES: u64 = 27 * 4;
/// Byte offset of the growth work's node dispatch.
const GROWING_NODES: u64 = 48;
/// Byte offset of the growth work's attraction dispatch.
const GROWING_ATTRACTIONS: u64 = 60;
/// Byte offset of the growth work's slot dispatch.
const GROWING_SLOTS: u64 = 72;
/// Byte offset of the node dispatch of this step's grid rebuild.
const CHANGED_NODES: u64 = 84;
/// Byte offset of the attraction dispatch of this step's remove.
const CHANGED_ATTRACTIONS: u64 = 96;
/// Byte offset of the line draw's arguments.
pub const LINE_ARGS: u64 = 12;
/// Byte offset of the tube draw's (indexed) arguments.
pub const TUBE_ARGS: u64 = 28;

/// The growth kernels and their layouts.
pub struct Kernels {
    clear_accum: ComputeKernel,
    search: ComputeKernel,
    attract: ComputeKernel,
    connect: ComputeKernel,
    finalize: ComputeKernel,
    clear_cells: ComputeKernel,
    count_cells: ComputeKernel,
    take_counts: ComputeKernel,
    scatter: ComputeKernel,
    remove: ComputeKernel,
    grow: ComputeKernel,
    pose: ComputeKernel,
    scan: PrefixSum,
    growth_layout: wgpu::BindGroupLayout,
    args_layout: wgpu::BindGroupLayout,
    pose_layout: wgpu::BindGroupLayout,
}

impl Kernels {
    /// Builds every pipeline from `space_colonization.wgsl` and `prefix_sum.wgsl`.
    pub fn new(setup: &NodeSetup<'_>) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let storage = |binding| storage_entry(binding, compute, false);
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: compute,
            ty: crate::gpu::block_binding(true, wgpu::BufferSize::new(size_of::<GrowthUniforms>() as u64)),
            count: None,
        }];
        entries.extend((1..=9).map(storage));
        let growth_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("space_colonization_growth_layout"),
            entries: &entries,
        });
        let args_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("space_colonization_args_layout"),
            entries: &[storage(4)],
        });
        let pose_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("space_colonization_pose_layout"),
            entries: &[
                uniform_entry::<PoseUniforms>(0, compute),
                storage(1),
                storage_entry(2, compute, true),
                storage_entry(3, compute, true),
            ],
        });
        let bindings = [
            ("g", 0),
            ("attractions", 1),
            ("nodes", 2),
            ("accum", 3),
            ("flags", 4),
            ("candidates", 5),
            ("cell_start", 6),
            ("cell_fill", 7),
            ("sorted", 8),
            ("counters", 9),
        ];
        let (origin, source) = setup.shader_source("space_colonization.wgsl", &bindings)?;
        let kernel = |entry, extra: Option<&wgpu::BindGroupLayout>| {
            let mut layouts = vec![&growth_layout];
            layouts.extend(extra);
            ComputeKernel::new(device, &origin, &source, entry, &layouts)
        };
        let (scan_origin, scan_source) = setup.shader_source("prefix_sum.wgsl", &crate::gpu::SCAN_BINDINGS)?;
        Ok(Self {
            clear_accum: kernel("clear_accum", None)?,
            search: kernel("search", None)?,
            attract: kernel("attract", None)?,
            connect: kernel("connect", None)?,
            finalize: kernel("finalize", Some(&args_layout))?,
            clear_cells: kernel("clear_cells", None)?,
            count_cells: kernel("count_cells", None)?,
            take_counts: kernel("take_counts", None)?,
            scatter: kernel("scatter", None)?,
            remove: kernel("remove", None)?,
            grow: kernel("grow", None)?,
            pose: kernel("pose", Some(&pose_layout))?,
            scan: PrefixSum::new(device, &scan_origin, &scan_source)?,
            growth_layout,
            args_layout,
            pose_layout,
        })
    }
}

/// One dispatch (or dispatch group) of a frame, with the uniform block it reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Op {
    /// Counting sort of the nodes into the grid of `cells` cells.
    BuildGrid { block: u32, cells: u32 },
    /// Search, attract, scan, connect, finalize.
    Branch { block: u32 },
    /// Attractions near nodes die.
    Remove { block: u32 },
    /// t grows.
    Grow { block: u32 },
}

/// Per-node skinning data for the pose kernel (joints and weights of a mesh vertex).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VertexSkin {
    /// Joint indices.
    pub joints: [u32; 4],
    /// Weights (sum 1).
    pub weights: [f32; 4],
}

fn buffer(device: &wgpu::Device, label: &str, bytes: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC | usage,
        mapped_at_creation: false,
    })
}

/// What a skinned source adds: every vertex's skin and the bind-pose mesh (to draw it).
#[derive(Clone, Debug, Default)]
pub struct SkinData {
    /// Joints and weights per mesh vertex (a node's `skin` indexes this).
    pub skins: Vec<VertexSkin>,
    /// Bind-pose positions.
    pub positions: Vec<[f32; 3]>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
}

/// The model's mesh on the GPU, for drawing it.
pub struct MeshBuffers {
    /// Positions as vec4s.
    pub positions: wgpu::Buffer,
    /// Triangle indices.
    pub indices: wgpu::Buffer,
    /// Index count (0: no mesh).
    pub index_count: u32,
}

/// A buffer the frame graph imports, with its resource id.
pub struct Imported {
    /// The buffer.
    pub buffer: wgpu::Buffer,
    /// Its id in the graph.
    pub id: u64,
}

impl Imported {
    fn new(buffer: wgpu::Buffer) -> Self {
        Self { buffer, id: crate::graph::next_resource_id() }
    }
}

/// All buffers and bind groups of one cloud.
pub struct GrowthState {
    /// Node slots.
    pub capacity: u32,
    /// Attractions.
    pub attraction_count: u32,
    /// Roots.
    pub seed_count: u32,
    /// The cloud's distance unit and bounds.
    pub unit: f32,
    /// The cloud's bounds.
    pub bounds: ([f32; 3], [f32; 3]),
    /// Attractions (imported: the simulation writes them).
    pub attractions: Imported,
    /// Nodes (imported).
    pub nodes: Imported,
    /// World positions and t per node (imported: pose writes, the draw reads).
    pub posed: Imported,
    /// Indirect arguments (imported: the draw reads them).
    pub args: Imported,
    counters: wgpu::Buffer,
    accum: wgpu::Buffer,
    flags: wgpu::Buffer,
    candidates: wgpu::Buffer,
    sorted: wgpu::Buffer,
    cells: Option<(u32, wgpu::Buffer, wgpu::Buffer, ScanTarget)>,
    flag_scan: ScanTarget,
    pose_uniform: wgpu::Buffer,
    /// Skinning matrices of the current frame.
    pub joints: wgpu::Buffer,
    /// Joints and weights per mesh vertex.
    pub skins: wgpu::Buffer,
    /// The model's mesh (an empty one for the sphere).
    pub mesh: MeshBuffers,
    growth_group: Option<(u64, wgpu::BindGroup)>,
    args_group: wgpu::BindGroup,
    pose_group: wgpu::BindGroup,
    /// The layout the grid was last built for (None: stale).
    grid_for: Option<GridLayout>,
}

impl GrowthState {
    /// Buffers for `cloud` with `seeds` as the first nodes; `skins` are the source's vertex skins.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &Kernels,
        cloud: &Cloud,
        seeds: &[Node],
        skin: &SkinData,
        tube_indices: u32,
    ) -> Self {
        use wgpu::util::DeviceExt;
        let skins = &skin.skins;
        let capacity = cloud.attractions.len().max(seeds.len()).max(1) as u32;
        let cap = u64::from(capacity);
        let none = wgpu::BufferUsages::empty();
        let attractions = buffer(device, "sc_attractions", cap * size_of::<Attraction>() as u64, none);
        let nodes = buffer(device, "sc_nodes", cap * size_of::<Node>() as u64, none);
        let posed = buffer(device, "sc_posed", cap * 16, none);
        let args = buffer(device, "sc_args", ARGS_BYTES, wgpu::BufferUsages::INDIRECT);
        let counters = buffer(device, "sc_counters", 16, none);
        let accum = buffer(device, "sc_accum", cap * ACCUM * 4, none);
        let flags = buffer(device, "sc_flags", (cap + 1) * 4, none);
        let candidates = buffer(device, "sc_candidates", cap * 16, none);
        let sorted = buffer(device, "sc_sorted", cap * 16, none);
        let pose_uniform = crate::gpu::uniform_buffer::<PoseUniforms>(device, "sc_pose");
        let joints = buffer(device, "sc_joints", 64 * 256, none);
        let skin_data: Vec<VertexSkin> = if skins.is_empty() {
            vec![VertexSkin { joints: [0; 4], weights: [1.0, 0.0, 0.0, 0.0] }]
        } else {
            skins.to_vec()
        };
        let skins = buffer(device, "sc_vertex_skins", (skin_data.len() * size_of::<VertexSkin>()) as u64, none);
        queue.write_buffer(&skins, 0, bytemuck::cast_slice(&skin_data));
        queue.write_buffer(&attractions, 0, bytemuck::cast_slice(&cloud.attractions));
        queue.write_buffer(&nodes, 0, bytemuck::cast_slice(seeds));
        let count = seeds.len() as u32;
        queue.write_buffer(&counters, 0, bytemuck::cast_slice(&[count, 0, 0, 0]));
        let initial = initial_args(count, seeds.len() as u32, cloud.attractions.len() as u32, capacity, tube_indices);
        queue.write_buffer(&args, 0, bytemuck::cast_slice(&initial));
        let args_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sc_args_group"),
            layout: &kernels.args_layout,
            entries: &[wgpu::BindGroupEntry { binding: 4, resource: args.as_entire_binding() }],
        });
        let pose_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sc_pose_group"),
            layout: &kernels.pose_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: pose_uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: posed.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: joints.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: skins.as_entire_binding() },
            ],
        });
        let flag_scan = kernels.scan.target(device, &flags, capacity);
        let positions: Vec<[f32; 4]> = skin.positions.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
        let mesh_positions = buffer(device, "sc_mesh_positions", (positions.len() * 16) as u64, none);
        queue.write_buffer(&mesh_positions, 0, bytemuck::cast_slice(&positions));
        let index_data: Vec<u32> = skin.triangles.iter().flatten().copied().collect();
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sc_mesh_indices"),
            contents: bytemuck::cast_slice(if index_data.is_empty() { &[0u32; 3][..] } else { &index_data }),
            // Drawn by the pipeline as indices, read by the compute draw's glow.
            usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::STORAGE,
        });
        let mesh = MeshBuffers { positions: mesh_positions, indices, index_count: index_data.len() as u32 };
        Self {
            capacity,
            attraction_count: cloud.attractions.len() as u32,
            seed_count: seeds.len() as u32,
            unit: cloud.unit,
            bounds: (cloud.lo, cloud.hi),
            attractions: Imported::new(attractions),
            nodes: Imported::new(nodes),
            posed: Imported::new(posed),
            args: Imported::new(args),
            counters,
            accum,
            flags,
            candidates,
            sorted,
            cells: None,
            flag_scan,
            pose_uniform,
            joints,
            skins,
            mesh,
            growth_group: None,
            args_group,
            pose_group,
            grid_for: None,
        }
    }

    /// Fills in the cloud's part of a step's uniforms and its grid layout.
    pub fn complete(&self, mut u: GrowthUniforms, hash_seed: u32, tube_indices: u32) -> (GrowthUniforms, GridLayout) {
        let layout = GridLayout::covering(self.bounds.0, self.bounds.1, u.influence.max(u.kill));
        u.attraction_count = self.attraction_count;
        u.capacity = self.capacity;
        u.seed_count = self.seed_count;
        u.cell_count = layout.cells();
        u.dims = layout.dims;
        u.origin = layout.origin;
        u.cell_size = layout.cell_size;
        u.hash_seed = hash_seed;
        u.tube_indices = tube_indices;
        (u, layout)
    }

    /// The dispatches of one frame: `steps[i]` growth steps (0: grow only) at block i.
    pub fn plan(&mut self, steps: &[(GrowthUniforms, GridLayout, u32)]) -> Vec<Op> {
        let mut ops = Vec::new();
        for (block, (u, layout, growth_steps)) in steps.iter().enumerate() {
            let block = block as u32;
            let grid = u.brute_force == 0;
            let build = |ops: &mut Vec<Op>| ops.push(Op::BuildGrid { block, cells: layout.cells() });
            for _ in 0..*growth_steps {
                if grid && self.grid_for != Some(*layout) {
                    build(&mut ops);
                }
                ops.push(Op::Branch { block });
                // The nodes just changed: the grid is rebuilt for remove (and the next search).
                if grid {
                    build(&mut ops);
                }
                self.grid_for = grid.then_some(*layout);
                ops.push(Op::Remove { block });
                ops.push(Op::Grow { block });
            }
            if *growth_steps == 0 {
                ops.push(Op::Grow { block });
            }
        }
        ops
    }

    /// Saves every buffer a step reads before it writes (the grid of the last step included,
    /// which the next step's branch search reuses) and the layout the grid was built for.
    pub fn save(&self, gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
        for (name, buffer) in self.buffers() {
            save_buffer(gpu, state, name, buffer)?;
        }
        state.put_u64("cells", u64::from(self.cells.as_ref().map_or(0, |c| c.0)));
        if let Some((_, start, fill, _)) = &self.cells {
            save_buffer(gpu, state, "cell_start", start)?;
            save_buffer(gpu, state, "cell_fill", fill)?;
        }
        let grid = self.grid_for.map(|g| [g.origin[0], g.origin[1], g.origin[2], g.cell_size].map(f32::to_bits));
        let grid: Vec<u32> = grid.into_iter().flatten().chain(self.grid_for.into_iter().flat_map(|g| g.dims)).collect();
        state.put_pod("grid_for", &grid);
        Ok(())
    }

    /// Puts back what [`GrowthState::save`] wrote, into the state of the same cloud.
    pub fn load(&mut self, gpu: &Gpu, kernels: &Kernels, state: &NodeState) -> Result<(), CheckpointError> {
        for (name, buffer) in self.buffers() {
            load_buffer(gpu, state, name, buffer)?;
        }
        let cells = u32::try_from(state.get_u64("cells")?).unwrap_or(u32::MAX);
        if cells > 0 {
            if !cells.is_power_of_two() || cells > MAX_CELLS.next_power_of_two() {
                return Err(state.error("cells", format!("{cells} cells is not a grid this node makes")));
            }
            self.make_cells(&gpu.device, kernels, cells);
            let (_, start, fill, _) = self.cells.as_ref().expect("made above");
            load_buffer(gpu, state, "cell_start", start)?;
            load_buffer(gpu, state, "cell_fill", fill)?;
        }
        self.grid_for = match state.get_pod::<u32>("grid_for")?[..] {
            [] => None,
            [x, y, z, side, dx, dy, dz] => Some(GridLayout {
                origin: [x, y, z].map(f32::from_bits),
                cell_size: f32::from_bits(side),
                dims: [dx, dy, dz],
            }),
            _ => return Err(state.error("grid_for", "is not a grid layout".into())),
        };
        Ok(())
    }

    /// The buffers of one cloud that a step reads before it writes, by name.
    fn buffers(&self) -> [(&'static str, &wgpu::Buffer); 9] {
        [
            ("attractions", &self.attractions.buffer),
            ("nodes", &self.nodes.buffer),
            ("posed", &self.posed.buffer),
            ("args", &self.args.buffer),
            ("counters", &self.counters),
            ("accum", &self.accum),
            ("flags", &self.flags),
            ("candidates", &self.candidates),
            ("sorted", &self.sorted),
        ]
    }

    /// Cell buffers for `n` cells (a power of two); the growth group is made again.
    fn make_cells(&mut self, device: &wgpu::Device, kernels: &Kernels, n: u32) {
        let none = wgpu::BufferUsages::empty();
        let start = buffer(device, "sc_cell_start", u64::from(n + 1) * 4, none);
        let fill = buffer(device, "sc_cell_fill", u64::from(n) * 4, none);
        let scan = kernels.scan.target(device, &start, n);
        self.cells = Some((n, start, fill, scan));
        self.growth_group = None;
        self.grid_for = None;
    }

    /// Makes sure the cell buffers hold `cells` and the growth group binds `uniforms`.
    pub fn prepare(&mut self, device: &wgpu::Device, kernels: &Kernels, uniforms: &wgpu::Buffer, cells: u32) {
        if self.cells.as_ref().is_none_or(|c| c.0 < cells) {
            self.make_cells(device, kernels, cells.next_power_of_two().max(64));
        }
        let uniform_id = uniforms.size();
        if self.growth_group.as_ref().is_some_and(|g| g.0 == uniform_id) {
            return;
        }
        let (_, start, fill, _) = self.cells.as_ref().expect("made above");
        let resources = [
            &self.attractions.buffer,
            &self.nodes.buffer,
            &self.accum,
            &self.flags,
            &self.candidates,
            start,
            fill,
            &self.sorted,
            &self.counters,
        ];
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: uniforms,
                offset: 0,
                size: wgpu::BufferSize::new(size_of::<GrowthUniforms>() as u64),
            }),
        }];
        entries.extend(
            resources
                .iter()
                .enumerate()
                .map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32 + 1, resource: b.as_entire_binding() }),
        );
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sc_growth_group"),
            layout: &kernels.growth_layout,
            entries: &entries,
        });
        self.growth_group = Some((uniform_id, group));
    }

    /// Writes the pose kernel's uniforms and joint matrices (≤ 256).
    pub fn set_pose(&self, queue: &wgpu::Queue, pose: &PoseUniforms, joints: &[[[f32; 4]; 4]]) {
        queue.write_buffer(&self.pose_uniform, 0, bytemuck::bytes_of(pose));
        if !joints.is_empty() {
            queue.write_buffer(&self.joints, 0, bytemuck::cast_slice(&joints[..joints.len().min(256)]));
        }
    }

    /// Records `ops` into `pass`.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>, k: &Kernels, ops: &[Op]) {
        let Some((_, group)) = &self.growth_group else { return };
        let (_, _, _, cell_scan) = self.cells.as_ref().expect("prepared");
        let bind = |pass: &mut wgpu::ComputePass<'_>, kernel: &ComputeKernel, block: u32| {
            pass.set_pipeline(&kernel.pipeline);
            pass.set_bind_group(0, group, &[block * BLOCK as u32]);
        };
        let direct = |pass: &mut wgpu::ComputePass<'_>, kernel: &ComputeKernel, block: u32, threads: u32| {
            bind(pass, kernel, block);
            let [x, y, z] = kernel.workgroups([threads.max(1), 1, 1]);
            pass.dispatch_workgroups(x, y, z);
        };
        // Sizes only the GPU knows: the node count, or zero once the pool is full.
        let indirect = |pass: &mut wgpu::ComputePass<'_>, kernel: &ComputeKernel, block: u32, offset: u64| {
            bind(pass, kernel, block);
            pass.dispatch_workgroups_indirect(&self.args.buffer, offset);
        };
        for op in ops {
            match *op {
                Op::BuildGrid { block, cells } => {
                    direct(pass, &k.clear_cells, block, cells);
                    indirect(pass, &k.count_cells, block, CHANGED_NODES);
                    direct(pass, &k.take_counts, block, cells);
                    k.scan.record(pass, cell_scan);
                    indirect(pass, &k.scatter, block, CHANGED_NODES);
                }
                Op::Branch { block } => {
                    indirect(pass, &k.clear_accum, block, GROWING_NODES);
                    indirect(pass, &k.search, block, GROWING_ATTRACTIONS);
                    indirect(pass, &k.attract, block, GROWING_SLOTS);
                    k.scan.record(pass, &self.flag_scan);
                    indirect(pass, &k.connect, block, GROWING_NODES);
                    bind(pass, &k.finalize, block);
                    pass.set_bind_group(1, &self.args_group, &[]);
                    pass.dispatch_workgroups(1, 1, 1);
                }
                Op::Remove { block } => indirect(pass, &k.remove, block, CHANGED_ATTRACTIONS),
                Op::Grow { block } => indirect(pass, &k.grow, block, 0),
            }
        }
    }

    /// Records the pose kernel (world positions for the draw).
    pub fn record_pose(&self, pass: &mut wgpu::ComputePass<'_>, k: &Kernels) {
        let Some((_, group)) = &self.growth_group else { return };
        pass.set_pipeline(&k.pose.pipeline);
        pass.set_bind_group(0, group, &[0]);
        pass.set_bind_group(1, &self.pose_group, &[]);
        pass.dispatch_workgroups_indirect(&self.args.buffer, 0);
    }

    /// Nodes in use after the last submitted frame (blocking; tests and tools).
    pub fn node_count(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> u32 {
        let bytes = crate::gpu::read_buffer(device, queue, &self.counters, 0, 4).unwrap_or_default();
        bytes.get(..4).map_or(0, |c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
    }

    /// Reads the nodes in use and the attractions back (blocking; tests and tools).
    pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> (Vec<Attraction>, Vec<Node>) {
        let read =
            |b: &wgpu::Buffer, bytes: u64| crate::gpu::read_buffer(device, queue, b, 0, bytes).unwrap_or_default();
        let count = self.node_count(device, queue);
        let attractions =
            read(&self.attractions.buffer, u64::from(self.attraction_count) * size_of::<Attraction>() as u64);
        let nodes = read(&self.nodes.buffer, u64::from(count.max(1)) * size_of::<Node>() as u64);
        let nodes: Vec<Node> = bytemuck::pod_collect_to_vec(&nodes);
        (bytemuck::pod_collect_to_vec(&attractions), nodes[..count as usize].to_vec())
    }
}

/// The indirect arguments for `count` nodes of which `seeds` are roots, `attractions` and
/// `capacity` slots (the shader's `write_args`).
pub fn initial_args(count: u32, seeds: u32, attractions: u32, capacity: u32, tube_indices: u32) -> [u32; 27] {
    let edges = count - count.min(seeds);
    let growing = |n: u32| if count < capacity { n.div_ceil(128) } else { 0 };
    let nodes = count.div_ceil(128);
    let (a, c) = (growing(attractions), growing(count));
    [
        nodes,
        1,
        1,
        2,
        edges,
        0,
        0,
        tube_indices,
        edges,
        0,
        0,
        0,
        c,
        1,
        1,
        a,
        1,
        1,
        growing(capacity),
        1,
        1,
        c,
        1,
        1,
        a,
        1,
        1,
    ]
}
