// extends: transition.wgsl
// A wipe from left to right with a soft edge 2 % of the width wide.

const EDGE: f32 = 0.02;

fn transition(uv: vec2<f32>, progress: f32) -> vec4<f32> {
    // The edge travels from just left of the image (p = 0) to just right of it (p = 1).
    let front = progress * (1.0 + EDGE);
    let shows_from = smoothstep(front - EDGE, front, uv.x);
    return mix(to_color(uv), from_color(uv), shows_from);
}
