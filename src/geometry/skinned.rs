//! A skinned, animated mesh from glTF 2.0 (`.gltf` with embedded or external buffers, `.glb`):
//! the first skinned mesh's triangles, 4 joints and weights per vertex, the skin's joints and
//! inverse bind matrices, the node hierarchy's rest transforms, and the first animation's
//! translation / rotation / scale channels (step and linear; cubic splines use their key values
//! linearly). Posing is plain CPU math: joint matrices for a time, linear blend skinning.

use std::path::Path;

use glam::{Mat4, Quat, Vec3};
use gltf::json::validation::Checked;

use crate::files::{self, FileError, FileRules};

/// The most data one model may hold: its file, each buffer, and all its accessors together.
pub const MODEL_DATA_LIMIT: u64 = 256 << 20;

/// How a channel interpolates between keys.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Interpolation {
    /// Hold the previous key.
    Step,
    /// Lerp (slerp for rotations).
    Linear,
}

/// What a channel drives.
#[derive(Clone, Debug)]
pub enum Keys {
    /// Translations.
    Translation(Vec<Vec3>),
    /// Rotations.
    Rotation(Vec<Quat>),
    /// Scales.
    Scale(Vec<Vec3>),
}

/// One animated property of one node.
#[derive(Clone, Debug)]
pub struct Channel {
    /// The node it moves.
    pub node: usize,
    /// Key times, seconds, increasing.
    pub times: Vec<f32>,
    /// Key values.
    pub keys: Keys,
    /// Interpolation.
    pub interpolation: Interpolation,
}

/// A node's rest transform and parent.
#[derive(Clone, Copy, Debug)]
pub struct RestNode {
    /// Parent node, if any.
    pub parent: Option<usize>,
    /// Translation.
    pub translation: Vec3,
    /// Rotation.
    pub rotation: Quat,
    /// Scale.
    pub scale: Vec3,
}

/// The mesh, its skin and its animation.
#[derive(Clone, Debug)]
pub struct SkinnedMesh {
    /// Bind-pose vertex positions (mesh space).
    pub positions: Vec<[f32; 3]>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Joint indices (into `joints`) per vertex.
    pub vertex_joints: Vec<[u32; 4]>,
    /// Weights per vertex, summing to 1.
    pub vertex_weights: Vec<[f32; 4]>,
    /// The skin's joints as node indices.
    pub joints: Vec<usize>,
    /// Inverse bind matrix per joint.
    pub inverse_bind: Vec<Mat4>,
    /// Every node of the document.
    pub nodes: Vec<RestNode>,
    /// The first animation's channels (empty: none).
    pub channels: Vec<Channel>,
    /// The animation's length in seconds.
    pub duration: f32,
    /// The node holding the mesh: its world transform places the bind pose.
    pub mesh_node: usize,
}

impl SkinnedMesh {
    /// Reads a `.gltf` or `.glb` file, its external buffers from its own folder; the error names
    /// the file and what is wrong.
    pub fn load(path: &Path) -> Result<Self, String> {
        let folder = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Self::load_confined(path, &FileRules::new([folder]))
    }

    /// Reads a `.gltf` or `.glb` file whose external buffers must lie inside `rules`' folders.
    /// The file and every buffer are regular files of bounded size, and the data the accessors
    /// claim is checked against [`MODEL_DATA_LIMIT`] before anything is allocated for it.
    pub fn load_confined(path: &Path, rules: &FileRules) -> Result<Self, String> {
        let bytes = files::read_limited(path, MODEL_DATA_LIMIT).map_err(|e| e.to_string())?;
        Self::from_file_bytes(path, &bytes, rules)
    }

