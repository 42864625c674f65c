// Chapter 6: tessellation and displacement without hull and domain stages.
//
// The base mesh is the book's plane: G×G quads of 10×10 units, two triangles each, computed from
// indices (no tables). Per frame:
//   edges   one thread per edge: the book's edge factor max(1, length · screen height /
//           (target px · distance to the edge's midpoint)), clamped to 64, as an integer level.
//           A shared edge is computed once, so both of its patches see the same level.
//   patches one thread per patch: culled (level 0) when all three vertices lie outside one side
//           plane of the frustum by more than 1.5 × displacement; else the level n is the larger of
//           ⌈mean of the edge factors⌉ (the book's inside factor) and the three edge levels.
//   scan    one workgroup: triangle offsets (n² per patch, exclusive prefix sum in patch order)
//           and the indirect draw's vertex count — no CPU round trip, no atomics.
//   draw    the vertex shader finds its patch by binary search and evaluates its lattice point:
//           a point on a patch edge is snapped to that edge's own subdivision, from the same
//           integers and endpoints in the edge's canonical direction, so neighbours with
//           different levels meet exactly (crack-free); interior points are barycentric. Points
//           are geomorphed by the fractional factors (see `morphed`): levels are integers, but
//           vertices glide between them instead of popping. The
//           height is sampled at the point's UV, the surface displaced along the normal, and the
//           normal recomputed from the height field's gradient.
//
// The sample locations, for the compute draw:
// extends: msaa_samples.wgsl

struct Tess {
    model: mat4x4<f32>,
    view_proj: mat4x4<f32>,
    // Frustum side planes (left, right, bottom, top) in world space, inside ≥ 0.
    planes: array<vec4<f32>, 4>,
    camera: vec4<f32>,
    light_dir: vec4<f32>,
    // Blinn-Phong: albedo, specular colour; background.
    albedo: vec4<f32>,
    spec_color: vec4<f32>,
    background: vec4<f32>,
    grid: u32,
    patch_count: u32,
    edge_count: u32,
    view_mode: u32,
    // Target edge length in pixels, output height in pixels, displacement (signed), light.
    edge_px: f32,
    screen_height: f32,
    displacement: f32,
    light_intensity: f32,
    specular: f32,
    gloss: f32,
    luminance: u32,
    plane_size: f32,
}

@group(0) @binding(0) var<uniform> u: Tess;
@group(0) @binding(1) var<storage, read_write> edge_factors: array<f32>;
@group(0) @binding(2) var<storage, read_write> patch_levels: array<u32>;
@group(0) @binding(3) var<storage, read_write> offsets: array<u32>;
// vertex_count, instance_count, first_vertex, first_instance, then the triangle total, then the
// compute rasterizer's dispatch (see `scan` and tessellation_raster.wgsl).
@group(0) @binding(4) var<storage, read_write> draw_args: array<u32>;

const MAX_LEVEL: f32 = 64.0;

// ---- the base mesh, from indices ----

fn vertex_xz(v: u32) -> vec2<u32> {
    return vec2<u32>(v % (u.grid + 1u), v / (u.grid + 1u));
}

fn base_uv(v: u32) -> vec2<f32> {
    return vec2<f32>(vertex_xz(v)) / f32(u.grid);
}

fn local_position(uv: vec2<f32>) -> vec3<f32> {
    return vec3<f32>((uv.x - 0.5) * u.plane_size, 0.0, (uv.y - 0.5) * u.plane_size);
}

fn world_position(uv: vec2<f32>) -> vec3<f32> {
    return (u.model * vec4<f32>(local_position(uv), 1.0)).xyz;
}

fn horizontal_edges() -> u32 {
    return (u.grid + 1u) * u.grid;
}

