//! Time of one capillary SPM step of the fluid node (L2020 sections 2.4–2.6): bead states
//! published, fluid-phase-field (φ and ψ* from the beads, one semi-implicit Cahn–Hilliard
//! step advected by u, its diagnostics), fluid-momentum-exchange (φ again, the capillary
//! force of eqs. 33–34 into u*, impulses), impulses read, fluid-penalty. Bead states are
//! prescribed (a straight chain of affinity 0.3 moving slowly across a droplet), so no fibre
//! node runs. The grids and chains are those of `spm_step`, so the two benches give the
//! cost of the phase field:
//!
//! - 2D 256 x 200 with an 18-bead chain of r_b = 6, a droplet of R = 50 (xi = 2, xi_c = 5);
//! - 3D 128 x 120 x 120 with a 10-bead chain of r_b = 6, a droplet of R = 30.
//!
//! The reports are brief (`cosim::Detail::Brief`), as at every step a run does not log: no
//! free energy, droplet diagnostics (pressure, radius) or divergence. Throughput is per grid
//! cell.
use cosim::{Component, Detail, Exchange, InProcessExchange, Phase, Port};
use criterion::{criterion_group, criterion_main, Criterion};
use fluid_node::FluidComponent;
#[path = "common/pool_thread.rs"]
mod pool_thread;
#[path = "common/spm_chain.rs"]
mod spm_chain;
use spm_chain::{centre, chain, exchange_and_penalty, grid_toml, spm_scene_head};

fn bench_case(c: &mut Criterion, name: &str, dims: usize, grid: [usize; 3], beads: usize) {
    // The droplet sits at the centre of the box: R = 50 in 2D, 30 in 3D.
    let half = [grid[0] / 2, grid[1] / 2, grid[2] / 2];
    let (centre_toml, radius) = (grid_toml(dims, half), if dims == 2 { 50 } else { 30 });
    let scene = format!(
        "{}[fluid.binary]\nxi = 2\ne0 = 0.1\nmobility = 1\ninitial = \"droplet\"\n\
         centre = {centre_toml}\nradius = {radius}\n\
         [[fibre]]\nbeads = {beads}\nbead_radius = 6\naffinity = 0.3\n",
        spm_scene_head(dims, grid)
    );
    let mut comp = FluidComponent::new();
    let mut x = InProcessExchange::new();
    comp.configure(&scene, &mut x).unwrap();
    let centre = centre(grid);
    let mut n = 0u64;
    let mut imp = Vec::with_capacity(beads);
    let mut group = spm_chain::group(c, "capillary_step", dims, grid);
    group.bench_function(name, |b| {
        pool_thread::on_pool_thread(|| {
            b.iter(|| {
                let at_n = chain(beads, centre, dims, n);
                let at_n1 = chain(beads, centre, dims, n + 1);
                x.publish_states(Port::BeadStates, n, &at_n).unwrap();
                let pf = comp
                    .run_phase_with(n, Phase::FluidPhaseField, Detail::Brief, &mut x)
                    .unwrap();
                let r =
                    exchange_and_penalty(&mut comp, &mut x, (n, Detail::Brief), &at_n1, &mut imp);
                n += 1;
                std::hint::black_box((pf, r))
            })
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
