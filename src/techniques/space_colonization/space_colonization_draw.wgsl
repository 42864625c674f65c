// Chapter 1 drawing (plus the skinned scene's floor and the model's faint glow): each edge (parent → child) is one instance; the child end is drawn at
// mix(parent, child, t) so branches visibly grow out. Lines: two vertices, added up (the book's
// look). Tubes: an instanced capsule — a round ring of SIDES vertices at each end and a
// hemispherical cap on the growing tip — in world space, coloured by the normal as in the book,
// or lit (Blinn-Phong) with tips that glow while they grow. Positions come from `posed` (world
// space, w = t), written by the growth shader's `pose` kernel. The tube's shading is shared with
// the compute draw (space_colonization_raster.wgsl), which builds on this file.
// extends: msaa_samples.wgsl

struct View {
    view_proj: mat4x4<f32>,
    camera: vec4<f32>,
    color: vec4<f32>,
    // xyz: towards the light; w: emission of a tip at t = 0.
    light: vec4<f32>,
    thickness: f32,
    seed_count: u32,
    lit: u32,
    // Strength of the model's glow.
    ghost: f32,
    // Local → world of the model's mesh (after skinning).
    model: mat4x4<f32>,
    // Linear floor colour; w: half size (0: none).
    floor: vec4<f32>,
}

struct VertexSkin {
    joints: vec4<u32>,
    weights: vec4<f32>,
}

struct Node {
    pos: vec3<f32>,
    t: f32,
    depth: u32,
    mass: f32,
    parent: u32,
    skin: u32,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> posed: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> nodes: array<Node>;
@group(0) @binding(3) var<storage, read> mesh_positions: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> vertex_skins: array<VertexSkin>;
@group(0) @binding(5) var<storage, read> joint_matrices: array<mat4x4<f32>>;

const PI: f32 = 3.14159265;
// Must match `TUBE_SIDES` and `TUBE_CAP_ROWS` in render.rs (the index buffer).
const SIDES: u32 = 8u;
const CAP_ROWS: u32 = 3u;

struct Edge {
    from_pos: vec3<f32>,
    to_pos: vec3<f32>,
    // Unit direction of the full edge (also while it is still short).
    axis: vec3<f32>,
    t: f32,
}

fn edge(instance: u32) -> Edge {
    let child = view.seed_count + instance;
    let a = posed[nodes[child].parent];
    let b = posed[child];
    let full = b.xyz - a.xyz;
    let len = length(full);
    var axis = vec3<f32>(0.0, 1.0, 0.0);
    if len > 0.0 {
        axis = full / len;
    }
    return Edge(a.xyz, mix(a.xyz, b.xyz, b.w), axis, b.w);
}

@vertex
fn vs_line(@builtin(vertex_index) v: u32, @builtin(instance_index) instance: u32) -> @builtin(position) vec4<f32> {
    let e = edge(instance);
    return view.view_proj * vec4<f32>(select(e.from_pos, e.to_pos, v == 1u), 1.0);
}

@fragment
fn fs_line() -> @location(0) vec4<f32> {
    return vec4<f32>(view.color.rgb, 1.0);
}

struct TubeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) world: vec3<f32>,
    @location(2) t: f32,
}

// A right-handed orthonormal pair perpendicular to unit n (Duff et al. 2017, branch-free).
fn perpendiculars(n: vec3<f32>) -> mat2x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    return mat2x3<f32>(vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x), vec3<f32>(b, s + n.y * n.y * a, -n.y));
}

@vertex
fn vs_tube(@builtin(vertex_index) v: u32, @builtin(instance_index) instance: u32) -> TubeOut {
    let e = edge(instance);
    let frame = perpendiculars(e.axis);
    let row = v / SIDES;
    let angle = f32(v % SIDES) / f32(SIDES) * 2.0 * PI;
    let radial = frame[0] * cos(angle) + frame[1] * sin(angle);
    // Row 0: the ring at the parent; row 1: at the tip; rows 2…: the cap, closing at the pole.
    var centre = e.from_pos;
    var normal = radial;
    if row >= 1u {
        centre = e.to_pos;
    }
    if row >= 2u {
        let polar = f32(row - 1u) / f32(CAP_ROWS) * 0.5 * PI;
        normal = radial * cos(polar) + e.axis * sin(polar);
    }
    let world = centre + normal * view.thickness;
    var out: TubeOut;
    out.clip = view.view_proj * vec4<f32>(world, 1.0);
    out.normal = normal;
    out.world = world;
    out.t = e.t;
    return out;
}

