//! One fixed step of the fluid as a list of dispatches, each with its own uniform block: which
//! kernel, which field slots it reads and writes, and its coefficients. Pure CPU, so the order of
//! the solver is testable without a GPU.

use super::Settings;

/// A field slot of N² floats in the fields buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Field {
    /// Velocity, x (cells per second).
    U,
    /// Velocity, y.
    V,
    /// Scratch for u.
    UTmp,
    /// Scratch for v.
    VTmp,
    /// Density (the height the fluid shows).
    Density,
    /// Scratch for density.
    DensityTmp,
    /// Pressure.
    Pressure,
    /// Scratch for pressure.
    PressureTmp,
    /// Divergence of the velocity.
    Divergence,
    /// The right-hand side of a diffusion solve (the field before it).
    Before,
}

impl Field {
    /// Number of slots.
    pub const COUNT: usize = 10;
}

/// The kernels of `grid_fluid.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// Adds the cursor's splat.
    AddSource,
    /// dst = src.
    Copy,
    /// One Jacobi sweep.
    Jacobi,
    /// Zero velocity on the walls.
    Walls,
    /// Divergence, and pressure cleared.
    Divergence,
    /// Velocity minus the pressure gradient.
    SubtractGradient,
    /// Semi-Lagrangian advection.
    Advect,
    /// Density into the output image.
    WriteOutput,
}

impl Kernel {
    /// Every kernel, in pipeline order.
    pub const ALL: [Kernel; 8] = [
        Kernel::AddSource,
        Kernel::Copy,
        Kernel::Jacobi,
        Kernel::Walls,
        Kernel::Divergence,
        Kernel::SubtractGradient,
        Kernel::Advect,
        Kernel::WriteOutput,
    ];

    /// The WGSL entry point.
    pub fn entry(self) -> &'static str {
        match self {
            Kernel::AddSource => "add_source",
            Kernel::Copy => "copy",
            Kernel::Jacobi => "jacobi",
            Kernel::Walls => "walls",
            Kernel::Divergence => "divergence",
            Kernel::SubtractGradient => "subtract_gradient",
            Kernel::Advect => "advect",
            Kernel::WriteOutput => "write_output",
        }
    }
}

/// One dispatch's uniform block (`Dispatch` in the shader).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FluidDispatch {
    /// Grid side.
    pub n: u32,
    /// Slot read.
    pub src: u32,
    /// Slot written.
    pub dst: u32,
    /// Auxiliary slot (right-hand side, pressure, advecting u).
    pub aux: u32,
    /// Jacobi neighbour weight.
    pub a: f32,
    /// Jacobi weight of `aux`.
    pub c0: f32,
    /// Jacobi divisor.
    pub c1: f32,
    /// Step, seconds.
    pub dt: f32,
    /// Splat centre, cells.
    pub centre: [f32; 2],
    /// Splat velocity, cells per second.
    pub impulse: [f32; 2],
    /// Splat radius, cells.
    pub radius: f32,
    /// Density added per second at the splat's centre.
    pub density: f32,
    /// Factor kept after advection (dissipation).
    pub keep: f32,
    /// Second slot (v for velocity kernels).
    pub second: u32,
}

/// A dispatch: the kernel and its block.
pub type Planned = (Kernel, FluidDispatch);

impl FluidDispatch {
    fn new(n: u32, dt: f32) -> Self {
        Self {
            n,
            src: 0,
            dst: 0,
            aux: 0,
            a: 0.0,
            c0: 0.0,
            c1: 1.0,
            dt,
            centre: [0.0; 2],
            impulse: [0.0; 2],
            radius: 1.0,
            density: 0.0,
            keep: 1.0,
            second: 0,
        }
    }

    /// The dispatch that writes the density image.
    pub fn output(n: u32) -> Planned {
        (Kernel::WriteOutput, FluidDispatch { src: Field::Density as u32, ..Self::new(n, 0.0) })
    }
}

/// Fastest splat velocity, in boxes per second (a flick of the mouse must not blow up the step).
pub(super) const MAX_IMPULSE: f32 = 4.0;

/// Builds the dispatches of one step.
struct Plan {
    n: u32,
    dt: f32,
    out: Vec<Planned>,
}

impl Plan {
    fn push(&mut self, kernel: Kernel, edit: impl FnOnce(&mut FluidDispatch)) {
        let mut d = FluidDispatch::new(self.n, self.dt);
        edit(&mut d);
        self.out.push((kernel, d));
    }

    fn copy(&mut self, from: Field, to: Field) {
        self.push(Kernel::Copy, |d| (d.src, d.dst) = (from as u32, to as u32));
    }

