//! Triangulation end to end: earcut's fixture suite in four exact rotations (deviation bounds and
//! triangle counts), property tests on random simple polygons with holes, and random garbage that
//! must not panic or hang.

use indra::geometry::triangulate::{Mesh2D, Triangulator, triangulate, triangulate_flat};
use proptest::prelude::*;

#[path = "../common/earcut_fixtures.rs"]
mod earcut_fixtures;

use earcut_fixtures::{Ring, earcut_triangles, fixture, flat, rotate};

fn ring_area(ring: &[[f64; 2]]) -> f64 {
    let mut sum = 0.0;
    for (i, a) in ring.iter().enumerate() {
        let b = ring[(i + 1) % ring.len()];
        sum += a[0] * b[1] - b[0] * a[1];
    }
    sum / 2.0
}

/// earcut's deviation: |Σ |triangle| − (|outer| − Σ |hole|)| / (|outer| − Σ |hole|). For a
/// polygon of no area, the triangles' area relative to the bounding box instead.
fn deviation(rings: &[Ring], indices: &[u32]) -> f64 {
    let vertices: Vec<[f64; 2]> = rings.concat();
    let polygon = ring_area(&rings[0]).abs() - rings[1..].iter().map(|r| ring_area(r).abs()).sum::<f64>();
    let triangles: f64 = indices
        .chunks_exact(3)
        .map(|t| ring_area(&[vertices[t[0] as usize], vertices[t[1] as usize], vertices[t[2] as usize]]).abs())
        .sum();
    if polygon > 0.0 {
        ((triangles - polygon) / polygon).abs()
    } else {
        let (lo, hi) = vertices.iter().fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), p| {
            ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
        });
        triangles / ((hi[0] - lo[0]) * (hi[1] - lo[1])).max(f64::MIN_POSITIVE)
    }
}

/// (fixture, earcut's triangle count, maximum deviation). Counts are implementation-specific
/// (collinear points merge, fallbacks drop points): ours must not exceed earcut's by more than 2%
/// or 3 triangles, nor n + 2h − 2. Deviation bounds are those of earcut's own suite (0 = exact, 1e-14)
/// except for [`CROSSING`].
const FIXTURES: &[(&str, usize, f64)] = &[
    ("building", 13, 0.0),
    ("dude", 106, 0.0),
    ("water", 2482, 9e-4),
    ("water2", 1212, 0.0),
    ("water3", 197, 0.0),
    ("water3b", 25, 0.0),
    ("water4", 705, 0.0),
    ("water-huge", 5174, CROSSING),
    ("water-huge2", 4461, CROSSING),
    ("degenerate", 0, 0.0),
    ("bad-hole", 42, CROSSING),
    ("empty-square", 0, 0.0),
    ("issue16", 12, 0.0),
    ("issue17", 11, 0.0),
    ("steiner", 9, 0.0),
    ("issue29", 40, 0.0),
    ("issue34", 139, 0.0),
    ("issue35", 844, 0.0),
    ("self-touching", 124, 3.4e-14),
    ("outside-ring", 64, 0.0),
    ("simplified-us-border", 120, 0.0),
    ("touching-holes", 57, 0.0),
    ("hole-touching-outer", 77, 0.0),
    ("hilbert", 1024, 0.0),
    ("issue45", 10, 0.0),
    ("eberly-3", 73, 0.0),
    ("eberly-6", 1429, 0.0),
    ("issue52", 109, 0.0),
    ("shared-points", 4, 0.0),
    ("bad-diagonals", 7, 0.0),
    ("issue83", 0, 1e-14),
    ("infinite-loop-jhl", 0, 1e-14),
    ("filtered-bridge-jhl", 25, 1e-14),
    ("issue142", 0, 0.13),
    ("issue149", 0, 1e-14),
];

/// Marks the fixtures whose rings cross each other (no exact triangulation exists; the result
/// depends on where the cuts fall): water-huge, water-huge2, bad-hole. Ours is held to the
/// `earcut` crate's own deviation on the same rotation (the measure), with no slack:
/// holes are bridged and ears clipped as earcut does, ties between copies of a point included,
/// so both cover the same in all 12. Before, bridging and walking otherwise, ours was worse in
/// 5 of the 12 and once covered 0.11 too much; before ties went by ring order, water-huge2 at
/// 270° covered 0.0032348 against earcut's 0.0031764.
const CROSSING: f64 = f64::INFINITY;

