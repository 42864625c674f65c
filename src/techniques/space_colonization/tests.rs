use super::*;

#[test]
fn the_books_lattice_sizes() {
    // seed-reference §1: side 28 keeps 10,144 points, side 16 keeps 1,736.
    assert_eq!(Cloud::lattice_sphere(28, 1).attractions.len(), 10_144);
    assert_eq!(Cloud::lattice_sphere(16, 1).attractions.len(), 1_736);
}

#[test]
fn the_jitter_stays_within_half_a_cell() {
    let side = 20;
    let spacing = 1.0 / (side - 1) as f32;
    let cloud = Cloud::lattice_sphere(side, 7);
    for a in &cloud.attractions {
        let r = a.pos.iter().map(|c| c * c).sum::<f32>().sqrt();
        assert!(r < 0.5 + spacing, "{r}");
    }
    assert!((cloud.unit - 0.1).abs() < 1e-6);
}

#[test]
fn seeds_are_distinct_attractions() {
    let cloud = Cloud::lattice_sphere(12, 3);
    let seeds = cloud.seeds(16, 3);
    assert_eq!(seeds.len(), 16);
    for (i, s) in seeds.iter().enumerate() {
        assert!(cloud.attractions.iter().any(|a| a.pos == s.pos));
        assert!(seeds[..i].iter().all(|o| o.pos != s.pos));
        assert_eq!((s.t, s.parent, s.depth), (1.0, NONE, 0));
    }
}

#[test]
fn a_grid_cell_is_never_narrower_than_the_reach_and_the_grid_is_bounded() {
    for reach in [1e-5f32, 0.001, 0.02, 0.3, 2.0] {
        let g = GridLayout::covering([-0.5; 3], [0.5; 3], reach);
        assert!(g.cell_size >= reach);
        assert!(g.cells() <= MAX_CELLS, "{reach}: {:?}", g.dims);
        assert!(g.dims.iter().all(|&d| d as f32 * g.cell_size >= 1.0));
    }
}

#[test]
fn a_capsule_is_closed_around_and_at_the_tip() {
    let indices = tube_indices();
    assert_eq!(indices.len() as u32, (1 + TUBE_CAP_ROWS) * TUBE_SIDES * 6);
    assert!(indices.iter().all(|&i| i < (2 + TUBE_CAP_ROWS) * TUBE_SIDES));
}
