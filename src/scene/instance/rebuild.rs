//! Rebuilds made ahead: the nodes (and show runtime or transitions) a scene switch or a shader
//! edit needs are built from a [`SceneSnapshot`] of the running scene — on a worker thread in a
//! live show, where pipelines may take seconds to compile — and installed in one step on the
//! render thread, if the scene is still the one they were built for.

use super::{SceneInstance, create_node};
use crate::assets::Assets;
use crate::gpu::{Gpu, ShaderError};
use crate::params::{ParamSet, Remap};
use crate::scene::SceneNode;
use crate::scene::model::Scene;
use crate::scene::show::{Mixer, ShowRuntime};
use crate::techniques::Technique;

/// What a rebuild is made from: the running scene and its parameters as they were taken.
pub struct SceneSnapshot {
    /// The running scene.
    pub scene: Scene,
    /// Each node's parameters when the snapshot was taken.
    pub params: Vec<ParamSet>,
    /// The instance's revision then: a rebuild installs only on the same one.
    revision: u64,
}

/// A rebuild made for a scene that has changed since (another reload, or a new device): it is
/// dropped and made again from a new snapshot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Outdated;

/// Where a replacement's show gets its transitions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transitions {
    /// Compiled for it (a reload: the show file may name others).
    Compile,
    /// Taken from the running show at the install (a chain edit: they do not change).
    TakeRunning,
}

/// A switch to an edited scene, built ahead (see [`SceneInstance::install`]).
pub struct Replacement {
    revision: u64,
    scene: Scene,
    /// Per new node: the old node it keeps (same id, technique and parameters), if any.
    kept: Vec<Option<usize>>,
    /// Per new node: its new instance, where it is not kept.
    fresh: Vec<Option<Box<dyn Technique>>>,
    /// Per new node: its parameters as the new scene starts them (cloned off the render thread).
    params: Vec<ParamSet>,
    /// Per new node: (parameter, the old node's parameter) pairs whose live value carries over
    /// (same name, type and default), for kept nodes.
    carried: Vec<Vec<(usize, usize)>>,
    show: Option<ShowRuntime>,
    transitions: Transitions,
}

impl Replacement {
    /// Builds what switching from `snapshot`'s scene to `scene` needs: nodes whose id, technique
    /// and parameter names are unchanged are kept (with their simulation state) unless `rebuild`
    /// picks them (their file changed: an ISF shader); the rest are created. A changed sample
    /// count rebuilds every node (pipelines are made for one count).
    pub fn prepare(
        snapshot: &SceneSnapshot,
        scene: Scene,
        gpu: &Gpu,
        assets: &Assets,
        output_size: (u32, u32),
        (rebuild, transitions): (&dyn Fn(&SceneNode) -> bool, Transitions),
    ) -> Result<Self, ShaderError> {
        let old = &snapshot.scene;
        let same_msaa = old.msaa == scene.msaa;
        let same_decls = |a: &ParamSet, b: &ParamSet| {
            a.decls().len() == b.decls().len() && a.decls().iter().zip(b.decls()).all(|(x, y)| x.name == y.name)
        };
        let kept: Vec<Option<usize>> = scene
            .nodes
            .iter()
            .map(|n| {
                old.nodes.iter().position(|o| {
                    same_msaa
                        && o.id == n.id
                        && o.technique.name == n.technique.name
                        && same_decls(&o.params, &n.params)
                        && !rebuild(n)
                })
            })
            .collect();
        let mut fresh = Vec::with_capacity(scene.nodes.len());
        for (i, n) in scene.nodes.iter().enumerate() {
            fresh.push(match kept[i] {
                Some(_) => None,
                None => Some(create_node(&scene, i, &n.params, gpu, assets, output_size)?),
            });
        }
        // What the install does on the render thread is only copying values: the parameter sets
        // and which values carry over are worked out here.
        let params: Vec<ParamSet> = scene.nodes.iter().map(|n| n.params.clone()).collect();
        let carried = scene
            .nodes
            .iter()
            .zip(&kept)
            .map(|(n, kept)| {
                let Some(o) = *kept else { return Vec::new() };
                let old_decls = &snapshot.params[o];
                let decls = n.params.decls().iter().enumerate();
                decls
                    .filter_map(|(p, decl)| {
                        let op = old_decls.index(&decl.name)?;
                        let before = &old_decls.decls()[op];
                        (before.default == decl.default && before.ty() == decl.ty()).then_some((p, op))
                    })
                    .collect()
            })
            .collect();
        let show = match transitions {
            Transitions::Compile => ShowRuntime::new(gpu, assets, &scene, output_size)?,
            Transitions::TakeRunning => ShowRuntime::taking_transitions(gpu, assets, &scene, output_size),
        };
        Ok(Self { revision: snapshot.revision, scene, kept, fresh, params, carried, show, transitions })
    }
}

