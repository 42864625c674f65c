//! The working state of ear slicing: vertex rings as circular doubly-linked lists in one arena
//! (indices, not pointers), plus the geometric predicates the slicer asks of them.
//!
//! Convention: y up, outer rings counter-clockwise, holes clockwise; `area(p, q, r) > 0` is a
//! left turn.

use super::zorder::{ZHash, sort_by_code};

/// "No node".
pub(super) const NIL: u32 = u32::MAX;

/// One vertex of a ring.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node {
    pub x: f64,
    pub y: f64,
    /// Index of the vertex in the caller's vertex array (what triangles refer to).
    pub vertex: u32,
    pub prev: u32,
    pub next: u32,
    /// Its Morton code, once [`Rings::link_z`] put it on a z-order list: the walk over the list
    /// reads code and position from one 32-byte node.
    pub z: u32,
}

/// The z-order list of the ring being sliced, beside the nodes rather than in them: walking it
/// chases one 8-byte link per step, the next address one load away (in the nodes, each step
/// also waited on an index multiplied by the node size).
#[derive(Default)]
pub(super) struct ZList {
    /// Per node: its neighbours on the list, lower code first (NIL at the ends and for nodes
    /// not on it).
    pub links: Vec<[u32; 2]>,
    /// Per node: the last node found blocking its ear (NIL if none yet). Tested first the next
    /// time round, it usually blocks again: one test instead of a walk along the list.
    pub blockers: Vec<u32>,
}

/// Per-node marks, beside the nodes (rarely read, and keeping them out holds a node to 32 bytes).
pub(super) mod mark {
    /// A hole of one point: never filtered away.
    pub const STEINER: u8 = 1;
    /// The node waits in the slicer's queue.
    pub const QUEUED: u8 = 2;
}

/// The node arena (reused between calls).
#[derive(Default)]
pub(super) struct Rings {
    pub nodes: Vec<Node>,
    /// While set, [`Rings::filter`] records here each node whose outgoing edge it changed.
    pub recording: bool,
    pub touched: Vec<u32>,
    /// Per node: its [`mark`] bits.
    pub marks: Vec<u8>,
    /// The z-order list, once [`Rings::link_z`] made one.
    pub z: ZList,
}

