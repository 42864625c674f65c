//! Bridging holes into their outer ring [UGP4 ch.5, after Eberly, "Triangulation by Ear
//! Clipping" §3, mirrored as in earcut]: holes are taken left to right by their leftmost vertex
//! M; a ray from M to −x finds the nearest outer edge, and the bridge goes to the visible vertex
//! that makes the smallest angle with the ray. (The book and Eberly go right to left; the
//! mirror image merges rings as earcut does, so the two cut crossing input alike.) Cutting along
//! the bridge (both ends duplicated) turns an outer ring with holes into one weakly simple ring.
//! Holes that touch the ring so far at their leftmost point bridge there (zero length), in the
//! order of their first edges' slopes, so each lands in its own corner of the shared point.
//!
//! Walking the whole merged ring per hole is O(holes × vertices): the ring's edges are bucketed
//! into horizontal bands instead, so that both searches only visit edges near the hole's y.

use super::linked::{NIL, Rings, area, mark, point_in_triangle};
use super::ring_order::RingOrder;

/// Edges of the merged ring bucketed by y: each band lists the start nodes of the edges whose y
/// range overlaps it. Entries go stale when nodes are removed (checked on use) and are added for
/// every new edge, so a band always lists every live edge crossing it.
#[derive(Default)]
pub(super) struct Bands {
    min_y: f64,
    inv_height: f64,
    lists: Vec<Vec<u32>>,
}

impl Bands {
    fn reset(&mut self, [min_y, max_y]: [f64; 2], count: usize) {
        let count = count.max(1);
        self.lists.iter_mut().for_each(Vec::clear);
        self.lists.resize_with(count, Vec::new);
        self.lists.truncate(count);
        self.min_y = min_y;
        self.inv_height = if max_y > min_y { count as f64 / (max_y - min_y) } else { 0.0 };
    }

    #[inline]
    fn band(&self, y: f64) -> usize {
        // `as` takes negatives to 0.
        (((y - self.min_y) * self.inv_height) as usize).min(self.lists.len() - 1)
    }

    /// Registers the edge that starts at `p`.
    fn add_edge(&mut self, rings: &Rings, p: u32) {
        let (a, b) = (rings.get(p).y, rings.get(rings.next(p)).y);
        self.add_span(p, self.band(a), self.band(b));
    }

    /// Registers every edge of the outer ring, from its node `start` on (earcut's order: ties in
    /// the bridge search go to the edge listed first). Its nodes are the arena's first, in ring
    /// order (see [`OuterRing`]): read in order, each node's band worked out once (walking the
    /// ring, each node's load waited on the one before).
    fn add_outer_ring(&mut self, rings: &Rings, outer: &OuterRing) {
        let (start, size) = (outer.node, outer.size);
        let first = self.band(rings.get(start).y);
        let mut band = first;
        for p in (start..size).chain(0..start) {
            let next = rings.next(p);
            let next_band = if next == start { first } else { self.band(rings.get(next).y) };
            self.add_span(p, band, next_band);
            band = next_band;
        }
    }

    /// Lists the edge that starts at `p` in every band from `a`'s to `b`'s (either order).
    #[inline]
    fn add_span(&mut self, p: u32, a: usize, b: usize) {
        for band in a.min(b)..=a.max(b) {
            self.lists[band].push(p);
        }
    }
}

/// The outer ring, linked first into the arena: nodes `0..size`, each followed by the next
/// (the last by the first).
pub(super) struct OuterRing {
    /// Its start node (`link_ring`'s answer), where earcut's scans of the ring begin.
    pub node: u32,
    pub size: u32,
    /// Its lowest and highest y.
    pub y_range: [f64; 2],
}

