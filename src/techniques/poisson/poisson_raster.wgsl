// Chapter 7's discs and spheres drawn in compute (the steps shared in `shaders/splat_draw.wgsl`).
// A sample's quad faces the camera, so on screen it is an axis-aligned box with one depth, and
// its disc an ellipse found per sample position without any mesh. A sample keeps the nearest
// disc by (inverted depth bits, inverted index): the pipeline's depth test (less, the first
// drawn winning a tie, as overlapping 2-D discs all lie at one depth). A disc is shaded at the
// pixel centre by the fragment shader's own `disc_colour`.
// extends: poisson.wgsl
// extends: splat_draw.wgsl

@group(1) @binding(1) var<storage, read> discs: array<vec4<f32>>;

// A disc on screen: centre and signed radii in pixels (y down), depth, and whether the
// pipeline would draw it at all (in front of the camera, between the depth planes).
struct Footprint {
    centre: vec2<f32>,
    radius: vec2<f32>,
    depth: f32,
    drawn: bool,
};

fn to_pixels(clip: vec4<f32>) -> vec2<f32> {
    let ndc = clip.xy / clip.w;
    return vec2<f32>((ndc.x + 1.0) * 0.5 * f32(splat.width), (1.0 - ndc.y) * 0.5 * f32(splat.height));
}

fn footprint(disc: vec4<f32>) -> Footprint {
    let centre = u.view_proj * vec4<f32>(disc.xyz, 1.0);
    let right = u.view_proj * vec4<f32>(disc.xyz + u.right.xyz * u.draw_radius, 1.0);
    let up = u.view_proj * vec4<f32>(disc.xyz + u.up.xyz * u.draw_radius, 1.0);
    let c = to_pixels(centre);
    let depth = centre.z / centre.w;
    let drawn = centre.w > 0.0 && depth >= 0.0 && depth < 1.0;
    return Footprint(c, vec2<f32>(to_pixels(right).x - c.x, c.y - to_pixels(up).y), depth, drawn);
}

// The quad coordinates ([-1, 1] at the rim, y up) of pixel position p.
fn corner_at(f: Footprint, p: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(p.x - f.centre.x, f.centre.y - p.y) / f.radius;
}

// The pixels with a sample the disc may cover.
fn splat_box(f: Footprint) -> PixelBox {
    if !f.drawn {
        return PixelBox(vec2<i32>(0), vec2<i32>(0));
    }
    return pixels_around(f.centre - abs(f.radius), f.centre + abs(f.radius));
}

// Covers pixels first, first + step, … below `end` of the disc's box `b`.
fn cover(f: Footprint, b: PixelBox, index: u32, first: i32, step: i32, end: i32) {
    let depth_key = ~bitcast<u32>(f.depth);
    for (var k = first; k < min(end, b.size.x * b.size.y); k += step) {
        let pixel = box_pixel(b.lo, b.size.x, k);
        for (var s = 0u; s < splat.samples; s++) {
            let c = corner_at(f, sample_position(pixel, s));
            if dot(c, c) <= 1.0 {
                keep(pixel, s, depth_key, ~index);
            }
        }
    }
}

// The hooks of `splat_draw.wgsl`'s entry points (and `splat_box`, `cover` above).

fn splat_primitive(index: u32) -> Footprint {
    return footprint(discs[index]);
}

// The disc a sample key names, shaded at a pixel centre.
fn splat_shade(key: u32, centre: vec2<f32>) -> vec3<f32> {
    let disc = discs[~key];
    return disc_colour(corner_at(footprint(disc), centre), order_of(disc.w));
}
