//! Time-step limits of the Cahn–Hilliard step, from a frozen-coefficient (linear) analysis of
//! one Fourier mode k, with `a = Δt D0 k²`, `D0 = e0 M`, and `g' = 3ψ² - 1 + 3φ²` the slope of
//! the bulk part of μ_ψ / e0 (the bulk curvature of f):
//!
//! - Semi-implicit ([`Scheme::SemiImplicit`]): the amplification factor is
//!   `(1 + a (S - g')) / (1 + a (S + ξ² k²))`. It is at most 1 whenever `g' + ξ² k² >= 0` (the
//!   only growth left is the physical spinodal growth inside interfaces) and at least -1 for
//!   every Δt and k when `2 S >= g'`. With `|ψ| <= `[`PSI_BOUND`] and `φ <= φ_max`,
//!   `g' <= 3 PSI_BOUND² - 1 + 3 φ_max²` ([`bulk_curvature_bound`]), so
//!   `S >= `[`min_stabilisation`] (2.815 for φ_max = 1) means no diffusive limit. A smaller S
//!   needs `a (c - ξ² k²) <= 2` with `c = g'_max - 2 S`, i.e.
//!   `Δt <= 2 / (D0 max_k k² (c - ξ² k²))`.
//! - Explicit ([`Scheme::Explicit`]): the factor `1 - a (g' + ξ² k²)` needs
//!   `Δt <= 2 / (D0 k²_max (g'_max + ξ² k²_max))`, with `k²_max` the largest `|k|²` of the
//!   grid (`π²` per even axis): the `ξ² k⁴` term makes it tiny.
//! - Advection (explicit Euler on the dealiased flux) adds `-i Δt u·k` to the numerator; with
//!   `2 S >= g'` the factor stays at most 1 when `(Δt u k)² <= 2 a (g' + ξ² k²)`, which holds
//!   for every k when `u² Δt <= 2 D0 g'`. About a bulk phase (ψ = ±1, `g' = 2`) this is
//!   `u_max² Δt <= 4 D0`. Besides, the advective CFL `u_max Δt <= `[`CFL_MAX`] (as for the flow
//!   solver) keeps the transport accurate.
use super::{CahnHilliardConfig, CahnHilliardError, Scheme};
use crate::grid::Grid;
use crate::stability::{TimeStepLimit, CFL_MAX};
use std::f64::consts::PI;

/// Bound on |ψ| assumed by the limits: the bulk values ±1 shifted by curvature (Gibbs–Thomson)
/// and by the undershoot of the profile near solids.
pub const PSI_BOUND: f64 = 1.1;

/// Upper bound of `g' = ∂²f_bulk/∂ψ² = 3ψ² - 1 + 3φ²` for `|ψ| <= PSI_BOUND`, `φ <= phi_max`.
pub fn bulk_curvature_bound(phi_max: f64) -> f64 {
    3.0 * PSI_BOUND * PSI_BOUND - 1.0 + 3.0 * phi_max * phi_max
}

/// Smallest stabilisation S for which the semi-implicit step has no diffusive limit.
pub fn min_stabilisation(phi_max: f64) -> f64 {
    0.5 * bulk_curvature_bound(phi_max)
}

/// Largest `|k|²` on the grid: the sum over the axes of the largest `(2π m / n)²`.
pub fn max_wavenumber_squared(grid: Grid) -> f64 {
    grid.sizes()
        .iter()
        .take(grid.dims)
        .map(|&n| {
            let k = 2.0 * PI * (n / 2) as f64 / n as f64;
            k * k
        })
        .sum()
}

/// The finite time-step limits of a phase field with configuration `cfg` on `grid`, for the
/// largest speed `u_max` of the advecting flow (0 without flow) and the largest solid
/// fraction `phi_max`.
pub fn time_step_limits(
    grid: Grid,
    cfg: &CahnHilliardConfig,
    u_max: f64,
    phi_max: f64,
) -> Vec<TimeStepLimit> {
    let d0 = cfg.diffusivity();
    let xi2 = cfg.xi * cfg.xi;
    let kmax = max_wavenumber_squared(grid);
    let gmax = bulk_curvature_bound(phi_max);
    let mut out = Vec::new();
    match cfg.scheme {
        Scheme::Explicit => out.push(TimeStepLimit {
            name: "explicit Cahn-Hilliard diffusion",
            dt_max: 2.0 / (d0 * kmax * (gmax + xi2 * kmax)),
            detail: format!(
                "dt D0 k2max (g'max + xi^2 k2max) <= 2 with D0 = e0 M = {d0}, k2max = {kmax:.4}, \
                 g'max = {gmax:.4}, xi = {}",
                cfg.xi
            ),
        }),
        Scheme::SemiImplicit => {
            let c = gmax - 2.0 * cfg.stabilisation;
            if c > 0.0 {
                let kstar = (c / (2.0 * xi2)).min(kmax);
                let worst = kstar * (c - xi2 * kstar);
                out.push(TimeStepLimit {
                    name: "Cahn-Hilliard stabilisation",
                    dt_max: 2.0 / (d0 * worst),
                    detail: format!(
                        "S = {} is below g'max / 2 = {:.4}: dt D0 k2 (g'max - 2 S - xi^2 k2) <= 2",
                        cfg.stabilisation,
                        gmax / 2.0
                    ),
                });
            }
        }
    }
    if u_max > 0.0 {
        out.push(TimeStepLimit {
            name: "phase-field advective CFL",
            dt_max: CFL_MAX / u_max,
            detail: format!("max|u| dt / dx <= {CFL_MAX} with max|u| = {u_max}, dx = 1"),
        });
        out.push(TimeStepLimit {
            name: "phase-field advection against Cahn-Hilliard damping",
            dt_max: 4.0 * d0 / (u_max * u_max),
            detail: format!("max|u|^2 dt <= 4 D0 with max|u| = {u_max}, D0 = e0 M = {d0}"),
        });
    }
    out
}

/// The smallest of [`time_step_limits`] (infinite when there is none).
pub fn max_stable_dt(grid: Grid, cfg: &CahnHilliardConfig, u_max: f64, phi_max: f64) -> f64 {
    time_step_limits(grid, cfg, u_max, phi_max)
        .iter()
        .fold(f64::INFINITY, |m, l| m.min(l.dt_max))
}

/// Refuse `cfg.dt` above any limit, naming it with the numbers; otherwise the limits.
pub fn check_time_step(
    grid: Grid,
    cfg: &CahnHilliardConfig,
    u_max: f64,
    phi_max: f64,
) -> Result<Vec<TimeStepLimit>, CahnHilliardError> {
    let all = time_step_limits(grid, cfg, u_max, phi_max);
    if let Some(l) = all.iter().find(|l| cfg.dt > l.dt_max) {
        return Err(CahnHilliardError::TimeStep {
            name: l.name,
            dt: cfg.dt,
            dt_max: l.dt_max,
            detail: l.detail.clone(),
        });
    }
    Ok(all)
}
