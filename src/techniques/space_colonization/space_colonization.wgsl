// Chapter 1: space colonization on the GPU — one growth step is
//   search      each live attraction: the nearest node strictly within the influence distance
//               (a uniform grid over the nodes, or brute force); its unit vector towards the
//               attraction is added to that node's sum in 16.16 fixed point, so the sum is the
//               same whatever order the atomics run in
//   attract     each grown node (t ≥ 1) that was chosen: candidate = node + normalised mean
//               direction · growth distance (the sample did not normalise: bug 2); flag it
//   [scan]      the flags' exclusive prefix sum (prefix_sum.wgsl): a candidate's rank in node order
//   connect     candidate of node i becomes node count + rank (t = 0, depth + 1, hashed mass)
//   finalize    one thread: the new count, the indirect dispatch and draw arguments
//   [grid]      counting sort of the nodes by cell: clear, count, take counts, scan, scatter
//   remove      attractions within the kill distance of any node die
//   grow        t += dt · growth speed · mass, at most 1
// Node-sized dispatches are indirect (their size is on the GPU), and so are search, attract
// and remove: their arguments drop to zero once the pool is full. Nothing is read back.
// Plus `pose`: node positions in world space for drawing (model transform or 4-weight skinning).

struct Growth {
    attraction_count: u32,
    capacity: u32,
    seed_count: u32,
    cell_count: u32,
    dims: vec3<u32>,
    brute_force: u32,
    origin: vec3<f32>,
    cell_size: f32,
    influence: f32,
    growth: f32,
    kill: f32,
    grow_step: f32,
    mass_min: f32,
    mass_max: f32,
    hash_seed: u32,
    tube_indices: u32,
}

struct Attraction {
    pos: vec3<f32>,
    alive: u32,
    // The node it chose in the last search (NONE: none within reach).
    nearest: u32,
    // Index of the mesh vertex whose skin it carries (skinned sources).
    skin: u32,
    _pad0: u32,
    _pad1: u32,
}

struct Node {
    pos: vec3<f32>,
    t: f32,
    depth: u32,
    mass: f32,
    parent: u32,
    skin: u32,
}

struct Counters {
    node_count: u32,
    added: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> g: Growth;
@group(0) @binding(1) var<storage, read_write> attractions: array<Attraction>;
@group(0) @binding(2) var<storage, read_write> nodes: array<Node>;
// Per node: Σ x, Σ y, Σ z (16.16 fixed point), count, lowest choosing attraction.
@group(0) @binding(3) var<storage, read_write> accum: array<atomic<i32>>;
@group(0) @binding(4) var<storage, read_write> flags: array<u32>;
@group(0) @binding(5) var<storage, read_write> candidates: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> cell_start: array<u32>;
@group(0) @binding(7) var<storage, read_write> cell_fill: array<atomic<u32>>;
// The nodes in cell order: position and index (bitcast into w), so a search reads each cell's
// nodes from consecutive memory.
@group(0) @binding(8) var<storage, read_write> sorted: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> counters: Counters;

// finalize only: indirect arguments (dispatch x y z, draw, indexed draw), never bound while used.
@group(1) @binding(4) var<storage, read_write> args: array<u32>;

const NONE: u32 = 0xffffffffu;
const FIXED: f32 = 65536.0;
const ACCUM: u32 = 5u;
// A mean direction shorter than this (attractions all around) gives no candidate.
const MIN_MEAN: f32 = 1e-3;
const WG: u32 = 128u;

fn cell_of(p: vec3<f32>) -> vec3<i32> {
    let c = vec3<i32>(floor((p - g.origin) / g.cell_size));
    return clamp(c, vec3<i32>(0), vec3<i32>(g.dims) - vec3<i32>(1));
}

fn cell_index(c: vec3<i32>) -> u32 {
    return (u32(c.z) * g.dims.y + u32(c.y)) * g.dims.x + u32(c.x);
}

fn distance2(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let d = a - b;
    return d.x * d.x + d.y * d.y + d.z * d.z;
}

// The nearest node strictly within sqrt(reach2) of p; ties go to the lower index, so the grid
// and brute force (and any visiting order) agree.
fn nearest_node(p: vec3<f32>, reach2: f32) -> u32 {
    var best_d2 = reach2;
    var best = NONE;
    if g.brute_force != 0u {
        for (var j = 0u; j < counters.node_count; j++) {
            let d2 = distance2(nodes[j].pos, p);
            if d2 < best_d2 {
                best_d2 = d2;
                best = j;
            }
        }
        return best;
    }
    // The cell is at least as wide as the reach: the 27 cells around p hold every candidate.
    let c = cell_of(p);
    for (var dz = -1; dz <= 1; dz++) {
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let n = c + vec3<i32>(dx, dy, dz);
                if any(n < vec3<i32>(0)) || any(n >= vec3<i32>(g.dims)) {
                    continue;
                }
                let cell = cell_index(n);
                for (var s = cell_start[cell]; s < cell_start[cell + 1u]; s++) {
                    let entry = sorted[s];
                    let j = bitcast<u32>(entry.w);
                    let d2 = distance2(entry.xyz, p);
                    if d2 < best_d2 || (d2 == best_d2 && j < best) {
                        best_d2 = d2;
                        best = j;
                    }
                }
            }
        }
    }
    return best;
}

