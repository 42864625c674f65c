//! earcut's fixture polygons (`tests/fixtures/earcut/`, ISC, see its NOTICE.md), read as rings
//! or in earcut's flat layout. Shared by `tests/suite/triangulate.rs` and `benches/triangulate.rs`.
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
