//! The cubes alive at a given time, as a pure function of time, parameters and seed: cube `i` is
//! born at `i / rate` seconds (negative `i` were born before the show started, so the field is
//! full from frame 0, as the sample's prewarmed particle system).

use std::f32::consts::TAU;

use super::Settings;
use crate::time::FrameTime;

/// Most cubes drawn (rate × life beyond this keeps the newest).
pub const MAX_CUBES: usize = 8192;

/// One cube as the vertex shader reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CubeInstance {
    /// Centre (xyz) and edge length (w).
    pub position_size: [f32; 4],
    /// Unit quaternion (x, y, z, w).
    pub rotation: [f32; 4],
}

/// Fills `out` with the cubes alive at `time`.
pub fn cubes_at(p: &Settings, time: &FrameTime, out: &mut Vec<CubeInstance>) {
    out.clear();
    let (rate, life) = (f64::from(p.rate), f64::from(p.life));
    if rate <= 0.0 {
        return;
    }
    let now = time.seconds;
    let newest = (now * rate).floor() as i64;
    let oldest = ((now - life) * rate).floor() as i64 + 1;
    let oldest = oldest.max(newest - MAX_CUBES as i64 + 1);
    let [w, h] = p.emitter_size;
    let (distance, speed, size) = (p.emitter_distance, p.speed, p.cube_size);
    let spin = p.spin.to_radians();
    for i in oldest..=newest {
        let age = (now - i as f64 / rate) as f32;
        let r = |k: u64| unit_random(time.seed, i, k);
        let start = glam::Vec3::new((r(0) - 0.5) * w, (r(1) - 0.5) * h, distance);
        let position = start + glam::Vec3::NEG_Z * speed * age;
        let initial = glam::Quat::from_euler(glam::EulerRot::XYZ, r(2) * TAU, r(3) * TAU, r(4) * TAU);
        let spinning = glam::Quat::from_euler(glam::EulerRot::XYZ, spin * age, spin * age, spin * age);
        let q = (initial * spinning).normalize();
        out.push(CubeInstance { position_size: [position.x, position.y, position.z, size], rotation: q.to_array() });
    }
}

/// A uniform number in [0, 1) from (seed, particle, stream), by SplitMix64.
fn unit_random(seed: u64, particle: i64, stream: u64) -> f32 {
    let mut z =
        seed ^ (particle as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 24) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{ParamSet, ParamValue};

    fn at(seconds: f64, p: &ParamSet) -> Vec<CubeInstance> {
        let mut out = Vec::new();
        cubes_at(&super::super::Settings::read(p), &FrameTime { frame: 0, seconds, dt: 0.0, seed: 3 }, &mut out);
        out
    }

    #[test]
    fn the_field_is_full_from_the_start_and_stays_rate_times_life() {
        let p = ParamSet::new(super::super::Settings::decls());
        for t in [0.0, 0.5, 7.25, 100.0] {
            let n = at(t, &p).len();
            assert!((999..=1001).contains(&n), "{n} cubes at {t} s");
        }
    }

    #[test]
    fn cubes_move_towards_the_camera_and_stay_in_the_emitter_footprint() {
        let p = ParamSet::new(super::super::Settings::decls());
        let cubes = at(3.0, &p);
        for c in &cubes {
            let [x, y, z, _] = c.position_size;
            assert!(x.abs() <= 2.5 && y.abs() <= 5.0, "{x} {y}");
            assert!((2.0 - 1e-3..=12.0 + 1e-3).contains(&z), "{z}");
            let q = glam::Quat::from_array(c.rotation);
            assert!((q.length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn same_time_and_seed_give_the_same_field() {
        let mut p = ParamSet::new(super::super::Settings::decls());
        assert_eq!(at(4.2, &p), at(4.2, &p));
        p.set_at(p.index("rate").unwrap(), ParamValue::Float(0.0));
        assert!(at(4.2, &p).is_empty());
    }
}
