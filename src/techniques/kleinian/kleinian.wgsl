// Limit sets of Kleinian groups (Maskit slice) by Jos Leys' escape-time test [UGP4 ch.2],
// [Leys, "Kleinian escape-time", josleys.com]. One invocation per output pixel; dispatched over
// the output extent (`render`), or adaptively: `corners`, then `render_edges`. Writes linear
// colour to an rgba16float storage texture.
//
// Corrections to the book's sample (seed-reference §9 items 8-11): the shear uses signed v; the
// strip test (y < 0 or y > u: outside) runs up front; position = uv * scale + offset everywhere;
// anti-aliasing jitter is centred on the pixel and one pixel wide at any scale.

struct KleinianUniforms {
    t: vec2<f32>,              // (u, v): the Maskit parameter t = u + iv
    scale: f32,                // fractal units per output height
    iterations: u32,           // escape-time cap
    offset: vec2<f32>,         // fractal position of the bottom-left corner
    samples: u32,              // jittered samples per pixel (1 = pixel centre)
    inversion: u32,            // 1 = circle inversion before the test
    circle_center: vec2<f32>,  // inversion circle centre, fractal units
    circle_radius: f32,        // inversion circle radius
    seed: u32,                 // scene seed for the jitter pattern
    hit_color: vec4<f32>,      // linear RGBA inside the limit set's disks
    back_color: vec4<f32>,     // linear RGBA elsewhere
    size: vec2<u32>,           // output size in pixels
    _pad: vec2<u32>,
};

@group(0) @binding(0) var<uniform> params: KleinianUniforms;
@group(0) @binding(1) var output: texture_storage_2d<rgba16float, write>;

// Wraps x into [left, left + width).
fn wrap(x: f32, width: f32, left: f32) -> f32 {
    let shifted = x - left;
    return shifted - width * floor(shifted / width) + left;
}

// Loop invariants of the escape-time test, derived once per sample from t = u + iv.
struct Slice {
    u: f32,
    v: f32,
    shear: f32,        // v / u: Line 1's slope factor
    rotation: vec2<f32>, // (-v, u): the centre of the 180° turn (doubled) and a's translation
    bend: f32,         // sign(v) (2u - 1.95) / 4: the separation line's amplitude
    decay: f32,        // -(7.2 - (1.95 - u) 15): the separation line's exponent per unit of |d|
    band_low: f32,     // u/2 - |bend|: the separation line never runs below this height
    band_high: f32,    // u/2 + |bend|: ... nor above this one
};

fn slice_of(t: vec2<f32>) -> Slice {
    let u = t.x;
    let v = t.y;
    let bend = sign(v) * (2.0 * u - 1.95) / 4.0;
    let decay = -(7.2 - (1.95 - u) * 15.0);
    // With a growing exponent (u < 1.47) the line is unbounded: no band, always evaluate it.
    let bounded = decay <= 0.0;
    let band_low = select(-3.4e38, u * 0.5 - abs(bend), bounded);
    let band_high = select(3.4e38, u * 0.5 + abs(bend), bounded);
    return Slice(u, v, v / u, vec2<f32>(-v, u), bend, decay, band_low, band_high);
}

// Step 3's test: is z above Leys' empirical separation line (Line 3)?
fn above_separation(z: vec2<f32>, s: Slice) -> bool {
    // With a decaying exponent the line stays within u/2 ± |bend| (a few thousandths of u for
    // the book's t); rounding is monotonic, so the computed line stays inside the computed band
    // and the exp is only paid inside it. The answer is the same bit for bit.
    if (z.y >= s.band_high) {
        return true;
    }
    if (z.y < s.band_low) {
        return false;
    }
    let d = z.x + s.v * 0.5;
    return z.y >= s.u * 0.5 + s.bend * sign(d) * (1.0 - exp(s.decay * abs(d)));
}

