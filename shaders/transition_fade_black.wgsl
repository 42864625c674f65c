// extends: transition.wgsl
// Fade through black: the outgoing clip down to black over the first half, the incoming one up
// from black over the second.

fn transition(uv: vec2<f32>, progress: f32) -> vec4<f32> {
    if progress < 0.5 {
        let c = from_color(uv);
        return vec4<f32>(c.rgb * (1.0 - 2.0 * progress), c.a);
    }
    let c = to_color(uv);
    return vec4<f32>(c.rgb * (2.0 * progress - 1.0), c.a);
}
