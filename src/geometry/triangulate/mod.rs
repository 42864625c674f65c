//! Polygon triangulation by ear clipping with holes and nesting [UGP4 ch.5].
//!
//! [`triangulate`] takes any number of rings in any orientation and nesting; it builds the
//! nesting tree (odd depth = filled, even depth = hole, islands in holes filled again), bridges
//! each outer ring's holes into it and ear-slices the result. [`triangulate_flat`] takes earcut's
//! layout (one outer ring and its holes as flat coordinates plus hole start indices).
//!
//! Where the book's sample goes wrong (seed-reference §5, §9 items 18–19) this does not: sizes are
//! compared as floats, no hole is dropped silently, degenerate rings are reported rather than
//! half-triangulated, and the ear search is near-linear on real outlines (z-order hash) instead of
//! O(n²)–O(n³).

mod crossings;
mod ear;
mod holes;
mod linked;
mod nesting;
mod ring_order;
mod zorder;

use ear::{HASH_THRESHOLD, Slicer};
use linked::{NIL, Rings, signed_area};
use nesting::RingShape;
use std::ops::Range;
use zorder::{ZHash, ZIndex};

/// Why a triangulation could not be made at all.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TriangulateError {
    /// A coordinate is NaN or infinite.
    #[error("ring {ring}, vertex {vertex}: coordinate is not a finite number")]
    NonFinite {
        /// Ring index.
        ring: usize,
        /// Vertex index within the ring.
        vertex: usize,
    },
    /// A coordinate so large that areas (products of coordinate differences) could overflow.
    #[error(
        "ring {ring}, vertex {vertex}: coordinate {value:e} is too large (|x| and |y| must stay within \
         {MAX_COORDINATE:e}, so that areas stay finite); scale the input down"
    )]
    TooLarge {
        /// Ring index.
        ring: usize,
        /// Vertex index within the ring.
        vertex: usize,
        /// The coordinate.
        value: f64,
    },
    /// More vertices than 32-bit indices can address.
    #[error("{0} vertices: at most {max} fit 32-bit indices", max = u32::MAX - 1)]
    TooManyVertices(usize),
    /// A flat coordinate list of odd length.
    #[error("flat coordinates must come in (x, y) pairs; got {0} numbers")]
    OddCoordinates(usize),
    /// A hole start index out of order or past the last vertex.
    #[error("hole start {start} is out of order or past the last vertex ({vertices} vertices)")]
    BadHoleIndex {
        /// The offending start index.
        start: usize,
        /// Number of vertices given.
        vertices: usize,
    },
}

/// Why an input ring was left out of the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DropReason {
    /// Fewer than three distinct points.
    TooFewPoints,
    /// All points on one line: the ring encloses nothing.
    ZeroArea,
    /// A single point (a Steiner point) outside every filled area or on its boundary.
    SteinerOutside,
}

/// An input ring that is not in the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DroppedRing {
    /// Index of the ring in the input.
    pub ring: usize,
    /// Why.
    pub reason: DropReason,
}

/// What a triangulation covered.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriangulationReport {
    /// Rings filled (odd nesting depth).
    pub outers: usize,
    /// Rings cut out (even nesting depth).
    pub holes: usize,
    /// Single-point rings placed inside a filled area as Steiner points (mesh vertices).
    pub steiner: usize,
    /// Rings left out, with the reason.
    pub dropped: Vec<DroppedRing>,
    /// Rings that crossed themselves, with the number of crossings: each was cut there into
    /// simple loops (the crossing points added to the positions), filled by non-zero winding.
    pub crossed: Vec<(usize, usize)>,
    /// Area enclosed by the kept rings: Σ |outer| − Σ |hole|.
    pub polygon_area: f64,
    /// Σ |triangle area| of the output.
    pub triangle_area: f64,
    /// Σ |area| of the kept rings, outers and holes alike: the scale a polygon of no area (a
    /// ring cancelled by its hole) measures its deviation against.
    pub rings_area: f64,
}

