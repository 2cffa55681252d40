//! A 3D reference for the Jeffery period of a rigid chain of touching spheres: unbounded
//! Stokes flow, solved by the rigid multiblob method (each sphere a shell of blobs coupled by
//! the Rotne-Prager-Yamakawa tensor).
//!
//! As in 2D (`stokes_chain_2d.rs`), a body symmetric about its axis, lying along x in the
//! shear `u = (gamma y, 0, 0)`, turns at `omega_z = -(gamma / 2) (1 - B)` with B its
//! Bretherton constant, and Jeffery's period for an orbit in the shear plane is
//! `gamma T = 4 pi / sqrt(1 - B²) = 2 pi (e + 1/e)`, `e` the aspect ratio of the equivalent
//! spheroid, `B = (e² - 1) / (e² + 1)`.
//!
//! The solve: every blob k at `r_k` exerts a force `lambda_k` on the fluid; its velocity is
//! the flow's plus `sum_j M_kj lambda_j` (RPY, blob radius `a`, viscosity 1), and must be the
//! rigid motion `U + Omega x r_k`; the body is free, `sum lambda = 0`, `sum r x lambda = 0`.
//! One dense positive definite solve of size 3 (blobs), for seven right-hand sides. Each sphere is the vertices of a
//! subdivided icosahedron (12, 42, 162, 642 blobs), blob radius half the shortest distance
//! between vertices; a lone shell's translational drag gives its hydrodynamic radius, and
//! the shells are scaled so that it is the bead radius, and placed touching (centres two
//! radii apart). [`chain_bretherton`] extrapolates from 42 and 162 blobs per sphere. Checked
//! against a sphere (B = 0) and against Jeffery's spheroids built the same way; the example
//! `stokes_chain_periods_3d` prints the chains at each resolution (docs/validation/spm.md,
//! "Jeffery orbit in 3D").
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;

