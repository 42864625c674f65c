//! StarGlow: Kawase's streak post effect — bright pass, directional 4-tap cascades, screen
//! accumulation and a final composite — as a node that takes any HDR texture and can end any
//! scene.
//!
//! Three pass layouts give one image: the book's (a pass per level per direction), the fused
//! (a pass per level for every direction), and, where the streaks step whole texels along the
//! axes and reach past the image, a scan: the cascade's weights multiply out to att^k for the
//! k-th texel along a streak, so one exponential suffix sum per line replaces the levels.
//!
//! Book: [UGP4 ch.4] "StarGlow" (xjine); [Kawase 2003] "Frame Buffer Postprocessing Effects in
//! DOUBLE-S.T.E.A.L", GDC. Shader: `star_glow.wgsl`. Goldens: `golden/`, made by `render_tests.rs`.
//!
//! Differences from the sample (seed-reference §9 item 17), on purpose: the accumulation target
//! starts black every frame; nothing is clamped to 1 (HDR stays HDR until the display encode);
//! the threshold leaves alpha alone; the bright pass max-pools its whole footprint instead of
//! taking one bilinear sample, so a one-pixel glint neither vanishes nor flickers as it moves;
//! and by default streaks keep their length relative to the image at any output size (the
//! sample's grow with resolution), matching the book exactly at 1080p.

mod passes;

use std::cell::RefCell;

use crate::gpu::{BindGroupCache, ComputeKernel, ShaderError};
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{ParamDecl, ParamSet, ParamValue};
use crate::time::FrameTime;

use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "star_glow",
    chapter: "4: StarGlow",
    summary: "Kawase streak glow on any HDR input: book layout, fused, or one scan per line",
    params: Settings::decls,
    inputs: &["source"],
    shaders: &["star_glow.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

/// Intermediate and output format.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Output height at which resolution-independent streaks take the book's texel steps.
pub const REFERENCE_HEIGHT: f32 = 1080.0;

/// Most passes one frame declares: bright, 16 directions × (5 levels + accumulate), composite.
pub const MAX_PASSES: usize = 2 + 16 * (5 + 1);

crate::param_enum! {
    /// How the glow joins the source (the shader's composite type, by index).
    pub enum Composite {
        /// source + glow
        Additive = "Additive",
        /// 1 − (1 − source)(1 − glow)
        Screen = "Screen",
        /// source + glow × colour
        ColoredAdditive = "ColoredAdditive",
        /// screen with the glow tinted
        ColoredScreen = "ColoredScreen",
        /// the glow alone
        Debug = "Debug",
    }
}

crate::param_enum! {
    /// The `layout` parameter: which pass layout to use.
    pub enum LayoutChoice {
        /// What `indra tune` measured fastest on this adapter; where it measured nothing, the
        /// scan where the streaks step whole texels along the axes and reach past the image (the
        /// book's defaults at 1080p and 4K), else Fused: the same image, the fewest passes.
        Auto = "Auto",
        /// The book's pass layout.
        Book = "Book",
        /// One pass per level for every direction.
        Fused = "Fused",
    }
}

crate::technique_params! {
    /// What a StarGlow node reads each frame, with the sample's C# defaults and ranges
    /// (seed-reference §4).
    pub struct Settings {
        /// brightness subtracted before streaking (HDR: may exceed 1)
        threshold: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.0, 10.0)), doc),
        /// gain of the bright pass; 0 switches the effect off
        intensity: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.0, 10.0)), doc),
        /// downsampling factor of the streak textures
        divide: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(3), Some((1.0, 20.0)), doc),
        /// cascade levels; a streak reaches 4^iteration texels
        iteration: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(5), Some((1.0, 5.0)), doc),
        /// weight falloff per texel along a streak
        attenuation: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.0, 1.0)), doc),
        /// rotation of the first streak
        angle: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((0.0, 360.0)), doc).with_unit("°"),
        /// number of streak directions
        streaks: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(4), Some((1.0, 16.0)), doc),
        /// how the glow joins the source
        composite: Composite = |n, doc| ParamDecl::choice(n, Composite::OPTIONS, 0, doc),
        /// tint of the coloured composite types
        color: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([1.0, 1.0, 1.0, 1.0]), None, doc),
        /// pass layout; Auto is the scan where it applies, else Fused (same output, fewer passes)
        layout: LayoutChoice = |n, doc| ParamDecl::choice(n, LayoutChoice::OPTIONS, 0, doc),
        /// streak length relative to the image (as the book at 1080p) instead of in texels
        resolution_independent: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(true), None, doc),
    }
}

