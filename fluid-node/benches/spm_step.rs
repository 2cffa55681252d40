//! Time of one coupled-like SPM step of the fluid node: bead states published, momentum
//! exchange (build phi, u* with advection and exact viscous decay, impulses), impulses read,
//! states published again, penalty and projection, diagnostics. Bead states are prescribed
//! (a straight chain moving slowly), so no fibre node runs.
//!
//! - 2D 256 x 200 with an 18-bead chain of r_b = 6 (L2020's droplet case, xi = 2, xi_c = 5);
//! - 3D 128 x 120 x 120 with a 10-bead chain of r_b = 6 (L2020's 3D grid, xi = 2, xi_c = 5).
//!
//! Throughput is per grid cell.
use cosim::{BeadState, Component, Exchange, InProcessExchange, Phase, Port};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use fluid_node::FluidComponent;
use std::time::Duration;

fn chain(beads: usize, centre: [f64; 3], dims: usize, n: u64) -> Vec<BeadState> {
    (0..beads)
        .map(|i| {
            let x = centre[0] + 12.0 * (i as f64 - 0.5 * (beads - 1) as f64) + 1e-3 * n as f64;
            BeadState {
                position: [x, centre[1], if dims == 3 { centre[2] } else { 0.0 }],
                orientation: [1.0, 0.0, 0.0, 0.0],
                velocity: [1e-3, 0.0, 0.0],
                angular_velocity: [0.0, 0.0, 1e-4],
            }
        })
        .collect()
}

fn bench_case(c: &mut Criterion, name: &str, dims: usize, grid: [usize; 3], beads: usize) {
    let grid_toml = if dims == 2 {
        format!("[{}, {}]", grid[0], grid[1])
    } else {
        format!("[{}, {}, {}]", grid[0], grid[1], grid[2])
    };
    let scene = format!(
        "dimensions = {dims}\n[time]\ndt = 0.5\n[fluid]\nmethod = \"spm\"\ngrid = {grid_toml}\n\
         viscosity = 1.0\nxi = 2\nxi_cutoff = 5\n[[fibre]]\nbeads = {beads}\nbead_radius = 6\n"
    );
    let mut comp = FluidComponent::new();
    let mut x = InProcessExchange::new();
    comp.configure(&scene, &mut x).unwrap();
    let centre = [
        grid[0] as f64 / 2.0,
        grid[1] as f64 / 2.0,
        grid[2] as f64 / 2.0,
    ];
    let mut n = 0u64;
    let mut imp = Vec::with_capacity(beads);
    let mut group = c.benchmark_group("spm_step");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(if dims == 3 { 4 } else { 2 }));
    group.throughput(Throughput::Elements(grid.iter().product::<usize>() as u64));
    group.bench_function(name, |b| {
        b.iter(|| {
            let s = chain(beads, centre, dims, n);
            x.publish_states(Port::BeadStates, n + 1, &s).unwrap();
            comp.run_phase(n, Phase::FluidMomentumExchange, &mut x)
                .unwrap();
            x.read_impulses(Port::BeadImpulses, &mut imp).unwrap();
            x.publish_states(Port::BeadStates, n + 1, &s).unwrap();
            let r = comp.run_phase(n, Phase::FluidPenalty, &mut x).unwrap();
            n += 1;
            std::hint::black_box(r)
        })
    });
    group.finish();
}

fn bench(c: &mut Criterion) {
    bench_case(c, "2d_256x200_18_beads", 2, [256, 200, 1], 18);
    bench_case(c, "3d_128x120x120_10_beads", 3, [128, 120, 120], 10);
}

criterion_group!(benches, bench);
criterion_main!(benches);
