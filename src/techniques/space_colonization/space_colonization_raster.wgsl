// Chapter 1's tubes drawn in compute, for GPUs whose raster path is narrow (the H100/H200: a
// million eight-sided tubes are 64 million triangles, 79 ms at 1080p through it). Each edge is an
// exact capsule — the segment from its parent to its growing tip, swept by the tube's radius —
// found by a ray per sample instead of a mesh: at the sizes the forest is seen (a branch a pixel
// or two across) the eight-sided mesh was its own level of detail, paying 64 triangles for a few
// pixels.
// extends: space_colonization_draw.wgsl
//   raster   one thread per edge: the capsule's box on screen, then for each sample of each
//            pixel in it (the standard sample locations) the ray from the camera; a hit keeps the
//            nearest edge with one 64-bit atomicMax of (inverted distance, edge + 1) — the same
//            result in any order, so renders are deterministic. Only the pixels inside the
//            capsule's outline on screen are walked, and a pixel whose centre ray passes the
//            capsule by more than a pixel is skipped. Edges whose box exceeds 4×4 px go to a
//            queue instead (one thread would walk it alone while its warp waits).
//   raster_medium  one thread per queued edge of up to 128 px (where edges are many enough to
//                  fill the GPU one thread each): warps of like sizes.
//   raster_large   32 lanes per queued edge of up to 1,024 px (where edges are many).
//   raster_huge    one 8×8 workgroup per larger queued edge, walking its outline.
//   floor_fill  (with the skinned scene's floor, in place of clearing the buffer) one thread per
//               pixel: each sample's ray meets the floor square or not; the edges then win where
//               nearer, as the pipeline draws the floor first and the tubes depth-tested over it.
//   glow     (with the model's glow) a workgroup per mesh triangle and chunk: the posed triangle's
//            box, a ray per sample; a sample nearer than the opaque hit in the buffer adds the
//            face's rim weight to the pixel's 32-bit sum — integers, so the sum is the same in any
//            order, as the pipeline's additive blend without depth writes is.
//   resolve  one thread per pixel: each distinct edge (or the floor) among its samples is shaded
//            once at the pixel centre (as multisampling shades once per pixel and primitive) and
//            weighted by the samples it holds; empty samples are the background; the glow adds.
// Hits nearer than the camera's near plane are dropped, as the pipeline clips them.

