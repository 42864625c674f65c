//! Attractions inside a skinned model: the mesh's bind-pose volume voxelised and Poisson-sampled
//! (`geometry::volume`), each attraction carrying the skin of its nearest vertex, so branches grown
//! in the bind pose follow the animation. The bundled Rigged Figure is built into the binary.

use super::cloud::{Attraction, Cloud};
use super::growth::VertexSkin;
use crate::assets::Assets;
use crate::geometry::skinned::{MODEL_DATA_LIMIT, SkinnedMesh};
use crate::geometry::volume;

/// The bundled models, by the path scenes use.
const BUNDLED: &[(&str, &[u8])] =
    &[("assets/models/RiggedFigure.gltf", include_bytes!("../../../assets/models/RiggedFigure.gltf"))];

/// Loads model `name` (beside the asset root, then as given, under the file rules; else the
/// bundled copy).
pub fn load(assets: &Assets, name: &str) -> Result<SkinnedMesh, String> {
    let bundled = BUNDLED.iter().find(|(bundled, _)| *bundled == name).map(|(_, bytes)| *bytes);
    let read = assets.read_file(name, MODEL_DATA_LIMIT, bundled).map_err(|e| format!("cannot read model: {e}"))?;
    match &read.path {
        Some(file) => SkinnedMesh::from_file_bytes(file, &read.bytes, assets.file_rules()),
        None => SkinnedMesh::from_slice(name, &read.bytes),
    }
}

/// How the model's volume is sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// Voxels along the model's longest side.
    pub voxels: u32,
    /// Least distance between attractions, in voxels.
    pub spacing: f32,
    /// Random seed.
    pub seed: u64,
}

/// The attractions inside `mesh` (its bind pose, mesh units) with the distance unit of one voxel,
/// and every vertex's skin.
pub fn cloud(mesh: &SkinnedMesh, sampling: Sampling) -> (Cloud, Vec<VertexSkin>) {
    let grid = volume::voxelize(&mesh.positions, &mesh.triangles, sampling.voxels.clamp(8, 256) as usize);
    let points = volume::sample_inside(&grid, grid.voxel * sampling.spacing, sampling.seed);
    let attractions = points.iter().map(|p| Attraction::new(*p, nearest_vertex(&mesh.positions, *p))).collect();
    let skins = mesh
        .vertex_joints
        .iter()
        .zip(&mesh.vertex_weights)
        .map(|(&joints, &weights)| VertexSkin { joints, weights })
        .collect();
    (Cloud::new(attractions, grid.voxel), skins)
}

fn nearest_vertex(positions: &[[f32; 3]], p: [f32; 3]) -> u32 {
    let d2 = |q: &[f32; 3]| (0..3).map(|k| (q[k] - p[k]).powi(2)).sum::<f32>();
    positions.iter().enumerate().min_by(|a, b| d2(a.1).total_cmp(&d2(b.1))).map_or(0, |(i, _)| i as u32)
}
