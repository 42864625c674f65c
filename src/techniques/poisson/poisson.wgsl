// Poisson disk samples [UGP4 ch.7] as instanced camera-facing quads: flat discs (2-D, seen from
// above) or sphere impostors lit by one light (3-D). Colour follows insertion order along a
// blue-magenta-yellow ramp, so the growth front reads as the brightest samples. A disc's rim is
// cut here, not by the rasterizer, so the fragment shader works out which of the pixel's samples
// the disc covers: multisampling then smooths the rim as it does a triangle's edge (a discard
// would drop every sample of the pixel and leave the rim stair-stepped).
// extends: msaa_samples.wgsl

struct PoissonUniforms {
    view_proj: mat4x4<f32>,
    right: vec4<f32>,       // xyz: camera right (world, unit)
    up: vec4<f32>,          // xyz: camera up (world, unit)
    draw_radius: f32,       // radius of each drawn disc or sphere (world units)
    count: f32,             // samples so far
    spheres: u32,           // 0: discs, 1: lit spheres
    samples: u32,           // samples per pixel of the draw
};

@group(0) @binding(0) var<uniform> u: PoissonUniforms;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) corner: vec2<f32>,   // quad coordinates in [-1, 1]
    @location(1) order: f32,          // insertion order in [0, 1]
};

@vertex
fn vs_main(@builtin(vertex_index) index: u32, @location(0) sample: vec4<f32>) -> VertexOut {
    let quad = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let c = quad[index];
    let world = sample.xyz + (u.right.xyz * c.x + u.up.xyz * c.y) * u.draw_radius;
    var out: VertexOut;
    out.clip = u.view_proj * vec4<f32>(world, 1.0);
    out.corner = c;
    out.order = order_of(sample.w);
    return out;
}

// A sample's place in the insertion order, 0 (first) to 1 (newest), from its index.
fn order_of(index: f32) -> f32 {
    return index / max(u.count - 1.0, 1.0);
}

// Deep blue → magenta → yellow (sRGB anchors), returned in linear light.
fn ramp(t: f32) -> vec3<f32> {
    let blue = vec3<f32>(0.15, 0.25, 0.95);
    let magenta = vec3<f32>(0.9, 0.2, 0.6);
    let yellow = vec3<f32>(1.0, 0.9, 0.25);
    let srgb = select(mix(magenta, yellow, t * 2.0 - 1.0), mix(blue, magenta, t * 2.0), t < 0.5);
    return pow(srgb, vec3<f32>(2.2));
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @builtin(sample_mask) coverage: u32,
};

// The samples of this pixel that the disc covers: the quad coordinates moved to each sample's
// position by their screen derivatives.
fn disc_coverage(corner: vec2<f32>, per_x: vec2<f32>, per_y: vec2<f32>) -> u32 {
    let count = max(u.samples, 1u);
    var mask = 0u;
    for (var s = 0u; s < count; s = s + 1u) {
        let offset = vec2<f32>(sample_offset(count, s)) / 16.0;
        let at = corner + per_x * offset.x + per_y * offset.y;
        if (dot(at, at) <= 1.0) {
            mask = mask | (1u << s);
        }
    }
    return mask;
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    let coverage = disc_coverage(in.corner, dpdx(in.corner), dpdy(in.corner));
    if (coverage == 0u) {
        discard;
    }
    return FragmentOut(vec4<f32>(disc_colour(in.corner, in.order), 1.0), coverage);
}

// The colour of the disc (or sphere) of insertion order `order` shaded at quad position
// `corner`: the pixel centre, which may lie just outside a disc some of whose samples it covers.
fn disc_colour(corner: vec2<f32>, order: f32) -> vec3<f32> {
    let d2 = min(dot(corner, corner), 1.0);
    var color = ramp(order);
    if (u.spheres == 1u) {
        // Sphere normal in camera space from the quad position; light from upper left, front.
        let normal = vec3<f32>(corner, -sqrt(1.0 - d2));
        let light = normalize(vec3<f32>(-0.5, 0.7, -0.6));
        color = color * (0.15 + 0.85 * max(dot(normal, light), 0.0));
    }
    return color;
}