    /// A `.gltf` or `.glb` already read from `path`, its external buffers read from beside it
    /// inside `rules`' folders (see [`SkinnedMesh::load_confined`]).
    pub fn from_file_bytes(path: &Path, bytes: &[u8], rules: &FileRules) -> Result<Self, String> {
        let named = |e: String| format!("{}: {e}", path.display());
        precheck(bytes).map_err(named)?;
        let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| named(e.to_string()))?;
        let folder = path.parent().unwrap_or(Path::new("."));
        let buffers = read_buffers(&gltf, folder, rules).map_err(named)?;
        Self::from_document(&gltf.document, &buffers).map_err(named)
    }

    /// Reads a self-contained `.gltf` (data URIs) or `.glb` from memory.
    pub fn from_slice(name: &str, bytes: &[u8]) -> Result<Self, String> {
        precheck(bytes).map_err(|e| format!("{name}: {e}"))?;
        let (document, buffers, _) = gltf::import_slice(bytes).map_err(|e| format!("{name}: {e}"))?;
        Self::from_document(&document, &buffers).map_err(|e| format!("{name}: {e}"))
    }

    fn from_document(document: &gltf::Document, buffers: &[gltf::buffer::Data]) -> Result<Self, String> {
        let holder = document
            .nodes()
            .find(|n| n.mesh().is_some() && n.skin().is_some())
            .ok_or("no skinned mesh (a node with both a mesh and a skin)")?;
        let (mesh, skin) = (holder.mesh().expect("found"), holder.skin().expect("found"));
        let source = |b: gltf::Buffer<'_>| buffers.get(b.index()).map(|d| &d.0[..]);
        let mut out = Self {
            positions: Vec::new(),
            triangles: Vec::new(),
            vertex_joints: Vec::new(),
            vertex_weights: Vec::new(),
            joints: skin.joints().map(|j| j.index()).collect(),
            inverse_bind: Vec::new(),
            nodes: rest_nodes(document),
            channels: Vec::new(),
            duration: 0.0,
            mesh_node: holder.index(),
        };
        if out.joints.is_empty() {
            return Err("the skin has no joints".into());
        }
        out.inverse_bind = match skin.reader(source).read_inverse_bind_matrices() {
            Some(m) => m.map(|c| Mat4::from_cols_array_2d(&c)).collect(),
            None => vec![Mat4::IDENTITY; out.joints.len()],
        };
        if out.inverse_bind.len() != out.joints.len() {
            return Err(format!("{} inverse bind matrices for {} joints", out.inverse_bind.len(), out.joints.len()));
        }
        for primitive in mesh.primitives().filter(|p| p.mode() == gltf::mesh::Mode::Triangles) {
            out.add_primitive(&primitive.reader(source))?;
        }
        if out.triangles.is_empty() {
            return Err("the skinned mesh has no triangles".into());
        }
        if let Some(animation) = document.animations().next() {
            out.channels = read_channels(&animation, source)?;
            out.duration = out.channels.iter().filter_map(|c| c.times.last()).fold(0.0, |a, &b| a.max(b));
        }
        Ok(out)
    }

    fn add_primitive<'a, 's, F>(&mut self, reader: &gltf::mesh::Reader<'a, 's, F>) -> Result<(), String>
    where
        F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
    {
        let base = self.positions.len() as u32;
        let positions: Vec<[f32; 3]> = reader.read_positions().ok_or("a primitive has no POSITION")?.collect();
        let n = positions.len();
        let joints: Vec<[u16; 4]> = reader.read_joints(0).ok_or("a primitive has no JOINTS_0")?.into_u16().collect();
        let weights: Vec<[f32; 4]> = reader.read_weights(0).ok_or("a primitive has no WEIGHTS_0")?.into_f32().collect();
        if joints.len() != n || weights.len() != n {
            return Err(format!("{n} positions but {} joint and {} weight sets", joints.len(), weights.len()));
        }
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..n as u32).collect(),
        };
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(format!("index {bad} past the primitive's {n} vertices"));
        }
        let joint_count = self.joints.len() as u32;
        for (j, w) in joints.iter().zip(&weights) {
            let j = j.map(u32::from);
            if let Some(bad) = j.iter().zip(w).find(|(j, w)| **j >= joint_count && **w > 0.0) {
                return Err(format!("joint {} past the skin's {joint_count}", bad.0));
            }
            let sum: f32 = w.iter().filter(|x| x.is_finite() && **x > 0.0).sum();
            // Weights are normalised (exporters leave rounding); unweighted vertices follow joint 0.
            let w = if sum > 0.0 {
                w.map(|x| if x.is_finite() && x > 0.0 { x / sum } else { 0.0 })
            } else {
                [1.0, 0.0, 0.0, 0.0]
            };
            self.vertex_joints.push(j.map(|x| x.min(joint_count - 1)));
            self.vertex_weights.push(w);
        }
        self.positions.extend(positions);
        self.triangles.extend(indices.chunks_exact(3).map(|t| [t[0] + base, t[1] + base, t[2] + base]));
        Ok(())
    }

    /// Every node's world transform at `time` (seconds into the animation; clamped to it).
    pub fn world_transforms(&self, time: f32) -> Vec<Mat4> {
        self.transforms(Some(time))
    }

    /// World transforms of the animation at `time`, or of the rest pose (`None`).
    fn transforms(&self, time: Option<f32>) -> Vec<Mat4> {
        let mut local: Vec<(Vec3, Quat, Vec3)> =
            self.nodes.iter().map(|n| (n.translation, n.rotation, n.scale)).collect();
        // The rest pose plays no channel.
        let channels = if time.is_some() { &self.channels[..] } else { &[] };
        let time = time.unwrap_or_default();
        for c in channels {
            let target = &mut local[c.node];
            match &c.keys {
                Keys::Translation(k) => target.0 = sample(&c.times, k, time, c.interpolation, Vec3::lerp),
                Keys::Rotation(k) => target.1 = sample(&c.times, k, time, c.interpolation, Quat::slerp),
                Keys::Scale(k) => target.2 = sample(&c.times, k, time, c.interpolation, Vec3::lerp),
            }
        }
        let mut world: Vec<Option<Mat4>> = vec![None; self.nodes.len()];
        for i in 0..self.nodes.len() {
            resolve(i, &self.nodes, &local, &mut world, 0);
        }
        world.into_iter().map(|m| m.unwrap_or(Mat4::IDENTITY)).collect()
    }

    /// Skinning matrices (joint world × inverse bind) at `time`.
    pub fn joint_matrices(&self, time: f32) -> Vec<Mat4> {
        let world = self.world_transforms(time);
        self.joints.iter().zip(&self.inverse_bind).map(|(&j, ib)| world[j] * *ib).collect()
    }

    /// The bind pose's place in the world (the mesh node's rest transform): what skinning with
    /// the rest pose gives.
    pub fn bind_transform(&self) -> Mat4 {
        self.transforms(None)[self.mesh_node]
    }

    /// Where vertex `v`'s skin takes a point `p` (bind pose) under `matrices`.
    pub fn skin_point(&self, v: usize, p: [f32; 3], matrices: &[Mat4]) -> [f32; 3] {
        let p = Vec3::from(p);
        let (j, w) = (self.vertex_joints[v], self.vertex_weights[v]);
        (0..4).map(|k| matrices[j[k] as usize].transform_point3(p) * w[k]).sum::<Vec3>().into()
    }

    /// The animation time of `seconds` played at `speed`, back and forth (ping-pong).
    pub fn ping_pong(&self, seconds: f64, speed: f32) -> f32 {
        if self.duration <= 0.0 {
            return 0.0;
        }
        let period = 2.0 * f64::from(self.duration);
        let phase = (seconds * f64::from(speed)).rem_euclid(period);
        (if phase > f64::from(self.duration) { period - phase } else { phase }) as f32
    }
}

