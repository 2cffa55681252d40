//! Ternary Cahn–Hilliard phase field of L2020 (sections 2.4–2.5) on a periodic grid of
//! spacing 1, 2D or 3D, any size.
//!
//! Free energy (L2020 eqs. 27–30), with `e0 = kB T0 / v0` the energy density scale:
//!
//! ```text
//! F = e0 ∫ f,   f = (1/4)(1 - ψ²)² + (3/2) φ² (ψ - ψ*)² + (ξ²/2) |∇ψ|²
//! μ_ψ = δF/δψ = e0 [ψ³ - ψ + 3 φ² (ψ - ψ*) - ξ² ∇²ψ]
//! μ_φ = ∂F/∂φ = e0 3 φ (ψ - ψ*)²
//! ```
//!
//! ψ = +1 is fluid A, ψ = -1 fluid B; φ is the solid fraction of the beads (eq. 26), a field
//! the caller fills ([`CahnHilliard::phi_mut`]), already normalised to at most 1 where
//! profiles overlap. The affinity ψ* (eq. 31, from the bead's ψ0 by [`psi_star`]) is a
//! per-node field too ([`CahnHilliard::psi_star_mut`]) so that beads of different fibres may
//! differ: where profiles of different affinities overlap the caller stores the φ-weighted
//! mean `Σ φ_i ψ*_i / Σ φ_i`; away from solids its value is irrelevant (it is multiplied by
//! φ²). μ_φ is the partial derivative at fixed ψ*; a spatially varying ψ* would add a force
//! `-(∂f/∂ψ*) ∇ψ*` that is not included (it vanishes for uniform affinity).
//!
//! Transport (L2020 eq. 32) in conservative form, `∂ψ/∂t + ∇·(u ψ) = M ∇² μ_ψ` (equal to
//! eq. 32 for the divergence-free u of eq. 33), with `D0 = e0 M` (eq. 41). One step, per
//! Fourier mode k (see [`Scheme`]):
//!
//! ```text
//! ψ̂ⁿ⁺¹ [1 + a (S + ξ² k²)] = ψ̂ⁿ - Δt (∇·(u ψⁿ))^ - a [ĝ(ψⁿ) - S ψ̂ⁿ],   a = Δt D0 k²
//! ```
//!
//! with `g = ψ³ - ψ + 3 φ² (ψ - ψ*)` the bulk part of μ_ψ / e0. The `ξ² ∇⁴` term is implicit
//! and the linear stabilisation `S` (added and subtracted, REFERENCE.md section 6) keeps the
//! explicit bulk part stable (limits in [`limits`]). Both the advection term (`-i k·` of a
//! flux) and the diffusion term (`k²`) vanish at k = 0, so the mean of ψ is the untouched
//! k = 0 coefficient of the spectral state: it is conserved exactly. The advection flux is
//! dealiased by the 2/3 rule as in the flow solver; the bulk term is not (the interface is
//! resolved over several nodes).
//!
//! Accuracy: first order in Δt. Besides explicit Euler for advection, evaluating the `S` and
//! `ξ² k²` terms at the new level adds `a (S + ξ² k²) (ψ̂ⁿ⁺¹ - ψ̂ⁿ)`, an error of order
//! `Δt D0 (S + ξ² k²) k² ∂ψ/∂t` that vanishes at equilibrium (the fixed point of the step is
//! exactly μ_ψ uniform, whatever Δt and S).
//!
//! The spectral ψ̂ is the state; the real ψ is its inverse transform. Everything is allocated
//! in [`CahnHilliard::new`]; a step allocates nothing.
use crate::grid::{Grid, Wavenumbers};
use crate::parallel::{for_each_row, grain, per_row};
use crate::transform::{Modes, Transform};
use rayon::prelude::*;
use rustfft::num_complex::Complex64;

mod energy;
mod equilibrium;
mod initial;
pub mod limits;
mod params;
mod pressure;
#[cfg(test)]
mod tests;

pub use energy::FreeEnergy;
pub use equilibrium::{
    contact_angle, wall_equilibrium, ContactAngle, WallEquilibrium, WallProblem,
};
pub use initial::{droplet, half_droplet, stratified};
pub use limits::{check_time_step, max_stable_dt, time_step_limits};
pub use params::{
    mobility_from_peclet, psi_star, sigma_ab, CahnHilliardConfig, CahnHilliardError, Fluid, Scheme,
};

