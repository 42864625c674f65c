//! Projection-mapping geometry: the corner pin (a homography from the unit square to four
//! corners, exact for a flat wall), the mesh warp (a grid of control points for curved walls) and
//! soft edge blending (ramps that sum to one where two projectors overlap), plus the RON warp
//! file that stores one output's warp.
//!
//! Coordinates are view units: 0–1 across the output, y up, like every pointer parameter. The
//! source image's own coordinates (u, v) are 0–1 too, v up.

use serde::{Deserialize, Serialize};

/// Most control points a mesh has along one side.
pub const MAX_MESH_SIDE: u32 = 16;

/// A projective map of the plane, as the 3×3 matrix `m` (row-major) acting on (x, y, 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homography {
    /// Row-major: x' = m[0]·(x, y, 1), y' = m[1]·…, w = m[2]·….
    pub m: [[f64; 3]; 3],
}

impl Homography {
    /// The map that takes the unit square's corners (0,0), (1,0), (1,1), (0,1) to `quad`'s four
    /// points in that order (Heckbert's square-to-quad). A degenerate quad (three corners on a
    /// line) falls back to the affine map through the first, second and fourth corner, so a
    /// corner dragged through its neighbours never produces NaNs.
    pub fn square_to_quad(quad: [[f64; 2]; 4]) -> Self {
        let [q0, q1, q2, q3] = quad;
        let sx = q0[0] - q1[0] + q2[0] - q3[0];
        let sy = q0[1] - q1[1] + q2[1] - q3[1];
        let affine =
            Self { m: [[q1[0] - q0[0], q3[0] - q0[0], q0[0]], [q1[1] - q0[1], q3[1] - q0[1], q0[1]], [0.0, 0.0, 1.0]] };
        if sx.abs() < 1e-12 && sy.abs() < 1e-12 {
            return affine;
        }
        let (dx1, dx2) = (q1[0] - q2[0], q3[0] - q2[0]);
        let (dy1, dy2) = (q1[1] - q2[1], q3[1] - q2[1]);
        let den = dx1 * dy2 - dx2 * dy1;
        if den.abs() < 1e-12 {
            return affine;
        }
        let g = (sx * dy2 - dx2 * sy) / den;
        let h = (dx1 * sy - sx * dy1) / den;
        let m = [
            [q1[0] - q0[0] + g * q1[0], q3[0] - q0[0] + h * q3[0], q0[0]],
            [q1[1] - q0[1] + g * q1[1], q3[1] - q0[1] + h * q3[1], q0[1]],
            [g, h, 1.0],
        ];
        if m.iter().flatten().all(|v| v.is_finite()) { Self { m } } else { affine }
    }

    /// Where `p` lands (None where the map sends it to infinity).
    pub fn apply(&self, p: [f64; 2]) -> Option<[f64; 2]> {
        let row = |r: [f64; 3]| r[0] * p[0] + r[1] * p[1] + r[2];
        let w = row(self.m[2]);
        (w.abs() > 1e-15).then(|| [row(self.m[0]) / w, row(self.m[1]) / w])
    }

    /// The inverse map (the adjugate; None for a singular matrix).
    pub fn inverse(&self) -> Option<Self> {
        let m = self.m;
        let cof = |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
        let adj = [
            [cof(1, 2, 1, 2), -cof(0, 2, 1, 2), cof(0, 1, 1, 2)],
            [-cof(1, 2, 0, 2), cof(0, 2, 0, 2), -cof(0, 1, 0, 2)],
            [cof(1, 2, 0, 1), -cof(0, 2, 0, 1), cof(0, 1, 0, 1)],
        ];
        let det = m[0][0] * adj[0][0] + m[0][1] * adj[1][0] + m[0][2] * adj[2][0];
        (det.abs() > 1e-15 && det.is_finite()).then(|| Self { m: adj.map(|r| r.map(|v| v / det)) })
    }

    /// The matrix as three columns of a WGSL `mat3x3<f32>` (each padded to four floats).
    pub fn to_wgsl_columns(&self) -> [[f32; 4]; 3] {
        let m = self.m;
        std::array::from_fn(|c| [m[0][c] as f32, m[1][c] as f32, m[2][c] as f32, 0.0])
    }
}

