//! earcut's fixture polygons (`tests/fixtures/earcut/`, ISC, see its NOTICE.md), read as rings
//! or in earcut's flat layout, turned, and as the `earcut` crate triangulates them. Shared by
//! `tests/suite/triangulate.rs`, `benches/triangulate.rs`, `examples/triangulate_deviation.rs`
//! and the triangulator's unit tests; with them, a generated input of touching holes.
#![allow(dead_code)]

/// One ring of [x, y] points.
pub type Ring = Vec<[f64; 2]>;

/// The rings of fixture `name` (ring 0 outer, the rest holes).
pub fn fixture(name: &str) -> Vec<Ring> {
    let path = format!("{}/tests/fixtures/earcut/{name}.json", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let rings: Vec<Vec<Vec<f64>>> = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
    rings.into_iter().map(|r| r.into_iter().map(|p| [p[0], p[1]]).collect()).collect()
}

/// earcut's flat layout of rings: coordinates and the vertex index where each hole starts.
pub fn flat(rings: &[Ring]) -> (Vec<f64>, Vec<usize>) {
    let coords = rings.iter().flatten().flatten().copied().collect();
    let starts = rings[..rings.len() - 1]
        .iter()
        .scan(0, |n, ring| {
            *n += ring.len();
            Some(*n)
        })
        .collect();
    (coords, starts)
}

/// The rings turned counter-clockwise by `quarter_turns` × 90° (exact: coordinates only swap
/// and change sign).
pub fn rotate(rings: &[Ring], quarter_turns: u32) -> Vec<Ring> {
    let turn = |[x, y]: [f64; 2]| match quarter_turns % 4 {
        0 => [x, y],
        1 => [-y, x],
        2 => [-x, -y],
        _ => [y, -x],
    };
    rings.iter().map(|r| r.iter().map(|&p| turn(p)).collect()).collect()
}

/// The `earcut` crate's triangles for flat input (coordinates and hole starts, as [`flat`]).
pub fn earcut_triangles(coords: &[f64], starts: &[usize]) -> Vec<u32> {
    let points: Vec<[f64; 2]> = coords.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
    let holes: Vec<u32> = starts.iter().map(|&s| s as u32).collect();
    let mut indices = Vec::new();
    earcut::Earcut::new().earcut(points.iter().copied(), &holes, &mut indices);
    indices
}

/// A `side` × `side` checkerboard of unit squares, the dark ones holes touching at their
/// corners (ring 0 the outer square, then the holes, in earcut's orientation-free layout).
pub fn checkerboard(side: u32) -> Vec<Ring> {
    let s = f64::from(side);
    let mut rings = vec![vec![[0.0, 0.0], [s, 0.0], [s, s], [0.0, s]]];
    for i in 0..side {
        for j in (0..side).filter(|j| (i + j) % 2 == 0) {
            let (x, y) = (f64::from(i), f64::from(j));
            rings.push(vec![[x, y], [x, y + 1.0], [x + 1.0, y + 1.0], [x + 1.0, y]]);
        }
    }
    rings
}
