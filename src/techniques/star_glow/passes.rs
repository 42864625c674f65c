//! Declaring StarGlow's passes: every intermediate is a transient texture sized relative to the
//! output, so the frame graph's pool reuses them (a book-layout frame of N streaks needs a handful
//! of physical textures, not N × iteration).

use super::{Binding, FORMAT, Kernel, Layout, LayoutChoice, Settings, StarGlow, StarGlowUniforms, streak_step};
use crate::graph::{Extent, FrameGraph, PassContext, TextureDesc, TextureHandle};
use crate::techniques::srgb_to_linear;

/// Invocations of one scan workgroup, each a texel of a chunk of a line (`SCAN_WIDTH` in the
/// shader).
const SCAN_WIDTH: u32 = 256;

/// Longest line the scan layout takes (`SCAN_MAX_CHUNKS` chunks in the shader).
const SCAN_MAX_LINE: u32 = 16 * SCAN_WIDTH;

/// Longest whole-texel step the scan takes (a chunk must hold at least one step).
const SCAN_MAX_STEP: f32 = 64.0;

/// One frame's worth of StarGlow work, decided from the parameters.
pub(super) struct Plan {
    layout: Layout,
    /// `layout: Auto`: the scan where it applies.
    auto: bool,
    base: StarGlowUniforms,
    streaks: u32,
    iteration: u32,
    angle: f32,
    resolution_independent: bool,
    /// Multiplies every tap step: output height / 1080 when resolution independent, else 1.
    step_scale: f32,
}

/// A pass to declare: its kernel, what it reads and writes at which binding, and how many
/// invocations it runs: (x, y, directions) over the texture it writes, or `threads`.
struct PassSpec<'k> {
    name: String,
    kernel: &'k Kernel,
    reads: Vec<(Binding, TextureHandle)>,
    write: (Binding, TextureHandle),
    uniforms: StarGlowUniforms,
    layers: u32,
    threads: Option<[u32; 3]>,
}

