//! Ordering, culling and resource lifetimes: everything decided before any GPU work is recorded.

use std::collections::BTreeSet;

use super::builder::{Access, BufferOrigin, FrameGraph, Resource, TextureOrigin};

/// Why a frame's declarations cannot run.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum GraphError {
    /// Passes depend on each other in a circle.
    #[error("frame graph has a dependency cycle through the passes: {}", .0.join(" → "))]
    Cycle(Vec<String>),
    /// Nothing was set as output.
    #[error("frame graph has no output texture (call set_output)")]
    NoOutput,
    /// A pass reads a transient resource that no pass writes.
    #[error("pass '{pass}' reads '{resource}', which no pass writes")]
    ReadOfUnwritten {
        /// The reading pass.
        pass: String,
        /// The resource.
        resource: String,
    },
}

/// The result of compiling: which passes run in which order, and when each transient lives.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CompiledGraph {
    /// Indices of the passes to execute, in execution order.
    pub order: Vec<usize>,
    /// Per texture: (first, last) position in `order` where it is used; `None` if unused.
    pub texture_lifetimes: Vec<Option<(usize, usize)>>,
    /// Per buffer: (first, last) position in `order`.
    pub buffer_lifetimes: Vec<Option<(usize, usize)>>,
}

impl CompiledGraph {
    /// Number of passes that run.
    pub fn executed(&self) -> usize {
        self.order.len()
    }
}

/// Sorts passes by their dependencies, culls those that reach no output, computes lifetimes.
///
/// Dependencies: a pass that reads a resource comes after every pass that writes it; among
/// passes that write the same resource, declaration order is kept (a read-modify-write chain).
/// Ties are broken by declaration order, so the result is deterministic.
pub fn compile(graph: &FrameGraph<'_>) -> Result<CompiledGraph, GraphError> {
    let output = match (graph.output, graph.simulation_only) {
        (_, true) => None,
        (Some(output), false) => Some(output),
        (None, false) => return Err(GraphError::NoOutput),
    };
    let n = graph.passes.len();
    let writers = |r: Resource| -> Vec<usize> {
        (0..n).filter(|&p| graph.passes[p].accesses.iter().any(|&(res, a)| res == r && a != Access::Read)).collect()
    };
    let writes = |p: usize, r: Resource| graph.passes[p].accesses.iter().any(|&(res, a)| res == r && a != Access::Read);

    // Edges: deps[p] = passes that must run before p.
    let mut deps: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
    for (p, pass) in graph.passes.iter().enumerate() {
        for &(res, access) in &pass.accesses {
            for w in writers(res) {
                if w == p {
                    continue;
                }
                let is_reader_only = access == Access::Read && !writes(p, res);
                if is_reader_only || w < p {
                    deps[p].insert(w);
                }
            }
        }
    }

    let shown: Vec<super::TextureHandle> = output.into_iter().chain(graph.extra_outputs.iter().copied()).collect();
    let live = live_passes(graph, &shown, &deps);
    let order = topological_order(graph, &deps, &live)?;
    check_reads(graph, &order)?;

    let mut texture_lifetimes = vec![None; graph.textures.len()];
    let mut buffer_lifetimes = vec![None; graph.buffers.len()];
    for (position, &p) in order.iter().enumerate() {
        for &(res, _) in &graph.passes[p].accesses {
            let slot = match res {
                Resource::Texture(t) => &mut texture_lifetimes[t as usize],
                Resource::Buffer(b) => &mut buffer_lifetimes[b as usize],
            };
            *slot = Some(match *slot {
                None => (position, position),
                Some((first, _)) => (first, position),
            });
        }
    }
    // The outputs are read after the last pass (display encode / readback).
    for shown in &shown {
        if let Some((first, _)) = texture_lifetimes[shown.0 as usize] {
            texture_lifetimes[shown.0 as usize] = Some((first, usize::MAX));
        }
    }
    Ok(CompiledGraph { order, texture_lifetimes, buffer_lifetimes })
}

