//! A CPU version of the shader's membership test and pixel mapping (one sample at the pixel
//! centre), in f32 like the GPU. Tests compare the GPU image against it.

/// Wraps x into [left, left + width).
fn wrap(x: f32, width: f32, left: f32) -> f32 {
    let shifted = x - left;
    shifted - width * (shifted / width).floor() + left
}

/// The escape-time test of `kleinian.wgsl::in_limit_set`.
pub fn in_limit_set(start: [f32; 2], t: [f32; 2], iterations: u32) -> bool {
    classify(start, t, iterations).0
}

/// (hit, loop iterations run) — the second is the sample's cost on the GPU.
pub fn classify(start: [f32; 2], t: [f32; 2], iterations: u32) -> (bool, u32) {
    let [u, v] = t;
    let [mut x, mut y] = start;
    if y < 0.0 || y > u {
        return (false, 0);
    }
    let (mut lz, mut llz) = ([x + 1.0, y + 1.0], [x - 1.0, y - 1.0]);
    for i in 0..iterations {
        let shear = v / u * y;
        x = wrap(x + shear, 2.0, -1.0) - shear;
        let d = x + v * 0.5;
        let separation = u * 0.5
            + v.signum_or_zero() * (2.0 * u - 1.95) / 4.0
                * d.signum_or_zero()
                * (1.0 - (-(7.2 - (1.95 - u) * 15.0) * d.abs()).exp());
        if y >= separation {
            (x, y) = (-v - x, u - y);
        }
        let r2 = x * x + y * y;
        (x, y) = (x / r2 - v, -y / r2 + u);
        if y < 0.0 {
            return (true, i + 1);
        }
        // |z - z''| < 1e-6, squared as in the shader.
        if (x - llz[0]).powi(2) + (y - llz[1]).powi(2) < 1e-12 {
            return (false, i + 1);
        }
        llz = lz;
        lz = [x, y];
    }
    (false, iterations)
}

/// The fractal-plane point at the centre of pixel (px, py) (y down) of a `height`-tall image.
pub fn pixel_to_plane(px: u32, py: u32, height: u32, scale: f32, offset: [f32; 2]) -> [f32; 2] {
    let h = height as f32;
    let uv = [(px as f32 + 0.5) / h, 1.0 - (py as f32 + 0.5) / h];
    [uv[0] * scale + offset[0], uv[1] * scale + offset[1]]
}

/// WGSL's `sign`: 0 at 0 (Rust's `signum` gives ±1 there).
trait SignOrZero {
    fn signum_or_zero(self) -> Self;
}

impl SignOrZero for f32 {
    fn signum_or_zero(self) -> f32 {
        if self == 0.0 { 0.0 } else { self.signum() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classic_set_basics() {
        let t = [2.0, 0.0];
        // a maps the disk |z - i/4| < 1/4 (the inverse of the line y = u = 2) below y = 0.
        assert!(in_limit_set([0.0, 0.2], t, 200));
        assert!(in_limit_set([2.0, 0.2], t, 200), "period 2 along x");
        assert!(in_limit_set([0.0, 1.8], t, 200), "point symmetry about (-v/2, u/2) = (0, 1)");
        // (0, 1) is the fixed point of the reflection and of a: it cycles, never escapes.
        assert!(!in_limit_set([0.0, 1.0], t, 200));
        assert!(!in_limit_set([0.0, -0.1], t, 200), "below the strip");
        assert!(!in_limit_set([0.0, 2.1], t, 200), "above the strip");
    }
}