/// How a mesh runs between its control points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum MeshInterpolation {
    /// Straight between neighbouring points (bilinear cells).
    Linear,
    /// A smooth surface through every point (Catmull-Rom in both directions), for curved walls.
    #[default]
    Smooth,
}

/// A grid of control points over the source image: point (i, j) is where the source's
/// (i / (columns − 1), j / (rows − 1)) lands, before the corner pin. Rows run bottom to top, each
/// left to right. A regular grid changes nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeshWarp {
    /// Control points across (2 to [`MAX_MESH_SIDE`]).
    pub columns: u32,
    /// Control points up (2 to [`MAX_MESH_SIDE`]).
    pub rows: u32,
    /// How the surface runs between points.
    #[serde(default)]
    pub interpolation: MeshInterpolation,
    /// `columns × rows` points, row by row from the bottom.
    pub points: Vec<[f32; 2]>,
}

impl MeshWarp {
    /// The regular (identity) grid of `columns × rows` points.
    pub fn regular(columns: u32, rows: u32) -> Self {
        let (c, r) = (columns.clamp(2, MAX_MESH_SIDE), rows.clamp(2, MAX_MESH_SIDE));
        let points =
            (0..r).flat_map(|j| (0..c).map(move |i| [i as f32 / (c - 1) as f32, j as f32 / (r - 1) as f32])).collect();
        Self { columns: c, rows: r, interpolation: MeshInterpolation::default(), points }
    }

    /// What is wrong with it, if anything (sizes, point count, non-finite points).
    pub fn problem(&self) -> Option<String> {
        let sides = 2..=MAX_MESH_SIDE;
        if !sides.contains(&self.columns) || !sides.contains(&self.rows) {
            return Some(format!(
                "a mesh of {}×{} points: each side needs 2 to {MAX_MESH_SIDE}",
                self.columns, self.rows
            ));
        }
        let expected = (self.columns * self.rows) as usize;
        if self.points.len() != expected {
            return Some(format!(
                "a {}×{} mesh needs {expected} points, the file has {}",
                self.columns,
                self.rows,
                self.points.len()
            ));
        }
        if let Some(i) = self.points.iter().position(|p| !(p[0].is_finite() && p[1].is_finite())) {
            return Some(format!("mesh point {i} is not a finite number"));
        }
        None
    }

    /// Whether it is the identity (every point where the regular grid has it).
    pub fn is_identity(&self) -> bool {
        self.points == Self::regular(self.columns, self.rows).points
    }

    /// The control points with the extrapolated ring around them that the surface reads:
    /// `(columns + 2) × (rows + 2)`, row by row from the bottom, starting at (−1, −1).
    pub fn extended_points(&self) -> Vec<[f32; 2]> {
        let (c, r) = (i64::from(self.columns), i64::from(self.rows));
        (-1..=r).flat_map(|j| (-1..=c).map(move |i| (i, j))).map(|(i, j)| self.point(i, j)).collect()
    }

    /// Control point (i, j); one step outside the grid it is extrapolated linearly (2·edge −
    /// next), so the smooth surface reproduces a regular grid exactly, border cells included.
    fn point(&self, i: i64, j: i64) -> [f32; 2] {
        let (c, r) = (i64::from(self.columns), i64::from(self.rows));
        let beyond = |k: i64, n: i64| {
            if k < 0 {
                Some((0, 1))
            } else if k >= n {
                Some((n - 1, n - 2))
            } else {
                None
            }
        };
        if let Some((edge, next)) = beyond(i, c) {
            let (a, b) = (self.point(edge, j), self.point(next, j));
            return [2.0 * a[0] - b[0], 2.0 * a[1] - b[1]];
        }
        if let Some((edge, next)) = beyond(j, r) {
            let (a, b) = (self.point(i, edge), self.point(i, next));
            return [2.0 * a[0] - b[0], 2.0 * a[1] - b[1]];
        }
        self.points[(j * c + i) as usize]
    }