    /// `iterations` Jacobi sweeps of (c1·x − a·Σ neighbours = c0·rhs), between `x` and `tmp`;
    /// the result ends in `x`.
    fn jacobi(&mut self, x: Field, tmp: Field, rhs: Field, (a, c0, c1): (f32, f32, f32), iterations: u32) {
        for k in 0..iterations {
            let (src, dst) = if k % 2 == 0 { (x, tmp) } else { (tmp, x) };
            self.push(Kernel::Jacobi, |d| {
                (d.src, d.dst, d.aux) = (src as u32, dst as u32, rhs as u32);
                (d.a, d.c0, d.c1) = (a, c0, c1);
            });
        }
        if iterations % 2 == 1 {
            self.copy(tmp, x);
        }
    }

    /// Backward-Euler diffusion of `x` with a = dt·ν·N² (ν in boxes² per second).
    fn diffuse(&mut self, x: Field, tmp: Field, a: f32, sweeps: u32) {
        if a <= 0.0 {
            return;
        }
        self.copy(x, Field::Before);
        self.jacobi(x, tmp, Field::Before, (a, 1.0, 1.0 + 4.0 * a), sweeps);
    }

    fn walls(&mut self) {
        self.push(Kernel::Walls, |d| (d.src, d.second) = (Field::U as u32, Field::V as u32));
    }

    /// Makes the velocity divergence-free: solve ∇²p = ∇·u, subtract ∇p.
    fn project(&mut self, iterations: u32) {
        self.push(Kernel::Divergence, |d| {
            (d.src, d.second, d.dst, d.aux) =
                (Field::U as u32, Field::V as u32, Field::Divergence as u32, Field::Pressure as u32);
        });
        self.jacobi(Field::Pressure, Field::PressureTmp, Field::Divergence, (1.0, 1.0, 4.0), iterations);
        self.push(Kernel::SubtractGradient, |d| {
            (d.src, d.second, d.aux) = (Field::U as u32, Field::V as u32, Field::Pressure as u32);
        });
        self.walls();
    }

    /// Advects `x` along the velocity into `tmp`, scaled by `keep`.
    fn advect(&mut self, x: Field, tmp: Field, keep: f32) {
        self.push(Kernel::Advect, |d| {
            (d.src, d.dst, d.aux, d.second) = (x as u32, tmp as u32, Field::U as u32, Field::V as u32);
            d.keep = keep;
        });
    }
}

/// The dispatches of one fixed step of `dt` seconds on an `n`² grid, with the cursor's splat
/// `(position, motion since the last step)` in box units when it is stirring.
pub fn step_dispatches(n: u32, params: &Settings, dt: f32, source: Option<([f32; 2], [f32; 2])>) -> Vec<Planned> {
    let mut plan = Plan { n, dt, out: Vec::new() };
    let cells = n as f32;
    let per_step = |coefficient: f32| dt * coefficient * 1e-5 * cells * cells;
    let sweeps = params.sweeps.clamp(1, 64) as u32;
    let pressure = params.pressure_iterations.clamp(1, 400) as u32;

    // Velocity: add, diffuse, project, self-advect, project.
    if let Some((cursor, motion)) = source {
        let coef = params.velocity_coef;
        let velocity = motion.map(|m| m / dt.max(1e-6) * coef);
        let speed = (velocity[0] * velocity[0] + velocity[1] * velocity[1]).sqrt();
        let limit = if speed > MAX_IMPULSE { MAX_IMPULSE / speed } else { 1.0 };
        let density = params.density_coef;
        let radius = params.radius * cells;
        plan.push(Kernel::AddSource, |d| {
            (d.src, d.dst, d.aux) = (Field::U as u32, Field::V as u32, Field::Density as u32);
            d.centre = cursor.map(|c| c * cells);
            d.impulse = velocity.map(|v| v * limit * cells);
            (d.radius, d.density) = (radius, density);
        });
    }
    let viscosity = per_step(params.viscosity);
    plan.diffuse(Field::U, Field::UTmp, viscosity, sweeps);
    plan.diffuse(Field::V, Field::VTmp, viscosity, sweeps);
    plan.walls();
    plan.project(pressure);
    plan.advect(Field::U, Field::UTmp, 1.0);
    plan.advect(Field::V, Field::VTmp, 1.0);
    plan.copy(Field::UTmp, Field::U);
    plan.copy(Field::VTmp, Field::V);
    plan.walls();
    plan.project(pressure);

    // Density: diffuse, advect, dissipate.
    plan.diffuse(Field::Density, Field::DensityTmp, per_step(params.diffusion), sweeps);
    let keep = (-params.dissipation * dt).exp();
    plan.advect(Field::Density, Field::DensityTmp, keep);
    plan.copy(Field::DensityTmp, Field::Density);
    plan.out
}
