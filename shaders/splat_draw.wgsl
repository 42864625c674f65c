// A draw in compute of primitives that each cover a box of pixels on screen (Poisson's discs,
// the cube field's cubes, the cloth's triangles), for GPUs whose raster path is narrow (the
// H100/H200: a 4× multisampled 4K target with depth costs ~8 ms to clear and resolve before
// anything is drawn).
// The bindings, the steps and the three entry points of the technique's kernels
// (`techniques/splat_draw.rs` binds and dispatches them):
//   raster      one thread per primitive (`splat_index`): a box of up to INLINE_PIXELS it
//               covers itself (`covers_inline`), larger ones are queued;
//   raster_big  dispatched from the queue (`big_job`, `job_span`): a workgroup per CHUNK_PIXELS
//               of a queued primitive's box, up to MAX_CHUNKS, so that a primitive as large as
//               the image still spreads over the GPU while small ones launch few workgroups;
//   resolve     one thread per pixel (`Resolve`): each sample's primitive shaded at the pixel
//               centre once per run of equal keys, stored at the multisampled target's precision
//               (`as_stored`) and averaged as the multisample resolve does.
// The technique's raster shader extends this file and its own, binds its primitives at group 1
// binding 1, and defines the hooks the entry points call, for its primitive type P:
//   splat_primitive(index: u32) -> P     primitive `index` in the form the other hooks take
//   splat_box(p: P) -> PixelBox          the pixels it may cover
//   cover(p: P, b: PixelBox, index: u32, first: i32, step: i32, end: i32)
//                                        keeps (`keep`) its samples in pixels first, first +
//                                        step, … below end of the box
//   splat_shade(key: u32, centre: vec2<f32>) -> vec3<f32>
//                                        the primitive a sample key names, shaded at a pixel
//                                        centre
// This file alone is no whole shader: `indra check` and live reload validate it through the
// files that extend it.
// Each sample keeps the nearest primitive with one 64-bit atomicMax of (depth key, key)
// (`keep`): the same image whatever order the threads run in. Key 0 is the background.
// extends: msaa_samples.wgsl

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
// The large primitives' dispatch (queued, chunks of the largest, rows of 65,535 queued).
@group(1) @binding(6) var<storage, read_write> big_args: array<atomic<u32>>;
@group(1) @binding(7) var<storage, read> big_queue_in: array<u32>;

// Boxes of at most this many pixels are covered by their primitive's own thread.
const INLINE_PIXELS: i32 = 64;
// Threads of a `raster_big` workgroup; the pixels of a box each workgroup covers, and the most
// workgroups one primitive gets (each takes a larger share beyond).
const BIG_THREADS: i32 = 64;
const CHUNK_PIXELS: i32 = 1024;
const MAX_CHUNKS: i32 = 64;

// The workgroups of `raster_big` a box of `pixels` gets.
fn chunks_of(pixels: i32) -> i32 {
    return clamp((pixels + CHUNK_PIXELS - 1) / CHUNK_PIXELS, 1, MAX_CHUNKS);
}

// The primitive of thread `id` of `raster` (rows of at most 65,535 workgroups of 64).
fn splat_index(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * 64u;
}

// Whether primitive `index`, whose box holds `pixels`, is covered by this thread; if not, it
// goes to the queue of `raster_big`.
fn covers_inline(index: u32, pixels: i32) -> bool {
    if pixels <= INLINE_PIXELS {
        return true;
    }
    let slot = atomicAdd(&big_queue[0], 1u);
    atomicStore(&big_queue[1u + slot], index);
    atomicMax(&big_args[0], min(slot + 1u, 65535u));
    atomicMax(&big_args[1], u32(chunks_of(pixels)));
    atomicMax(&big_args[2], slot / 65535u + 1u);
    return false;
}

// One `raster_big` thread: primitive `index` (the primitive count when none), which of its
// chunks, which lane.
struct BigJob {
    index: u32,
    chunk: i32,
    lane: i32,
};

fn big_job(group: vec3<u32>, groups: vec3<u32>, lane: u32) -> BigJob {
    let slot = group.x + group.z * groups.x;
    if slot >= big_queue_in[0] {
        return BigJob(splat.count, 0, 0);
    }
    return BigJob(big_queue_in[1u + slot], i32(group.y), i32(lane));
}

// Pixels first, first + step, … below end of a box.
struct Span {
    first: i32,
    step: i32,
    end: i32,
};

// The pixels of a box of `pixels` that `job`'s thread covers.
fn job_span(job: BigJob, pixels: i32) -> Span {
    let chunks = chunks_of(pixels);
    if job.chunk >= chunks {
        return Span(0, 1, 0);
    }
    let share = (pixels + chunks - 1) / chunks;
    let first = job.chunk * share;
    return Span(first + job.lane, BIG_THREADS, min(first + share, pixels));
}

// Sample s of `pixel` in pixels (y down).
fn sample_position(pixel: vec2<i32>, s: u32) -> vec2<f32> {
    return vec2<f32>(pixel) + 0.5 + vec2<f32>(sample_offset(splat.samples, s)) / 16.0;
}

// Sample s of `pixel` sees primitive `key` at `depth_key` (larger: nearer).
fn keep(pixel: vec2<i32>, s: u32, depth_key: u32, key: u32) {
    let word = (u32(pixel.y) * splat.width + u32(pixel.x)) * splat.samples + s;
    atomicMax(&visibility[word], (u64(depth_key) << 32u) | u64(key));
}

// The pixels of the image with a sample inside the screen rectangle lo..hi (pixels, y down).
struct PixelBox {
    lo: vec2<i32>,
    size: vec2<i32>,
};

