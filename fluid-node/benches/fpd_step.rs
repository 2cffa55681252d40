//! Time of one coupled FPD step of the fluid node (S2023 section II C): bead states and
//! forces published, then `fluid-lattice-step` (profiles and viscosity field in the bead
//! boxes, force density spread, one MRT collide-stream step of the whole lattice, bead
//! velocities as profile-weighted means), bead velocities read back. The fibre is
//! prescribed (a straight chain drifting slowly with constant forces), so no fibre node runs;
//! `lbm_step` times the bare kernel.
//!
//! - S2023 Fig. 7 at the paper's resolution (`configs/fpd/fig7_jeffery_paper_resolution.toml`):
//!   500 x 400, N = 10 beads of d = 20;
//! - the repository's flexible-fibre scene (`configs/fpd/flexible_shear.toml`): 200 x 160,
//!   N = 10 beads of d = 8.
//!
//! Throughput is per lattice node (MLUPS), on the machine's rayon pool.
use cosim::{BeadForce, BeadState, Component, Exchange, InProcessExchange, Phase, Port};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use fluid_node::FluidComponent;
use std::time::Duration;
#[path = "common/pool_thread.rs"]
mod pool_thread;

/// The fluid node's part of the scene: an FPD lattice of `nx` x `ny` between walls at -+0.05,
/// r_eta = 100, r_xi = 0.125, and one chain of `beads` beads of radius `a`.
fn scene(nx: usize, ny: usize, beads: usize, a: f64) -> String {
    format!(
        "dimensions = 2\n[time]\ndt = 1.0\n[fluid]\nmethod = \"fpd-lbm\"\ngrid = [{nx}, {ny}]\n\
         viscosity = 0.6666666666666666\ndensity = 1.0\nviscosity_ratio = 100.0\n\
         interface_ratio = 0.125\ninitial_velocity = \"couette\"\n[walls]\n\
         velocity = [-0.05, 0.05]\n[[fibre]]\nmodel = \"bead-spring\"\nbeads = {beads}\n\
         bead_radius = {a}\n"
    )
}

/// Touching beads along x through the centre, shifted by 1e-3 per step so that the profiles
/// move as in a run.
fn chain(beads: usize, a: f64, centre: [f64; 2], n: u64, out: &mut Vec<BeadState>) {
    out.clear();
    out.extend((0..beads).map(|i| {
        let x = centre[0] + 2.0 * a * (i as f64 - 0.5 * (beads - 1) as f64) + 1e-3 * n as f64;
        BeadState::at_rest([x, centre[1], 0.0])
    }));
}

fn bench_case(c: &mut Criterion, name: &str, nx: usize, ny: usize, beads: usize, a: f64) {
    let mut comp = FluidComponent::new();
    let mut x = InProcessExchange::new();
    comp.configure(&scene(nx, ny, beads, a), &mut x).unwrap();
    let centre = [nx as f64 / 2.0, ny as f64 / 2.0 - 0.5];
    // Opposite forces on the two halves: a torque, no net force.
    let forces: Vec<BeadForce> = (0..beads)
        .map(|i| BeadForce {
            force: [0.0, if 2 * i < beads { 1e-4 } else { -1e-4 }, 0.0],
        })
        .collect();
    let mut states = Vec::with_capacity(beads);
    let mut velocities = Vec::with_capacity(beads);
    let mut n = 0u64;
    let mut group = c.benchmark_group("fpd_step");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Elements((nx * ny) as u64));
    group.bench_function(name, |b| {
        pool_thread::on_pool_thread(|| {
            b.iter(|| {
                chain(beads, a, centre, n, &mut states);
                x.publish_states(Port::BeadStates, n, &states).unwrap();
                x.publish_forces(Port::BeadForces, n, &forces).unwrap();
                let r = comp.run_phase(n, Phase::FluidLatticeStep, &mut x).unwrap();
                x.read_states(Port::BeadVelocities, &mut velocities)
                    .unwrap();
                n += 1;
                std::hint::black_box(r)
            })
        })
    });
    group.finish();
    assert!(velocities.iter().all(|s| s.velocity[0].is_finite()));
}

fn bench(c: &mut Criterion) {
    bench_case(c, "s2023_fig7_500x400_10_beads_d20", 500, 400, 10, 10.0);
    bench_case(c, "flexible_shear_200x160_10_beads_d8", 200, 160, 10, 4.0);
}

criterion_group!(benches, bench);
criterion_main!(benches);
