//! Ear slicing of one linked ring (an outer ring with its holes already bridged in), after
//! Eberly's ear clipping and Held's FIST as refined in mapbox's earcut, in two ways:
//!
//! - First earcut's: walk round the ring clipping every ear met, and, above
//!   [`HASH_THRESHOLD`] vertices, test "no vertex inside the ear" only on the nodes of a linked
//!   z-order list whose codes lie between those of the ear box's corners.
//! - When the walk has spent its budget (see [`WALK_STEPS_PER_NODE`]), from a queue of corners
//!   (the neighbours of clipped ears) with a sorted z-order index that jumps over code ranges
//!   outside the ear's box (BIGMIN): near-linear where the walk and the list grow
//!   quadratically (long reflex stretches, the thin ears of spikes).
//!
//! Rings that stop yielding ears go through three fallbacks: drop collinear/repeated points,
//! cut off local self-intersections, split along any valid diagonal.

use std::collections::VecDeque;

use super::linked::{NIL, Node, Rings, area, greatest, least, mark};
use super::zorder::{ZHash, ZIndex, bigmin, box_codes, code, in_box};

/// Rings with more vertices than this use the z-order hash (below it, a plain walk is faster).
pub(super) const HASH_THRESHOLD: usize = 80;

/// Nodes the walk may visit per node of the ring before it hands the ring to the queue: z-order
/// list steps, and two for each corner visited (it reads three nodes). About 33 on real outlines
/// (water, 2,523 vertices), thousands on the thin ears of a spiky star, where the walk took
/// 0.16 s at 25,000 points (0.015 s with this budget). Corners count twice since the blocker
/// cache (see `is_ear_linked`) made most list walks one test: counted once, crossing input
/// (water-huge2) stayed in the walk through dozens of stuck rounds, 10% slower. At 64, one of
/// water-huge2's stuck rings went to the queue, whose other order of ears covered 0.0025 too
/// much where earcut's walk (and ours at 96) covers 0.0022.
const WALK_STEPS_PER_NODE: usize = 96;

/// Nodes of a ring that get the full [`WALK_STEPS_PER_NODE`]; each node beyond adds
/// [`WALK_STEPS_PER_LARGE_NODE`]. On a 10⁶-point star or wavy ring the walk is wasted work
/// before the queue takes over (96 a node cost 0.4 s of 1.1); on a checkerboard of touching
/// holes the walk is what works: the queue's order of ears left rings where no corner was an
/// ear, and splitting those took 25 s on 130 × 130 squares (with this budget, 0.5 s, exact;
/// earcut 0.9 s).
const WALK_FULL_BUDGET_NODES: usize = 1 << 15;

/// The walk's budget per node beyond [`WALK_FULL_BUDGET_NODES`].
const WALK_STEPS_PER_LARGE_NODE: usize = 8;

/// How many nodes the walk may visit on a ring before the queue takes it over (by default
/// [`WALK_STEPS_PER_NODE`] and [`WALK_STEPS_PER_LARGE_NODE`] a node, plus 4,096).
#[derive(Clone, Copy)]
pub(super) struct WalkBudget {
    per_node: usize,
    per_large_node: usize,
    base: usize,
}

impl WalkBudget {
    /// No walk on hashed rings: every one goes to the queue at once (tests of the queue).
    #[cfg(test)]
    pub const NONE: Self = Self { per_node: 0, per_large_node: 0, base: 0 };

    fn for_ring(self, size: usize) -> usize {
        let full = size.min(WALK_FULL_BUDGET_NODES);
        self.per_node * full + self.per_large_node * (size - full) + self.base
    }
}

impl Default for WalkBudget {
    fn default() -> Self {
        Self { per_node: WALK_STEPS_PER_NODE, per_large_node: WALK_STEPS_PER_LARGE_NODE, base: 4096 }
    }
}

/// A counter-clockwise triangle (a, b, c): a convex corner tested as an ear.
#[derive(Clone, Copy)]
struct Triangle {
    a: [f64; 2],
    b: [f64; 2],
    c: [f64; 2],
}

