// Projection mapping as a per-pixel inverse mapping, in compute: each output pixel goes back
// through the corner pin (the exact inverse homography) and then through the mesh warp (Newton's
// method on the mesh's surface, the identity skipped), and samples the source there. Edges are
// antialiased by the pixel's coverage of the unit square, from the mapping's derivatives. Soft
// edges and the black-level lift are applied in linear light, in the source's own coordinates,
// so the ramps of two overlapping projectors sum to one on the wall. `uv` runs over the part of
// the source this output shows (its region), so blends and the grid belong to the projector.

// The most control points with their extrapolated ring: (16 + 2)², two to a vec4.
const MAX_POINT_PAIRS: u32 = 162u;

struct WarpUniforms {
    // View units (0–1, y up) → the unit square after the mesh: the inverse corner pin.
    inverse_pin: mat3x3<f32>,
    // Blend widths: left, right, top, bottom (shares of the source).
    blend: vec4<f32>,
    // x: ramp exponent, y: gamma of the weight, z: black-level lift, w: 1 draws the edit grid.
    shape: vec4<f32>,
    // x, y: mesh cells across and up; z: 1 when the mesh is the identity; w: 1 smooth, 0 linear.
    grid: vec4<f32>,
    // The part of the source shown: min x, min y, max x, max y (v up).
    region: vec4<f32>,
    // The control points and the ring around them, (cells + 3) per row, rows from the bottom.
    points: array<vec4<f32>, MAX_POINT_PAIRS>,
}

@group(0) @binding(0) var<uniform> u: WarpUniforms;
@group(0) @binding(1) var linear_clamp: sampler;
@group(0) @binding(2) var src0: texture_2d<f32>;
@group(0) @binding(8) var dst: texture_storage_2d<rgba16float, write>;

// Control point (i, j), −1 ≤ i ≤ columns, −1 ≤ j ≤ rows.
fn point(i: i32, j: i32) -> vec2<f32> {
    let row = i32(u.grid.x) + 3;
    let k = u32((j + 1) * row + (i + 1));
    let pair = u.points[k / 2u];
    return select(pair.xy, pair.zw, (k & 1u) == 1u);
}

// Weights of the four points along one direction at t, and their derivatives.
fn weights(t: f32) -> mat2x4<f32> {
    if u.grid.w < 0.5 {
        return mat2x4<f32>(vec4<f32>(0.0, 1.0 - t, t, 0.0), vec4<f32>(0.0, -1.0, 1.0, 0.0));
    }
    // Catmull-Rom, as the CPU's `MeshWarp::evaluate`.
    let t2 = t * t;
    let t3 = t2 * t;
    let w = 0.5 * vec4<f32>(-t3 + 2.0 * t2 - t, 3.0 * t3 - 5.0 * t2 + 2.0, -3.0 * t3 + 4.0 * t2 + t, t3 - t2);
    let d = 0.5 * vec4<f32>(-3.0 * t2 + 4.0 * t - 1.0, 9.0 * t2 - 10.0 * t, -9.0 * t2 + 8.0 * t + 1.0, 3.0 * t2 - 2.0 * t);
    return mat2x4<f32>(w, d);
}

struct MeshPoint {
    at: vec2<f32>,
    // d at / d uv: columns ∂/∂u and ∂/∂v.
    jacobian: mat2x2<f32>,
}

// Where the mesh sends source point `uv` (beyond the unit square, its border cells go on).
fn mesh(uv: vec2<f32>) -> MeshPoint {
    let cells = u.grid.xy;
    let xy = uv * cells;
    let cell = clamp(floor(xy), vec2<f32>(0.0), cells - 1.0);
    let st = xy - cell;
    let wu = weights(st.x);
    let wv = weights(st.y);
    var at = vec2<f32>(0.0);
    var du = vec2<f32>(0.0);
    var dv = vec2<f32>(0.0);
    for (var b = 0; b < 4; b++) {
        for (var a = 0; a < 4; a++) {
            let p = point(i32(cell.x) + a - 1, i32(cell.y) + b - 1);
            at += wu[0][a] * wv[0][b] * p;
            du += wu[1][a] * wv[0][b] * p;
            dv += wu[0][a] * wv[1][b] * p;
        }
    }
    return MeshPoint(at, mat2x2<f32>(du * cells.x, dv * cells.y));
}