/// The lesser of two finite numbers, by a plain comparison (one instruction; `f64::min`'s NaN
/// handling costs several and chains them in loops).
#[inline]
pub(super) fn least(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// The greater of two finite numbers (see [`least`]).
#[inline]
pub(super) fn greatest(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

/// Twice the signed area of triangle (p, q, r): positive when p → q → r turns left.
#[inline]
pub(super) fn area(p: &Node, q: &Node, r: &Node) -> f64 {
    (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x)
}

/// Whether (px, py) lies in or on the triangle (a, b, c), whatever its orientation.
#[inline]
pub(super) fn point_in_triangle(a: [f64; 2], b: [f64; 2], c: [f64; 2], p: [f64; 2]) -> bool {
    let d1 = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
    let d2 = (c[0] - b[0]) * (p[1] - b[1]) - (c[1] - b[1]) * (p[0] - b[0]);
    let d3 = (a[0] - c[0]) * (p[1] - c[1]) - (a[1] - c[1]) * (p[0] - c[0]);
    let negative = d1 < 0.0 || d2 < 0.0 || d3 < 0.0;
    let positive = d1 > 0.0 || d2 > 0.0 || d3 > 0.0;
    !(negative && positive)
}

#[inline]
fn sign(v: f64) -> i8 {
    (v > 0.0) as i8 - (v < 0.0) as i8
}

/// For collinear p, q, r: whether q lies within the bounding box of segment p–r.
#[inline]
fn on_segment(p: &Node, q: &Node, r: &Node) -> bool {
    q.x <= p.x.max(r.x) && q.x >= p.x.min(r.x) && q.y <= p.y.max(r.y) && q.y >= p.y.min(r.y)
}

/// Whether segments p1–q1 and p2–q2 meet (touching and collinear overlap included).
pub(super) fn intersects(p1: &Node, q1: &Node, p2: &Node, q2: &Node) -> bool {
    let o1 = sign(area(p1, q1, p2));
    let o2 = sign(area(p1, q1, q2));
    let o3 = sign(area(p2, q2, p1));
    let o4 = sign(area(p2, q2, q1));
    (o1 != o2 && o3 != o4)
        || (o1 == 0 && on_segment(p1, p2, q1))
        || (o2 == 0 && on_segment(p1, q2, q1))
        || (o3 == 0 && on_segment(p2, p1, q2))
        || (o4 == 0 && on_segment(p2, q1, q2))
}

/// Whether segments p1–q1 and p2–q2 cross at a point inside both (touching does not count).
pub(super) fn crosses(p1: &Node, q1: &Node, p2: &Node, q2: &Node) -> bool {
    let (o1, o2) = (sign(area(p1, q1, p2)), sign(area(p1, q1, q2)));
    let (o3, o4) = (sign(area(p2, q2, p1)), sign(area(p2, q2, q1)));
    o1 * o2 < 0 && o3 * o4 < 0
}

impl Rings {
    /// Forgets every node (keeps the allocation).
    pub fn clear(&mut self) {
        self.nodes.clear();
        self.marks.clear();
        self.z.links.clear();
        self.z.blockers.clear();
    }

    #[inline]
    pub fn get(&self, i: u32) -> &Node {
        debug_assert!((i as usize) < self.nodes.len());
        // SAFETY: every node id the slicer holds came from `insert` (so is below the arena's
        // length), and nodes leave the arena only in `clear`, after which no id is used.
        unsafe { self.nodes.get_unchecked(i as usize) }
    }

    /// Node `i`'s neighbours on the z-order list, lower code first.
    #[inline]
    pub fn z_links(&self, i: u32) -> [u32; 2] {
        debug_assert!((i as usize) < self.z.links.len());
        // SAFETY: as in `get`; `link_z` sizes the links to the arena before any walk.
        unsafe { *self.z.links.get_unchecked(i as usize) }
    }

    /// Whether node `i` carries mark `bit`.
    #[inline]
    pub fn marked(&self, i: u32, bit: u8) -> bool {
        self.marks[i as usize] & bit != 0
    }

    /// Sets or clears mark `bit` of node `i`.
    #[inline]
    pub fn set_mark(&mut self, i: u32, bit: u8, on: bool) {
        let m = &mut self.marks[i as usize];
        *m = if on { *m | bit } else { *m & !bit };
    }

    #[inline]
    pub fn next(&self, i: u32) -> u32 {
        self.get(i).next
    }

    #[inline]
    pub fn prev(&self, i: u32) -> u32 {
        self.get(i).prev
    }

    /// Calls `visit` with every node of the ring of `start`, in ring order.
    pub fn for_each_node(&self, start: u32, mut visit: impl FnMut(u32)) {
        let mut p = start;
        loop {
            visit(p);
            p = self.next(p);
            if p == start {
                break;
            }
        }
    }

    /// Twice the signed area of the triangle of three nodes.
    #[inline]
    pub fn area(&self, p: u32, q: u32, r: u32) -> f64 {
        area(self.get(p), self.get(q), self.get(r))
    }

    /// Whether a node is still linked into a ring.
    #[inline]
    pub fn alive(&self, p: u32) -> bool {
        self.prev(self.next(p)) == p
    }

    /// Whether every corner of the ring of `start` turns strictly left.
    pub fn is_convex(&self, start: u32) -> bool {
        let mut p = start;
        loop {
            let n = self.get(p);
            if area(self.get(n.prev), n, self.get(n.next)) <= 0.0 {
                return false;
            }
            p = n.next;
            if p == start {
                return true;
            }
        }
    }

    /// Whether two nodes sit at the same position.
    #[inline]
    pub fn equals(&self, a: u32, b: u32) -> bool {
        let (a, b) = (self.get(a), self.get(b));
        a.x == b.x && a.y == b.y
    }

    /// Appends a node for `vertex` after `last` (or as a ring of one) and returns it.
    fn insert(&mut self, vertex: u32, [x, y]: [f64; 2], last: u32) -> u32 {
        let id = self.nodes.len() as u32;
        let mut node = Node { x, y, vertex, prev: id, next: id, z: 0 };
        if last != NIL {
            node.prev = last;
            node.next = self.next(last);
            let after = node.next;
            self.nodes[after as usize].prev = id;
            self.nodes[last as usize].next = id;
        }
        self.nodes.push(node);
        self.marks.push(0);
        id
    }

    /// Unlinks a node from its ring and its z-order list (it keeps its own links).
    #[inline]
    pub fn remove(&mut self, p: u32) {
        let Node { prev, next, .. } = *self.get(p);
        self.nodes[next as usize].prev = prev;
        self.nodes[prev as usize].next = next;
        if (p as usize) < self.z.links.len() {
            self.unlink_z(p);
        }
    }

    /// Takes node `p` off the z-order list: its neighbours there join up (`p` keeps its links).
    fn unlink_z(&mut self, p: u32) {
        let [down, up] = self.z.links[p as usize];
        if down != NIL {
            self.z.links[down as usize][1] = up;
        }
        if up != NIL {
            self.z.links[up as usize][0] = down;
        }
    }

    /// Gives every node of the arena a z-order link pair and blocker slot (NIL for new ones).
    fn size_z(&mut self) {
        self.z.links.resize(self.nodes.len(), [NIL; 2]);
        self.z.blockers.resize(self.nodes.len(), NIL);
    }

    /// Puts the nodes of the ring of `start` on a z-order list of their own, sorted by code
    /// (`keys` and `scratch` are scratch space); returns the ring's size. Nodes of other rings
    /// keep their links.
    pub fn link_z(&mut self, start: u32, hash: &ZHash, keys: &mut Vec<u64>, scratch: &mut Vec<u64>) -> usize {
        self.size_z();
        keys.clear();
        let mut p = start;
        loop {
            let node = &mut self.nodes[p as usize];
            let z = hash.z(node.x, node.y);
            node.z = z;
            self.z.blockers[p as usize] = NIL;
            keys.push((u64::from(z) << 32) | u64::from(p));
            p = node.next;
            if p == start {
                break;
            }
        }
        sort_by_code(keys, scratch);
        let mut before = NIL;
        for &key in keys.iter() {
            let p = key as u32;
            self.z.links[p as usize][0] = before;
            if before != NIL {
                self.z.links[before as usize][1] = p;
            }
            before = p;
        }
        self.z.links[before as usize][1] = NIL;
        keys.len()
    }

    /// Puts `copy` (a new node at `original`'s position) on the z-order list right after
    /// `original`, with its code.
    pub fn z_insert_copy(&mut self, original: u32, copy: u32) {
        self.size_z();
        self.nodes[copy as usize].z = self.nodes[original as usize].z;
        let up = self.z.links[original as usize][1];
        self.z.links[copy as usize] = [original, up];
        self.z.links[original as usize][1] = copy;
        if up != NIL {
            self.z.links[up as usize][0] = copy;
        }
    }

    /// Takes every node of the ring of `start` off the z-order list (their links become NIL).
    pub fn z_unlink_ring(&mut self, start: u32) {
        let mut p = start;
        loop {
            self.unlink_z(p);
            self.z.links[p as usize] = [NIL; 2];
            p = self.next(p);
            if p == start {
                return;
            }
        }
    }

    /// Whether the ring of `a` has at most as many nodes as the ring of `b` (walking both in
    /// step, so the cost is the smaller ring's size).
    pub fn smaller_ring(&self, a: u32, b: u32) -> bool {
        let (mut p, mut q) = (self.next(a), self.next(b));
        loop {
            if p == a {
                return true;
            }
            if q == b {
                return false;
            }
            (p, q) = (self.next(p), self.next(q));
        }
    }

    /// Links `points` (vertex index, position) into a ring that runs counter-clockwise when
    /// `ccw` (clockwise otherwise), whatever their input order. Repeated points stay, as in
    /// earcut, for the filters to take: dropped here, a hole that repeats its leftmost point
    /// was bridged and healed otherwise than earcut's, and on crossing input (water-huge) cut
    /// elsewhere. `signed_area` is the ring's shoelace area (positive = counter-clockwise).
    /// Returns a node of the ring, or NIL when there were no points.
    pub fn link_ring(&mut self, vertices: &[[f64; 2]], first_vertex: u32, signed_area: f64, ccw: bool) -> u32 {
        // Built in one go: node k of the ring is node `first + k` of the arena, its
        // neighbours known as it is pushed (inserting one by one cost a tenth of a small
        // polygon's time).
        let first = self.nodes.len() as u32;
        let mut push = |i: usize| {
            let [x, y] = vertices[i];
            let id = self.nodes.len() as u32;
            self.nodes.push(Node {
                x,
                y,
                vertex: first_vertex + i as u32,
                prev: id.wrapping_sub(1),
                next: id + 1,
                z: 0,
            });
        };
        if (signed_area > 0.0) == ccw {
            (0..vertices.len()).for_each(&mut push);
        } else {
            (0..vertices.len()).rev().for_each(&mut push);
        }
        let end = self.nodes.len() as u32;
        if end == first {
            return NIL;
        }
        let mut last = end - 1;
        // A closing point equal to the first goes; the ring then starts at the first point.
        let closed = last != first && self.equals(last, first);
        if closed {
            self.nodes.pop();
            last -= 1;
        }
        self.nodes[first as usize].prev = last;
        self.nodes[last as usize].next = first;
        self.marks.resize(self.nodes.len(), 0);
        if closed { first } else { last }
    }

    /// Removes repeated points and collinear runs from `start` up to `end` (the whole ring when
    /// `end` is NIL); returns a node still on the ring. A partial filter stays local: after a
    /// removal it looks back one node and goes on towards `end`, rather than around the whole
    /// ring (which made each of a bridge's tidy-ups O(n): a third of the time on 443 holes).
    pub fn filter(&mut self, start: u32, end: u32) -> u32 {
        self.filter_changed(start, end).0
    }

    /// [`Rings::filter`], and whether it removed anything.
    pub fn filter_changed(&mut self, start: u32, end: u32) -> (u32, bool) {
        if start == NIL {
            return (start, false);
        }
        let full = end == NIL;
        let mut removed = false;
        let mut end = if full { start } else { end };
        let mut p = start;
        loop {
            let next = self.next(p);
            let prev = self.prev(p);
            let removable = p != next
                && (self.equals(p, next) || self.area(prev, p, next) == 0.0)
                && !self.marked(p, mark::STEINER);
            let again = if removable {
                if full || p == end {
                    end = prev;
                }
                self.remove(p);
                removed = true;
                if self.recording {
                    self.touched.push(prev);
                }
                p = prev;
                true
            } else if full || p != end {
                p = next;
                !full
            } else {
                false
            };
            if !again && p == end {
                return (end, removed);
            }
        }
    }

    /// Cuts the ring along the diagonal a–b into two rings, duplicating a and b; returns the
    /// copy of b, a node of the second ring (a stays on the first).
    pub fn split(&mut self, a: u32, b: u32) -> u32 {
        let (an, bp) = (self.next(a), self.prev(b));
        let a2 = self.insert(self.get(a).vertex, [self.get(a).x, self.get(a).y], NIL);
        let b2 = self.insert(self.get(b).vertex, [self.get(b).x, self.get(b).y], NIL);
        let n = &mut self.nodes;
        n[a as usize].next = b;
        n[b as usize].prev = a;
        n[a2 as usize].next = an;
        n[an as usize].prev = a2;
        n[b2 as usize].next = a2;
        n[a2 as usize].prev = b2;
        n[bp as usize].next = b2;
        n[b2 as usize].prev = bp;
        b2
    }

    /// Whether the diagonal from a towards b starts into the polygon's interior at a.
    pub fn locally_inside(&self, a: u32, b: u32) -> bool {
        let (ap, an) = (self.prev(a), self.next(a));
        if self.area(ap, a, an) > 0.0 {
            self.area(a, b, an) <= 0.0 && self.area(a, ap, b) <= 0.0
        } else {
            self.area(a, b, ap) > 0.0 || self.area(a, an, b) > 0.0
        }
    }

    /// Whether the midpoint of a–b is inside the ring of a (even–odd crossing count).
    pub fn middle_inside(&self, a: u32, b: u32) -> bool {
        let (na, nb) = (self.get(a), self.get(b));
        let (px, py) = ((na.x + nb.x) / 2.0, (na.y + nb.y) / 2.0);
        let mut inside = false;
        let mut p = a;
        loop {
            let (n, nn) = (self.get(p), self.get(self.next(p)));
            if (n.y > py) != (nn.y > py) && nn.y != n.y && px < (nn.x - n.x) * (py - n.y) / (nn.y - n.y) + n.x {
                inside = !inside;
            }
            p = n.next;
            if p == a {
                return inside;
            }
        }
    }

    /// Whether segment a–b crosses an edge of a's ring that does not end at a or b. The edges
    /// that start at `hints` (nodes, or NIL) are tried first, and an edge found crossing joins
    /// them: the split's search tries diagonal after diagonal from one node, and an edge that
    /// crossed a recent one most often crosses the next (a walk of the whole ring each time was
    /// half the time on crossing input).
    pub fn intersects_ring(&self, a: u32, b: u32, hints: &mut [u32; 4]) -> bool {
        let (na, nb) = (self.get(a), self.get(b));
        let (va, vb) = (na.vertex, nb.vertex);
        let (x0, x1) = (least(na.x, nb.x), greatest(na.x, nb.x));
        let (y0, y1) = (least(na.y, nb.y), greatest(na.y, nb.y));
        let crosses_edge = |p: u32| {
            let np = self.get(p);
            let nq = self.get(np.next);
            // Edges whose box misses the segment's box cannot touch it.
            let overlaps = greatest(np.x, nq.x) >= x0
                && least(np.x, nq.x) <= x1
                && greatest(np.y, nq.y) >= y0
                && least(np.y, nq.y) <= y1;
            overlaps
                && np.vertex != va
                && nq.vertex != va
                && np.vertex != vb
                && nq.vertex != vb
                && intersects(np, nq, na, nb)
        };
        // The caller keeps the hints for one search on an unchanged ring: edges of it.
        if hints.iter().any(|&h| h != NIL && crosses_edge(h)) {
            return true;
        }
        let mut p = a;
        loop {
            if crosses_edge(p) {
                hints.rotate_right(1);
                hints[0] = p;
                return true;
            }
            p = self.next(p);
            if p == a {
                return false;
            }
        }
    }

    /// Whether a–b is a diagonal that splits the ring into two valid rings. The O(1) tests run
    /// before the two that walk the ring; `hints` as in [`Rings::intersects_ring`].
    pub fn is_valid_diagonal(&self, a: u32, b: u32, hints: &mut [u32; 4]) -> bool {
        let (na, nb) = (self.get(a), self.get(b));
        if self.get(na.next).vertex == nb.vertex || self.get(na.prev).vertex == nb.vertex {
            return false;
        }
        // Both sectors must not face each other across a zero-area spike.
        let not_opposite = self.area(na.prev, a, nb.prev) != 0.0 || self.area(a, nb.prev, b) != 0.0;
        let locally = not_opposite && self.locally_inside(a, b) && self.locally_inside(b, a);
        // Two reflex copies of one point may always be joined.
        let zero_length =
            self.equals(a, b) && self.area(na.prev, a, na.next) < 0.0 && self.area(nb.prev, b, nb.next) < 0.0;
        if !(locally || zero_length) || self.intersects_ring(a, b, hints) {
            return false;
        }
        zero_length || self.middle_inside(a, b)
    }

    /// Whether the sector at `p` lies inside the sector at `m` (two nodes at one position).
    pub fn sector_contains_sector(&self, m: u32, p: u32) -> bool {
        self.area(self.prev(m), m, self.prev(p)) > 0.0 && self.area(self.next(p), m, self.next(m)) > 0.0
    }
}

/// Shoelace signed area of a ring (positive = counter-clockwise), summed in a form that keeps
/// precision for coordinates far from the origin.
pub(super) fn signed_area(vertices: &[[f64; 2]]) -> f64 {
    let Some(&last) = vertices.last() else { return 0.0 };
    let mut sum = 0.0;
    let mut j = last;
    for &i in vertices {
        sum += (j[0] - i[0]) * (j[1] + i[1]);
        j = i;
    }
    sum / 2.0
}
