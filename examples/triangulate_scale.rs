//! One timed run each of ours and the `earcut` crate on the large single rings of
//! `benches/triangulate.rs`'s `scale` group, where earcut takes too long for criterion's
//! repeated samples: `cargo run --release --example triangulate_scale -- [n] [--no-earcut]`
//! (n = points, 1,000,000 by default).

use std::time::Instant;

use indra::geometry::triangulate::Triangulator;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.iter().find_map(|a| a.parse().ok()).unwrap_or(1_000_000);
    let with_earcut = !args.iter().any(|a| a == "--no-earcut");
    let tau = std::f64::consts::TAU;
    let spiky = |i: usize| if i.is_multiple_of(2) { 1000.0 } else { 500.0 };
    let wavy = |i: usize| {
        let t = i as f64 / n as f64 * tau;
        1000.0 * (1.0 + 0.08 * (37.0 * t).sin() + 0.03 * (211.0 * t).cos())
    };
    let shapes: [(&str, &dyn Fn(usize) -> f64); 2] = [("spiky star", &spiky), ("wavy", &wavy)];
    for (name, radius) in shapes {
        let ring: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * tau;
                [radius(i) * t.cos(), radius(i) * t.sin()]
            })
            .collect();
        let coords: Vec<f64> = ring.iter().flatten().copied().collect();
        let mut out = Vec::new();
        let start = Instant::now();
        Triangulator::new().flat(&coords, &[], &mut out).expect("finite input");
        println!("{name}, {n} points: indra {:.3} s, {} triangles", start.elapsed().as_secs_f64(), out.len() / 3);
        if with_earcut {
            let mut theirs: Vec<u32> = Vec::new();
            let start = Instant::now();
            earcut::Earcut::new().earcut(ring.iter().copied(), &[], &mut theirs);
            println!(
                "{name}, {n} points: earcut {:.3} s, {} triangles",
                start.elapsed().as_secs_f64(),
                theirs.len() / 3
            );
        }
    }
}
