//! Numbers a binary-fluid scene reports when configured ("derived" in the summary): σ, the
//! affinities, the dimensionless numbers of L2020 eqs. 39–42 as far as the scene defines
//! them, the contact-angle reference of L2020 eq. 44 for a bead at a flat interface, and the
//! eq. 45 radius of an initial droplet (`fluid.binary.initial_droplet_radius`).
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

/// Below this interface width (grid spacings) the phase field's surface tension is off.
pub const UNRESOLVED_XI: f64 = 0.75;

/// Advice on `[fluid.binary]` `b`: an interface narrower than [`UNRESOLVED_XI`] grid
/// spacings is not resolved by the grid, and the surface tension it carries is not L2020's
/// sigma_AB = (2 sqrt 2 / 3) e0 xi (measured with `configs/capillary/laplace_2d.toml`,
/// R = 16: the Laplace pressure jump within 2.5 % of sigma / R for xi from 0.75 to 3, 16 %
/// low at 0.25 and 0.5; docs/validation/capillary.md).
pub fn notes(b: &BinaryConfig) -> Vec<String> {
    let xi = b.ch.xi;
    if xi < UNRESOLVED_XI {
        vec![format!(
            "fluid-node: fluid.binary.xi = {xi} grid spacings does not resolve the interface: \
             below {UNRESOLVED_XI} the surface tension departs from sigma_AB = (2 sqrt 2 / 3) \
             e0 xi (the Laplace pressure of a droplet was 16 % low at xi = 0.25 and 0.5, within \
             2.5 % from 0.75 to 3; docs/validation/capillary.md); use xi >= 1"
        )]
    } else {
        Vec::new()
    }
}

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
    if let Some(r) = initial_droplet_radius(b, grid) {
        out.push(("fluid.binary.initial_droplet_radius".into(), r));
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

/// The equivalent radius of an initial droplet or half-droplet by L2020 eq. 45,
/// π R² = ∫_{ψ>0.5} ψ dx (2D; in 3D the sphere of the same integral, 4/3 π R³), on the
/// initial ψ (the fluid inside counted positive, so a droplet of B works too). It needs
/// the field because the tanh edge counts: for a disk of radius a, R is a little below a.
/// None for a flat initial interface.
pub fn initial_droplet_radius(b: &BinaryConfig, grid: Grid) -> Option<f64> {
    let sign = match b.initial {
        InitialPsi::Droplet { inside, .. } | InitialPsi::HalfDroplet { inside, .. } => inside.psi(),
        InitialPsi::Flat { .. } => return None,
    };
    let psi = super::initial_psi(b, grid).ok()?;
    let integral: f64 = psi.iter().map(|p| sign * p).filter(|&p| p > 0.5).sum();
    Some(if grid.dims == 2 {
        (integral / PI).sqrt()
    } else {
        (0.75 * integral / PI).cbrt()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. 45 counts ψ only where ψ > 0.5, so across a flat tanh edge of width w = √2 ξ it
    /// misses δ = w (atanh 0.5 + ln(4/3)) = 0.837 w of a sharp edge (∫ from 0.549 w of
    /// tanh(s/w) ds = L - 0.549 w - w ln(1 + e^{-1.099})). A disk of radius a has
    /// R ≈ a - δ; a half-disk R² ≈ a²/2 - (π + 2) a δ / π (its perimeter times δ).
    #[test]
    fn eq45_radius_of_a_disk_and_a_half_disk() {
        use crate::cahn_hilliard::{CahnHilliardConfig, Fluid, Scheme};
        let ch = CahnHilliardConfig {
            xi: 2.0,
            e0: 0.1,
            mobility: 1.0,
            dt: 0.5,
            stabilisation: 3.0,
            scheme: Scheme::SemiImplicit,
        };
        let grid = Grid::new(2, [160, 160, 1]);
        let cfg = |initial| BinaryConfig {
            ch: ch.clone(),
            velocity_scale: None,
            wall_affinity: 0.0,
            initial,
        };
        let disk = cfg(InitialPsi::Droplet {
            centre: [80.0, 80.0, 0.0],
            radius: 40.0,
            inside: Fluid::A,
        });
        let delta = 2f64.sqrt() * 2.0 * (0.5f64.atanh() + (4.0f64 / 3.0).ln());
        let r = initial_droplet_radius(&disk, grid).unwrap();
        assert!((r - (40.0 - delta)).abs() < 0.1, "{r} vs {}", 40.0 - delta);
        let half = cfg(InitialPsi::HalfDroplet {
            centre: [80.0, 40.0, 0.0],
            normal: [0.0, 1.0, 0.0],
            radius: 60.0,
            inside: Fluid::B,
        });
        let r = initial_droplet_radius(&half, grid).unwrap();
        let expect = (1800.0 - (PI + 2.0) * 60.0 * delta / PI).sqrt();
        assert!((r - expect).abs() < 0.3, "{r} vs {expect}");
    }
}