    /// Where the source point (u, v) lands before the corner pin.
    pub fn evaluate(&self, u: f32, v: f32) -> [f32; 2] {
        let x = u.clamp(0.0, 1.0) * (self.columns - 1) as f32;
        let y = v.clamp(0.0, 1.0) * (self.rows - 1) as f32;
        let (i, j) =
            ((x.floor() as i64).min(i64::from(self.columns) - 2), (y.floor() as i64).min(i64::from(self.rows) - 2));
        let (s, t) = (x - i as f32, y - j as f32);
        let weights = |t: f32| match self.interpolation {
            MeshInterpolation::Linear => [0.0, 1.0 - t, t, 0.0],
            // Catmull-Rom: through every point, C1.
            MeshInterpolation::Smooth => {
                let (t2, t3) = (t * t, t * t * t);
                [
                    0.5 * (-t3 + 2.0 * t2 - t),
                    0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
                    0.5 * (-3.0 * t3 + 4.0 * t2 + t),
                    0.5 * (t3 - t2),
                ]
            }
        };
        let (wu, wv) = (weights(s), weights(t));
        let mut out = [0.0f32; 2];
        for (b, wb) in wv.iter().enumerate() {
            for (a, wa) in wu.iter().enumerate() {
                let p = self.point(i + a as i64 - 1, j + b as i64 - 1);
                out[0] += wa * wb * p[0];
                out[1] += wa * wb * p[1];
            }
        }
        out
    }
}

/// Soft edges: each side fades over `width` (a share of the source, 0–0.5) along Bourke's ramp of
/// exponent `curve`, in linear light, so two projectors whose overlaps carry complementary ramps
/// add up to the image. `gamma` bends the weight for a projector that does not follow sRGB.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EdgeBlend {
    /// Width of the fade on the left side.
    pub left: f32,
    /// … right side.
    pub right: f32,
    /// … top side.
    pub top: f32,
    /// … bottom side.
    pub bottom: f32,
    /// Ramp exponent: 1 linear, 2 the usual S-curve, higher is steeper in the middle.
    pub curve: f32,
    /// Exponent applied to the product of the ramps (1: exact in linear light).
    pub gamma: f32,
}

impl Default for EdgeBlend {
    fn default() -> Self {
        Self { left: 0.0, right: 0.0, top: 0.0, bottom: 0.0, curve: 2.0, gamma: 1.0 }
    }
}

/// Bourke's blend ramp at `t` in [0, 1]: 0 → 0, 1 → 1, and ramp(t) + ramp(1 − t) = 1 for any
/// exponent, which is what makes two overlapping projectors sum to one.
pub fn blend_ramp(t: f32, curve: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    if t < 0.5 { 0.5 * (2.0 * t).powf(curve) } else { 1.0 - 0.5 * (2.0 * (1.0 - t)).powf(curve) }
}

impl EdgeBlend {
    /// The weight at source point (u, v) (the shader computes the same).
    pub fn weight(&self, u: f32, v: f32) -> f32 {
        let side = |x: f32, width: f32| if width <= 0.0 { 1.0 } else { blend_ramp(x / width, self.curve) };
        let w = side(u, self.left) * side(1.0 - u, self.right) * side(v, self.bottom) * side(1.0 - v, self.top);
        w.powf(self.gamma)
    }
}

/// The four corners of the corner pin, where the source's corners land on the output.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Corners {
    /// Where the source's top-left corner lands.
    pub top_left: [f32; 2],
    /// … top-right.
    pub top_right: [f32; 2],
    /// … bottom-right.
    pub bottom_right: [f32; 2],
    /// … bottom-left.
    pub bottom_left: [f32; 2],
}

impl Default for Corners {
    fn default() -> Self {
        Self { top_left: [0.0, 1.0], top_right: [1.0, 1.0], bottom_right: [1.0, 0.0], bottom_left: [0.0, 0.0] }
    }
}

impl Corners {
    /// The corner pin: unit square → these corners.
    pub fn homography(&self) -> Homography {
        let f = |p: [f32; 2]| [f64::from(p[0]), f64::from(p[1])];
        Homography::square_to_quad([f(self.bottom_left), f(self.bottom_right), f(self.top_right), f(self.top_left)])
    }
}

/// The part of the source an output shows (source units, v up): two projectors side by side
/// show overlapping halves, e.g. left 0–0.6 and 0.4–1.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Region {
    /// Lower-left corner.
    pub min: [f32; 2],
    /// Upper-right corner.
    pub max: [f32; 2],
}

impl Default for Region {
    fn default() -> Self {
        Self { min: [0.0, 0.0], max: [1.0, 1.0] }
    }
}