/// The shader's uniform block; layout checked against naga's reflection in the tests.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct StarGlowUniforms {
    /// Size of the texture the pass writes.
    pub dst_size: [u32; 2],
    /// Bright pass threshold.
    pub threshold: f32,
    /// Bright pass gain.
    pub intensity: f32,
    /// Streak pass: tap step in texels (y down) × power.
    pub offset: [f32; 2],
    /// Tap weight base.
    pub attenuation: f32,
    /// Streak level power 4^(n−1).
    pub power: f32,
    /// Composite type index.
    pub composite_type: u32,
    /// Fused: number of directions.
    pub directions: u32,
    /// Accumulate: 1 for the first direction (start from black).
    pub first: u32,
    /// Bright pass: source texels per output texel.
    pub divide: u32,
    /// Linear tint.
    pub color: [f32; 4],
    /// Fused: tap step per direction × power (xy used).
    pub steps: [[f32; 4]; 16],
}

/// The unit tap step of streak `i` (1-based, as the sample counts) in texture space (y down):
/// (0, −1) rotated counter-clockwise by 360°/n·i + angle in the book's y-up uv space.
pub fn streak_step(i: u32, n: u32, angle_deg: f32) -> [f32; 2] {
    let theta = (360.0 / n as f32 * i as f32 + angle_deg).to_radians();
    [theta.sin(), theta.cos()]
}

/// Which pass layout a frame uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// The book's: one pass per streak level per direction plus one accumulation per direction,
    /// 2 + N (iteration + 1) passes.
    Book,
    /// One pass per level for every direction at once (layered textures), the accumulation
    /// folded into the last level: iteration + 2 passes, the same arithmetic.
    Fused,
    /// Axis-aligned whole-texel streaks that reach past the image: the levels' product of
    /// weights as one suffix scan per line and direction, then the accumulation: 4 passes.
    Scan,
}

impl Layout {
    /// The layout the `layout` parameter asks for before the frame's size is known (`Auto` is
    /// `Fused`; the plan takes the scan for it where the size allows).
    pub fn choose(p: &ParamSet) -> Self {
        Self::of(Settings::read(p).layout)
    }

    /// The layout `choice` stands for where the scan does not apply.
    pub fn of(choice: LayoutChoice) -> Self {
        match choice {
            LayoutChoice::Book => Layout::Book,
            LayoutChoice::Auto | LayoutChoice::Fused => Layout::Fused,
        }
    }
}

/// A StarGlow node.
pub struct StarGlow {
    kernels: Kernels,
    sampler: wgpu::Sampler,
    /// One uniform buffer per pass slot of a frame (the most a frame can declare), reused.
    uniforms: Vec<wgpu::Buffer>,
    /// Bind groups by (slot, kernel id, texture ids): steady-state frames create none.
    bind_groups: RefCell<BindGroupCache<(usize, [u64; 4])>>,
    /// What `layout: Auto` takes on this adapter (`Auto` itself: the scan where it applies).
    tuned: LayoutChoice,
}

/// A pipeline and the layout of its one bind group.
struct Kernel {
    compute: ComputeKernel,
    layout: wgpu::BindGroupLayout,
    /// Identifies the kernel in bind-group keys (a slot changes kernels when the layout flips).
    id: u64,
}

struct Kernels {
    bright: Kernel,
    streak: Kernel,
    accumulate: Kernel,
    composite: Kernel,
    level_single: Kernel,
    level_first: Kernel,
    level_next: Kernel,
    level_last: Kernel,
    streak_scan: Kernel,
    streak_screen: Kernel,
}

