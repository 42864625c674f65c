// The cloth and its sphere drawn in compute (the steps shared in `shaders/splat_draw.wgsl`),
// for GPUs whose raster path is narrow (the H100/H200). Each triangle of the draw — the grid's
// two per cell, then the sphere's 32 × 16 × 2 — is found by a ray per sample: where the ray
// meets the triangle's plane, with barycentrics inside it, and its depth in [0, 1). A sample
// keeps the nearest by (inverted depth bits, triangle + 1): the pipeline's depth test (less or
// equal, the later triangle winning a tie). The resolve shades at the pixel centre with the
// barycentrics of the centre's ray — the perspective-correct interpolation the rasterizer gives
// `world` and `normal` — and the fragment shader's own `shade`. A hit nearer than the near plane
// is dropped, as the pipeline clips it.
// extends: cloth_render.wgsl
// extends: splat_draw.wgsl

// A triangle of the draw: corners, their normals, and whether it belongs to the sphere.
struct Triangle {
    a: vec3<f32>,
    b: vec3<f32>,
    c: vec3<f32>,
    na: vec3<f32>,
    nb: vec3<f32>,
    nc: vec3<f32>,
    sphere: bool,
};

// Particles per side of the grid.
fn grid_side() -> u32 {
    return u32(round(sqrt(f32(arrayLength(&positions)))));
}

// Triangle `index` in draw order: the surface's index buffer, then the sphere's vertices.
fn triangle(index: u32) -> Triangle {
    let res = grid_side();
    let surface = 2u * (res - 1u) * (res - 1u);
    if index < surface {
        let cell = index / 2u;
        let a = (cell / (res - 1u)) * res + cell % (res - 1u);
        var i = vec3<u32>(a, a + 1u, a + res);
        if (index & 1u) == 1u {
            i = vec3<u32>(a + 1u, a + res + 1u, a + res);
        }
        let p = array<vec3<f32>, 3>(positions[i.x].xyz, positions[i.y].xyz, positions[i.z].xyz);
        let n = array<vec3<f32>, 3>(normals[i.x].xyz, normals[i.y].xyz, normals[i.z].xyz);
        return Triangle(p[0], p[1], p[2], n[0], n[1], n[2], false);
    }
    let k = index - surface;
    let first = (k / 2u) * 6u + (k & 1u) * 3u;
    let v0 = sphere_vertex(first);
    let v1 = sphere_vertex(first + 1u);
    let v2 = sphere_vertex(first + 2u);
    return Triangle(v0.position, v1.position, v2.position, v0.direction, v1.direction, v2.direction, true);
}

// The ray from the camera through pixel position p (y down), not normalised.
fn pixel_ray(p: vec2<f32>) -> vec3<f32> {
    return view.ray_origin.xyz + view.ray_x.xyz * p.x + view.ray_y.xyz * p.y;
}

// Where ray d from the camera meets the triangle's plane: (t, barycentric of b, of c).
fn plane_hit(tr: Triangle, d: vec3<f32>) -> vec3<f32> {
    let e1 = tr.b - tr.a;
    let e2 = tr.c - tr.a;
    let pv = cross(d, e2);
    // A ray along the plane gives an infinite or undefined answer, which no test below passes.
    let inverse = 1.0 / dot(e1, pv);
    let tv = view.camera.xyz - tr.a;
    let qv = cross(tv, e1);
    return vec3<f32>(dot(e2, qv), dot(tv, pv), dot(d, qv)) * inverse;
}

// Depth (0 near, 1 far) of world point p.
fn depth_of(p: vec3<f32>) -> f32 {
    let clip = view.view_proj * vec4<f32>(p, 1.0);
    return clip.z / clip.w;
}

// The pixels with a sample the triangle may cover: its corners' box on screen.
fn splat_box(tr: Triangle) -> PixelBox {
    var b = box_start();
    box_add(&b, view.view_proj * vec4<f32>(tr.a, 1.0));
    box_add(&b, view.view_proj * vec4<f32>(tr.b, 1.0));
    box_add(&b, view.view_proj * vec4<f32>(tr.c, 1.0));
    return box_pixels(b);
}

// Covers pixels first, first + step, … below `end` of the triangle's box `b`.
fn cover(tr: Triangle, b: PixelBox, index: u32, first: i32, step: i32, end: i32) {
    for (var k = first; k < min(end, b.size.x * b.size.y); k += step) {
        let pixel = box_pixel(b.lo, b.size.x, k);
        for (var s = 0u; s < splat.samples; s++) {
            let d = pixel_ray(sample_position(pixel, s));
            let hit = plane_hit(tr, d);
            if hit.x > 0.0 && hit.y >= 0.0 && hit.z >= 0.0 && hit.y + hit.z <= 1.0 {
                let depth = depth_of(view.camera.xyz + d * hit.x);
                if depth >= 0.0 && depth < 1.0 {
                    keep(pixel, s, ~bitcast<u32>(depth), index + 1u);
                }
            }
        }
    }
}

// The hooks of `splat_draw.wgsl`'s entry points (and `splat_box`, `cover` above).

fn splat_primitive(index: u32) -> Triangle {
    return triangle(index);
}

// Triangle `key - 1` shaded at pixel position `centre`.
fn splat_shade(key: u32, centre: vec2<f32>) -> vec3<f32> {
    let tr = triangle(key - 1u);
    let hit = plane_hit(tr, pixel_ray(centre));
    let world = tr.a + (tr.b - tr.a) * hit.y + (tr.c - tr.a) * hit.z;
    let normal = tr.na * (1.0 - hit.y - hit.z) + tr.nb * hit.y + tr.nc * hit.z;
    let albedo = select(view.color.rgb, view.sphere_color.rgb, tr.sphere);
    return shade(world, normal, albedo).rgb;
}
