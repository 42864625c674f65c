//! A ring that crosses itself (a bow-tie, a figure eight, a scribble) is cut at its crossing
//! points into the faces of the drawing it makes, and the faces the ring winds around (non-zero
//! winding, the fill rule of SVG and of most drawing tools) are kept. Faces of one closed curve
//! are simple polygons that meet only along edges and at points, so each triangulates on its
//! own and none overlaps another: the ring is filled instead of dropped or half-covered.

use std::collections::HashMap;

/// Rings with more points than this are not searched for crossings: the sweep still compares
/// every pair of edges whose x ranges overlap, which for long spiky rings (generated stars) is
/// nearly every pair, and long rings from files are simple in practice.
/// They triangulate as before, with the area warning if they do cross.
pub const MAX_CHECKED_POINTS: usize = 2048;

/// A ring's filled faces as indices into `positions`; the crossing points are appended to
/// `positions`.
pub struct Split {
    /// Simple, counter-clockwise loops (the ring itself when it does not cross).
    pub loops: Vec<Vec<u32>>,
    /// How many crossings were found.
    pub crossings: usize,
}

/// Cuts `ring` (indices into `positions`) at every proper crossing of two of its edges and keeps
/// the faces with a non-zero winding number. Callers check rings of at most
/// [`MAX_CHECKED_POINTS`].
pub fn split_crossings(ring: Vec<u32>, positions: &mut Vec<[f64; 2]>) -> Split {
    let n = ring.len();
    // Per edge: (position along it, crossing point index).
    let mut on_edge: Vec<Vec<(f64, u32)>> = vec![Vec::new(); n];
    let mut crossings = 0;
    for (i, j, t, u, point) in all_crossings(&ring, positions) {
        let at = positions.len() as u32;
        positions.push(point);
        on_edge[i].push((t, at));
        on_edge[j].push((u, at));
        crossings += 1;
    }
    if crossings == 0 {
        return Split { loops: vec![ring], crossings };
    }
    // The walk along the ring with every crossing point inserted on both of its edges.
    let mut walk = Vec::with_capacity(n + 2 * crossings);
    for (i, &v) in ring.iter().enumerate() {
        walk.push(v);
        on_edge[i].sort_by(|a, b| a.0.total_cmp(&b.0));
        walk.extend(on_edge[i].iter().map(|&(_, p)| p));
    }
    let ring_points: Vec<[f64; 2]> = ring.iter().map(|&v| positions[v as usize]).collect();
    let loops = faces(&walk, positions)
        .into_iter()
        .filter(|face| {
            let points: Vec<[f64; 2]> = face.iter().map(|&v| positions[v as usize]).collect();
            super::linked::signed_area(&points) > 0.0
                && interior_point(&points).is_some_and(|p| winding_number(&ring_points, p) != 0)
        })
        .collect();
    Split { loops, crossings }
}

/// The faces of the planar drawing of the closed `walk` (each edge walk[k] → walk[k + 1]),
/// traced with the face on the left: bounded faces come out counter-clockwise, the outside
/// clockwise.
fn faces(walk: &[u32], positions: &[[f64; 2]]) -> Vec<Vec<u32>> {
    let len = walk.len();
    // Half-edges 2k (walk[k] → walk[k+1]) and 2k + 1 (back).
    let from = |h: usize| if h.is_multiple_of(2) { walk[h / 2] } else { walk[(h / 2 + 1) % len] };
    let to = |h: usize| from(h ^ 1);
    let angle = |h: usize| {
        let (a, b) = (positions[from(h) as usize], positions[to(h) as usize]);
        (b[1] - a[1]).atan2(b[0] - a[0])
    };
    // Outgoing half-edges of each point, counter-clockwise by angle.
    let mut around: HashMap<u32, Vec<usize>> = HashMap::new();
    for h in 0..2 * len {
        around.entry(from(h)).or_default().push(h);
    }
    let mut slot = vec![0; 2 * len];
    for list in around.values_mut() {
        list.sort_by(|&a, &b| angle(a).total_cmp(&angle(b)));
        for (i, &h) in list.iter().enumerate() {
            slot[h] = i;
        }
    }
    // Arriving along h, the face on the left continues along the outgoing edge just clockwise
    // of the way back.
    let next = |h: usize| {
        let list = &around[&to(h)];
        let back = slot[h ^ 1];
        list[(back + list.len() - 1) % list.len()]
    };
    let mut done = vec![false; 2 * len];
    let mut out = Vec::new();
    for start in 0..2 * len {
        let mut face = Vec::new();
        let mut h = start;
        while !done[h] {
            done[h] = true;
            face.push(from(h));
            h = next(h);
        }
        if face.len() >= 3 {
            out.push(face);
        }
    }
    out
}

/// A point strictly inside the simple counter-clockwise polygon `points`: the centroid of an ear
/// (a convex corner whose triangle holds no other vertex; every simple polygon has one). None
/// for a degenerate face.
fn interior_point(points: &[[f64; 2]]) -> Option<[f64; 2]> {
    let n = points.len();
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
    (0..n).find_map(|i| {
        let (a, b, c) = (points[(i + n - 1) % n], points[i], points[(i + 1) % n]);
        if cross(a, b, c) <= 0.0 {
            return None;
        }
        let inside = |p: [f64; 2]| cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0;
        let blocked = points.iter().any(|&p| p != a && p != b && p != c && inside(p));
        (!blocked).then(|| [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0])
    })
}

