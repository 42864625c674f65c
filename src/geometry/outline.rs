//! Outlines to rings: flattens lines, quadratic and cubic Béziers into closed point rings (for
//! triangulation), from SVG path data or any other path source such as font glyphs.

/// Collects path commands into flattened rings. Curves are split into segments so that the
/// polyline stays within `tolerance` of the curve.
#[derive(Debug, Clone)]
pub struct RingBuilder {
    tolerance: f64,
    rings: Vec<Vec<[f64; 2]>>,
    current: Vec<[f64; 2]>,
}

impl RingBuilder {
    /// A builder with the given flattening tolerance (in path units).
    pub fn new(tolerance: f64) -> Self {
        Self { tolerance: tolerance.max(1e-9), rings: Vec::new(), current: Vec::new() }
    }

    fn last(&self) -> [f64; 2] {
        self.current.last().copied().unwrap_or([0.0, 0.0])
    }

    /// Starts a new ring (closing the current one).
    pub fn move_to(&mut self, p: [f64; 2]) {
        self.close();
        self.current.push(p);
    }

    /// A straight segment.
    pub fn line_to(&mut self, p: [f64; 2]) {
        self.current.push(p);
    }

    /// A quadratic Bézier with control point `c`.
    pub fn quad_to(&mut self, c: [f64; 2], p: [f64; 2]) {
        let a = self.last();
        // Segments from the curve's second difference: error ≤ |a − 2c + p| / (8 n²).
        let dd = ((a[0] - 2.0 * c[0] + p[0]).powi(2) + (a[1] - 2.0 * c[1] + p[1]).powi(2)).sqrt();
        let n = ((dd / (8.0 * self.tolerance)).sqrt().ceil() as usize).clamp(1, 256);
        for i in 1..=n {
            let t = i as f64 / n as f64;
            let u = 1.0 - t;
            self.current.push([
                u * u * a[0] + 2.0 * u * t * c[0] + t * t * p[0],
                u * u * a[1] + 2.0 * u * t * c[1] + t * t * p[1],
            ]);
        }
    }

    /// A cubic Bézier with control points `c1`, `c2`.
    pub fn cubic_to(&mut self, c1: [f64; 2], c2: [f64; 2], p: [f64; 2]) {
        let a = self.last();
        // Bound the second derivative by its values at both ends (it is linear in t).
        let dd = |x0: [f64; 2], x1: [f64; 2], x2: [f64; 2]| {
            ((x0[0] - 2.0 * x1[0] + x2[0]).powi(2) + (x0[1] - 2.0 * x1[1] + x2[1]).powi(2)).sqrt()
        };
        let m = dd(a, c1, c2).max(dd(c1, c2, p)) * 6.0;
        let n = ((m / (8.0 * self.tolerance)).sqrt().ceil() as usize).clamp(1, 256);
        for i in 1..=n {
            let t = i as f64 / n as f64;
            let u = 1.0 - t;
            let (b0, b1, b2, b3) = (u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t);
            self.current.push([
                b0 * a[0] + b1 * c1[0] + b2 * c2[0] + b3 * p[0],
                b0 * a[1] + b1 * c1[1] + b2 * c2[1] + b3 * p[1],
            ]);
        }
    }

    /// Ends the current ring (a last point equal to the first is dropped).
    pub fn close(&mut self) {
        if self.current.len() > 1 && self.current.first() == self.current.last() {
            self.current.pop();
        }
        if !self.current.is_empty() {
            self.rings.push(std::mem::take(&mut self.current));
        }
    }

    /// The rings so far (the current one closed).
    pub fn finish(mut self) -> Vec<Vec<[f64; 2]>> {
        self.close();
        self.rings
    }
}

/// Flattens SVG path data (`d` attribute: all commands, relative or absolute, arcs included)
/// into rings.
///
/// # Errors
/// A syntax error in the path data, with its position.
pub fn svg_path_rings(data: &str, tolerance: f64) -> Result<Vec<Vec<[f64; 2]>>, String> {
    use svgtypes::{SimplePathSegment as S, SimplifyingPathParser};
    let mut builder = RingBuilder::new(tolerance);
    for segment in SimplifyingPathParser::from(data) {
        match segment.map_err(|e| format!("SVG path data: {e}"))? {
            S::MoveTo { x, y } => builder.move_to([x, y]),
            S::LineTo { x, y } => builder.line_to([x, y]),
            S::Quadratic { x1, y1, x, y } => builder.quad_to([x1, y1], [x, y]),
            S::CurveTo { x1, y1, x2, y2, x, y } => builder.cubic_to([x1, y1], [x2, y2], [x, y]),
            S::ClosePath => builder.close(),
        }
    }
    Ok(builder.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_with_a_hole_and_relative_commands() {
        let rings = svg_path_rings("M0 0 H10 V10 H0 Z m2 2 v6 h6 v-6 z", 0.1).unwrap();
        assert_eq!(
            rings,
            vec![
                vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]],
                vec![[2.0, 2.0], [2.0, 8.0], [8.0, 8.0], [8.0, 2.0]],
            ]
        );
    }

    #[test]
    fn curves_stay_within_tolerance() {
        // A circle of radius 100 from four arcs: every flattened point lies on it, and chords
        // deviate by less than the tolerance.
        let rings = svg_path_rings(
            "M100 0 A100 100 0 0 1 0 100 A100 100 0 0 1 -100 0 A100 100 0 0 1 0 -100 A100 100 0 0 1 100 0 Z",
            0.5,
        )
        .unwrap();
        let ring = &rings[0];
        assert!(ring.len() > 16);
        for (i, p) in ring.iter().enumerate() {
            let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
            assert!((r - 100.0).abs() < 0.05, "point {i} at radius {r}");
            let q = ring[(i + 1) % ring.len()];
            let mid = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
            assert!(100.0 - (mid[0] * mid[0] + mid[1] * mid[1]).sqrt() < 0.5);
        }
    }

    #[test]
    fn bad_path_data_is_an_error() {
        assert!(svg_path_rings("M0 0 L10 x", 0.1).unwrap_err().contains("SVG path data"));
    }
}
