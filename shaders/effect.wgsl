// The base of every WGSL effect (a show's effect chains, or an `wgsl_effect` node). An effect
// file starts with `// extends: effect.wgsl` and defines
//
//     fn effect(uv: vec2<f32>) -> vec4<f32>
//
// the colour at `uv` (0–1, (0, 0) the top left) of the image it changes, which it reads with
// input_color(uv): linear HDR. `u.amount` (0–1, the node's `amount` parameter) is there to drive
// its strength; `u.seconds` (the show's clock), `u.aspect` and `u.size` (pixels) for patterns.
// indra adds the entry point.

struct EffectUniforms {
    amount: f32,
    seconds: f32,
    aspect: f32,
    _pad: f32,
    size: vec2<f32>,
    _pad2: vec2<f32>,
}

@group(0) @binding(0) var<uniform> u: EffectUniforms;
@group(0) @binding(1) var linear_clamp: sampler;
@group(0) @binding(2) var src0: texture_2d<f32>;
@group(0) @binding(8) var dst: texture_storage_2d<rgba16float, write>;

// The image at `uv`.
fn input_color(uv: vec2<f32>) -> vec4<f32> {
    return textureSampleLevel(src0, linear_clamp, uv, 0.0);
}

// Relative luminance of linear Rec. 709 colour.
fn luma(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}
