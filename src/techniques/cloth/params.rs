//! Cloth parameters and the uniform block built from them.

use crate::params::{InputRole, ParamDecl, ParamValue};
use crate::techniques::Rasterizer;
use crate::time::FrameTime;

crate::param_enum! {
    /// The cloth solver.
    pub enum Solver {
        /// The book's mass-spring model.
        Verlet = "Verlet",
        /// Stiff small-step constraints.
        Xpbd = "XPBD",
    }
}

crate::param_enum! {
    /// Which particles are fixed.
    pub enum Pin {
        /// The whole top row.
        TopRow = "TopRow",
        /// The top row's two corners.
        TwoCorners = "TwoCorners",
        /// None: the cloth falls.
        None = "None",
    }
}

crate::param_enum! {
    /// What is drawn.
    pub enum View {
        /// The lit surface.
        Lit = "Lit",
        /// Particles and springs coloured by kind.
        Debug = "Debug",
    }
}

crate::technique_params! {
    /// What a cloth node reads each step, with the sample's C# defaults (seed-reference §3). The
    /// sample's `TimeStep` is the scene's fixed `dt`: each clock step simulates exactly dt
    /// seconds in `substeps` parts.
    pub struct Settings {
        /// Verlet: the book's mass-spring model; XPBD: stiff small-step constraints
        solver: Solver = |n, doc| ParamDecl::choice(n, Solver::OPTIONS, 0, doc),
        /// particles per side (changing it resets)
        resolution: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(128), Some((4.0, 1024.0)), doc),
        /// solver steps per clock step (the sample's VerletIterationNum)
        substeps: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(4), Some((1.0, 64.0)), doc),
        /// structural spring length
        rest_length: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.02), Some((0.001, 1.0)), doc).with_unit("m"),
        /// Verlet spring constant
        stiffness: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(10000.0), Some((1.0, 1e7)), doc).with_unit("N/m"),
        /// velocity damping coefficient, applied once per particle (the sample applied it per neighbour)
        damping: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.996), Some((0.0, 100.0)), doc).with_unit("kg/s"),
        /// XPBD inverse stiffness; 0 = inextensible
        compliance: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((0.0, 1.0)), doc).with_unit("m/N"),
        /// XPBD bending stiffness of the fabric: how hard it resists folding, whatever the resolution
        bending: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((0.0, 0.01)), doc).with_unit("N·m"),
        /// XPBD long-range attachments: nothing hangs farther from its pins than at rest
        attachments: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(true), None, doc),
        /// mass per particle
        mass: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.001, 100.0)), doc).with_unit("kg"),
        /// gravity
        gravity: [f32; 3] =
            |n, doc| ParamDecl::new(n, ParamValue::Vec3([0.0, -9.81, 0.0]), Some((-100.0, 100.0)), doc).with_unit("m/s²"),
        /// which particles are fixed
        pin: Pin = |n, doc| ParamDecl::choice(n, Pin::OPTIONS, 0, doc),
        /// collide with the sphere
        sphere: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(true), None, doc),
        /// sphere centre at rest
        sphere_center: [f32; 3] = |n, doc| ParamDecl::new(n, ParamValue::Vec3([0.0, 0.0, 0.0]), Some((-50.0, 50.0)), doc),
        /// sphere radius
        sphere_radius: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.01), Some((0.01, 20.0)), doc).with_unit("m"),
        /// amplitude of the sphere's z oscillation
        sphere_travel: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(4.0), Some((0.0, 50.0)), doc).with_unit("m"),
        /// angular speed of the oscillation (the sample's 0.125 ≈ 50 s period)
        sphere_speed: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.125), Some((0.0, 10.0)), doc).with_unit("rad/s"),
        /// wind direction
        wind: [f32; 3] = |n, doc| ParamDecl::new(n, ParamValue::Vec3([0.0, 0.0, 1.0]), Some((-1.0, 1.0)), doc),
        /// wind force per particle
        wind_strength: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((0.0, 100.0)), doc).with_unit("N"),
        /// how much the wind varies (smooth noise)
        wind_gust: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.5), Some((0.0, 1.0)), doc),
        /// lit surface, or particles and springs
        view: View = |n, doc| ParamDecl::choice(n, View::OPTIONS, 0, doc),
        /// how the lit surface is drawn — compute: its triangles found by a ray per sample into
        /// a visibility buffer (where the adapter has 64-bit atomics); pipeline: the hardware
        /// rasterizer (the debug view always uses it)
        rasterizer: Rasterizer = |n, doc| ParamDecl::choice(n, Rasterizer::OPTIONS, 0, doc),
        /// cloth colour
        color: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([0.0, 0.273, 1.0, 1.0]), None, doc),
        /// sphere colour
        sphere_color: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([1.0, 0.1, 0.1, 1.0]), None, doc),
        /// background colour (Unity's default sky blue)
        background: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([0.19, 0.3, 0.47, 1.0]), None, doc),
        /// direction towards the light
        light_dir: [f32; 3] = |n, doc| ParamDecl::new(n, ParamValue::Vec3([-0.3, 0.6, -0.75]), Some((-1.0, 1.0)), doc),
        /// camera distance in front of the cloth
        camera_distance: f32 =
            |n, doc| ParamDecl::new(n, ParamValue::Float(10.0), Some((0.5, 100.0)), doc).with_unit("m"),
        /// vertical field of view
        fov: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(60.0), Some((5.0, 120.0)), doc).with_unit("°"),
        /// put the cloth back to its rest pose (R in the window)
        reset: bool = |n, doc| ParamDecl::trigger(n, doc).with_role(InputRole::Key('r')),
    }
}