impl Plan {
    pub fn new(p: &Settings) -> Self {
        let c = p.color;
        // Scenes may give their own ranges: the shader's limits are kept here.
        let base = StarGlowUniforms {
            dst_size: [0; 2],
            threshold: p.threshold,
            intensity: p.intensity,
            offset: [0.0; 2],
            attenuation: p.attenuation,
            power: 1.0,
            composite_type: p.composite.index(),
            directions: p.streaks.clamp(1, 16) as u32,
            first: 0,
            divide: p.divide.clamp(1, 20) as u32,
            color: [srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2]), c[3]],
            steps: [[0.0; 4]; 16],
        };
        Self {
            layout: Layout::of(p.layout),
            auto: p.layout == LayoutChoice::Auto,
            base,
            streaks: base.directions,
            iteration: p.iteration.clamp(1, 5) as u32,
            angle: p.angle,
            resolution_independent: p.resolution_independent,
            step_scale: 1.0,
        }
    }

    /// Declares the passes; returns the composited output.
    pub fn declare<'r>(
        mut self,
        node: &'r StarGlow,
        graph: &mut FrameGraph<'r>,
        source: TextureHandle,
    ) -> TextureHandle {
        if self.resolution_independent {
            self.step_scale = graph.output_size().1 as f32 / super::REFERENCE_HEIGHT;
        }
        let small =
            TextureDesc { extent: Extent::Relative(1, self.base.divide), format: FORMAT, layers: None, samples: 1 };
        let small_size = small.extent.resolve(graph.output_size());
        if self.auto && self.scan_applies(small_size) {
            self.layout = Layout::Scan;
        }
        let mut passes = Vec::new();
        let k = &node.kernels;
        let bright = graph.create_texture("star_glow/bright", small);
        passes.push(self.spec("star_glow/bright", &k.bright, &[(Binding::TexA, source)], (Binding::Dst, bright), 1.0));
        let glow = match self.layout {
            Layout::Book => self.book(node, graph, small, bright, &mut passes),
            Layout::Fused => self.fused(node, graph, small, bright, &mut passes),
            Layout::Scan => self.scan(node, graph, (small, small_size), bright, &mut passes),
        };
        let out = graph.create_texture("star_glow/image", TextureDesc::full(FORMAT));
        let reads = [(Binding::TexA, source), (Binding::TexB, glow)];
        passes.push(self.spec("star_glow/composite", &k.composite, &reads, (Binding::Dst, out), 1.0));
        for (slot, pass) in passes.into_iter().enumerate() {
            declare(graph, node, slot, pass);
        }
        out
    }

    /// Per direction: `iteration` streak passes, then a screen accumulation.
    fn book<'k>(
        &self,
        node: &'k StarGlow,
        graph: &mut FrameGraph<'_>,
        small: TextureDesc,
        bright: TextureHandle,
        passes: &mut Vec<PassSpec<'k>>,
    ) -> TextureHandle {
        let k = &node.kernels;
        let mut acc: Option<TextureHandle> = None;
        for i in 1..=self.streaks {
            let [x, y] = streak_step(i, self.streaks, self.angle);
            let step = [x * self.step_scale, y * self.step_scale];
            let mut level = bright;
            for n in 1..=self.iteration {
                let power = 4f32.powi(n as i32 - 1);
                let out = graph.create_texture("star_glow/streak", small);
                let mut spec = self.spec(
                    &format!("star_glow/streak{i}.{n}"),
                    &k.streak,
                    &[(Binding::TexA, level)],
                    (Binding::Dst, out),
                    power,
                );
                spec.uniforms.offset = [step[0] * power, step[1] * power];
                passes.push(spec);
                level = out;
            }
            let next = graph.create_texture("star_glow/accumulation", small);
            let reads = [(Binding::TexA, acc.unwrap_or(level)), (Binding::TexB, level)];
            let mut spec =
                self.spec(&format!("star_glow/accumulate{i}"), &k.accumulate, &reads, (Binding::Dst, next), 1.0);
            spec.uniforms.first = u32::from(acc.is_none());
            passes.push(spec);
            acc = Some(next);
        }
        acc.expect("at least one streak")
    }

    /// One scan per line and direction into a layered texture, then the accumulation; `small`
    /// with its size at this output.
    fn scan<'k>(
        &self,
        node: &'k StarGlow,
        graph: &mut FrameGraph<'_>,
        (small, (w, h)): (TextureDesc, (u32, u32)),
        bright: TextureHandle,
        passes: &mut Vec<PassSpec<'k>>,
    ) -> TextureHandle {
        let k = &node.kernels;
        let streaks = graph.create_texture("star_glow/streaks", small.with_layers(self.streaks));
        // The streak's length in taps rides in `power`; the steps are the level-1 steps.
        let taps = 4f32.powi(self.iteration as i32);
        let mut spec =
            self.spec("star_glow/scan", &k.streak_scan, &[(Binding::TexA, bright)], (Binding::DstLayers, streaks), 1.0);
        spec.uniforms.power = taps;
        // One workgroup per line (rows for the x streaks, columns for the y streaks).
        spec.threads = Some([SCAN_WIDTH * w.max(h), self.streaks, 1]);
        passes.push(spec);
        let glow = graph.create_texture("star_glow/glow", small);
        let reads = [(Binding::SrcLayers, streaks)];
        passes.push(self.spec("star_glow/screen", &k.streak_screen, &reads, (Binding::Dst, glow), 1.0));
        glow
    }

    /// Per level: every direction at once on layered textures; the last level accumulates.
    fn fused<'k>(
        &self,
        node: &'k StarGlow,
        graph: &mut FrameGraph<'_>,
        small: TextureDesc,
        bright: TextureHandle,
        passes: &mut Vec<PassSpec<'k>>,
    ) -> TextureHandle {
        let k = &node.kernels;
        let glow = graph.create_texture("star_glow/glow", small);
        if self.iteration == 1 {
            passes.push(self.spec(
                "star_glow/level1",
                &k.level_single,
                &[(Binding::TexA, bright)],
                (Binding::Dst, glow),
                1.0,
            ));
            return glow;
        }
        let layered = small.with_layers(self.streaks);
        let mut previous = bright;
        for n in 1..=self.iteration {
            let power = 4f32.powi(n as i32 - 1);
            let name = format!("star_glow/level{n}");
            let spec = if n == 1 {
                let out = graph.create_texture("star_glow/levels", layered);
                let mut s =
                    self.spec(&name, &k.level_first, &[(Binding::TexA, previous)], (Binding::DstLayers, out), power);
                s.layers = self.streaks;
                previous = out;
                s
            } else if n < self.iteration {
                let out = graph.create_texture("star_glow/levels", layered);
                let mut s = self.spec(
                    &name,
                    &k.level_next,
                    &[(Binding::SrcLayers, previous)],
                    (Binding::DstLayers, out),
                    power,
                );
                s.layers = self.streaks;
                previous = out;
                s
            } else {
                self.spec(&name, &k.level_last, &[(Binding::SrcLayers, previous)], (Binding::Dst, glow), power)
            };
            passes.push(spec);
        }
        glow
    }

    /// A pass spec with this plan's uniforms at level `power` (per-direction steps × power).
    fn spec<'k>(
        &self,
        name: &str,
        kernel: &'k Kernel,
        reads: &[(Binding, TextureHandle)],
        write: (Binding, TextureHandle),
        power: f32,
    ) -> PassSpec<'k> {
        let mut uniforms = StarGlowUniforms { power, ..self.base };
        for i in 0..self.streaks {
            let [x, y] = streak_step(i + 1, self.streaks, self.angle);
            let s = power * self.step_scale;
            uniforms.steps[i as usize] = [x * s, y * s, 0.0, 0.0];
        }
        PassSpec { name: name.into(), kernel, reads: reads.to_vec(), write, uniforms, layers: 1, threads: None }
    }

    /// Whether the scan gives what the cascade gives at this small size: every streak steps
    /// whole texels along an axis (angle a multiple of 90°, 1, 2 or 4 streaks, the step scale a
    /// whole number) and its 4^iteration taps reach past the end of every line it runs along.
    fn scan_applies(&self, (w, h): (u32, u32)) -> bool {
        let s = self.step_scale;
        if s < 1.0 || s.fract() != 0.0 || s > SCAN_MAX_STEP {
            return false;
        }
        let reach = 4f32.powi(self.iteration as i32) * s;
        (1..=self.streaks).all(|i| {
            let [x, y] = streak_step(i, self.streaks, self.angle);
            // f32 sines of multiples of 90° up to 720° miss by < 1e-6.
            let axis = |a: f32, b: f32| (a.abs() - 1.0).abs() < 1e-5 && b.abs() < 1e-5;
            let line = if axis(x, y) {
                w
            } else if axis(y, x) {
                h
            } else {
                return false;
            };
            reach >= line as f32 && line <= SCAN_MAX_LINE
        })
    }
}

