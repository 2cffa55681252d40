//! One-dimensional equilibria at a flat solid wall and the contact angle they predict
//! (L2020 Fig. 4 and eq. 44).
//!
//! The problem: a periodic line of `nodes` nodes (a 2D grid of `nodes x 1`), a solid slab
//! filling its middle half with the profile of L2020 eq. 25 (`φ = 1/2 + 1/2 tanh(s / (√2 ξ))`,
//! s the distance into the solid, truncated at the cut-off `ξ_c`), ψ* from ψ0 by eq. 31,
//! and one fluid (A or B) in the rest. ψ is relaxed to a minimum of F with zero chemical
//! potential, the value shared by the bulk phases ψ = ±1 and ψ = ψ0 in the solid, by the
//! non-conserved flow of [`CahnHilliard::relax_non_conserved`] (a conserved relaxation would
//! shift the bulk values by the adsorbed amount over the domain length).
//!
//! Energy excess. The solid bulk has the energy density
//! `f_S = (1/4)(1 - ψ0²)² + (3/2)(ψ0 - ψ*)²`, the fluid bulks 0. With the Gibbs dividing
//! surface where φ = 1/2, the reference energy is `e0 f_S Σ φ` (Σ φ is the sharp solid length
//! in 1D since the profile is odd about the surface), and the excess per wall is
//! `σ = (F - e0 f_S Σ φ) / 2` (two walls in the periodic line). The dividing-surface choice
//! shifts σ_AS and σ_BS alike and cancels in the contact angle.
//!
//! Contact angle. Young's law with θ_A measured through fluid A gives
//! `cos θ_A = (σ_BS - σ_AS) / σ_AB`. L2020 eq. 44 writes `θ = acos((σ_AS - σ_BS) / σ_AB)`,
//! the same angle measured through fluid B: `θ_L2020 = 180° - θ_A`. A bead with ψ0 > 0 is
//! wetted by A (σ_AS < σ_BS, θ_A < 90°), as L2020 section 2.4 states.
use super::{
    psi_star, sigma_ab, CahnHilliard, CahnHilliardConfig, CahnHilliardError, Fluid, Relaxation,
};
use crate::grid::Grid;
use crate::parallel::for_each_row;
use crate::smoothed_profile::interface;

/// Parameters of the 1D wall problem.
#[derive(Debug, Clone, PartialEq)]
pub struct WallProblem {
    /// Interfacial length ξ (grid units), also the width of the solid profile (eq. 25).
    pub xi: f64,
    /// Cut-off ξ_c of the solid profile (eq. 25), grid units.
    pub cutoff: f64,
    /// Energy density scale e0.
    pub e0: f64,
    /// Nodes of the periodic line; the solid fills the middle half. Default
    /// `max(64, 4 ceil(ξ_c + 12 ξ))`, leaving every interface twelve ξ of bulk.
    pub nodes: usize,
    /// Relaxation pseudo time step (the relaxation is stable for any). Default 2.
    pub relaxation_dt: f64,
    /// Stop when max |μ_ψ| / e0 falls below this. Default 1e-11.
    pub tolerance: f64,
    /// Default 200 000.
    pub max_iterations: usize,
}

impl WallProblem {
    pub fn new(xi: f64, cutoff: f64, e0: f64) -> Self {
        let nodes = (4 * (cutoff + 12.0 * xi).ceil() as usize).max(64);
        Self {
            xi,
            cutoff,
            e0,
            nodes,
            relaxation_dt: 2.0,
            tolerance: 1e-11,
            max_iterations: 200_000,
        }
    }
}

/// The relaxed wall profile and its energy excess.
#[derive(Debug, Clone, PartialEq)]
pub struct WallEquilibrium {
    /// Energy excess per wall area, σ_AS or σ_BS (units e0 × length).
    pub sigma: f64,
    pub psi: Vec<f64>,
    pub phi: Vec<f64>,
    /// Free energy density e0 f(x) with `|∇ψ|²` by spectral derivative (L2020 Fig. 4).
    pub energy_density: Vec<f64>,
    pub relaxation: Relaxation,
}

