//! Deviation of ours and of the `earcut` crate on earcut's fixtures, each turned by 0°, 90°,
//! 180° and 270°, by earcut's own formula on the same flat data:
//! `cargo run --release --example triangulate_deviation -- water-huge water-huge2 bad-hole`.
//! "worse" marks a rotation where ours covers the area less exactly than earcut.

#[path = "../tests/common/earcut_fixtures.rs"]
mod earcut_fixtures;

use indra::geometry::triangulate::triangulate_flat;

fn main() {
    let names: Vec<String> = std::env::args().skip(1).collect();
    if names.is_empty() {
        eprintln!("usage: triangulate_deviation FIXTURE... (names in tests/fixtures/earcut/)");
        std::process::exit(2);
    }
    for name in names {
        let base = earcut_fixtures::fixture(&name);
        let mut line = format!("{name}:");
        for turn in 0..4 {
            let rings = earcut_fixtures::rotate(&base, turn);
            let (coords, hole_starts) = earcut_fixtures::flat(&rings);
            let points: Vec<[f64; 2]> = coords.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
            let holes: Vec<u32> = hole_starts.iter().map(|&h| h as u32).collect();
            let ours = triangulate_flat(&coords, &hole_starts).expect("fixture triangulates");
            let theirs = earcut_fixtures::earcut_triangles(&coords, &hole_starts);
            let ours = earcut::deviation(points.iter().copied(), &holes, &ours);
            let theirs = earcut::deviation(points.iter().copied(), &holes, &theirs);
            let worse = if ours > theirs { " worse" } else { "" };
            line += &format!("  {}°: {ours:.4} vs earcut {theirs:.4}{worse}", turn * 90);
        }
        println!("{line}");
    }
}
