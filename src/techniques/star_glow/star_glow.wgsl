// StarGlow: Kawase's streak filter (GDC 2003) as in [UGP4 ch.4] (xjine). Every entry point runs
// one invocation per texel it writes, dispatched over that texture's extent (and, for the layered
// fused passes, one z-slice per streak direction). All textures are linear HDR (rgba16float);
// nothing is clamped before the final display encode.
//
// Book layout: bright -> per direction: `iteration` streak passes -> accumulate -> composite
// (2 + N (iteration + 1) passes).
// Fused layout: the same cascade, but each level runs every direction at once on a layered
// texture (one layer per direction), and the last level screen-accumulates the directions
// itself: bright -> level 1 .. level `iteration` -> composite (iteration + 2 passes). The
// arithmetic is the book's, tap for tap.

const MAX_DIRECTIONS: u32 = 16u;

struct StarGlowUniforms {
    dst_size: vec2<u32>,   // size of the texture this pass writes
    threshold: f32,        // bright pass: subtracted from each colour channel
    intensity: f32,        // bright pass: gain after the threshold
    offset: vec2<f32>,     // streak pass: tap step in source texels (y down), already x power
    attenuation: f32,      // weight base: tap j of a level with power p weighs att^(p j)
    power: f32,            // streak pass: 4^(n-1) for level n
    composite_type: u32,   // 0 additive, 1 screen, 2 coloured additive, 3 coloured screen, 4 debug
    directions: u32,       // fused: number of streak directions
    first: u32,            // accumulate: 1 for the first direction (start from black)
    divide: u32,           // bright pass: source texels per output texel on each axis
    color: vec4<f32>,      // coloured composite types: tint
    steps: array<vec4<f32>, 16>, // fused: per-direction tap step in texels, x power (xy, y down)
};

@group(0) @binding(0) var<uniform> u: StarGlowUniforms;
@group(0) @binding(1) var linear_clamp: sampler;
@group(0) @binding(2) var tex_a: texture_2d<f32>;
@group(0) @binding(3) var tex_b: texture_2d<f32>;
@group(0) @binding(4) var dst: texture_storage_2d<rgba16float, write>;
@group(0) @binding(5) var src_layers: texture_2d_array<f32>;
@group(0) @binding(6) var dst_layers: texture_storage_2d_array<rgba16float, write>;

fn uv_of(id: vec2<u32>) -> vec2<f32> {
    return (vec2<f32>(id) + 0.5) / vec2<f32>(u.dst_size);
}

// Screen blend made safe for HDR: a + b (1 - a) with the (1 - a) factor never negative.
fn screen(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return a + b * max(vec3<f32>(1.0) - a, vec3<f32>(0.0));
}

// Weight of tap j at level power p: att^(p j), with 0^0 = 1.
fn tap_weight(j: f32, p: f32) -> f32 {
    if (j == 0.0) {
        return 1.0;
    }
    return pow(u.attenuation, p * j);
}

// Bright pass: threshold every source texel of the footprint, keep the brightest (max-pooling
// keeps a one-pixel glint from vanishing or flickering as it moves under a coarse texel).
@compute @workgroup_size(8, 8, 1)
fn bright(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= u.dst_size)) {
        return;
    }
    let src_size = vec2<i32>(textureDimensions(tex_a));
    let origin = vec2<i32>(id.xy * u.divide);
    var brightest = vec3<f32>(0.0);
    for (var y = 0; y < i32(u.divide); y = y + 1) {
        for (var x = 0; x < i32(u.divide); x = x + 1) {
            let p = min(origin + vec2<i32>(x, y), src_size - 1);
            let c = textureLoad(tex_a, p, 0).rgb;
            brightest = max(brightest, max(c - vec3<f32>(u.threshold), vec3<f32>(0.0)));
        }
    }
    textureStore(dst, vec2<i32>(id.xy), vec4<f32>(brightest * u.intensity, 1.0));
}

// The 4 taps of one level from a 2-D source, starting at uv, `step` texels apart.
fn taps_2d(uv0: vec2<f32>, step: vec2<f32>) -> vec3<f32> {
    let texel_step = step / vec2<f32>(textureDimensions(tex_a));
    var sum = vec3<f32>(0.0);
    for (var j = 0; j < 4; j = j + 1) {
        sum += textureSampleLevel(tex_a, linear_clamp, uv0 + f32(j) * texel_step, 0.0).rgb * tap_weight(f32(j), u.power);
    }
    return sum;
}

