//! The book's tessellation factors and culling on the CPU, mirroring the compute passes of
//! `tessellation.wgsl` (same mesh numbering), for tests.

use glam::{Mat4, Vec3, Vec4};

use super::params::{PLANE_SIZE, TessUniforms};

/// Largest factor (the hardware tessellator's clamp).
pub const MAX_LEVEL: f32 = 64.0;

fn vertex_uv(grid: u32, v: u32) -> (f32, f32) {
    ((v % (grid + 1)) as f32 / grid as f32, (v / (grid + 1)) as f32 / grid as f32)
}

fn world(model: Mat4, grid: u32, v: u32) -> Vec3 {
    let (u, w) = vertex_uv(grid, v);
    model.transform_point3(Vec3::new((u - 0.5) * PLANE_SIZE, 0.0, (w - 0.5) * PLANE_SIZE))
}

/// The two vertices of edge `e`, lower index first.
pub fn edge_vertices(grid: u32, e: u32) -> (u32, u32) {
    let (g, row, h) = (grid, grid + 1, (grid + 1) * grid);
    if e < h {
        let (z, x) = (e / g, e % g);
        (z * row + x, z * row + x + 1)
    } else if e < 2 * h {
        let (z, x) = ((e - h) / row, (e - h) % row);
        (z * row + x, (z + 1) * row + x)
    } else {
        let (z, x) = ((e - 2 * h) / g, (e - 2 * h) % g);
        (z * row + x, (z + 1) * row + x + 1)
    }
}

/// Vertices and edges of patch `p` (edge k joins vertex k and k + 1).
pub fn patch(grid: u32, p: u32) -> ([u32; 3], [u32; 3]) {
    let (g, row, h) = (grid, grid + 1, (grid + 1) * grid);
    let (x, z) = ((p / 2) % g, (p / 2) / g);
    let v00 = z * row + x;
    let (v10, v01) = (v00 + 1, v00 + row);
    let v11 = v01 + 1;
    let (bottom, top) = (z * g + x, (z + 1) * g + x);
    let left = h + z * row + x;
    let diagonal = 2 * h + z * g + x;
    if p.is_multiple_of(2) {
        ([v00, v10, v11], [bottom, left + 1, diagonal])
    } else {
        ([v00, v11, v01], [diagonal, top, left])
    }
}

/// The book's edge factor of every edge: max(1, length · screen height / (target px · distance
/// from the camera to the edge's midpoint)), clamped to 64.
pub fn edge_factors(u: &TessUniforms) -> Vec<f32> {
    let model = Mat4::from_cols_array_2d(&u.model);
    let camera = Vec4::from_array(u.camera).truncate();
    (0..u.edge_count)
        .map(|e| {
            let (a, b) = edge_vertices(u.grid, e);
            let (a, b) = (world(model, u.grid, a), world(model, u.grid, b));
            let distance = ((a + b) * 0.5 - camera).length().max(1e-4);
            ((a - b).length() * u.screen_height / (u.edge_px * distance)).clamp(1.0, MAX_LEVEL)
        })
        .collect()
}

/// Whether patch `p` is culled: all three vertices outside one side plane by more than
/// 1.5 × displacement.
pub fn culled(u: &TessUniforms, p: u32) -> bool {
    let model = Mat4::from_cols_array_2d(&u.model);
    let (v, _) = patch(u.grid, p);
    let margin = 1.5 * u.displacement.abs();
    u.planes.iter().any(|plane| {
        let plane = Vec4::from_array(*plane);
        v.iter().all(|&i| plane.truncate().dot(world(model, u.grid, i)) + plane.w < -margin)
    })
}

/// The level of patch `p` from edge `factors`: 0 if culled, else the larger of ⌈mean⌉ and the
/// three edge levels.
pub fn patch_level(u: &TessUniforms, factors: &[f32], p: u32) -> u32 {
    if culled(u, p) {
        return 0;
    }
    let (_, e) = patch(u.grid, p);
    let f = e.map(|i| factors[i as usize]);
    let inside = ((f[0] + f[1] + f[2]) / 3.0).ceil() as u32;
    f.iter().map(|x| x.ceil() as u32).fold(inside, u32::max)
}

/// Where point `m` of `level` equal parts lies (0–1) when the factor is `phi` (0–1) into that
/// level — the geomorph of `tessellation.wgsl`'s `morphed`: at `phi` = 1 the even
/// subdivision, at 0 the points of `level` − 1 parts (up to the middle they keep their number,
/// past it they take the one before: the two middle points start as one).
pub fn morphed(m: u32, level: u32, phi: f32) -> f32 {
    let exact = m as f32 / level as f32;
    if level <= 1 {
        return exact;
    }
    let coarse = (level - 1) as f32;
    let parent = if 2 * m <= level { m as f32 } else { (m - 1) as f32 } / coarse;
    parent + (exact - parent) * phi
}

/// How far `factor` is into its level (`level` = ⌈factor⌉), 0–1.
pub fn morph_fraction(factor: f32, level: u32) -> f32 {
    (factor - level as f32 + 1.0).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The points of an edge at `factor`, sorted.
    fn points(factor: f32) -> Vec<f32> {
        let level = factor.ceil() as u32;
        let phi = morph_fraction(factor, level);
        let mut p: Vec<f32> = (0..=level).map(|m| morphed(m, level, phi)).collect();
        p.sort_by(f32::total_cmp);
        p
    }

    #[test]
    fn geomorphed_points_glide_across_every_level_change_and_stay_ordered() {
        for level in 1..64u32 {
            let just_past = points(level as f32 + 1e-4);
            let at = points(level as f32);
            // Crossing the level adds one point, on top of an old one: nothing jumps.
            assert_eq!(just_past.len(), at.len() + 1);
            for q in &just_past {
                let nearest = at.iter().map(|a| (a - q).abs()).fold(f32::MAX, f32::min);
                assert!(nearest < 1e-3, "level {level}: {q} appeared from nowhere ({just_past:?} vs {at:?})");
            }
            // At any fraction: from 0 to 1 and in order (no triangle folds over).
            for phi in [0.0, 0.3, 0.7, 1.0] {
                let n = level + 1;
                let p: Vec<f32> = (0..=n).map(|m| morphed(m, n, phi)).collect();
                assert_eq!((p[0], p[n as usize]), (0.0, 1.0));
                assert!(p.windows(2).all(|w| w[0] <= w[1]), "level {n}, phi {phi}: {p:?}");
            }
        }
    }
}