#[test]
fn earcut_fixtures_in_four_rotations() {
    let mut failures = Vec::new();
    for &(name, expected, bound) in FIXTURES {
        let base = fixture(name);
        let n: usize = base.iter().map(Vec::len).sum();
        let formula = (n + 2 * (base.len() - 1)).saturating_sub(2);
        for turn in 0..4 {
            let rings = rotate(&base, turn);
            let (coords, starts) = flat(&rings);
            let indices = triangulate_flat(&coords, &starts).unwrap();
            let count = indices.len() / 3;
            let dev = deviation(&rings, &indices);
            // Crossing input: earcut's deviation by the same formula.
            let bound = if bound == CROSSING { deviation(&rings, &earcut_triangles(&coords, &starts)) } else { bound };
            // Fewer is fine (collinear points merged); more would mean extra cuts.
            let near = count as f64 <= (expected as f64 * 1.02).max(expected as f64 + 3.0);
            if count > formula || (expected > 0 && !near) || dev > bound.max(1e-14) {
                failures.push(format!(
                    "{name} @{}°: {count} triangles (earcut {expected}), deviation {dev:.3e} (bound {bound:.1e})",
                    turn * 90
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn fixtures_without_a_valid_interior_give_no_triangles() {
    for name in ["degenerate", "empty-square"] {
        let (coords, starts) = flat(&fixture(name));
        assert!(triangulate_flat(&coords, &starts).unwrap().is_empty(), "{name}");
    }
}

/// A star-shaped ring around `centre`: n angles evenly spaced and jittered by up to half a step
/// (`jitter` in [0, 1)), radii in whatever range the caller drew.
fn star(centre: [f64; 2], jitter: &[f64], radii: &[f64]) -> Ring {
    let step = std::f64::consts::TAU / jitter.len() as f64;
    jitter
        .iter()
        .zip(radii)
        .enumerate()
        .map(|(i, (&j, &r))| {
            let t = (i as f64 + 0.5 * j) * step;
            [centre[0] + r * t.cos(), centre[1] + r * t.sin()]
        })
        .collect()
}

/// A random simple polygon: a star-shaped outer ring (≥ 12 vertices, radius 0.5–1, so angular
/// gaps < 45° keep the disc of radius 0.45 inside) and up to 16 star-shaped holes of radius ≤ 0.075
/// in disjoint cells of a 4×4 grid of pitch 0.16 within that disc (from 8 holes the bridge search
/// uses its band index, so both paths are covered).
fn polygon() -> impl Strategy<Value = Vec<Ring>> {
    let ring = |n: std::ops::Range<usize>, r_min: f64, r_max: f64| {
        n.prop_flat_map(move |n| (prop::collection::vec(0.0..1.0, n), prop::collection::vec(r_min..r_max, n)))
    };
    let outer = ring(12..80, 0.5, 1.0);
    let holes = prop::collection::vec((any::<prop::sample::Index>(), ring(3..12, 0.02, 0.075)), 0..24);
    (outer, holes).prop_map(|((jitter, radii), holes)| {
        let mut rings = vec![star([0.0, 0.0], &jitter, &radii)];
        let mut used = [false; 16];
        for (cell, (hole_jitter, hole_radii)) in holes {
            let c = cell.index(16);
            if std::mem::replace(&mut used[c], true) {
                continue;
            }
            let centre = [(c % 4) as f64 * 0.16 - 0.24, (c / 4) as f64 * 0.16 - 0.24];
            rings.push(star(centre, &hole_jitter, &hole_radii));
        }
        rings
    })
}

/// Three nearly collinear consecutive points would let a correct triangulator merge them.
fn in_general_position(rings: &[Ring]) -> bool {
    rings.iter().all(|r| {
        (0..r.len()).all(|i| {
            let (a, b, c) = (r[i], r[(i + 1) % r.len()], r[(i + 2) % r.len()]);
            ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs() > 1e-9
        })
    })
}

fn point_in_ring(p: [f64; 2], ring: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let mut j = ring.len() - 1;
    for i in 0..ring.len() {
        let (a, b) = (ring[i], ring[j]);
        if (a[1] > p[1]) != (b[1] > p[1]) && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0] {
            inside = !inside;
        }
        j = i;
    }
    inside
}

fn check_mesh(rings: &[Ring], mesh: &Mesh2D) -> Result<(), TestCaseError> {
    // The outer ring is the largest, wherever the input put it.
    let outer = (0..rings.len()).max_by(|&a, &b| ring_area(&rings[a]).abs().total_cmp(&ring_area(&rings[b]).abs()));
    let outer = outer.unwrap();
    let mut ordered = vec![rings[outer].clone()];
    ordered.extend(rings.iter().enumerate().filter(|&(i, _)| i != outer).map(|(_, r)| r.clone()));
    let n: usize = rings.iter().map(Vec::len).sum();
    let h = rings.len() - 1;
    prop_assert_eq!(mesh.triangle_count(), n + 2 * h - 2);
    prop_assert!(mesh.report.area_deviation() <= 1e-9, "deviation {}", mesh.report.area_deviation());
    // Independently of the report: mesh positions are the input rings in input order.
    prop_assert_eq!(&mesh.positions, &rings.concat());
    let triangles: f64 =
        mesh.indices.chunks_exact(3).map(|t| ring_area(&[t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]))).sum();
    let polygon = ring_area(&ordered[0]).abs() - ordered[1..].iter().map(|r| ring_area(r).abs()).sum::<f64>();
    prop_assert!(((triangles - polygon) / polygon).abs() <= 1e-9);
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
        let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        prop_assert!(cross > 0.0, "triangle {:?} not counter-clockwise", t);
        let centroid = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
        prop_assert!(point_in_ring(centroid, &ordered[0]), "triangle {:?} outside the outer ring", t);
        prop_assert!(!ordered[1..].iter().any(|hole| point_in_ring(centroid, hole)), "triangle {:?} in a hole", t);
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn random_polygons_with_holes(rings in polygon(), reverse in any::<bool>()) {
        prop_assume!(in_general_position(&rings));
        for turn in 0..4 {
            let mut rings = rotate(&rings, turn);
            if reverse {
                // Orientation and ring order must not matter.
                rings.iter_mut().for_each(|r| r.reverse());
                rings.reverse();
            }
            let mesh = triangulate(&rings).unwrap();
            check_mesh(&rings, &mesh)?;
        }
    }

    #[test]
    fn scribbles_that_cross_themselves_are_covered_exactly(
        points in prop::collection::vec(prop::array::uniform2(-1000i32..1000), 4..14),
    ) {
        // A ring drawn at random crosses itself many times. Cut at its crossings into loops
        // that nest, it must be covered exactly, every triangle counter-clockwise.
        let ring: Ring = points.iter().map(|p| [f64::from(p[0]) + 0.37, f64::from(p[1]) * 1.01 + 0.11]).collect();
        prop_assume!(in_general_position(std::slice::from_ref(&ring)));
        let mesh = triangulate(&[ring]).unwrap();
        prop_assert!(mesh.report.dropped.is_empty() || mesh.report.polygon_area == 0.0, "{:?}", mesh.report);
        prop_assert!(mesh.report.area_deviation() <= 1e-9, "{:?}", mesh.report);
        for t in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
            prop_assert!((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0.0);
        }
    }

    #[test]
    fn garbage_never_panics(rings in prop::collection::vec(prop::collection::vec(prop::array::uniform2(-3i8..3), 0..40), 0..6)) {
        // Integer grids are full of repeats, collinear runs, touching and crossing rings.
        let rings: Vec<Ring> = rings.iter().map(|r| r.iter().map(|p| [p[0] as f64, p[1] as f64]).collect()).collect();
        let mesh = triangulate(&rings).unwrap();
        prop_assert!(mesh.indices.iter().all(|&i| (i as usize) < mesh.positions.len()));
        prop_assert!(mesh.report.area_deviation().is_finite() || mesh.report.polygon_area == 0.0);
    }
}

proptest! {
    // Not shrunk: every shrinking step of a hang would wait out the watchdog.
    #![proptest_config(ProptestConfig { cases: 20_000, max_shrink_iters: 0, ..ProptestConfig::default() })]

    #[test]
    fn garbage_in_every_layout_finishes(rings in prop::collection::vec(prop::collection::vec(prop::array::uniform2(0i8..8), 1..14), 1..8)) {
        // earcut's layout takes every ring after the first as a hole, as given: collinear holes,
        // holes outside, holes crossing the outer ring. A hang here stops a show, so each run
        // gets a watchdog (a 14-point input once looped for ever).
        // Holes drawn in the middle of the outer ring's grid, where they meet its edges.
        let rings: Vec<Ring> = rings
            .iter()
            .enumerate()
            .map(|(ring, r)| {
                let at = |v: i8| if ring == 0 { f64::from(v) } else { f64::from(2 + v % 4) };
                r.iter().map(|p| [at(p[0]), at(p[1])]).collect()
            })
            .collect();
        let (done, finished) = std::sync::mpsc::channel();
        let input = rings.clone();
        std::thread::spawn(move || {
            let (coords, starts) = flat(&input);
            let indices = triangulate_flat(&coords, &starts).unwrap();
            let mesh = Triangulator::new().outer_and_holes(&input).unwrap();
            let nested = triangulate(&input).unwrap();
            let _ = done.send((indices, mesh, nested, coords.len() / 2));
        });
        let result = finished.recv_timeout(std::time::Duration::from_secs(10));
        prop_assert!(result.is_ok(), "no result within 10 s (hang or panic): {:?}", rings);
        let (indices, mesh, nested, vertices) = result.unwrap();
        prop_assert!(indices.iter().all(|&i| (i as usize) < vertices));
        prop_assert!(mesh.indices.iter().all(|&i| (i as usize) < mesh.positions.len()));
        prop_assert!(nested.indices.iter().all(|&i| (i as usize) < nested.positions.len()));
    }
}

/// Holes that touch: `k` thin triangles fanned around one shared point `apex` (inside the outer
/// rectangle or on its boundary), like earcut's touching-holes fixtures.
fn fan_of_holes(apex: [f64; 2], k: usize, from: f64, spread: f64) -> Vec<Ring> {
    let outer = vec![[-20.0, 0.0], [20.0, 0.0], [20.0, 25.0], [-20.0, 25.0]];
    let mut rings = vec![outer];
    for i in 0..k {
        let a = from + spread * i as f64 / k as f64;
        let b = a + 0.6 * spread / k as f64;
        rings.push(vec![
            apex,
            [apex[0] + 12.0 * a.cos(), apex[1] + 9.0 * a.sin()],
            [apex[0] + 12.0 * b.cos(), apex[1] + 9.0 * b.sin()],
        ]);
    }
    rings
}

/// A checkerboard of square holes that touch at their corners, and a 2 × 2 block of holes that
/// share edges, inside a square.
fn touching_squares(block: bool) -> Vec<Ring> {
    let square = |x: f64, y: f64| vec![[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]];
    let mut rings = vec![vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]];
    if block {
        rings.extend([square(2.0, 2.0), square(3.0, 2.0), square(2.0, 3.0), square(3.0, 3.0)]);
        // And one touching the outer ring along an edge and at a corner.
        rings.push(vec![[6.0, 0.0], [7.0, 1.0], [8.0, 0.0], [7.0, 2.0]]);
        rings.push(vec![[10.0, 10.0], [9.0, 9.5], [9.5, 9.0]]);
    } else {
        for i in 1..9 {
            for j in 1..9 {
                if (i + j) % 2 == 0 {
                    rings.push(square(f64::from(i), f64::from(j)));
                }
            }
        }
    }
    rings
}

#[test]
fn touching_holes_are_exact_in_every_layout_and_rotation() {
    let tau = std::f64::consts::TAU;
    let cases = [
        ("fan inside", fan_of_holes([2.0, 12.0], 26, 0.3, 0.8 * tau)),
        ("fan all round", fan_of_holes([0.0, 12.0], 52, 0.0, tau)),
        ("fan on the outer edge", fan_of_holes([2.0, 0.0], 20, 0.1, 0.45 * tau)),
        ("fan at the outer corner", fan_of_holes([-20.0, 0.0], 12, 0.05, 0.22 * tau)),
        ("checkerboard", touching_squares(false)),
        ("shared edges", touching_squares(true)),
    ];
    let mut failures = Vec::new();
    for (name, base) in cases {
        for turn in 0..4 {
            let rings = rotate(&base, turn);
            let mesh = triangulate(&rings).unwrap();
            let (coords, starts) = flat(&rings);
            let flat_dev = deviation(&rings, &triangulate_flat(&coords, &starts).unwrap());
            let dev = mesh.report.area_deviation();
            if dev > 1e-9 || flat_dev > 1e-9 || mesh.report.holes != rings.len() - 1 {
                failures.push(format!(
                    "{name} @{}°: deviation {dev:.3e} (flat {flat_dev:.3e}), {} holes",
                    turn * 90,
                    mesh.report.holes
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
