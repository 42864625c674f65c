// GPU cloth [UGP4 ch.3] (oishi): particles on a res x res grid, springs to 12 neighbours: the
// 8-ring (structural and shear) and four bend springs two particles away along the grid lines.
// (The sample's bend springs ran along the (+-2, +-2) diagonals, which barely resist a fold along a
// row: a hanging sheet in wind crumpled into grid-scale wrinkles under its pins.) Two solvers:
//   verlet  - the book's mass-spring model, F = k (|d| - L0) d^ per spring, damping once
//             (F -= damping v, a coefficient in kg/s; the sample subtracted it per neighbour),
//             x' = 2x - x_prev + F/m dt^2;
//   xpbd    - small-steps XPBD [Macklin et al. 2019, "Small Steps in Physics Simulation"]: predict,
//             then one Jacobi projection of every distance constraint with compliance alpha/dt^2,
//             corrections averaged per particle; plus long-range attachments [Kim, Chentanez &
//             Mueller 2012]: no particle farther from its pins than its rest distance, which a
//             Jacobi sweep (one row per substep) cannot achieve on a tall hanging cloth.
// Wind pushes along the local normal (see `wind_at`). Positions are vec4: xyz, w = inverse mass
// (0 = pinned; every free particle has the same). Each substep is one dispatch of 16x16
// workgroups over the res x res grid that stages a 20x20 tile (a halo of 2) in workgroup memory,
// so each of the 12 neighbour reads is local; the normals for drawing run one invocation per
// particle, once per frame, and check the positions for a blow-up there.
//
// Speed (H200, 1024^2, us per substep, Verlet / XPBD; a copy of the bytes a substep moves takes
// 12 us): 45 / 41 with the global reads issued a few at a time and the blow-up check in the
// substep; 26 / 33 with every read of an invocation in flight at once (both tile slots, its own
// previous position and normal) and the check once per frame; 24 / 28 with the neighbour tests
// left out of interior workgroups (see `at_border`); XPBD 29 with the fabric's bending on. Reading
// the attachment anchors early too, a packed normal, and normals made from the tile instead of
// read did not pay.

struct ClothUniforms {
    res: u32,            // particles per side
    count: u32,          // res * res
    solver: u32,         // 0 verlet, 1 xpbd
    bending: f32,        // xpbd: share of the way to the neighbours' mean per substep (0 = off)
    dt: f32,             // substep length, seconds
    rest: f32,           // structural rest length
    stiffness: f32,      // verlet spring constant k (N/m)
    damping: f32,        // verlet: velocity damping coefficient; xpbd: velocity retention loss per second
    mass: f32,           // particle mass (kg)
    compliance: f32,     // xpbd: inverse stiffness (m/N); 0 = inextensible
    sphere_radius: f32,  // collision sphere radius (0 = no sphere)
    attachments: u32,    // xpbd long-range attachments: 0 off, 1 top row, 2 two top corners
    acceleration: vec4<f32>, // gravity (xyz)
    sphere: vec4<f32>,       // collision sphere centre (xyz)
    wind: vec4<f32>,         // wind force / mass (xyz), felt along the local normal
};

@group(0) @binding(0) var<uniform> u: ClothUniforms;
@group(0) @binding(1) var<storage, read> prev: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> cur: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> next: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> status: array<atomic<u32>>;
// Vertex normals, written once per frame after its substeps (for drawing, and for the
// wind of the next step's substeps).
@group(0) @binding(5) var<storage, read_write> normals: array<vec4<f32>>;

// The 12 neighbours: the 8-ring, then the four bend springs (+-2, 0), (0, +-2) (see `spring`).

const TILE: u32 = 16u;
const SPAN: u32 = 20u; // TILE + 2 halo on each side
var<workgroup> tile: array<vec4<f32>, 400>;

// Each invocation fills two tile slots: `local` and `local + SECOND` (400 slots, 256 invocations;
// the second slot of the last 112 lies past the tile and is not stored).
const SECOND: u32 = TILE * TILE;

fn tile_origin(group: vec2<u32>) -> vec2<i32> {
    return vec2<i32>(group * TILE) - vec2<i32>(2);
}

// The particle that tile slot k stages (clamped at the grid border; a slot past the tile stages
// the last slot's particle, so its read stays in bounds).
fn tile_source(k: u32, origin: vec2<i32>) -> u32 {
    let slot = min(k, SPAN * SPAN - 1u);
    let last = vec2<i32>(i32(u.res) - 1);
    let c = clamp(origin + vec2<i32>(i32(slot % SPAN), i32(slot / SPAN)), vec2<i32>(0), last);
    return u32(c.y) * u.res + u32(c.x);
}

