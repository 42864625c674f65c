//! Bridging holes into their outer ring [UGP4 ch.5, after Eberly, "Triangulation by Ear
//! Clipping" §3, mirrored as in earcut]: holes are taken left to right by their leftmost vertex
//! M; a ray from M to −x finds the nearest outer edge, and the bridge goes to the visible vertex
//! that makes the smallest angle with the ray. (The book and Eberly go right to left; the
//! mirror image merges rings as earcut does, so the two cut crossing input alike.) Cutting along
//! the bridge (both ends duplicated) turns an outer ring with holes into one weakly simple ring.
//!
//! With many holes, walking the whole merged ring per hole is O(holes × vertices); above
//! [`BANDS_FROM_HOLES`] holes the ring's edges are bucketed into horizontal bands so that both
//! searches only visit edges near the hole's y.

use std::collections::HashMap;

use super::linked::{NIL, Node, Rings, area, greatest, least, mark, point_in_triangle};

/// Holes from which the band index pays for itself.
const BANDS_FROM_HOLES: usize = 8;

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
    fn reset(&mut self, min_y: f64, max_y: f64, count: usize) {
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

    /// Registers every edge of the ring of `start`, each node's band worked out once (edge by
    /// edge, each was worked out twice).
    fn add_ring(&mut self, rings: &Rings, start: u32) {
        let mut p = start;
        let mut band = self.band(rings.get(p).y);
        loop {
            let next = rings.next(p);
            let next_band = self.band(rings.get(next).y);
            self.add_span(p, band, next_band);
            (p, band) = (next, next_band);
            if p == start {
                return;
            }
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

/// Where the bridge searches look for outer edges and vertices.
enum Search<'a> {
    /// Walk the whole ring from a node.
    Ring(u32),
    /// Look up the bands.
    Bands(&'a Bands),
}

/// Splices every hole (a node of each linked clockwise hole ring in `holes`) into the outer ring
/// of `outer`; returns a node of the merged ring.
pub(super) fn eliminate_holes(rings: &mut Rings, bands: &mut Bands, mut outer: u32, holes: &mut [u32]) -> u32 {
    if holes.is_empty() {
        // Nothing cut, nothing to tidy: collinear points of the ring itself wait for the
        // slicer's first fallback, as in earcut (a pass over a small ring cost 13% of it).
        return outer;
    }
    for hole in holes.iter_mut() {
        *hole = leftmost(rings, *hole);
    }
    // Left first: every hole to the left of the current one is already part of the outer ring,
    // so its ray can only meet the outer ring. Holes whose leftmost points meet go in order of
    // their first edge's slope (counter-clockwise), so each bridges at the shared point.
    holes.sort_unstable_by(|&a, &b| {
        let (na, nb) = (rings.get(a), rings.get(b));
        let slope = |n: &Node| {
            let next = rings.get(n.next);
            (next.y - n.y) / (next.x - n.x)
        };
        na.x.total_cmp(&nb.x).then(na.y.total_cmp(&nb.y)).then(slope(na).total_cmp(&slope(nb))).then(a.cmp(&b))
    });
    let banded = holes.len() >= BANDS_FROM_HOLES;
    if banded {
        let (mut lo, mut hi, mut count) = (f64::INFINITY, f64::NEG_INFINITY, 0);
        rings.for_each_node(outer, |p| {
            lo = least(lo, rings.get(p).y);
            hi = greatest(hi, rings.get(p).y);
            count += 1;
        });
        // About four edges a band, but no more bands than the holes' searches need: filling
        // them is paid per edge, and on a long ring with a few holes (water: 2,397 vertices,
        // 9 holes) it cost a tenth of the whole triangulation.
        bands.reset(lo, hi, (count / 4).min(holes.len() * 8));
        bands.add_ring(rings, outer);
        rings.recording = true;
    }
    let mut touching = Touching::new(rings, outer, holes);
    for &hole in holes.iter() {
        // A hole that shares a point with the ring so far is joined there, in the copy of the
        // point whose corner it sits in: bridging it elsewhere would leave the ring touching
        // itself at that point, where ears can reach across.
        let (bridge, hole) = match touching.find(rings, hole) {
            Some(joint) => joint,
            None => {
                let search = if banded { Search::Bands(bands) } else { Search::Ring(outer) };
                match find_bridge(rings, hole, search) {
                    Some(bridge) => (bridge, hole),
                    // No outer edge to the right: the hole is not inside this ring. Leave it out.
                    None => continue,
                }
            }
        };
        rings.touched.clear();
        if banded {
            // The hole's edges join the ring: note them while the hole is still a ring of its own.
            let mut touched = std::mem::take(&mut rings.touched);
            rings.for_each_node(hole, |p| touched.push(p));
            rings.touched = touched;
        }
        touching.add_ring(rings, hole);
        let one_point = rings.next(hole) == hole;
        let reverse = rings.split(bridge, hole);
        // A hole bridged to a Steiner point: the copy of the point stays one too. Filtered away
        // as collinear, it would leave the point on the edge that replaced it, a vertex of the
        // triangles on one side only. (Not the copy of a one-point hole: two copies of a point
        // that may not go would block every ear at it.)
        let bridge_copy = rings.next(reverse);
        let steiner = rings.marked(bridge, mark::STEINER) && !one_point;
        rings.set_mark(bridge_copy, mark::STEINER, steiner);
        touching.add(rings, reverse);
        touching.add(rings, rings.next(reverse));
        outer = heal_bridge(rings, bridge, reverse, hole);
        if banded {
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
    }
    rings.recording = false;
    // Bridges line up with edges often enough that a pass over the merged ring pays off.
    rings.filter(outer, NIL)
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

/// Points that two or more input rings share (holes touching each other or the outer ring), and
/// the nodes of the merged ring at each (some may have been filtered away since).
struct Touching {
    copies: HashMap<(u64, u64), Vec<u32>>,
    /// A 4,096-bit filter of the shared points: most nodes skip hashing their point.
    filter: BitFilter,
}

fn key(rings: &Rings, p: u32) -> (u64, u64) {
    let n = rings.get(p);
    // +0.0 and −0.0 are one point.
    ((n.x + 0.0).to_bits(), (n.y + 0.0).to_bits())
}

impl Touching {
    /// Finds the shared points — hole points that another hole or the outer ring also has (a
    /// sort of the hole points, a binary search per outer point) — and records the outer
    /// ring's nodes at them. Without holes nothing is sorted or allocated.
    fn new(rings: &Rings, outer: u32, holes: &[u32]) -> Self {
        let mut touching = Self { copies: HashMap::new(), filter: BitFilter::default() };
        if holes.is_empty() {
            return touching;
        }
        let mut hole_points = Vec::new();
        // The hole points: most outer points skip the binary search.
        let mut filter = BitFilter::default();
        for (ring, &start) in holes.iter().enumerate() {
            rings.for_each_node(start, |p| {
                let k = key(rings, p);
                filter.insert(k);
                hole_points.push((k, ring));
            });
        }
        hole_points.sort_unstable();
        let mut shared: Vec<(u64, u64)> = hole_points
            .windows(2)
            .filter(|pair| pair[0].0 == pair[1].0 && pair[0].1 != pair[1].1)
            .map(|pair| pair[0].0)
            .collect();
        rings.for_each_node(outer, |p| {
            let k = key(rings, p);
            if !filter.may_hold(k) {
                return;
            }
            let at = hole_points.partition_point(|probe| probe.0 < k);
            if hole_points.get(at).is_some_and(|probe| probe.0 == k) {
                shared.push(k);
            }
        });
        for &k in &shared {
            touching.filter.insert(k);
        }
        touching.copies.extend(shared.into_iter().map(|k| (k, Vec::new())));
        touching.add_ring(rings, outer);
        touching
    }

    /// Records a node of the merged ring if it sits at a shared point.
    fn add(&mut self, rings: &Rings, p: u32) {
        let k = key(rings, p);
        if !self.filter.may_hold(k) {
            return;
        }
        if let Some(list) = self.copies.get_mut(&k) {
            list.push(p);
        }
    }

    fn add_ring(&mut self, rings: &Rings, start: u32) {
        if !self.copies.is_empty() {
            rings.for_each_node(start, |p| self.add(rings, p));
        }
    }

    /// A node of the merged ring and a node of the hole at the same point, the hole sitting in
    /// that node's corner.
    fn find(&self, rings: &Rings, hole: u32) -> Option<(u32, u32)> {
        if self.copies.is_empty() {
            return None;
        }
        let mut h = hole;
        loop {
            let k = key(rings, h);
            if let Some(list) = self.filter.may_hold(k).then(|| self.copies.get(&k)).flatten() {
                let fits = |&&q: &&u32| rings.alive(q) && rings.equals(q, h) && corner_holds(rings, q, h);
                if let Some(&q) = list.iter().find(fits) {
                    return Some((q, h));
                }
            }
            h = rings.next(h);
            if h == hole {
                return None;
            }
        }
    }
}

/// A 4,096-bit set of points (a one-hash Bloom filter): `false` from [`Self::may_hold`] is
/// certain, `true` may be wrong.
struct BitFilter([u64; 64]);

impl Default for BitFilter {
    fn default() -> Self {
        Self([0; 64])
    }
}

impl BitFilter {
    /// A point's bit: its coordinate bits mixed and multiplied (a Fibonacci hash), the top 12.
    fn bit((x, y): (u64, u64)) -> usize {
        ((x ^ y.rotate_left(29)).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 52) as usize
    }

    fn insert(&mut self, k: (u64, u64)) {
        let bit = Self::bit(k);
        self.0[bit >> 6] |= 1 << (bit & 63);
    }

    fn may_hold(&self, k: (u64, u64)) -> bool {
        let bit = Self::bit(k);
        self.0[bit >> 6] & (1 << (bit & 63)) != 0
    }
}

/// Whether the hole's corner at `h` lies inside the ring's corner at `q` (same point): going
/// counter-clockwise around the point from the ring's outgoing edge, the hole's edges come (in
/// the hole's clockwise order: incoming, then outgoing) before the ring's incoming edge.
fn corner_holds(rings: &Rings, q: u32, h: u32) -> bool {
    let at = rings.get(q);
    let direction = |p: u32| {
        let n = rings.get(p);
        (n.y - at.y).atan2(n.x - at.x)
    };
    let start = direction(rings.next(q));
    let turn = |p: u32| (direction(p) - start).rem_euclid(std::f64::consts::TAU);
    let (hole_in, hole_out, ring_in) = (turn(rings.prev(h)), turn(rings.next(h)), turn(rings.prev(q)));
    hole_in < hole_out && hole_out <= ring_in
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
fn for_each_edge(rings: &Rings, search: &Search, y0: f64, y1: f64, mut visit: impl FnMut(u32)) {
    match search {
        Search::Ring(start) => {
            let mut p = *start;
            loop {
                visit(p);
                p = rings.next(p);
                if p == *start {
                    break;
                }
            }
        }
        Search::Bands(bands) => {
            for band in bands.band(y0)..=bands.band(y1) {
                for &p in &bands.lists[band] {
                    if rings.alive(p) {
                        visit(p);
                    }
                }
            }
        }
    }
}

/// The outer vertex the hole's leftmost vertex connects to.
fn find_bridge(rings: &Rings, hole: u32, search: Search) -> Option<u32> {
    let (hx, hy) = (rings.get(hole).x, rings.get(hole).y);
    // The nearest crossing of the ray y = hy, x ≤ hx with an outer edge seen from inside
    // (counter-clockwise, so an edge going down).
    let mut qx = f64::NEG_INFINITY;
    let mut m = NIL;
    let mut touch = NIL;
    for_each_edge(rings, &search, hy, hy, |p| {
        let (n, nn) = (rings.get(p), rings.get(rings.next(p)));
        if nn.y <= hy && hy <= n.y && nn.y != n.y {
            let x = n.x + (hy - n.y) * (nn.x - n.x) / (nn.y - n.y);
            // The hole touches the outer ring at a vertex: bridge there (zero length).
            let vertex = match x == hx {
                true if hy == n.y => p,
                true if hy == nn.y => n.next,
                _ => NIL,
            };
            if x <= hx && x > qx {
                qx = x;
                m = if n.x < nn.x { p } else { n.next };
                touch = vertex;
            } else if x == hx && touch == NIL && vertex != NIL {
                // Another edge through the hole point, at a vertex of it: that one.
                touch = vertex;
            }
        }
    });
    if touch != NIL {
        return Some(touch);
    }
    if m == NIL {
        return None;
    }
    if qx == hx {
        // The hole point lies on an outer edge, between its ends: bridge to its left end (the
        // triangle searched below would have no area).
        return Some(m);
    }
    // A reflex vertex inside triangle (hole point, crossing, endpoint) may hide the endpoint;
    // the visible one is the vertex in there with the smallest angle to the ray.
    let (mx, my) = (rings.get(m).x, rings.get(m).y);
    let mut tan_min = f64::INFINITY;
    let mut best = m;
    let consider = |p: u32| {
        let n = rings.get(p);
        if mx <= n.x && n.x <= hx && hx != n.x && point_in_triangle([hx, hy], [qx, hy], [mx, my], [n.x, n.y]) {
            let tan = (hy - n.y).abs() / (hx - n.x);
            let b = rings.get(best);
            let next = rings.get(n.next);
            // An outer edge along the ray, leading past the hole point, is seen from it too; so is
            // a Steiner point (a spike of no width, inside from every side), which a bridge
            // passing through it would leave out of the mesh.
            let along = n.y == hy && next.y == hy && next.x > hx;
            if (rings.locally_inside(p, hole) || along || rings.marked(p, mark::STEINER))
                && (tan < tan_min
                    || (tan == tan_min && (n.x > b.x || (n.x == b.x && rings.sector_contains_sector(best, p)))))
            {
                best = p;
                tan_min = tan;
            }
        }
    };
    // Walking the ring, start at the endpoint (the sample's order, which decides exact ties).
    let around = match search {
        Search::Ring(_) => Search::Ring(m),
        bands => bands,
    };
    for_each_edge(rings, &around, hy.min(my), hy.max(my), consider);
    Some(best)
}
