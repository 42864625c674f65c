//! Ear slicing of one linked ring (an outer ring with its holes already bridged in), after
//! Eberly's ear clipping and Held's FIST as refined in mapbox's earcut: ears are taken as found
//! walking the ring, the next search starts two nodes on (fewer slivers than the sample's FIFO),
//! and, above [`HASH_THRESHOLD`] vertices, the "no vertex inside the ear" test only visits nodes
//! whose z-order code falls in the ear's bounding box. Rings that stop yielding ears go through
//! three fallbacks: drop collinear/repeated points, cut off local self-intersections, split along
//! any valid diagonal.

use super::linked::{NIL, Node, Rings, area, point_in_triangle};

/// Rings with more vertices than this use the z-order hash (below it, a plain walk is faster).
pub(super) const HASH_THRESHOLD: usize = 80;

/// Quantisation of positions to the 15-bit grid the Morton codes are built on.
#[derive(Clone, Copy, Debug)]
pub(super) struct ZHash {
    pub min_x: f64,
    pub min_y: f64,
    /// 32767 / the larger side of the bounding box (0 for a box of no size).
    pub inv_size: f64,
}

impl ZHash {
    /// The hash for points in the box from `min` to `max`.
    pub fn new(min: [f64; 2], max: [f64; 2]) -> Self {
        let size = (max[0] - min[0]).max(max[1] - min[1]);
        Self { min_x: min[0], min_y: min[1], inv_size: if size > 0.0 { 32767.0 / size } else { 0.0 } }
    }

    /// Morton code of a position (clamped, so points outside the box still order monotonically).
    #[inline]
    pub fn z(&self, x: f64, y: f64) -> u32 {
        let q = |v: f64, min: f64| ((v - min) * self.inv_size).clamp(0.0, 32767.0) as u32;
        spread(q(x, self.min_x)) | (spread(q(y, self.min_y)) << 1)
    }
}

/// Spreads the low 16 bits of `v` to the even bit positions.
#[inline]
fn spread(mut v: u32) -> u32 {
    v = (v | (v << 8)) & 0x00FF_00FF;
    v = (v | (v << 4)) & 0x0F0F_0F0F;
    v = (v | (v << 2)) & 0x3333_3333;
    (v | (v << 1)) & 0x5555_5555
}

/// A convex corner (a, b, c) tested as an ear, with its bounding box.
struct Corner<'a> {
    a: &'a Node,
    b: &'a Node,
    c: &'a Node,
    min: [f64; 2],
    max: [f64; 2],
}

/// Which fallback a ring is on.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Pass {
    Ears,
    Filtered,
    Cured,
}

/// Slices rings into triangles, appending vertex-index triples (counter-clockwise) to `out`.
pub(super) struct Slicer<'a> {
    pub rings: &'a mut Rings,
    pub hash: Option<ZHash>,
    pub out: &'a mut Vec<u32>,
    /// Reused buffer for sorting nodes by Morton code.
    pub scratch: &'a mut Vec<u64>,
    /// Reused stack of rings still to slice.
    pub jobs: &'a mut Vec<(u32, Pass)>,
}

