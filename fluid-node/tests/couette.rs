//! Plane Couette flow between two moving walls, no fibre, from rest to steady state.
//!
//! Reference: the linear profile u_x(y) = u_b + (u_t - u_b) (y - y_b) / H between the
//! walls' inner faces (y_b = T - 1/2, H = ny - 2 T), checked with the node's own
//! `couette_max_error` diagnostic: max over the gap, 2 xi away from the faces, of
//! |<u_x>(y) - linear| / |u_t - u_b|, <.> the average over x (and z).
//!
//! The SPM's no-slip plane depends on nu dt / xi^2 (REFERENCE.md section 6): the penalty
//! acts once per step on a velocity that diffused sqrt(nu dt) into the wall since the last
//! one. Measured on 8 x 96 (xi = 1, T = 4), shift of the no-slip plane per wall into the
//! fluid (negative) or into the wall: nu dt / xi^2 = 0.1: -1.49 xi; 0.25: -0.99 xi;
//! 0.5: -0.56 xi; 1: +0.09 xi; 2: +2.0 xi (the same in units of xi for xi = 2 up to 1).
mod common;
use common::*;

fn run(grid: &str, dims: u8, nu: f64, dt: f64, xi: f64, u: f64, steps: u64) -> f64 {
    let scene = format!(
        "dimensions = {dims}\n[time]\ndt = {dt}\n[fluid]\nmethod = \"spm\"\ngrid = {grid}\n\
         viscosity = {nu}\nxi = {xi}\n[walls]\nvelocity = [{}, {u}]\nthickness = {}\n",
        -u,
        4.0 * xi
    );
    let (mut c, mut x, cfg) = configure(&scene);
    assert_eq!(cfg.effects, vec!["walls".to_string()]);
    let mut err = f64::NAN;
    for n in 0..steps {
        let r = step(&mut c, &mut x, n);
        err = diag(&r, "couette_max_error");
        assert!(diag(&r, "max_divergence") < 1e-14);
    }
    err
}

/// Steps for 1e-4 of the slowest mode to remain: 8 H^2 / (pi^2 nu) / dt.
fn steps_to_steady(gap: f64, nu: f64, dt: f64) -> u64 {
    (8.0 * gap * gap / (std::f64::consts::PI.powi(2) * nu) / dt).ceil() as u64
}

#[test]
fn couette_2d_from_rest_reaches_the_linear_profile() {
    // Measured: 16 x 64, xi = 1: 5.6e-3 at nu dt / xi^2 = 0.7, 5.3e-4 at 1;
    // 16 x 96, xi = 2 (T = 8): 7.5e-3 at 0.7.
    for (grid, gap, xi, q, tol) in [
        ("[16, 64]", 56.0, 1.0, 0.7, 1e-2),
        ("[16, 64]", 56.0, 1.0, 1.0, 1e-3),
        ("[16, 96]", 80.0, 2.0, 0.7, 1e-2),
    ] {
        let nu = 1.0;
        let dt = q * xi * xi / nu;
        let steps = steps_to_steady(gap, nu, dt);
        let err = run(grid, 2, nu, dt, xi, 0.01, steps);
        eprintln!("Couette 2D {grid}, xi {xi}, nu dt / xi^2 = {q}: {steps} steps, couette_max_error {err:.2e}");
        assert!(err < tol);
    }
}

#[test]
fn couette_3d_from_rest_reaches_the_linear_profile() {
    let (nu, dt) = (1.0, 1.0);
    let steps = steps_to_steady(56.0, nu, dt);
    let err = run("[8, 64, 8]", 3, nu, dt, 1.0, 0.01, steps);
    eprintln!("Couette 3D 8 x 64 x 8, nu dt / xi^2 = 1: couette_max_error {err:.2e}");
    assert!(err < 1e-3);
}