/// Splices every hole (a node of each linked clockwise hole ring in `holes`) into the outer ring
/// of `outer`; returns a node of the merged ring.
pub(super) fn eliminate_holes(
    rings: &mut Rings,
    bands: &mut Bands,
    order: &mut RingOrder,
    outer: &OuterRing,
    holes: &mut [u32],
) -> u32 {
    let mut merged = outer.node;
    order.reset(outer.node);
    for hole in holes.iter_mut() {
        *hole = leftmost(rings, *hole);
    }
    // Left first: every hole to the left of the current one is already part of the outer ring,
    // so its ray can only meet the outer ring. Holes whose leftmost points meet go in order of
    // their first edge's slope (counter-clockwise), so each bridges at the shared point.
    let point = |h: u32| [rings.get(h).x, rings.get(h).y];
    holes.sort_unstable_by(|&a, &b| {
        let ([ax, ay], [bx, by]) = (point(a), point(b));
        ax.total_cmp(&bx).then(ay.total_cmp(&by)).then(a.cmp(&b))
    });
    for run in holes.chunk_by_mut(|&a, &b| point(a) == point(b)) {
        order_by_slope(rings, run);
    }
    // About four edges a band, but no more bands than the holes' searches need: filling them is
    // paid per edge, and on a long ring with a few holes (water: 2,397 vertices, 9 holes) it
    // cost a tenth of the whole triangulation. With fewer than eight holes the ring was walked
    // round twice per hole instead: no faster on dude (2 holes) or water4 (5), slower on water2
    // (7 holes: 230 against 196 µs, the least of five runs each).
    bands.reset(outer.y_range, (outer.size as usize / 4).min(holes.len() * 8));
    bands.add_outer_ring(rings, outer);
    rings.recording = true;
    for &hole in holes.iter() {
        // No outer edge to the left: the hole is not inside this ring. Leave it out.
        let Some(bridge) = find_bridge(rings, hole, bands, order) else { continue };
        // The hole's edges join the ring: note them while the hole is still a ring of its own.
        rings.touched.clear();
        let mut p = hole;
        loop {
            rings.touched.push(p);
            p = rings.next(p);
            if p == hole {
                break;
            }
        }
        let one_point = rings.next(hole) == hole;
        let after = rings.next(bridge);
        let reverse = rings.split(bridge, hole);
        order.spliced(rings, bridge, after);
        // A hole bridged to a Steiner point: the copy of the point stays one too. Filtered away
        // as collinear, it would leave the point on the edge that replaced it, a vertex of the
        // triangles on one side only. (Not the copy of a one-point hole: two copies of a point
        // that may not go would block every ear at it.)
        let bridge_copy = rings.next(reverse);
        let steiner = rings.marked(bridge, mark::STEINER) && !one_point;
        rings.set_mark(bridge_copy, mark::STEINER, steiner);
        merged = heal_bridge(rings, bridge, reverse, hole);
        // New edges: the hole's, both bridge edges, and those the filters shortened.
        for p in [bridge, reverse, rings.next(reverse), rings.prev(reverse)] {
            if rings.alive(p) {
                bands.add_edge(rings, p);
            }
        }
        for i in 0..rings.touched.len() {
            let p = rings.touched[i];
            if rings.alive(p) {
                bands.add_edge(rings, p);
            }
        }
    }
    rings.recording = false;
    // Bridges line up with edges often enough that a pass over the merged ring pays off.
    rings.filter(merged, NIL)
}

/// Tidies collinear and repeated points around the two new edges of a bridge (`bridge` on the
/// outer ring, `reverse` the copy of the hole's point after it); returns a node of the ring.
/// The copy of the bridge's point ahead of the hole is left alone: dropped as collinear, it
/// would leave the bridge's point lying on the healed edge, where a later hole could bridge
/// into it from outside its corner. Likewise the bridge's own point, when it lies strictly
/// between its predecessor and the hole.
fn heal_bridge(rings: &mut Rings, bridge: u32, reverse: u32, hole: u32) -> u32 {
    let healed = rings.filter(rings.prev(reverse), reverse);
    if !rings.alive(bridge) {
        // A hole that is a spike once bridged (two points, or collinear ones), bridged along
        // an outer edge in line with the bridge: the filter went back through the whole hole and
        // the bridge's node. Going on from the removed node (its links are stale) walked a ring
        // it was no longer on, for ever.
        return healed;
    }
    let (before, at, to) = (rings.get(rings.prev(bridge)), rings.get(bridge), rings.get(hole));
    let between =
        area(before, at, to) == 0.0 && (before.x - at.x) * (to.x - at.x) + (before.y - at.y) * (to.y - at.y) < 0.0;
    if between { bridge } else { rings.filter(bridge, rings.next(bridge)) }
}

/// Orders holes that share their leftmost point by the slope of their first edge, keeping
/// input order where a slope is undefined (a first edge of no length: a hole of repeated
/// points), as earcut's stable sort does, which calls such a slope equal to any other. A total
/// order (NaN first or last) bridged such holes in another order than earcut's: on crossing
/// input, other triangles. An insertion sort, as that rule is no total order (a sort may panic
/// on one); runs are a few holes long.
fn order_by_slope(rings: &Rings, run: &mut [u32]) {
    let slope = |h: u32| {
        let (n, next) = (rings.get(h), rings.get(rings.next(h)));
        (next.y - n.y) / (next.x - n.x)
    };
    for i in 1..run.len() {
        let mut j = i;
        while j > 0 && slope(run[j]) < slope(run[j - 1]) {
            run.swap(j, j - 1);
            j -= 1;
        }
    }
}

/// The node of a ring with the smallest x (lowest y among ties).
fn leftmost(rings: &Rings, start: u32) -> u32 {
    let mut best = start;
    let mut p = rings.next(start);
    while p != start {
        let (n, b) = (rings.get(p), rings.get(best));
        if n.x < b.x || (n.x == b.x && n.y < b.y) {
            best = p;
        }
        p = n.next;
    }
    best
}

