//! Momentum conservation of the SPM exchange (L2020 eqs. 35-38) for beads moving through
//! fluid, fed through an InProcessExchange.
//!
//! Over one step the fluid momentum P = rho Σ u (whole box, cell volume 1) changes by the
//! body force f V dt in u^n -> u* (advection in divergence form, exact viscous decay and
//! projection leave the mean mode alone) and by rho ∫ phi (u_p - u*) in the penalty. With the
//! same normalised phi_i in eqs. 35 and 38, and u_i* the rigid velocity at n,
//!
//! ```text
//! ΔP + Σ_i J_i = f V dt + rho Σ_i ∫ phi_i (u_i^{n+1} - u_i^n) dV,
//! ```
//!
//! so for beads keeping their velocities the impulses balance the fluid's change exactly
//! (to round-off), and a uniform change ΔV of all bead velocities adds rho ΔV Σ_i ∫ phi_i.
mod common;
use common::*;
use cosim::BeadState;

fn scene(dims: u8, grid: &str, force: &str) -> String {
    format!(
        "dimensions = {dims}\n[time]\ndt = 0.7\n[fluid]\nmethod = \"spm\"\ngrid = {grid}\n\
         viscosity = 0.5\nbody_force = {force}\n\
         [[fibre]]\nbeads = 3\nbead_radius = 4\n[[fibre]]\nbeads = 1\nbead_radius = 3\n"
    )
}

/// Beads 0 and 1 overlap (spacing 6 < 8); bead 3 wraps across the periodic boundary.
fn beads(dims: u8, t: f64, v: [f64; 3], w: [f64; 3]) -> Vec<BeadState> {
    let z = if dims == 3 { 10.0 } else { 0.0 };
    let base = [
        [10.0, 12.0, z],
        [16.0, 12.5, z],
        [24.0, 14.0, z],
        [-1.0, 30.0, z + 0.5 * (dims as f64 - 2.0)],
    ];
    base.iter()
        .map(|p| BeadState {
            position: std::array::from_fn(|c| p[c] + v[c] * t),
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: v,
            angular_velocity: w,
        })
        .collect()
}

fn check(dims: u8, grid: &str, force: [f64; 3], cells: f64) {
    let fs = if dims == 2 {
        format!("[{}, {}]", force[0], force[1])
    } else {
        format!("[{}, {}, {}]", force[0], force[1], force[2])
    };
    let (mut c, mut x, _) = configure(&scene(dims, grid, &fs));
    let dt = 0.7;
    let v = [0.02, -0.01, if dims == 3 { 0.005 } else { 0.0 }];
    let w = if dims == 3 {
        [0.001, -0.002, 0.003]
    } else {
        [0.0, 0.0, 0.003]
    };
    let mut worst: f64 = 0.0;
    for n in 0..40u64 {
        let p0 = momentum(&c, 1.0);
        let s = beads(dims, (n + 1) as f64 * dt, v, w);
        let (imp, _) = bead_step(&mut c, &mut x, n, &s, &s);
        let p1 = momentum(&c, 1.0);
        for k in 0..dims as usize {
            let j: f64 = imp.iter().map(|i| i.impulse[k]).sum();
            let scale: f64 = imp.iter().map(|i| i.impulse[k].abs()).sum::<f64>() + p1[k].abs();
            let residual = p1[k] - p0[k] + j - force[k] * cells * dt;
            worst = worst.max(residual.abs() / scale);
        }
    }
    // A bead that speeds up: the fluid gains rho ΔV ∫ phi beyond the impulses.
    let n = 40u64;
    let p0 = momentum(&c, 1.0);
    let before = beads(dims, (n + 1) as f64 * dt, v, w);
    let dv = [0.004, 0.002, if dims == 3 { -0.001 } else { 0.0 }];
    let after: Vec<BeadState> = before
        .iter()
        .map(|s| BeadState {
            velocity: std::array::from_fn(|k| s.velocity[k] + dv[k]),
            ..*s
        })
        .collect();
    cosim::Exchange::publish_states(&mut x, cosim::Port::BeadPositions, n + 1, &before).unwrap();
    let rep = cosim::Component::run_phase(&mut c, n, cosim::Phase::FluidMomentumExchange, &mut x)
        .unwrap();
    let volume = diag(&rep, "bead_volume");
    let mut imp = Vec::new();
    cosim::Exchange::read_impulses(&mut x, cosim::Port::BeadImpulses, &mut imp).unwrap();
    cosim::Exchange::publish_states(&mut x, cosim::Port::BeadStates, n + 1, &after).unwrap();
    cosim::Component::run_phase(&mut c, n, cosim::Phase::FluidPenalty, &mut x).unwrap();
    let p1 = momentum(&c, 1.0);
    for k in 0..dims as usize {
        let j: f64 = imp.iter().map(|i| i.impulse[k]).sum();
        let scale: f64 = imp.iter().map(|i| i.impulse[k].abs()).sum::<f64>() + p1[k].abs();
        let residual = p1[k] - p0[k] + j - force[k] * cells * dt - volume * dv[k];
        worst = worst.max(residual.abs() / scale);
    }
    eprintln!(
        "{dims}D {grid}: worst relative momentum residual {worst:.1e} (bead volume {volume:.3})"
    );
    assert!(worst < 1e-12);
}

#[test]
fn exchange_and_penalty_conserve_momentum_2d() {
    check(2, "[40, 36]", [0.0, 0.0, 0.0], 1440.0);
    check(2, "[40, 36]", [1e-4, -2e-4, 0.0], 1440.0);
}

#[test]
fn exchange_and_penalty_conserve_momentum_3d() {
    check(3, "[36, 40, 20]", [2e-5, 0.0, -1e-5], 28800.0);
}