/// Passes whose work reaches the output, an imported resource, or that have side effects.
fn live_passes(graph: &FrameGraph<'_>, shown: &[super::TextureHandle], deps: &[BTreeSet<usize>]) -> Vec<bool> {
    let is_root = |p: usize| {
        let pass = &graph.passes[p];
        pass.side_effect
            || pass.accesses.iter().any(|&(res, a)| {
                a != Access::Read
                    && match res {
                        Resource::Texture(t) => {
                            shown.iter().any(|o| o.0 == t)
                                || matches!(graph.textures[t as usize].origin, TextureOrigin::Imported(..))
                        }
                        Resource::Buffer(b) => {
                            matches!(graph.buffers[b as usize].origin, BufferOrigin::Imported(..))
                        }
                    }
            })
    };
    let mut live = vec![false; graph.passes.len()];
    let mut stack: Vec<usize> = (0..graph.passes.len()).filter(|&p| is_root(p)).collect();
    while let Some(p) = stack.pop() {
        if !std::mem::replace(&mut live[p], true) {
            stack.extend(deps[p].iter().copied().filter(|&d| !live[d]));
        }
    }
    live
}

/// Kahn's algorithm over live passes, smallest declaration index first.
fn topological_order(
    graph: &FrameGraph<'_>,
    deps: &[BTreeSet<usize>],
    live: &[bool],
) -> Result<Vec<usize>, GraphError> {
    let mut remaining: BTreeSet<usize> = (0..deps.len()).filter(|&p| live[p]).collect();
    let mut order = Vec::with_capacity(remaining.len());
    while !remaining.is_empty() {
        let ready = remaining.iter().copied().find(|&p| deps[p].iter().all(|d| !remaining.contains(d)));
        match ready {
            Some(p) => {
                remaining.remove(&p);
                order.push(p);
            }
            None => {
                let names = remaining.iter().map(|&p| graph.passes[p].name.clone()).collect();
                return Err(GraphError::Cycle(names));
            }
        }
    }
    Ok(order)
}