impl TriangulationReport {
    /// |Σ triangle area − polygon area| / polygon area (0 for an empty polygon covered by nothing).
    pub fn area_deviation(&self) -> f64 {
        let diff = (self.triangle_area - self.polygon_area).abs();
        // |…| of the polygon area: earcut's layout can list holes larger than the outer ring.
        // A polygon of no area is measured against its rings' area: slivers of 10⁻²⁸ left where
        // a hole cancels its outer ring are no crossing (earcut's fixture infinite-loop-jhl).
        if self.polygon_area == 0.0 {
            match (diff, self.rings_area) {
                (0.0, _) => 0.0,
                (_, rings) if rings > 0.0 => diff / rings,
                _ => f64::INFINITY,
            }
        } else {
            diff / self.polygon_area.abs()
        }
    }

    /// One line per thing the caller should know: dropped rings, area not covered.
    pub fn warnings(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .dropped
            .iter()
            .map(|d| match d.reason {
                DropReason::TooFewPoints => format!("ring {} left out: fewer than 3 distinct points", d.ring),
                DropReason::ZeroArea => format!("ring {} left out: its points are collinear", d.ring),
                DropReason::SteinerOutside => {
                    format!("ring {} left out: a single point (Steiner point) outside the filled area", d.ring)
                }
            })
            .collect();
        out.extend(self.crossed.iter().map(|&(ring, crossings)| {
            format!(
                "ring {ring} crosses itself ({crossings} crossing(s)): filled where it winds around (non-zero rule)"
            )
        }));
        let deviation = self.area_deviation();
        if deviation > 1e-9 {
            out.push(format!(
                "triangles cover {:.6} of the polygon's area {:.6} (deviation {:.2e}): the input crosses itself",
                self.triangle_area, self.polygon_area, deviation
            ));
        }
        out
    }
}

/// A triangulated polygon set.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh2D {
    /// Every input vertex, rings concatenated in input order (triangles index into this); then,
    /// for rings that cross themselves, the crossing points and the vertices of their loops.
    pub positions: Vec<[f64; 2]>,
    /// Counter-clockwise triangles, three indices each.
    pub indices: Vec<u32>,
    /// Positions normalised by the bounding rectangle of all vertices (the book's UVs).
    pub uvs: Vec<[f32; 2]>,
    /// What was covered and what was left out.
    pub report: TriangulationReport,
}

impl Mesh2D {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// Triangulates rings given in any orientation and nesting. Rings need not be closed (a last
/// point equal to the first is ignored).
///
/// # Errors
/// Non-finite coordinates, or more than 2³² − 2 vertices. Degenerate rings are not errors: they
/// are left out and listed in the report.
pub fn triangulate<R: AsRef<[[f64; 2]]>>(rings: &[R]) -> Result<Mesh2D, TriangulateError> {
    Triangulator::default().rings(rings)
}

/// Triangulates one outer ring with holes in earcut's flat layout: `coords` = x0, y0, x1, y1, …;
/// `hole_starts` = the vertex index where each hole begins. Returns triangle vertex indices,
/// counter-clockwise.
///
/// # Errors
/// Odd coordinate count, non-finite coordinates, hole starts out of order or range.
pub fn triangulate_flat(coords: &[f64], hole_starts: &[usize]) -> Result<Vec<u32>, TriangulateError> {
    let mut out = Vec::new();
    Triangulator::default().flat(coords, hole_starts, &mut out)?;
    Ok(out)
}

/// A triangulator that keeps its buffers between calls (for many polygons per frame).
#[derive(Default)]
pub struct Triangulator {
    rings: Rings,
    zindex: ZIndex,
    holes: Vec<u32>,
    bands: holes::Bands,
    order: ring_order::RingOrder,
    walk_budget: ear::WalkBudget,
    ranges: Vec<Range<usize>>,
    jobs: Vec<(u32, ear::Pass)>,
    queue: std::collections::VecDeque<u32>,
}

impl Triangulator {
    /// A triangulator with empty buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// [`triangulate_flat`], appending to `out` and reusing this triangulator's buffers.
    ///
    /// # Errors
    /// As [`triangulate_flat`].
    pub fn flat(&mut self, coords: &[f64], hole_starts: &[usize], out: &mut Vec<u32>) -> Result<(), TriangulateError> {
        if !coords.len().is_multiple_of(2) {
            return Err(TriangulateError::OddCoordinates(coords.len()));
        }
        let vertices: &[[f64; 2]] = bytemuck::cast_slice(coords);
        check_count(vertices.len())?;
        let mut ranges = std::mem::take(&mut self.ranges);
        ranges.clear();
        let mut start = 0;
        for &end in hole_starts.iter().chain([&vertices.len()]) {
            if end < start || end > vertices.len() {
                self.ranges = ranges;
                return Err(TriangulateError::BadHoleIndex { start: end, vertices: vertices.len() });
            }
            ranges.push(start..end);
            start = end;
        }
        let checked = ranges.iter().enumerate().try_for_each(|(ring, r)| check_coordinates(&vertices[r.clone()], ring));
        if checked.is_ok() {
            self.group(vertices, ranges[0].clone(), &ranges[1..], out);
        }
        self.ranges = ranges;
        checked
    }

