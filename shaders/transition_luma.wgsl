// extends: transition.wgsl
// A luma dissolve keyed by the incoming picture: its brightest parts appear first, its darkest
// last, with a soft threshold 10 % of the luminance range wide.

const SOFTNESS: f32 = 0.1;

fn transition(uv: vec2<f32>, progress: f32) -> vec4<f32> {
    let to = to_color(uv);
    let key = clamp(luma(to.rgb), 0.0, 1.0);
    // The threshold falls from above white (p = 0: nothing shows) to below black (p = 1: all).
    let threshold = 1.0 - progress * (1.0 + SOFTNESS);
    let shows_to = smoothstep(threshold, threshold + SOFTNESS, key);
    return mix(from_color(uv), to, shows_to);
}
