//! Numbers a binary-fluid scene reports when configured ("derived" in the summary): σ, the
//! affinities, the dimensionless numbers of L2020 eqs. 39–42 as far as the scene defines
//! them, and the contact-angle reference of L2020 eq. 44 for a bead at a flat interface.
//!
//! Scales (L2020 section 3): L0 = Δ = 1 (the grid spacing), ρ0 = `fluid.density`,
//! η0 = `fluid.viscosity`, σ0 = e0 L0 (not σ_AB = (2√2/3) σ0 ξ), D0 = e0 M, and U0 the
//! "arbitrarily set" reference velocity: `fluid.binary.velocity_scale`, else the largest
//! wall speed; without either, Re, We and Pe are not reported. Ec = k0 / σ0 with
//! k0 = π r_b E / 2 (eq. 11) per fibre that gives `youngs_modulus`.
use super::scene::{BinaryConfig, InitialPsi};
use crate::cahn_hilliard::{contact_angle, psi_star, WallProblem};
use crate::config::FluidConfig;
use crate::grid::Grid;
use std::f64::consts::PI;

/// The derived numbers of `[fluid.binary]` `b` in scene `cfg` on `grid`.
pub fn numbers(cfg: &FluidConfig, b: &BinaryConfig, grid: Grid) -> Vec<(String, f64)> {
    let e0 = b.ch.e0;
    let d0 = b.ch.diffusivity();
    let sigma0 = e0; // σ0 = e0 L0, L0 = 1.
    let mut out = vec![
        ("fluid.binary.xi".to_string(), b.ch.xi),
        ("fluid.binary.e0".to_string(), e0),
        ("fluid.binary.mobility".to_string(), b.ch.mobility),
        ("fluid.binary.diffusivity".to_string(), d0),
        ("fluid.binary.sigma".to_string(), b.sigma()),
    ];
    if let Some(u0) = b.velocity_scale {
        out.push(("fluid.binary.velocity_scale".into(), u0));
        // Eqs. 39–41 with L0 = 1.
        out.push((
            "fluid.binary.reynolds".into(),
            cfg.density * u0 / cfg.viscosity,
        ));
        out.push(("fluid.binary.weber".into(), cfg.density * u0 * u0 / sigma0));
        out.push(("fluid.binary.peclet".into(), u0 / d0));
    }
    for (n, f) in cfg.fibres.iter().enumerate() {
        out.push((format!("fibre.{n}.psi_star"), psi_star(f.affinity)));
        if let Some(e) = f.youngs_modulus {
            // Eq. 42 with k0 = π r_b E / 2 (eq. 11).
            out.push((
                format!("fibre.{n}.elastocapillary"),
                PI * f.bead_radius * e / 2.0 / sigma0,
            ));
        }
    }
    if cfg.walls.is_some() {
        out.push(("walls.psi_star".into(), psi_star(b.wall_affinity)));
    }
    if let InitialPsi::Flat { axis, .. } = b.initial {
        // Two interfaces close the periodic slab: area 2 × the cross-section.
        let n = grid.sizes();
        let cross: usize = (0..grid.dims)
            .filter(|&c| c != axis)
            .map(|c| n[c])
            .product();
        out.push(("fluid.binary.interface_area".into(), 2.0 * cross as f64));
        // The 1D wall equilibria (L2020 Fig. 4, eq. 44) assume one ξ for the solid profile
        // and the phase field, as L2020 does; with two different ξ there is no reference.
        if let Some(f) = cfg.fibres.first() {
            if (cfg.xi - b.ch.xi).abs() <= 1e-12 * b.ch.xi {
                let p = WallProblem::new(b.ch.xi, cfg.xi_cutoff, e0);
                if let Ok(a) = contact_angle(&p, f.affinity) {
                    out.push((
                        "fibre.0.contact_angle_reference_deg".into(),
                        a.theta_a_degrees,
                    ));
                }
            }
        }
    }
    out
}
