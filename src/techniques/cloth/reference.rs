//! A CPU version of one Verlet substep of `cloth.wgsl`, for checking the GPU on small
//! grids.

use super::ClothUniforms;

const OFFSETS: [(i32, i32); 12] =
    [(-1, -1), (0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-2, 0), (2, 0), (0, -2), (0, 2)];

/// One explicit Verlet substep: (previous, current) → next, the wind pushing along `normals`
/// (the normals buffer as the last clock step left it).
pub fn verlet_step(u: &ClothUniforms, prev: &[[f32; 4]], cur: &[[f32; 4]], normals: &[[f32; 4]]) -> Vec<[f32; 4]> {
    let res = u.res as i32;
    (0..cur.len())
        .map(|i| {
            let x = cur[i];
            if x[3] == 0.0 {
                return x;
            }
            let (ci, cj) = (i as i32 % res, i as i32 / res);
            let wind = wind_on(u, normals[i]);
            let mut f = [0.0f32; 3];
            for k in 0..3 {
                let v = (x[k] - prev[i][k]) / u.dt;
                f[k] = (u.acceleration[k] + wind[k]) * u.mass - u.damping * v;
            }
            for (dx, dy) in OFFSETS {
                let (ni, nj) = (ci + dx, cj + dy);
                if ni < 0 || nj < 0 || ni >= res || nj >= res {
                    continue;
                }
                let o = cur[(nj * res + ni) as usize];
                let d = [o[0] - x[0], o[1] - x[1], o[2] - x[2]];
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let rest = ((dx * dx + dy * dy) as f32).sqrt() * u.rest;
                for k in 0..3 {
                    f[k] += u.stiffness * (len - rest) * d[k] / len.max(1e-9);
                }
            }
            let mut p = [0.0f32; 3];
            for k in 0..3 {
                p[k] = 2.0 * x[k] - prev[i][k] + f[k] / u.mass * u.dt * u.dt;
            }
            let c = u.sphere;
            let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if u.sphere_radius > 0.0 && len < u.sphere_radius {
                for k in 0..3 {
                    p[k] = c[k] + d[k] / len.max(1e-6) * u.sphere_radius;
                }
            }
            [p[0], p[1], p[2], x[3]]
        })
        .collect()
}

/// The wind's acceleration along the normal `n`.
fn wind_on(u: &ClothUniforms, n: [f32; 4]) -> [f32; 3] {
    let along = u.wind[0] * n[0] + u.wind[1] * n[1] + u.wind[2] * n[2];
    [along * n[0], along * n[1], along * n[2]]
}
