//! The image node as a picture (linear, premultiplied, fitted) and as data (values as stored).

#[test]
fn a_still_is_a_fitted_linear_picture_or_its_stored_values() {
    let dir = crate::common::clips::clip_dir();
    let path = dir.join("half_grey.png");
    // sRGB 128 grey, 8 × 4: half the height of a square output when contained.
    image::RgbaImage::from_pixel(8, 4, image::Rgba([128, 128, 128, 255])).save(&path).unwrap();
    let scene = |values: &str| {
        format!(
            r#"(name: "still", size: (16, 16), seed: 1, dt: 0.04,
                nodes: [(id: "still", technique: "image", params: {{ "path": "{}", "values": "{values}" }})],
                output: "still")"#,
            path.display()
        )
    };
    let assets = crate::common::assets().allowing(&dir);
    let render = |ron: &str| {
        let scene = indra::scene::parse_scene("still.ron", ron).unwrap();
        let mut r =
            indra::offscreen::OffscreenRenderer::new(crate::common::gpu(), &assets, scene, None, None, None).unwrap();
        r.render_next().unwrap()
    };
    let picture = render(&scene("picture"));
    let at = |x: u32, y: u32| picture.rgba[((y * 16 + x) * 4) as usize];
    // Contained: grey (sRGB 128 in, linear inside, sRGB 128 out) in rows 4–11, black bars.
    assert!(at(8, 8).abs_diff(128) <= 1, "grey comes back as it went in: {}", at(8, 8));
    assert_eq!((at(8, 1), at(8, 14)), (0, 0), "bars above and below");
    // As data the stored 0.502 is the value itself (a height), shown as linear 0.5: sRGB ≈ 188,
    // and it fills the output (its own size, stretched by the display).
    let data = render(&scene("data"));
    let value = data.rgba[((16 + 8) * 4) as usize]; // row 1, column 8
    assert!(value.abs_diff(188) <= 2, "data is not colour-converted: {value}");

    // OpenEXR is linear already: 0.25 stays 0.25 (sRGB ≈ 137), not decoded again as sRGB (≈ 64).
    let exr = dir.join("quarter.exr");
    image::DynamicImage::ImageRgba32F(image::Rgba32FImage::from_pixel(8, 4, image::Rgba([0.25, 0.25, 0.25, 1.0])))
        .save(&exr)
        .unwrap();
    let ron = scene("picture").replace(path.to_str().unwrap(), exr.to_str().unwrap());
    let picture = render(&ron);
    let centre = picture.rgba[((8 * 16 + 8) * 4) as usize];
    assert!(centre.abs_diff(137) <= 2, "EXR values are linear: {centre}");
}
