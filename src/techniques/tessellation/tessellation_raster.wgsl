// Chapter 6's draw in compute: a visibility buffer, for GPUs whose raster path is narrow (the
// H100/H200 clear and resolve a 4× multisampled 4K target in ~6 ms before drawing anything).
// Built after tessellation.wgsl (the lattice, the surface and the shading come from there; the
// line below joins them); needs 64-bit atomics (SHADER_INT64_ATOMIC_MIN_MAX), so it is a module
// of its own.
// extends: tessellation.wgsl
//   raster      one thread per refined triangle: evaluates its three corners as the vertex shader
//               does, clips it at the near plane, snaps it to 1/16 px and tests the standard
//               sample positions of each pixel it may cover; a covered sample keeps the nearest
//               triangle with one 64-bit atomicMax of (inverted depth, triangle + 1) — the same
//               result in any order, so renders are deterministic. Triangles whose box exceeds
//               16×16 px go to a queue instead.
//   raster_big  one 8×8 workgroup per queued triangle, walking its box.
//   resolve     one thread per pixel: shades each distinct triangle among its samples at the
//               pixel centre (as multisampling shades once per pixel and triangle), averages;
//               the raster pass keeps each triangle's corners for it where memory allows.
// Coverage uses integer edge functions with a tie rule, so an edge shared by two triangles gives
// each of its samples to exactly one of them: no cracks, no double hits.

