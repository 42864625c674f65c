//! Estimates what a Kleinian frame costs the GPU: the mean and the warp-maximum escape-time
//! iteration count per sample (the GPU pays the slowest lane of each 32-lane warp, an 8×4 tile
//! of the 8×8 workgroup), from the CPU version of the membership test at pixel centres; and,
//! for adaptive sampling, the share of pixels whose 4 × 4 neighbouring corners are not all one
//! class (they take every sample) and of warps holding one (they wait for it).
//!
//! `cargo run --release --example kleinian_cost -- [width height u v scale iterations]`
//! (defaults: the book's first demo at frame 0, 1920×1080, 50 iterations).

use indra::techniques::kleinian::reference::{classify, pixel_to_plane};

fn main() {
    let args: Vec<f64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let arg = |i: usize, default: f64| args.get(i).copied().unwrap_or(default);
    let (w, h) = (arg(0, 1920.0) as u32, arg(1, 1080.0) as u32);
    let t = [arg(2, 1.98795) as f32, arg(3, 0.005859) as f32];
    let (scale, cap) = (arg(4, 1.9) as f32, arg(5, 50.0) as u32);
    let cost = |x: u32, y: u32| classify(pixel_to_plane(x, y, h, scale, [0.0, 0.0]), t, cap).1;
    // Corner (i, j) of the grid with its one-corner margin sits at pixel-space point (i-1, j-1).
    let hf = h as f32;
    let corner_hit: Vec<bool> = (0..h + 3)
        .flat_map(|j| (0..w + 3).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (x, y) = (i as f32 - 1.0, j as f32 - 1.0);
            classify([x / hf * scale, (1.0 - y / hf) * scale], t, cap).0
        })
        .collect();
    let is_edge = |x: u32, y: u32| {
        let first = corner_hit[(y * (w + 3) + x) as usize];
        (y..y + 4).any(|j| (x..x + 4).any(|i| corner_hit[(j * (w + 3) + i) as usize] != first))
    };
    let (mut sum, mut warp_max_sum, mut warps, mut edges, mut edge_warps) = (0u64, 0u64, 0u64, 0u64, 0u64);
    for ty in (0..h).step_by(4) {
        for tx in (0..w).step_by(8) {
            let (mut worst, mut holds_edge) = (0, false);
            for y in ty..(ty + 4).min(h) {
                for x in tx..(tx + 8).min(w) {
                    let c = cost(x, y);
                    sum += u64::from(c);
                    worst = worst.max(c);
                    let edge = is_edge(x, y);
                    edges += u64::from(edge);
                    holds_edge |= edge;
                }
            }
            warp_max_sum += u64::from(worst) * 32;
            warps += 1;
            edge_warps += u64::from(holds_edge);
        }
    }
    let pixels = f64::from(w) * f64::from(h);
    println!(
        "{w}x{h} t=({}, {}) scale {scale} cap {cap}: mean {:.2} iterations/sample, warp-max mean {:.2}; \
         adaptive: edge pixels {:.2}%, warps holding one {:.2}%",
        t[0],
        t[1],
        sum as f64 / pixels,
        warp_max_sum as f64 / (warps as f64 * 32.0),
        edges as f64 / pixels * 100.0,
        edge_warps as f64 / warps as f64 * 100.0
    );
}
