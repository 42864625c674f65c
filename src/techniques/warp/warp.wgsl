// Projection mapping: draws the source image on a tessellated mesh whose vertices went through
// the mesh warp (on the CPU), then the corner pin (here, as a homography in clip space so the
// GPU's perspective-correct interpolation makes the pin exact inside every triangle). Soft edges
// and the black-level lift are applied in linear light, in the source's own coordinates, so the
// ramps of two overlapping projectors sum to one on the wall. `uv` runs over the part of the
// source this output shows (its region), so blends and the grid belong to the projector.

struct WarpUniforms {
    // Unit square (after the mesh) → output view units (0–1, y up).
    homography: mat3x3<f32>,
    // Blend widths: left, right, top, bottom (shares of the source).
    blend: vec4<f32>,
    // x: ramp exponent, y: gamma of the weight, z: black-level lift, w: 1 draws the edit grid.
    shape: vec4<f32>,
    // x, y: mesh cells across and up; z, w: unused.
    grid: vec4<f32>,
    // The part of the source shown: min x, min y, max x, max y (v up).
    region: vec4<f32>,
}

@group(0) @binding(0) var<uniform> u: WarpUniforms;
@group(1) @binding(0) var source: texture_2d<f32>;
@group(1) @binding(1) var source_sampler: sampler;

struct VsOut {
    @builtin(position) position: vec4<f32>,
    // Source coordinates (0–1, v up).
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_main(@location(0) uv: vec2<f32>, @location(1) warped: vec2<f32>) -> VsOut {
    let h = u.homography * vec3<f32>(warped, 1.0);
    // view = h.xy / h.z; NDC = 2·view − 1, kept homogeneous: (2x − w, 2y − w, 0, w).
    var out: VsOut;
    out.position = vec4<f32>(2.0 * h.x - h.z, 2.0 * h.y - h.z, 0.0, h.z);
    out.uv = uv;
    return out;
}

// Bourke's ramp: 0 → 0, 1 → 1, ramp(t) + ramp(1 − t) = 1 for every exponent.
fn ramp(t: f32, curve: f32) -> f32 {
    let x = clamp(t, 0.0, 1.0);
    if x < 0.5 {
        return 0.5 * pow(2.0 * x, curve);
    }
    return 1.0 - 0.5 * pow(2.0 * (1.0 - x), curve);
}

fn side(x: f32, width: f32) -> f32 {
    if width <= 0.0 {
        return 1.0;
    }
    return ramp(x / width, u.shape.x);
}

// Distance (in pixels) to the nearest mesh line, and to the nearest control point.
fn grid_distances(uv: vec2<f32>) -> vec2<f32> {
    let s = uv * u.grid.xy;
    let pixel = max(fwidth(s), vec2<f32>(1e-6));
    let to_line = abs(s - round(s)) / pixel;
    return vec2<f32>(min(to_line.x, to_line.y), length(to_line));
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let uv = in.uv;
    let at = mix(u.region.xy, u.region.zw, uv);
    var color = textureSample(source, source_sampler, vec2<f32>(at.x, 1.0 - at.y)).rgb;
    let w = side(uv.x, u.blend.x) * side(1.0 - uv.x, u.blend.y) * side(1.0 - uv.y, u.blend.z) * side(uv.y, u.blend.w);
    color = color * pow(w, u.shape.y);
    // The lift raises black where only this projector shines (outside every blend zone).
    let inside = uv.x >= u.blend.x && 1.0 - uv.x >= u.blend.y && 1.0 - uv.y >= u.blend.z && uv.y >= u.blend.w;
    if inside {
        color = u.shape.z + color * (1.0 - u.shape.z);
    }
    if u.shape.w > 0.5 {
        let d = grid_distances(uv);
        let line = 1.0 - smoothstep(0.5, 1.5, d.x);
        let handle = 1.0 - smoothstep(5.0, 6.5, d.y);
        color = mix(color, vec3<f32>(0.1, 0.9, 1.0), line * 0.8);
        color = mix(color, vec3<f32>(1.0, 0.55, 0.1), handle);
    }
    return vec4<f32>(color, 1.0);
}