/// One output's warp as stored on disk (RON).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WarpFile {
    /// The part of the source shown (default: all of it).
    pub region: Region,
    /// The corner pin.
    pub corners: Corners,
    /// Soft edges.
    pub blend: EdgeBlend,
    /// Brightness (linear, 0–0.25) added outside the blend zones so black matches the overlap,
    /// where two projectors' blacks add up.
    pub black_lift: f32,
    /// The mesh warp, if any.
    pub mesh: Option<MeshWarp>,
}

impl WarpFile {
    /// Reads a warp from RON text; `origin` names it in errors (with line and column).
    pub fn parse(origin: &str, text: &str) -> Result<Self, String> {
        let warp: Self = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str(text)
            .map_err(|e| format!("{origin}:{}:{}: {}", e.span.start.line, e.span.start.col, e.code))?;
        warp.problem().map_or(Ok(warp), |p| Err(format!("{origin}: {p}")))
    }

    /// What is wrong with the values, if anything.
    pub fn problem(&self) -> Option<String> {
        let c = &self.corners;
        let corners = [c.top_left, c.top_right, c.bottom_right, c.bottom_left];
        if corners.iter().flatten().any(|v| !v.is_finite()) {
            return Some("a corner is not a finite number".into());
        }
        let r = &self.region;
        let inside = |v: f32| (0.0..=1.0).contains(&v);
        if !(r.min.iter().chain(&r.max).all(|&v| inside(v)) && r.min[0] < r.max[0] && r.min[1] < r.max[1]) {
            return Some("region must have 0 ≤ min < max ≤ 1 on both axes".into());
        }
        let b = &self.blend;
        if [b.left, b.right, b.top, b.bottom].iter().any(|w| !(0.0..=0.5).contains(w)) {
            return Some("blend widths must be between 0 and 0.5 (a share of the image)".into());
        }
        if !(b.curve > 0.0 && b.curve <= 16.0 && b.gamma > 0.0 && b.gamma <= 8.0) {
            return Some("blend curve must be in (0, 16] and gamma in (0, 8]".into());
        }
        if !(0.0..=0.25).contains(&self.black_lift) {
            return Some("black_lift must be between 0 and 0.25".into());
        }
        self.mesh.as_ref().and_then(MeshWarp::problem)
    }

    /// The RON text [`WarpFile::parse`] reads back to the same warp.
    pub fn to_ron(&self) -> String {
        let config = ron::ser::PrettyConfig::new().depth_limit(3).struct_names(false);
        let body = ron::ser::to_string_pretty(self, config).unwrap_or_default();
        format!("// indra warp: corner pin, edge blend and mesh of one output (view units, y up)\n{body}\n")
    }

