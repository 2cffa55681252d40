//! The isotropic pressure of the binary fluid (a diagnostic for the Laplace law).
//!
//! The capillary force of L2020 eq. 33, `F = -ψ∇μ_ψ - φ∇μ_φ`, is minus the divergence of
//! the thermodynamic stress `P = p_t I + e0 ξ² ∇ψ ⊗ ∇ψ` with the isotropic part
//! `p_t = ψ μ_ψ + φ μ_φ - e0 f` (f of eq. 28, gradient term included; the identity holds
//! for a uniform ψ*). The flow solver's own pressure `P_s` removes the gradient part of F
//! (projection, eq. 34); for a fluid at rest, or in the Stokes steady state of its
//! parasitic currents, `∇²P_s = ∇·F`. The mechanical pressure is `p = P_s + p_t`: in a bulk
//! phase (∇ψ = 0, P isotropic) it is the pressure a sharp-interface model would have, and
//! its jump across a droplet's surface is the Laplace pressure. At equilibrium μ_ψ = μ0 is
//! uniform, F = 0, P_s is uniform and `Δp = Δ(ψ μ0 - e0 f_bulk) ≈ μ0 Δψ` (f_bulk is second
//! order in the bulk shift of ψ).
use super::{times_ik, CahnHilliard, CahnHilliardError};
use crate::parallel::grain;
use rayon::prelude::*;
use rustfft::num_complex::Complex64;

impl CahnHilliard {
    /// The mechanical pressure `p = P_s + ψ μ_ψ + φ μ_φ - e0 f` (see the module docs) at
    /// every node into `out`, up to a constant (P_s has zero mean); `force` is scratch for
    /// the capillary force, one field per dimension. Costs about two phase-field steps:
    /// meant for reporting, not for every step.
    pub fn pressure<V: AsMut<[f64]>>(
        &mut self,
        out: &mut [f64],
        force: &mut [V],
    ) -> Result<(), CahnHilliardError> {
        self.check_len("pressure", out.len())?;
        self.capillary_force(force)?;
        let g = self.grid;
        let nxh = g.nxh();
        // P̂_s = -i k·F̂ / k², accumulated in adv_hat (its k = 0 mode stays 0).
        self.adv_hat
            .par_iter_mut()
            .with_min_len(grain())
            .for_each(|v| *v = Complex64::default());
        for (c, f) in force.iter_mut().enumerate().take(g.dims) {
            self.transform.forward(f.as_mut(), &mut self.tmp_hat);
            let w = &self.waves;
            let fh = &self.tmp_hat;
            let mut fields = [&mut self.adv_hat[..]];
            crate::parallel::for_each_row(&mut fields, nxh, |r, rows| {
                let (iy, iz) = g.row_yz(r);
                let k2yz = w.y.k2[iy] + w.z.k2[iz];
                for ix in 0..nxh {
                    let k2 = w.x.k2[ix] + k2yz;
                    if k2 > 0.0 {
                        let k = [w.x.k[ix], w.y.k[iy], w.z.k[iz]][c];
                        rows[0][ix] -= times_ik(k, fh[r * nxh + ix]) / k2;
                    }
                }
            });
        }
        self.transform.inverse(&self.adv_hat, out);
        // The energy density into mu_phi (taken out to lend it), μ_ψ into mu.
        let mut density = std::mem::take(&mut self.mu_phi);
        let result = self.free_energy_density(&mut density);
        if result.is_ok() {
            self.chemical_potential();
            let e0 = self.cfg.e0;
            let (psi, phi, ps, mu) = (&self.psi, &self.phi, &self.psi_star, &self.mu);
            out.par_iter_mut()
                .zip(density.par_iter())
                .enumerate()
                .with_min_len(grain())
                .for_each(|(i, (o, f))| {
                    let d = psi[i] - ps[i];
                    // ψ μ_ψ + φ μ_φ - e0 f, with φ μ_φ = 3 e0 φ² (ψ - ψ*)².
                    *o += psi[i] * mu[i] + 3.0 * e0 * phi[i] * phi[i] * d * d - f;
                });
        }
        self.mu_phi = density;
        result
    }
}
