// Spinning white cubes lit by one directional light with Blinn-Phong, rendered into linear HDR:
// specular glints exceed 1.0, which is what StarGlow's threshold picks out [UGP4 ch.4 sample].
// The cube's 36 vertices come from the vertex index; each instance is a position, an edge
// length and a rotation quaternion.

struct CubeFieldUniforms {
    view_proj: mat4x4<f32>,
    light_dir: vec4<f32>,      // xyz: direction towards the light (world, unit)
    light_color: vec4<f32>,    // rgb: linear colour x intensity
    albedo: vec4<f32>,         // rgb: linear surface colour
    ambient: f32,              // constant fill
    specular: f32,             // specular strength (HDR peaks ~ specular x light)
    shininess: f32,            // Blinn-Phong exponent
    _pad: f32,
    // The compute draw's camera rays: through pixel position p (y down) runs
    // ray_origin + ray_x p.x + ray_y p.y from the camera at the origin.
    ray_origin: vec4<f32>,
    ray_x: vec4<f32>,
    ray_y: vec4<f32>,
};

struct Instance {
    @location(0) position_size: vec4<f32>,  // xyz centre, w edge length
    @location(1) rotation: vec4<f32>,       // unit quaternion (x, y, z, w)
};

@group(0) @binding(0) var<uniform> u: CubeFieldUniforms;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
};

fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

// Face f (0..5: +x -x +y -y +z -z), corner c (0..5: two triangles of the face's quad).
@vertex
fn vs_main(@builtin(vertex_index) index: u32, instance: Instance) -> VertexOut {
    let face = index / 6u;
    let corner = index % 6u;
    let axis = face / 2u;
    let sign = select(1.0, -1.0, (face & 1u) == 1u);
    // Quad corners in (s, t): triangles (0,1,2) and (0,2,3) of (-1,-1) (1,-1) (1,1) (-1,1).
    let quad = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let st = quad[corner] * sign;
    var local = vec3<f32>(sign, st.x, st.y);
    var normal = vec3<f32>(sign, 0.0, 0.0);
    if (axis == 1u) {
        local = vec3<f32>(st.y, sign, st.x);
        normal = vec3<f32>(0.0, sign, 0.0);
    } else if (axis == 2u) {
        local = vec3<f32>(st.x, st.y, sign);
        normal = vec3<f32>(0.0, 0.0, sign);
    }
    let world = instance.position_size.xyz + rotate(instance.rotation, local * 0.5 * instance.position_size.w);
    var out: VertexOut;
    out.clip = u.view_proj * vec4<f32>(world, 1.0);
    out.normal = rotate(instance.rotation, normal);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(face_colour(in.normal), 1.0);
}

// The colour of a face with (world) normal `normal`.
fn face_colour(normal: vec3<f32>) -> vec3<f32> {
    let n = normalize(normal);
    let l = u.light_dir.xyz;
    // The camera looks down +z from the origin; for small cubes far away the view vector is ~ -z.
    let v = vec3<f32>(0.0, 0.0, -1.0);
    let h = normalize(l + v);
    let diffuse = max(dot(n, l), 0.0);
    let spec = select(0.0, pow(max(dot(n, h), 0.0), u.shininess), diffuse > 0.0);
    return u.albedo.rgb * (u.ambient + diffuse * u.light_color.rgb) + u.specular * spec * u.light_color.rgb;
}
