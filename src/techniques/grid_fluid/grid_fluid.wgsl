// Stable fluids (Stam 1999) on an N×N grid, the displacement source of chapter 6 (the book uses
// the vol.1 grid fluid). Every field is a slot of N² floats in one storage buffer; each dispatch
// gets its own uniform block (dynamic offset) naming the slots it reads and writes. Every kernel
// is one thread per cell and reads only what the previous dispatch wrote (ping-pong), so results
// never depend on thread timing.
//
// Fixes of the sample (seed-reference §9 item 22): the advection clamp is applied; the divergence
// is −½((u_r − u_l) + (v_t − v_b)) for both axes; pressure is solved (Jacobi) and its gradient
// subtracted; diffusion and pressure iterate between two slots, never in place; velocity is
// self-advected; density dissipates.

struct Dispatch {
    n: u32,
    // Slots (field indices) this dispatch reads and writes.
    src: u32,
    dst: u32,
    aux: u32,
    // Jacobi: dst = (c0·aux + a·Σneighbours(src)) / c1.
    a: f32,
    c0: f32,
    c1: f32,
    // Seconds of this step.
    dt: f32,
    // Source splat: centre (cells), radius (cells), velocity impulse (cells/s), density amount.
    centre: vec2<f32>,
    impulse: vec2<f32>,
    radius: f32,
    density: f32,
    // Density kept after advection (dissipation), 1 = none.
    keep: f32,
    // Which velocity component a boundary pass treats (0 = u, 1 = v), or the slot of v.
    second: u32,
}

@group(0) @binding(0) var<uniform> d: Dispatch;
@group(0) @binding(1) var<storage, read_write> fields: array<f32>;
@group(0) @binding(2) var output: texture_storage_2d<rgba16float, write>;

fn at(slot: u32, x: i32, y: i32) -> f32 {
    let n = i32(d.n);
    let cx = clamp(x, 0, n - 1);
    let cy = clamp(y, 0, n - 1);
    return fields[slot * d.n * d.n + u32(cy) * d.n + u32(cx)];
}

fn index(slot: u32, x: u32, y: u32) -> u32 {
    return slot * d.n * d.n + y * d.n + x;
}

fn on_wall(x: u32, y: u32) -> bool {
    return x == 0u || y == 0u || x == d.n - 1u || y == d.n - 1u;
}

// Adds the cursor's splat: velocity into slots src (u) and dst (v), density into aux.
// Falloff f = saturate(1 − |p − c|² / R²), as the sample's source pass.
@compute @workgroup_size(16, 16)
fn add_source(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= d.n || id.y >= d.n || on_wall(id.x, id.y) {
        return;
    }
    let p = vec2<f32>(f32(id.x), f32(id.y)) + 0.5;
    let q = (p - d.centre) / max(d.radius, 1e-3);
    let f = clamp(1.0 - dot(q, q), 0.0, 1.0);
    if f <= 0.0 {
        return;
    }
    fields[index(d.src, id.x, id.y)] += d.impulse.x * f * d.dt;
    fields[index(d.dst, id.x, id.y)] += d.impulse.y * f * d.dt;
    fields[index(d.aux, id.x, id.y)] += d.density * f * d.dt;
}

// dst = src (saving x0 before diffusion).
@compute @workgroup_size(16, 16)
fn copy(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= d.n || id.y >= d.n {
        return;
    }
    fields[index(d.dst, id.x, id.y)] = fields[index(d.src, id.x, id.y)];
}

// One Jacobi sweep of (c1·x − a·Σ neighbours = c0·aux): diffusion (c0 = 1, c1 = 1 + 4a) and the
// pressure Poisson equation (a = 1, c0 = 1, c1 = 4). Neighbours past the wall read the wall cell
// (zero normal derivative). The sum is ordered (l + r) + (b + t) so mirrored set-ups stay mirrored.
@compute @workgroup_size(16, 16)
fn jacobi(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= d.n || id.y >= d.n {
        return;
    }
    let x = i32(id.x);
    let y = i32(id.y);
    let sum = (at(d.src, x - 1, y) + at(d.src, x + 1, y)) + (at(d.src, x, y - 1) + at(d.src, x, y + 1));
    fields[index(d.dst, id.x, id.y)] = (d.c0 * at(d.aux, x, y) + d.a * sum) / d.c1;
}

// Velocity (slots src = u, second = v) is zero on the walls: a closed box, no slip.
@compute @workgroup_size(16, 16)
fn walls(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= d.n || id.y >= d.n || !on_wall(id.x, id.y) {
        return;
    }
    fields[index(d.src, id.x, id.y)] = 0.0;
    fields[index(d.second, id.x, id.y)] = 0.0;
}

// dst = −½((u_r − u_l) + (v_t − v_b)) with u in slot src, v in slot second; pressure (aux) = 0.
@compute @workgroup_size(16, 16)
fn divergence(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= d.n || id.y >= d.n {
        return;
    }
    let x = i32(id.x);
    let y = i32(id.y);
    let du = at(d.src, x + 1, y) - at(d.src, x - 1, y);
    let dv = at(d.second, x, y + 1) - at(d.second, x, y - 1);
    fields[index(d.dst, id.x, id.y)] = -0.5 * (du + dv);
    fields[index(d.aux, id.x, id.y)] = 0.0;
}

// u −= ½(p_r − p_l), v −= ½(p_t − p_b): u in slot src, v in slot second, p in aux.
@compute @workgroup_size(16, 16)
fn subtract_gradient(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= d.n || id.y >= d.n || on_wall(id.x, id.y) {
        return;
    }
    let x = i32(id.x);
    let y = i32(id.y);
    fields[index(d.src, id.x, id.y)] -= 0.5 * (at(d.aux, x + 1, y) - at(d.aux, x - 1, y));
    fields[index(d.second, id.x, id.y)] -= 0.5 * (at(d.aux, x, y + 1) - at(d.aux, x, y - 1));
}

// Semi-Lagrangian advection of slot src into dst along the velocity (u in slot aux, v in slot
// second), in cells per second; the backtrace is clamped inside the box (the sample dropped its
// clamp). The result is scaled by `keep` (dissipation).
@compute @workgroup_size(16, 16)
fn advect(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= d.n || id.y >= d.n {
        return;
    }
    let i = index(0u, id.x, id.y);
    let velocity = vec2<f32>(fields[d.aux * d.n * d.n + i], fields[d.second * d.n * d.n + i]);
    let limit = f32(d.n) - 1.0;
    let back = clamp(vec2<f32>(f32(id.x), f32(id.y)) - d.dt * velocity, vec2<f32>(0.0), vec2<f32>(limit));
    let base = floor(back);
    let t = back - base;
    let x0 = i32(base.x);
    let y0 = i32(base.y);
    let bottom = mix(at(d.src, x0, y0), at(d.src, x0 + 1, y0), t.x);
    let top = mix(at(d.src, x0, y0 + 1), at(d.src, x0 + 1, y0 + 1), t.x);
    fields[index(d.dst, id.x, id.y)] = mix(bottom, top, t.y) * d.keep;
}

// The density (slot src) as an image, y up: row 0 of the texture is the top of the box.
@compute @workgroup_size(16, 16)
fn write_output(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= d.n || id.y >= d.n {
        return;
    }
    let density = fields[index(d.src, id.x, id.y)];
    textureStore(output, vec2<i32>(i32(id.x), i32(d.n - 1u - id.y)), vec4<f32>(density, density, density, 1.0));
}
