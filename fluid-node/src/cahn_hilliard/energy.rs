//! The discrete free energy (L2020 eqs. 27–30): total by term and density per node.
use super::{CahnHilliard, CahnHilliardError};
use crate::parallel::{for_each_row, grain, ordered_sum, per_row};
use rayon::prelude::*;

/// The free energy split by term, in units of e0 × volume (cell volume 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeEnergy {
    /// `e0 Σ (1/4)(1 - ψ²)²` (eq. 29).
    pub double_well: f64,
    /// `e0 Σ (3/2) φ² (ψ - ψ*)²` (eq. 30).
    pub solid: f64,
    /// `e0 (ξ²/2) Σ |∇ψ|²`, evaluated as `-(ξ²/2) Σ ψ ∇²ψ` with the spectral Laplacian so
    /// that μ_ψ is exactly the derivative of the total with respect to ψ at a node.
    pub gradient: f64,
    pub total: f64,
}

impl CahnHilliard {
    /// The discrete free energy F (L2020 eq. 27, cell volume 1), by term.
    pub fn free_energy(&mut self) -> FreeEnergy {
        let g = self.grid;
        let nxh = g.nxh();
        {
            let w = &self.waves;
            let ph = &self.psi_hat;
            let mut fields = [&mut self.tmp_hat[..]];
            for_each_row(&mut fields, nxh, |r, rows| {
                let (iy, iz) = g.row_yz(r);
                let k2yz = w.y.k2[iy] + w.z.k2[iz];
                for ix in 0..nxh {
                    rows[0][ix] = ph[r * nxh + ix] * (w.x.k2[ix] + k2yz);
                }
            });
        }
        // work = -∇²ψ
        self.transform.inverse(&self.tmp_hat, &mut self.work);
        let (psi, phi, ps, lap) = (&self.psi, &self.phi, &self.psi_star, &self.work);
        let nx = g.nx;
        let mut sums = [0.0; 3];
        for (t, sum) in sums.iter_mut().enumerate() {
            per_row(&mut self.partials, g.rows(), nx, |r| {
                let mut acc = 0.0;
                for i in r * nx..(r + 1) * nx {
                    let p = psi[i];
                    acc += match t {
                        0 => 0.25 * (1.0 - p * p) * (1.0 - p * p),
                        1 => 1.5 * phi[i] * phi[i] * (p - ps[i]) * (p - ps[i]),
                        _ => 0.5 * p * lap[i],
                    };
                }
                acc
            });
            *sum = ordered_sum(&self.partials);
        }
        let e0 = self.cfg.e0;
        let xi2 = self.cfg.xi * self.cfg.xi;
        let (double_well, solid, gradient) = (e0 * sums[0], e0 * sums[1], e0 * xi2 * sums[2]);
        FreeEnergy {
            double_well,
            solid,
            gradient,
            total: double_well + solid + gradient,
        }
    }

    /// The free energy density `e0 f` at every node (L2020 eq. 28) into `out`, with
    /// `|∇ψ|²` from spectral first derivatives (its sum differs from
    /// [`CahnHilliard::free_energy`]'s gradient term only through the Nyquist modes).
    pub fn free_energy_density(&mut self, out: &mut [f64]) -> Result<(), CahnHilliardError> {
        self.check_len("energy density", out.len())?;
        let g = self.grid;
        let (e0, xi2) = (self.cfg.e0, self.cfg.xi * self.cfg.xi);
        {
            let (psi, phi, ps) = (&self.psi, &self.phi, &self.psi_star);
            out.par_iter_mut()
                .enumerate()
                .with_min_len(grain())
                .for_each(|(i, o)| {
                    let p = psi[i];
                    *o = e0
                        * (0.25 * (1.0 - p * p) * (1.0 - p * p)
                            + 1.5 * phi[i] * phi[i] * (p - ps[i]) * (p - ps[i]));
                });
        }
        for c in 0..g.dims {
            self.derivative_into_work(c, true);
            let work = &self.work;
            out.par_iter_mut()
                .zip(work.par_iter())
                .with_min_len(grain())
                .for_each(|(o, d)| *o += 0.5 * e0 * xi2 * d * d);
        }
        Ok(())
    }
}
