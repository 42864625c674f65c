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

// Möbius map a: z -> conj(z) / |z|^2 + (-v, u).
fn trans_a(z: vec2<f32>, t: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(z.x, -z.y) / dot(z, z) + vec2<f32>(-t.y, t.x);
}

// True when z lies in one of the disks bounded by the limit set (drawn in the hit colour).
fn in_limit_set(start: vec2<f32>, t: vec2<f32>, iterations: u32) -> bool {
    let u = t.x;
    let v = t.y;
    var z = start;
    // Algorithm step 1: the limit set lies in the strip 0 <= y <= u.
    if (z.y < 0.0 || z.y > u) {
        return false;
    }
    var lz = z + vec2<f32>(1.0, 1.0);
    var llz = z - vec2<f32>(1.0, 1.0);
    for (var i = 0u; i < iterations; i = i + 1u) {
        // Step 2: into the central parallelogram between Lines 1 and 2 (shear by signed v).
        let shear = v / u * z.y;
        z.x = wrap(z.x + shear, 2.0, -1.0) - shear;
        // Step 3: above Line 3, reflect through (-v/2, u/2). Leys' empirical separation line.
        let d = z.x + v * 0.5;
        let separation = u * 0.5
            + sign(v) * (2.0 * u - 1.95) / 4.0 * sign(d) * (1.0 - exp(-(7.2 - (1.95 - u) * 15.0) * abs(d)));
        if (z.y >= separation) {
            z = vec2<f32>(-v, u) - z;
        }
        // Step 4: transformation a; step 5: below y = 0 means inside the largest disk.
        z = trans_a(z, t);
        if (z.y < 0.0) {
            return true;
        }
        // Step 6: a 2-cycle across Line 3 means the point never escapes: not in the set.
        if (length(z - llz) < 1e-6) {
            return false;
        }
        llz = lz;
        lz = z;
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