// The two vertex indices of edge `e`, lower index first (the canonical direction).
fn edge_vertices(e: u32) -> vec2<u32> {
    let g = u.grid;
    let row = g + 1u;
    let h = horizontal_edges();
    if e < h {
        let z = e / g;
        let x = e % g;
        return vec2<u32>(z * row + x, z * row + x + 1u);
    }
    if e < 2u * h {
        let k = e - h;
        let z = k / row;
        let x = k % row;
        return vec2<u32>(z * row + x, (z + 1u) * row + x);
    }
    let k = e - 2u * h;
    let z = k / g;
    let x = k % g;
    return vec2<u32>(z * row + x, (z + 1u) * row + x + 1u);
}

struct Patch {
    v: array<u32, 3>,
    e: array<u32, 3>,
}

// Patch p: quad p / 2, triangle A (v00, v10, v11) or B (v00, v11, v01); edge k joins v[k], v[k+1].
fn patch_of(p: u32) -> Patch {
    let g = u.grid;
    let row = g + 1u;
    let h = horizontal_edges();
    let quad = p / 2u;
    let x = quad % g;
    let z = quad / g;
    let v00 = z * row + x;
    let v10 = v00 + 1u;
    let v01 = v00 + row;
    let v11 = v01 + 1u;
    let bottom = z * g + x;
    let top = (z + 1u) * g + x;
    let left = h + z * row + x;
    let right = left + 1u;
    let diagonal = 2u * h + z * g + x;
    var out: Patch;
    if p % 2u == 0u {
        out.v = array<u32, 3>(v00, v10, v11);
        out.e = array<u32, 3>(bottom, right, diagonal);
    } else {
        out.v = array<u32, 3>(v00, v11, v01);
        out.e = array<u32, 3>(diagonal, top, left);
    }
    return out;
}

// ---- factors, levels, scan ----

@compute @workgroup_size(64)
fn edges(@builtin(global_invocation_id) id: vec3<u32>) {
    let e = id.x;
    if e >= u.edge_count {
        return;
    }
    let ends = edge_vertices(e);
    let a = world_position(base_uv(ends.x));
    let b = world_position(base_uv(ends.y));
    let distance = max(length((a + b) * 0.5 - u.camera.xyz), 1e-4);
    let factor = length(a - b) * u.screen_height / (u.edge_px * distance);
    edge_factors[e] = clamp(factor, 1.0, MAX_LEVEL);
}

fn level_of(factor: f32) -> u32 {
    return u32(ceil(factor));
}

// A patch's factor: the larger of the mean of its edges' (the book's inside factor) and the
// edges' own, so that its level (the ceiling) holds every edge's subdivision.
fn patch_factor(f: vec3<f32>) -> f32 {
    return max((f.x + f.y + f.z) / 3.0, max(f.x, max(f.y, f.z)));
}

fn outside(planes_index: u32, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, margin: f32) -> bool {
    let p = u.planes[planes_index];
    return dot(p.xyz, a) + p.w < -margin && dot(p.xyz, b) + p.w < -margin && dot(p.xyz, c) + p.w < -margin;
}

@compute @workgroup_size(64)
fn patches(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.x;
    if p >= u.patch_count {
        return;
    }
    let t = patch_of(p);
    let a = world_position(base_uv(t.v[0]));
    let b = world_position(base_uv(t.v[1]));
    let c = world_position(base_uv(t.v[2]));
    let margin = 1.5 * abs(u.displacement);
    var culled = false;
    for (var i = 0u; i < 4u; i++) {
        culled = culled || outside(i, a, b, c, margin);
    }
    let f = vec3<f32>(edge_factors[t.e[0]], edge_factors[t.e[1]], edge_factors[t.e[2]]);
    patch_levels[p] = select(level_of(patch_factor(f)), 0u, culled);
}

const SCAN_THREADS: u32 = 256u;
var<workgroup> chunk_sums: array<u32, 256>;