// Steps 2-4 of one iteration: into the central parallelogram, the reflection above Line 3, then
// transformation a.
fn escape_step(start: vec2<f32>, s: Slice) -> vec2<f32> {
    var z = start;
    // Step 2: into the central parallelogram between Lines 1 and 2 (shear by signed v).
    let shear = s.shear * z.y;
    z.x = wrap(z.x + shear, 2.0, -1.0) - shear;
    // Step 3: above Line 3, reflect through (-v/2, u/2).
    if (above_separation(z, s)) {
        z = s.rotation - z;
    }
    // Step 4: transformation a.
    return vec2<f32>(z.x, -z.y) / dot(z, z) + s.rotation;
}

// Step 6: a 2-cycle across Line 3 means the point never escapes: not in the set. (Squared
// distance against 1e-6 squared: the same test without a square root.)
fn closes_cycle(z: vec2<f32>, two_back: vec2<f32>) -> bool {
    let d = z - two_back;
    return dot(d, d) < 1e-12;
}

// True when z lies in one of the disks bounded by the limit set (drawn in the hit colour).
// Step 5 follows every step: below y = 0 means inside the largest disk.
fn in_limit_set(start: vec2<f32>, t: vec2<f32>, iterations: u32) -> bool {
    let s = slice_of(t);
    // Algorithm step 1: the limit set lies in the strip 0 <= y <= u.
    if (start.y < 0.0 || start.y > s.u || iterations == 0u) {
        return false;
    }
    // The first step's cycle test compares against start - (1, 1), the second's against
    // start + (1, 1): Leys' seeds for the two points before the start.
    let first = escape_step(start, s);
    if (first.y < 0.0) {
        return true;
    }
    if (closes_cycle(first, start - vec2<f32>(1.0, 1.0))) {
        return false;
    }
    // Two steps per trip, each replacing the older of the last two points (the one its cycle
    // test needs), so no point is copied from register to register: 5% at 4K, 10 samples.
    var older = start + vec2<f32>(1.0, 1.0);
    var newer = first;
    var done = 1u;
    loop {
        if (done >= iterations) {
            break;
        }
        let z = escape_step(newer, s);
        if (z.y < 0.0) {
            return true;
        }
        if (closes_cycle(z, older)) {
            return false;
        }
        older = z;
        if (done + 1u >= iterations) {
            break;
        }
        let w = escape_step(older, s);
        if (w.y < 0.0) {
            return true;
        }
        if (closes_cycle(w, newer)) {
            return false;
        }
        newer = w;
        done = done + 2u;
    }
    return false;
}

fn circle_inverse(p: vec2<f32>, center: vec2<f32>, radius: f32) -> vec2<f32> {
    let d = p - center;
    return center + d * (radius * radius) / max(dot(d, d), 1e-30);
}

// PCG-style 2-D hash (Jarzynski & Olano 2020) -> two floats in [0, 1).
fn hash2(key: vec3<u32>) -> vec2<f32> {
    var v = key * 1664525u + 1013904223u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v ^= v >> vec3<u32>(16u);
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    return vec2<f32>(v.xy >> vec2<u32>(8u)) / 16777216.0;
}

// The fractal-plane point at `pixel` (output pixel units, origin top-left): uv has its origin
// bottom-left and spans 0..1 vertically (x scaled by the aspect), then the optional inversion.
fn plane_point(pixel: vec2<f32>) -> vec2<f32> {
    let height = f32(params.size.y);
    let uv = vec2<f32>(pixel.x / height, 1.0 - pixel.y / height);
    let p = uv * params.scale + params.offset;
    if (params.inversion != 0u) {
        return circle_inverse(p, params.circle_center, params.circle_radius);
    }
    return p;
}

// The colour of a sample: the hit colour inside the set's disks.
fn class_color(hit: bool) -> vec4<f32> {
    return select(params.back_color, params.hit_color, hit);
}

// Sample `s` of a pixel: at the centre for a single-sample render, otherwise uniform jitter
// over the pixel's own square.
fn sample_hits(id: vec2<u32>, s: u32) -> bool {
    var jitter = vec2<f32>(0.0);
    if (params.samples > 1u) {
        jitter = hash2(vec3<u32>(id.x, id.y, s ^ (params.seed * 747796405u))) - 0.5;
    }
    let p = plane_point(vec2<f32>(f32(id.x), f32(id.y)) + 0.5 + jitter);
    return in_limit_set(p, params.t, params.iterations);
}

