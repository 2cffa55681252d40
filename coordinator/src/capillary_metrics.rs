//! Observables of binary-fluid scenes (L2020 section 3.3), from the fluid node's
//! diagnostics of the last step and the numbers it derived when configured:
//!
//! - `surface_tension`: the excess free energy per interface area of a flat interface,
//!   `F / A` (diagnostic `free_energy`, derived `fluid.binary.interface_area`), against the
//!   analytic `σ_AB = (2√2/3) e0 ξ` (derived `fluid.binary.sigma`). Meaningful for a scene
//!   with a flat interface and no solids (F also holds the solids' energy).
//! - `contact_angle_deg`: the geometric contact angle of bead 0 through fluid A,
//!   `θ_A = acos(h / r_b)` with h the signed height of the bead centre above the flat
//!   interface towards A (diagnostic `contact_angle_deg`, which the fluid node computes from
//!   ψ away from the meniscus), against Young's law with the 1D wall equilibria,
//!   `cos θ_A = (σ_BS - σ_AS) / σ_AB` (derived `fibre.0.contact_angle_reference_deg`; L2020
//!   eq. 44 measures the same angle through B, 180° - θ_A).
//! - `laplace_pressure_jump`: the jump of the mechanical pressure across the surface of a
//!   droplet, inside minus outside (diagnostic `pressure_jump`, which the fluid node
//!   computes at reporting steps as `P_s + ψ μ_ψ + φ μ_φ - e0 f`, the projection pressure
//!   plus the isotropic thermodynamic pressure of L2020 eqs. 28 and 33, averaged over the
//!   bulk on either side), against the Laplace law σ_AB / R (2D) or 2 σ_AB / R (3D) with R
//!   the droplet's equimolar radius measured from ψ at the same step (diagnostic
//!   `droplet_radius`), not the initial one.
use crate::metrics::{lookup, Metric};

/// Metric names this module computes.
pub const CAPILLARY_METRICS: &[&str] = &[
    "surface_tension",
    "contact_angle_deg",
    "laplace_pressure_jump",
];

fn with_reference(value: f64, reference: f64, source: &str) -> Metric {
    Metric::with_reference(value, reference, source)
}

