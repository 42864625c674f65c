// Chapter 7's discs and spheres drawn in compute, for GPUs whose raster path is narrow (the
// H100/H200: clearing and resolving a 4× multisampled 4K target with depth takes ~8 ms before
// anything is drawn). A sample's quad faces the camera, so on screen it is an axis-aligned box
// with one depth, and its disc an ellipse found per sample position without any mesh.
// extends: poisson.wgsl
//   raster   one thread per disc walks the pixels of the disc's box (a workgroup per disc
//            where the box is large, queued) and, for each covered sample (the standard
//            locations), keeps the nearest disc with one 64-bit atomicMax of (inverted depth,
//            inverted index) — the pipeline's depth test (less, the first drawn winning a tie)
//            whatever order the threads run in.
//   resolve  one thread per pixel: each sample's disc shaded at the pixel centre as the
//            fragment shader does, stored at the target's precision, and averaged as the
//            multisample resolve does.

struct Raster {
    width: u32,  // image size in pixels
    height: u32,
    count: u32,  // discs drawn
    _pad: u32,
};

@group(1) @binding(0) var<uniform> r: Raster;
@group(1) @binding(1) var<storage, read> discs: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read_write> visibility: array<atomic<u64>>;
@group(1) @binding(3) var<storage, read> visibility_in: array<u64>;
@group(1) @binding(4) var image: texture_storage_2d<rgba16float, write>;
// The large discs' queue: its length, then disc indices (one slot per disc).
@group(1) @binding(5) var<storage, read_write> big_queue: array<atomic<u32>>;
// The large discs' dispatch (x, y, 1).
@group(1) @binding(6) var<storage, read_write> big_args: array<atomic<u32>>;
@group(1) @binding(7) var<storage, read> big_queue_in: array<u32>;

// A disc on screen: centre and signed radii in pixels (y down), depth, and whether the
// pipeline would draw it at all (in front of the camera, between the depth planes).
struct Footprint {
    centre: vec2<f32>,
    radius: vec2<f32>,
    depth: f32,
    drawn: bool,
};

fn to_pixels(clip: vec4<f32>) -> vec2<f32> {
    let ndc = clip.xy / clip.w;
    return vec2<f32>((ndc.x + 1.0) * 0.5 * f32(r.width), (1.0 - ndc.y) * 0.5 * f32(r.height));
}

fn footprint(disc: vec4<f32>) -> Footprint {
    let centre = u.view_proj * vec4<f32>(disc.xyz, 1.0);
    let right = u.view_proj * vec4<f32>(disc.xyz + u.right.xyz * u.draw_radius, 1.0);
    let up = u.view_proj * vec4<f32>(disc.xyz + u.up.xyz * u.draw_radius, 1.0);
    let c = to_pixels(centre);
    let depth = centre.z / centre.w;
    let drawn = centre.w > 0.0 && depth >= 0.0 && depth < 1.0;
    return Footprint(c, vec2<f32>(to_pixels(right).x - c.x, c.y - to_pixels(up).y), depth, drawn);
}

// The quad coordinates ([-1, 1] at the rim, y up) of pixel position p.
fn corner_at(f: Footprint, p: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(p.x - f.centre.x, f.centre.y - p.y) / f.radius;
}

// Discs whose box holds at most this many pixels are covered by their own thread; larger ones
// are queued for a workgroup each.
const INLINE_PIXELS: i32 = 64;
const BIG_THREADS: i32 = 64;

// What one disc's coverage needs: its footprint, its key and the box of pixels with a sample it
// may cover (samples lie within half a pixel of the centre); `pixels` 0 when it covers none.
struct Cover {
    f: Footprint,
    key: u64,
    lo: vec2<i32>,
    size: vec2<i32>,
    pixels: i32,
};

fn cover_setup(index: u32) -> Cover {
    let f = footprint(discs[index]);
    let reach = abs(f.radius) + 0.5;
    let lo = max(vec2<i32>(floor(f.centre - reach)), vec2<i32>(0));
    let hi = min(vec2<i32>(ceil(f.centre + reach)), vec2<i32>(i32(r.width), i32(r.height)) - 1);
    let size = max(hi - lo + 1, vec2<i32>(0));
    let key = (u64(~bitcast<u32>(f.depth)) << 32u) | u64(~index);
    return Cover(f, key, lo, size, select(0, size.x * size.y, f.drawn));
}

// Covers pixels first, first + step, ... of the disc's box.
fn cover_pixels(c: Cover, first: i32, step: i32) {
    let samples = max(u.samples, 1u);
    for (var k = first; k < c.pixels; k += step) {
        let pixel = c.lo + vec2<i32>(k % c.size.x, k / c.size.x);
        let base = (u32(pixel.y) * r.width + u32(pixel.x)) * samples;
        for (var s = 0u; s < samples; s++) {
            let at = vec2<f32>(pixel) + 0.5 + vec2<f32>(sample_offset(samples, s)) / 16.0;
            let corner = corner_at(c.f, at);
            if dot(corner, corner) <= 1.0 {
                atomicMax(&visibility[base + s], c.key);
            }
        }
    }
}

// One thread per disc: small discs covered here, large ones queued for `raster_big`.
@compute @workgroup_size(64)
fn raster(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Rows of at most 65,535 workgroups.
    let index = id.x + id.y * groups.x * 64u;
    if index >= r.count {
        return;
    }
    let c = cover_setup(index);
    if c.pixels <= INLINE_PIXELS {
        cover_pixels(c, 0, 1);
        return;
    }
    let slot = atomicAdd(&big_queue[0], 1u);
    atomicStore(&big_queue[1u + slot], index);
    atomicMax(&big_args[0], min(slot + 1u, 65535u));
    atomicMax(&big_args[1], slot / 65535u + 1u);
}

// One workgroup per queued disc (dispatched indirectly from `big_args`).
@compute @workgroup_size(64)
fn raster_big(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let slot = group.x + group.y * groups.x;
    if slot >= big_queue_in[0] {
        return;
    }
    cover_pixels(cover_setup(big_queue_in[1u + slot]), i32(lane), BIG_THREADS);
}

// A colour as the multisampled target stores it (half floats).
fn as_stored(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(unpack2x16float(pack2x16float(c.rg)), unpack2x16float(pack2x16float(c.bb)).x);
}

@compute @workgroup_size(16, 16)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= r.width || id.y >= r.height {
        return;
    }
    let samples = max(u.samples, 1u);
    let base = (id.y * r.width + id.x) * samples;
    let centre = vec2<f32>(id.xy) + 0.5;
    // Neighbouring samples mostly see the same disc: shade it once for the run.
    var last = 0lu;
    var colour = vec3<f32>(0.0); // the cleared background
    var sum = vec3<f32>(0.0);
    for (var s = 0u; s < samples; s++) {
        let key = visibility_in[base + s];
        if key != last {
            last = key;
            colour = vec3<f32>(0.0);
            if key != 0lu {
                let disc = discs[~u32(key & 0xFFFFFFFFlu)];
                colour = as_stored(disc_colour(corner_at(footprint(disc), centre), order_of(disc.w)));
            }
        }
        sum += colour;
    }
    textureStore(image, id.xy, vec4<f32>(sum / f32(samples), 1.0));
}
