//! The CPU side of a Poisson disk node: a 2-D or 3-D run of the sampler, stepped, read as
//! instances, and saved and resumed for checkpoints.

use super::RunKey;
use crate::geometry::poisson::{PoissonDisk, PoissonSettings, Step};

/// The sampler settings of a run of `key` in `extent`.
fn settings<const N: usize>(key: &RunKey, extent: [f64; N]) -> PoissonSettings<N> {
    let mut s = PoissonSettings::new(extent, f64::from(key.radius), key.seed as u64);
    s.attempts = key.attempts.max(1) as u32;
    s
}

/// A run in two or three dimensions.
pub(super) enum Sampler {
    /// 2-D.
    Flat(PoissonDisk<2>),
    /// 3-D.
    Volume(PoissonDisk<3>),
}

impl Sampler {
    /// A run of `key` with its first sample placed.
    pub(super) fn new(key: &RunKey) -> Self {
        let [x, y, z] = key.extent.map(f64::from);
        if key.three_d {
            Sampler::Volume(PoissonDisk::new(settings(key, [x, y, z])))
        } else {
            Sampler::Flat(PoissonDisk::new(settings(key, [x, y])))
        }
    }

    /// The run's samples (flattened), active list and generator state.
    pub(super) fn progress(&self) -> (Vec<f64>, Vec<u64>, u64) {
        fn flat<const N: usize>(s: &PoissonDisk<N>) -> (Vec<f64>, Vec<u64>, u64) {
            let (points, active, rng) = s.progress();
            (points.iter().flatten().copied().collect(), active.iter().map(|&i| i as u64).collect(), rng)
        }
        match self {
            Sampler::Flat(s) => flat(s),
            Sampler::Volume(s) => flat(s),
        }
    }

    /// The run of `key` resumed from [`Sampler::progress`], or `None` if that is not one.
    pub(super) fn resume(key: &RunKey, points: &[f64], active: Vec<u64>, rng: u64) -> Option<Self> {
        fn run<const N: usize>(key: &RunKey, points: &[f64], active: Vec<u64>, rng: u64) -> Option<PoissonDisk<N>> {
            if !points.len().is_multiple_of(N) {
                return None;
            }
            let points = points.chunks_exact(N).map(|p| std::array::from_fn(|d| p[d])).collect();
            let active = active.into_iter().map(usize::try_from).collect::<Result<_, _>>().ok()?;
            let extent = std::array::from_fn(|d| f64::from(key.extent[d]));
            PoissonDisk::resume(settings(key, extent), points, active, rng)
        }
        if key.three_d {
            run(key, points, active, rng).map(Sampler::Volume)
        } else {
            run(key, points, active, rng).map(Sampler::Flat)
        }
    }

    /// One sampler step; false when the run is complete.
    pub(super) fn step(&mut self) -> bool {
        match self {
            Sampler::Flat(s) => !matches!(s.step(), Step::Done),
            Sampler::Volume(s) => !matches!(s.step(), Step::Done),
        }
    }

    /// Sample positions from `from` on, centred on the origin, as (x, y, z, insertion index).
    pub(super) fn instances_from(&self, from: usize, key: &RunKey, out: &mut Vec<[f32; 4]>) {
        fn centred<const N: usize>(points: &[[f64; N]], from: usize, half: [f32; 3], out: &mut Vec<[f32; 4]>) {
            out.extend(points[from..].iter().enumerate().map(|(i, p)| {
                let mut v = [0.0, 0.0, 0.0, (from + i) as f32];
                for k in 0..N {
                    v[k] = p[k] as f32 - half[k];
                }
                v
            }));
        }
        let half = key.extent.map(|e| e / 2.0);
        match self {
            Sampler::Flat(s) => centred(s.points(), from, half, out),
            Sampler::Volume(s) => centred(s.points(), from, half, out),
        }
    }

    /// Samples so far.
    pub(super) fn len(&self) -> usize {
        match self {
            Sampler::Flat(s) => s.points().len(),
            Sampler::Volume(s) => s.points().len(),
        }
    }
}
