//! Triangulation, ours against the `earcut` (georust) and `earcutr` crates on the same inputs:
//! earcut's fixtures (building 15 vertices … water-huge2 5,488 vertices / 443 rings) and a
//! generated star polygon of 20,000 vertices with 400 holes. Each library reuses its buffers where
//! its API allows. Run: `cargo bench --bench triangulate`; report ours/earcut as ratios.
//!
//! The `scale` group times ours alone on inputs where both crates take seconds to minutes (they
//! grow quadratically there): a 10⁶-point star with spikes of twice the inner radius, a wavy
//! 10⁶-gon, and 10⁵ separate squares read by nesting.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use indra::geometry::triangulate::Triangulator;

#[path = "../tests/common/earcut_fixtures.rs"]
mod earcut_fixtures;

struct Input {
    name: String,
    coords: Vec<f64>,
    holes: Vec<usize>,
}

fn from_rings(name: &str, rings: &[earcut_fixtures::Ring]) -> Input {
    let (coords, holes) = earcut_fixtures::flat(rings);
    Input { name: name.to_string(), coords, holes }
}

/// A wavy star of `n` vertices with a grid of small square holes inside its inner disc.
fn generated(n: usize, holes_per_side: usize) -> Input {
    let outer: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            let r = 1000.0 * (1.0 + 0.08 * (37.0 * t).sin() + 0.03 * (211.0 * t).cos());
            [r * t.cos(), r * t.sin()]
        })
        .collect();
    let mut rings = vec![outer];
    let pitch = 1200.0 / holes_per_side as f64;
    for i in 0..holes_per_side {
        for j in 0..holes_per_side {
            let (cx, cy) = (-600.0 + (i as f64 + 0.5) * pitch, -600.0 + (j as f64 + 0.5) * pitch);
            let s = pitch * 0.3;
            rings.push(vec![[cx - s, cy - s], [cx - s, cy + s], [cx + s, cy + s], [cx + s, cy - s]]);
        }
    }
    from_rings(&format!("star{n}-holes{}", holes_per_side * holes_per_side), &rings)
}

fn bench(c: &mut Criterion) {
    let mut inputs: Vec<Input> = ["building", "dude", "water", "water-huge", "water-huge2"]
        .map(|name| from_rings(name, &earcut_fixtures::fixture(name)))
        .into();
    inputs.push(generated(20_000, 20));
    let mut group = c.benchmark_group("triangulate");
    for input in &inputs {
        let vertices = input.coords.len() / 2;
        group.throughput(Throughput::Elements(vertices as u64));
        let points: Vec<[f64; 2]> = input.coords.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
        let holes_u32: Vec<u32> = input.holes.iter().map(|&h| h as u32).collect();

        let mut ours = Triangulator::new();
        let mut out = Vec::new();
        group.bench_function(BenchmarkId::new("indra", &input.name), |b| {
            b.iter(|| {
                out.clear();
                ours.flat(&input.coords, &input.holes, &mut out).unwrap();
                out.len()
            })
        });
        let mut theirs = earcut::Earcut::new();
        let mut out32: Vec<u32> = Vec::new();
        group.bench_function(BenchmarkId::new("earcut", &input.name), |b| {
            b.iter(|| {
                theirs.earcut(points.iter().copied(), &holes_u32, &mut out32);
                out32.len()
            })
        });
        group.bench_function(BenchmarkId::new("earcutr", &input.name), |b| {
            b.iter(|| earcutr::earcut(&input.coords, &input.holes, 2).unwrap().len())
        });
        eprintln!(
            "{}: {vertices} vertices, {} rings; triangles indra {}, earcut {}",
            input.name,
            input.holes.len() + 1,
            out.len() / 3,
            out32.len() / 3
        );
    }
    group.finish();
}

/// `n` points, every other one at half the radius.
fn spiky_star(n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            let r = if i.is_multiple_of(2) { 1000.0 } else { 500.0 };
            [r * t.cos(), r * t.sin()]
        })
        .collect()
}

/// The outer ring of [`generated`] alone.
fn wavy(n: usize) -> Vec<[f64; 2]> {
    let input = generated(n, 0);
    input.coords.chunks_exact(2).map(|p| [p[0], p[1]]).collect()
}

/// `count` unit squares on a grid, apart.
fn squares(count: usize) -> Vec<Vec<[f64; 2]>> {
    let side = (count as f64).sqrt().ceil() as usize;
    (0..count)
        .map(|i| {
            let (x, y) = ((i % side) as f64 * 3.0, (i / side) as f64 * 3.0);
            vec![[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]]
        })
        .collect()
}

fn scale(c: &mut Criterion) {
    let mut group = c.benchmark_group("scale");
    group.sample_size(10);
    let mut ours = Triangulator::new();
    for (name, ring) in [("spiky-star-1e6", spiky_star(1_000_000)), ("wavy-1e6", wavy(1_000_000))] {
        let coords: Vec<f64> = ring.iter().flatten().copied().collect();
        let mut out = Vec::new();
        group.bench_function(BenchmarkId::new("indra", name), |b| {
            b.iter(|| {
                out.clear();
                ours.flat(&coords, &[], &mut out).unwrap();
                out.len()
            })
        });
    }
    let rings = squares(100_000);
    group.bench_function(BenchmarkId::new("indra", "squares-1e5"), |b| {
        b.iter(|| ours.rings(&rings).unwrap().indices.len())
    });
    // Touching holes at scale: earcut takes about 0.9 s here.
    let (coords, starts) = earcut_fixtures::flat(&earcut_fixtures::checkerboard(130));
    let mut out = Vec::new();
    group.bench_function(BenchmarkId::new("indra", "checkerboard-130"), |b| {
        b.iter(|| {
            out.clear();
            ours.flat(&coords, &starts, &mut out).unwrap();
            out.len()
        })
    });
    group.finish();
}

criterion_group!(benches, bench, scale);
criterion_main!(benches);
