//! Helpers shared by the integration tests: a lavapipe-friendly device, scene rendering, and
//! pixel classification.
#![allow(dead_code)]

pub mod clips;
// FLIP goldens need the `golden` feature (on by default); the CLI tests also run without it,
// against the render-node build.
#[cfg(feature = "golden")]
mod golden;
#[cfg(feature = "golden")]
#[allow(unused_imports)] // each test binary uses some of them
pub use golden::{golden, golden_beside, golden_in};

use indra::assets::Assets;
use indra::gpu::{BackendChoice, Gpu, GpuOptions};
use indra::offscreen::{OffscreenRenderer, RenderedFrame};
use indra::scene::{Scene, load_scene, parse_scene};

/// A headless device. Vulkan (lavapipe on CI) so that goldens are made by one backend.
pub fn gpu() -> Gpu {
    Gpu::headless(&GpuOptions { backend: BackendChoice::Vulkan, ..GpuOptions::default() })
        .expect("a Vulkan adapter (on a machine without a GPU: apt-get install mesa-vulkan-drivers libvulkan1)")
}

/// The project's assets (scenes/ and shaders/ of this checkout).
pub fn assets() -> Assets {
    Assets::new(Some(env!("CARGO_MANIFEST_DIR").into()))
}

/// Renders frame `frame` of `scene` at `size`.
pub fn render_scene(scene: Scene, size: (u32, u32), frame: u64) -> RenderedFrame {
    render_frames(scene, size, &[frame]).pop().expect("one frame")
}

/// Renders `frames` (ascending) of `scene` at `size` in one run, seeking between them: the frames
/// between are stepped, not drawn (the same bytes as playing them, which the seek tests check).
pub fn render_frames(scene: Scene, size: (u32, u32), frames: &[u64]) -> Vec<RenderedFrame> {
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene, Some(size), None, None).expect("scene builds");
    frames
        .iter()
        .map(|&frame| {
            r.seek(frame).expect("seek reaches the frame");
            r.render_next().expect("frame renders")
        })
        .collect()
}

/// Renders a bundled scene by name.
pub fn render_named(name: &str, size: (u32, u32), frame: u64) -> RenderedFrame {
    render_scene(load_scene(&assets(), name).expect("scene is valid"), size, frame)
}

/// Renders a scene given as RON text.
pub fn render_text(ron: &str, size: (u32, u32)) -> RenderedFrame {
    render_scene(parse_scene("inline.ron", ron).unwrap_or_else(|e| panic!("{e}")), size, 0)
}

/// Whether pixel (x, y) is bright (mean of RGB above half).
pub fn bright(frame: &RenderedFrame, x: u32, y: u32) -> bool {
    let i = ((y * frame.size.0 + x) * 4) as usize;
    let p = &frame.rgba[i..i + 3];
    (u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2])) > 3 * 128
}

/// A private copy of the project's scenes/ and shaders/ (in the temporary folder, named after
/// `name` and this process) for a test to edit; the techniques' own shaders are copied into its
/// shaders/ too, as a performer's overrides of them would be.
pub fn sandbox(name: &str) -> std::path::PathBuf {
    let root = std::env::temp_dir().join(format!("indra-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let project = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let techniques = std::fs::read_dir(project.join("src/techniques")).unwrap().map(|e| e.unwrap().path());
    let copies = [(project.join("scenes"), "scenes"), (project.join("shaders"), "shaders")]
        .into_iter()
        .chain(techniques.filter(|p| p.is_dir()).map(|p| (p, "shaders")));
    for (from, to) in copies {
        std::fs::create_dir_all(root.join(to)).unwrap();
        for entry in std::fs::read_dir(&from).unwrap() {
            let path = entry.unwrap().path();
            let wanted = to == "scenes" || path.extension().is_some_and(|e| e == "wgsl");
            if path.is_file() && wanted {
                std::fs::copy(&path, root.join(to).join(path.file_name().unwrap())).unwrap();
            }
        }
    }
    root
}

/// A `Rgba16Float` texture of `size` holding `texels` (linear RGBA, row by row from the top), as
/// an upstream node's output would be.
pub fn float_texture(gpu: &Gpu, size: (u32, u32), texels: &[[f32; 4]]) -> indra::graph::PersistentTexture {
    let texture =
        indra::graph::PersistentTexture::new(&gpu.device, "test_source", size, wgpu::TextureFormat::Rgba16Float);
    let bytes: Vec<u8> = texels.iter().flatten().flat_map(|&x| half::f16::from_f32(x).to_le_bytes()).collect();
    gpu.queue.write_texture(
        texture.texture.as_image_copy(),
        &bytes,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(size.0 * 8), rows_per_image: Some(size.1) },
        texture.texture.size(),
    );
    texture
}

/// Reads a `Rgba16Float` texture back as linear RGBA texels.
pub fn read_float_texture(gpu: &Gpu, texture: &wgpu::Texture) -> Vec<[f32; 4]> {
    indra::gpu::read_texture_bytes(&gpu.device, &gpu.queue, texture)
        .unwrap()
        .chunks_exact(8)
        .map(|t| std::array::from_fn(|c| half::f16::from_le_bytes([t[2 * c], t[2 * c + 1]]).to_f32()))
        .collect()
}

/// Runs the `indra` binary with `args` on Vulkan, against this checkout's scenes and shaders.
/// (Cargo names the binary to integration tests only, not to the crate's own tests.)
pub fn indra(args: &[&str]) -> std::process::Output {
    let Some(binary) = option_env!("CARGO_BIN_EXE_indra") else {
        panic!("the binary is built for integration tests only");
    };
    std::process::Command::new(binary)
        .args(args)
        .args(["--backend", "vulkan"])
        .env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

/// What a run printed, stdout then stderr.
pub fn text(o: &std::process::Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}