impl Slicer<'_> {
    /// Triangulates the ring of `start` completely (or as far as the fallbacks get).
    pub fn run(&mut self, start: u32) {
        // An explicit stack instead of recursion: degenerate input can split many times.
        let mut jobs = std::mem::take(self.jobs);
        jobs.clear();
        jobs.push((start, Pass::Ears));
        while let Some((ring, pass)) = jobs.pop() {
            self.slice(ring, pass, &mut jobs);
        }
        *self.jobs = jobs;
    }

    fn slice(&mut self, start: u32, pass: Pass, jobs: &mut Vec<(u32, Pass)>) {
        if start == NIL {
            return;
        }
        if pass == Pass::Ears && self.hash.is_some() {
            self.index_curve(start);
        }
        let mut ear = start;
        let mut stop = ear;
        while self.rings.prev(ear) != self.rings.next(ear) {
            let (prev, next) = (self.rings.prev(ear), self.rings.next(ear));
            let is_ear = if self.hash.is_some() { self.is_ear_hashed(ear) } else { self.is_ear(ear) };
            if is_ear {
                self.emit(prev, ear, next);
                self.rings.remove(ear);
                // Skip the next vertex: clipping from the same spot again makes fans of slivers.
                ear = self.rings.next(next);
                stop = ear;
                continue;
            }
            ear = next;
            if ear == stop {
                match pass {
                    Pass::Ears => jobs.push((self.rings.filter(ear, NIL), Pass::Filtered)),
                    Pass::Filtered => {
                        let filtered = self.rings.filter(ear, NIL);
                        let cured = self.cure_local_intersections(filtered);
                        jobs.push((cured, Pass::Cured));
                    }
                    Pass::Cured => self.split(ear, jobs),
                }
                return;
            }
        }
    }

    /// Emits triangle (a, b, c), turned counter-clockwise if the fallbacks produced it clockwise;
    /// a triangle of no area covers nothing and is left out.
    fn emit(&mut self, a: u32, b: u32, c: u32) {
        let (va, vb, vc) = (self.rings.get(a).vertex, self.rings.get(b).vertex, self.rings.get(c).vertex);
        let area = self.rings.area(a, b, c);
        if area < 0.0 {
            self.out.extend_from_slice(&[va, vc, vb]);
        } else if area > 0.0 {
            self.out.extend_from_slice(&[va, vb, vc]);
        }
    }

    /// The convex corner at `ear` as a candidate ear; `None` if reflex or flat.
    #[inline]
    fn corner(&self, ear: u32) -> Option<Corner<'_>> {
        let r = &*self.rings;
        let (a, b, c) = (r.get(r.prev(ear)), r.get(ear), r.get(r.next(ear)));
        (area(a, b, c) > 0.0).then(|| Corner {
            a,
            b,
            c,
            min: [a.x.min(b.x).min(c.x), a.y.min(b.y).min(c.y)],
            max: [a.x.max(b.x).max(c.x), a.y.max(b.y).max(c.y)],
        })
    }

    /// Whether node `p` blocks the ear: it lies in or on the triangle (bounding box first), is
    /// not a copy of a (bridges duplicate points), and is reflex or flat — only those can poke
    /// into an ear.
    #[inline]
    fn blocks(&self, ear: &Corner<'_>, p: u32) -> bool {
        let n = self.rings.get(p);
        let (a, b, c) = (ear.a, ear.b, ear.c);
        n.x >= ear.min[0]
            && n.x <= ear.max[0]
            && n.y >= ear.min[1]
            && n.y <= ear.max[1]
            && !(n.x == a.x && n.y == a.y)
            && point_in_triangle([a.x, a.y], [b.x, b.y], [c.x, c.y], [n.x, n.y])
            && area(self.rings.get(n.prev), n, self.rings.get(n.next)) <= 0.0
    }

    fn is_ear(&self, ear: u32) -> bool {
        let Some(corner) = self.corner(ear) else { return false };
        let mut p = corner.c.next;
        while p != corner.b.prev {
            if self.blocks(&corner, p) {
                return false;
            }
            p = self.rings.next(p);
        }
        true
    }

    fn is_ear_hashed(&self, ear: u32) -> bool {
        let Some(corner) = self.corner(ear) else { return false };
        let r = &*self.rings;
        let (ia, ic) = (corner.b.prev, corner.b.next);
        let hash = self.hash.expect("hashed ear test without a hash");
        let (min_z, max_z) = (hash.z(corner.min[0], corner.min[1]), hash.z(corner.max[0], corner.max[1]));
        let candidate = |p: u32| p != ia && p != ic && self.blocks(&corner, p);
        // Walk the z-order list both ways from the ear, alternating, while codes stay in range.
        let (mut p, mut n) = (corner.b.prev_z, corner.b.next_z);
        while p != NIL && r.get(p).z >= min_z && n != NIL && r.get(n).z <= max_z {
            if candidate(p) || candidate(n) {
                return false;
            }
            p = r.get(p).prev_z;
            n = r.get(n).next_z;
        }
        while p != NIL && r.get(p).z >= min_z {
            if candidate(p) {
                return false;
            }
            p = r.get(p).prev_z;
        }
        while n != NIL && r.get(n).z <= max_z {
            if candidate(n) {
                return false;
            }
            n = r.get(n).next_z;
        }
        true
    }

    /// Computes Morton codes for the ring of `start` and links its nodes in code order.
    fn index_curve(&mut self, start: u32) {
        let hash = self.hash.expect("indexing without a hash");
        self.scratch.clear();
        let mut p = start;
        loop {
            let node = &mut self.rings.nodes[p as usize];
            node.z = hash.z(node.x, node.y);
            self.scratch.push((u64::from(node.z) << 32) | u64::from(p));
            p = node.next;
            if p == start {
                break;
            }
        }
        self.scratch.sort_unstable();
        let mut prev = NIL;
        for &key in self.scratch.iter() {
            let id = key as u32;
            self.rings.nodes[id as usize].prev_z = prev;
            if prev != NIL {
                self.rings.nodes[prev as usize].next_z = id;
            }
            prev = id;
        }
        if prev != NIL {
            self.rings.nodes[prev as usize].next_z = NIL;
        }
    }

    /// Where a ring crosses itself locally (a–p and p.next–b cross), cuts off triangle
    /// (a, p, b) and drops p and p.next.
    fn cure_local_intersections(&mut self, start: u32) -> u32 {
        if start == NIL {
            return start;
        }
        let mut start = start;
        let mut p = start;
        loop {
            let r = &*self.rings;
            let (a, pn) = (r.prev(p), r.next(p));
            let b = r.next(pn);
            if !r.equals(a, b)
                && super::linked::intersects(r.get(a), r.get(p), r.get(pn), r.get(b))
                && r.locally_inside(a, b)
                && r.locally_inside(b, a)
            {
                self.emit(a, p, b);
                self.rings.remove(p);
                self.rings.remove(pn);
                p = b;
                start = b;
            }
            p = self.rings.next(p);
            if p == start || self.rings.next(p) == p {
                break;
            }
        }
        self.rings.filter(p, NIL)
    }

    /// Splits the ring along the first valid diagonal found and queues both halves.
    fn split(&mut self, start: u32, jobs: &mut Vec<(u32, Pass)>) {
        let mut a = start;
        loop {
            let mut b = self.rings.next(self.rings.next(a));
            while b != self.rings.prev(a) {
                if self.rings.get(a).vertex != self.rings.get(b).vertex && self.rings.is_valid_diagonal(a, b) {
                    let c = self.rings.split(a, b);
                    let a = self.rings.filter(a, self.rings.next(a));
                    let c = self.rings.filter(c, self.rings.next(c));
                    jobs.push((a, Pass::Ears));
                    jobs.push((c, Pass::Ears));
                    return;
                }
                b = self.rings.next(b);
            }
            a = self.rings.next(a);
            if a == start {
                return;
            }
        }
    }
}