struct Raster {
    // The ray through pixel position p (y down) is ray_origin + ray_x p.x + ray_y p.y (a
    // perspective camera's rays are affine in the pixel position), not normalised; ray_origin.w:
    // the widest angle a pixel spans (at the image's centre).
    ray_origin: vec4<f32>,
    ray_x: vec4<f32>,
    ray_y: vec4<f32>,
    // The view axis (unit).
    forward: vec4<f32>,
    background: vec4<f32>,
    width: u32,
    height: u32,
    samples: u32,
    // Edge slots: threads past the grown count return at once.
    capacity: u32,
    // Boxes of more pixels go to the large edges' queue (32 lanes each).
    large_pixels: i32,
    // 1: the floor is drawn (floor_fill fills the buffer).
    floor: u32,
    // 1: the model's glow is drawn (glow_in holds its sums).
    glow: u32,
    // The mesh's triangles (the glow kernel's workgroups in x).
    triangles: u32,
    // Boxes of more pixels go to the huge edges' queue (a workgroup each).
    huge_pixels: i32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(1) @binding(0) var<uniform> r: Raster;
@group(1) @binding(1) var<storage, read_write> visibility: array<atomic<u64>>;
// The growth step's indirect arguments: the tubes' instance count is word `TUBE_INSTANCES`.
@group(1) @binding(2) var<storage, read> draw_args: array<u32>;
@group(1) @binding(3) var<storage, read> visibility_in: array<u64>;
@group(1) @binding(4) var image: texture_storage_2d<rgba16float, write>;
// The queue: words 0, 1 and 2 count the medium, large and huge edges. Medium edges follow from
// word QUEUE_START and large ones come down from QUEUE_START + capacity (together no more than
// the edges); huge ones come down from the buffer's end (its length is at least QUEUE_START +
// twice the capacity).
@group(1) @binding(5) var<storage, read_write> big_queue: array<atomic<u32>>;
// The queue kernels' dispatches, (x, 1, 1) for the medium at word 0, the large at word 4 and the
// huge at word 8:
// enough workgroups for the counts (at most 65,535, which then loop), zeroed before each frame.
@group(1) @binding(6) var<storage, read_write> big_args: array<atomic<u32>>;
@group(1) @binding(8) var<storage, read> big_queue_in: array<u32>;
// The glow's sum per pixel, GLOW_SCALE per unit of rim weight and sample.
@group(1) @binding(9) var<storage, read_write> glow_sum: array<atomic<u32>>;
@group(1) @binding(10) var<storage, read> glow_in: array<u32>;
// The floor's fill writes every word (it is the frame's first writer).
@group(1) @binding(11) var<storage, read_write> visibility_out: array<u64>;
// The model's triangles (3 vertex indices each), for the glow.
@group(0) @binding(6) var<storage, read> mesh_indices: array<u32>;

// Must match `TUBE_ARGS` / 4 + 1 in growth.rs: the instance count of the indexed tube draw.
const TUBE_INSTANCES: u32 = 8u;
// The projection's near plane (params.rs `view_proj`).
const NEAR: f32 = 0.05;
// Boxes of more pixels than this go to the queue, as medium edges (one thread each) or, past
// the uniforms' large_pixels and huge_pixels, large (32 lanes each) and huge ones (64): an edge
// walked inline keeps its warp waiting.
const INLINE_PIXELS: i32 = 16;
// The queue's first edge word (words 0, 1 and 2 count its medium, large and huge edges).
const QUEUE_START: u32 = 4u;
// The floor's key (edges are 1 + their instance).
const FLOOR_KEY: u32 = 0xFFFFFFFFu;
// The glow's fixed point: 2^16 per unit of rim weight and sample (a pixel overflows past 2^16
// samples of full weight: 16,384 layers of skin at 4 samples).
const GLOW_SCALE: f32 = 65536.0;
// Workgroups per glow triangle: a triangle that fills the image still spreads over the GPU.
const GLOW_CHUNKS: u32 = 16u;

// The unit ray from the camera through pixel position p (y down).
fn pixel_ray(p: vec2<f32>) -> vec3<f32> {
    return normalize(r.ray_origin.xyz + r.ray_x.xyz * p.x + r.ray_y.xyz * p.y);
}

// Where the unit ray (o, d) enters and leaves the capsule a–b of radius `radius`, as distances
// along it (-1 where it misses). The ray starts again near the capsule before the quadratics, so
// that their terms are of the capsule's size and not the camera's distance (no cancellation in
// f32).
fn capsule_span(o: vec3<f32>, d: vec3<f32>, a: vec3<f32>, b: vec3<f32>, radius: f32) -> vec2<f32> {
    let start = max(dot(a - o, d) - length(b - a) - 2.0 * radius, 0.0);
    let ro = o + d * start;
    let ba = b - a;
    let oa = ro - a;
    let baba = dot(ba, ba);
    let bard = dot(ba, d);
    let baoa = dot(ba, oa);
    let qa = baba - bard * bard;
    let qb = baba * dot(d, oa) - baoa * bard;
    let qc = baba * dot(oa, oa) - baoa * baoa - radius * radius * baba;
    let h = qb * qb - qa * qc;
    var span = vec2<f32>(1e30, -1e30);
    if qa > 0.0 {
        // The capsule lies inside the infinite cylinder round its axis: a ray that misses the
        // cylinder misses it (most rays tested do).
        if h < 0.0 {
            return vec2<f32>(-1.0);
        }
        // The side: kept where the hit lies between the end caps.
        let ts = (vec2<f32>(-qb) + vec2<f32>(-1.0, 1.0) * sqrt(h)) / qa;
        let along = vec2<f32>(baoa) + ts * bard;
        let inside = (along > vec2<f32>(0.0)) & (along < vec2<f32>(baba));
        // Where the cylinder's entry and exit both lie between the caps they are the capsule's:
        // it is convex and inside the cylinder.
        if all(inside) {
            return ts + start;
        }
        span = select(span, ts, inside);
    }
    // The round ends (the whole capsule when the edge has no length yet).
    for (var end = 0u; end < 2u; end++) {
        let oc = ro - select(a, b, end == 1u);
        let sb = dot(d, oc);
        let sh = sb * sb - (dot(oc, oc) - radius * radius);
        if sh >= 0.0 {
            span = vec2<f32>(min(span.x, -sb - sqrt(sh)), max(span.y, -sb + sqrt(sh)));
        }
    }
    return select(vec2<f32>(-1.0), span + start, span.y >= span.x);
}

// The distance to the capsule's surface that the pipeline would show on this ray: where it
// enters, or — where that is nearer than the near plane, which clips it — where it leaves (the
// inside of a tube the near plane cuts open); -1 if none.
fn visible_hit(d: vec3<f32>, span: vec2<f32>) -> f32 {
    if span.x > 0.0 && beyond_near(d, span.x) {
        return span.x;
    }
    return select(-1.0, span.y, span.y > 0.0 && beyond_near(d, span.y));
}

// Pixel coordinates (y down) of a clip-space point in front of the camera.
fn to_pixels(clip: vec4<f32>) -> vec2<f32> {
    let ndc = clip.xy / clip.w;
    return vec2<f32>((ndc.x * 0.5 + 0.5) * f32(r.width), (0.5 - ndc.y * 0.5) * f32(r.height));
}

// The pixels from lo to hi (pixel coordinates), clipped to the image: (x0, y0, x1, y1).
fn pixel_box(lo: vec2<f32>, hi: vec2<f32>) -> vec4<i32> {
    let size = vec2<f32>(f32(r.width), f32(r.height));
    let first = vec2<i32>(floor(clamp(lo, vec2<f32>(0.0), size)));
    let last = vec2<i32>(floor(clamp(hi, vec2<f32>(-1.0), size - 1.0)));
    return vec4<i32>(first, last);
}

// The capsule's box in pixels (x0, y0, x1, y1), clipped to the image (empty, x0 > x1, when off
// screen): the projection of its world box's part in front of the near plane — the corners in
// front and the points where the box's edges cross the plane.
fn capsule_box(a: vec3<f32>, b: vec3<f32>, radius: f32) -> vec4<i32> {
    let lo = min(a, b) - vec3<f32>(radius);
    let hi = max(a, b) + vec3<f32>(radius);
    var lo_hi = vec4<f32>(vec2<f32>(1e30), vec2<f32>(-1e30));
    for (var c = 0u; c < 8u; c++) {
        let corner = select(lo, hi, vec3<bool>((c & 1u) != 0u, (c & 2u) != 0u, (c & 4u) != 0u));
        let clip = view.view_proj * vec4<f32>(corner, 1.0);
        if clip.w >= NEAR {
            lo_hi = grow_by_point(lo_hi, clip);
            continue;
        }
        // Behind the plane: where each box edge from this corner to one in front crosses it.
        for (var axis = 0u; axis < 3u; axis++) {
            let other_corner = select(lo, hi, vec3<bool>(
                ((c ^ (1u << axis)) & 1u) != 0u,
                ((c ^ (1u << axis)) & 2u) != 0u,
                ((c ^ (1u << axis)) & 4u) != 0u,
            ));
            lo_hi = grow_by_crossing(lo_hi, clip, view.view_proj * vec4<f32>(other_corner, 1.0));
        }
    }
    return pixel_box(lo_hi.xy - 0.5, lo_hi.zw + 0.5);
}

// Box `lo_hi` (lo.xy, hi.xy in pixels) grown by clip position p where it lies beyond the near
// plane.
fn grow_by_point(lo_hi: vec4<f32>, p: vec4<f32>) -> vec4<f32> {
    if p.w < NEAR {
        return lo_hi;
    }
    let at = to_pixels(p);
    return vec4<f32>(min(lo_hi.xy, at), max(lo_hi.zw, at));
}

// Box `lo_hi` grown by the point where the segment between clip positions p and q crosses the
// near plane, where it does.
fn grow_by_crossing(lo_hi: vec4<f32>, p: vec4<f32>, q: vec4<f32>) -> vec4<f32> {
    if (p.w >= NEAR) == (q.w >= NEAR) {
        return lo_hi;
    }
    let at = to_pixels(mix(p, q, (NEAR - p.w) / (q.w - p.w)));
    return vec4<f32>(min(lo_hi.xy, at), max(lo_hi.zw, at));
}

// Whether a hit at distance t along unit ray d from the camera lies beyond the near plane (the
// pipeline clips what is nearer).
fn beyond_near(d: vec3<f32>, t: f32) -> bool {
    let m = view.view_proj;
    let p = view.camera.xyz + d * t;
    return m[0].w * p.x + m[1].w * p.y + m[2].w * p.z + m[3].w >= NEAR;
}

// An edge ready for coverage: its end points and its key.
struct Cover {
    e: Edge,
    key: u64,
}

fn cover_setup(instance: u32) -> Cover {
    return Cover(edge(instance), u64(instance + 1u));
}

// The point of the edge's axis nearest the unit ray (o, d).
fn axis_point_nearest(e: Edge, o: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let ba = e.to_pos - e.from_pos;
    let w = o - e.from_pos;
    let bd = dot(ba, d);
    let s = clamp((dot(ba, w) - bd * dot(d, w)) / max(dot(ba, ba) - bd * bd, 1e-30), 0.0, 1.0);
    return e.from_pos + ba * s;
}

// Tests every sample of pixel (x, y) against the edge — after one test at the pixel's centre:
// where the capsule's axis lies farther from the centre ray than its radius and a pixel's width
// (at the capsule's far end), no sample of the pixel can see it.
fn cover_pixel(c: Cover, x: i32, y: i32) {
    let o = view.camera.xyz;
    let centre = pixel_ray(vec2<f32>(f32(x), f32(y)) + 0.5);
    let to_axis = axis_point_nearest(c.e, o, centre) - o;
    let along = dot(to_axis, centre);
    // Sample rays part from the centre ray by under a pixel's angle: at most this far at the
    // capsule's far end.
    let farthest = max(dot(c.e.from_pos - o, centre), dot(c.e.to_pos - o, centre)) + view.thickness;
    let reach = view.thickness + max(farthest, 0.0) * r.ray_origin.w;
    if dot(to_axis, to_axis) - along * along > reach * reach {
        return;
    }
    let base = (u32(y) * r.width + u32(x)) * r.samples;
    for (var k = 0u; k < r.samples; k++) {
        let d = pixel_ray(sample_at(vec2<u32>(u32(x), u32(y)), k));
        let t = visible_hit(d, capsule_span(o, d, c.e.from_pos, c.e.to_pos, view.thickness));
        let inverted = ~bitcast<u32>(t);
        if t > 0.0 {
            atomicMax(&visibility[base + k], (u64(inverted) << 32u) | c.key);
        }
    }
}

// The capsule's outline on screen, conservatively: a 2D capsule (stadium) around the projected
// axis p0–p1, `radius` px wide — the world radius at the nearer end's distance and angle off the
// view axis (a plane image stretches what lies off-axis by up to 1 / cos² of the angle), plus
// the reach of a pixel's samples. `whole` when an end lies too near the camera to say: the box's
// rows are walked whole.
struct Footprint {
    p0: vec2<f32>,
    p1: vec2<f32>,
    radius: f32,
    whole: bool,
}

fn footprint(c: Cover) -> Footprint {
    let o = view.camera.xyz;
    var f = Footprint(vec2<f32>(0.0), vec2<f32>(0.0), 0.0, false);
    var radius = 0.0;
    for (var end = 0u; end < 2u; end++) {
        let p = select(c.e.from_pos, c.e.to_pos, end == 1u);
        let clip = view.view_proj * vec4<f32>(p, 1.0);
        let distance = length(p - o);
        let cosine = dot(p - o, r.forward.xyz) / max(distance, 1e-30);
        if clip.w < NEAR + view.thickness || distance <= view.thickness || cosine <= 0.1 {
            f.whole = true;
            return f;
        }
        let px = to_pixels(clip);
        if end == 0u {
            f.p0 = px;
        } else {
            f.p1 = px;
        }
        // The angle the radius subtends (a sphere seen from `distance`), in pixels.
        let angle = asin(min(view.thickness / distance, 1.0));
        radius = max(radius, angle / (r.ray_origin.w * cosine * cosine));
    }
    f.radius = radius * 1.25 + 1.0;
    return f;
}

// The pixels to walk, as a box (x0, y0, x1, y1) clipped to the image: the footprint's, or the
// projected world box's where the footprint cannot say.
fn cover_box(c: Cover, f: Footprint) -> vec4<i32> {
    if f.whole {
        return capsule_box(c.e.from_pos, c.e.to_pos, view.thickness);
    }
    return pixel_box(min(f.p0, f.p1) - f.radius - 0.5, max(f.p0, f.p1) + f.radius - 0.5);
}

// The part of `band` (an interval of x) where slope·x + offset lies within `limit`. (Called once
// per limit rather than looping over an array of them: a dynamically indexed array lives in
// local memory.)
fn band_within(band: vec2<f32>, slope: f32, offset: f32, limit: vec2<f32>) -> vec2<f32> {
    if abs(slope) > 1e-9 {
        let a = (limit.x - offset) / slope;
        let b = (limit.y - offset) / slope;
        return vec2<f32>(max(band.x, min(a, b)), min(band.y, max(a, b)));
    }
    if offset < limit.x || offset > limit.y {
        return vec2<f32>(1e30, -1e30);
    }
    return band;
}

// The pixels of row y whose centres lie in the footprint, as [first, last] within the box.
fn footprint_row(f: Footprint, box: vec4<i32>, y: i32) -> vec2<i32> {
    if f.whole {
        return box.xz;
    }
    let cy = f32(y) + 0.5;
    let rr = f.radius * f.radius;
    var lo = 1e30;
    var hi = -1e30;
    // The round ends.
    for (var end = 0u; end < 2u; end++) {
        let p = select(f.p0, f.p1, end == 1u);
        let dy = cy - p.y;
        if dy * dy <= rr {
            let half = sqrt(rr - dy * dy);
            lo = min(lo, p.x - half);
            hi = max(hi, p.x + half);
        }
    }
    // The band along the axis: |n·(P − p0)| ≤ radius and 0 ≤ u·(P − p0) ≤ length, each linear in x.
    let axis = f.p1 - f.p0;
    let length = sqrt(dot(axis, axis));
    if length > 1e-6 {
        let u = axis / length;
        let n = vec2<f32>(-u.y, u.x);
        var band = vec2<f32>(-1e30, 1e30);
        band = band_within(band, n.x, n.y * (cy - f.p0.y) - n.x * f.p0.x, vec2<f32>(-f.radius, f.radius));
        band = band_within(band, u.x, u.y * (cy - f.p0.y) - u.x * f.p0.x, vec2<f32>(0.0, length));
        if band.x <= band.y {
            lo = min(lo, band.x);
            hi = max(hi, band.y);
        }
    }
    // Pixel x has its centre at x + 0.5.
    let first = max(i32(ceil(clamp(lo, -1e9, 1e9) - 0.5)), box.x);
    let last = min(i32(floor(clamp(hi, -1e9, 1e9) - 0.5)), box.z);
    return vec2<i32>(first, last);
}

@compute @workgroup_size(256)
fn raster(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let instance = id.y * groups.x * 256u + id.x;
    if instance >= min(draw_args[TUBE_INSTANCES], r.capacity) {
        return;
    }
    let c = cover_setup(instance);
    let f = footprint(c);
    let box = cover_box(c, f);
    let pixels = (box.z - box.x + 1) * (box.w - box.y + 1);
    if pixels > max(r.huge_pixels, INLINE_PIXELS) {
        // Huge edges from the buffer's end, a workgroup each.
        let slot = atomicAdd(&big_queue[2], 1u);
        atomicStore(&big_queue[arrayLength(&big_queue) - 1u - slot], instance);
        atomicMax(&big_args[8], min(slot + 1u, 65535u));
        return;
    }
    if pixels > max(r.large_pixels, INLINE_PIXELS) {
        // Large edges down from the medium region's end, two to a workgroup.
        let slot = atomicAdd(&big_queue[1], 1u);
        atomicStore(&big_queue[QUEUE_START + r.capacity - 1u - slot], instance);
        atomicMax(&big_args[4], min(slot / 2u + 1u, 65535u));
        return;
    }
    if pixels > INLINE_PIXELS {
        // Medium edges from its start, one thread each, in warps of like sizes.
        let slot = atomicAdd(&big_queue[0], 1u);
        atomicStore(&big_queue[QUEUE_START + slot], instance);
        atomicMax(&big_args[0], min(slot / 64u + 1u, 65535u));
        return;
    }
    cover_walk(c, f, box, vec2<i32>(0), vec2<i32>(1));
}

// Walks the pixels of edge `instance` inside its outline on screen, every `step.x`-th column
// and `step.y`-th row from `first` (one thread: 0 and 1).
fn cover_edge(instance: u32, first: vec2<i32>, step: vec2<i32>) {
    let c = cover_setup(instance);
    let f = footprint(c);
    cover_walk(c, f, cover_box(c, f), first, step);
}

fn cover_walk(c: Cover, f: Footprint, box: vec4<i32>, first: vec2<i32>, step: vec2<i32>) {
    for (var y = box.y + first.y; y <= box.w; y += step.y) {
        let span = footprint_row(f, box, y);
        for (var x = span.x + first.x; x <= span.y; x += step.x) {
            cover_pixel(c, x, y);
        }
    }
}

@compute @workgroup_size(64)
fn raster_medium(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var q = id.x; q < big_queue_in[0]; q += groups.x * 64u) {
        cover_edge(big_queue_in[QUEUE_START + q], vec2<i32>(0), vec2<i32>(1));
    }
}

