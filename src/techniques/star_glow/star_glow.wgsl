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
// Scan layout, where every streak steps whole texels along an axis and reaches past the image
// (the book's defaults at 1080p and 4K): the cascade's weights multiply out to att^k for the
// k-th texel along the streak (k < 4^iteration, one tap per level: the base-4 digits of k), so
// one exponential suffix scan per line and direction gives what the levels give, and the
// directions are screen-accumulated after: bright -> scan -> screen -> composite (4 passes).

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

// Invocations of one scan workgroup: one per texel of a chunk of a line.
const SCAN_WIDTH: u32 = 256u;
// Longest line a scan takes (16 chunks; the engine uses the cascade beyond).
const SCAN_MAX_CHUNKS: u32 = 16u;
// The chunk being scanned, and the finished sums of the chunk scanned before it (further along).
var<workgroup> scan_sums: array<vec3<f32>, 256>;
var<workgroup> scan_carry: array<vec3<f32>, 256>;

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

// The texel at distance t along line `line`, for taps stepping along `axis_x` (else y) in the
// `forward` (+) direction or against it; t = n - 1 is the far end, where the taps clamp.
fn scan_texel(line: u32, t: u32, n: u32, axis_x: bool, forward: bool) -> vec2<i32> {
    let along = select(n - 1u - t, t, forward);
    return select(vec2<i32>(i32(line), i32(along)), vec2<i32>(i32(along), i32(line)), axis_x);
}

// Weight of the taps past the far end, k0 .. taps - 1, which all read the end texel:
// sum of att^k.
fn past_end_weight(k0: f32, taps: f32) -> f32 {
    if (k0 >= taps) {
        return 0.0;
    }
    if (u.attenuation == 1.0) {
        return taps - k0;
    }
    return (pow(u.attenuation, k0) - pow(u.attenuation, taps)) / (1.0 - u.attenuation);
}

// One line (workgroup x) of one direction (workgroup y) of the bright texture (tex_a) into layer
// y of dst_layers: out(t) = sum over k < taps of att^k bright(min(t + k s, n - 1)), taps =
// u.power = 4^iteration, s = the whole-texel step. With taps * s >= n every streak runs off the
// far end, so out(t) is the suffix sum S(t) = bright(t) + att S(t + s) plus the end texel times
// the weights of the taps past it. The line is scanned in chunks of 256 from the far end back,
// each chunk by doubling steps in workgroup memory, its sums completed from the chunk before.
@compute @workgroup_size(256, 1, 1)
fn streak_scan(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) i: u32) {
    let step = u.steps[group.y].xy;
    let axis_x = abs(step.x) > abs(step.y);
    let forward = select(step.y, step.x, axis_x) > 0.0;
    let s = u32(round(max(abs(step.x), abs(step.y))));
    let n = select(u.dst_size.y, u.dst_size.x, axis_x);
    let line = group.x;
    if (line >= select(u.dst_size.x, u.dst_size.y, axis_x) || group.y >= u.directions) {
        return;
    }
    let chunks = min((n + SCAN_WIDTH - 1u) / SCAN_WIDTH, SCAN_MAX_CHUNKS);
    // Every load of the line first, so their latencies overlap.
    var texels: array<vec3<f32>, SCAN_MAX_CHUNKS>;
    for (var c = 0u; c < chunks; c = c + 1u) {
        let t = i32(n) - i32(SCAN_WIDTH * (c + 1u)) + i32(i);
        texels[c] = vec3<f32>(0.0);
        if (t >= 0) {
            texels[c] = textureLoad(tex_a, scan_texel(line, u32(t), n, axis_x, forward), 0).rgb;
        }
    }
    let end = textureLoad(tex_a, scan_texel(line, n - 1u, n, axis_x, forward), 0).rgb;
    for (var c = 0u; c < chunks; c = c + 1u) {
        scan_sums[i] = texels[c];
        workgroupBarrier();
        // After the step of offset o: the sum over j < 2 o / s of att^j bright(t + j s).
        for (var o = s; o < SCAN_WIDTH; o = o * 2u) {
            var further = vec3<f32>(0.0);
            if (i + o < SCAN_WIDTH) {
                further = scan_sums[i + o];
            }
            workgroupBarrier();
            scan_sums[i] += pow(u.attenuation, f32(o / s)) * further;
            workgroupBarrier();
        }
        // The chunk's first q terms are in hand; the rest is S at the first texel past it.
        var sum = scan_sums[i];
        if (c > 0u) {
            let q = (SCAN_WIDTH - i + s - 1u) / s;
            sum += pow(u.attenuation, f32(q)) * scan_carry[i + q * s - SCAN_WIDTH];
        }
        workgroupBarrier();
        scan_carry[i] = sum;
        let t = i32(n) - i32(SCAN_WIDTH * (c + 1u)) + i32(i);
        if (t >= 0) {
            let k0 = f32((n - 1u - u32(t)) / s + 1u);
            let out = sum + end * past_end_weight(k0, u.power);
            textureStore(dst_layers, scan_texel(line, u32(t), n, axis_x, forward), i32(group.y), vec4<f32>(out, 1.0));
        }
        workgroupBarrier();
    }
}

// Scan layout: every direction's streak (src_layers), screen-accumulated in order into dst.
@compute @workgroup_size(16, 16, 1)
fn streak_screen(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= u.dst_size)) {
        return;
    }
    var acc = vec3<f32>(0.0);
    for (var d = 0u; d < min(u.directions, MAX_DIRECTIONS); d = d + 1u) {
        acc = screen(acc, textureLoad(src_layers, vec2<i32>(id.xy), d, 0).rgb);
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
