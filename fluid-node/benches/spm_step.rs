//! Time of one coupled-like SPM step of the fluid node: bead states published, momentum
//! exchange (build phi, u* with advection and exact viscous decay, impulses), impulses read,
//! states published again, penalty and projection, diagnostics. Bead states are prescribed
//! (a straight chain moving slowly), so no fibre node runs. The reports are brief
//! (`cosim::Detail::Brief`, no divergence), as at every step a run does not log; the 2D case
//! also in full (`_logged`), as at a logged step.
//!
//! - 2D 256 x 200 with an 18-bead chain of r_b = 6 (L2020's droplet case, xi = 2, xi_c = 5);
//! - 3D 128 x 120 x 120 with a 10-bead chain of r_b = 6 (L2020's 3D grid, xi = 2, xi_c = 5).
//!
//! Throughput is per grid cell.
use cosim::{Component, Detail, InProcessExchange};
use criterion::{criterion_group, criterion_main, Criterion};
use fluid_node::FluidComponent;
#[path = "common/pool_thread.rs"]
mod pool_thread;
#[path = "common/spm_chain.rs"]
mod spm_chain;
use spm_chain::{centre, chain, exchange_and_penalty, spm_scene_head};

fn bench_case(
    c: &mut Criterion,
    (name, detail): (&str, Detail),
    dims: usize,
    grid: [usize; 3],
    beads: usize,
) {
    let scene = format!(
        "{}[[fibre]]\nbeads = {beads}\nbead_radius = 6\n",
        spm_scene_head(dims, grid)
    );
    let mut comp = FluidComponent::new();
    let mut x = InProcessExchange::new();
    comp.configure(&scene, &mut x).unwrap();
    let centre = centre(grid);
    let mut n = 0u64;
    let mut imp = Vec::with_capacity(beads);
    let mut group = spm_chain::group(c, "spm_step", dims, grid);
    group.bench_function(name, |b| {
        pool_thread::on_pool_thread(|| {
            b.iter(|| {
                let s = chain(beads, centre, dims, n);
                let r = exchange_and_penalty(&mut comp, &mut x, (n, detail), &s, &mut imp);
                n += 1;
                std::hint::black_box(r)
            })
        })
    });
    group.finish();
}

fn bench(c: &mut Criterion) {
    bench_case(
        c,
        ("2d_256x200_18_beads", Detail::Brief),
        2,
        [256, 200, 1],
        18,
    );
    // A logged step: the full report adds the divergence (an inverse transform).
    let logged = ("2d_256x200_18_beads_logged", Detail::Full);
    bench_case(c, logged, 2, [256, 200, 1], 18);
    bench_case(
        c,
        ("3d_128x120x120_10_beads", Detail::Brief),
        3,
        [128, 120, 120],
        10,
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