/// How many times `ring` winds around `p` (counter-clockwise positive).
fn winding_number(ring: &[[f64; 2]], p: [f64; 2]) -> i32 {
    let mut w = 0;
    for (a, b) in ring.iter().zip(ring.iter().cycle().skip(1)) {
        let side = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        if a[1] <= p[1] && b[1] > p[1] && side > 0.0 {
            w += 1;
        } else if a[1] > p[1] && b[1] <= p[1] && side < 0.0 {
            w -= 1;
        }
    }
    w
}

/// Every pair of non-adjacent edges (i < j) that cross at a point interior to both: (i, j, the
/// position along edge i and along edge j, the point). Touching at a vertex or overlapping
/// along a line is not a crossing. Edges are swept left to right by their x extent, so only
/// pairs whose x ranges overlap are compared.
fn all_crossings(ring: &[u32], positions: &[[f64; 2]]) -> Vec<(usize, usize, f64, f64, [f64; 2])> {
    let n = ring.len();
    let mut out = Vec::new();
    if n < 4 {
        return out;
    }
    let at = |k: usize| positions[ring[k % n] as usize];
    let mut order: Vec<(f64, usize)> = (0..n).map(|i| (at(i)[0].min(at(i + 1)[0]), i)).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (k, &(_, e)) in order.iter().enumerate() {
        let (a, b) = (at(e), at(e + 1));
        let (right, lo_y, hi_y) = (a[0].max(b[0]), a[1].min(b[1]), a[1].max(b[1]));
        for &(left, f) in &order[k + 1..] {
            if left > right {
                break;
            }
            let adjacent = f.abs_diff(e) == 1 || f.abs_diff(e) == n - 1;
            let (c, d) = (at(f), at(f + 1));
            if adjacent || c[1].max(d[1]) < lo_y || c[1].min(d[1]) > hi_y {
                continue;
            }
            let (i, j, (a, b, c, d)) = if e < f { (e, f, (a, b, c, d)) } else { (f, e, (c, d, a, b)) };
            if let Some((t, u, point)) = proper_crossing(a, b, c, d) {
                out.push((i, j, t, u, point));
            }
        }
    }
    out
}

/// Where segments a–b and c–d cross, if they cross at a point strictly inside both: the
/// positions along each (0–1) and the point.
fn proper_crossing(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Option<(f64, f64, [f64; 2])> {
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
    let (d1, d2) = (cross(a, b, c), cross(a, b, d));
    let (d3, d4) = (cross(c, d, a), cross(c, d, b));
    let strictly_apart = |x: f64, y: f64| (x > 0.0 && y < 0.0) || (x < 0.0 && y > 0.0);
    if !(strictly_apart(d1, d2) && strictly_apart(d3, d4)) {
        return None;
    }
    let (t, u) = (d3 / (d3 - d4), d1 / (d1 - d2));
    Some((t, u, [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn split(points: &[[f64; 2]]) -> (Split, Vec<[f64; 2]>) {
        let mut positions = points.to_vec();
        let s = split_crossings((0..points.len() as u32).collect(), &mut positions);
        (s, positions)
    }

    #[test]
    fn a_bow_tie_is_two_triangles_meeting_at_its_crossing() {
        let (s, positions) = split(&[[-5.33, -3.0], [5.33, 3.0], [5.33, -3.0], [-5.33, 3.0]]);
        assert_eq!(s.crossings, 1);
        assert_eq!(s.loops.len(), 2);
        assert!(s.loops.iter().all(|l| l.len() == 3 && l.contains(&4)), "{:?}", s.loops);
        let x = positions[4];
        assert!(x[0].abs() < 1e-12 && x[1].abs() < 1e-12, "{x:?}");
    }

    #[test]
    fn simple_rings_and_touching_vertices_are_left_whole() {
        let (s, _) = split(&[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]);
        assert_eq!((s.crossings, s.loops.len()), (0, 1));
        // Two squares touching at one vertex, drawn as one ring through it: no proper crossing.
        let (s, _) =
            split(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0], [1.0, 1.0], [0.0, 1.0]]);
        assert_eq!((s.crossings, s.loops.len()), (0, 1));
    }

    #[test]
    fn a_pentagram_fills_its_five_points_and_the_pentagon_it_winds_around_twice() {
        let (s, _) = split(&super::super::tests::pentagram());
        assert_eq!(s.crossings, 5);
        let mut sizes: Vec<usize> = s.loops.iter().map(Vec::len).collect();
        sizes.sort_unstable();
        assert_eq!(sizes, [3, 3, 3, 3, 3, 5], "{:?}", s.loops);
    }

    #[test]
    fn winding_numbers_count_turns() {
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(winding_number(&square, [0.5, 0.5]), 1);
        let reversed: Vec<[f64; 2]> = square.iter().rev().copied().collect();
        assert_eq!(winding_number(&reversed, [0.5, 0.5]), -1);
        assert_eq!(winding_number(&square, [1.5, 0.5]), 0);
    }
}