/// Calls `visit` with the start node of every live edge that may cross y in [y0, y1].
fn for_each_edge(rings: &Rings, bands: &Bands, y0: f64, y1: f64, mut visit: impl FnMut(u32)) {
    for band in bands.band(y0)..=bands.band(y1) {
        for &p in &bands.lists[band] {
            if rings.alive(p) {
                visit(p);
            }
        }
    }
}

/// The outer vertex the hole's leftmost vertex connects to. Where candidates tie, the one
/// earcut's scan meets first in ring order wins (see [`RingOrder`]).
fn find_bridge(rings: &Rings, hole: u32, bands: &Bands, order: &mut RingOrder) -> Option<u32> {
    let (hx, hy) = (rings.get(hole).x, rings.get(hole).y);
    // The nearest crossing of the ray y = hy, x ≤ hx with an outer edge seen from inside
    // (counter-clockwise, so an edge going down). A vertex at the hole point itself, or an
    // edge through it, ends earcut's scan: the bridge has no length there.
    let head = order.live_head(rings);
    let mut qx = f64::NEG_INFINITY;
    let (mut hits, mut crossings) = (std::mem::take(&mut order.hits), std::mem::take(&mut order.crossings));
    hits.clear();
    crossings.clear();
    for_each_edge(rings, bands, hy, hy, |p| {
        let (n, nn) = (rings.get(p), rings.get(rings.next(p)));
        if nn.x == hx && nn.y == hy {
            hits.push((p, n.next));
            return;
        }
        if nn.y <= hy && hy <= n.y && nn.y != n.y {
            let x = n.x + (hy - n.y) * (nn.x - n.x) / (nn.y - n.y);
            let m = if n.x < nn.x { p } else { n.next };
            if x == hx {
                // Leaving the hole point: the edge into it was met first (unless it starts at
                // the head), and found the vertex.
                let from_vertex = n.x == hx && n.y == hy && p != head;
                hits.push(if from_vertex { (n.prev, p) } else { (p, m) });
            } else if x < hx && x >= qx {
                if x > qx {
                    qx = x;
                    crossings.clear();
                }
                // Its left end: where a bridge to this crossing goes.
                crossings.push((p, m));
            }
        }
    });
    let found = if !hits.is_empty() {
        Some(order.first(rings, &hits))
    } else if !crossings.is_empty() {
        let m = order.first(rings, &crossings);
        Some(visible_vertex(rings, hole, bands, order, m, qx))
    } else {
        // No outer edge to the left.
        None
    };
    (order.hits, order.crossings) = (hits, crossings);
    found
}

/// A reflex vertex inside triangle (hole point, crossing at `qx`, endpoint `m`) may hide `m`;
/// the visible one is the vertex in there with the smallest angle to the ray (the rightmost
/// among equal angles, and of copies of one point the one whose sector lies inside the
/// other's).
fn visible_vertex(rings: &Rings, hole: u32, bands: &Bands, order: &mut RingOrder, m: u32, qx: f64) -> u32 {
    let (hx, hy) = (rings.get(hole).x, rings.get(hole).y);
    let (mx, my) = (rings.get(m).x, rings.get(m).y);
    let mut tan_min = f64::INFINITY;
    let mut best_x = f64::NEG_INFINITY;
    // Every candidate at the best angle and x, met in band order.
    let mut group = std::mem::take(&mut order.group);
    group.clear();
    let consider = |p: u32| {
        let n = rings.get(p);
        if mx <= n.x && n.x <= hx && hx != n.x && point_in_triangle([hx, hy], [qx, hy], [mx, my], [n.x, n.y]) {
            let tan = (hy - n.y).abs() / (hx - n.x);
            if tan > tan_min || (tan == tan_min && n.x < best_x) {
                return;
            }
            let next = rings.get(n.next);
            // An outer edge along the ray, leading past the hole point, is seen from it too; so is
            // a Steiner point (a spike of no width, inside from every side), which a bridge
            // passing through it would leave out of the mesh.
            let along = n.y == hy && next.y == hy && next.x > hx;
            if !(rings.locally_inside(p, hole) || along || rings.marked(p, mark::STEINER)) {
                return;
            }
            if tan < tan_min || n.x > best_x {
                (tan_min, best_x) = (tan, n.x);
                group.clear();
            }
            if !group.contains(&p) {
                group.push(p);
            }
        }
    };
    for_each_edge(rings, bands, hy.min(my), hy.max(my), consider);
    if group.len() > 1 {
        order.sort(rings, &mut group);
    }
    // In ring order, a candidate whose sector lies inside the one kept so far replaces it.
    let best = group.iter().copied().reduce(|best, p| if rings.sector_contains_sector(best, p) { p } else { best });
    order.group = group;
    best.unwrap_or(m)
}
