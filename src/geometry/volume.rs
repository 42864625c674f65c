//! Mesh volume sampling (the sample's VolumeSampler, done robustly): voxelise a closed triangle
//! mesh by winding number along rays through voxel centres — front faces +1, back faces −1, so
//! overlapping closed parts fill as their union — on all three axes with a majority vote (a
//! small hole in a mesh fools one axis, not two), then Poisson-disk sample the filled voxels.

use super::poisson::{PoissonDisk, PoissonSettings};

/// Filled voxels of a mesh.
#[derive(Clone, Debug)]
pub struct VoxelGrid {
    /// Lowest corner.
    pub origin: [f32; 3],
    /// Voxel side.
    pub voxel: f32,
    /// Voxels per axis.
    pub dims: [usize; 3],
    /// Inside or not, x fastest.
    pub filled: Vec<bool>,
}

impl VoxelGrid {
    /// The voxel holding `p`, if inside the grid.
    pub fn index_of(&self, p: [f32; 3]) -> Option<usize> {
        let mut at = [0usize; 3];
        for a in 0..3 {
            let c = ((p[a] - self.origin[a]) / self.voxel).floor();
            if c < 0.0 || c >= self.dims[a] as f32 {
                return None;
            }
            at[a] = c as usize;
        }
        Some((at[2] * self.dims[1] + at[1]) * self.dims[0] + at[0])
    }

    /// Whether `p` lies in a filled voxel.
    pub fn contains(&self, p: [f32; 3]) -> bool {
        self.index_of(p).is_some_and(|i| self.filled[i])
    }

    /// Filled voxels.
    pub fn filled_count(&self) -> usize {
        self.filled.iter().filter(|&&f| f).count()
    }
}

