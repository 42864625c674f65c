// Layer blending in linear HDR: `src1` (the layer) over `src0` (what lies below), at `opacity`
// times the layer's alpha. Each mode picks the colour the layer contributes; the result mixes
// from the image below towards it, so at opacity 0 every mode leaves the image below untouched.

struct BlendUniforms {
    // 0 normal, 1 add, 2 screen, 3 multiply, 4 difference, 5 lighten (the `blend` option order)
    mode: u32,
    opacity: f32,
    _pad: vec2<u32>,
}

@group(0) @binding(0) var<uniform> u: BlendUniforms;
@group(0) @binding(1) var linear_clamp: sampler;
@group(0) @binding(2) var src0: texture_2d<f32>;
@group(0) @binding(3) var src1: texture_2d<f32>;
@group(0) @binding(8) var dst: texture_storage_2d<rgba16float, write>;

fn blended(below: vec3<f32>, over: vec3<f32>, mode: u32) -> vec3<f32> {
    switch mode {
        case 1u: { return below + over; }
        case 2u: { return below + over - below * over; }
        case 3u: { return below * over; }
        case 4u: { return abs(below - over); }
        case 5u: { return max(below, over); }
        default: { return over; }
    }
}

// 16×16 invocations: a read and a write per pixel ran at a third of the H200's bandwidth in
// 8×8 groups (4K blend 0.089 → 0.049 ms, fader 0.089 → 0.044; the same bytes).
@compute @workgroup_size(16, 16)
fn blend(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(dst);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let uv = (vec2<f32>(id.xy) + 0.5) / vec2<f32>(size);
    let below = textureSampleLevel(src0, linear_clamp, uv, 0.0);
    let over = textureSampleLevel(src1, linear_clamp, uv, 0.0);
    let a = clamp(u.opacity, 0.0, 1.0) * clamp(over.a, 0.0, 1.0);
    let rgb = mix(below.rgb, blended(below.rgb, over.rgb, u.mode), a);
    textureStore(dst, vec2<i32>(id.xy), vec4<f32>(rgb, below.a + a * (1.0 - below.a)));
}
