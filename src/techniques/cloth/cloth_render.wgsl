// Drawing the cloth [UGP4 ch.3]: the surface as an indexed grid whose vertices are particles
// (fetched by integer index, never by UV), shaded on both sides by flipping normals that face
// away from the camera; the collision sphere, generated from the vertex index; and the debug
// view: particles as points, springs as lines coloured by kind (instance index).

struct ClothView {
    view_proj: mat4x4<f32>,
    camera: vec4<f32>,       // camera position (xyz), half the cloth's rest width (w)
    light_dir: vec4<f32>,    // towards the light (xyz, unit)
    color: vec4<f32>,        // linear cloth colour
    sphere_color: vec4<f32>, // linear sphere colour (rgb), output aspect (w)
    sphere: vec4<f32>,       // centre (xyz), radius (w)
    // The compute draw's camera rays: through pixel position p (y down) runs
    // ray_origin + ray_x p.x + ray_y p.y from the camera.
    ray_origin: vec4<f32>,
    ray_x: vec4<f32>,
    ray_y: vec4<f32>,
};

@group(0) @binding(0) var<uniform> view: ClothView;
@group(0) @binding(1) var<storage, read> positions: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> normals: array<vec4<f32>>;

struct Shaded {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
};

fn shade(world: vec3<f32>, normal: vec3<f32>, albedo: vec3<f32>) -> vec4<f32> {
    var n = normalize(normal);
    let v = normalize(view.camera.xyz - world);
    if (dot(n, v) < 0.0) {
        n = -n; // the back of the cloth
    }
    let l = view.light_dir.xyz;
    let h = normalize(l + v);
    let diffuse = max(dot(n, l), 0.0);
    let specular = pow(max(dot(n, h), 0.0), 32.0) * 0.25 * select(0.0, 1.0, diffuse > 0.0);
    return vec4<f32>(albedo * (0.25 + 0.85 * diffuse) + vec3<f32>(specular), 1.0);
}

// One invocation per index of the surface grid; the index is the particle.
@vertex
fn vs_surface(@builtin(vertex_index) particle: u32) -> Shaded {
    let p = positions[particle].xyz;
    var out: Shaded;
    out.clip = view.view_proj * vec4<f32>(p, 1.0);
    out.world = p;
    out.normal = normals[particle].xyz;
    return out;
}

@fragment
fn fs_surface(in: Shaded) -> @location(0) vec4<f32> {
    return shade(in.world, in.normal, view.color.rgb);
}

const SPHERE_SEGMENTS: u32 = 32u;
const SPHERE_RINGS: u32 = 16u;
const PI: f32 = 3.14159265;

// A vertex of the sphere: its position and its outward direction.
struct SphereVertex {
    position: vec3<f32>,
    direction: vec3<f32>,
};

// Vertex `index` of the sphere's 32 x 16 quads, 6 vertices each.
fn sphere_vertex(index: u32) -> SphereVertex {
    let quad = index / 6u;
    let corner = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0),
    )[index % 6u];
    let s = (f32(quad % SPHERE_SEGMENTS) + corner.x) / f32(SPHERE_SEGMENTS);
    let r = (f32(quad / SPHERE_SEGMENTS) + corner.y) / f32(SPHERE_RINGS);
    let theta = r * PI;
    let phi = s * 2.0 * PI;
    let dir = vec3<f32>(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
    return SphereVertex(view.sphere.xyz + dir * view.sphere.w * 0.985, dir); // just inside the collider
}

@vertex
fn vs_sphere(@builtin(vertex_index) index: u32) -> Shaded {
    let v = sphere_vertex(index);
    var out: Shaded;
    out.clip = view.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.direction;
    return out;
}

@fragment
fn fs_sphere(in: Shaded) -> @location(0) vec4<f32> {
    return shade(in.world, in.normal, view.sphere_color.rgb);
}

struct Flat {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

// Debug: one point per particle (cyan), or one line end per index; the instance index is the
// spring kind: 0 structural (blue), 1 shear (green), 2 bend, two along a grid line (red).
@vertex
fn vs_debug(@builtin(vertex_index) particle: u32, @builtin(instance_index) kind: u32) -> Flat {
    let colors = array<vec4<f32>, 4>(
        vec4<f32>(0.1, 0.3, 1.0, 1.0), vec4<f32>(0.1, 1.0, 0.2, 1.0), vec4<f32>(1.0, 0.15, 0.1, 1.0),
        vec4<f32>(0.2, 1.0, 1.0, 1.0),
    );
    var out: Flat;
    out.clip = view.view_proj * vec4<f32>(positions[particle].xyz, 1.0);
    // Lines and points add up (one + one): each at a fraction of full intensity, so that where
    // hundreds overlap the kinds still read as colours instead of saturating to white.
    out.color = colors[min(kind, 3u)] * 0.3;
    return out;
}

@fragment
fn fs_debug(in: Flat) -> @location(0) vec4<f32> {
    return in.color;
}

// Debug insets: the position buffer (xyz mapped from the cloth's rest extent to colour) and the
// normal buffer (n * 0.5 + 0.5), each as a res x res image in the top-left corner of the view.
// Instance 0 draws positions, instance 1 normals.
struct Inset {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) which: u32,
};

@vertex
fn vs_inset(@builtin(vertex_index) index: u32, @builtin(instance_index) which: u32) -> Inset {
    let corner = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0),
    )[index];
    // Each inset is 0.4 clip units high, square in pixels, stacked left to right from the corner.
    let aspect = view.sphere_color.w; // the render shader stores the output aspect here
    let size = vec2<f32>(0.4 / aspect, 0.4);
    let origin = vec2<f32>(-0.98 + f32(which) * (size.x + 0.02), 0.98 - size.y);
    var out: Inset;
    out.clip = vec4<f32>(origin + corner * size, 0.0, 1.0);
    out.uv = vec2<f32>(corner.x, 1.0 - corner.y);
    out.which = which;
    return out;
}

@fragment
fn fs_inset(in: Inset) -> @location(0) vec4<f32> {
    let res = u32(round(sqrt(f32(arrayLength(&positions)))));
    let cell = min(vec2<u32>(in.uv * f32(res)), vec2<u32>(res - 1u));
    let i = cell.y * res + cell.x;
    if (in.which == 0u) {
        let extent = max(view.camera.w, 1e-6); // half the cloth's rest width, stored in camera.w
        return vec4<f32>(positions[i].xyz / (2.0 * extent) + 0.5, 1.0);
    }
    return vec4<f32>(normals[i].xyz * 0.5 + 0.5, 1.0);
}