    /// [`triangulate`], reusing this triangulator's buffers.
    ///
    /// # Errors
    /// As [`triangulate`].
    pub fn rings<R: AsRef<[[f64; 2]]>>(&mut self, rings: &[R]) -> Result<Mesh2D, TriangulateError> {
        let (mut positions, ranges) = concatenate(rings)?;

        let mut report = TriangulationReport::default();
        let (ranges, ring_of) = split_crossing_rings(&mut positions, ranges, &mut report);
        check_count(positions.len())?;
        let mut kept = Vec::new();
        let mut areas = Vec::new();
        let mut points = Vec::new();
        for (index, range) in ranges.iter().enumerate() {
            let ring = &positions[range.clone()];
            if ring.first().is_some_and(|&first| ring.iter().all(|&p| p == first)) {
                points.push(index);
                continue;
            }
            match classify(ring) {
                Ok(area) => {
                    kept.push(index);
                    areas.push(area.abs());
                }
                Err(reason) => {
                    let dropped = DroppedRing { ring: ring_of[index], reason };
                    if !report.dropped.contains(&dropped) {
                        report.dropped.push(dropped);
                    }
                }
            }
        }
        let crossed = |ring: usize| report.crossed.iter().any(|&(r, _)| r == ring);
        let shapes: Vec<RingShape> = kept
            .iter()
            .map(|&r| RingShape {
                family: crossed(ring_of[r]).then_some(ring_of[r]),
                ..RingShape::new(&positions[ranges[r].clone()])
            })
            .collect();
        let groups = nesting::nest(&shapes);
        // Steiner points join the group whose filled area holds them, as holes of one point.
        let mut steiner = vec![Vec::new(); groups.len()];
        for &point in &points {
            let at = positions[ranges[point].start];
            match groups.iter().position(|g| nesting::fills(&shapes, g, at)) {
                Some(group) => {
                    steiner[group].push(ranges[point].start..ranges[point].start + 1);
                    report.steiner += 1;
                }
                None => report.dropped.push(DroppedRing { ring: ring_of[point], reason: DropReason::SteinerOutside }),
            }
        }
        report.dropped.sort_by_key(|d| d.ring);
        let mut indices = Vec::new();
        let mut hole_ranges = Vec::new();
        for (group, steiner) in groups.iter().zip(steiner) {
            report.outers += 1;
            report.holes += group.holes.len();
            report.polygon_area += areas[group.outer] - group.holes.iter().map(|&h| areas[h]).sum::<f64>();
            report.rings_area += areas[group.outer] + group.holes.iter().map(|&h| areas[h]).sum::<f64>();
            hole_ranges.clear();
            hole_ranges.extend(group.holes.iter().map(|&h| ranges[kept[h]].clone()));
            hole_ranges.extend(steiner);
            self.group(&positions, ranges[kept[group.outer]].clone(), &hole_ranges, &mut indices);
        }
        report.triangle_area = triangle_area(&positions, &indices);
        let uvs = bounding_rect_uvs(&positions);
        Ok(Mesh2D { positions, indices, uvs, report })
    }