/// The capillary metric `name` from the last step's `diagnostics` and the configured
/// `derived` numbers of a scene of `dims` dimensions, or what is missing.
pub fn capillary_metric(
    name: &str,
    diagnostics: &[(String, f64)],
    derived: &[(String, f64)],
    dims: usize,
) -> Result<Metric, String> {
    let need = |list: &[(String, f64)], key: &str, what: &str| {
        lookup(list, key).ok_or_else(|| format!("metric `{name}` needs {what} (`{key}`)"))
    };
    match name {
        "surface_tension" => {
            let f = need(
                diagnostics,
                "free_energy",
                "a binary fluid ([fluid.binary]) whose node reports its free energy",
            )?;
            let area = need(
                derived,
                "fluid.binary.interface_area",
                "a flat initial interface (fluid.binary.initial = \"flat\")",
            )?;
            let sigma = need(derived, "fluid.binary.sigma", "a binary fluid")?;
            let mut m = with_reference(
                f / area,
                sigma,
                "sigma_AB = (2 sqrt 2 / 3) e0 xi, the excess of the flat tanh profile (L2020 section 3.3)",
            );
            m.extra.insert("free_energy".into(), f);
            m.extra.insert("interface_area".into(), area);
            Ok(m)
        }
        "contact_angle_deg" => {
            let theta = need(
                diagnostics,
                "contact_angle_deg",
                "a bead at a flat initial interface of a binary fluid",
            )?;
            let reference = need(
                derived,
                "fibre.0.contact_angle_reference_deg",
                "fluid.binary.xi equal to fluid.xi (the 1D wall equilibria use one xi)",
            )?;
            let mut m = with_reference(
                theta,
                reference,
                "Young's law cos theta_A = (sigma_BS - sigma_AS) / sigma_AB with the 1D wall \
                 equilibria (L2020 Fig. 4, eq. 44 through fluid A)",
            );
            if let Some(h) = lookup(diagnostics, "bead_height") {
                m.extra.insert("bead_height".into(), h);
            }
            Ok(m)
        }
        "laplace_pressure_jump" => {
            let what = "a droplet (fluid.binary.initial = \"droplet\") and a last step the \
                        fluid node reports on (the last of time.steps)";
            let jump = need(diagnostics, "pressure_jump", what)?;
            let radius = need(diagnostics, "droplet_radius", what)?;
            let sigma = need(derived, "fluid.binary.sigma", "a binary fluid")?;
            // Curvature of a circle (2D) or a sphere (3D).
            let curvature = (dims as f64 - 1.0) / radius;
            let mut m = with_reference(
                jump,
                sigma * curvature,
                "Laplace law, sigma_AB / R (2D) or 2 sigma_AB / R (3D), R the equimolar radius \
                 of the droplet measured from psi at the last step",
            );
            m.extra.insert("droplet_radius".into(), radius);
            if let Some(j) = lookup(diagnostics, "pressure_jump_mu") {
                m.extra.insert("pressure_jump_mu".into(), j);
            }
            Ok(m)
        }
        other => Err(format!("`{other}` is not a capillary metric")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn list(v: &[(&str, f64)]) -> Vec<(String, f64)> {
        v.iter().map(|(k, x)| (k.to_string(), *x)).collect()
    }

    #[test]
    fn surface_tension_is_the_excess_energy_per_area() {
        let d = list(&[("free_energy", 9.0), ("mean_psi", 0.0)]);
        let c = list(&[
            ("fluid.binary.interface_area", 96.0),
            ("fluid.binary.sigma", 0.1),
        ]);
        let m = capillary_metric("surface_tension", &d, &c, 2).unwrap();
        assert_eq!(m.value, 9.0 / 96.0);
        assert_eq!(m.reference, Some(0.1));
        assert!((m.relative_error.unwrap() - (0.1 - 0.09375) / 0.1).abs() < 1e-15);
        let e = capillary_metric("surface_tension", &d, &c[1..], 2).unwrap_err();
        assert!(e.contains("fluid.binary.interface_area"), "{e}");
        let e = capillary_metric("surface_tension", &[], &c, 2).unwrap_err();
        assert!(e.contains("free_energy"), "{e}");
    }

    #[test]
    fn contact_angle_against_the_wall_equilibria() {
        let d = list(&[("contact_angle_deg", 60.0), ("bead_height", 10.0)]);
        let c = list(&[("fibre.0.contact_angle_reference_deg", 62.0)]);
        let m = capillary_metric("contact_angle_deg", &d, &c, 2).unwrap();
        assert_eq!(m.value, 60.0);
        assert!((m.relative_error.unwrap() - 2.0 / 62.0).abs() < 1e-15);
        assert_eq!(m.extra.get("bead_height"), Some(&10.0));
        let e = capillary_metric("contact_angle_deg", &d, &[], 2).unwrap_err();
        assert!(e.contains("fibre.0.contact_angle_reference_deg"), "{e}");
        assert!(capillary_metric("drag_ratio", &d, &c, 2).is_err());
    }

    #[test]
    fn laplace_reference_is_sigma_times_the_curvature() {
        let d = list(&[
            ("pressure_jump", 0.02),
            ("droplet_radius", 10.0),
            ("pressure_jump_mu", 0.021),
        ]);
        let c = list(&[("fluid.binary.sigma", 0.2)]);
        let m2 = capillary_metric("laplace_pressure_jump", &d, &c, 2).unwrap();
        assert_eq!(m2.value, 0.02);
        assert!((m2.reference.unwrap() - 0.02).abs() < 1e-15);
        assert_eq!(m2.extra.get("droplet_radius"), Some(&10.0));
        let m3 = capillary_metric("laplace_pressure_jump", &d, &c, 3).unwrap();
        assert!((m3.reference.unwrap() - 0.04).abs() < 1e-15);
        let e = capillary_metric("laplace_pressure_jump", &d[1..], &c, 2).unwrap_err();
        assert!(e.contains("(`pressure_jump`)"), "{e}");
        let e = capillary_metric("laplace_pressure_jump", &d, &[], 3).unwrap_err();
        assert!(e.contains("fluid.binary.sigma"), "{e}");
    }
}
