// The book's DrawTest [UGP4 ch.5]: a triangulated polygon set filled with a generated UV checker
// (UVs from the bounding rectangle of all polygons), its triangle edges as a wireframe, and the
// loop being drawn in a hue that cycles with time.

struct PolygonUniforms {
    view_proj: mat4x4<f32>,
    loop_color: vec4<f32>,   // rgb: colour of the open loop (linear)
    checker: f32,            // checker cells across the UV range
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
};

@group(0) @binding(0) var<uniform> u: PolygonUniforms;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

@vertex
fn vs_main(@location(0) position: vec2<f32>, @location(1) uv: vec2<f32>) -> VertexOut {
    var out: VertexOut;
    out.clip = u.view_proj * vec4<f32>(position, 0.0, 1.0);
    out.uv = uv;
    return out;
}

// Checker cells tinted by UV (red along u, blue along v), so the mapping reads at a glance.
@fragment
fn fs_fill(in: VertexOut) -> @location(0) vec4<f32> {
    let cell = floor(in.uv * u.checker);
    let odd = (i32(cell.x) + i32(cell.y)) & 1;
    let base = vec3<f32>(0.25 + 0.6 * in.uv.x, 0.35, 0.25 + 0.6 * in.uv.y);
    let shade = select(1.0, 0.35, odd == 1);
    return vec4<f32>(pow(base * shade, vec3<f32>(2.2)), 1.0);
}

@fragment
fn fs_wire(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(0.9, 0.9, 0.9, 1.0);
}

@fragment
fn fs_loop(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(u.loop_color.rgb, 1.0);
}