    /// Where source point (u, v) lands on the output (mesh, then corner pin).
    pub fn map(&self, u: f32, v: f32) -> Option<[f64; 2]> {
        let p = self.mesh.as_ref().map_or([u, v], |m| m.evaluate(u, v));
        self.corners.homography().apply([f64::from(p[0]), f64::from(p[1])])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 2], b: [f64; 2], eps: f64) -> bool {
        (a[0] - b[0]).abs() < eps && (a[1] - b[1]).abs() < eps
    }

    #[test]
    fn the_corner_pin_sends_the_square_corners_to_the_quad_and_back() {
        let quads = [
            [[0.1, 0.05], [0.93, 0.12], [0.8, 0.97], [0.02, 0.88]],
            [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            [[0.2, 0.2], [0.6, 0.2], [0.9, 0.8], [0.1, 0.8]],
            [[-0.3, 0.1], [1.4, -0.2], [1.1, 1.3], [0.0, 0.9]],
        ];
        for quad in quads {
            let h = Homography::square_to_quad(quad);
            let inv = h.inverse().unwrap();
            for (corner, target) in [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].into_iter().zip(quad) {
                assert!(close(h.apply(corner).unwrap(), target, 1e-12), "{corner:?} → {target:?}");
                assert!(close(inv.apply(target).unwrap(), corner, 1e-9));
            }
            // Straight lines stay straight: the centre is where the quad's diagonals cross.
            let c = h.apply([0.5, 0.5]).unwrap();
            let side =
                |a: [f64; 2], b: [f64; 2], p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
            assert!(side(quad[0], quad[2], c).abs() < 1e-12 && side(quad[1], quad[3], c).abs() < 1e-12);
        }
    }

    #[test]
    fn a_degenerate_quad_is_affine_not_nan() {
        let h = Homography::square_to_quad([[0.0, 0.0], [0.5, 0.5], [1.0, 1.0], [0.0, 1.0]]);
        assert!(h.m.iter().flatten().all(|v| v.is_finite()));
    }

    #[test]
    fn complementary_ramps_sum_to_one_for_every_curve() {
        for curve in [0.5, 1.0, 2.0, 3.7, 8.0] {
            for i in 0..=100 {
                let t = i as f32 / 100.0;
                let sum = blend_ramp(t, curve) + blend_ramp(1.0 - t, curve);
                assert!((sum - 1.0).abs() < 1e-6, "curve {curve}, t {t}: {sum}");
            }
        }
        assert_eq!(blend_ramp(0.0, 2.0), 0.0);
        assert_eq!(blend_ramp(1.0, 2.0), 1.0);
    }

    #[test]
    fn two_projectors_overlapping_by_a_fifth_sum_to_one_in_linear_light() {
        // Projector A shows source x in [0, 0.6], B shows [0.4, 1]: each has its own u in 0–1.
        let a = EdgeBlend { right: 1.0 / 3.0, ..Default::default() };
        let b = EdgeBlend { left: 1.0 / 3.0, ..Default::default() };
        for i in 0..=100 {
            let x = i as f32 / 100.0;
            let wa = if x <= 0.6 { a.weight(x / 0.6, 0.5) } else { 0.0 };
            let wb = if x >= 0.4 { b.weight((x - 0.4) / 0.6, 0.5) } else { 0.0 };
            assert!((wa + wb - 1.0).abs() < 1e-5, "x {x}: {wa} + {wb}");
        }
    }

    #[test]
    fn a_regular_mesh_changes_nothing_and_a_smooth_one_passes_through_its_points() {
        for interpolation in [MeshInterpolation::Linear, MeshInterpolation::Smooth] {
            let mut mesh = MeshWarp { interpolation, ..MeshWarp::regular(4, 3) };
            for (u, v) in [(0.0, 0.0), (0.3, 0.7), (1.0, 1.0), (0.5, 0.5)] {
                let p = mesh.evaluate(u, v);
                assert!((p[0] - u).abs() < 1e-6 && (p[1] - v).abs() < 1e-6, "{interpolation:?} ({u}, {v}) → {p:?}");
            }
            mesh.points[5] = [0.4, 0.6];
            let p = mesh.evaluate(1.0 / 3.0, 0.5);
            assert!((p[0] - 0.4).abs() < 1e-6 && (p[1] - 0.6).abs() < 1e-6, "{p:?}");
        }
    }

    #[test]
    fn warp_files_round_trip_and_bad_ones_say_where() {
        let warp = WarpFile {
            region: Region { min: [0.4, 0.0], max: [1.0, 1.0] },
            corners: Corners { top_left: [0.05, 0.9], ..Default::default() },
            blend: EdgeBlend { right: 0.2, curve: 3.0, ..Default::default() },
            black_lift: 0.02,
            mesh: Some(MeshWarp {
                points: {
                    let mut m = MeshWarp::regular(3, 3);
                    m.points[4] = [0.52, 0.47];
                    m.points
                },
                ..MeshWarp::regular(3, 3)
            }),
        };
        assert_eq!(WarpFile::parse("w.ron", &warp.to_ron()).unwrap(), warp);
        assert_eq!(WarpFile::parse("w.ron", "()").unwrap(), WarpFile::default());
        let e = WarpFile::parse("w.ron", "(\n  corners: (top_left: (0.0, 1.0)),\n)").unwrap_err();
        assert!(e.starts_with("w.ron:2:"), "{e}");
        let e = WarpFile::parse("w.ron", "(blend: (left: 0.9))").unwrap_err();
        assert!(e.contains("between 0 and 0.5"), "{e}");
        let e = WarpFile::parse("w.ron", "(mesh: (columns: 3, rows: 2, points: [(0.0, 0.0)]))").unwrap_err();
        assert!(e.contains("needs 6 points"), "{e}");
        let e = WarpFile::parse("w.ron", "(region: (min: (0.6, 0.0), max: (0.4, 1.0)))").unwrap_err();
        assert!(e.contains("region"), "{e}");
        let e = WarpFile::parse("w.ron", "(colour: 1)").unwrap_err();
        assert!(e.contains("colour"), "{e}");
    }
}