fn hash(x: u32) -> u32 {
    // PCG output permutation: integer-only, so every GPU gives the same masses.
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn unit_hash(x: u32) -> f32 {
    return f32(hash(x) >> 8u) / 16777216.0;
}

@compute @workgroup_size(WG)
fn clear_accum(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= counters.node_count {
        return;
    }
    for (var k = 0u; k < ACCUM - 1u; k++) {
        atomicStore(&accum[i * ACCUM + k], 0);
    }
    atomicStore(&accum[i * ACCUM + ACCUM - 1u], 0x7fffffff);
}

@compute @workgroup_size(WG)
fn search(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= g.attraction_count {
        return;
    }
    if attractions[i].alive == 0u {
        attractions[i].nearest = NONE;
        return;
    }
    let p = attractions[i].pos;
    let n = nearest_node(p, g.influence * g.influence);
    attractions[i].nearest = n;
    if n == NONE {
        return;
    }
    let d = p - nodes[n].pos;
    let len = sqrt(distance2(p, nodes[n].pos));
    if len <= 0.0 {
        return; // an attraction on the node itself pulls nowhere (and dies in remove)
    }
    let q = vec3<i32>(round(d / len * FIXED));
    atomicAdd(&accum[n * ACCUM], q.x);
    atomicAdd(&accum[n * ACCUM + 1u], q.y);
    atomicAdd(&accum[n * ACCUM + 2u], q.z);
    atomicAdd(&accum[n * ACCUM + 3u], 1);
    atomicMin(&accum[n * ACCUM + 4u], i32(i));
}

// Direct over the capacity: slots past the count must read 0 for the scan.
@compute @workgroup_size(WG)
fn attract(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= g.capacity {
        return;
    }
    var flag = 0u;
    if i < counters.node_count {
        let count = atomicLoad(&accum[i * ACCUM + 3u]);
        if nodes[i].t >= 1.0 && count > 0 {
            let sum = vec3<f32>(
                f32(atomicLoad(&accum[i * ACCUM])),
                f32(atomicLoad(&accum[i * ACCUM + 1u])),
                f32(atomicLoad(&accum[i * ACCUM + 2u])),
            );
            let len = sqrt(sum.x * sum.x + sum.y * sum.y + sum.z * sum.z);
            if len > MIN_MEAN * FIXED * f32(count) {
                let skin = attractions[u32(atomicLoad(&accum[i * ACCUM + 4u]))].skin;
                candidates[i] = vec4<f32>(nodes[i].pos + sum / len * g.growth, bitcast<f32>(skin));
                flag = 1u;
            }
        }
    }
    flags[i] = flag;
}

@compute @workgroup_size(WG)
fn connect(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= counters.node_count {
        return;
    }
    let rank = flags[i];
    if flags[i + 1u] == rank {
        return;
    }
    let slot = counters.node_count + rank;
    if slot >= g.capacity {
        return; // the pool is empty: the lowest-index candidates won
    }
    let c = candidates[i];
    let mass = mix(g.mass_min, g.mass_max, unit_hash(slot ^ g.hash_seed));
    nodes[slot] = Node(c.xyz, 0.0, nodes[i].depth + 1u, mass, i, bitcast<u32>(c.w));
}

fn write_args(count: u32, changed: bool) {
    let edges = count - min(count, g.seed_count);
    args[0] = (count + WG - 1u) / WG;
    args[1] = 1u;
    args[2] = 1u;
    // Lines: 2 vertices per edge.
    args[3] = 2u;
    args[4] = edges;
    args[5] = 0u;
    args[6] = 0u;
    // Tubes: the capsule's indices per edge.
    args[7] = g.tube_indices;
    args[8] = edges;
    args[9] = 0u;
    args[10] = 0u;
    args[11] = 0u;
    // The growth work of the next step: none once the pool is full (nothing can change but t),
    // so a finished forest costs only its grow.
    let growing = count < g.capacity;
    args[12] = select(0u, (count + WG - 1u) / WG, growing);
    args[13] = 1u;
    args[14] = 1u;
    args[15] = select(0u, (g.attraction_count + WG - 1u) / WG, growing);
    args[16] = 1u;
    args[17] = 1u;
    args[18] = select(0u, (g.capacity + WG - 1u) / WG, growing);
    args[19] = 1u;
    args[20] = 1u;
    // The rest of this step (grid rebuild, remove): needed while this step could add nodes.
    args[21] = select(0u, (count + WG - 1u) / WG, changed);
    args[22] = 1u;
    args[23] = 1u;
    args[24] = select(0u, (g.attraction_count + WG - 1u) / WG, changed);
    args[25] = 1u;
    args[26] = 1u;
}

@compute @workgroup_size(1)
fn finalize() {
    let before = counters.node_count;
    let count = min(before + flags[g.capacity], g.capacity);
    counters.node_count = count;
    counters.added = count - before;
    write_args(count, before < g.capacity);
}

@compute @workgroup_size(WG)
fn clear_cells(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < g.cell_count {
        atomicStore(&cell_fill[id.x], 0u);
    }
}

@compute @workgroup_size(WG)
fn count_cells(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i < counters.node_count {
        atomicAdd(&cell_fill[cell_index(cell_of(nodes[i].pos))], 1u);
    }
}

@compute @workgroup_size(WG)
fn take_counts(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < g.cell_count {
        cell_start[id.x] = atomicLoad(&cell_fill[id.x]);
        atomicStore(&cell_fill[id.x], 0u);
    }
}

// The order inside a cell follows the atomics, which is fine: every reader takes a minimum.
@compute @workgroup_size(WG)
fn scatter(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i < counters.node_count {
        let pos = nodes[i].pos;
        let cell = cell_index(cell_of(pos));
        sorted[cell_start[cell] + atomicAdd(&cell_fill[cell], 1u)] = vec4<f32>(pos, bitcast<f32>(i));
    }
}

@compute @workgroup_size(WG)
fn remove(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= g.attraction_count || attractions[i].alive == 0u {
        return;
    }
    if nearest_node(attractions[i].pos, g.kill * g.kill) != NONE {
        attractions[i].alive = 0u;
    }
}

@compute @workgroup_size(WG)
fn grow(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i < counters.node_count {
        nodes[i].t = min(1.0, nodes[i].t + g.grow_step * nodes[i].mass);
    }
}

// ---- pose: world positions for drawing ----

struct Pose {
    model: mat4x4<f32>,
    skinned: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct VertexSkin {
    joints: vec4<u32>,
    weights: vec4<f32>,
}

@group(1) @binding(0) var<uniform> pose_info: Pose;
@group(1) @binding(1) var<storage, read_write> posed: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read> joint_matrices: array<mat4x4<f32>>;
@group(1) @binding(3) var<storage, read> vertex_skins: array<VertexSkin>;

@compute @workgroup_size(WG)
fn pose(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= counters.node_count {
        return;
    }
    let node = nodes[i];
    var p = vec4<f32>(node.pos, 1.0);
    if pose_info.skinned != 0u {
        // Linear blend skinning with all four weights (the sample used one rigid bone: bug 6).
        let s = vertex_skins[node.skin];
        p = (joint_matrices[s.joints.x] * p) * s.weights.x + (joint_matrices[s.joints.y] * p) * s.weights.y
            + (joint_matrices[s.joints.z] * p) * s.weights.z + (joint_matrices[s.joints.w] * p) * s.weights.w;
    }
    posed[i] = vec4<f32>((pose_info.model * p).xyz, node.t);
}