struct Raster {
    width: u32,
    height: u32,
    samples: u32,
    big_capacity: u32,
    // 1: the raster pass keeps each triangle's corners in `corners` for the resolve.
    cached: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// One queued large triangle: snapped corners (x0, y0, x1, y1), (x2, y2, id, 0), NDC depths.
struct BigTriangle {
    v01: vec4<i32>,
    v2_id: vec4<i32>,
    z: vec4<f32>,
}

@group(2) @binding(0) var<uniform> r: Raster;
@group(2) @binding(1) var<storage, read_write> visibility: array<atomic<u64>>;
@group(2) @binding(2) var<storage, read_write> big_triangles: array<BigTriangle>;
// The queue's dispatch (x, 1, 1) and its length (x and the length zeroed before each frame;
// x ≤ capacity).
@group(2) @binding(3) var<storage, read_write> big_args: array<atomic<u32>>;
@group(2) @binding(4) var<storage, read> visibility_in: array<u64>;
@group(2) @binding(5) var image: texture_storage_2d<rgba16float, write>;
// Each triangle's corners as the resolve shades them: 3 × (position, level), 3 × (normal, 0).
// Evaluating a corner takes five height samples and the lattice; a pixel shades 1–4 triangles.
@group(2) @binding(6) var<storage, read_write> corners: array<vec4<f32>>;
@group(2) @binding(7) var<storage, read> corners_in: array<vec4<f32>>;

const CORNER_VEC4S: u32 = 6u;

// Subpixel steps per pixel: Vulkan's standard sample positions are in sixteenths.
const SUBPIXEL: f32 = 16.0;
// Snapped coordinates are clamped to ±2^24 sixteenths (1M px): edge products fit in i64.
const SNAP_LIMIT: f32 = 16777216.0;
// A triangle whose box holds more pixels than this goes to the queue.
const INLINE_PIXELS: i32 = 256;

// A triangle ready for coverage: corners in sixteenths of a pixel (y down) relative to `origin`,
// counter-clockwise in that frame (positive area), NDC depths, and 1 + its index in the mesh.
// Edge functions are translation-invariant in integers, so a triangle measured from its own
// corner gets exactly the values it would get from the image's corner — in i32 when it is small.
struct Setup {
    origin: vec2<i32>,
    v0: vec2<i32>,
    v1: vec2<i32>,
    v2: vec2<i32>,
    z: vec3<f32>,
    area: f32,
    key: u32,
}

fn snap(c: vec4<f32>) -> vec2<i32> {
    let ndc = c.xy / c.w;
    let px = vec2<f32>((ndc.x * 0.5 + 0.5) * f32(r.width), (0.5 - ndc.y * 0.5) * f32(r.height));
    return vec2<i32>(round(clamp(px * SUBPIXEL, vec2<f32>(-SNAP_LIMIT), vec2<f32>(SNAP_LIMIT))));
}

// Twice the signed area of (a, b, p), exactly.
fn edge(a: vec2<i32>, b: vec2<i32>, p: vec2<i32>) -> i64 {
    return i64(b.x - a.x) * i64(p.y - a.y) - i64(b.y - a.y) * i64(p.x - a.x);
}

// The same for a triangle spanning at most 2^14 sixteenths (1,024 px) measured from its corner:
// every product stays below 2^29.
fn edge32(a: vec2<i32>, b: vec2<i32>, p: vec2<i32>) -> i32 {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Whether an edge a → b takes the points on it: when it points down or, level, left. An edge
// shared by two triangles runs opposite ways in each, so exactly one of them takes its samples.
fn takes_ties(a: vec2<i32>, b: vec2<i32>) -> bool {
    let d = b - a;
    return d.y > 0 || (d.y == 0 && d.x < 0);
}

// The pixel box [min, max] of a setup, clamped to the image (empty: min > max).
fn pixel_box(s: Setup) -> vec4<i32> {
    let lo = s.origin + min(s.v0, min(s.v1, s.v2));
    let hi = s.origin + max(s.v0, max(s.v1, s.v2));
    // Sample x = 16 px + 8 + offset with |offset| ≤ 8: pixels from (lo − 16) / 16 to hi / 16.
    let first = max((lo - vec2<i32>(16)) >> vec2<u32>(4u), vec2<i32>(0));
    let last = min(hi >> vec2<u32>(4u), vec2<i32>(i32(r.width) - 1, i32(r.height) - 1));
    return vec4<i32>(first, last);
}

// Keeps the nearest triangle at sample word `index`: e are the three edge values at the sample.
fn keep(s: Setup, index: u32, e: vec3<f32>) {
    let depth = dot(e, s.z) / s.area;
    if depth <= 1.0 {
        let inverted = ~bitcast<u32>(max(depth, 0.0));
        atomicMax(&visibility[index], (u64(inverted) << 32u) | u64(s.key));
    }
}

// The sample k of pixel (x, y) relative to the setup's origin.
fn sample_at(s: Setup, x: i32, y: i32, k: u32) -> vec2<i32> {
    return vec2<i32>(x * 16 + 8, y * 16 + 8) + sample_offset(r.samples, k) - s.origin;
}

// Tests every sample of pixel (x, y) against a small setup (i32 edge values).
fn cover_pixel32(s: Setup, x: i32, y: i32) {
    let base = (u32(y) * r.width + u32(x)) * r.samples;
    let ties = vec3<bool>(takes_ties(s.v1, s.v2), takes_ties(s.v2, s.v0), takes_ties(s.v0, s.v1));
    for (var k = 0u; k < r.samples; k++) {
        let p = sample_at(s, x, y, k);
        let e = vec3<i32>(edge32(s.v1, s.v2, p), edge32(s.v2, s.v0, p), edge32(s.v0, s.v1, p));
        if all((e > vec3<i32>(0)) | ((e == vec3<i32>(0)) & ties)) {
            keep(s, base + k, vec3<f32>(e));
        }
    }
}

// Tests every sample of pixel (x, y) against any setup (i64 edge values).
fn cover_pixel64(s: Setup, x: i32, y: i32) {
    let base = (u32(y) * r.width + u32(x)) * r.samples;
    let ties = vec3<bool>(takes_ties(s.v1, s.v2), takes_ties(s.v2, s.v0), takes_ties(s.v0, s.v1));
    for (var k = 0u; k < r.samples; k++) {
        let p = sample_at(s, x, y, k);
        let e0 = edge(s.v1, s.v2, p);
        let e1 = edge(s.v2, s.v0, p);
        let e2 = edge(s.v0, s.v1, p);
        let positive = vec3<bool>(e0 > 0li, e1 > 0li, e2 > 0li);
        let zero = vec3<bool>(e0 == 0li, e1 == 0li, e2 == 0li);
        if all(positive | (zero & ties)) {
            keep(s, base + k, vec3<f32>(f32(e0), f32(e1), f32(e2)));
        }
    }
}

fn cover_box(s: Setup, box: vec4<i32>, first: vec2<i32>, step: i32) {
    for (var y = box.y + first.y; y <= box.w; y += step) {
        for (var x = box.x + first.x; x <= box.z; x += step) {
            cover_pixel64(s, x, y);
        }
    }
}

// Covers the triangle of clip-space corners a, b, c (all in front of the near plane).
fn cover(key: u32, a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) {
    var s: Setup;
    s.v0 = snap(a);
    s.v1 = snap(b);
    s.v2 = snap(c);
    s.z = vec3<f32>(a.z / a.w, b.z / b.w, c.z / c.w);
    s.key = key;
    let area = edge(s.v0, s.v1, s.v2);
    if area == 0li {
        return;
    }
    if area < 0li {
        // Two-sided: the same triangle, wound the other way.
        let v = s.v1;
        s.v1 = s.v2;
        s.v2 = v;
        s.z = s.z.xzy;
    }
    s.area = abs(f32(area));
    let box = pixel_box(s);
    if box.x > box.z || box.y > box.w {
        return;
    }
    let span = max(s.v0, max(s.v1, s.v2)) - min(s.v0, min(s.v1, s.v2));
    let small = max(span.x, span.y) <= 16384;
    if small && (box.z - box.x + 1) * (box.w - box.y + 1) <= INLINE_PIXELS {
        // Measured from its first corner.
        s.origin = s.v0;
        s.v1 -= s.origin;
        s.v2 -= s.origin;
        s.v0 = vec2<i32>(0);
        for (var y = box.y; y <= box.w; y++) {
            for (var x = box.x; x <= box.z; x++) {
                cover_pixel32(s, x, y);
            }
        }
        return;
    }
    let slot = atomicAdd(&big_args[3], 1u);
    if slot < r.big_capacity {
        atomicMax(&big_args[0], slot + 1u);
        big_triangles[slot] = BigTriangle(
            vec4<i32>(s.v0, s.v1),
            vec4<i32>(s.v2, bitcast<i32>(key), 0),
            vec4<f32>(s.z, s.area),
        );
        return;
    }
    cover_box(s, box, vec2<i32>(0), 1);
}

// Where edge (inside, outside) crosses the near plane z = 0, computed from the inside end, so
// the two triangles of a shared edge get the same point.
fn near_point(inside: vec4<f32>, outside: vec4<f32>) -> vec4<f32> {
    return mix(inside, outside, inside.z / (inside.z - outside.z));
}

fn corner_clip(uv: vec2<f32>) -> vec4<f32> {
    return u.view_proj * vec4<f32>(displaced(uv, height_at(uv)), 1.0);
}

@compute @workgroup_size(64)
fn raster(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let triangle = id.y * groups.x * 64u + id.x;
    if triangle >= offsets_in[u.patch_count] {
        return;
    }
    let t = refined_triangle(triangle);
    var clip: array<vec4<f32>, 3>;
    if r.cached != 0u {
        let base = triangle * CORNER_VEC4S;
        for (var k = 0u; k < 3u; k++) {
            let s = surface_at(t.uv[k]);
            corners[base + k] = vec4<f32>(s.position, f32(t.level));
            corners[base + 3u + k] = vec4<f32>(s.normal, 0.0);
            clip[k] = u.view_proj * vec4<f32>(s.position, 1.0);
        }
    } else {
        clip = array<vec4<f32>, 3>(corner_clip(t.uv[0]), corner_clip(t.uv[1]), corner_clip(t.uv[2]));
    }
    // Clip at the near plane (Sutherland–Hodgman): 3 or 4 corners, drawn as a fan.
    var polygon: array<vec4<f32>, 4>;
    var count = 0u;
    for (var k = 0u; k < 3u; k++) {
        let a = clip[k];
        let b = clip[(k + 1u) % 3u];
        if a.z >= 0.0 {
            polygon[count] = a;
            count++;
        }
        if (a.z >= 0.0) != (b.z >= 0.0) {
            polygon[count] = select(near_point(b, a), near_point(a, b), a.z >= 0.0);
            count++;
        }
    }
    if count >= 3u {
        cover(triangle + 1u, polygon[0], polygon[1], polygon[2]);
    }
    if count == 4u {
        cover(triangle + 1u, polygon[0], polygon[2], polygon[3]);
    }
}

@compute @workgroup_size(8, 8)
fn raster_big(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let b = big_triangles[group.x];
    var s: Setup;
    s.v0 = b.v01.xy;
    s.v1 = b.v01.zw;
    s.v2 = b.v2_id.xy;
    s.key = bitcast<u32>(b.v2_id.z);
    s.z = b.z.xyz;
    s.area = b.z.w;
    cover_box(s, pixel_box(s), vec2<i32>(lid.xy), 8);
}

// Perspective-correct barycentric weights of the NDC point `ndc` in the triangle of clip-space
// corners c (valid also when a corner lies behind the camera): λ with Σλ(c.xy − ndc·c.w) = 0.
fn perspective_weights(c: array<vec4<f32>, 3>, ndc: vec2<f32>) -> vec3<f32> {
    let a = vec3<f32>(c[0].x - ndc.x * c[0].w, c[1].x - ndc.x * c[1].w, c[2].x - ndc.x * c[2].w);
    let b = vec3<f32>(c[0].y - ndc.y * c[0].w, c[1].y - ndc.y * c[1].w, c[2].y - ndc.y * c[2].w);
    let w = cross(a, b);
    let sum = w.x + w.y + w.z;
    return select(vec3<f32>(1.0 / 3.0), w / sum, abs(sum) > 1e-30);
}

fn smallest(v: vec3<f32>) -> f32 {
    return min(v.x, min(v.y, v.z));
}

// The colour of triangle `triangle` at the centre of pixel `pixel`.
fn shade_triangle(triangle: u32, pixel: vec2<u32>) -> vec3<f32> {
    var s: array<Surface, 3>;
    var level: u32;
    if r.cached != 0u {
        let base = triangle * CORNER_VEC4S;
        for (var k = 0u; k < 3u; k++) {
            let p = corners_in[base + k];
            s[k] = Surface(p.xyz, corners_in[base + 3u + k].xyz);
            level = u32(p.w);
        }
    } else {
        let t = refined_triangle(triangle);
        s = array<Surface, 3>(surface_at(t.uv[0]), surface_at(t.uv[1]), surface_at(t.uv[2]));
        level = t.level;
    }
    var clip: array<vec4<f32>, 3>;
    for (var k = 0u; k < 3u; k++) {
        clip[k] = u.view_proj * vec4<f32>(s[k].position, 1.0);
    }
    let size = vec2<f32>(f32(r.width), f32(r.height));
    let centre = (vec2<f32>(pixel) + 0.5) / size;
    let ndc = vec2<f32>(centre.x * 2.0 - 1.0, 1.0 - centre.y * 2.0);
    let l = perspective_weights(clip, ndc);
    // The wireframe's line width: how much the smallest weight changes over one pixel.
    let edge = smallest(l);
    let dx = smallest(perspective_weights(clip, ndc + vec2<f32>(2.0 / size.x, 0.0))) - edge;
    let dy = smallest(perspective_weights(clip, ndc - vec2<f32>(0.0, 2.0 / size.y))) - edge;
    let world = s[0].position * l.x + s[1].position * l.y + s[2].position * l.z;
    let normal = s[0].normal * l.x + s[1].normal * l.y + s[2].normal * l.z;
    return shade(world, normal, level, edge, abs(dx) + abs(dy));
}

// The triangle key (1 + index, 0: none) of sample word i.
fn key_at(i: u32) -> u32 {
    return u32(visibility_in[i] & 0xFFFFFFFFlu);
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= r.width || id.y >= r.height {
        return;
    }
    let base = (id.y * r.width + id.x) * r.samples;
    // Each distinct triangle among the samples is shaded once (key 0: the background) and
    // weighted by the samples it covers; no per-invocation arrays (they would live in slow
    // local memory), the keys are read again instead.
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < r.samples; k++) {
        let key = key_at(base + k);
        var first = true;
        for (var j = 0u; j < k; j++) {
            first = first && key_at(base + j) != key;
        }
        if !first {
            continue;
        }
        var count = 1u;
        for (var j = k + 1u; j < r.samples; j++) {
            count += u32(key_at(base + j) == key);
        }
        var colour = u.background.rgb;
        if key != 0u {
            colour = shade_triangle(key - 1u, id.xy);
        }
        sum += colour * f32(count);
    }
    textureStore(image, id.xy, vec4<f32>(sum / f32(r.samples), 1.0));
}