// Stores a staged value in slot k, if the slot is in the tile.
fn stage(k: u32, value: vec4<f32>) {
    if (k < SPAN * SPAN) {
        tile[k] = value;
    }
}

// Loads the workgroup's tile from `cur`, both slots' reads in flight together. Call from uniform
// control flow: every invocation takes part before any returns.
fn load_tile(local: u32, origin: vec2<i32>) {
    let first = cur[tile_source(local, origin)];
    let second = cur[tile_source(local + SECOND, origin)];
    stage(local, first);
    stage(local + SECOND, second);
    workgroupBarrier();
}

fn from_tile(c: vec2<i32>, origin: vec2<i32>) -> vec4<f32> {
    let t = c - origin;
    return tile[u32(t.y) * SPAN + u32(t.x)];
}

fn coord(i: u32) -> vec2<i32> {
    return vec2<i32>(i32(i % u.res), i32(i / u.res));
}

fn inside(c: vec2<i32>) -> bool {
    return all(c >= vec2<i32>(0)) && all(c < vec2<i32>(i32(u.res)));
}

fn index(c: vec2<i32>) -> u32 {
    return u32(c.y) * u.res + u32(c.x);
}

const SQRT2: f32 = 1.41421356;

// Whether the workgroup's tile reaches past the grid, so that some of its particles miss
// neighbours. The others (all but the outer ring of workgroups) skip the 12 per-neighbour tests:
// the substep is bound by instruction issue once its reads are in flight, and the tests were a
// fifth of the instructions (H200, 1024^2: 26.2 -> 23.6 us Verlet, 32.0 -> 28.2 us XPBD).
fn at_border(origin: vec2<i32>) -> bool {
    return any(origin < vec2<i32>(0)) || any(origin + vec2<i32>(i32(SPAN)) > vec2<i32>(i32(u.res)));
}

// Verlet: the force of the spring to neighbour c + offset (zero outside the grid; `border` as in
// `at_border`). Called once per neighbour with constant arguments: a dynamically indexed constant
// array would be copied to per-invocation memory by the SPIR-V backend.
fn spring(x: vec3<f32>, c: vec2<i32>, origin: vec2<i32>, offset: vec2<i32>, factor: f32, border: bool) -> vec3<f32> {
    let nc = c + offset;
    if (border && !inside(nc)) {
        return vec3<f32>(0.0);
    }
    let d = from_tile(nc, origin).xyz - x;
    // One inverse square root instead of a length and a divide (4% faster on the H200).
    let len2 = dot(d, d);
    let inv = inverseSqrt(max(len2, 1e-18));
    return (u.stiffness * (len2 * inv - factor * u.rest) * inv) * d;
}

// XPBD: this particle's correction from the constraint to neighbour c + offset (xyz), and 1 in w
// if the constraint exists. `weights` holds 1 / (w_self + w_other + alpha) for a free neighbour
// and for a pinned one: every free particle has the same inverse mass, so these are the only two
// (a divide per constraint cost 2%).
fn constraint(x: vec4<f32>, c: vec2<i32>, origin: vec2<i32>, offset: vec2<i32>, factor: f32, weights: vec2<f32>, border: bool) -> vec4<f32> {
    let nc = c + offset;
    if (border && !inside(nc)) {
        return vec4<f32>(0.0);
    }
    let other = from_tile(nc, origin);
    let d = x.xyz - other.xyz;
    let len2 = dot(d, d);
    let inv = inverseSqrt(max(len2, 1e-18));
    // Delta lambda from zero (one iteration per small step), applied to this particle only.
    let lambda = -(len2 * inv - factor * u.rest) * select(weights.x, weights.y, other.w == 0.0);
    return vec4<f32>((x.w * lambda * inv) * d, 1.0);
}

// Keeps p within `limit` of `anchor` (a unilateral distance constraint).
fn tether(p: vec3<f32>, anchor: vec3<f32>, limit: f32) -> vec3<f32> {
    let d = p - anchor;
    let len = length(d);
    return select(p, anchor + d / len * limit, len > limit);
}

