//! One growth step on the CPU, with the GPU's exact rules (brute-force search, lowest index on
//! ties, 16.16 fixed-point direction sums, candidates in node order, the same mass hash) — the
//! reference the GPU step is tested against.

use super::cloud::{Attraction, NONE, Node};
use super::params::GrowthUniforms;

/// Fixed-point scale of the direction sums (the shader's `FIXED`).
pub const FIXED: f32 = 65536.0;
/// Shortest mean direction that still gives a candidate (the shader's `MIN_MEAN`).
pub const MIN_MEAN: f32 = 1e-3;

fn distance2(a: [f32; 3], b: [f32; 3]) -> f32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

/// The nearest node strictly within `sqrt(reach2)` of `p`, lowest index on ties.
pub fn nearest_node(nodes: &[Node], p: [f32; 3], reach2: f32) -> u32 {
    let mut best = (reach2, NONE);
    for (j, n) in nodes.iter().enumerate() {
        let d2 = distance2(n.pos, p);
        if d2 < best.0 {
            best = (d2, j as u32);
        }
    }
    best.1
}

/// The shader's PCG hash.
pub fn hash(x: u32) -> u32 {
    let state = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The mass of a node in slot `slot`.
pub fn mass(u: &GrowthUniforms, slot: u32) -> f32 {
    let t = (hash(slot ^ u.hash_seed) >> 8) as f32 / 16_777_216.0;
    u.mass_min * (1.0 - t) + u.mass_max * t
}

/// Runs one growth step (search, attract, connect, remove, grow) on `attractions` and `nodes`.
pub fn step(attractions: &mut [Attraction], nodes: &mut Vec<Node>, u: &GrowthUniforms) {
    // Search: each live attraction's nearest node; unit vectors summed per node, fixed point.
    let mut sums = vec![([0i32; 3], 0i32, i32::MAX); nodes.len()];
    for (i, a) in attractions.iter_mut().enumerate() {
        a.nearest = NONE;
        if a.alive == 0 {
            continue;
        }
        let n = nearest_node(nodes, a.pos, u.influence * u.influence);
        a.nearest = n;
        if n == NONE {
            continue;
        }
        let np = nodes[n as usize].pos;
        let len = distance2(a.pos, np).sqrt();
        if len <= 0.0 {
            continue;
        }
        let s = &mut sums[n as usize];
        for (k, sum) in s.0.iter_mut().enumerate() {
            *sum = sum.wrapping_add(((a.pos[k] - np[k]) / len * FIXED).round_ties_even() as i32);
        }
        s.1 += 1;
        s.2 = s.2.min(i as i32);
    }
    // Attract + connect: candidates in node order take the next free slots.
    let count = nodes.len();
    for i in 0..count {
        let (sum, chosen_by, first) = sums[i];
        let node = nodes[i];
        if node.t < 1.0 || chosen_by == 0 {
            continue;
        }
        let v = sum.map(|c| c as f32);
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if len <= MIN_MEAN * FIXED * chosen_by as f32 {
            continue;
        }
        let slot = nodes.len() as u32;
        if slot >= u.capacity {
            continue;
        }
        let pos = std::array::from_fn(|k| node.pos[k] + v[k] / len * u.growth);
        let skin = attractions[first as usize].skin;
        nodes.push(Node { pos, t: 0.0, depth: node.depth + 1, mass: mass(u, slot), parent: i as u32, skin });
    }
    // Remove: attractions within the kill distance of any node (the new ones included) die.
    for a in attractions.iter_mut().filter(|a| a.alive != 0) {
        if nearest_node(nodes, a.pos, u.kill * u.kill) != NONE {
            a.alive = 0;
        }
    }
    // Grow.
    for n in nodes.iter_mut() {
        n.t = (n.t + u.grow_step * n.mass).min(1.0);
    }
}