// Two large edges per workgroup, 32 lanes each; lane i starts at pixel (i % 4, i / 4) of the
// box and steps 4 columns and 8 rows. (For the million at 4K on the H200, 32 lanes walked edges
// of 128-1,024 px in 7.4 ms against 9.0 for a thread each up to 256 px and a workgroup past it;
// at 1080p and 720p both took 3.6 and 2.1 ms.)
@compute @workgroup_size(64)
fn raster_large(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
) {
    let lane = index % 32u;
    let first = vec2<i32>(vec2<u32>(lane % 4u, lane / 4u));
    for (var q = group.x * 2u + index / 32u; q < big_queue_in[1]; q += groups.x * 2u) {
        cover_edge(big_queue_in[QUEUE_START + r.capacity - 1u - q], first, vec2<i32>(4, 8));
    }
}

// One huge edge per workgroup: lane (x, y) walks every 8th column and row from (x, y).
@compute @workgroup_size(8, 8)
fn raster_huge(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
) {
    for (var q = group.x; q < big_queue_in[2]; q += groups.x) {
        cover_edge(big_queue_in[arrayLength(&big_queue_in) - 1u - q], vec2<i32>(lid.xy), vec2<i32>(8));
    }
}

// The colour of edge `instance` seen through the pixel centre `p`: at the ray's hit, or — for an
// edge that holds samples of the pixel but not its centre — at its silhouette, the point of the
// capsule nearest the ray.
fn shade_edge(instance: u32, p: vec2<f32>) -> vec3<f32> {
    let e = edge(instance);
    let o = view.camera.xyz;
    let d = pixel_ray(p);
    let t = visible_hit(d, capsule_span(o, d, e.from_pos, e.to_pos, view.thickness));
    let ba = e.to_pos - e.from_pos;
    let baba = max(dot(ba, ba), 1e-30);
    var on_ray = o + d * t;
    if t <= 0.0 {
        on_ray = o + d * max(dot(axis_point_nearest(e, o, d) - o, d), 0.0);
    }
    let along = clamp(dot(on_ray - e.from_pos, ba) / baba, 0.0, 1.0);
    let centre = e.from_pos + ba * along;
    var n = on_ray - centre;
    n = select(-d, normalize(n), dot(n, n) > 1e-30);
    return tube_colour(n, centre + n * view.thickness, e.t);
}

