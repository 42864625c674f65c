//! The nesting tree of a set of rings [UGP4 ch.5]: rings sorted by bounding-box area, largest
//! first, each placed under the deepest ring that contains it. Odd depth = an outer ring (filled),
//! even depth = a hole; islands inside holes come out as outer rings of their own.

use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree};

use super::linked::{greatest, least};

/// What the tree needs to know of one ring.
pub(super) struct RingShape<'a> {
    pub vertices: &'a [[f64; 2]],
    pub min: [f64; 2],
    pub max: [f64; 2],
    /// The input ring a face came from, for the faces of a ring cut at its crossings: faces of
    /// one ring never lie inside each other (they only share edges and points).
    pub family: Option<usize>,
}

impl<'a> RingShape<'a> {
    /// A ring and its bounding box.
    pub fn new(vertices: &'a [[f64; 2]]) -> Self {
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        // Plain comparisons (coordinates are finite by now): `f64::min`'s NaN handling was 5%
        // of a 104-vertex polygon's time.
        for v in vertices {
            for k in 0..2 {
                min[k] = least(min[k], v[k]);
                max[k] = greatest(max[k], v[k]);
            }
        }
        Self { vertices, min, max, family: None }
    }

    fn box_area(&self) -> f64 {
        (self.max[0] - self.min[0]) * (self.max[1] - self.min[1])
    }

    fn box_contains(&self, other: &Self) -> bool {
        (0..2).all(|k| self.min[k] <= other.min[k] && other.max[k] <= self.max[k])
    }

    /// Inside (`Some(true)`), outside (`Some(false)`) or on the boundary (`None`), by counting
    /// crossings of a ray to +x.
    pub fn locate(&self, p: [f64; 2]) -> Option<bool> {
        let mut inside = false;
        let mut j = *self.vertices.last()?;
        for &i in self.vertices {
            // On the edge j–i?
            let cross = (i[0] - j[0]) * (p[1] - j[1]) - (i[1] - j[1]) * (p[0] - j[0]);
            if cross == 0.0
                && p[0] >= i[0].min(j[0])
                && p[0] <= i[0].max(j[0])
                && p[1] >= i[1].min(j[1])
                && p[1] <= i[1].max(j[1])
            {
                return None;
            }
            if (i[1] > p[1]) != (j[1] > p[1]) && p[0] < (j[0] - i[0]) * (p[1] - i[1]) / (j[1] - i[1]) + i[0] {
                inside = !inside;
            }
            j = i;
        }
        Some(inside)
    }

    /// Whether `other` lies inside this ring: decided by its first vertex not on this ring's
    /// boundary (rings may touch). A ring lying wholly on this one's boundary is not inside.
    fn contains(&self, other: &Self) -> bool {
        let siblings = self.family.is_some() && self.family == other.family;
        !siblings && self.box_contains(other) && other.vertices.iter().find_map(|&v| self.locate(v)).unwrap_or(false)
    }
}

/// Whether a point lies strictly inside the area a group fills: inside its outer ring and
/// outside each of its holes (on no boundary).
pub(super) fn fills(shapes: &[RingShape], group: &Group, p: [f64; 2]) -> bool {
    let outer = &shapes[group.outer];
    let in_box = (0..2).all(|k| outer.min[k] <= p[k] && p[k] <= outer.max[k]);
    in_box && outer.locate(p) == Some(true) && group.holes.iter().all(|&h| shapes[h].locate(p) == Some(false))
}

/// An outer ring and the holes directly inside it (indices into the shapes).
#[derive(Debug, PartialEq, Eq)]
pub(super) struct Group {
    pub outer: usize,
    pub holes: Vec<usize>,
}

/// Builds the nesting tree and returns it as outer rings with their holes. Rings are placed
/// largest box first; a ring's parent is the deepest placed ring that contains it, found among
/// the rings whose boxes contain its box's corner (an R-tree query, so 10⁵ separate rings do not
/// test each other pairwise).
pub(super) fn nest(shapes: &[RingShape]) -> Vec<Group> {
    let mut order: Vec<usize> = (0..shapes.len()).collect();
    order.sort_by(|&a, &b| shapes[b].box_area().total_cmp(&shapes[a].box_area()).then(a.cmp(&b)));
    let mut rank = vec![0; shapes.len()];
    for (place, &ring) in order.iter().enumerate() {
        rank[ring] = place;
    }
    let boxes = RTree::bulk_load(
        shapes.iter().enumerate().map(|(i, s)| GeomWithData::new(Rectangle::from_corners(s.min, s.max), i)).collect(),
    );
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); shapes.len()];
    let mut depth = vec![0usize; shapes.len()];
    for &ring in &order {
        let corner = AABB::from_point(shapes[ring].min);
        let parent = boxes
            .locate_in_envelope_intersecting(&corner)
            .map(|candidate| candidate.data)
            .filter(|&c| rank[c] < rank[ring] && shapes[c].contains(&shapes[ring]))
            .max_by_key(|&c| (depth[c], rank[c]));
        depth[ring] = parent.map_or(1, |p| depth[p] + 1);
        if let Some(p) = parent {
            children[p].push(ring);
        }
    }
    (0..shapes.len())
        .filter(|&r| depth[r] % 2 == 1)
        .map(|outer| Group { outer, holes: std::mem::take(&mut children[outer]) })
        .collect()
}
