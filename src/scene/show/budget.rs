//! The show's texture budget check, worded for a performer: which clips take what.

use crate::scene::model::{MAX_TEXTURE_BYTES, Scene};

/// Whether the show's textures fit the scene budget at `size`; if not, one sentence on which
/// clips take what.
pub(super) fn budget(scene: &Scene, size: (u32, u32)) -> Result<(), String> {
    scene.check_texture_budget(size).map_err(|_| {
        let per_node = scene.texture_bytes_of(1, size);
        let gib = |b: u64| b as f64 / f64::from(1u32 << 30);
        let show = scene.show.as_deref().expect("a show");
        let clips: Vec<String> =
            show.clips.iter().map(|c| format!("{} {:.1} GiB", c.id, gib(per_node * c.nodes.len() as u64))).collect();
        format!(
            "the show needs about {:.1} GiB of textures at {}x{} with msaa {} (what can be on screen at once), over the {:.0} GiB a show may use: {} (lower the size or the msaa, or move clips to another show)",
            gib(scene.texture_bytes(size)),
            size.0,
            size.1,
            scene.msaa,
            gib(MAX_TEXTURE_BYTES),
            clips.join(", ")
        )
    })
}