@fragment
fn fs_tube(in: TubeOut) -> @location(0) vec4<f32> {
    return vec4<f32>(tube_colour(normalize(in.normal), in.world, in.t), 1.0);
}

// The colour of a tube's surface at `world` with unit normal `n`, on an edge grown to `t`.
fn tube_colour(n: vec3<f32>, world: vec3<f32>, t: f32) -> vec3<f32> {
    if view.lit == 0u {
        return view.color.rgb * (n * 0.5 + 0.5);
    }
    let l = normalize(view.light.xyz);
    let to_eye = normalize(view.camera.xyz - world);
    let h = normalize(l + to_eye);
    let diffuse = max(dot(n, l), 0.0);
    let specular = pow(max(dot(n, h), 0.0), 48.0) * 0.35;
    // The book's emissive tips: 1 at t = 0 fading to 0 at t = 1.
    let glow = (1.0 - smoothstep(0.0, 1.0, t)) * view.light.w;
    return view.color.rgb * (0.18 + 0.82 * diffuse) + vec3<f32>(specular) + view.color.rgb * glow;
}

// ---- the floor: a lit square at y = 0 ----

struct FloorOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
}

@vertex
fn vs_floor(@builtin(vertex_index) v: u32) -> FloorOut {
    let corners = array<vec2<f32>, 6>(vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));
    let c = corners[v] * view.floor.w;
    var out: FloorOut;
    out.world = vec3<f32>(c.x, 0.0, c.y);
    out.clip = view.view_proj * vec4<f32>(out.world, 1.0);
    return out;
}

@fragment
fn fs_floor(in: FloorOut) -> @location(0) vec4<f32> {
    return vec4<f32>(floor_colour(in.world), 1.0);
}

// The floor's colour at `world` (a point at y = 0; also the compute draw's).
fn floor_colour(world: vec3<f32>) -> vec3<f32> {
    let l = normalize(view.light.xyz);
    let diffuse = max(l.y, 0.0);
    // Fades out towards the edge so the square does not end in a hard line.
    let fade = 1.0 - smoothstep(0.6, 1.0, length(world.xz) / view.floor.w);
    return view.floor.rgb * (0.25 + 0.75 * diffuse) * fade;
}

// ---- the model's skin, drawn as a faint additive glow ----

struct MeshOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
}

// Mesh vertex v posed: its 4-weight skin, then the model's transform (world space).
fn skinned_vertex(v: u32) -> vec3<f32> {
    let s = vertex_skins[v];
    let p = mesh_positions[v];
    let skinned = (joint_matrices[s.joints.x] * p) * s.weights.x + (joint_matrices[s.joints.y] * p) * s.weights.y
        + (joint_matrices[s.joints.z] * p) * s.weights.z + (joint_matrices[s.joints.w] * p) * s.weights.w;
    return (view.model * skinned).xyz;
}

// The glow of a face of unit normal `n` seen along the unit direction `towards_camera`, before
// the colour and strength: grazing faces glow most (a rim).
fn glow_weight(n: vec3<f32>, towards_camera: vec3<f32>) -> f32 {
    return 1.0 - abs(dot(n, towards_camera));
}

@vertex
fn vs_mesh(@builtin(vertex_index) v: u32) -> MeshOut {
    var out: MeshOut;
    out.world = skinned_vertex(v);
    out.clip = view.view_proj * vec4<f32>(out.world, 1.0);
    return out;
}

@fragment
fn fs_mesh(in: MeshOut) -> @location(0) vec4<f32> {
    // Flat normal from the screen derivatives.
    let n = normalize(cross(dpdx(in.world), dpdy(in.world)));
    let weight = glow_weight(n, normalize(view.camera.xyz - in.world));
    return vec4<f32>(view.color.rgb * view.ghost * weight, 1.0);
}