/// Relax the wall problem for affinity `psi0` with `fluid` outside the solid.
pub fn wall_equilibrium(
    p: &WallProblem,
    psi0: f64,
    fluid: Fluid,
) -> Result<WallEquilibrium, CahnHilliardError> {
    if !(psi0.is_finite() && psi0.abs() <= 1.0) {
        return Err(CahnHilliardError::InvalidParameter {
            name: "psi0",
            value: psi0,
            reason: "must lie in [-1, 1]",
        });
    }
    if !(p.cutoff.is_finite() && p.cutoff >= 0.0) {
        return Err(CahnHilliardError::InvalidParameter {
            name: "cutoff",
            value: p.cutoff,
            reason: "must be finite and non-negative",
        });
    }
    let n = p.nodes;
    let grid = Grid::new(2, [n, 1, 1]);
    let cfg = CahnHilliardConfig {
        xi: p.xi,
        e0: p.e0,
        ..CahnHilliardConfig::default()
    };
    let mut ch = CahnHilliard::new(grid, cfg)?;
    let half = n as f64 / 2.0;
    let quarter = n as f64 / 4.0;
    for (x, f) in ch.phi_mut().iter_mut().enumerate() {
        *f = interface(quarter - (x as f64 - half).abs(), p.xi, p.cutoff);
    }
    ch.set_uniform_affinity(psi0);
    let start: Vec<f64> = ch
        .phi()
        .iter()
        .map(|&f| f * psi0 + (1.0 - f) * fluid.psi())
        .collect();
    ch.set_psi(&start)?;
    let relaxation = ch.relax_non_conserved(p.relaxation_dt, p.tolerance, p.max_iterations)?;
    let ps = psi_star(psi0);
    let f_solid = 0.25 * (1.0 - psi0 * psi0).powi(2) + 1.5 * (psi0 - ps).powi(2);
    let solid_length: f64 = ch.phi().iter().sum();
    let total = ch.free_energy().total;
    let sigma = 0.5 * (total - p.e0 * f_solid * solid_length);
    let mut energy_density = vec![0.0; n];
    ch.free_energy_density(&mut energy_density)?;
    Ok(WallEquilibrium {
        sigma,
        psi: ch.psi().to_vec(),
        phi: ch.phi().to_vec(),
        energy_density,
        relaxation,
    })
}

/// Energy excesses and the contact angle they predict (L2020 eq. 44).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactAngle {
    pub psi0: f64,
    pub sigma_as: f64,
    pub sigma_bs: f64,
    /// Analytic [`sigma_ab`].
    pub sigma_ab: f64,
    /// `(σ_BS - σ_AS) / σ_AB` (Young, angle through A); outside [-1, 1]: complete wetting.
    pub cos_theta_a: f64,
    /// θ_A in degrees (the cosine clamped to [-1, 1]).
    pub theta_a_degrees: f64,
    /// L2020 eq. 44's angle, through fluid B: `180° - θ_A`.
    pub theta_l2020_degrees: f64,
}

/// σ_AS and σ_BS by [`wall_equilibrium`], σ_AB analytic, and the angles.
pub fn contact_angle(p: &WallProblem, psi0: f64) -> Result<ContactAngle, CahnHilliardError> {
    let sigma_as = wall_equilibrium(p, psi0, Fluid::A)?.sigma;
    let sigma_bs = wall_equilibrium(p, psi0, Fluid::B)?.sigma;
    let sab = sigma_ab(p.e0, p.xi);
    let cos_theta_a = (sigma_bs - sigma_as) / sab;
    let theta_a_degrees = cos_theta_a.clamp(-1.0, 1.0).acos().to_degrees();
    Ok(ContactAngle {
        psi0,
        sigma_as,
        sigma_bs,
        sigma_ab: sab,
        cos_theta_a,
        theta_a_degrees,
        theta_l2020_degrees: 180.0 - theta_a_degrees,
    })
}

impl CahnHilliard {
    /// Relax ψ towards a minimum of F at zero chemical potential by the non-conserved
    /// (Allen–Cahn) flow `∂ψ/∂t = -μ_ψ / e0`, semi-implicit with the same stabilisation,
    /// until max |μ_ψ| / e0 < `tolerance`. The mean of ψ is NOT conserved: this prepares
    /// equilibria in contact with the bulk phases ψ = ±1 and ψ0 (which all have μ = 0).
    pub fn relax_non_conserved(
        &mut self,
        dt: f64,
        tolerance: f64,
        max_iterations: usize,
    ) -> Result<Relaxation, CahnHilliardError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(CahnHilliardError::InvalidParameter {
                name: "relaxation dt",
                value: dt,
                reason: "must be finite and positive",
            });
        }
        let g = self.grid;
        let nxh = g.nxh();
        let (xi2, s) = (self.cfg.xi * self.cfg.xi, self.cfg.stabilisation);
        let mut residual = f64::INFINITY;
        let mut it = 0;
        while it < max_iterations {
            if it % 10 == 0 {
                residual = self.residual();
                if residual < tolerance {
                    break;
                }
            }
            self.bulk_transform();
            let w = &self.waves;
            let gh = &self.g_hat;
            let mut fields = [&mut self.psi_hat[..]];
            for_each_row(&mut fields, nxh, |r, rows| {
                let (iy, iz) = g.row_yz(r);
                let k2yz = w.y.k2[iy] + w.z.k2[iz];
                for ix in 0..nxh {
                    let k2 = w.x.k2[ix] + k2yz;
                    let p = rows[0][ix];
                    rows[0][ix] =
                        (p - (gh[r * nxh + ix] - p * s) * dt) / (1.0 + dt * (s + xi2 * k2));
                }
            });
            self.transform.inverse(&self.psi_hat, &mut self.psi);
            it += 1;
        }
        if it == max_iterations {
            residual = self.residual();
        }
        if residual < tolerance {
            Ok(Relaxation {
                iterations: it,
                residual,
            })
        } else {
            Err(CahnHilliardError::NotConverged {
                iterations: it,
                residual,
                tolerance,
            })
        }
    }

    /// max |μ_ψ| / e0.
    fn residual(&mut self) -> f64 {
        let e0 = self.cfg.e0;
        self.chemical_potential();
        crate::parallel::max_abs(&self.mu) / e0
    }
}