/// Accessor references checked before the crate validates: gltf-json 1.4.1 indexes the accessor
/// list with a primitive's POSITION index unchecked, so an out-of-range one panics.
fn precheck(bytes: &[u8]) -> Result<(), String> {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| e.to_string())?;
    let json = gltf.document.as_json();
    // A sparse accessor may claim any count with no data behind it: 2³¹ elements in a 1 KB file
    // used to abort the process. What the accessors describe must fit the budget.
    let mut claimed: u64 = 0;
    for (i, accessor) in json.accessors.iter().enumerate() {
        let (Checked::Valid(kind), Checked::Valid(component)) = (&accessor.type_, &accessor.component_type) else {
            return Err(format!("accessor {i} has an unknown type"));
        };
        let element = (kind.multiplicity() * component.0.size()) as u64;
        let bytes = accessor.count.0.saturating_mul(element);
        claimed = claimed.saturating_add(bytes);
        if claimed > MODEL_DATA_LIMIT {
            return Err(format!(
                "accessor {i} claims {} elements; the model's data would pass the {} MiB a model may take",
                accessor.count.0,
                MODEL_DATA_LIMIT >> 20
            ));
        }
    }
    if let Some(b) = json.buffers.iter().find(|b| b.byte_length.0 > MODEL_DATA_LIMIT) {
        return Err(format!("a buffer of {} bytes; a model may take {} MiB", b.byte_length.0, MODEL_DATA_LIMIT >> 20));
    }
    let accessors = json.accessors.len();
    for (m, mesh) in gltf.document.as_json().meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let attributes = primitive.attributes.iter().map(|(semantic, a)| (format!("{semantic:?}"), a.value()));
            let indices = primitive.indices.iter().map(|a| ("indices".to_string(), a.value()));
            if let Some((what, a)) = attributes.chain(indices).find(|(_, a)| *a >= accessors) {
                return Err(format!("mesh {m} primitive {p}: {what} names accessor {a}, but there are {accessors}"));
            }
        }
    }
    Ok(())
}