// Exclusive prefix sum of n² over the patches in patch order (deterministic), then the draw.
@compute @workgroup_size(256)
fn scan(@builtin(local_invocation_id) lid: vec3<u32>) {
    let t = lid.x;
    let per = (u.patch_count + SCAN_THREADS - 1u) / SCAN_THREADS;
    let first = t * per;
    let last = min(first + per, u.patch_count);
    var sum = 0u;
    for (var p = first; p < last; p++) {
        let n = patch_levels[p];
        sum += n * n;
    }
    chunk_sums[t] = sum;
    workgroupBarrier();
    // Hillis–Steele inclusive scan of the chunk sums.
    for (var step = 1u; step < SCAN_THREADS; step *= 2u) {
        var add = 0u;
        if t >= step {
            add = chunk_sums[t - step];
        }
        workgroupBarrier();
        chunk_sums[t] += add;
        workgroupBarrier();
    }
    var running = chunk_sums[t] - sum;
    for (var p = first; p < last; p++) {
        offsets[p] = running;
        let n = patch_levels[p];
        running += n * n;
    }
    if t == SCAN_THREADS - 1u {
        let total = chunk_sums[t];
        offsets[u.patch_count] = total;
        draw_args[0] = 3u * total;
        draw_args[1] = 1u;
        draw_args[2] = 0u;
        draw_args[3] = 0u;
        draw_args[4] = total;
        // The compute rasterizer's dispatch: 64 triangles a workgroup, at most 32768 a row.
        let groups = (total + 63u) / 64u;
        draw_args[5] = min(groups, 32768u);
        draw_args[6] = (groups + 32767u) / 32768u;
        draw_args[7] = 1u;
    }
}

// ---- evaluation of a lattice point ----
// Group 1 reads what the compute passes wrote, read-only (vertex shaders may not write storage).

@group(1) @binding(0) var height_map: texture_2d<f32>;
@group(1) @binding(1) var height_sampler: sampler;
@group(1) @binding(2) var<storage, read> factors_in: array<f32>;
@group(1) @binding(3) var<storage, read> levels_in: array<u32>;
@group(1) @binding(4) var<storage, read> offsets_in: array<u32>;

fn height_at(uv: vec2<f32>) -> f32 {
    // Texture rows go down; the plane's v goes up.
    let c = textureSampleLevel(height_map, height_sampler, vec2<f32>(uv.x, 1.0 - uv.y), 0.0);
    return select(c.r, dot(c.rgb, vec3<f32>(0.2126, 0.7152, 0.0722)), u.luminance != 0u);
}

// Geomorphing: how far a factor is into its level, 0 just past level − 1 to 1 at the level.
fn morph_fraction(factor: f32, level: u32) -> f32 {
    return clamp(factor - f32(level) + 1.0, 0.0, 1.0);
}

// Where point m of `level` equal parts lies (0–1) when the factor is `phi` into that level: at
// phi = 1 at m / level; at phi = 0 on the level − 1 points, those up to the middle keeping their
// number and those past it taking the one before, so the two middle points start as one — the
// vertices glide instead of popping as the factor grows, and the new triangles start with no
// area. Edges are always walked from their lower vertex, so both patches agree. Mirrored by
// `reference::morphed`.
fn morphed(m: u32, level: u32, phi: f32) -> f32 {
    let exact = f32(m) / f32(level);
    if level <= 1u {
        return exact;
    }
    let coarse = f32(level - 1u);
    let parent = select(f32(m - 1u), f32(m), 2u * m <= level) / coarse;
    return mix(parent, exact, phi);
}

