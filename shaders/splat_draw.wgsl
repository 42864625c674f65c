// A draw in compute of primitives that each cover a box of pixels on screen (Poisson's discs),
// for GPUs whose raster path is narrow (the H100/H200: a 4× multisampled 4K
// target with depth costs ~8 ms to clear and resolve before anything is drawn). Joined before the
// technique's shaders (`techniques/splat_draw.rs`), which provide:
//   fn primitive_pixels(index: u32) -> i32                the pixels in primitive `index`'s box
//                                                         (0: it draws nothing)
//   fn cover(index: u32, first: i32, step: i32)           tests pixels first, first + step, … of
//                                                         that box, calling `keep` per sample hit
//   fn shade(key: u32, centre: vec2<f32>) -> vec3<f32>    the colour of the primitive `key` names,
//                                                         at a pixel centre
//   @group(1) @binding(1) the primitives
// and group 0 (the technique's own uniforms).
//   raster      one thread per primitive covers a box of up to INLINE_PIXELS itself; larger
//               ones are queued for a workgroup each (`raster_big`, dispatched indirectly).
//   resolve     one thread per pixel: each sample's primitive shaded at the pixel centre (once
//               per run of equal keys), stored at the multisampled target's precision (half
//               floats) and averaged as the multisample resolve does.
// Each sample keeps the nearest primitive with one 64-bit atomicMax of (depth key, key): the same
// image whatever order the threads run in. Key 0 is the background.

struct Splat {
    width: u32,        // image size in pixels
    height: u32,
    count: u32,        // primitives drawn
    samples: u32,      // samples per pixel (the standard locations)
    background: vec4<f32>, // linear colour where nothing is drawn
};

@group(1) @binding(0) var<uniform> splat: Splat;
@group(1) @binding(2) var<storage, read_write> visibility: array<atomic<u64>>;
@group(1) @binding(3) var<storage, read> visibility_in: array<u64>;
@group(1) @binding(4) var image: texture_storage_2d<rgba16float, write>;
// The large primitives' queue: its length, then primitive indices (one slot per primitive).
@group(1) @binding(5) var<storage, read_write> big_queue: array<atomic<u32>>;
// The large primitives' dispatch (x, y, 1).
@group(1) @binding(6) var<storage, read_write> big_args: array<atomic<u32>>;
@group(1) @binding(7) var<storage, read> big_queue_in: array<u32>;

// Boxes of at most this many pixels are covered by their primitive's own thread.
const INLINE_PIXELS: i32 = 64;
const BIG_THREADS: i32 = 64;

// Sample s of `pixel` in pixels (y down).
fn sample_position(pixel: vec2<i32>, s: u32) -> vec2<f32> {
    return vec2<f32>(pixel) + 0.5 + vec2<f32>(sample_offset(splat.samples, s)) / 16.0;
}

// Sample s of `pixel` sees primitive `key` at `depth_key` (larger: nearer).
fn keep(pixel: vec2<i32>, s: u32, depth_key: u32, key: u32) {
    let word = (u32(pixel.y) * splat.width + u32(pixel.x)) * splat.samples + s;
    atomicMax(&visibility[word], (u64(depth_key) << 32u) | u64(key));
}

// Pixel k of a box at `lo`, `width` pixels wide.
fn box_pixel(lo: vec2<i32>, width: i32, k: i32) -> vec2<i32> {
    return lo + vec2<i32>(k % width, k / width);
}

@compute @workgroup_size(64)
fn raster(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Rows of at most 65,535 workgroups.
    let index = id.x + id.y * groups.x * 64u;
    if index >= splat.count {
        return;
    }
    let pixels = primitive_pixels(index);
    if pixels <= INLINE_PIXELS {
        cover(index, 0, 1);
        return;
    }
    let slot = atomicAdd(&big_queue[0], 1u);
    atomicStore(&big_queue[1u + slot], index);
    atomicMax(&big_args[0], min(slot + 1u, 65535u));
    atomicMax(&big_args[1], slot / 65535u + 1u);
}

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
    cover(big_queue_in[1u + slot], i32(lane), BIG_THREADS);
}

// A colour as the multisampled target stores it (half floats).
fn as_stored(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(unpack2x16float(pack2x16float(c.rg)), unpack2x16float(pack2x16float(c.bb)).x);
}

@compute @workgroup_size(16, 16)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= splat.width || id.y >= splat.height {
        return;
    }
    let base = (id.y * splat.width + id.x) * splat.samples;
    let centre = vec2<f32>(id.xy) + 0.5;
    var last = 0u;
    var colour = as_stored(splat.background.rgb);
    var sum = vec3<f32>(0.0);
    for (var s = 0u; s < splat.samples; s++) {
        let key = u32(visibility_in[base + s] & 0xFFFFFFFFlu);
        if key != last {
            last = key;
            colour = as_stored(splat.background.rgb);
            if key != 0u {
                colour = as_stored(shade(key, centre));
            }
        }
        sum += colour;
    }
    textureStore(image, id.xy, vec4<f32>(sum / f32(splat.samples), 1.0));
}