/// Every transient resource a live pass reads must be written by some live pass before it.
fn check_reads(graph: &FrameGraph<'_>, order: &[usize]) -> Result<(), GraphError> {
    let mut written: BTreeSet<Resource> = BTreeSet::new();
    for &p in order {
        let pass = &graph.passes[p];
        for &(res, access) in &pass.accesses {
            let imported = match res {
                Resource::Texture(t) => matches!(graph.textures[t as usize].origin, TextureOrigin::Imported(..)),
                Resource::Buffer(b) => {
                    matches!(graph.buffers[b as usize].origin, BufferOrigin::Imported(..))
                }
            };
            let self_written = pass.accesses.iter().any(|&(r, a)| r == res && a != Access::Read);
            if access == Access::Read && !imported && !self_written && !written.contains(&res) {
                let resource = match res {
                    Resource::Texture(t) => graph.textures[t as usize].name.clone(),
                    Resource::Buffer(b) => graph.buffers[b as usize].name.clone(),
                };
                return Err(GraphError::ReadOfUnwritten { pass: pass.name.clone(), resource });
            }
        }
        for &(res, access) in &pass.accesses {
            if access != Access::Read {
                written.insert(res);
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{TextureDesc, TextureHandle};

    const F: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

    fn names(graph: &FrameGraph<'_>, compiled: &CompiledGraph) -> Vec<String> {
        compiled.order.iter().map(|&p| graph.passes[p].name.clone()).collect()
    }

    fn pass(graph: &mut FrameGraph<'_>, name: &str, reads: &[TextureHandle], writes: &[TextureHandle]) {
        let mut b = graph.add_pass(name);
        for &r in reads {
            b = b.read(r);
        }
        for &w in writes {
            b = b.write(w);
        }
        b.record(|_| {});
    }

    #[test]
    fn passes_declared_out_of_order_are_sorted_by_dependency() {
        let mut g = FrameGraph::new((64, 64));
        let a = g.create_texture("a", TextureDesc::full(F));
        let b = g.create_texture("b", TextureDesc::full(F));
        let out = g.create_texture("out", TextureDesc::full(F));
        pass(&mut g, "composite", &[b], &[out]);
        pass(&mut g, "blur", &[a], &[b]);
        pass(&mut g, "bright", &[], &[a]);
        g.set_output(out);
        let c = compile(&g).unwrap();
        assert_eq!(names(&g, &c), ["bright", "blur", "composite"]);
    }

    #[test]
    fn passes_that_reach_no_output_are_culled() {
        let mut g = FrameGraph::new((64, 64));
        let a = g.create_texture("a", TextureDesc::full(F));
        let unused = g.create_texture("unused", TextureDesc::full(F));
        let out = g.create_texture("out", TextureDesc::full(F));
        pass(&mut g, "make_a", &[], &[a]);
        pass(&mut g, "dead_end", &[a], &[unused]);
        pass(&mut g, "final", &[a], &[out]);
        g.set_output(out);
        let c = compile(&g).unwrap();
        assert_eq!(names(&g, &c), ["make_a", "final"]);
        assert_eq!(c.texture_lifetimes[unused.0 as usize], None);
    }

    #[test]
    fn side_effects_and_imported_writes_survive_culling() {
        let device_free_graph = |side_effect: bool| {
            let mut g = FrameGraph::new((8, 8));
            let t = g.create_texture("t", TextureDesc::full(F));
            let out = g.create_texture("out", TextureDesc::full(F));
            let b = g.add_pass("stats").write(t);
            if side_effect { b.side_effect() } else { b }.record(|_| {});
            pass(&mut g, "final", &[], &[out]);
            g.set_output(out);
            compile(&g).unwrap().executed()
        };
        assert_eq!(device_free_graph(true), 2);
        assert_eq!(device_free_graph(false), 1);
    }

    #[test]
    fn a_cycle_is_a_clear_error() {
        let mut g = FrameGraph::new((64, 64));
        let x = g.create_texture("x", TextureDesc::full(F));
        let y = g.create_texture("y", TextureDesc::full(F));
        let out = g.create_texture("out", TextureDesc::full(F));
        pass(&mut g, "p", &[x], &[y]);
        pass(&mut g, "q", &[y], &[x]);
        pass(&mut g, "final", &[y], &[out]);
        g.set_output(out);
        let err = compile(&g).unwrap_err();
        assert!(matches!(&err, GraphError::Cycle(n) if n.contains(&"p".to_string()) && n.contains(&"q".to_string())));
        assert!(err.to_string().contains("cycle"), "{err}");
    }

    #[test]
    fn reading_a_texture_nobody_writes_is_an_error() {
        let mut g = FrameGraph::new((64, 64));
        let ghost = g.create_texture("ghost", TextureDesc::full(F));
        let out = g.create_texture("out", TextureDesc::full(F));
        pass(&mut g, "final", &[ghost], &[out]);
        g.set_output(out);
        assert_eq!(
            compile(&g).unwrap_err(),
            GraphError::ReadOfUnwritten { pass: "final".into(), resource: "ghost".into() }
        );
    }

    #[test]
    fn no_output_is_an_error() {
        let g = FrameGraph::new((64, 64));
        assert_eq!(compile(&g).unwrap_err(), GraphError::NoOutput);
    }

    #[test]
    fn a_simulation_only_frame_keeps_only_work_on_persistent_state() {
        let mut g = FrameGraph::simulation_only((64, 64));
        let state = g.create_buffer("forces", 64);
        let scratch = g.create_texture("scratch", TextureDesc::full(F));
        let image = g.create_texture("image", TextureDesc::full(F));
        // "forces" is transient, but the side-effect step reads it: it must run too.
        g.add_pass("forces").write_buffer(state).record(|_| {});
        g.add_pass("step").read_buffer(state).side_effect().record(|_| {});
        pass(&mut g, "blur", &[], &[scratch]);
        pass(&mut g, "draw", &[scratch], &[image]);
        g.set_output(image);
        assert_eq!(g.output(), None, "a simulation-only frame has no output");
        let c = compile(&g).unwrap();
        assert_eq!(names(&g, &c), ["forces", "step"]);
    }

    #[test]
    fn read_modify_write_chain_keeps_declaration_order() {
        let mut g = FrameGraph::new((64, 64));
        let acc = g.create_texture("acc", TextureDesc::full(F));
        let out = g.create_texture("out", TextureDesc::full(F));
        pass(&mut g, "clear", &[], &[acc]);
        pass(&mut g, "add_1", &[acc], &[acc]);
        pass(&mut g, "add_2", &[acc], &[acc]);
        pass(&mut g, "final", &[acc], &[out]);
        g.set_output(out);
        let c = compile(&g).unwrap();
        assert_eq!(names(&g, &c), ["clear", "add_1", "add_2", "final"]);
        assert_eq!(c.texture_lifetimes[acc.0 as usize], Some((0, 3)));
    }
}
