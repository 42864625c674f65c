use super::plan::MAX_IMPULSE;
use super::*;
use crate::params::ParamSet;

#[test]
fn the_dispatch_block_matches_the_wgsl_struct() {
    let source = include_str!("grid_fluid.wgsl");
    assert_eq!(crate::gpu::wgsl_struct_size(source, "Dispatch"), Some(size_of::<FluidDispatch>() as u32));
    assert!(size_of::<FluidDispatch>() as u64 <= BLOCK);
}

#[test]
fn a_step_solves_in_the_books_order_and_every_solve_ends_in_its_field() {
    let params = ParamSet::new(Settings::decls());
    let plan = step_dispatches(64, &Settings::read(&params), 1.0 / 60.0, Some(([0.5, 0.5], [0.01, 0.0])));
    let kernels: Vec<Kernel> = plan.iter().map(|p| p.0).collect();
    assert_eq!(kernels[0], Kernel::AddSource);
    // Two projections, each with the configured pressure iterations (40, even: no final copy).
    let divergences = kernels.iter().filter(|&&k| k == Kernel::Divergence).count();
    assert_eq!(divergences, 2);
    let jacobi = kernels.iter().filter(|&&k| k == Kernel::Jacobi).count();
    assert_eq!(jacobi, 2 * 40 + 3 * 2, "pressure twice, u, v and density diffusion with 2 sweeps");
    // The last dispatch of the step leaves the advected density in its own field.
    let (last_kernel, last) = plan.last().unwrap();
    assert_eq!((*last_kernel, last.src, last.dst), (Kernel::Copy, Field::DensityTmp as u32, Field::Density as u32));
    // Without stirring there is no source, and an odd iteration count copies back.
    let mut odd = ParamSet::new(super::Settings::decls());
    odd.set_at(odd.index("pressure_iterations").unwrap(), crate::params::ParamValue::Int(3));
    let still = step_dispatches(64, &Settings::read(&odd), 1.0 / 60.0, None);
    assert!(still.iter().all(|p| p.0 != Kernel::AddSource));
    let after_pressure = still.iter().position(|p| p.0 == Kernel::SubtractGradient).unwrap();
    let copy = &still[after_pressure - 1];
    assert_eq!((copy.0, copy.1.src, copy.1.dst), (Kernel::Copy, Field::PressureTmp as u32, Field::Pressure as u32));
}

#[test]
fn a_flick_of_the_cursor_is_limited() {
    let params = ParamSet::new(Settings::decls());
    let plan = step_dispatches(100, &Settings::read(&params), 1.0 / 60.0, Some(([0.5, 0.5], [0.9, 0.0])));
    let impulse = plan[0].1.impulse;
    assert!((impulse[0] - MAX_IMPULSE * 100.0).abs() < 1e-3 && impulse[1] == 0.0, "{impulse:?}");
}