/// The nodes (and show transitions) that use an edited shader, built anew (see
/// [`SceneInstance::install_nodes`]).
pub struct NodeRebuild {
    revision: u64,
    nodes: Vec<(usize, Box<dyn Technique>)>,
    mixer: Option<(Mixer, Assets)>,
}

impl NodeRebuild {
    /// Builds, with `assets`, every node of `snapshot` whose technique loads shader file `name`,
    /// and the show's transitions if they do. Either all of them build or the error is returned.
    pub fn prepare(
        snapshot: &SceneSnapshot,
        name: &str,
        gpu: &Gpu,
        assets: &Assets,
        output_size: (u32, u32),
    ) -> Result<Self, ShaderError> {
        let scene = &snapshot.scene;
        // A technique's own shaders, or the file a node names (a WGSL effect's).
        let names_file = |i: usize| {
            let node = &scene.nodes[i];
            let file = node.technique.declare.and_then(|d| node.params.index(d.file_param));
            matches!(file.map(|p| snapshot.params[i].value_at(p)),
                Some(crate::params::ParamValue::Text(f)) if f.as_str().rsplit('/').next() == Some(name))
        };
        let nodes = (0..scene.nodes.len())
            .filter(|&i| scene.nodes[i].technique.shaders.contains(&name) || names_file(i))
            .map(|i| Ok((i, create_node(scene, i, &snapshot.params[i], gpu, assets, output_size)?)))
            .collect::<Result<Vec<_>, ShaderError>>()?;
        let mixer = match &scene.show {
            Some(show) if Mixer::files_for(show).iter().any(|f| f == name) => {
                Some((Mixer::new(gpu, assets, show)?, assets.clone()))
            }
            _ => None,
        };
        Ok(Self { revision: snapshot.revision, nodes, mixer })
    }

    /// Whether anything uses the shader.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty() && self.mixer.is_none()
    }
}

impl SceneInstance {
    /// The running scene and its parameters now, to build a rebuild from.
    pub fn snapshot(&self) -> SceneSnapshot {
        SceneSnapshot { scene: self.scene.clone(), params: self.params.clone(), revision: self.revision }
    }

    /// Switches to the edited scene `replacement` was built for. Kept nodes keep their instance
    /// and simulation state; parameters keep their live values unless the file changed their
    /// default. Returns where each old parameter is now, for everything that holds parameter
    /// positions across the reload (queued events, scripts, MIDI learn).
    pub fn install(&mut self, replacement: Replacement) -> Result<Remap, Outdated> {
        let Replacement { revision, scene, kept, mut fresh, mut params, carried, mut show, transitions } = replacement;
        if revision != self.revision {
            return Err(Outdated);
        }
        let in_place: Vec<bool> = kept.iter().enumerate().map(|(i, k)| *k == Some(i)).collect();
        let mut old_nodes: Vec<Option<Box<dyn Technique>>> = self.nodes.drain(..).map(Some).collect();
        // Kept nodes carry their live values (the ones now, not the snapshot's) and instances.
        for (((set, new), kept), carried) in params.iter_mut().zip(fresh.iter_mut()).zip(kept).zip(&carried) {
            if let Some(old) = kept {
                let old_set = &self.params[old];
                for &(p, op) in carried {
                    set.set_at(p, old_set.target_at(op));
                }
                set.snap();
                *new = old_nodes[old].take();
            }
        }
        let remap = Remap::between(
            self.scene.nodes.iter().map(|n| n.id.as_str()).zip(&self.params),
            scene.nodes.iter().map(|n| n.id.as_str()).zip(&params),
        );
        self.nodes = fresh.into_iter().map(|n| n.expect("every node kept or created")).collect();
        // The old scene and parameter sets are many small allocations: freed off the render thread.
        crate::gpu::drop_later((
            std::mem::replace(&mut self.scene, scene),
            std::mem::replace(&mut self.params, params),
        ));
        if let (Some(show), Some(old)) = (&mut show, &mut self.show) {
            if transitions == Transitions::TakeRunning {
                show.take_transitions(old);
            }
            let messages = show.carry_over(old, &self.scene, &self.params, &mut self.nodes, &|n| in_place[n]);
            self.messages.extend(messages);
        }
        // What the switch lets go of (GPU objects) is released off the render thread.
        crate::gpu::drop_later((std::mem::replace(&mut self.show, show), old_nodes));
        self.overridden.clear();
        self.morph = None;
        self.pending_morph = None;
        self.revision += 1;
        Ok(remap)
    }

    /// Swaps in the nodes (and transitions) `rebuild` made for an edited shader. Stateless
    /// techniques lose nothing; stateful ones restart.
    pub fn install_nodes(&mut self, rebuild: NodeRebuild) -> Result<(), Outdated> {
        if rebuild.revision != self.revision {
            return Err(Outdated);
        }
        for (i, node) in rebuild.nodes {
            self.nodes[i] = node;
        }
        if let (Some(show), Some((mixer, assets))) = (self.show.as_mut(), rebuild.mixer) {
            show.install_mixer(mixer, &assets);
        }
        self.revision += 1;
        Ok(())
    }
}
