// extends: effect.wgsl
// A colour grade in linear light: lift the shadows towards blue and the highlights towards amber,
// and desaturate a little, all by `amount` (0 leaves the image as it is).

fn effect(uv: vec2<f32>) -> vec4<f32> {
    let c = input_color(uv);
    let y = luma(c.rgb);
    let toned = mix(vec3<f32>(0.02, 0.04, 0.10), vec3<f32>(1.10, 0.95, 0.75), clamp(y, 0.0, 1.0)) * y;
    let graded = mix(c.rgb, mix(toned, c.rgb, 0.6), u.amount);
    return vec4<f32>(graded, c.a);
}