// Long-range attachments: the top-row pin of the same column (at j rest lengths), or the two
// top corners (at their rest distances).
fn attach(p: vec3<f32>, c: vec2<i32>) -> vec3<f32> {
    let j = f32(c.y);
    if (u.attachments == 1u) {
        return tether(p, cur[u32(c.x)].xyz, j * u.rest);
    }
    if (u.attachments == 2u) {
        let far = f32(i32(u.res) - 1 - c.x);
        let q = tether(p, cur[0].xyz, sqrt(f32(c.x * c.x) + j * j) * u.rest);
        return tether(q, cur[u.res - 1u].xyz, sqrt(far * far + j * j) * u.rest);
    }
    return p;
}

// Wind acts on a sheet through the pressure on its faces: only the component of the wind along
// the normal pushes (a uniform force would shear the whole cloth sideways, which an
// inextensible grid without bending stiffness answers with grid-scale wrinkles). The normal is
// the one drawn last: the shape at the start of the clock step.
fn wind_at(i: u32) -> vec3<f32> {
    let n = normals[i].xyz;
    return dot(u.wind.xyz, n) * n;
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

// Flags a non-finite position so the CPU resets the cloth. Called once per frame from the normals
// pass, not per substep (where it cost 30% of the Verlet substep): a blown-up particle stays
// non-finite (NaN and infinity survive every later update), so the end of the frame sees it.
fn check(p: vec3<f32>) {
    let finite = all(abs(p) < vec3<f32>(1e30)) && all(p == p);
    if (!finite) {
        atomicStore(&status[0], 1u);
    }
}

// The sum of the 12 spring forces on the particle at c. Called with a constant `border` in each
// branch of a workgroup-uniform test, so that the compiler drops the neighbour tests inside.
fn springs(p0: vec3<f32>, c: vec2<i32>, origin: vec2<i32>, border: bool) -> vec3<f32> {
    var force = vec3<f32>(0.0);
    force += spring(p0, c, origin, vec2<i32>(-1, -1), SQRT2, border) + spring(p0, c, origin, vec2<i32>(0, -1), 1.0, border);
    force += spring(p0, c, origin, vec2<i32>(1, -1), SQRT2, border) + spring(p0, c, origin, vec2<i32>(1, 0), 1.0, border);
    force += spring(p0, c, origin, vec2<i32>(1, 1), SQRT2, border) + spring(p0, c, origin, vec2<i32>(0, 1), 1.0, border);
    force += spring(p0, c, origin, vec2<i32>(-1, 1), SQRT2, border) + spring(p0, c, origin, vec2<i32>(-1, 0), 1.0, border);
    force += spring(p0, c, origin, vec2<i32>(-2, 0), 2.0, border) + spring(p0, c, origin, vec2<i32>(2, 0), 2.0, border);
    force += spring(p0, c, origin, vec2<i32>(0, -2), 2.0, border) + spring(p0, c, origin, vec2<i32>(0, 2), 2.0, border);
    return force;
}

@compute @workgroup_size(16, 16, 1)
fn verlet(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let c = vec2<i32>(id.xy);
    let i = index(min(c, vec2<i32>(i32(u.res) - 1)));
    let before = prev[i].xyz;
    let wind = wind_at(i);
    let origin = tile_origin(group.xy);
    load_tile(local, origin);
    if (any(id.xy >= vec2<u32>(u.res))) {
        return;
    }
    let x = from_tile(c, origin);
    if (x.w == 0.0) {
        next[i] = x;
        return;
    }
    let v = (x.xyz - before) / u.dt;
    var force = (u.acceleration.xyz + wind) * u.mass - u.damping * v;
    let p0 = x.xyz;
    if (at_border(origin)) {
        force += springs(p0, c, origin, true);
    } else {
        force += springs(p0, c, origin, false);
    }
    let p = collide(2.0 * x.xyz - before + force / u.mass * u.dt * u.dt);
    next[i] = vec4<f32>(p, x.w);
}

// XPBD bending along one grid line: the offset from the particle to the midpoint of its two
// neighbours on the line (offset and -offset), and 1 in w if both exist. See `bending_share` in
// params.rs for the model.
fn bend(x: vec3<f32>, c: vec2<i32>, origin: vec2<i32>, offset: vec2<i32>, border: bool) -> vec4<f32> {
    if (border && !(inside(c - offset) && inside(c + offset))) {
        return vec4<f32>(0.0);
    }
    let mid = 0.5 * (from_tile(c - offset, origin).xyz + from_tile(c + offset, origin).xyz);
    return vec4<f32>(mid - x, 1.0);
}

// The summed corrections of the 12 constraints of the particle at c (as `springs`).
fn constraints(x: vec4<f32>, c: vec2<i32>, origin: vec2<i32>, weights: vec2<f32>, border: bool) -> vec4<f32> {
    var sum = constraint(x, c, origin, vec2<i32>(-1, -1), SQRT2, weights, border) + constraint(x, c, origin, vec2<i32>(0, -1), 1.0, weights, border);
    sum += constraint(x, c, origin, vec2<i32>(1, -1), SQRT2, weights, border) + constraint(x, c, origin, vec2<i32>(1, 0), 1.0, weights, border);
    sum += constraint(x, c, origin, vec2<i32>(1, 1), SQRT2, weights, border) + constraint(x, c, origin, vec2<i32>(0, 1), 1.0, weights, border);
    sum += constraint(x, c, origin, vec2<i32>(-1, 1), SQRT2, weights, border) + constraint(x, c, origin, vec2<i32>(-1, 0), 1.0, weights, border);
    sum += constraint(x, c, origin, vec2<i32>(-2, 0), 2.0, weights, border) + constraint(x, c, origin, vec2<i32>(2, 0), 2.0, weights, border);
    sum += constraint(x, c, origin, vec2<i32>(0, -2), 2.0, weights, border) + constraint(x, c, origin, vec2<i32>(0, 2), 2.0, weights, border);
    return sum;
}

// XPBD's projection of the particle at c: the averaged corrections of its 12 constraints, then
// its bending (as `springs` for `border`).
fn project(x: vec4<f32>, c: vec2<i32>, origin: vec2<i32>, weights: vec2<f32>, border: bool) -> vec3<f32> {
    let sum = constraints(x, c, origin, weights, border);
    // Averaging keeps the Jacobi sum from overshooting (Bridson et al. 2003 style).
    var p = x.xyz + sum.xyz * (1.5 / max(sum.w, 1.0));
    if (u.bending > 0.0) {
        let fold = bend(x.xyz, c, origin, vec2<i32>(1, 0), border) + bend(x.xyz, c, origin, vec2<i32>(0, 1), border);
        p += fold.xyz * (u.bending / max(fold.w, 1.0));
    }
    return p;
}

// XPBD's inertial prediction of a particle from its current and previous position and its wind
// (pinned particles stay).
fn predict(x: vec4<f32>, before: vec3<f32>, wind: vec3<f32>) -> vec4<f32> {
    let keep = max(1.0 - u.damping * u.dt, 0.0);
    let p = x.xyz + (x.xyz - before) * keep + (u.acceleration.xyz + wind) * u.dt * u.dt;
    return vec4<f32>(select(x.xyz, p, x.w != 0.0), x.w);
}

// XPBD, one small step in one pass: inertial prediction with gravity and wind, then one Jacobi
// projection of the 12 distance constraints of each particle, the long-range attachments and
// the collision. The workgroup predicts its tile and halo itself, so no predicted buffer goes
// through memory.
@compute @workgroup_size(16, 16, 1)
fn xpbd(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let c = vec2<i32>(id.xy);
    let origin = tile_origin(group.xy);
    let j = vec2<u32>(tile_source(local, origin), tile_source(local + SECOND, origin));
    let x0 = cur[j.x];
    let x1 = cur[j.y];
    let before0 = prev[j.x].xyz;
    let before1 = prev[j.y].xyz;
    let wind0 = wind_at(j.x);
    let wind1 = wind_at(j.y);
    stage(local, predict(x0, before0, wind0));
    stage(local + SECOND, predict(x1, before1, wind1));
    workgroupBarrier();
    if (any(id.xy >= vec2<u32>(u.res))) {
        return;
    }
    let i = index(c);
    let x = from_tile(c, origin);
    if (x.w == 0.0) {
        next[i] = x;
        return;
    }
    let alpha = u.compliance / (u.dt * u.dt);
    let weights = vec2<f32>(1.0 / (x.w + x.w + alpha), 1.0 / (x.w + alpha));
    var p: vec3<f32>;
    if (at_border(origin)) {
        p = project(x, c, origin, weights, true);
    } else {
        p = project(x, c, origin, weights, false);
    }
    p = collide(attach(p, c));
    next[i] = vec4<f32>(p, x.w);
}

// Vertex normals from central differences of the grid (one-sided at the borders), oriented
// consistently (+z facing for the undeformed cloth); never divides by zero.
@compute @workgroup_size(256, 1, 1)
fn compute_normals(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= u.count) {
        return;
    }
    check(cur[i].xyz);
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