/// The document's buffers: the binary chunk, data URIs, and files beside the document that
/// `rules` allow (other URI schemes are refused).
fn read_buffers(gltf: &gltf::Gltf, folder: &Path, rules: &FileRules) -> Result<Vec<gltf::buffer::Data>, String> {
    let mut blob = gltf.blob.clone();
    let mut buffers = Vec::new();
    for buffer in gltf.document.buffers() {
        let mut data = match buffer.source() {
            gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => {
                if uri.contains(':') {
                    return Err(format!("buffer '{uri}': only files beside the model and data URIs are read"));
                }
                let name = folder.join(&*urlencoding::decode(uri).map_err(|e| format!("buffer '{uri}': {e}"))?);
                let file = rules.locate(None, &name.to_string_lossy()).map_err(|e| match e {
                    FileError::NotFound(_) => format!("buffer file {uri} not found beside it"),
                    FileError::Refused(why) => format!("buffer '{uri}': {why}"),
                })?;
                files::read_limited(&file, MODEL_DATA_LIMIT).map_err(|e| format!("buffer {e}"))?
            }
            source => gltf::buffer::Data::from_source_and_blob(source, None, &mut blob).map_err(|e| e.to_string())?.0,
        };
        if data.len() < buffer.length() {
            return Err(format!("buffer {} holds {} bytes, {} expected", buffer.index(), data.len(), buffer.length()));
        }
        data.resize(data.len().next_multiple_of(4), 0);
        buffers.push(gltf::buffer::Data(data));
    }
    Ok(buffers)
}

fn rest_nodes(document: &gltf::Document) -> Vec<RestNode> {
    let mut nodes: Vec<RestNode> = document
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            RestNode { parent: None, translation: t.into(), rotation: Quat::from_array(r).normalize(), scale: s.into() }
        })
        .collect();
    for n in document.nodes() {
        for c in n.children() {
            nodes[c.index()].parent = Some(n.index());
        }
    }
    nodes
}

/// A node's world matrix, from its parents' (depth-bounded: a cycle cannot hang us).
fn resolve(
    i: usize,
    nodes: &[RestNode],
    local: &[(Vec3, Quat, Vec3)],
    world: &mut [Option<Mat4>],
    depth: usize,
) -> Mat4 {
    if let Some(m) = world[i] {
        return m;
    }
    let (t, r, s) = local[i];
    let own = Mat4::from_scale_rotation_translation(s, r, t);
    let m = match nodes[i].parent {
        Some(p) if depth < 256 => resolve(p, nodes, local, world, depth + 1) * own,
        _ => own,
    };
    world[i] = Some(m);
    m
}

fn sample<T: Copy>(times: &[f32], keys: &[T], time: f32, mode: Interpolation, lerp: impl Fn(T, T, f32) -> T) -> T {
    let next = times.partition_point(|&k| k <= time);
    if next == 0 {
        return keys[0];
    }
    if next >= times.len() {
        return keys[times.len() - 1];
    }
    let (a, b) = (times[next - 1], times[next]);
    match mode {
        Interpolation::Step => keys[next - 1],
        Interpolation::Linear => lerp(keys[next - 1], keys[next], ((time - a) / (b - a).max(1e-9)).clamp(0.0, 1.0)),
    }
}

