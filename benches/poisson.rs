//! Poisson disk sampling, ours against the `fast_poisson` crate on the same box and radius
//! (2-D unit square and 3-D unit cube, k = 30, seeded), at about 10⁴, 10⁵ and (2-D) 10⁶ samples.
//! Run: `cargo bench --bench poisson`; compare the medians as ratios.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use indra::geometry::poisson::{PoissonDisk, PoissonSettings};

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("poisson_2d");
    group.sample_size(10);
    for target in [10_000u64, 100_000, 1_000_000] {
        // A maximal-ish 2-D set has ~0.68 / r² points per unit area.
        let radius = (0.68 / target as f64).sqrt();
        let ours = PoissonDisk::new(PoissonSettings::new([1.0, 1.0], radius, 1)).generate().len();
        let theirs = fast_poisson::Poisson2D::new().with_dimensions([1.0, 1.0], radius).with_seed(1).generate().len();
        eprintln!("target {target}: indra {ours} samples, fast_poisson {theirs} samples");
        group.throughput(Throughput::Elements(target));
        group.bench_with_input(BenchmarkId::new("indra", target), &radius, |b, &r| {
            b.iter(|| PoissonDisk::new(PoissonSettings::new([1.0, 1.0], r, 1)).generate().len())
        });
        group.bench_with_input(BenchmarkId::new("fast_poisson", target), &radius, |b, &r| {
            b.iter(|| fast_poisson::Poisson2D::new().with_dimensions([1.0, 1.0], r).with_seed(1).generate().len())
        });
    }
    group.finish();

    // 3-D unit cube: a maximal-ish set has ~0.5 / r³ points per unit volume here.
    let mut group = c.benchmark_group("poisson_3d");
    group.sample_size(10);
    for target in [10_000u64, 100_000] {
        let radius = (0.5 / target as f64).cbrt();
        let ours = PoissonDisk::new(PoissonSettings::new([1.0; 3], radius, 1)).generate().len();
        let theirs = fast_poisson::Poisson3D::new().with_dimensions([1.0; 3], radius).with_seed(1).generate().len();
        eprintln!("3-D target {target}: indra {ours} samples, fast_poisson {theirs} samples");
        group.throughput(Throughput::Elements(target));
        group.bench_with_input(BenchmarkId::new("indra", target), &radius, |b, &r| {
            b.iter(|| PoissonDisk::new(PoissonSettings::new([1.0; 3], r, 1)).generate().len())
        });
        group.bench_with_input(BenchmarkId::new("fast_poisson", target), &radius, |b, &r| {
            b.iter(|| fast_poisson::Poisson3D::new().with_dimensions([1.0; 3], r).with_seed(1).generate().len())
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