/// The simulation shader's uniform block.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ClothUniforms {
    /// Particles per side.
    pub res: u32,
    /// res².
    pub count: u32,
    /// 0 Verlet, 1 XPBD.
    pub solver: u32,
    /// XPBD bending: the share of the way to the mean of its neighbours along each grid line that
    /// a particle moves per substep ([`bending_share`]); 0 = off.
    pub bending: f32,
    /// Substep length.
    pub dt: f32,
    /// Structural rest length.
    pub rest: f32,
    /// Verlet k.
    pub stiffness: f32,
    /// Damping.
    pub damping: f32,
    /// Particle mass.
    pub mass: f32,
    /// XPBD compliance.
    pub compliance: f32,
    /// Sphere radius (0: none).
    pub sphere_radius: f32,
    /// XPBD long-range attachments: 0 off, 1 top row, 2 two corners.
    pub attachments: u32,
    /// Gravity.
    pub acceleration: [f32; 4],
    /// Sphere centre.
    pub sphere: [f32; 4],
    /// Wind force / mass; each particle feels its component along the cloth's normal there.
    pub wind: [f32; 4],
}

impl ClothUniforms {
    /// The uniforms of the substeps that advance from `time` by one clock step.
    pub fn from_params(p: &Settings, time: &FrameTime, res: u32) -> Self {
        let substeps = p.substeps.clamp(1, 64) as f32;
        let mass = p.mass;
        let dt = time.dt / substeps;
        let g = p.gravity;
        let wind = wind_force(p, time.seconds);
        Self {
            res,
            count: res * res,
            solver: p.solver.index(),
            bending: bending_share(p.bending, mass, p.rest_length, dt),
            dt,
            rest: p.rest_length,
            stiffness: p.stiffness,
            damping: p.damping,
            mass,
            compliance: p.compliance,
            sphere_radius: if p.sphere { p.sphere_radius } else { 0.0 },
            // Attachments follow the pins: the top row (1) or the two corners (2).
            attachments: match (p.solver, p.attachments, p.pin) {
                (Solver::Xpbd, true, Pin::TopRow | Pin::TwoCorners) => p.pin.index() + 1,
                _ => 0,
            },
            acceleration: [g[0], g[1], g[2], 0.0],
            sphere: {
                let c = sphere_center(p, time.seconds);
                [c[0], c[1], c[2], 0.0]
            },
            wind: [wind[0] / mass, wind[1] / mass, wind[2] / mass, 0.0],
        }
    }
}

/// The most of the way to its neighbours' mean a particle moves per substep: past it the bending
/// step and the distance constraints' over-relaxed Jacobi step together overshoot (a bending
/// stiffness of 0.01 N·m on the 1024² sheet, a share of 0.63, blew it up).
pub const MAX_BENDING_SHARE: f32 = 0.25;

/// The bending step's share for stiffness `stiffness` (N·m): the XPBD projection of a bending
/// constraint C = x − (a + b) / 2 along a grid line (a, b the particle's neighbours on it), moving
/// this particle only. Its energy 2B|C|²/h² is the continuous (B/2)∫|x''|² with x'' ≈ 2C/h², so
/// the compliance is h²/(4B) and the share 1 / (1 + m h² / (4 B dt²)): folds keep a physical
/// radius at any resolution instead of the grid's (a 1024² sheet with no bending crumpled into
/// wrinkles a few particles wide, which 256² cannot show).
pub fn bending_share(stiffness: f32, mass: f32, rest: f32, dt: f32) -> f32 {
    if stiffness <= 0.0 {
        return 0.0;
    }
    (1.0 / (1.0 + mass * rest * rest / (4.0 * stiffness * dt * dt))).min(MAX_BENDING_SHARE)
}

/// The sphere's centre at clock time `seconds`: it oscillates along z as in the sample.
pub fn sphere_center(p: &Settings, seconds: f64) -> [f32; 3] {
    let c = p.sphere_center;
    let z = c[2] + (f64::from(p.sphere_speed) * seconds).cos() as f32 * p.sphere_travel;
    [c[0], c[1], z]
}

/// Wind force at clock time `seconds`: direction × strength × (1 + gust × smooth noise), the
/// noise a sum of incommensurate sines (deterministic, no state).
pub fn wind_force(p: &Settings, seconds: f64) -> [f32; 3] {
    let d = p.wind;
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-6);
    let t = seconds;
    let noise = ((t * 1.3).sin() * 0.5 + (t * 2.9 + 1.0).sin() * 0.3 + (t * 7.1 + 2.0).sin() * 0.2) as f32;
    let s = p.wind_strength * (1.0 + p.wind_gust * noise);
    [d[0] / len * s, d[1] / len * s, d[2] / len * s]
}

/// The rest pose: particle (i, j) at ((i − (res−1)/2)·rest, ((res−1)/2 − j)·rest, 0), row 0 on
/// top (centred on the grid, not off by half a spacing as in the sample), with w = inverse mass
/// and 0 for pinned particles.
pub fn rest_pose(res: u32, rest: f32, mass: f32, pin: u32) -> Vec<[f32; 4]> {
    let half = (res - 1) as f32 / 2.0;
    let inverse_mass = 1.0 / mass;
    (0..res * res)
        .map(|k| {
            let (i, j) = (k % res, k / res);
            let pinned = match pin {
                0 => j == 0,
                1 => j == 0 && (i == 0 || i == res - 1),
                _ => false,
            };
            [(i as f32 - half) * rest, (half - j as f32) * rest, 0.0, if pinned { 0.0 } else { inverse_mass }]
        })
        .collect()
}