fn read_channels<'a, 's>(
    animation: &gltf::Animation<'a>,
    source: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
) -> Result<Vec<Channel>, String> {
    use gltf::animation::util::ReadOutputs;
    let mut channels = Vec::new();
    for channel in animation.channels() {
        let reader = channel.reader(source.clone());
        let times: Vec<f32> = reader.read_inputs().ok_or("an animation channel has no key times")?.collect();
        let (interpolation, stride) = match channel.sampler().interpolation() {
            gltf::animation::Interpolation::Step => (Interpolation::Step, 1),
            gltf::animation::Interpolation::Linear => (Interpolation::Linear, 1),
            // In-tangent, value, out-tangent per key: the values, linearly.
            gltf::animation::Interpolation::CubicSpline => (Interpolation::Linear, 3),
        };
        let pick = |all: Vec<[f32; 4]>| -> Vec<[f32; 4]> { all.into_iter().skip(stride / 2).step_by(stride).collect() };
        let keys = match reader.read_outputs().ok_or("an animation channel has no values")? {
            ReadOutputs::Translations(v) => Keys::Translation(
                pick(v.map(|x| [x[0], x[1], x[2], 0.0]).collect())
                    .iter()
                    .map(|x| Vec3::new(x[0], x[1], x[2]))
                    .collect(),
            ),
            ReadOutputs::Rotations(v) => {
                Keys::Rotation(pick(v.into_f32().collect()).iter().map(|x| Quat::from_array(*x).normalize()).collect())
            }
            ReadOutputs::Scales(v) => Keys::Scale(
                pick(v.map(|x| [x[0], x[1], x[2], 0.0]).collect())
                    .iter()
                    .map(|x| Vec3::new(x[0], x[1], x[2]))
                    .collect(),
            ),
            ReadOutputs::MorphTargetWeights(_) => continue,
        };
        let count = match &keys {
            Keys::Translation(k) | Keys::Scale(k) => k.len(),
            Keys::Rotation(k) => k.len(),
        };
        if times.is_empty()
            || count != times.len()
            || times.windows(2).any(|w| w[0].partial_cmp(&w[1]).is_none_or(|o| o.is_gt()))
        {
            return Err(format!(
                "animation channel on node {}: {} key times for {count} values, or not increasing",
                channel.target().node().index(),
                times.len()
            ));
        }
        channels.push(Channel { node: channel.target().node().index(), times, keys, interpolation });
    }
    Ok(channels)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FIGURE: &[u8] = include_bytes!("../../assets/models/RiggedFigure.gltf");

    fn figure() -> SkinnedMesh {
        SkinnedMesh::from_slice("RiggedFigure.gltf", FIGURE).unwrap()
    }

    #[test]
    fn the_rigged_figure_loads_with_its_skin_and_clip() {
        let m = figure();
        assert_eq!(m.joints.len(), 19);
        assert_eq!(m.positions.len(), 370);
        assert_eq!(m.triangles.len(), 256);
        assert!((m.duration - 1.25).abs() < 1e-6, "{}", m.duration);
        for w in &m.vertex_weights {
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{w:?}");
        }
    }

    #[test]
    fn skinning_with_the_rest_pose_gives_the_bind_pose() {
        let m = figure();
        // Rest pose: no animation applied.
        let rest = SkinnedMesh { channels: Vec::new(), ..m.clone() };
        let matrices = rest.joint_matrices(0.0);
        // The bind pose is the mesh in its node's place (here under the Z-up → Y-up root).
        let holder = m.bind_transform();
        for (v, p) in m.positions.iter().enumerate() {
            let skinned = Vec3::from(rest.skin_point(v, *p, &matrices));
            let bind = holder.transform_point3(Vec3::from(*p));
            assert!((skinned - bind).length() < 1e-4, "vertex {v}: {skinned} vs {bind}");
        }
    }
}

#[cfg(test)]
mod budget_tests {
    use super::*;

    #[test]
    fn accessors_claiming_more_data_than_the_budget_are_refused_before_allocating() {
        // A sparse accessor with no data behind it, claiming 2³¹ positions.
        let json = r#"{"asset":{"version":"2.0"},"accessors":[{"componentType":5126,"count":2147483648,
            "type":"VEC3","sparse":{"count":1,"indices":{"bufferView":0,"componentType":5125},
            "values":{"bufferView":0}}}],"buffers":[{"byteLength":16,
            "uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAAAAAA=="}],
            "bufferViews":[{"buffer":0,"byteLength":16}]}"#;
        let e = SkinnedMesh::from_slice("sparse.gltf", json.as_bytes()).unwrap_err();
        assert!(e.contains("sparse.gltf") && e.contains("claims 2147483648"), "{e}");
    }

    #[test]
    fn buffers_outside_the_model_folder_or_behind_a_scheme_are_refused() {
        let dir = std::env::temp_dir().join(format!("indra-gltf-uri-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("models")).unwrap();
        for (uri, says) in [("../secret.bin", "outside the folders"), ("file:///etc/passwd", "only files beside")] {
            let json = format!(r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":4,"uri":"{uri}"}}]}}"#);
            let path = dir.join("models/escape.gltf");
            std::fs::write(dir.join("secret.bin"), [0u8; 4]).unwrap();
            std::fs::write(&path, json).unwrap();
            let e = SkinnedMesh::load(&path).unwrap_err();
            assert!(e.contains(says), "{uri}: {e}");
        }
        std::fs::remove_dir_all(dir).unwrap();
    }
}
