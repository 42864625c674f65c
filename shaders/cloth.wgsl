// GPU cloth [UGP4 ch.3] (oishi): particles on a res x res grid, springs to 12 neighbours (the
// 8-ring plus the four (+-2, +-2) diagonals). Two solvers:
//   verlet  - the book's mass-spring model, F = k (|d| - L0) d^ per spring, damping once
//             (F -= damping v, a coefficient in kg/s; the sample subtracted it per neighbour),
//             x' = 2x - x_prev + F/m dt^2;
//   xpbd    - small-steps XPBD [Macklin et al. 2019, "Small Steps in Physics Simulation"]: predict,
//             then one Jacobi projection of every distance constraint with compliance alpha/dt^2,
//             corrections averaged per particle; stiff without tiny explicit time steps.
// Positions are vec4: xyz, w = inverse mass (0 = pinned). One invocation per particle;
// dispatched over res*res particles.

struct ClothUniforms {
    res: u32,            // particles per side
    count: u32,          // res * res
    solver: u32,         // 0 verlet, 1 xpbd
    _pad0: u32,
    dt: f32,             // substep length, seconds
    rest: f32,           // structural rest length
    stiffness: f32,      // verlet spring constant k (N/m)
    damping: f32,        // verlet: velocity damping coefficient; xpbd: velocity retention loss per second
    mass: f32,           // particle mass (kg)
    compliance: f32,     // xpbd: inverse stiffness (m/N); 0 = inextensible
    sphere_radius: f32,  // collision sphere radius (0 = no sphere)
    _pad1: f32,
    acceleration: vec4<f32>, // gravity + wind force / mass (xyz)
    sphere: vec4<f32>,       // collision sphere centre (xyz)
};

@group(0) @binding(0) var<uniform> u: ClothUniforms;
@group(0) @binding(1) var<storage, read> prev: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> cur: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> next: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> status: array<atomic<u32>>;

// The 12 neighbour offsets: ring 1, then the distance-2 diagonals.
const OFFSETS = array<vec2<i32>, 12>(
    vec2<i32>(-1, -1), vec2<i32>(0, -1), vec2<i32>(1, -1), vec2<i32>(1, 0),
    vec2<i32>(1, 1), vec2<i32>(0, 1), vec2<i32>(-1, 1), vec2<i32>(-1, 0),
    vec2<i32>(-2, -2), vec2<i32>(2, -2), vec2<i32>(2, 2), vec2<i32>(-2, 2),
);

fn coord(i: u32) -> vec2<i32> {
    return vec2<i32>(i32(i % u.res), i32(i / u.res));
}

fn inside(c: vec2<i32>) -> bool {
    return all(c >= vec2<i32>(0)) && all(c < vec2<i32>(i32(u.res)));
}

fn index(c: vec2<i32>) -> u32 {
    return u32(c.y) * u.res + u32(c.x);
}

// Pushes p out of the sphere onto its surface.
fn collide(p: vec3<f32>) -> vec3<f32> {
    let d = p - u.sphere.xyz;
    let len = length(d);
    if (u.sphere_radius > 0.0 && len < u.sphere_radius) {
        return u.sphere.xyz + d / max(len, 1e-6) * u.sphere_radius;
    }
    return p;
}

// Flags a non-finite result so the CPU resets the cloth.
fn check(p: vec3<f32>) {
    let finite = all(abs(p) < vec3<f32>(1e30)) && all(p == p);
    if (!finite) {
        atomicStore(&status[0], 1u);
    }
}

@compute @workgroup_size(256, 1, 1)
fn verlet(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= u.count) {
        return;
    }
    let x = cur[i];
    if (x.w == 0.0) {
        next[i] = x;
        return;
    }
    let c = coord(i);
    let v = (x.xyz - prev[i].xyz) / u.dt;
    var force = u.acceleration.xyz * u.mass - u.damping * v;
    for (var k = 0; k < 12; k = k + 1) {
        let nc = c + OFFSETS[k];
        if (!inside(nc)) {
            continue;
        }
        let d = cur[index(nc)].xyz - x.xyz;
        let len = length(d);
        let rest = length(vec2<f32>(OFFSETS[k])) * u.rest;
        force += u.stiffness * (len - rest) * d / max(len, 1e-9);
    }
    let p = collide(2.0 * x.xyz - prev[i].xyz + force / u.mass * u.dt * u.dt);
    check(p);
    next[i] = vec4<f32>(p, x.w);
}

// XPBD step 1: inertial prediction with external acceleration (writes `next`).
@compute @workgroup_size(256, 1, 1)
fn predict(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= u.count) {
        return;
    }
    let x = cur[i];
    if (x.w == 0.0) {
        next[i] = x;
        return;
    }
    let keep = max(1.0 - u.damping * u.dt, 0.0);
    let p = x.xyz + (x.xyz - prev[i].xyz) * keep + u.acceleration.xyz * u.dt * u.dt;
    next[i] = vec4<f32>(p, x.w);
}

// XPBD step 2: one Jacobi projection of the 12 distance constraints of each particle, reading
// the predicted positions (bound as `cur`) and writing the projected ones; then collision.
@compute @workgroup_size(256, 1, 1)
fn project(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= u.count) {
        return;
    }
    let x = cur[i];
    if (x.w == 0.0) {
        next[i] = x;
        return;
    }
    let c = coord(i);
    let alpha = u.compliance / (u.dt * u.dt);
    var correction = vec3<f32>(0.0);
    var n = 0.0;
    for (var k = 0; k < 12; k = k + 1) {
        let nc = c + OFFSETS[k];
        if (!inside(nc)) {
            continue;
        }
        let other = cur[index(nc)];
        let d = x.xyz - other.xyz;
        let len = length(d);
        let rest = length(vec2<f32>(OFFSETS[k])) * u.rest;
        let w = x.w + other.w;
        // Delta lambda from zero (one iteration per small step), applied to this particle only.
        let lambda = -(len - rest) / (w + alpha);
        correction += x.w * lambda * d / max(len, 1e-9);
        n += 1.0;
    }
    // Averaging keeps the Jacobi sum from overshooting (Bridson et al. 2003 style).
    let p = collide(x.xyz + correction * (1.5 / max(n, 1.0)));
    check(p);
    next[i] = vec4<f32>(p, x.w);
}

// Vertex normals from central differences of the grid (one-sided at the borders), oriented
// consistently (+z facing for the undeformed cloth); never divides by zero.
@group(0) @binding(5) var<storage, read_write> normals: array<vec4<f32>>;

@compute @workgroup_size(256, 1, 1)
fn compute_normals(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= u.count) {
        return;
    }
    let c = coord(i);
    let last = i32(u.res) - 1;
    let l = cur[index(vec2<i32>(max(c.x - 1, 0), c.y))].xyz;
    let r = cur[index(vec2<i32>(min(c.x + 1, last), c.y))].xyz;
    let d = cur[index(vec2<i32>(c.x, max(c.y - 1, 0)))].xyz;
    let t = cur[index(vec2<i32>(c.x, min(c.y + 1, last)))].xyz;
    let n = cross(t - d, r - l);
    let len = length(n);
    normals[i] = vec4<f32>(select(vec3<f32>(0.0, 0.0, 1.0), n / len, len > 1e-12), 0.0);
}