/// Voxelises the mesh `triangles` over `positions` with `resolution` voxels along its longest
/// side (plus a voxel of margin all round).
pub fn voxelize(positions: &[[f32; 3]], triangles: &[[u32; 3]], resolution: usize) -> VoxelGrid {
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    for p in positions {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    if positions.is_empty() {
        (lo, hi) = ([0.0; 3], [1.0; 3]);
    }
    let longest = (0..3).map(|a| hi[a] - lo[a]).fold(1e-6, f32::max);
    let voxel = longest / resolution.max(1) as f32;
    let origin = lo.map(|c| c - voxel);
    let dims: [usize; 3] = std::array::from_fn(|a| (((hi[a] - lo[a]) / voxel).ceil() as usize).max(1) + 2);
    let votes: Vec<Vec<bool>> =
        (0..3).map(|axis| winding_fill(positions, triangles, origin, voxel, dims, axis)).collect();
    let filled = (0..votes[0].len()).map(|i| votes.iter().filter(|v| v[i]).count() >= 2).collect();
    VoxelGrid { origin, voxel, dims, filled }
}

/// Inside-ness of every voxel centre by the winding number along `axis`.
fn winding_fill(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    origin: [f32; 3],
    voxel: f32,
    dims: [usize; 3],
    axis: usize,
) -> Vec<bool> {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    // Column centres nudged off the lattice so that no ray passes exactly through an edge.
    let nudge = [0.000_123_4 * voxel, 0.000_234_5 * voxel];
    let centre = |a: usize, i: usize| origin[a] + (i as f32 + 0.5) * voxel;
    let mut crossings: Vec<Vec<(f32, i32)>> = vec![Vec::new(); dims[u] * dims[v]];
    for t in triangles {
        let [p0, p1, p2] = t.map(|i| positions.get(i as usize).copied().unwrap_or_default());
        let area = (p1[u] - p0[u]) * (p2[v] - p0[v]) - (p2[u] - p0[u]) * (p1[v] - p0[v]);
        if area == 0.0 {
            continue; // edge-on: no ray crosses it
        }
        let range = |a: usize, nudge: f32| {
            let min = p0[a].min(p1[a]).min(p2[a]);
            let max = p0[a].max(p1[a]).max(p2[a]);
            let first = ((min - nudge - origin[a]) / voxel - 0.5).ceil().max(0.0) as usize;
            let last = (((max - nudge - origin[a]) / voxel - 0.5).floor() as isize).min(dims[a] as isize - 1);
            first..(last + 1).max(0) as usize
        };
        for j in range(v, nudge[1]) {
            for i in range(u, nudge[0]) {
                let (x, y) = (centre(u, i) + nudge[0], centre(v, j) + nudge[1]);
                // Barycentric coordinates in the (u, v) projection.
                let w1 = ((x - p0[u]) * (p2[v] - p0[v]) - (p2[u] - p0[u]) * (y - p0[v])) / area;
                let w2 = ((p1[u] - p0[u]) * (y - p0[v]) - (x - p0[u]) * (p1[v] - p0[v])) / area;
                let w0 = 1.0 - w1 - w2;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let depth = w0 * p0[axis] + w1 * p1[axis] + w2 * p2[axis];
                // A face whose normal points against the ray is entered: +1.
                crossings[j * dims[u] + i].push((depth, if area > 0.0 { -1 } else { 1 }));
            }
        }
    }
    let mut filled = vec![false; dims[0] * dims[1] * dims[2]];
    let mut at = [0usize; 3];
    for (column, hits) in crossings.iter_mut().enumerate() {
        if hits.is_empty() {
            continue;
        }
        hits.sort_by(|a, b| a.0.total_cmp(&b.0));
        (at[u], at[v]) = (column % dims[u], column / dims[u]);
        let (mut winding, mut next) = (0, 0);
        for k in 0..dims[axis] {
            let c = centre(axis, k);
            while next < hits.len() && hits[next].0 < c {
                winding += hits[next].1;
                next += 1;
            }
            at[axis] = k;
            filled[(at[2] * dims[1] + at[1]) * dims[0] + at[0]] = winding != 0;
        }
    }
    filled
}

/// Poisson-disk samples at least `spacing` apart inside the filled voxels of `grid`.
pub fn sample_inside(grid: &VoxelGrid, spacing: f32, seed: u64) -> Vec<[f32; 3]> {
    let extent = grid.dims.map(|d| f64::from(d as u32) * f64::from(grid.voxel));
    let spacing = f64::from(spacing.max(grid.voxel * 0.05).max(1e-9));
    let points = PoissonDisk::new(PoissonSettings::new(extent, spacing, seed)).generate();
    points
        .into_iter()
        .map(|p| std::array::from_fn(|a| grid.origin[a] + p[a] as f32))
        .filter(|p| grid.contains(*p))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed axis-aligned box as 12 outward-facing triangles.
    fn cube(lo: [f32; 3], hi: [f32; 3]) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let p = (0..8)
            .map(|i| {
                [
                    if i & 1 == 0 { lo[0] } else { hi[0] },
                    if i & 2 == 0 { lo[1] } else { hi[1] },
                    if i & 4 == 0 { lo[2] } else { hi[2] },
                ]
            })
            .collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let t = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        (p, t)
    }

    #[test]
    fn a_box_fills_its_volume() {
        let (p, t) = cube([0.0; 3], [1.0, 0.5, 0.25]);
        let g = voxelize(&p, &t, 40);
        let expected = 40 * 20 * 10;
        assert_eq!(g.filled_count(), expected);
        assert!(g.contains([0.5, 0.25, 0.125]) && !g.contains([1.2, 0.25, 0.125]));
    }

    #[test]
    fn overlapping_closed_parts_fill_as_their_union_and_a_hole_is_outvoted() {
        let (mut p, mut t) = cube([0.0; 3], [1.0; 3]);
        let (p2, t2) = cube([0.5; 3], [1.5; 3]);
        let base = p.len() as u32;
        p.extend(p2);
        t.extend(t2.iter().map(|tri| tri.map(|i| i + base)));
        let g = voxelize(&p, &t, 30);
        assert!(g.contains([0.75; 3]), "the overlap is inside");
        assert_eq!(g.filled_count(), 2 * 20 * 20 * 20 - 10 * 10 * 10);
        // Knock out one triangle: one axis sees a hole, the vote keeps the volume.
        t.remove(0);
        assert_eq!(voxelize(&p, &t, 30).filled_count(), 2 * 20 * 20 * 20 - 10 * 10 * 10);
    }

    #[test]
    fn samples_lie_inside_and_keep_their_spacing() {
        let (p, t) = cube([0.0; 3], [1.0, 1.0, 0.3]);
        let g = voxelize(&p, &t, 20);
        let s = sample_inside(&g, 0.05, 3);
        assert!(s.len() > 500, "{}", s.len());
        assert!(s.iter().all(|q| g.contains(*q)));
        for (i, a) in s.iter().enumerate().step_by(7) {
            for b in &s[i + 1..] {
                let d2: f32 = (0..3).map(|k| (a[k] - b[k]).powi(2)).sum();
                assert!(d2 >= 0.05f32.powi(2) * 0.999, "{a:?} {b:?}");
            }
        }
    }
}