// The mean colour of the pixel's samples, given the sum of those before `first`.
fn sampled_color(id: vec2<u32>, first: u32, sum_before: vec4<f32>) -> vec4<f32> {
    let samples = max(params.samples, 1u);
    var sum = sum_before;
    for (var s = first; s < samples; s = s + 1u) {
        sum += class_color(sample_hits(id, s));
    }
    return sum / f32(samples);
}

// Every sample of every pixel; dispatched over the output extent.
@compute @workgroup_size(8, 8, 1)
fn render(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.size.x || id.y >= params.size.y) {
        return;
    }
    textureStore(output, vec2<i32>(id.xy), sampled_color(id.xy, 0u, vec4<f32>(0.0)));
}

// Adaptive sampling (from 4 samples up): the class of every pixel corner, then one sample per
// pixel, and the rest of the samples only where a pixel's 4 × 4 neighbourhood of corners is not
// all one class or its first sample disagrees with them. At 4K and the book's t 2% of pixels are
// such edges; the rest take their corners' colour.

// Corner classes, one bit each, with a margin of one corner on every side so that no read
// needs clamping: row j (0..=height + 2) holds corners i = 0..=width + 2 at pixel-space point
// (i - 1, j - 1), bit i % 32 of word i / 32 of the row's `corner_words`.
@group(0) @binding(2) var<storage, read_write> corner_bits: array<u32>;

fn corner_words() -> u32 {
    return (params.size.x + 34u) / 32u;
}

var<workgroup> corner_rows: array<atomic<u32>, 8>;

// One invocation per stored corner ((width + 3) × (height + 3)); a row of 32 lanes packs its
// word in workgroup memory, so no buffer has to be cleared first.
@compute @workgroup_size(32, 8, 1)
fn corners(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    if (local.x == 0u) {
        atomicStore(&corner_rows[local.y], 0u);
    }
    workgroupBarrier();
    let inside = id.x < params.size.x + 3u && id.y < params.size.y + 3u;
    let point = vec2<f32>(id.xy) - 1.0;
    if (inside && in_limit_set(plane_point(point), params.t, params.iterations)) {
        atomicOr(&corner_rows[local.y], 1u << local.x);
    }
    workgroupBarrier();
    if (local.x == 0u && id.y < params.size.y + 3u) {
        corner_bits[id.y * corner_words() + id.x / 32u] = atomicLoad(&corner_rows[local.y]);
    }
}

// Four stored corners of row `row` from column `first` on, as bits 0..3.
fn four_corners(row: u32, first: u32) -> u32 {
    let word = row * corner_words() + first / 32u;
    let shift = first % 32u;
    var bits = corner_bits[word] >> shift;
    if (shift > 28u) {
        bits |= corner_bits[word + 1u] << (32u - shift);
    }
    return bits & 15u;
}

// One invocation per output pixel, after `corners`.
@compute @workgroup_size(8, 8, 1)
fn render_edges(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.size.x || id.y >= params.size.y) {
        return;
    }
    // Pixel (x, y) has corners x..x+1, y..y+1; its neighbours' reach one further each way:
    // stored columns and rows x..x+3, y..y+3.
    var all = 15u;
    var any = 0u;
    for (var r = 0u; r < 4u; r = r + 1u) {
        let row = four_corners(id.y + r, id.x);
        all &= row;
        any |= row;
    }
    // Sample 0 is taken everywhere. Where the corners are all one class and it agrees, that
    // class is the pixel's colour; otherwise the pixel takes the rest of its samples: an edge,
    // or a feature that slipped between the corners (the gap where two disks touch, a disk
    // smaller than a pixel).
    let first = sample_hits(id.xy, 0u);
    let one_class = all == 15u || any == 0u;
    var color = class_color(first);
    if (!one_class || first != (all == 15u)) {
        color = sampled_color(id.xy, 1u, color);
    }
    textureStore(output, vec2<i32>(id.xy), color);
}
