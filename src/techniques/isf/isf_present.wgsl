// The image of an ISF node whose last pass renders into a buffer (a feedback shader's
// persistent TARGET): that buffer holds display values, straight alpha, as ISF shaders write
// them; the node's image is linear light with alpha premultiplied, like every node's.

struct PresentUniforms {
    _pad: vec4<u32>,
}

@group(0) @binding(0) var<uniform> u: PresentUniforms;
@group(0) @binding(1) var linear_clamp: sampler;
@group(0) @binding(2) var src0: texture_2d<f32>;
@group(0) @binding(8) var dst: texture_storage_2d<rgba16float, write>;

fn decoded(c: vec3<f32>) -> vec3<f32> {
    let x = max(c, vec3<f32>(0.0));
    return select(pow((x + 0.055) / 1.055, vec3<f32>(2.4)), x / 12.92, x <= vec3<f32>(0.04045));
}

@compute @workgroup_size(8, 8)
fn isf_present(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(dst);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let uv = (vec2<f32>(id.xy) + 0.5) / vec2<f32>(size);
    let c = textureSampleLevel(src0, linear_clamp, uv, 0.0);
    let a = clamp(c.a, 0.0, 1.0);
    textureStore(dst, vec2<i32>(id.xy), vec4<f32>(decoded(c.rgb) * a, a));
}
