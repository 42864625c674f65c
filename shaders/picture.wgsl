// A picture (a clip's frame, a camera's, a still) into a node's image: fitted (contain, cover or
// stretch), decoded from what the upload holds (HAP Q's scaled YCoCg, a separate HAP alpha,
// RGBA), from sRGB to linear light, alpha premultiplied — what every node's image is.

struct PictureUniforms {
    // 0 RGB (opaque), 1 RGBA, 2 scaled YCoCg (HAP Q), 3 alpha only (a white matte)
    channels: u32,
    // 0 contain, 1 cover, 2 stretch (the `fit` option order)
    fit: u32,
    // 1 when src1's red channel is the alpha (HAP Q Alpha)
    separate_alpha: u32,
    // 1 when the values are linear already (OpenEXR: HDR kept), 0 sRGB-encoded
    linear_values: u32,
    // The frame's size in pixels.
    size: vec2<f32>,
    // The frame's share of its texture (block-compressed textures are padded to 4 × 4).
    uv_scale: vec2<f32>,
}

@group(0) @binding(0) var<uniform> u: PictureUniforms;
@group(0) @binding(1) var linear_clamp: sampler;
@group(0) @binding(2) var src0: texture_2d<f32>;
@group(0) @binding(3) var src1: texture_2d<f32>;
@group(0) @binding(8) var dst: texture_storage_2d<rgba16float, write>;

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

// Scaled YCoCg-DXT5 (van Waveren & Castaño 2007), as HAP Q stores it: Co, Cg in R, G around
// 0.5 (in 8-bit steps), their scale in B, luma in A.
fn scaled_ycocg_to_rgb(c: vec4<f32>) -> vec3<f32> {
    let scale = c.b * (255.0 / 8.0) + 1.0;
    let co = (c.r - 128.0 / 255.0) / scale;
    let cg = (c.g - 128.0 / 255.0) / scale;
    let y = c.a;
    return vec3<f32>(y + co - cg, y + cg, y - co - cg);
}

// Where in the frame (0–1) output point `p` (0–1) falls, by the fit mode.
fn fitted(p: vec2<f32>, out_size: vec2<f32>) -> vec2<f32> {
    let frame_aspect = u.size.x / max(u.size.y, 1.0);
    let out_aspect = out_size.x / max(out_size.y, 1.0);
    // The frame's extent in output units: contain fits inside, cover fills and crops.
    var extent = vec2<f32>(1.0);
    let wider = frame_aspect > out_aspect;
    if u.fit == 0u && wider || u.fit == 1u && !wider {
        extent.y = out_aspect / frame_aspect;
    } else if u.fit != 2u {
        extent.x = frame_aspect / out_aspect;
    }
    return (p - 0.5) / extent + 0.5;
}

// 16×16 invocations: a read and a write per pixel ran at a third of the H200's bandwidth in
// 8×8 groups (4K blend 0.089 → 0.049 ms, fader 0.089 → 0.044; the same bytes).
@compute @workgroup_size(16, 16)
fn picture(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(dst);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let uv = fitted((vec2<f32>(id.xy) + 0.5) / vec2<f32>(size), vec2<f32>(size));
    if any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) {
        textureStore(dst, vec2<i32>(id.xy), vec4<f32>(0.0));
        return;
    }
    let texel = textureSampleLevel(src0, linear_clamp, uv * u.uv_scale, 0.0);
    var rgb = texel.rgb;
    var alpha = 1.0;
    switch u.channels {
        case 1u: { alpha = texel.a; }
        case 2u: { rgb = scaled_ycocg_to_rgb(texel); }
        case 3u: { rgb = vec3<f32>(1.0); alpha = texel.r; }
        default: {}
    }
    if u.separate_alpha == 1u {
        alpha = textureSampleLevel(src1, linear_clamp, uv * u.uv_scale, 0.0).r;
    }
    alpha = clamp(alpha, 0.0, 1.0);
    var colour = max(rgb, vec3<f32>(0.0));
    if u.linear_values == 0u {
        colour = srgb_to_linear(min(colour, vec3<f32>(1.0)));
    }
    textureStore(dst, vec2<i32>(id.xy), vec4<f32>(colour * alpha, alpha));
}