fn pixels_around(lo: vec2<f32>, hi: vec2<f32>) -> PixelBox {
    let first = max(vec2<i32>(floor(lo - 0.5)), vec2<i32>(0));
    let last = min(vec2<i32>(ceil(hi + 0.5)), vec2<i32>(i32(splat.width), i32(splat.height)) - 1);
    return PixelBox(first, max(last - first + 1, vec2<i32>(0)));
}

// The screen box of a primitive inside the hull of some corners, grown corner by corner
// (`box_start`, `box_add` with each corner's clip position, then `box_pixels`). An accumulator
// rather than an array of corners: an array passed by value lives in local memory, and with it
// the cube field's raster took 2.8× as long (0.97 against 0.35 ms at 4K on the H200).
struct ScreenBox {
    lo: vec2<f32>,
    hi: vec2<f32>,
    // Corners behind the camera, and all corners.
    behind: u32,
    count: u32,
};

fn box_start() -> ScreenBox {
    return ScreenBox(vec2<f32>(f32(splat.width), f32(splat.height)), vec2<f32>(0.0), 0u, 0u);
}

fn box_add(b: ptr<function, ScreenBox>, clip: vec4<f32>) {
    (*b).count += 1u;
    if clip.w <= 1e-6 {
        (*b).behind += 1u;
        return;
    }
    let ndc = clip.xy / clip.w;
    let p = vec2<f32>((ndc.x + 1.0) * 0.5, (1.0 - ndc.y) * 0.5) * vec2<f32>(f32(splat.width), f32(splat.height));
    (*b).lo = min((*b).lo, p);
    (*b).hi = max((*b).hi, p);
}

// The pixels the primitive may cover: the box's, none when all its corners lie behind the
// camera, the whole image when some do (the primitive reaches round the camera).
fn box_pixels(b: ScreenBox) -> PixelBox {
    if b.behind == b.count {
        return PixelBox(vec2<i32>(0), vec2<i32>(0));
    }
    if b.behind > 0u {
        return pixels_around(vec2<f32>(0.0), vec2<f32>(f32(splat.width), f32(splat.height)));
    }
    return pixels_around(b.lo, b.hi);
}

// Pixel k of a box at `lo`, `width` pixels wide.
fn box_pixel(lo: vec2<i32>, width: i32, k: i32) -> vec2<i32> {
    return lo + vec2<i32>(k % width, k / width);
}

// The key sample s of `pixel` kept (0: the background).
fn sample_key(pixel: vec2<u32>, s: u32) -> u32 {
    return u32(visibility_in[(pixel.y * splat.width + pixel.x) * splat.samples + s] & 0xFFFFFFFFlu);
}

// A colour as the multisampled target stores it (half floats).
fn as_stored(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(unpack2x16float(pack2x16float(c.rg)), unpack2x16float(pack2x16float(c.bb)).x);
}

// One pixel of the resolve: its samples walked in order, each run of equal keys shaded once.
// The technique's resolve is
//     var r = resolve_begin(id.xy);
//     while resolve_next(&r) { resolve_shade(&r, <colour of primitive r.key at r.centre>); }
//     resolve_end(r);
struct Resolve {
    pixel: vec2<u32>,
    centre: vec2<f32>, // the pixel centre, where primitives are shaded
    inside: bool,      // the pixel lies in the image
    s: u32,            // the next sample
    key: u32,          // the primitive to shade now
    last: u32,         // the key of the run so far (0: the background)
    colour: vec3<f32>, // its colour as stored
    sum: vec3<f32>,
};

fn resolve_begin(pixel: vec2<u32>) -> Resolve {
    let inside = pixel.x < splat.width && pixel.y < splat.height;
    // The background is stored as a clear is, unrounded.
    return Resolve(pixel, vec2<f32>(pixel) + 0.5, inside, 0u, 0u, 0u, splat.background.rgb, vec3<f32>(0.0));
}

// Adds the samples that repeat the run's key or show the background; true when sample
// r.s - 1 starts a run of primitive r.key, to be shaded by `resolve_shade`.
fn resolve_next(r: ptr<function, Resolve>) -> bool {
    while (*r).inside && (*r).s < splat.samples {
        let key = sample_key((*r).pixel, (*r).s);
        (*r).s += 1u;
        if key != (*r).last {
            (*r).last = key;
            if key != 0u {
                (*r).key = key;
                return true;
            }
            (*r).colour = splat.background.rgb;
        }
        (*r).sum += (*r).colour;
    }
    return false;
}

// The colour `c` of the run `resolve_next` started.
fn resolve_shade(r: ptr<function, Resolve>, c: vec3<f32>) {
    (*r).colour = as_stored(c);
    (*r).sum += (*r).colour;
}

// Stores the mean of the pixel's samples.
fn resolve_end(r: Resolve) {
    if r.inside {
        textureStore(image, r.pixel, vec4<f32>(r.sum / f32(splat.samples), 1.0));
    }
}

@compute @workgroup_size(64)
fn raster(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let index = splat_index(id, groups);
    if index >= splat.count {
        return;
    }
    let p = splat_primitive(index);
    let b = splat_box(p);
    if covers_inline(index, b.size.x * b.size.y) {
        cover(p, b, index, 0, 1, INLINE_PIXELS);
    }
}

@compute @workgroup_size(64)
fn raster_big(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let job = big_job(group, groups, lane);
    if job.index < splat.count {
        let p = splat_primitive(job.index);
        let b = splat_box(p);
        let span = job_span(job, b.size.x * b.size.y);
        cover(p, b, job.index, span.first, span.step, span.end);
    }
}

@compute @workgroup_size(16, 16)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    var r = resolve_begin(id.xy);
    while resolve_next(&r) {
        resolve_shade(&r, splat_shade(r.key, r.centre));
    }
    resolve_end(r);
}
