use super::*;

#[test]
fn uniform_layout_matches_the_wgsl_struct() {
    let source = include_str!("star_glow.wgsl");
    assert_eq!(crate::gpu::wgsl_struct_size(source, "StarGlowUniforms"), Some(size_of::<StarGlowUniforms>() as u32));
}

#[test]
fn streak_directions_follow_the_sample() {
    // One streak at angle 0: (0, -1) in y-up uv turned by 360° → (0, +1) in y-down texels.
    let [x, y] = streak_step(1, 1, 0.0);
    assert!(x.abs() < 1e-6 && (y - 1.0).abs() < 1e-6, "{x} {y}");
    // Four streaks: 90° apart; the first at 90° points to +x.
    let [x, y] = streak_step(1, 4, 0.0);
    assert!((x - 1.0).abs() < 1e-6 && y.abs() < 1e-6, "{x} {y}");
}

#[test]
fn auto_layout_is_fused_and_book_is_selectable() {
    let mut p = ParamSet::new(Settings::decls());
    assert_eq!(Layout::choose(&p), Layout::Fused);
    p.set_at(p.index("layout").unwrap(), ParamValue::Enum(1));
    assert_eq!(Layout::choose(&p), Layout::Book);
}