/// The texture bindings of `star_glow.wgsl` besides the uniform (0) and sampler (1).
#[derive(Clone, Copy)]
enum Binding {
    TexA = 2,
    TexB = 3,
    Dst = 4,
    SrcLayers = 5,
    DstLayers = 6,
}

impl Binding {
    fn entry(self) -> wgpu::BindGroupLayoutEntry {
        let sampled = |view_dimension| wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension,
            multisampled: false,
        };
        let storage = |view_dimension| wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format: FORMAT,
            view_dimension,
        };
        let ty = match self {
            Binding::TexA | Binding::TexB => sampled(wgpu::TextureViewDimension::D2),
            Binding::SrcLayers => sampled(wgpu::TextureViewDimension::D2Array),
            Binding::Dst => storage(wgpu::TextureViewDimension::D2),
            Binding::DstLayers => storage(wgpu::TextureViewDimension::D2Array),
        };
        wgpu::BindGroupLayoutEntry { binding: self as u32, visibility: wgpu::ShaderStages::COMPUTE, ty, count: None }
    }
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    let device = &setup.gpu.device;
    use Binding::*;
    let names = [("tex_a", TexA), ("tex_b", TexB), ("dst", Dst), ("src_layers", SrcLayers), ("dst_layers", DstLayers)];
    let bindings: Vec<(&str, u32)> =
        [("u", 0), ("linear_clamp", 1)].into_iter().chain(names.map(|(n, b)| (n, b as u32))).collect();
    let (origin, source) = setup.shader_source("star_glow.wgsl", &bindings)?;
    let kernel = |entry: &str, bindings: &[Binding]| -> Result<Kernel, ShaderError> {
        let mut entries = vec![
            crate::gpu::uniform_entry::<StarGlowUniforms>(0, wgpu::ShaderStages::COMPUTE),
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ];
        entries.extend(bindings.iter().map(|b| b.entry()));
        let label = format!("star_glow_{entry}_layout");
        let layout = device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(&label), entries: &entries });
        let compute = ComputeKernel::new(device, &origin, &source, entry, &[&layout])?;
        Ok(Kernel { compute, layout, id: crate::graph::next_resource_id() })
    };
    let kernels = Kernels {
        bright: kernel("bright", &[TexA, Dst])?,
        streak: kernel("streak", &[TexA, Dst])?,
        accumulate: kernel("accumulate", &[TexA, TexB, Dst])?,
        composite: kernel("composite", &[TexA, TexB, Dst])?,
        level_single: kernel("level_single", &[TexA, Dst])?,
        level_first: kernel("level_first", &[TexA, DstLayers])?,
        level_next: kernel("level_next", &[SrcLayers, DstLayers])?,
        level_last: kernel("level_last", &[SrcLayers, Dst])?,
        streak_scan: kernel("streak_scan", &[TexA, DstLayers])?,
        streak_screen: kernel("streak_screen", &[SrcLayers, Dst])?,
    };
    // Clamp to edge, as Unity's render textures: streaks smear the border texel, never wrap.
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("star_glow_sampler"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    let uniforms =
        (0..MAX_PASSES).map(|_| crate::gpu::uniform_buffer::<StarGlowUniforms>(device, "star_glow_uniforms")).collect();
    let tuned = setup.tuned(INFO.name, "layout").unwrap_or(LayoutChoice::Auto);
    Ok(Box::new(StarGlow { kernels, sampler, uniforms, bind_groups: RefCell::default(), tuned }))
}

impl Technique for StarGlow {
    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        _time: &FrameTime,
        inputs: &[TextureHandle],
    ) -> TextureHandle {
        let source = inputs[0];
        let mut settings = Settings::read(params);
        if settings.layout == LayoutChoice::Auto {
            settings.layout = self.tuned;
        }
        // A zero-effect setting adds no passes: the source goes straight through.
        if settings.intensity <= 0.0 {
            return source;
        }
        let plan = passes::Plan::new(&settings);
        self.bind_groups.get_mut().begin_frame();
        let this: &'r StarGlow = self;
        plan.declare(this, graph, source)
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod render_tests;