/// Largest |ψ| a step accepts before reporting divergence (the physical range is about
/// [-1.1, 1.1]).
pub const DIVERGENCE_BOUND: f64 = 10.0;

/// `dst := i k_c src`, the spectrum of ∂_c of the field whose spectrum is `src`.
fn spectral_derivative(
    g: Grid,
    w: &Wavenumbers,
    c: usize,
    src: &[Complex64],
    dst: &mut [Complex64],
) {
    let nxh = g.nxh();
    for_each_row(&mut [dst], nxh, |r, rows| {
        let (iy, iz) = g.row_yz(r);
        for ix in 0..nxh {
            let k = [w.x.k[ix], w.y.k[iy], w.z.k[iz]][c];
            rows[0][ix] = times_ik(k, src[r * nxh + ix]);
        }
    });
}

/// `out := ĥ` with `h = h(ψ, φ, ψ*)` at every node (`fields` = [ψ, φ, ψ*]), formed row by row
/// as the transform takes it, so h is never stored.
fn transform_pointwise(
    t: &mut Transform,
    out: &mut [Complex64],
    fields: [&[f64]; 3],
    h: impl Fn(f64, f64, f64) -> f64 + Sync,
) {
    let nx = t.grid().nx;
    let [psi, phi, ps] = fields;
    t.forward_rows(
        &mut [out],
        |_, r, row_out| {
            let row = r * nx..(r + 1) * nx;
            let (p, f, s) = (&psi[row.clone()], &phi[row.clone()], &ps[row]);
            for (i, o) in row_out.iter_mut().enumerate() {
                *o = h(p[i], f[i], s[i]);
            }
        },
        Modes::All,
    );
}

/// μ_φ = 3 e0 φ (ψ - ψ*)² at a node (see [`CahnHilliard::solid_chemical_potential`]).
#[inline]
fn mu_phi(e0: f64, psi: f64, phi: f64, ps: f64) -> f64 {
    3.0 * e0 * phi * (psi - ps) * (psi - ps)
}

/// Bulk part of μ_ψ / e0: `g = ψ³ - ψ + 3 φ² (ψ - ψ*)` (L2020 eqs. 29–30).
#[inline]
fn bulk_derivative(psi: f64, phi: f64, ps: f64) -> f64 {
    psi * psi * psi - psi + 3.0 * phi * phi * (psi - ps)
}

/// Result of [`CahnHilliard::relax_non_conserved`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relaxation {
    pub iterations: usize,
    /// Final max |μ_ψ| / e0.
    pub residual: f64,
}

/// The phase-field solver: fields, plans and scratch for one grid.
pub struct CahnHilliard {
    grid: Grid,
    cfg: CahnHilliardConfig,
    waves: Wavenumbers,
    transform: Transform,
    /// Real order parameter (the inverse transform of `psi_hat`).
    psi: Vec<f64>,
    /// Spectral order parameter (the state).
    psi_hat: Vec<Complex64>,
    phi: Vec<f64>,
    psi_star: Vec<f64>,
    mu: Vec<f64>,
    mu_phi: Vec<f64>,
    work: Vec<f64>,
    g_hat: Vec<Complex64>,
    /// The advection term; in 2D the transformed flux `(u_y ψ)^` it is formed from (with
    /// `(u_x ψ)^` in `tmp_hat`).
    adv_hat: Vec<Complex64>,
    tmp_hat: Vec<Complex64>,
    partials: Vec<f64>,
    steps: u64,
    /// Stored kx that the 2/3 rule keeps (a prefix).
    kept_kx: usize,
}

/// `i k p`.
#[inline]
fn times_ik(k: f64, p: Complex64) -> Complex64 {
    Complex64::new(-k * p.im, k * p.re)
}

