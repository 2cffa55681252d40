//! Time of one full fibre step (fibre-positions + fibre-velocities, including the bead-state
//! publications on an in-process exchange), 3D, for both models at 10, 100 and 1000 beads.
//! Throughput is reported per bead.
use cosim::{Component, InProcessExchange, Phase};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use fibre_node::FibreComponent;

fn scene(model: &str, beads: usize, dt: f64) -> String {
    format!(
        "[time]\ndt = {dt}\n[[fibre]]\nmodel = \"{model}\"\nbeads = {beads}\nbead_radius = 1\n\
         youngs_modulus = 1\nclamp = [0]\nloads = [{{ bead = -1, force = [0, -1e-3, 1e-3], \
         torque = [{}, 0, 0] }}]\n",
        if model == "cohesive-beam" { 1e-3 } else { 0.0 }
    )
}

fn configured(model: &str, beads: usize) -> (FibreComponent, InProcessExchange) {
    let mut c = FibreComponent::new();
    let mut x = InProcessExchange::new();
    let cfg = c.configure(&scene(model, beads, 1e-9), &mut x).unwrap();
    let limit = cfg.time_step_limits[0].1;
    c.configure(&scene(model, beads, 0.5 * limit), &mut x)
        .unwrap();
    (c, x)
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("fibre_step_3d");
    for model in ["cohesive-beam", "bead-spring"] {
        for beads in [10usize, 100, 1000] {
            let (mut comp, mut x) = configured(model, beads);
            let mut n = 0u64;
            group.throughput(Throughput::Elements(beads as u64));
            group.bench_with_input(BenchmarkId::new(model, beads), &beads, |b, _| {
                b.iter(|| {
                    comp.run_phase(n, Phase::FibrePositions, &mut x).unwrap();
                    let r = comp.run_phase(n, Phase::FibreVelocities, &mut x).unwrap();
                    n += 1;
                    std::hint::black_box(r)
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
