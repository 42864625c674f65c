// extends: effect.wgsl
// A mirror: the left half of the image reflected onto the right, blended in by `amount`.

fn effect(uv: vec2<f32>) -> vec4<f32> {
    let mirrored = vec2<f32>(0.5 - abs(uv.x - 0.5), uv.y);
    return mix(input_color(uv), input_color(mirrored), u.amount);
}