// The edge key (1 + instance, 0: none, FLOOR_KEY: the floor) of sample word i.
fn key_at(i: u32) -> u32 {
    return u32(visibility_in[i] & 0xFFFFFFFFlu);
}

// The distance along the unit ray of sample word i's hit (infinite where it holds none).
fn depth_at(i: u32) -> f32 {
    let word = visibility_in[i];
    return select(bitcast<f32>(~u32(word >> 32u)), 1e38, word == 0lu);
}

// Sample k of pixel (x, y): its position in pixel coordinates.
fn sample_at(pixel: vec2<u32>, k: u32) -> vec2<f32> {
    return vec2<f32>(pixel) + 0.5 + vec2<f32>(sample_offset(r.samples, k)) / 16.0;
}

// Where the unit ray d from the camera meets the floor square (y = 0, half size view.floor.w)
// beyond the near plane; -1 where it does not.
fn floor_hit(d: vec3<f32>) -> f32 {
    let o = view.camera.xyz;
    let t = -o.y / d.y;
    let p = o + d * t;
    let inside = abs(p.x) <= view.floor.w && abs(p.z) <= view.floor.w;
    return select(-1.0, t, t > 0.0 && t < 1e30 && inside && beyond_near(d, t));
}

@compute @workgroup_size(8, 8)
fn floor_fill(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= r.width || id.y >= r.height {
        return;
    }
    let base = (id.y * r.width + id.x) * r.samples;
    for (var k = 0u; k < r.samples; k++) {
        let t = floor_hit(pixel_ray(sample_at(id.xy, k)));
        visibility_out[base + k] = select(0lu, (u64(~bitcast<u32>(t)) << 32u) | u64(FLOOR_KEY), t > 0.0);
    }
}