/// Vertices of an icosahedron subdivided `level` times, on the unit sphere (12, 42, 162,
/// 642, ... points), in a fixed order.
pub fn icosphere(level: u32) -> Vec<[f64; 3]> {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut faces: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let unit = |p: [f64; 3]| {
        let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        [p[0] / n, p[1] / n, p[2] / n]
    };
    for p in v.iter_mut() {
        *p = unit(*p);
    }
    for _ in 0..level {
        let mut mid = std::collections::BTreeMap::<(usize, usize), usize>::new();
        let mut next = Vec::with_capacity(4 * faces.len());
        for f in &faces {
            let mut m = [0usize; 3];
            for e in 0..3 {
                let (a, b) = (f[e], f[(e + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[e] = *mid.entry(key).or_insert_with(|| {
                    let (p, q) = (v[a], v[b]);
                    v.push(unit([p[0] + q[0], p[1] + q[1], p[2] + q[2]]));
                    v.len() - 1
                });
            }
            next.push([f[0], m[0], m[2]]);
            next.push([f[1], m[1], m[0]]);
            next.push([f[2], m[2], m[1]]);
            next.push([m[0], m[1], m[2]]);
        }
        faces = next;
    }
    v
}

fn dist(p: [f64; 3], q: [f64; 3]) -> f64 {
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

/// Blob radius of the shell `icosphere(level)` scaled to radius 1: half the shortest distance
/// between its vertices.
fn blob_radius(level: u32) -> f64 {
    let v = icosphere(level);
    let mut h = f64::INFINITY;
    for (i, p) in v.iter().enumerate() {
        for q in &v[i + 1..] {
            h = h.min(dist(*p, *q));
        }
    }
    0.5 * h
}

/// The RPY mobility between blobs at `p` and `q`, radius `a`, viscosity 1.
fn rpy(p: [f64; 3], q: [f64; 3], a: f64) -> [[f64; 3]; 3] {
    let r = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let d = dist(p, q);
    let mut m = [[0.0; 3]; 3];
    if d == 0.0 {
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = 1.0 / (6.0 * PI * a);
        }
        return m;
    }
    let (c1, c2) = if d > 2.0 * a {
        let k = 1.0 / (8.0 * PI * d);
        (
            k * (1.0 + 2.0 * a * a / (3.0 * d * d)),
            k * (1.0 - 2.0 * a * a / (d * d)),
        )
    } else {
        let k = 1.0 / (6.0 * PI * a);
        (k * (1.0 - 9.0 * d / (32.0 * a)), k * (3.0 * d / (32.0 * a)))
    };
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = c2 * r[i] * r[j] / (d * d) + if i == j { c1 } else { 0.0 };
        }
    }
    m
}

/// The RPY mobility matrix of `blobs` (radius `a`), 3 rows and columns per blob.
fn mobility(blobs: &[[f64; 3]], a: f64) -> DMatrix<f64> {
    let m = blobs.len();
    let mut mob = DMatrix::<f64>::zeros(3 * m, 3 * m);
    for (k, p) in blobs.iter().enumerate() {
        for (j, q) in blobs.iter().enumerate() {
            let b = rpy(*p, *q, a);
            for r in 0..3 {
                for c in 0..3 {
                    mob[(3 * k + r, 3 * j + c)] = b[r][c];
                }
            }
        }
    }
    mob
}

/// The free rigid body made of `blobs` (radius `a`) in the linear flow `u = g x`: its
/// velocity U and angular velocity Omega about the origin. With `K` the map from (U, Omega)
/// to the blobs' rigid velocities, `M lambda = K Y - u` and `K^T lambda = 0` (no net force
/// or torque) give `(K^T M^-1 K) Y = K^T M^-1 u`: one Cholesky factorisation of the RPY
/// matrix (positive definite for any positions) and seven solves.
fn rigid_motion(blobs: &[[f64; 3]], a: f64, g: [[f64; 3]; 3]) -> ([f64; 3], [f64; 3]) {
    let m = blobs.len();
    let chol = mobility(blobs, a)
        .cholesky()
        .expect("the RPY mobility is positive definite");
    // Columns 0-5: K (U_x, U_y, U_z, Omega_x, Omega_y, Omega_z); column 6: the flow.
    let mut rhs = DMatrix::<f64>::zeros(3 * m, 7);
    for (k, p) in blobs.iter().enumerate() {
        for r in 0..3 {
            rhs[(3 * k + r, r)] = 1.0;
            rhs[(3 * k + r, 6)] = g[r][0] * p[0] + g[r][1] * p[1] + g[r][2] * p[2];
        }
        // Omega x p: x-row (w_y p_z - w_z p_y), y-row (w_z p_x - w_x p_z), z-row (w_x p_y - w_y p_x).
        rhs[(3 * k, 4)] = p[2];
        rhs[(3 * k, 5)] = -p[1];
        rhs[(3 * k + 1, 5)] = p[0];
        rhs[(3 * k + 1, 3)] = -p[2];
        rhs[(3 * k + 2, 3)] = p[1];
        rhs[(3 * k + 2, 4)] = -p[0];
    }
    let solved = chol.solve(&rhs);
    let k = rhs.columns(0, 6);
    let kt_mk = k.transpose() * solved.columns(0, 6);
    let kt_mu = k.transpose() * solved.column(6);
    let y = kt_mk
        .lu()
        .solve(&kt_mu)
        .expect("a rigid body of blobs has a positive definite resistance");
    ([y[0], y[1], y[2]], [y[3], y[4], y[5]])
}

/// The simple shear `u = (y, 0, 0)` (gamma = 1).
const SHEAR: [[f64; 3]; 3] = [[0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]];

/// Hydrodynamic radius of the unit shell at `level`: its drag over 6 pi U.
fn shell_hydrodynamic_radius(level: u32) -> f64 {
    let v = icosphere(level);
    let a = blob_radius(level);
    // Translated at U = 1 along x: the blob forces solve `M lambda = U`; their sum is the
    // drag 6 pi R_h U.
    let m = v.len();
    let sys = mobility(&v, a);
    let mut rhs = DVector::<f64>::zeros(3 * m);
    for k in 0..m {
        rhs[3 * k] = 1.0;
    }
    let lambda = sys
        .cholesky()
        .expect("the shell's mobility is positive definite")
        .solve(&rhs);
    let fx: f64 = (0..m).map(|k| lambda[3 * k]).sum();
    fx / (6.0 * PI)
}

/// The shell `icosphere(level)` scaled so that its hydrodynamic radius is 1: its points, its
/// blob radius, and the scale (below 1: a unit shell's drag is a larger sphere's).
fn unit_shell(level: u32) -> (Vec<[f64; 3]>, f64, f64) {
    let scale = 1.0 / shell_hydrodynamic_radius(level);
    (icosphere(level), scale * blob_radius(level), scale)
}

/// Blobs of `n` touching spheres of hydrodynamic radius 1 along x, centred on the origin,
/// each the shell `icosphere(level)`; and the blob radius.
pub fn chain_blobs(n: usize, level: u32) -> (Vec<[f64; 3]>, f64) {
    let (shell, a, scale) = unit_shell(level);
    let mut out = Vec::with_capacity(n * shell.len());
    for i in 0..n {
        let cx = 2.0 * i as f64 - (n as f64 - 1.0);
        for p in &shell {
            out.push([cx + scale * p[0], scale * p[1], scale * p[2]]);
        }
    }
    (out, a)
}

/// Blobs of a prolate spheroid of semi-axes `e` (along x) and 1, the check on the method:
/// the shell `icosphere(level)` stretched along x, its surface set back from the spheroid's
/// by the thickness a lone sphere's shell adds to its radius (its hydrodynamic radius less
/// its geometric one, at the same blob radius); and the blob radius.
pub fn spheroid_blobs(e: f64, level: u32) -> (Vec<[f64; 3]>, f64) {
    let (shell, a, scale) = unit_shell(level);
    let set_back = 1.0 - scale;
    let out = shell
        .into_iter()
        .map(|p| {
            [
                (e - set_back) * p[0],
                (1.0 - set_back) * p[1],
                (1.0 - set_back) * p[2],
            ]
        })
        .collect();
    (out, a)
}

/// Bretherton constant of a body along x made of `blobs` (radius `a`), from its rotation in
/// the shear: `omega_z = -(1 - B) / 2`.
pub fn bretherton(blobs: &[[f64; 3]], a: f64) -> f64 {
    let (_, omega) = rigid_motion(blobs, a, SHEAR);
    1.0 + 2.0 * omega[2]
}

/// Bretherton constant of a rigid chain of `n` touching spheres, shells at `level`.
pub fn chain_bretherton_at(n: usize, level: u32) -> f64 {
    let (b, a) = chain_blobs(n, level);
    bretherton(&b, a)
}

/// How much the error of B falls from one shell level to the next (each has about four times
/// the blobs of the one before): 2.8-3.7 for the spheroids of the tests, 3.0-3.1 for the
/// chains (`stokes_chain_periods_3d`).
pub const REFINEMENT_RATIO: f64 = 3.0;

/// Bretherton constant of a rigid chain of `beads` touching spheres: the shells of 42 and
/// 162 blobs per sphere, extrapolated with [`REFINEMENT_RATIO`] (Richardson). On Jeffery's
/// spheroids this is within 0.2 % of the exact B, closer than 642 blobs per sphere are.
pub fn chain_bretherton(beads: usize) -> f64 {
    let (coarse, fine) = (chain_bretherton_at(beads, 1), chain_bretherton_at(beads, 2));
    fine - (coarse - fine) / (REFINEMENT_RATIO - 1.0)
}

/// gamma T of a full Jeffery period (in the shear plane) and the equivalent spheroid's
/// aspect ratio, from B: the same law as for the 2D ellipse.
pub use super::stokes_chain_2d::{equivalent_aspect_ratio, period_gamma};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_has_the_vertex_counts_of_a_subdivided_icosahedron() {
        for (level, n) in [(0, 12), (1, 42), (2, 162)] {
            let v = icosphere(level);
            assert_eq!(v.len(), n);
            for p in v {
                assert!((dist(p, [0.0; 3]) - 1.0).abs() < 1e-14);
            }
        }
    }

    /// Jeffery's prolate spheroids, B = (e^2 - 1) / (e^2 + 1), as blob shells: at 162 blobs
    /// within 2.1 % (measured 2.0 % at e = 2), and extrapolated from 42 and 162 blobs as
    /// [`chain_bretherton`] does within 0.3 % (measured 0.18 %, 0.06 %, 0.05 % at e = 2, 3,
    /// 4).
    #[test]
    fn spheroids_turn_as_jeffery_says() {
        for e in [2.0f64, 3.0, 4.0] {
            let exact = (e * e - 1.0) / (e * e + 1.0);
            let at = |level| {
                let (b, a) = spheroid_blobs(e, level);
                bretherton(&b, a)
            };
            let (coarse, fine) = (at(1), at(2));
            let extrapolated = fine - (coarse - fine) / (REFINEMENT_RATIO - 1.0);
            assert!(
                (fine / exact - 1.0).abs() < 0.021,
                "e {e}: {fine} vs {exact}"
            );
            assert!(
                (extrapolated / exact - 1.0).abs() < 0.003,
                "e {e}: {extrapolated} vs {exact}"
            );
            // The error falls with the blobs: the extrapolation corrects in the right sense.
            assert!((coarse - exact).abs() > (fine - exact).abs());
        }
    }

    /// The two-sphere chain: 642 blobs per sphere land within 2e-3 of the extrapolation from
    /// 42 and 162 (measured 0.5949 against 0.5935), and the chains grow more elongated with N.
    #[test]
    fn chains_converge_and_lengthen() {
        let b2 = chain_bretherton(2);
        let fine = chain_bretherton_at(2, 3);
        assert!((fine - b2).abs() < 2e-3, "{fine} vs {b2}");
        let b3 = chain_bretherton(3);
        assert!(b2 < b3 && b3 < 1.0, "{b2} {b3}");
        // gamma T for a sphere pair: 2 pi (e + 1/e) with e near 2.
        let e = equivalent_aspect_ratio(b2);
        assert!((e - 2.0).abs() < 0.1, "{e}");
        assert!((period_gamma(b2) - 2.0 * PI * (e + 1.0 / e)).abs() < 1e-12);
    }

    /// A sphere turns with the shear's vorticity, -gamma / 2 (B = 0), and does not move;
    /// its shell's hydrodynamic radius lies near its geometric one.
    #[test]
    fn a_sphere_turns_at_half_the_shear_rate() {
        for level in [1, 2] {
            let (b, a) = chain_blobs(1, level);
            let (u, omega) = rigid_motion(&b, a, SHEAR);
            assert!(u.iter().all(|c| c.abs() < 1e-12), "{u:?}");
            assert!((omega[2] + 0.5).abs() < 1e-3, "level {level}: {omega:?}");
            let r = shell_hydrodynamic_radius(level);
            assert!(r > 1.0 && r < 1.3, "level {level}: {r}");
        }
    }
}
