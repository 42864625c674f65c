// The cubes drawn in compute (the steps shared in `shaders/splat_draw.wgsl`): each cube is found
// by a ray per sample (a slab test in the cube's own frame) instead of 12 triangles; a sample
// keeps the nearest face by (inverted depth bits, cube and face). Faces are flat (one normal,
// one view vector), so a face is shaded at the pixel centre by the fragment shader's own
// `face_colour`. A hit nearer than the near plane is dropped and the exit kept instead, as the
// pipeline shows the inside of a cube the plane cuts open.
// extends: cube_field.wgsl
// extends: splat_draw.wgsl

struct Cube {
    position_size: vec4<f32>, // xyz centre, w edge length
    rotation: vec4<f32>,      // unit quaternion (x, y, z, w)
};

@group(1) @binding(1) var<storage, read> cubes: array<Cube>;

fn conjugate(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

fn pixel_ray(p: vec2<f32>) -> vec3<f32> {
    return u.ray_origin.xyz + u.ray_x.xyz * p.x + u.ray_y.xyz * p.y;
}

// Depth (0 near, 1 far) of the point t along ray d from the camera; outside [0, 1) unseen.
fn depth_at(d: vec3<f32>, t: f32) -> f32 {
    let clip = u.view_proj * vec4<f32>(d * t, 1.0);
    return clip.z / clip.w;
}

// The visible face a ray meets: depth and face (axis 2 + 1 if the face points down the axis),
// face -1 for none.
struct Hit {
    depth: f32,
    face: i32,
};

// The local face (axis, sign) as its code.
fn face_code(axis: i32, negative: bool) -> i32 {
    return axis * 2 + select(0, 1, negative);
}

fn axis_of(v: vec3<f32>, value: f32) -> i32 {
    return select(select(2, 1, v.y == value), 0, v.x == value);
}

fn cube_hit(c: Cube, d: vec3<f32>) -> Hit {
    let q = conjugate(c.rotation);
    let o = rotate(q, -c.position_size.xyz);
    let dl = rotate(q, d);
    let half = c.position_size.w * 0.5;
    let t1 = (-half - o) / dl;
    let t2 = (half - o) / dl;
    let near = min(t1, t2);
    let far = max(t1, t2);
    let enter = max(max(near.x, near.y), near.z);
    let exit = min(min(far.x, far.y), far.z);
    if !(enter <= exit) || exit <= 0.0 {
        return Hit(1.0, -1);
    }
    // Entering through a face whose outward normal points against the ray.
    let enter_depth = depth_at(d, enter);
    if enter > 0.0 && enter_depth >= 0.0 && enter_depth < 1.0 {
        let axis = axis_of(near, enter);
        return Hit(enter_depth, face_code(axis, dl[axis] > 0.0));
    }
    let exit_depth = depth_at(d, exit);
    if exit_depth >= 0.0 && exit_depth < 1.0 {
        let axis = axis_of(far, exit);
        return Hit(exit_depth, face_code(axis, dl[axis] < 0.0));
    }
    return Hit(1.0, -1);
}

// The pixels with a sample the cube may cover: its corners' box on screen.
fn splat_box(c: Cube) -> PixelBox {
    var b = box_start();
    for (var k = 0u; k < 8u; k++) {
        let corner = vec3<f32>(f32(k & 1u), f32((k >> 1u) & 1u), f32(k >> 2u)) - 0.5;
        let world = c.position_size.xyz + rotate(c.rotation, corner * c.position_size.w);
        box_add(&b, u.view_proj * vec4<f32>(world, 1.0));
    }
    return box_pixels(b);
}

// Covers pixels first, first + step, … below `end` of the cube's box `b`.
fn cover(c: Cube, b: PixelBox, index: u32, first: i32, step: i32, end: i32) {
    for (var k = first; k < min(end, b.size.x * b.size.y); k += step) {
        let pixel = box_pixel(b.lo, b.size.x, k);
        for (var s = 0u; s < splat.samples; s++) {
            let hit = cube_hit(c, pixel_ray(sample_position(pixel, s)));
            if hit.face >= 0 {
                keep(pixel, s, ~bitcast<u32>(hit.depth), index * 8u + u32(hit.face) + 1u);
            }
        }
    }
}

// The hooks of `splat_draw.wgsl`'s entry points (and `splat_box`, `cover` above).

fn splat_primitive(index: u32) -> Cube {
    return cubes[index];
}

// The cube face a sample key names (cube × 8 + face + 1), shaded: faces are flat, so the
// pixel centre does not matter.
fn splat_shade(key: u32, centre: vec2<f32>) -> vec3<f32> {
    let c = cubes[(key - 1u) / 8u];
    let face = i32((key - 1u) % 8u);
    var normal = vec3<f32>(0.0);
    normal[face / 2] = select(1.0, -1.0, (face & 1) == 1);
    return face_colour(rotate(c.rotation, normal));
}