impl Triangle {
    /// Whether a point lies in or on the triangle and is not a copy of a (bridges duplicate
    /// points).
    #[inline]
    fn holds(&self, p: [f64; 2]) -> bool {
        // Left of (or on) each edge in turn, most points failing the first or second test.
        let left = |s: [f64; 2], e: [f64; 2]| (e[0] - s[0]) * (p[1] - s[1]) >= (e[1] - s[1]) * (p[0] - s[0]);
        left(self.a, self.b) && left(self.b, self.c) && left(self.c, self.a) && p != self.a
    }
}

/// A convex corner tested as an ear, with its bounding box.
#[derive(Clone, Copy)]
struct Corner {
    triangle: Triangle,
    min: [f64; 2],
    max: [f64; 2],
}

impl Corner {
    /// The corner (a, b, c) as a candidate ear; `None` if reflex or flat.
    #[inline]
    fn of(a: &Node, b: &Node, c: &Node) -> Option<Self> {
        (area(a, b, c) > 0.0).then(|| Self {
            triangle: Triangle { a: [a.x, a.y], b: [b.x, b.y], c: [c.x, c.y] },
            min: [min3(a.x, b.x, c.x), min3(a.y, b.y, c.y)],
            max: [max3(a.x, b.x, c.x), max3(a.y, b.y, c.y)],
        })
    }

    /// Whether a point lies in or on the triangle (bounding box first) and is not a copy of a
    /// (bridges duplicate points).
    #[inline]
    fn covers(&self, [x, y]: [f64; 2]) -> bool {
        x >= self.min[0] && x <= self.max[0] && y >= self.min[1] && y <= self.max[1] && self.triangle.holds([x, y])
    }

    /// Whether the whole box lies strictly outside the triangle, beyond one of its edges (the
    /// corner is counter-clockwise: inside is left of every edge).
    #[inline]
    fn misses_box(&self, lo: [f64; 2], hi: [f64; 2]) -> bool {
        let beyond = |p: [f64; 2], q: [f64; 2]| {
            let (ex, ey) = (q[0] - p[0], q[1] - p[1]);
            // The box corner furthest to the left of p → q.
            let (x, y) = (if ey > 0.0 { lo[0] } else { hi[0] }, if ex > 0.0 { hi[1] } else { lo[1] });
            ex * (y - p[1]) - ey * (x - p[0]) < 0.0
        };
        let Triangle { a, b, c } = self.triangle;
        beyond(a, b) || beyond(b, c) || beyond(c, a)
    }

    /// The last code of the largest aligned cell (2 × 2 grid steps or more) that holds code `z`
    /// and lies wholly outside the ear, if any. Cells nest, so the first that touches the ear
    /// ends the search.
    fn outside_cell(&self, hash: &ZHash, z: u32) -> Option<u32> {
        let mut end = None;
        for k in 1..15 {
            match hash.cell(z, k) {
                Some((lo, hi, last)) if self.misses_box(lo, hi) => end = Some(last),
                _ => break,
            }
        }
        end
    }
}

/// The least of three finite numbers.
#[inline]
fn min3(a: f64, b: f64, c: f64) -> f64 {
    least(least(a, b), c)
}

/// The greatest of three finite numbers.
#[inline]
fn max3(a: f64, b: f64, c: f64) -> f64 {
    greatest(greatest(a, b), c)
}

/// What the linked ear test found at a corner.
enum Verdict {
    Ear,
    /// Reflex or flat: no ear whatever lies near.
    Reflex,
    /// Convex, but this node lies in or on the triangle.
    BlockedBy(u32),
}

/// How a ring waiting to be sliced is to be sliced.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Pass {
    /// Walking round it, earcut's way.
    Walk,
    /// From the queue: the walk spent its budget on it.
    Queue,
}

/// Slices rings into triangles, appending vertex-index triples (counter-clockwise) to `out`.
pub(super) struct Slicer<'a> {
    pub rings: &'a mut Rings,
    pub hash: Option<ZHash>,
    pub walk_budget: WalkBudget,
    pub out: &'a mut Vec<u32>,
    /// The ring's nodes by Morton code, for jumps into the z-order list; reused between calls.
    pub index: &'a mut ZIndex,
    /// Reused stack of rings still to slice.
    pub jobs: &'a mut Vec<(u32, Pass)>,
    /// Reused queue of corners to test.
    pub queue: &'a mut VecDeque<u32>,
}

