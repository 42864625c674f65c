// The base of every show transition. A transition file starts with `// extends: transition.wgsl`
// and defines
//
//     fn transition(uv: vec2<f32>, progress: f32) -> vec4<f32>
//
// the layer's colour at `uv` (0–1, (0, 0) the top left) when the transition is `progress`
// (0 → 1) of the way from the outgoing clip to the incoming one. Read them with from_color(uv)
// and to_color(uv): linear HDR, alpha 0 where a side is an empty layer. `u.seconds` (since the
// transition began), `u.aspect` and `u.size` (pixels) are there for patterns. indra adds the
// entry point.

struct TransitionUniforms {
    progress: f32,
    seconds: f32,
    aspect: f32,
    _pad: f32,
    size: vec2<f32>,
    _pad2: vec2<f32>,
}

@group(0) @binding(0) var<uniform> u: TransitionUniforms;
@group(0) @binding(1) var linear_clamp: sampler;
@group(0) @binding(2) var src0: texture_2d<f32>;
@group(0) @binding(3) var src1: texture_2d<f32>;
@group(0) @binding(8) var dst: texture_storage_2d<rgba16float, write>;

// The outgoing clip at `uv`.
fn from_color(uv: vec2<f32>) -> vec4<f32> {
    return textureSampleLevel(src0, linear_clamp, uv, 0.0);
}

// The incoming clip at `uv`.
fn to_color(uv: vec2<f32>) -> vec4<f32> {
    return textureSampleLevel(src1, linear_clamp, uv, 0.0);
}

// Relative luminance of linear Rec. 709 colour.
fn luma(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}
