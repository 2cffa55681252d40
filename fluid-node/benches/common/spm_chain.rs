//! What the SPM benches share: the prescribed chain of beads, the scene's fluid table, the
//! momentum exchange and penalty of a step, and the criterion group settings (per-cell
//! throughput). Running on a pool thread is in `pool_thread.rs`.
use cosim::{
    BeadImpulse, BeadState, Component, Detail, Exchange, InProcessExchange, Phase, PhaseReport,
    Port,
};
use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, Throughput};
use fluid_node::FluidComponent;
use std::time::Duration;

/// A straight chain of `beads` beads of r_b = 6 (touching) along x through `centre`,
/// moving slowly in x and spinning about z; `n` shifts it by 1e-3 per step.
pub fn chain(beads: usize, centre: [f64; 3], dims: usize, n: u64) -> Vec<BeadState> {
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

/// `[nx, ny]` or `[nx, ny, nz]`.
pub fn grid_toml(dims: usize, grid: [usize; 3]) -> String {
    if dims == 2 {
        format!("[{}, {}]", grid[0], grid[1])
    } else {
        format!("[{}, {}, {}]", grid[0], grid[1], grid[2])
    }
}

/// The centre of the box.
pub fn centre(grid: [usize; 3]) -> [f64; 3] {
    [
        grid[0] as f64 / 2.0,
        grid[1] as f64 / 2.0,
        grid[2] as f64 / 2.0,
    ]
}

/// A group of 10 samples, 0.5 s warm-up, 2 s (2D) or 4 s (3D) of measurement, throughput
/// per grid cell.
pub fn group<'a>(
    c: &'a mut Criterion,
    name: &str,
    dims: usize,
    grid: [usize; 3],
) -> BenchmarkGroup<'a, WallTime> {
    let mut group = c.benchmark_group(name);
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(if dims == 3 { 4 } else { 2 }));
    group.throughput(Throughput::Elements(grid.iter().product::<usize>() as u64));
    group
}

/// The scene up to the end of `[fluid]`: an SPM fluid on `grid` (viscosity 1, xi = 2,
/// xi_c = 5, dt = 0.5), ready for more fluid keys or tables.
pub fn spm_scene_head(dims: usize, grid: [usize; 3]) -> String {
    format!(
        "dimensions = {dims}\n[time]\ndt = 0.5\n[fluid]\nmethod = \"spm\"\ngrid = {}\n\
         viscosity = 1.0\nxi = 2\nxi_cutoff = 5\n",
        grid_toml(dims, grid)
    )
}

/// The SPM half of step `n` once the bead states at n+1 are known (L2020 eqs. 35-38): states
/// published, momentum exchange, impulses read back into `imp`, states published again,
/// penalty. The penalty's report, with `detail`: brief at the steps a run does not log.
pub fn exchange_and_penalty(
    comp: &mut FluidComponent,
    x: &mut InProcessExchange,
    (n, detail): (u64, Detail),
    states: &[BeadState],
    imp: &mut Vec<BeadImpulse>,
) -> PhaseReport {
    x.publish_states(Port::BeadPositions, n + 1, states)
        .unwrap();
    comp.run_phase_with(n, Phase::FluidMomentumExchange, Detail::Brief, x)
        .unwrap();
    x.read_impulses(Port::BeadImpulses, imp).unwrap();
    x.publish_states(Port::BeadStates, n + 1, states).unwrap();
    comp.run_phase_with(n, Phase::FluidPenalty, detail, x)
        .unwrap()
}
