use super::params::{MAX_BENDING_SHARE, bending_share};
use super::*;

#[test]
fn uniform_layouts_match_the_wgsl_structs() {
    let sim = include_str!("cloth.wgsl");
    assert_eq!(crate::gpu::wgsl_struct_size(sim, "ClothUniforms"), Some(size_of::<ClothUniforms>() as u32));
    let draw = include_str!("cloth_render.wgsl");
    assert_eq!(crate::gpu::wgsl_struct_size(draw, "ClothView"), Some(size_of::<render::ClothViewUniforms>() as u32));
}

#[test]
fn rest_pose_is_centred_with_the_top_row_pinned() {
    let pose = rest_pose(4, 0.5, 2.0, 0);
    assert_eq!(pose[0], [-0.75, 0.75, 0.0, 0.0]);
    assert_eq!(pose[15], [0.75, -0.75, 0.0, 0.5]);
    let corners = rest_pose(4, 0.5, 1.0, 1);
    let pinned: Vec<usize> = (0..16).filter(|&i| corners[i][3] == 0.0).collect();
    assert_eq!(pinned, [0, 3]);
    assert!(rest_pose(4, 0.5, 1.0, 2).iter().all(|p| p[3] == 1.0));
}

#[test]
fn the_bending_share_grows_with_stiffness_up_to_its_cap() {
    let share = |b| bending_share(b, 0.001, 0.005, 1.0 / 960.0);
    assert_eq!(share(0.0), 0.0);
    // 1024² sheet, 16 substeps at 60 steps/s: m h² / (4 B dt²) = 0.0230 / (4 B).
    assert!((share(0.001) - 1.0 / (1.0 + 0.0230 / 0.004)).abs() < 1e-3, "{}", share(0.001));
    assert!(share(1e-4) < share(1e-3));
    assert_eq!(share(0.01), MAX_BENDING_SHARE);
}