// The same taps from one layer of the layered source.
fn taps_layer(uv0: vec2<f32>, step: vec2<f32>, layer: u32) -> vec3<f32> {
    let texel_step = step / vec2<f32>(textureDimensions(src_layers));
    var sum = vec3<f32>(0.0);
    for (var j = 0; j < 4; j = j + 1) {
        let uv = uv0 + f32(j) * texel_step;
        sum += textureSampleLevel(src_layers, linear_clamp, uv, layer, 0.0).rgb * tap_weight(f32(j), u.power);
    }
    return sum;
}

// One streak level of one direction (book layout): taps along `offset`; the glow extends
// opposite to it.
@compute @workgroup_size(8, 8, 1)
fn streak(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= u.dst_size)) {
        return;
    }
    textureStore(dst, vec2<i32>(id.xy), vec4<f32>(taps_2d(uv_of(id.xy), u.offset), 1.0));
}

// Screen-blends one finished streak (tex_b) over the accumulation so far (tex_a). The first
// direction starts from black, so a stale texture never leaks in.
@compute @workgroup_size(8, 8, 1)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= u.dst_size)) {
        return;
    }
    let p = vec2<i32>(id.xy);
    var acc = textureLoad(tex_a, p, 0).rgb;
    if (u.first == 1u) {
        acc = vec3<f32>(0.0);
    }
    textureStore(dst, p, vec4<f32>(screen(acc, textureLoad(tex_b, p, 0).rgb), 1.0));
}

// Fused level 1 of every direction: the bright texture into layer z (z = direction).
@compute @workgroup_size(8, 8, 1)
fn level_first(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= u.dst_size) || id.z >= u.directions) {
        return;
    }
    let sum = taps_2d(uv_of(id.xy), u.steps[id.z].xy);
    textureStore(dst_layers, vec2<i32>(id.xy), i32(id.z), vec4<f32>(sum, 1.0));
}

// Fused middle level of every direction: layer z of the previous level into layer z.
@compute @workgroup_size(8, 8, 1)
fn level_next(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= u.dst_size) || id.z >= u.directions) {
        return;
    }
    let sum = taps_layer(uv_of(id.xy), u.steps[id.z].xy, id.z);
    textureStore(dst_layers, vec2<i32>(id.xy), i32(id.z), vec4<f32>(sum, 1.0));
}

// Fused last level: every direction's final taps, screen-accumulated in registers.
@compute @workgroup_size(8, 8, 1)
fn level_last(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= u.dst_size)) {
        return;
    }
    let uv = uv_of(id.xy);
    var acc = vec3<f32>(0.0);
    for (var d = 0u; d < min(u.directions, MAX_DIRECTIONS); d = d + 1u) {
        acc = screen(acc, taps_layer(uv, u.steps[d].xy, d));
    }
    textureStore(dst, vec2<i32>(id.xy), vec4<f32>(acc, 1.0));
}

// Fused single level (iteration 1): every direction's taps of the bright texture, accumulated.
@compute @workgroup_size(8, 8, 1)
fn level_single(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= u.dst_size)) {
        return;
    }
    let uv = uv_of(id.xy);
    var acc = vec3<f32>(0.0);
    for (var d = 0u; d < min(u.directions, MAX_DIRECTIONS); d = d + 1u) {
        acc = screen(acc, taps_2d(uv, u.steps[d].xy));
    }
    textureStore(dst, vec2<i32>(id.xy), vec4<f32>(acc, 1.0));
}

// Final composite at output size: the source (tex_a, texel-exact) with the glow (tex_b, bilinear
// upsampled). 16×16 invocations: at 4K on the H200 the pass took 0.089 ms in 8×8 groups and
// 0.046 in 16×16 (32×8: 0.049, 16×8: 0.056), the same bytes.
@compute @workgroup_size(16, 16, 1)
fn composite(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= u.dst_size)) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let source = textureLoad(tex_a, p, 0);
    var glow = textureSampleLevel(tex_b, linear_clamp, uv_of(id.xy), 0.0).rgb;
    if (u.composite_type == 2u || u.composite_type == 3u) {
        glow = (glow.r + glow.g + glow.b) / 3.0 * u.color.rgb;
    }
    var out = source.rgb + glow;
    if (u.composite_type == 1u || u.composite_type == 3u) {
        out = screen(source.rgb, glow);
    } else if (u.composite_type == 4u) {
        out = glow;
    }
    textureStore(dst, p, vec4<f32>(out, source.a));
}