    /// Triangulates rings in earcut's layout: the first ring is the outer ring, every other
    /// ring a hole in it, a ring of one point a Steiner point (a vertex the mesh must contain).
    /// Nothing is nested or split: the report's polygon area is |outer| − Σ |hole|, earcut's.
    ///
    /// # Errors
    /// As [`triangulate`].
    pub fn outer_and_holes<R: AsRef<[[f64; 2]]>>(&mut self, rings: &[R]) -> Result<Mesh2D, TriangulateError> {
        let (positions, ranges) = concatenate(rings)?;
        let mut report = TriangulationReport::default();
        let mut indices = Vec::new();
        if let Some((outer, holes)) = ranges.split_first() {
            let area = |r: &Range<usize>| signed_area(&positions[r.clone()]).abs();
            report.outers = 1;
            report.steiner = holes.iter().filter(|r| r.len() == 1).count();
            report.holes = holes.len() - report.steiner;
            report.polygon_area = area(outer) - holes.iter().map(area).sum::<f64>();
            report.rings_area = area(outer) + holes.iter().map(area).sum::<f64>();
            self.group(&positions, outer.clone(), holes, &mut indices);
        }
        report.triangle_area = triangle_area(&positions, &indices);
        let uvs = bounding_rect_uvs(&positions);
        Ok(Mesh2D { positions, indices, uvs, report })
    }