impl CahnHilliard {
    /// Uniform fluid B (ψ = -1), no solid (φ = 0, ψ* = 0) on `grid`. Plans every transform and
    /// allocates every buffer.
    pub fn new(grid: Grid, cfg: CahnHilliardConfig) -> Result<Self, CahnHilliardError> {
        let sizes = grid.sizes();
        if !(grid.dims == 2 || grid.dims == 3) {
            return Err(CahnHilliardError::InvalidGrid {
                dims: grid.dims,
                sizes,
                reason: "dimensions must be 2 or 3",
            });
        }
        if sizes.iter().take(grid.dims).any(|&n| n == 0) || (grid.dims == 2 && grid.nz != 1) {
            return Err(CahnHilliardError::InvalidGrid {
                dims: grid.dims,
                sizes,
                reason: "every axis needs at least one node (and nz = 1 in 2D)",
            });
        }
        cfg.validate()?;
        let (n, m) = (grid.cells(), grid.modes());
        let waves = Wavenumbers::new(grid);
        let kept_kx = waves.x.keep.iter().take_while(|&&k| k).count();
        let mut s = Self {
            grid,
            cfg,
            waves,
            // 2D: the force's two components share their inverse transforms' passes.
            transform: Transform::with_batch(grid, 0, if grid.dims == 2 { 2 } else { 1 }),
            psi: vec![-1.0; n],
            psi_hat: vec![Complex64::default(); m],
            phi: vec![0.0; n],
            psi_star: vec![0.0; n],
            mu: vec![0.0; n],
            mu_phi: vec![0.0; n],
            work: vec![0.0; n],
            g_hat: vec![Complex64::default(); m],
            adv_hat: vec![Complex64::default(); m],
            tmp_hat: vec![Complex64::default(); m],
            partials: Vec::with_capacity(grid.rows()),
            steps: 0,
            kept_kx,
        };
        s.transform.forward(&s.psi, &mut s.psi_hat);
        Ok(s)
    }

    pub fn grid(&self) -> Grid {
        self.grid
    }