// UV of lattice point (i, j) of a patch of level n: snapped to its edge's level on an edge, and
// geomorphed by the edge's (or, inside, the patch's) fractional factor.
fn lattice_uv(t: Patch, n: u32, i: u32, j: u32) -> vec2<f32> {
    // Corners are the patch's vertices, exactly.
    if i == 0u && j == 0u {
        return base_uv(t.v[0]);
    }
    if i == n && j == 0u {
        return base_uv(t.v[1]);
    }
    if i == 0u && j == n {
        return base_uv(t.v[2]);
    }
    // On edge k, the point is k_along/n of the way from v[k] to v[k+1].
    var k = 3u;
    var along = 0u;
    if j == 0u {
        k = 0u;
        along = i;
    } else if i + j == n {
        k = 1u;
        along = j;
    } else if i == 0u {
        k = 2u;
        along = n - j;
    }
    if k < 3u {
        let start = t.v[k];
        let end = t.v[(k + 1u) % 3u];
        let f = factors_in[t.e[k]];
        let e = level_of(f);
        // The canonical direction (lower vertex first), then the edge's own subdivision:
        // m = round(along · e / n) in integers, the same from both patches of the edge.
        var s = along;
        var a = start;
        var b = end;
        if start > end {
            s = n - along;
            a = end;
            b = start;
        }
        let m = (2u * s * e + n) / (2u * n);
        return mix(base_uv(a), base_uv(b), morphed(m, e, morph_fraction(f, e)));
    }
    // Inside, the patch's own factor, whose level is n.
    let f = vec3<f32>(factors_in[t.e[0]], factors_in[t.e[1]], factors_in[t.e[2]]);
    let phi = morph_fraction(patch_factor(f), n);
    let w1 = morphed(i, n, phi);
    let w2 = morphed(j, n, phi);
    return base_uv(t.v[0]) * (1.0 - w1 - w2) + base_uv(t.v[1]) * w1 + base_uv(t.v[2]) * w2;
}

struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
}

// The displaced surface at `uv`, with the normal of the height field (not the flat plane's).
fn surface_at(uv: vec2<f32>) -> Surface {
    let size = vec2<f32>(textureDimensions(height_map));
    let du = 1.0 / max(size.x, 1.0);
    let dv = 1.0 / max(size.y, 1.0);
    let h = height_at(uv);
    let h_u = (height_at(uv + vec2<f32>(du, 0.0)) - height_at(uv - vec2<f32>(du, 0.0))) / (2.0 * du);
    let h_v = (height_at(uv + vec2<f32>(0.0, dv)) - height_at(uv - vec2<f32>(0.0, dv))) / (2.0 * dv);
    let n = plane_normal();
    let tu = (u.model * vec4<f32>(u.plane_size, 0.0, 0.0, 0.0)).xyz + n * (u.displacement * h_u);
    let tv = (u.model * vec4<f32>(0.0, 0.0, u.plane_size, 0.0)).xyz + n * (u.displacement * h_v);
    var s: Surface;
    s.position = displaced(uv, h);
    s.normal = normalize(cross(tv, tu));
    return s;
}

fn plane_normal() -> vec3<f32> {
    return normalize((u.model * vec4<f32>(0.0, 1.0, 0.0, 0.0)).xyz);
}

// The displaced position at `uv` with height h (one expression, so the compute rasterizer's
// positions are those the vertex shader and the crack test place).
fn displaced(uv: vec2<f32>, h: f32) -> vec3<f32> {
    return world_position(uv) + plane_normal() * (u.displacement * h);
}