/// Declares one compute pass of `spec` using uniform slot `slot`.
fn declare<'r>(graph: &mut FrameGraph<'r>, node: &'r StarGlow, slot: usize, spec: PassSpec<'r>) {
    let (w, h) = graph.texture_size(spec.write.1);
    let mut uniforms = spec.uniforms;
    uniforms.dst_size = [w, h];
    let mut pass = graph.add_pass(spec.name);
    for &(_, t) in &spec.reads {
        pass = pass.read(t);
    }
    let threads = spec.threads.unwrap_or([w, h, spec.layers]);
    let (kernel, reads, write) = (spec.kernel, spec.reads, spec.write);
    pass.write(write.1).record(move |ctx| {
        ctx.queue.write_buffer(&node.uniforms[slot], 0, bytemuck::bytes_of(&uniforms));
        let bind_group = node.bind_group(ctx, kernel, slot, &reads, write);
        let mut compute = ctx
            .encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("star_glow"), timestamp_writes: None });
        kernel.compute.dispatch(&mut compute, &[&bind_group], threads);
    });
}

impl StarGlow {
    /// The cached bind group for a pass slot and its resolved textures.
    fn bind_group(
        &self,
        ctx: &PassContext<'_>,
        kernel: &Kernel,
        slot: usize,
        reads: &[(Binding, TextureHandle)],
        write: (Binding, TextureHandle),
    ) -> wgpu::BindGroup {
        let mut ids = [kernel.id, 0, 0, 0];
        for (i, (_, t)) in reads.iter().chain([&write]).enumerate() {
            ids[i + 1] = ctx.texture_id(*t);
        }
        self.bind_groups
            .borrow_mut()
            .get_or_create((slot, ids), || {
                let mut entries = vec![
                    wgpu::BindGroupEntry { binding: 0, resource: self.uniforms[slot].as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&self.sampler) },
                ];
                for &(binding, t) in reads.iter().chain([&write]) {
                    entries.push(wgpu::BindGroupEntry {
                        binding: binding as u32,
                        resource: wgpu::BindingResource::TextureView(ctx.view(t)),
                    });
                }
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("star_glow_bind_group"),
                    layout: &kernel.layout,
                    entries: &entries,
                })
            })
            .clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ParamSet;

    /// A plan with the book's defaults (4 streaks at 0°, 5 iterations) and `step_scale`.
    fn book_plan(step_scale: f32) -> Plan {
        let mut plan = Plan::new(&Settings::read(&ParamSet::new(Settings::decls())));
        plan.step_scale = step_scale;
        plan
    }

    #[test]
    fn the_scan_takes_the_book_defaults_at_1080p_and_4k_only() {
        // Divide 3: 1080p's intermediates are 640×360 at step 1, 4K's 1280×720 at step 2; 1440p
        // steps 4/3 of a texel, so its taps fall between texels.
        assert!(book_plan(1.0).scan_applies((640, 360)));
        assert!(book_plan(2.0).scan_applies((1280, 720)));
        assert!(!book_plan(1440.0 / 1080.0).scan_applies((854, 480)));
        assert!(!book_plan(0.5).scan_applies((320, 180)));
    }

    #[test]
    fn the_scan_stops_at_the_shaders_limits() {
        // Lines up to SCAN_MAX_LINE texels: the shader holds that many in registers.
        assert!(book_plan(4.0).scan_applies((SCAN_MAX_LINE, 1440)));
        assert!(!book_plan(4.0).scan_applies((SCAN_MAX_LINE + 1, 1440)));
        assert!(!book_plan(4.0).scan_applies((2560, SCAN_MAX_LINE + 1)));
        // Steps up to SCAN_MAX_STEP texels.
        assert!(book_plan(SCAN_MAX_STEP).scan_applies((640, 360)));
        assert!(!book_plan(SCAN_MAX_STEP + 1.0).scan_applies((640, 360)));
        // The limits are the shader's own.
        let shader = include_str!("star_glow.wgsl");
        assert!(shader.contains(&format!("const SCAN_WIDTH: u32 = {SCAN_WIDTH}u;")));
        assert!(shader.contains(&format!("const SCAN_MAX_CHUNKS: u32 = {}u;", SCAN_MAX_LINE / SCAN_WIDTH)));
    }

    #[test]
    fn the_scan_needs_taps_past_the_line_and_streaks_on_the_axes() {
        // Two iterations at step 1 reach 16 texels: a line of 16 is covered, one of 17 is not.
        let mut plan = book_plan(1.0);
        plan.iteration = 2;
        assert!(plan.scan_applies((16, 16)));
        assert!(!plan.scan_applies((17, 16)));
        assert!(!plan.scan_applies((16, 17)));
        // Any multiple of 90° keeps the streaks on the axes; anything else does not.
        for (angle, on_axes) in [(90.0, true), (270.0, true), (360.0, true), (45.0, false), (0.01, false)] {
            let mut plan = book_plan(1.0);
            plan.angle = angle;
            assert_eq!(plan.scan_applies((640, 360)), on_axes, "angle {angle}");
        }
        // Six streaks are 60° apart: four of them are diagonal.
        let mut plan = book_plan(1.0);
        plan.streaks = 6;
        assert!(!plan.scan_applies((640, 360)));
    }
}