    pub fn config(&self) -> &CahnHilliardConfig {
        &self.cfg
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Change the time step (checked positive and finite).
    pub fn set_dt(&mut self, dt: f64) -> Result<(), CahnHilliardError> {
        let mut cfg = self.cfg.clone();
        cfg.dt = dt;
        cfg.validate()?;
        self.cfg = cfg;
        Ok(())
    }

    /// Real order parameter ψ (x fastest, see [`Grid::index`]).
    pub fn psi(&self) -> &[f64] {
        &self.psi
    }

    /// Spectral state ψ̂ (unnormalised forward transform of ψ).
    pub fn psi_spectrum(&self) -> &[Complex64] {
        &self.psi_hat
    }

    /// Mean of ψ from the spectral state (the conserved quantity).
    pub fn mean_psi(&self) -> f64 {
        self.psi_hat[0].re / self.grid.cells() as f64
    }

    /// Replace ψ by `psi` (one value per node).
    pub fn set_psi(&mut self, psi: &[f64]) -> Result<(), CahnHilliardError> {
        self.check_len("psi", psi.len())?;
        self.psi.copy_from_slice(psi);
        self.transform.forward(&self.psi, &mut self.psi_hat);
        // The real field is the inverse of the state, also for modes a real grid cannot hold
        // (e.g. the imaginary part of an even axis' Nyquist mode).
        self.transform.inverse(&self.psi_hat, &mut self.psi);
        Ok(())
    }

    /// Replace the spectral state (e.g. from a checkpoint) and rebuild the real ψ.
    pub fn set_psi_spectrum(&mut self, spectrum: &[Complex64]) -> Result<(), CahnHilliardError> {
        if spectrum.len() != self.grid.modes() {
            return Err(CahnHilliardError::FieldLength {
                name: "psi spectrum",
                expected: self.grid.modes(),
                got: spectrum.len(),
            });
        }
        self.psi_hat.copy_from_slice(spectrum);
        self.transform.inverse(&self.psi_hat, &mut self.psi);
        Ok(())
    }

    /// Solid fraction φ (L2020 eq. 26), 0 by default.
    pub fn phi(&self) -> &[f64] {
        &self.phi
    }

    /// The solid fraction for the caller to fill (values in [0, 1]).
    pub fn phi_mut(&mut self) -> &mut [f64] {
        &mut self.phi
    }

    /// Affinity field ψ* (eq. 31; see the module docs for overlapping beads).
    pub fn psi_star_field(&self) -> &[f64] {
        &self.psi_star
    }

    pub fn psi_star_mut(&mut self) -> &mut [f64] {
        &mut self.psi_star
    }

    /// ψ* := [`psi_star`]`(psi0)` everywhere (all beads of one affinity).
    pub fn set_uniform_affinity(&mut self, psi0: f64) {
        self.psi_star.fill(psi_star(psi0));
    }

    fn check_len(&self, name: &'static str, got: usize) -> Result<(), CahnHilliardError> {
        let expected = self.grid.cells();
        if got == expected {
            Ok(())
        } else {
            Err(CahnHilliardError::FieldLength {
                name,
                expected,
                got,
            })
        }
    }

    /// `g_hat := ĝ`, g = g(ψ, φ, ψ*) formed row by row as the transform takes it.
    fn bulk_transform(&mut self) {
        let fields = [&self.psi[..], &self.phi, &self.psi_star];
        transform_pointwise(
            &mut self.transform,
            &mut self.g_hat,
            fields,
            bulk_derivative,
        );
    }

    /// The transformed fluxes `(u_c ψ)^`, finished only on the modes the 2/3 rule keeps.
    /// 2D: both go to `tmp_hat` and `adv_hat` in one batch, and the step forms
    /// `-(∇·(u ψ))^` from them. 3D: one flux at a time, `adv_hat := -(∇·(u ψ))^` (dealiased).
    fn advection<V: AsRef<[f64]>>(&mut self, velocity: &[V]) {
        let g = self.grid;
        let (nx, nxh) = (g.nx, g.nxh());
        let band = Modes::Band {
            kx: self.kept_kx,
            ky: &self.waves.y.keep,
        };
        let psi = &self.psi;
        let flux = |u: &[f64], r: usize, out: &mut [f64]| {
            let row = r * nx..(r + 1) * nx;
            for ((o, a), b) in out.iter_mut().zip(&u[row.clone()]).zip(&psi[row]) {
                *o = a * b;
            }
        };
        if g.dims == 2 {
            let u = [velocity[0].as_ref(), velocity[1].as_ref()];
            self.transform.forward_rows(
                &mut [&mut self.tmp_hat[..], &mut self.adv_hat[..]],
                |c, r, out| flux(u[c], r, out),
                band,
            );
            return;
        }
        self.adv_hat
            .par_iter_mut()
            .with_min_len(grain())
            .for_each(|v| *v = Complex64::default());
        for (c, u) in velocity.iter().enumerate().take(g.dims) {
            let u = u.as_ref();
            self.transform.forward_rows(
                &mut [&mut self.tmp_hat[..]],
                |_, r, out| flux(u, r, out),
                band,
            );
            let w = &self.waves;
            let flux = &self.tmp_hat;
            let mut fields = [&mut self.adv_hat[..]];
            for_each_row(&mut fields, nxh, |r, rows| {
                let (iy, iz) = g.row_yz(r);
                let keep_yz = w.y.keep[iy] && w.z.keep[iz];
                for ix in 0..nxh {
                    if keep_yz && w.x.keep[ix] {
                        let k = [w.x.k[ix], w.y.k[iy], w.z.k[iz]][c];
                        rows[0][ix] -= times_ik(k, flux[r * nxh + ix]);
                    }
                }
            });
        }
    }

    /// One step of L2020 eq. 32 without flow.
    pub fn step(&mut self) -> Result<(), CahnHilliardError> {
        self.step_inner::<&[f64]>(None)
    }

    /// One step of L2020 eq. 32 advected by `velocity` (one real field per component, at
    /// least `dims` of them; divergence-free for eq. 32 and the conservative form to agree).
    pub fn step_advected<V: AsRef<[f64]>>(
        &mut self,
        velocity: &[V],
    ) -> Result<(), CahnHilliardError> {
        if velocity.len() < self.grid.dims {
            return Err(CahnHilliardError::FieldLength {
                name: "velocity components",
                expected: self.grid.dims,
                got: velocity.len(),
            });
        }
        for u in velocity.iter().take(self.grid.dims) {
            self.check_len("velocity component", u.as_ref().len())?;
        }
        self.step_inner(Some(velocity))
    }

    fn step_inner<V: AsRef<[f64]>>(
        &mut self,
        velocity: Option<&[V]>,
    ) -> Result<(), CahnHilliardError> {
        self.bulk_transform();
        if let Some(u) = velocity {
            self.advection(u);
        }
        let advect = velocity.is_some();
        let g = self.grid;
        let nxh = g.nxh();
        let w = &self.waves;
        let (dt, d0) = (self.cfg.dt, self.cfg.diffusivity());
        let (xi2, s) = (self.cfg.xi * self.cfg.xi, self.cfg.stabilisation);
        let explicit = self.cfg.scheme == Scheme::Explicit;
        let (gh, adv, flux_x) = (&self.g_hat, &self.adv_hat, &self.tmp_hat);
        let two_d = g.dims == 2;
        let mut fields = [&mut self.psi_hat[..]];
        for_each_row(&mut fields, nxh, |r, rows| {
            let (iy, iz) = g.row_yz(r);
            let k2yz = w.y.k2[iy] + w.z.k2[iz];
            let keep_y = w.y.keep[iy];
            for (ix, v) in rows[0].iter_mut().enumerate() {
                let i = r * nxh + ix;
                let k2 = w.x.k2[ix] + k2yz;
                let a = dt * d0 * k2;
                let p = *v;
                let mut num = p;
                if advect {
                    let adv_i = if !two_d {
                        adv[i]
                    } else if keep_y && w.x.keep[ix] {
                        // -(i k_x F̂_x) - (i k_y F̂_y), as the 3D path sums it.
                        let mut s = Complex64::default();
                        s -= times_ik(w.x.k[ix], flux_x[i]);
                        s -= times_ik(w.y.k[iy], adv[i]);
                        s
                    } else {
                        Complex64::default()
                    };
                    num += adv_i * dt;
                }
                *v = if explicit {
                    num - (gh[i] + p * (xi2 * k2)) * a
                } else {
                    (num - (gh[i] - p * s) * a) / (1.0 + a * (s + xi2 * k2))
                };
            }
        });
        self.transform.inverse(&self.psi_hat, &mut self.psi);
        self.steps += 1;
        let max_abs = self.max_abs_psi();
        if max_abs.is_nan() || max_abs > DIVERGENCE_BOUND {
            return Err(CahnHilliardError::Diverged {
                step: self.steps,
                max_abs,
            });
        }
        Ok(())
    }

    /// Largest |ψ| (NaN if any value is NaN).
    pub fn max_abs_psi(&mut self) -> f64 {
        let g = self.grid;
        let psi = &self.psi;
        per_row(&mut self.partials, g.rows(), g.nx, |r| {
            crate::parallel::max_abs(&psi[r * g.nx..(r + 1) * g.nx])
        });
        self.partials.iter().fold(0.0f64, |a, &b| {
            if a.is_nan() || b.is_nan() {
                f64::NAN
            } else {
                a.max(b)
            }
        })
    }

    /// `tmp_hat := μ̂_ψ` (with e0).
    fn mu_spectrum(&mut self) {
        self.bulk_transform();
        let g = self.grid;
        let nxh = g.nxh();
        let w = &self.waves;
        let (xi2, e0) = (self.cfg.xi * self.cfg.xi, self.cfg.e0);
        let (gh, ph) = (&self.g_hat, &self.psi_hat);
        let mut fields = [&mut self.tmp_hat[..]];
        for_each_row(&mut fields, nxh, |r, rows| {
            let (iy, iz) = g.row_yz(r);
            let k2yz = w.y.k2[iy] + w.z.k2[iz];
            for (ix, v) in rows[0].iter_mut().enumerate() {
                let i = r * nxh + ix;
                let k2 = w.x.k2[ix] + k2yz;
                *v = (gh[i] + ph[i] * (xi2 * k2)) * e0;
            }
        });
    }

    /// μ_ψ = δF/δψ (e0 included) at every node.
    pub fn chemical_potential(&mut self) -> &[f64] {
        self.mu_spectrum();
        self.transform.inverse(&self.tmp_hat, &mut self.mu);
        &self.mu
    }

    /// μ_φ = ∂F/∂φ = 3 e0 φ (ψ - ψ*)² at every node (the partial derivative of the field's
    /// energy at fixed ψ*; the beads' own energy is not included).
    pub fn solid_chemical_potential(&mut self) -> &[f64] {
        self.fill_mu_phi();
        &self.mu_phi
    }

    fn fill_mu_phi(&mut self) {
        let e0 = self.cfg.e0;
        let (psi, phi, ps) = (&self.psi, &self.phi, &self.psi_star);
        self.mu_phi
            .par_iter_mut()
            .zip(psi.par_iter().zip(phi.par_iter().zip(ps.par_iter())))
            .with_min_len(grain())
            .for_each(|(m, (&p, (&f, &s)))| *m = mu_phi(e0, p, f, s));
    }

    /// `work := ∂_c` of `psi_hat` (`of_psi`) or of `tmp_hat`, by a spectral derivative
    /// through `g_hat`.
    fn derivative_into_work(&mut self, c: usize, of_psi: bool) {
        let g = self.grid;
        let w = &self.waves;
        let src = if of_psi { &self.psi_hat } else { &self.tmp_hat };
        spectral_derivative(g, w, c, src, &mut self.g_hat);
        self.transform.inverse(&self.g_hat, &mut self.work);
    }

    /// With `h` the spectral field in `tmp_hat`: `out[c] := -ψ ∂_c h`, or with `use_phi`
    /// `out[c] -= φ ∂_c h` (spectral derivatives). The products are formed row by row as the
    /// inverse transforms finish them; in 2D both components share one batch (the
    /// derivatives' spectra in `g_hat` and `adv_hat`).
    fn gradient_product(&mut self, out: &mut [&mut [f64]], use_phi: bool) {
        let g = self.grid;
        let (nx, nxh) = (g.nx, g.nxh());
        let weight = if use_phi { &self.phi } else { &self.psi };
        let combine = |_: usize, r: usize, dh: &[f64], o: &mut [f64]| {
            let a = &weight[r * nx..(r + 1) * nx];
            for i in 0..nx {
                if use_phi {
                    o[i] -= a[i] * dh[i];
                } else {
                    o[i] = -a[i] * dh[i];
                }
            }
        };
        let w = &self.waves;
        let src = &self.tmp_hat;
        if g.dims == 2 {
            let mut fields = [&mut self.g_hat[..], &mut self.adv_hat[..]];
            for_each_row(&mut fields, nxh, |r, rows| {
                let (iy, _) = g.row_yz(r);
                for ix in 0..nxh {
                    let h = src[r * nxh + ix];
                    rows[0][ix] = times_ik(w.x.k[ix], h);
                    rows[1][ix] = times_ik(w.y.k[iy], h);
                }
            });
            self.transform
                .inverse_combine(&[&self.g_hat, &self.adv_hat], &mut out[..2], combine);
            return;
        }
        for c in 0..g.dims {
            spectral_derivative(g, w, c, src, &mut self.g_hat);
            self.transform
                .inverse_combine(&[&self.g_hat], &mut out[c..c + 1], combine);
        }
    }

    /// Capillary force density on the fluid, `-ψ ∇μ_ψ - φ ∇μ_φ` (L2020 eqs. 33–34), with
    /// spectral gradients, into `out` (one component per dimension, overwritten). The φ term
    /// is skipped where there is no solid anywhere.
    pub fn capillary_force<V: AsMut<[f64]>>(
        &mut self,
        out: &mut [V],
    ) -> Result<(), CahnHilliardError> {
        let d = self.grid.dims;
        if out.len() < d {
            return Err(CahnHilliardError::FieldLength {
                name: "force components",
                expected: d,
                got: out.len(),
            });
        }
        for o in out.iter_mut().take(d) {
            self.check_len("force component", o.as_mut().len())?;
        }
        let mut it = out.iter_mut();
        let mut comps: [&mut [f64]; 3] =
            std::array::from_fn(|_| it.next().map_or(&mut [][..], |v| v.as_mut()));
        self.mu_spectrum();
        self.gradient_product(&mut comps[..d], false);
        if self.phi.par_iter().any(|&p| p != 0.0) {
            // μ_φ vanishes off the solids, and those rows are skipped.
            let e0 = self.cfg.e0;
            let fields = [&self.psi[..], &self.phi, &self.psi_star];
            transform_pointwise(&mut self.transform, &mut self.tmp_hat, fields, |p, f, s| {
                mu_phi(e0, p, f, s)
            });
            self.gradient_product(&mut comps[..d], true);
        }
        Ok(())
    }
}