// Patch p with offsets[p] ≤ triangle < offsets[p + 1] (binary search; culled patches are empty).
fn find_patch(triangle: u32) -> u32 {
    var lo = 0u;
    var hi = u.patch_count;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if offsets_in[mid] <= triangle {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// The lattice point of corner `corner` of triangle `q` of a patch of level n: the n² triangles are
// laid out as an n×n square, a + b < n "up", else "down" mirrored (a bijection).
fn lattice_point(q: u32, n: u32, corner: u32) -> vec2<u32> {
    let a = q / n;
    let b = q % n;
    if a + b < n {
        return array<vec2<u32>, 3>(vec2<u32>(a, b), vec2<u32>(a + 1u, b), vec2<u32>(a, b + 1u))[corner];
    }
    let i = n - 1u - a;
    let j = n - 1u - b;
    return array<vec2<u32>, 3>(vec2<u32>(i + 1u, j), vec2<u32>(i + 1u, j + 1u), vec2<u32>(i, j + 1u))[corner];
}

// A triangle of the refined mesh: its corners' UVs and its patch's level.
struct RefinedTriangle {
    uv: array<vec2<f32>, 3>,
    level: u32,
}

fn refined_triangle(triangle: u32) -> RefinedTriangle {
    let p = find_patch(triangle);
    let t = patch_of(p);
    let n = levels_in[p];
    let q = triangle - offsets_in[p];
    var out: RefinedTriangle;
    out.level = n;
    for (var k = 0u; k < 3u; k++) {
        let ij = lattice_point(q, n, k);
        out.uv[k] = lattice_uv(t, n, ij.x, ij.y);
    }
    return out;
}

// ---- the crack test: every patch's boundary points, as the vertex shader places them ----

// (patch · 3 + edge) · 65 + along: the displaced position of the point `along`/n of the way
// along edge k (w = 1), or w = 0 past the patch's level.
@group(2) @binding(0) var<storage, read_write> boundary: array<vec4<f32>>;

@compute @workgroup_size(65)
fn evaluate_boundaries(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let slot = group.x;
    let p = slot / 3u;
    let k = slot % 3u;
    let along = lid.x;
    if p >= u.patch_count {
        return;
    }
    let n = levels_in[p];
    let index = slot * 65u + along;
    if n == 0u || along > n {
        boundary[index] = vec4<f32>(0.0);
        return;
    }
    var ij = vec2<u32>(along, 0u);
    if k == 1u {
        ij = vec2<u32>(n - along, along);
    } else if k == 2u {
        ij = vec2<u32>(0u, n - along);
    }
    let s = surface_at(lattice_uv(patch_of(p), n, ij.x, ij.y));
    boundary[index] = vec4<f32>(s.position, 1.0);
}

// ---- drawing ----

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) barycentric: vec3<f32>,
    @location(3) @interpolate(flat) level: u32,
}

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32) -> VertexOut {
    let triangle = vertex / 3u;
    let corner = vertex % 3u;
    let p = find_patch(triangle);
    let t = patch_of(p);
    let n = levels_in[p];
    let ij = lattice_point(triangle - offsets_in[p], n, corner);
    let s = surface_at(lattice_uv(t, n, ij.x, ij.y));
    var out: VertexOut;
    out.clip = u.view_proj * vec4<f32>(s.position, 1.0);
    out.world = s.position;
    out.normal = s.normal;
    out.barycentric = array<vec3<f32>, 3>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0))[corner];
    out.level = n;
    return out;
}

fn level_colour(level: u32) -> vec3<f32> {
    // log2(level) / 6 from blue (1) through green to red (64).
    let x = clamp(log2(f32(max(level, 1u))) / 6.0, 0.0, 1.0);
    return clamp(vec3<f32>(2.0 * x - 0.5, 1.0 - abs(2.0 * x - 1.0), 1.5 - 2.0 * x), vec3<f32>(0.0), vec3<f32>(1.0));
}

// The lit colour of a surface point; `edge` is the smallest barycentric coordinate and `width`
// its change over a pixel (the wireframe view draws a line where edge < width). Shared by the
// fragment shader and the compute rasterizer's resolve.
fn shade(world: vec3<f32>, normal: vec3<f32>, level: u32, edge: f32, width: f32) -> vec3<f32> {
    let view = normalize(u.camera.xyz - world);
    var n = normalize(normal);
    // Two-sided: a back face is lit as seen from the camera.
    if dot(n, view) < 0.0 {
        n = -n;
    }
    let l = normalize(-u.light_dir.xyz);
    let h = normalize(l + view);
    // The book's Blinn-Phong: exponent = specular × 128, scaled by gloss; light colour white.
    var albedo = u.albedo.rgb;
    if u.view_mode == 2u {
        albedo = level_colour(level);
    }
    let diffuse = albedo * max(dot(n, l), 0.0);
    let spec = pow(max(dot(n, h), 0.0), u.specular * 128.0) * u.gloss;
    var colour = u.light_intensity * (diffuse + u.spec_color.rgb * spec);
    if u.view_mode == 1u {
        let line = 1.0 - smoothstep(0.0, 1.5 * width, edge);
        colour = mix(colour, vec3<f32>(0.1, 0.55, 1.0), line);
    }
    return colour;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let edge = min(in.barycentric.x, min(in.barycentric.y, in.barycentric.z));
    return vec4<f32>(shade(in.world, in.normal, in.level, edge, fwidth(edge)), 1.0);
}
