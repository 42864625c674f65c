// extends: transition.wgsl
// A crossfade in linear light: (1 − p)·from + p·to, alpha included.

fn transition(uv: vec2<f32>, progress: f32) -> vec4<f32> {
    return mix(from_color(uv), to_color(uv), progress);
}