impl Slicer<'_> {
    /// Triangulates the ring of `start` completely (or as far as the fallbacks get).
    pub fn run(&mut self, start: u32) {
        // An explicit stack instead of recursion: degenerate input can split many times.
        let mut jobs = std::mem::take(self.jobs);
        jobs.clear();
        jobs.push((start, Pass::Walk));
        while let Some((ring, pass)) = jobs.pop() {
            self.slice(ring, pass, &mut jobs);
        }
        *self.jobs = jobs;
    }

    /// Clips ears of the ring of `start` until three nodes are left or none is found: by
    /// [`Self::walk`], or from a queue once the walk has spent its budget on the ring. The queue
    /// tests first the whole ring in order, then only the neighbours of clipped ears (the only
    /// corners whose shape changed), with a whole round again whenever the queue runs dry after
    /// a clip (a corner can also become an ear when the last reflex node inside it goes).
    /// Walking the ring round after round instead (earcut) costs a pass over every long reflex
    /// stretch per round: 512 million steps for a wavy 10⁶-gon. A ring on which the queue finds
    /// no ear goes through a fallback (see [`Self::fall_back`]) and back to the walk.
    fn slice(&mut self, start: u32, pass: Pass, jobs: &mut Vec<(u32, Pass)>) {
        if start == NIL {
            return;
        }
        if pass == Pass::Walk {
            self.walk(start, jobs);
            return;
        }
        // Built afresh each time: the walk's fallbacks may have cut the ring since.
        self.index_curve(start);
        let mut queue = std::mem::take(self.queue);
        queue.clear();
        let mut size = self.enqueue_ring(start, &mut queue);
        let (mut clipped, mut last, mut skip) = (false, start, NIL);
        while size > 2 {
            let Some(ear) = queue.pop_front() else {
                if !clipped {
                    self.fall_back(last, jobs);
                    break;
                }
                clipped = false;
                self.enqueue_ring(last, &mut queue);
                continue;
            };
            self.rings.set_mark(ear, mark::QUEUED, false);
            if !self.rings.alive(ear) {
                continue;
            }
            if std::mem::replace(&mut skip, NIL) == ear {
                // Not right after its neighbour: clipping from the same spot again makes fans
                // of slivers (without this, a 10⁶-point spiky star took 2.1 s instead of 0.75,
                // and 100 × 100 touching squares, whose rings reach the queue, 0.87 s instead
                // of 0.17).
                self.enqueue(ear, &mut queue);
                continue;
            }
            let (prev, next) = (self.rings.prev(ear), self.rings.next(ear));
            let is_ear = if self.hash.is_some() { self.is_ear_hashed(ear) } else { self.is_ear(ear) };
            if is_ear {
                self.emit_ear(prev, ear, next);
                self.rings.remove(ear);
                size -= 1;
                (clipped, last, skip) = (true, next, next);
                self.enqueue(prev, &mut queue);
                self.enqueue(next, &mut queue);
            }
        }
        *self.queue = queue;
    }

    /// [`Self::slice`] as earcut does it: round the ring
    /// from `start`, clipping each ear met and going on from its next neighbour, whose corner
    /// just changed (the `earcut` crate's way: the same triangles as earcut on rings bridged
    /// alike, and a fifth faster on water-huge than going on two nodes further, mapbox's way,
    /// which leaves that corner for the next round); a whole round
    /// without a clip drops collinear and repeated points and goes on if any went, else cures
    /// local crossings once, else splits the ring. On a few thousand nodes the queue's
    /// bookkeeping cost more than the rounds. A strictly convex ring (found in one pass) is
    /// clipped without ear tests until a corner fails.
    fn walk(&mut self, start: u32, jobs: &mut Vec<(u32, Pass)>) {
        let hash = self.hash;
        let size = match &hash {
            Some(hash) => self.rings.link_z(start, hash, &mut self.index.keys, &mut self.index.scratch),
            None => 0,
        };
        // Nodes visited (see WALK_STEPS_PER_NODE) before the ring goes to the queue instead
        // (hashed rings only: below the hash threshold the walk is cheap whatever it does).
        let budget = self.walk_budget.for_ring(size);
        let mut steps = 0;
        let mut convex = hash.is_some() && self.rings.is_convex(start);
        let (mut ear, mut stop, mut cured) = (start, start, false);
        loop {
            let (prev, next) = (self.rings.prev(ear), self.rings.next(ear));
            if prev == next {
                return;
            }
            steps += 2;
            let is_ear = match &hash {
                _ if convex => self.rings.area(prev, ear, next) > 0.0,
                Some(_) if steps > budget => {
                    jobs.push((ear, Pass::Queue));
                    return;
                }
                Some(_) => match self.is_ear_linked(ear, &mut steps) {
                    Verdict::Ear => true,
                    Verdict::Reflex => false,
                    Verdict::BlockedBy(p) => {
                        self.rings.z.blockers[ear as usize] = p;
                        false
                    }
                },
                None => self.is_ear(ear),
            };
            if is_ear {
                self.emit_ear(prev, ear, next);
                self.rings.remove(ear);
                (ear, stop) = (next, next);
                continue;
            }
            convex = false;
            ear = next;
            if ear != stop {
                continue;
            }
            let (filtered, changed) = self.rings.filter_changed(ear, NIL);
            (ear, stop) = (filtered, filtered);
            if changed {
                continue;
            }
            if !std::mem::replace(&mut cured, true) {
                ear = self.cure_local_intersections(ear).0;
                stop = ear;
                continue;
            }
            if hash.is_none() {
                // No z-order list to carry over: both halves start afresh.
                self.split(ear, jobs);
                return;
            }
            let Some(larger) = self.split_in_walk(ear, jobs) else { return };
            (ear, stop, cured) = (larger, larger, false);
            convex = self.rings.is_convex(larger);
        }
    }

    /// Queues every node of the ring of `start`, in ring order; returns the ring's size.
    fn enqueue_ring(&mut self, start: u32, queue: &mut VecDeque<u32>) -> usize {
        let mut p = start;
        let mut size = 0;
        loop {
            self.enqueue(p, queue);
            size += 1;
            p = self.rings.next(p);
            if p == start {
                return size;
            }
        }
    }

    #[inline]
    fn enqueue(&mut self, p: u32, queue: &mut VecDeque<u32>) {
        if !self.rings.marked(p, mark::QUEUED) {
            self.rings.set_mark(p, mark::QUEUED, true);
            queue.push_back(p);
        }
    }

    /// Changes a ring on which the queue found no ear, and hands it back to the walk: drops
    /// collinear and repeated points, else cures local crossings, else splits it. The walk
    /// starts afresh on what is left, with its own fallbacks; on touching holes its order of
    /// ears gets through where the queue's stopped again (100 × 100 touching squares: 0.17 s;
    /// left with the queue, whose rings then had to be split, 0.83 s, and 43 s on 150 × 150).
    /// Every fallback removes nodes or splits, so the hand-overs end.
    fn fall_back(&mut self, ear: u32, jobs: &mut Vec<(u32, Pass)>) {
        let (filtered, changed) = self.rings.filter_changed(ear, NIL);
        if changed {
            jobs.push((filtered, Pass::Walk));
            return;
        }
        let (cured, changed) = self.cure_local_intersections(filtered);
        if changed {
            jobs.push((cured, Pass::Walk));
            return;
        }
        self.split(filtered, jobs);
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

    /// Emits an ear: a corner the ear test found convex, so counter-clockwise with area.
    #[inline]
    fn emit_ear(&mut self, a: u32, b: u32, c: u32) {
        let vertex = |p: u32| self.rings.get(p).vertex;
        let triangle = [vertex(a), vertex(b), vertex(c)];
        self.out.extend_from_slice(&triangle);
    }

    /// The convex corner at `ear` as a candidate ear; `None` if reflex or flat.
    #[inline]
    fn corner(&self, ear: u32) -> Option<Corner> {
        let r = &*self.rings;
        Corner::of(r.get(r.prev(ear)), r.get(ear), r.get(r.next(ear)))
    }

    /// Whether node `p` blocks the ear: it lies in or on the triangle and is reflex or flat
    /// (only those can poke into an ear).
    #[inline]
    fn blocks(&self, ear: &Corner, p: u32) -> bool {
        let n = self.rings.get(p);
        ear.covers([n.x, n.y]) && !self.convex(p)
    }

    /// Whether the corner at `p` turns strictly left.
    #[inline]
    fn convex(&self, p: u32) -> bool {
        let n = self.rings.get(p);
        area(self.rings.get(n.prev), n, self.rings.get(n.next)) > 0.0
    }

    fn is_ear(&self, ear: u32) -> bool {
        let Some(corner) = self.corner(ear) else { return false };
        let last = self.rings.prev(ear);
        let mut p = self.rings.next(self.rings.next(ear));
        while p != last {
            if self.blocks(&corner, p) {
                return false;
            }
            p = self.rings.next(p);
        }
        true
    }

    /// [`Self::is_ear`] over the nodes of the linked z-order list whose codes lie between those
    /// of the ear box's corners, walking out from the ear's own node both ways in step (two
    /// independent chains of loads in flight), as earcut does.
    #[inline]
    fn is_ear_linked(&self, ear: u32, steps: &mut usize) -> Verdict {
        let r = &*self.rings;
        let c = r.next(ear);
        let (na, nb, nc) = (r.get(r.prev(ear)), r.get(ear), r.get(c));
        let Some(corner) = Corner::of(na, nb, nc) else { return Verdict::Reflex };
        // From the corners' codes: quantising the box's corners again was a sixth of the walk.
        let (min_z, max_z) = box_codes(na.z, nb.z, nc.z);
        // Whether a node blocks the ear: in or on the triangle (a copy of its first corner
        // aside), not its last corner, and reflex or flat.
        let blocks = |p: u32| {
            let n = r.get(p);
            p != c && corner.covers([n.x, n.y]) && !self.convex(p)
        };
        // The node that blocked this corner last time: if it is still on this ring's list (link_z
        // starts the cache afresh; a split takes the smaller half off the list) and still
        // blocks, the answer is the same as the list walk's.
        let known = r.z.blockers[ear as usize];
        if known != NIL && r.alive(known) && r.z_links(known) != [NIL; 2] && blocks(known) {
            return Verdict::BlockedBy(known);
        }
        let [mut down, mut up] = r.z_links(ear);
        while down != NIL && up != NIL {
            if r.get(down).z < min_z || r.get(up).z > max_z {
                break;
            }
            *steps += 2;
            if blocks(down) {
                return Verdict::BlockedBy(down);
            }
            if blocks(up) {
                return Verdict::BlockedBy(up);
            }
            (down, up) = (r.z_links(down)[0], r.z_links(up)[1]);
        }
        while down != NIL && r.get(down).z >= min_z {
            *steps += 1;
            if blocks(down) {
                return Verdict::BlockedBy(down);
            }
            down = r.z_links(down)[0];
        }
        while up != NIL && r.get(up).z <= max_z {
            *steps += 1;
            if blocks(up) {
                return Verdict::BlockedBy(up);
            }
            up = r.z_links(up)[1];
        }
        Verdict::Ear
    }

    /// [`Self::is_ear`] over the nodes on the z-order list whose code lies in the ear's box,
    /// in code order, jumping (BIGMIN) over stretches of the code range outside the box. The
    /// walk reads codes and positions from the sorted list and fetches a node only for a point
    /// inside the ear. Convex corners found there leave the list: clipping ears only makes the
    /// remaining corners more convex, so they cannot block an ear of this pass again. Without
    /// these, the long ears of a star's spikes and the large ears late in a convex remainder
    /// each scanned a good part of the ring: O(n²) in all.
    fn is_ear_hashed(&mut self, ear: u32) -> bool {
        let Some(corner) = self.corner(ear) else { return false };
        let own = [self.rings.prev(ear), self.rings.next(ear)];
        let hash = self.hash.expect("hashed ear test without a hash");
        let (min_z, max_z) = (hash.z(corner.min[0], corner.min[1]), hash.z(corner.max[0], corner.max[1]));
        let mut at = self.index.live_from(self.index.first_at_or_after(min_z));
        // Codes outside the box met in a row: a few are stepped over, more are jumped.
        let mut misses = 0;
        // Codes in the box but beside the ear met so far.
        let mut passed = 0;
        while let Some(&key) = self.index.keys.get(at) {
            let z = code(key);
            if z > max_z {
                return true;
            }
            if in_box(z, min_z, max_z) {
                misses = 0;
                let p = key as u32;
                if corner.covers(self.index.positions[at]) {
                    if !own.contains(&p) {
                        if !self.convex(p) {
                            return false;
                        }
                        self.index.remove(at);
                    }
                } else {
                    passed += 1;
                    // The box of a large ear holds long stretches of the ring that pass beside
                    // the triangle: past a few such codes, a cell of them wholly outside it is
                    // passed over at once (tried for every code, cells cost small ears 10–35%).
                    if passed >= 32
                        && let Some(end) = corner.outside_cell(&hash, z)
                    {
                        let Some(target) = (end < max_z).then(|| bigmin(end, min_z, max_z)).flatten() else {
                            return true;
                        };
                        at = self.index.live_from(self.index.first_at_or_after(target));
                        continue;
                    }
                }
                at = self.index.live_from(at + 1);
                continue;
            }
            misses += 1;
            if misses < 4 {
                at = self.index.live_from(at + 1);
                continue;
            }
            let Some(target) = bigmin(z, min_z, max_z) else { return true };
            at = self.index.live_from(self.index.first_at_or_after(target));
        }
        true
    }

    /// Builds the z-order list of the ring of `start`.
    fn index_curve(&mut self, start: u32) {
        let hash = self.hash.expect("indexing without a hash");
        self.index.keys.clear();
        self.rings.for_each_node(start, |p| {
            let node = self.rings.get(p);
            self.index.keys.push((u64::from(hash.z(node.x, node.y)) << 32) | u64::from(p));
        });
        let nodes = &self.rings.nodes;
        self.index.build(|p| [nodes[p as usize].x, nodes[p as usize].y]);
    }

    /// Where a ring crosses itself locally (a–p and p.next–b cross properly: merely touching
    /// edges are no crossing to cure, and cutting there made overlaps), cuts off triangle
    /// (a, p, b) and drops p and p.next. Returns a node of the ring and whether anything changed.
    fn cure_local_intersections(&mut self, start: u32) -> (u32, bool) {
        if start == NIL {
            return (start, false);
        }
        let mut changed = false;
        let mut start = start;
        let mut p = start;
        loop {
            let r = &*self.rings;
            let (a, pn) = (r.prev(p), r.next(p));
            let b = r.next(pn);
            if !r.equals(a, b)
                && super::linked::crosses(r.get(a), r.get(p), r.get(pn), r.get(b))
                && r.locally_inside(a, b)
                && r.locally_inside(b, a)
            {
                self.emit(a, p, b);
                self.rings.remove(p);
                self.rings.remove(pn);
                changed = true;
                p = b;
                start = b;
            }
            p = self.rings.next(p);
            if p == start || self.rings.next(p) == p {
                break;
            }
        }
        let (node, filtered) = self.rings.filter_changed(p, NIL);
        (node, changed || filtered)
    }

    /// Splits the ring along the first valid diagonal found and queues both halves.
    fn split(&mut self, start: u32, jobs: &mut Vec<(u32, Pass)>) {
        if let Some((a, b)) = self.find_diagonal(start) {
            let (a, c) = self.cut(a, b, false);
            jobs.push((a, Pass::Walk));
            jobs.push((c, Pass::Walk));
        }
    }

    /// [`Self::split`] inside the walk: queues the smaller half and returns a node of the larger,
    /// whose z-order list is the ring's own less the smaller half's nodes (the copies the cut
    /// makes join it beside their originals). On crossing input a stuck ring sheds a few nodes
    /// per split, dozens of times: building the larger half's list anew each time, and losing
    /// its blocker cache, was a fifth of the time.
    fn split_in_walk(&mut self, start: u32, jobs: &mut Vec<(u32, Pass)>) -> Option<u32> {
        let (a, b) = self.find_diagonal(start)?;
        let (a, c) = self.cut(a, b, true);
        let (smaller, larger) = if self.rings.smaller_ring(a, c) { (a, c) } else { (c, a) };
        self.rings.z_unlink_ring(smaller);
        jobs.push((smaller, Pass::Walk));
        Some(larger)
    }

    /// Cuts the ring along diagonal a–b and tidies both new edges; returns a node of each half.
    /// With `keep_z`, the two copies the cut makes join the z-order list beside their originals.
    fn cut(&mut self, a: u32, b: u32, keep_z: bool) -> (u32, u32) {
        let c = self.rings.split(a, b);
        if keep_z {
            self.rings.z_insert_copy(a, self.rings.next(c));
            self.rings.z_insert_copy(b, c);
        }
        let a = self.rings.filter(a, self.rings.next(a));
        let c = self.rings.filter(c, self.rings.next(c));
        (a, c)
    }

    /// The first valid diagonal from `start` on, in ring order.
    fn find_diagonal(&self, start: u32) -> Option<(u32, u32)> {
        let mut a = start;
        let mut hints = [NIL; 4];
        loop {
            let mut b = self.rings.next(self.rings.next(a));
            while b != self.rings.prev(a) {
                if self.rings.get(a).vertex != self.rings.get(b).vertex
                    && self.rings.is_valid_diagonal(a, b, &mut hints)
                {
                    return Some((a, b));
                }
                b = self.rings.next(b);
            }
            a = self.rings.next(a);
            if a == start {
                return None;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cell_passed_over_holds_no_point_of_the_ear() {
        let hash = ZHash::new([0.0, 0.0], [1000.0, 1000.0]);
        let mut rng = crate::geometry::rng::SplitMix64::new(5);
        let mut random = || rng.unit();
        let mut passed_over = 0;
        for _ in 0..300 {
            let mut point = || [1000.0 * random(), 1000.0 * random()];
            let (a, b, mut c) = (point(), point(), point());
            if (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0.0 {
                (c[0], c[1]) = (2.0 * a[0] - c[0], 2.0 * a[1] - c[1]);
            }
            let (min, max) = (
                [a[0].min(b[0]).min(c[0]), a[1].min(b[1]).min(c[1])],
                [a[0].max(b[0]).max(c[0]), a[1].max(b[1]).max(c[1])],
            );
            let corner = Corner { triangle: Triangle { a, b, c }, min, max };
            for _ in 0..40 {
                let p = [min[0] + (max[0] - min[0]) * random(), min[1] + (max[1] - min[1]) * random()];
                let z = hash.z(p[0], p[1]);
                // Every cell the walk may pass over: its whole box must lie outside the ear.
                for k in 1..15 {
                    let Some((lo, hi, _)) = hash.cell(z, k) else { break };
                    if !corner.misses_box(lo, hi) {
                        break;
                    }
                    passed_over += 1;
                    for _ in 0..50 {
                        let q = [lo[0] + (hi[0] - lo[0]) * random(), lo[1] + (hi[1] - lo[1]) * random()];
                        assert!(
                            !corner.covers(q),
                            "{q:?} is in the ear {a:?} {b:?} {c:?} but its cell was passed over"
                        );
                    }
                    assert!(
                        lo[0] <= p[0] && p[0] <= hi[0] && lo[1] <= p[1] && p[1] <= hi[1],
                        "the cell holds its point"
                    );
                }
                let skipped = corner.outside_cell(&hash, z);
                assert_eq!(skipped.is_some(), hash.cell(z, 1).is_some_and(|(lo, hi, _)| corner.misses_box(lo, hi)));
            }
        }
        assert!(passed_over > 1000, "only {passed_over} cells passed over: the test checks little");
    }
}