// The floor's colour at pixel centre `p` (where the pipeline interpolates it) — or, where the
// centre ray passes above the horizon, at the hit of the sample whose word is i.
fn shade_floor(p: vec2<f32>, i: u32, sample: vec2<f32>) -> vec3<f32> {
    let o = view.camera.xyz;
    let d = pixel_ray(p);
    let t = -o.y / d.y;
    if t > 0.0 && t < 1e30 {
        return floor_colour(o + d * t);
    }
    return floor_colour(o + pixel_ray(sample) * depth_at(i));
}

// Where the unit ray (o, d) meets triangle a b c (either side), -1 where it misses.
fn triangle_hit(o: vec3<f32>, d: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    let e1 = b - a;
    let e2 = c - a;
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return -1.0;
    }
    let s = o - a;
    let u = dot(s, p) / det;
    let q = cross(s, e1);
    let v = dot(d, q) / det;
    let t = dot(e2, q) / det;
    return select(-1.0, t, u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0);
}

// The box in pixels (x0, y0, x1, y1) of the part of triangle a b c beyond the near plane,
// clipped to the image (empty, x0 > x1, where none is): the projections of its corners in front
// of the plane and of the points where its sides cross it.
fn triangle_box(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec4<i32> {
    let pa = view.view_proj * vec4<f32>(a, 1.0);
    let pb = view.view_proj * vec4<f32>(b, 1.0);
    let pc = view.view_proj * vec4<f32>(c, 1.0);
    var lo_hi = vec4<f32>(vec2<f32>(1e30), vec2<f32>(-1e30));
    lo_hi = grow_by_crossing(grow_by_point(lo_hi, pa), pa, pb);
    lo_hi = grow_by_crossing(grow_by_point(lo_hi, pb), pb, pc);
    lo_hi = grow_by_crossing(grow_by_point(lo_hi, pc), pc, pa);
    return pixel_box(lo_hi.xy - 0.5, lo_hi.zw + 0.5);
}

@compute @workgroup_size(256)
fn glow(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let o = view.camera.xyz;
    for (var triangle = group.x; triangle < r.triangles; triangle += groups.x) {
        let a = skinned_vertex(mesh_indices[3u * triangle]);
        let b = skinned_vertex(mesh_indices[3u * triangle + 1u]);
        let c = skinned_vertex(mesh_indices[3u * triangle + 2u]);
        let n = normalize(cross(b - a, c - a));
        let box = triangle_box(a, b, c);
        if box.x > box.z || box.y > box.w {
            continue;
        }
        let width = box.z - box.x + 1;
        let pixels = width * (box.w - box.y + 1);
        for (var i = i32(group.y * 256u + lane); i < pixels; i += i32(256u * GLOW_CHUNKS)) {
            let pixel = vec2<u32>(vec2<i32>(box.x + i % width, box.y + i / width));
            let base = (pixel.y * r.width + pixel.x) * r.samples;
            var count = 0u;
            for (var k = 0u; k < r.samples; k++) {
                let d = pixel_ray(sample_at(pixel, k));
                let t = triangle_hit(o, d, a, b, c);
                count += u32(t > 0.0 && beyond_near(d, t) && t < depth_at(base + k));
            }
            if count > 0u {
                // Shaded once per pixel at its centre, as the pipeline's fragment is.
                let weight = glow_weight(n, -pixel_ray(vec2<f32>(pixel) + 0.5));
                atomicAdd(&glow_sum[pixel.y * r.width + pixel.x], u32(round(weight * f32(count) * GLOW_SCALE)));
            }
        }
    }
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= r.width || id.y >= r.height {
        return;
    }
    let base = (id.y * r.width + id.x) * r.samples;
    let centre = vec2<f32>(id.xy) + 0.5;
    // Each distinct edge among the samples is shaded once and weighted by its samples; the keys
    // are read again rather than kept in a per-invocation array (slow local memory).
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < r.samples; k++) {
        let key = key_at(base + k);
        var first = true;
        for (var j = 0u; j < k; j++) {
            first = first && key_at(base + j) != key;
        }
        if !first {
            continue;
        }
        var count = 1u;
        for (var j = k + 1u; j < r.samples; j++) {
            count += u32(key_at(base + j) == key);
        }
        var colour = r.background.rgb;
        if key == FLOOR_KEY {
            colour = shade_floor(centre, base + k, sample_at(id.xy, k));
        } else if key != 0u {
            colour = shade_edge(key - 1u, centre);
        }
        sum += colour * f32(count);
    }
    if r.glow != 0u {
        let glow = f32(glow_in[id.y * r.width + id.x]) / GLOW_SCALE;
        sum += view.color.rgb * view.ghost * glow;
    }
    textureStore(image, id.xy, vec4<f32>(sum / f32(r.samples), 1.0));
}
