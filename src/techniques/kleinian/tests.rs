use super::*;

#[test]
fn uniform_layout_matches_the_wgsl_struct() {
    let source = include_str!("kleinian.wgsl");
    assert_eq!(crate::gpu::wgsl_struct_size(source, "KleinianUniforms"), Some(size_of::<KleinianUniforms>() as u32));
}

#[test]
fn uniforms_convert_colours_to_linear_and_flags() {
    let mut p = ParamSet::new(Settings::decls());
    p.set_at(p.index("hit_color").unwrap(), ParamValue::Color([1.0, 0.5, 0.0, 1.0]));
    p.set_at(p.index("circle_inversion").unwrap(), ParamValue::Bool(true));
    let time = FrameTime { frame: 0, seconds: 0.0, dt: 0.1, seed: 9 };
    let u = KleinianUniforms::from_params(&p, &time, (64, 32));
    assert!((u.hit_color[1] - 0.21404).abs() < 1e-4, "{:?}", u.hit_color);
    assert_eq!((u.inversion, u.seed, u.size, u.iterations), (1, 9, [64, 32], 500));
}
