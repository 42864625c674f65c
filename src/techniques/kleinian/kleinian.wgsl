// Limit sets of Kleinian groups (Maskit slice) by Jos Leys' escape-time test [UGP4 ch.2],
// [Leys, "Kleinian escape-time", josleys.com]. One invocation per output pixel; dispatched over
// the output extent. Writes linear colour to an rgba16float storage texture.
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

// One invocation per output pixel; dispatched over the output extent.
@compute @workgroup_size(8, 8, 1)
fn render(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.size.x || id.y >= params.size.y) {
        return;
    }
    let height = f32(params.size.y);
    let samples = max(params.samples, 1u);
    var sum = vec4<f32>(0.0);
    for (var s = 0u; s < samples; s = s + 1u) {
        // Sample 0 of a single-sample render sits on the pixel centre; otherwise a uniform
        // jitter over the pixel's own square.
        var jitter = vec2<f32>(0.0);
        if (samples > 1u) {
            jitter = hash2(vec3<u32>(id.x, id.y, s ^ (params.seed * 747796405u))) - 0.5;
        }
        // uv has its origin bottom-left and spans 0..1 vertically (x scaled by the aspect).
        let pixel = vec2<f32>(f32(id.x), f32(id.y)) + 0.5 + jitter;
        let uv = vec2<f32>(pixel.x / height, 1.0 - pixel.y / height);
        var p = uv * params.scale + params.offset;
        if (params.inversion != 0u) {
            p = circle_inverse(p, params.circle_center, params.circle_radius);
        }
        let hit = in_limit_set(p, params.t, params.iterations);
        sum += select(params.back_color, params.hit_color, hit);
    }
    textureStore(output, vec2<i32>(id.xy), sum / f32(samples));
}
