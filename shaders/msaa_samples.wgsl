// Where a multisampled pixel's samples lie: the standard sample locations of Vulkan (and
// D3D) for 1, 2, 4 and 8 samples, which lavapipe and NVIDIA both use. Shared by the shaders that
// work out coverage themselves: the tessellation's compute draw (tessellation_raster.wgsl, through
// tessellation.wgsl) and the Poisson discs, whose rims are cut in the fragment shader.

// Sample s of `count` in sixteenths of a pixel from its centre (Vulkan's standard locations). A
// switch, not an indexed array: the SPIR-V backend would copy an array to per-invocation memory.
fn sample_offset(count: u32, s: u32) -> vec2<i32> {
    switch count * 8u + s {
        case 16u: { return vec2<i32>(4, 4); }
        case 17u: { return vec2<i32>(-4, -4); }
        case 32u: { return vec2<i32>(-2, -6); }
        case 33u: { return vec2<i32>(6, -2); }
        case 34u: { return vec2<i32>(-6, 2); }
        case 35u: { return vec2<i32>(2, 6); }
        case 64u: { return vec2<i32>(1, -3); }
        case 65u: { return vec2<i32>(-1, 3); }
        case 66u: { return vec2<i32>(5, 1); }
        case 67u: { return vec2<i32>(-3, -5); }
        case 68u: { return vec2<i32>(-5, 5); }
        case 69u: { return vec2<i32>(-7, -1); }
        case 70u: { return vec2<i32>(3, 7); }
        case 71u: { return vec2<i32>(7, -7); }
        default: { return vec2<i32>(0, 0); }
    }
}
