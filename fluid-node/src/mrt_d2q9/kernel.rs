//! The D2Q9 lattice and the MRT collision of one node (REFERENCE.md section 5; Lallemand &
//! Luo 2000): moments m = M f, relaxation with Guo forcing in moment space, f* = M^-1 m*.
//!
//! M and M^-1 are written out by hand: a dense 9 x 9 product would cost 81 multiply-adds per
//! transform, the sparse integer rows below about a quarter of that.

/// Number of discrete velocities.
pub const Q: usize = 9;

/// Discrete velocities c_i: rest, the four axes, the four diagonals (REFERENCE.md section 5).
pub const C: [[i32; 2]; Q] = [
    [0, 0],
    [1, 0],
    [0, 1],
    [-1, 0],
    [0, -1],
    [1, 1],
    [-1, 1],
    [-1, -1],
    [1, -1],
];

/// Lattice weights w_i.
pub const W: [f64; Q] = [
    4.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
];

/// Index of -c_i.
pub const OPP: [usize; Q] = [0, 3, 4, 1, 2, 7, 8, 5, 6];

/// The moment matrix M (rows: rho, e, eps, jx, qx, jy, qy, pxx, pxy), REFERENCE.md section 5.
pub const M: [[f64; Q]; Q] = [
    [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
    [-4.0, -1.0, -1.0, -1.0, -1.0, 2.0, 2.0, 2.0, 2.0],
    [4.0, -2.0, -2.0, -2.0, -2.0, 1.0, 1.0, 1.0, 1.0],
    [0.0, 1.0, 0.0, -1.0, 0.0, 1.0, -1.0, -1.0, 1.0],
    [0.0, -2.0, 0.0, 2.0, 0.0, 1.0, -1.0, -1.0, 1.0],
    [0.0, 0.0, 1.0, 0.0, -1.0, 1.0, 1.0, -1.0, -1.0],
    [0.0, 0.0, -2.0, 0.0, 2.0, 1.0, 1.0, -1.0, -1.0],
    [0.0, 1.0, -1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, -1.0, 1.0, -1.0],
];

/// Row norms: M^-1 = M^T diag(NORM) (REFERENCE.md section 5).
pub const NORM: [f64; Q] = [
    1.0 / 9.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 6.0,
    1.0 / 12.0,
    1.0 / 6.0,
    1.0 / 12.0,
    1.0 / 4.0,
    1.0 / 4.0,
];

/// Rate of the shear-stress moments pxx, pxy for a kinematic viscosity nu:
/// nu = (1/3)(1/s_nu - 1/2).
#[inline(always)]
pub fn s_nu(nu: f64) -> f64 {
    1.0 / (3.0 * nu + 0.5)
}

/// Rate of the energy-flux moments qx, qy tied to s_nu by
/// Lambda = (1/s_nu - 1/2)(1/s_q - 1/2) = 3/16, i.e. 1/s_q - 1/2 = 1/(16 nu): with it the
/// half-way bounce-back wall sits at the link midpoint whatever the viscosity (REFERENCE.md
/// section 5; Ginzburg's "magic" parameter).
#[inline(always)]
pub fn s_q(nu: f64) -> f64 {
    16.0 * nu / (8.0 * nu + 1.0)
}

/// m = M f.
#[inline(always)]
pub fn moments(f: &[f64; Q]) -> [f64; Q] {
    let a = f[1] + f[2] + f[3] + f[4];
    let d = f[5] + f[6] + f[7] + f[8];
    let d13 = f[1] - f[3];
    let d24 = f[2] - f[4];
    let d57 = f[5] - f[7];
    let d86 = f[8] - f[6];
    [
        f[0] + a + d,
        -4.0 * f[0] - a + 2.0 * d,
        4.0 * f[0] - 2.0 * a + d,
        d13 + d57 + d86,
        -2.0 * d13 + d57 + d86,
        d24 + d57 - d86,
        -2.0 * d24 + d57 - d86,
        f[1] - f[2] + f[3] - f[4],
        f[5] - f[6] + f[7] - f[8],
    ]
}

/// f = M^-1 m = M^T diag(NORM) m.
#[inline(always)]
pub fn populations(m: &[f64; Q]) -> [f64; Q] {
    let r = m[0] * NORM[0];
    let e = m[1] * NORM[1];
    let p = m[2] * NORM[2];
    let jx = m[3] * NORM[3];
    let qx = m[4] * NORM[4];
    let jy = m[5] * NORM[5];
    let qy = m[6] * NORM[6];
    let xx = m[7] * NORM[7];
    let xy = m[8] * NORM[8];
    let axis = r - e - 2.0 * p;
    let diag = r + 2.0 * e + p;
    let x = jx - 2.0 * qx;
    let y = jy - 2.0 * qy;
    let dx = jx + qx;
    let dy = jy + qy;
    [
        r - 4.0 * e + 4.0 * p,
        axis + x + xx,
        axis + y - xx,
        axis - x + xx,
        axis - y - xx,
        diag + dx + dy + xy,
        diag - dx + dy - xy,
        diag - dx - dy + xy,
        diag + dx - dy - xy,
    ]
}

/// Equilibrium moments for density rho and momentum j = rho u (REFERENCE.md section 5):
/// e = rho(-2 + 3u^2), eps = rho(1 - 3u^2), q = -j, pxx = rho(ux^2 - uy^2), pxy = rho ux uy.
#[inline(always)]
pub fn equilibrium_moments(rho: f64, ux: f64, uy: f64) -> [f64; Q] {
    let u2 = ux * ux + uy * uy;
    let (jx, jy) = (rho * ux, rho * uy);
    [
        rho,
        rho * (-2.0 + 3.0 * u2),
        rho * (1.0 - 3.0 * u2),
        jx,
        -jx,
        jy,
        -jy,
        rho * (ux * ux - uy * uy),
        rho * ux * uy,
    ]
}

/// Guo's forcing in moment space for velocity u and force density F (REFERENCE.md section 5):
/// F_hat = (0, 6u.F, -6u.F, Fx, -Fx, Fy, -Fy, 2(ux Fx - uy Fy), ux Fy + uy Fx).
#[inline(always)]
pub fn force_moments(ux: f64, uy: f64, fx: f64, fy: f64) -> [f64; Q] {
    let uf = 6.0 * (ux * fx + uy * fy);
    [
        0.0,
        uf,
        -uf,
        fx,
        -fx,
        fy,
        -fy,
        2.0 * (ux * fx - uy * fy),
        ux * fy + uy * fx,
    ]
}

/// Rest populations w_i rho0 subtracted from the stored ones: the lattice keeps
/// f~_i = f_i - w_i rho0, whose round-off scales with the deviation from rest rather than
/// with rho0 (Skordos 1993). Their moments are m - m_rest, m_rest = (rho0, -2 rho0, rho0, 0..).
#[inline(always)]
pub fn rest_moments(rho0: f64) -> [f64; Q] {
    [rho0, -2.0 * rho0, rho0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
}

/// Density and velocity of pre-collision deviations `fd` (f~ = f - w rho0) under force
/// density F: rho u = sum f c + F/2 (REFERENCE.md section 5).
#[inline(always)]
pub fn macroscopic(fd: &[f64; Q], rho0: f64, fx: f64, fy: f64) -> (f64, f64, f64) {
    let rho = rho0 + fd.iter().sum::<f64>();
    let jx = (fd[1] - fd[3]) + (fd[5] - fd[7]) + (fd[8] - fd[6]);
    let jy = (fd[2] - fd[4]) + (fd[5] - fd[7]) - (fd[8] - fd[6]);
    let inv = 1.0 / rho;
    (rho, (jx + 0.5 * fx) * inv, (jy + 0.5 * fy) * inv)
}

/// Fixed rates of the two even moments that do not carry shear stress.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixedRates {
    /// Rate of the energy moment e (sets the bulk viscosity).
    pub s_e: f64,
    /// Rate of the energy-square moment eps.
    pub s_eps: f64,
}

/// One MRT collision with Guo forcing, m* = m - S(m - m_eq) + (I - S/2) F_hat, of the
/// pre-collision deviations `fd` (f~ = f - w rho0) at a node of kinematic viscosity `nu`
/// and force density (`fx`, `fy`); returns the post-collision deviations (REFERENCE.md
/// section 5). The rest part w rho0 is a fixed point, so only the equilibria of e and eps
/// change: e~_eq = e_eq + 2 rho0, eps~_eq = eps_eq - rho0.
///
/// The conserved moments are not relaxed: rho* = rho, and j* = j + F whatever their rate,
/// since j_eq = j + F/2.
#[inline(always)]
pub fn collide(fd: &[f64; Q], rho0: f64, nu: f64, fx: f64, fy: f64, fixed: FixedRates) -> [f64; Q] {
    collide_with_velocity(fd, rho0, nu, fx, fy, fixed).0
}

/// [`collide`], also returning the node's velocity `u = (j + F/2) / rho` that the collision
/// used, so that a step can keep flow statistics without a second pass over the lattice.
#[inline(always)]
pub fn collide_with_velocity(
    fd: &[f64; Q],
    rho0: f64,
    nu: f64,
    fx: f64,
    fy: f64,
    fixed: FixedRates,
) -> ([f64; Q], f64, f64) {
    let m = moments(fd);
    let drho = m[0];
    let rho = rho0 + drho;
    let inv = 1.0 / rho;
    let ux = (m[3] + 0.5 * fx) * inv;
    let uy = (m[5] + 0.5 * fy) * inv;
    let sn = s_nu(nu);
    let sq = s_q(nu);
    let ru2 = 3.0 * rho * (ux * ux + uy * uy);
    let uf = 6.0 * (ux * fx + uy * fy);
    let (se, sp) = (fixed.s_e, fixed.s_eps);
    let e = m[1] - se * (m[1] - (ru2 - 2.0 * drho)) + (1.0 - 0.5 * se) * uf;
    let eps = m[2] - sp * (m[2] - (drho - ru2)) - (1.0 - 0.5 * sp) * uf;
    let hq = 1.0 - 0.5 * sq;
    let qx = m[4] - sq * (m[4] + rho * ux) - hq * fx;
    let qy = m[6] - sq * (m[6] + rho * uy) - hq * fy;
    let hn = 1.0 - 0.5 * sn;
    let pxx = m[7] - sn * (m[7] - rho * (ux * ux - uy * uy)) + hn * 2.0 * (ux * fx - uy * fy);
    let pxy = m[8] - sn * (m[8] - rho * ux * uy) + hn * (ux * fy + uy * fx);
    (
        populations(&[drho, e, eps, m[3] + fx, qx, m[5] + fy, qy, pxx, pxy]),
        ux,
        uy,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mat_vec(a: &[[f64; Q]; Q], v: &[f64; Q]) -> [f64; Q] {
        std::array::from_fn(|k| (0..Q).map(|i| a[k][i] * v[i]).sum())
    }

    fn sample() -> [f64; Q] {
        std::array::from_fn(|i| 0.1 + 0.37 * (i as f64 * 1.3).sin().abs())
    }

    /// The unrolled transforms equal the matrix of REFERENCE.md section 5, and M^-1 M = I.
    #[test]
    fn transforms_match_the_matrix_and_invert() {
        let f = sample();
        let m = moments(&f);
        let dense = mat_vec(&M, &f);
        for k in 0..Q {
            assert!((m[k] - dense[k]).abs() < 1e-14, "row {k}");
        }
        let back = populations(&m);
        for i in 0..Q {
            assert!((back[i] - f[i]).abs() < 1e-15, "population {i}");
        }
        let rest = populations(&rest_moments(0.7));
        for i in 0..Q {
            assert!((rest[i] - 0.7 * W[i]).abs() < 1e-16, "rest population {i}");
        }
        // M's rows are polynomials of the velocities (Lallemand & Luo 2000).
        for i in 0..Q {
            let (cx, cy) = (C[i][0] as f64, C[i][1] as f64);
            let c2 = cx * cx + cy * cy;
            assert_eq!(M[1][i], 3.0 * c2 - 4.0);
            assert_eq!(M[2][i], (9.0 * c2 * c2 - 21.0 * c2 + 8.0) / 2.0);
            assert_eq!(M[3][i], cx);
            assert_eq!(M[4][i], (3.0 * c2 - 5.0) * cx);
            assert_eq!(M[7][i], cx * cx - cy * cy);
            assert_eq!(M[8][i], cx * cy);
            assert_eq!(C[OPP[i]], [-C[i][0], -C[i][1]]);
        }
    }

    /// The equilibrium moments are the moments of the usual second-order
    /// f_eq = w rho (1 + 3 c.u + 9/2 (c.u)^2 - 3/2 u^2), and F_hat the moments of Guo's
    /// w (3 c.F + 9 (c.u)(c.F) - 3 u.F).
    #[test]
    fn equilibrium_and_force_are_the_velocity_space_ones() {
        let (rho, ux, uy, fx, fy) = (1.03, 0.041, -0.027, 2.1e-3, -0.7e-3);
        let feq: [f64; Q] = std::array::from_fn(|i| {
            let cu = C[i][0] as f64 * ux + C[i][1] as f64 * uy;
            W[i] * rho * (1.0 + 3.0 * cu + 4.5 * cu * cu - 1.5 * (ux * ux + uy * uy))
        });
        let guo: [f64; Q] = std::array::from_fn(|i| {
            let (cx, cy) = (C[i][0] as f64, C[i][1] as f64);
            let cu = cx * ux + cy * uy;
            let cf = cx * fx + cy * fy;
            W[i] * (3.0 * cf + 9.0 * cu * cf - 3.0 * (ux * fx + uy * fy))
        });
        let (me, mf) = (moments(&feq), moments(&guo));
        let (ee, ef) = (
            equilibrium_moments(rho, ux, uy),
            force_moments(ux, uy, fx, fy),
        );
        for k in 0..Q {
            assert!((me[k] - ee[k]).abs() < 1e-15, "equilibrium moment {k}");
            assert!((mf[k] - ef[k]).abs() < 1e-17, "force moment {k}");
        }
    }

    /// The fused collision equals the generic m - S(m - m_eq) + (I - S/2) F_hat; it keeps the
    /// mass and adds F to the momentum; equilibrium is a fixed point without force.
    #[test]
    fn collision_is_the_moment_space_relaxation() {
        let fixed = FixedRates {
            s_e: 1.1,
            s_eps: 1.1,
        };
        let (nu, fx, fy, rho0) = (0.09, 1.3e-3, -2.2e-3, 0.8);
        let f = sample();
        let fd: [f64; Q] = std::array::from_fn(|i| f[i] - W[i] * rho0);
        let m = moments(&f);
        let (rho, ux, uy) = macroscopic(&fd, rho0, fx, fy);
        assert!((rho - m[0]).abs() < 1e-15);
        let s = [
            0.0,
            fixed.s_e,
            fixed.s_eps,
            1.0,
            s_q(nu),
            1.0,
            s_q(nu),
            s_nu(nu),
            s_nu(nu),
        ];
        let (meq, fh) = (
            equilibrium_moments(rho, ux, uy),
            force_moments(ux, uy, fx, fy),
        );
        let generic: [f64; Q] =
            std::array::from_fn(|k| m[k] - s[k] * (m[k] - meq[k]) + (1.0 - 0.5 * s[k]) * fh[k]);
        let post = collide(&fd, rho0, nu, fx, fy, fixed);
        let post: [f64; Q] = std::array::from_fn(|i| post[i] + W[i] * rho0);
        let pm = moments(&post);
        for k in 0..Q {
            assert!((pm[k] - generic[k]).abs() < 1e-14, "moment {k}");
        }
        assert!((pm[0] - m[0]).abs() < 1e-15);
        assert!((pm[3] - (m[3] + fx)).abs() < 1e-15);
        let rest = rest_moments(rho0);
        let meq = equilibrium_moments(1.1, 0.05, -0.02);
        let eq = populations(&std::array::from_fn(|k| meq[k] - rest[k]));
        let again = collide(&eq, rho0, nu, 0.0, 0.0, fixed);
        for i in 0..Q {
            assert!((again[i] - eq[i]).abs() < 1e-15);
        }
        // Lambda = 3/16 for any viscosity.
        for nu in [1e-3, 0.01, 1.0 / 6.0, 0.5, 10.0] {
            let l = (1.0 / s_nu(nu) - 0.5) * (1.0 / s_q(nu) - 0.5);
            assert!((l - 3.0 / 16.0).abs() < 1e-12, "nu = {nu}: Lambda = {l}");
        }
    }
}
