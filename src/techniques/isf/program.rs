//! What translating an ISF shader gives: the GLSL of each stage, the textures it samples and
//! where each comes from, its uniform block's layout, and the bindings a pipeline gives them.

/// The binding of the uniform block.
pub const UNIFORM_BINDING: u32 = 0;
/// The binding of the one sampler.
pub const SAMPLER_BINDING: u32 = 1;
/// The binding of the first texture; the others follow in [`Program::textures`] order.
pub const FIRST_TEXTURE_BINDING: u32 = 2;

/// Where a texture the shader samples comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSource {
    /// An `image` input, wired from another node (linear, encoded when sampled).
    Node,
    /// A pass `TARGET` of this shader.
    Target,
    /// An `IMPORTED` image file.
    Imported,
    /// An `audio` (waveform) input.
    Audio,
    /// An `audioFFT` (spectrum) input.
    AudioFft,
}

/// One texture the shader samples: its name in the ISF file and where it comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextureSlot {
    /// The name the shader uses.
    pub name: String,
    /// Where its texels come from.
    pub source: TextureSource,
}

/// The type of one uniform block member.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    /// `int`.
    Int,
    /// `float`.
    Float,
    /// `vec2`.
    Vec2,
    /// `vec4`.
    Vec4,
}

impl Scalar {
    pub(super) fn glsl(self) -> &'static str {
        match self {
            Scalar::Int => "int",
            Scalar::Float => "float",
            Scalar::Vec2 => "vec2",
            Scalar::Vec4 => "vec4",
        }
    }

    /// (size, alignment) in std140.
    pub(super) fn layout(self) -> (u32, u32) {
        match self {
            Scalar::Int | Scalar::Float => (4, 4),
            Scalar::Vec2 => (8, 8),
            Scalar::Vec4 => (16, 16),
        }
    }
}

/// The uniform block: members with their std140 offsets.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UniformLayout {
    /// (GLSL name, type, byte offset).
    pub members: Vec<(String, Scalar, u32)>,
    /// The block's size in bytes (a multiple of 16).
    pub size: u32,
}

impl UniformLayout {
    pub(super) fn push(&mut self, name: &str, ty: Scalar) {
        let (size, align) = ty.layout();
        let offset = self.size.next_multiple_of(align);
        self.members.push((name.to_string(), ty, offset));
        self.size = offset + size;
    }

    pub(super) fn finish(&mut self) {
        self.size = self.size.next_multiple_of(16).max(16);
    }

    /// The byte offset of member `name`.
    pub fn offset(&self, name: &str) -> Option<u32> {
        self.members.iter().find(|(n, _, _)| n == name).map(|m| m.2)
    }

    pub(super) fn declaration(&self) -> String {
        let members: String = self.members.iter().map(|(n, ty, _)| format!(" {} {n};", ty.glsl())).collect();
        format!("layout(std140, set = 0, binding = {UNIFORM_BINDING}) uniform IsfUniforms {{{members} }};")
    }
}

/// An ISF shader made ready for naga: both stages' GLSL and what the host binds.
#[derive(Clone, Debug)]
pub struct Program {
    /// The fragment stage.
    pub fragment: Stage,
    /// The vertex stage (the `.vs` companion, or the default that only places the quad).
    pub vertex: Stage,
    /// The uniform block.
    pub uniforms: UniformLayout,
    /// The textures, bound from [`FIRST_TEXTURE_BINDING`] on, in this order.
    pub textures: Vec<TextureSlot>,
    /// The same fragment shader as a compute shader writing a storage image (one per target
    /// format: `rgba8`, `rgba16f`), where it needs nothing only rasterising gives — no `.vs`
    /// (varyings without one are plain globals), no derivatives or `discard`. GPUs built for compute (the H200) rasterise at a
    /// fraction of their memory bandwidth; this runs at full speed on all.
    pub compute: Option<[Stage; 2]>,
    /// Whether a rasterised pass draws every pixel of its target: the vertex stage leaves the
    /// quad where `isf_vertShaderInit` puts it (it never writes `gl_Position` itself) and the
    /// fragment stage never discards, so the target needs no clear first.
    pub covers_target: bool,
}

/// The binding of the storage image a compute variant writes: after the textures.
pub fn storage_binding(textures: usize) -> u32 {
    FIRST_TEXTURE_BINDING + textures as u32
}

/// The storage formats of [`Program::compute`], in order.
pub const COMPUTE_FORMATS: [&str; 2] = ["rgba8", "rgba16f"];

/// One stage's translated text.
#[derive(Clone, Debug)]
pub struct Stage {
    /// The GLSL naga parses.
    pub glsl: String,
    /// Lines of ours before the file's first line: translated line `n` is the file's `n − prelude`.
    pub prelude_lines: u32,
}

/// A translation error: the stage (`"fs"` or `"vs"`), the 1-based line, and what is wrong.
pub type TranslateError = (&'static str, u32, String);