fn inverse2(m: mat2x2<f32>) -> mat2x2<f32> {
    let det = m[0][0] * m[1][1] - m[1][0] * m[0][1];
    return mat2x2<f32>(vec2<f32>(m[1][1], -m[0][1]), vec2<f32>(-m[1][0], m[0][0])) * (1.0 / det);
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

// The share of a pixel on the inner side of the line where `d` (a coordinate) is 0, for a
// coordinate `d` that changes by `g` per pixel.
fn covered(d: f32, g: f32) -> f32 {
    return clamp(0.5 + d / max(g, 1e-9), 0.0, 1.0);
}

@compute @workgroup_size(8, 8)
fn warp(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(dst);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let pixel = 1.0 / vec2<f32>(size);
    let view = vec2<f32>((f32(id.x) + 0.5) * pixel.x, 1.0 - (f32(id.y) + 0.5) * pixel.y);
    let h = u.inverse_pin * vec3<f32>(view, 1.0);
    if h.z <= 0.0 {
        // Beyond the pin's horizon: nothing of the image lands here.
        textureStore(dst, id.xy, vec4<f32>(0.0, 0.0, 0.0, 1.0));
        return;
    }
    let q = h.xy / h.z;
    // The projective map's derivatives per pixel (one pixel right, one pixel down).
    let hx = u.inverse_pin[0] * pixel.x;
    let hy = -u.inverse_pin[1] * pixel.y;
    var dx = (hx.xy - q * hx.z) / h.z;
    var dy = (hy.xy - q * hy.z) / h.z;
    var uv = q;
    if u.grid.z < 0.5 {
        // Newton's method from the pinned point: meshes are gentle bends of the identity, and it
        // converges in two or three steps. It stops within 2e-6 (0.008 px at 4K): f32 cannot be
        // relied on to get much closer, and a tighter bound ran every pixel to the last step.
        var found = mesh(uv);
        for (var k = 0; k < 12; k++) {
            let r = found.at - q;
            if dot(r, r) < 4e-12 {
                break;
            }
            uv -= inverse2(found.jacobian) * r;
            found = mesh(uv);
        }
        if length(found.at - q) > 1e-4 {
            textureStore(dst, id.xy, vec4<f32>(0.0, 0.0, 0.0, 1.0));
            return;
        }
        let back = inverse2(found.jacobian);
        dx = back * dx;
        dy = back * dy;
    }
    // Coverage of the pixel by the image (the unit square in uv), side by side.
    let g = vec2<f32>(length(vec2<f32>(dx.x, dy.x)), length(vec2<f32>(dx.y, dy.y)));
    let coverage = covered(uv.x, g.x) * covered(1.0 - uv.x, g.x) * covered(uv.y, g.y) * covered(1.0 - uv.y, g.y);
    if coverage <= 0.0 {
        textureStore(dst, id.xy, vec4<f32>(0.0, 0.0, 0.0, 1.0));
        return;
    }
    let inside_uv = clamp(uv, vec2<f32>(0.0), vec2<f32>(1.0));
    let at = mix(u.region.xy, u.region.zw, inside_uv);
    var color = textureSampleLevel(src0, linear_clamp, vec2<f32>(at.x, 1.0 - at.y), 0.0).rgb;
    let w = side(inside_uv.x, u.blend.x) * side(1.0 - inside_uv.x, u.blend.y) * side(1.0 - inside_uv.y, u.blend.z)
        * side(inside_uv.y, u.blend.w);
    color = color * pow(w, u.shape.y);
    // The lift raises black where only this projector shines (outside every blend zone).
    let inside = inside_uv.x >= u.blend.x && 1.0 - inside_uv.x >= u.blend.y && 1.0 - inside_uv.y >= u.blend.z
        && inside_uv.y >= u.blend.w;
    if inside {
        color = u.shape.z + color * (1.0 - u.shape.z);
    }
    if u.shape.w > 0.5 {
        // Distance (in pixels) to the nearest mesh line, and to the nearest control point.
        let s = inside_uv * u.grid.xy;
        let footprint = max((abs(dx) + abs(dy)) * u.grid.xy, vec2<f32>(1e-6));
        let to_line = abs(s - round(s)) / footprint;
        let line = 1.0 - smoothstep(0.5, 1.5, min(to_line.x, to_line.y));
        let handle = 1.0 - smoothstep(5.0, 6.5, length(to_line));
        color = mix(color, vec3<f32>(0.1, 0.9, 1.0), line * 0.8);
        color = mix(color, vec3<f32>(1.0, 0.55, 0.1), handle);
    }
    textureStore(dst, id.xy, vec4<f32>(color * coverage, 1.0));
}