    /// Triangulates one outer ring and its holes (ranges into `vertices`), appending to `out`.
    fn group(&mut self, vertices: &[[f64; 2]], outer: Range<usize>, holes: &[Range<usize>], out: &mut Vec<u32>) {
        self.rings.clear();
        let outer_vertices = &vertices[outer.clone()];
        let mut node = self.rings.link_ring(outer_vertices, outer.start as u32, signed_area(outer_vertices), true);
        if node == NIL || self.rings.next(node) == self.rings.prev(node) {
            return;
        }
        let outer_nodes = self.rings.nodes.len() as u32;
        self.holes.clear();
        for hole in holes {
            let ring = &vertices[hole.clone()];
            let start = self.rings.link_ring(ring, hole.start as u32, signed_area(ring), false);
            if start == NIL {
                continue;
            }
            if self.rings.next(start) == start {
                self.rings.set_mark(start, linked::mark::STEINER, true);
            }
            self.holes.push(start);
        }
        let total = outer.len() + holes.iter().map(Range::len).sum::<usize>();
        let hashed = total > HASH_THRESHOLD;
        // The outer ring's box, read from the input in order (walking the ring for it was a
        // tenth of bridging): the hash's extent and the bands' height.
        let shape = (hashed || !self.holes.is_empty()).then(|| RingShape::new(outer_vertices));
        // Without holes nothing is cut and nothing tidied: collinear points of the ring itself
        // wait for the slicer's first fallback, as in earcut (a pass over a small ring cost 13%
        // of it).
        if let Some(shape) = &shape
            && !self.holes.is_empty()
        {
            let mut hole_nodes = std::mem::take(&mut self.holes);
            let outer = holes::OuterRing { node, size: outer_nodes, y_range: [shape.min[1], shape.max[1]] };
            node = holes::eliminate_holes(&mut self.rings, &mut self.bands, &mut self.order, &outer, &mut hole_nodes);
            self.holes = hole_nodes;
        }
        let hash = shape.filter(|_| hashed).map(|shape| ZHash::new(shape.min, shape.max));
        Slicer {
            rings: &mut self.rings,
            hash,
            walk_budget: self.walk_budget,
            out,
            index: &mut self.zindex,
            jobs: &mut self.jobs,
            queue: &mut self.queue,
        }
        .run(node);
    }
}

/// Cuts every ring that crosses itself into simple loops (see [`crossings`]), appending the
/// crossing points and each loop's vertices to `positions`. Returns the ranges to triangulate
/// and, for each, the input ring it came from.
fn split_crossing_rings(
    positions: &mut Vec<[f64; 2]>,
    ranges: Vec<Range<usize>>,
    report: &mut TriangulationReport,
) -> (Vec<Range<usize>>, Vec<usize>) {
    let (mut out, mut ring_of) = (Vec::with_capacity(ranges.len()), Vec::with_capacity(ranges.len()));
    for (ring, range) in ranges.into_iter().enumerate() {
        let split = (range.len() <= crossings::MAX_CHECKED_POINTS)
            .then(|| crossings::split_crossings((range.start as u32..range.end as u32).collect(), positions))
            .filter(|split| split.crossings > 0);
        let Some(split) = split else {
            out.push(range);
            ring_of.push(ring);
            continue;
        };
        report.crossed.push((ring, split.crossings));
        for lobe in split.loops {
            let start = positions.len();
            positions.extend(lobe.iter().map(|&i| positions[i as usize]).collect::<Vec<_>>());
            out.push(start..positions.len());
            ring_of.push(ring);
        }
    }
    (out, ring_of)
}

/// The largest coordinate magnitude accepted: differences stay below 2e150, so the products
/// in areas and orientation tests (and sums of them) stay far below f64's 1.8e308.
pub const MAX_COORDINATE: f64 = 1e150;

/// Every ring's points in one array, and each ring's range in it.
type Concatenated = (Vec<[f64; 2]>, Vec<Range<usize>>);

/// [`Concatenated`] rings, their coordinates and count checked.
fn concatenate<R: AsRef<[[f64; 2]]>>(rings: &[R]) -> Result<Concatenated, TriangulateError> {
    let mut positions = Vec::new();
    let mut ranges = Vec::with_capacity(rings.len());
    for (index, ring) in rings.iter().enumerate() {
        let ring = ring.as_ref();
        check_coordinates(ring, index)?;
        ranges.push(positions.len()..positions.len() + ring.len());
        positions.extend_from_slice(ring);
    }
    check_count(positions.len())?;
    Ok((positions, ranges))
}

fn check_coordinates(ring: &[[f64; 2]], index: usize) -> Result<(), TriangulateError> {
    for (vertex, v) in ring.iter().enumerate() {
        for value in *v {
            if !value.is_finite() {
                return Err(TriangulateError::NonFinite { ring: index, vertex });
            }
            if value.abs() > MAX_COORDINATE {
                return Err(TriangulateError::TooLarge { ring: index, vertex, value });
            }
        }
    }
    Ok(())
}

fn check_count(vertices: usize) -> Result<(), TriangulateError> {
    if vertices >= u32::MAX as usize { Err(TriangulateError::TooManyVertices(vertices)) } else { Ok(()) }
}

/// The signed area of a ring that encloses something, or why it encloses nothing.
fn classify(ring: &[[f64; 2]]) -> Result<f64, DropReason> {
    let mut distinct = ring.to_vec();
    distinct.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    distinct.dedup();
    if distinct.len() < 3 {
        return Err(DropReason::TooFewPoints);
    }
    let area = signed_area(ring);
    let shape = RingShape::new(ring);
    let diagonal2 = (shape.max[0] - shape.min[0]).powi(2) + (shape.max[1] - shape.min[1]).powi(2);
    // Relative to the ring's size: collinear points leave only rounding noise.
    if area.abs() <= 1e-12 * diagonal2 { Err(DropReason::ZeroArea) } else { Ok(area) }
}

/// Σ |area| of the triangles.
fn triangle_area(positions: &[[f64; 2]], indices: &[u32]) -> f64 {
    indices
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]];
            ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs() / 2.0
        })
        .sum()
}

/// UVs from the bounding rectangle of all positions (0 along an axis of no extent).
fn bounding_rect_uvs(positions: &[[f64; 2]]) -> Vec<[f32; 2]> {
    let shape = RingShape::new(positions);
    let size = [shape.max[0] - shape.min[0], shape.max[1] - shape.min[1]];
    let axis = |v: f64, k: usize| if size[k] > 0.0 { ((v - shape.min[k]) / size[k]) as f32 } else { 0.0 };
    positions.iter().map(|p| [axis(p[0], 0), axis(p[1], 1)]).collect()
}

#[cfg(test)]
mod tests;
