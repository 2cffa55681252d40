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
use crate::metrics::{lookup, Metric};

/// Metric names this module computes.
pub const CAPILLARY_METRICS: &[&str] = &["surface_tension", "contact_angle_deg"];

fn with_reference(value: f64, reference: f64, source: &str) -> Metric {
    Metric::with_reference(value, reference, source)
}

/// The capillary metric `name` from the last step's `diagnostics` and the configured
/// `derived` numbers, or what is missing.
pub fn capillary_metric(
    name: &str,
    diagnostics: &[(String, f64)],
    derived: &[(String, f64)],
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
        let m = capillary_metric("surface_tension", &d, &c).unwrap();
        assert_eq!(m.value, 9.0 / 96.0);
        assert_eq!(m.reference, Some(0.1));
        assert!((m.relative_error.unwrap() - (0.1 - 0.09375) / 0.1).abs() < 1e-15);
        let e = capillary_metric("surface_tension", &d, &c[1..]).unwrap_err();
        assert!(e.contains("fluid.binary.interface_area"), "{e}");
        let e = capillary_metric("surface_tension", &[], &c).unwrap_err();
        assert!(e.contains("free_energy"), "{e}");
    }

    #[test]
    fn contact_angle_against_the_wall_equilibria() {
        let d = list(&[("contact_angle_deg", 60.0), ("bead_height", 10.0)]);
        let c = list(&[("fibre.0.contact_angle_reference_deg", 62.0)]);
        let m = capillary_metric("contact_angle_deg", &d, &c).unwrap();
        assert_eq!(m.value, 60.0);
        assert!((m.relative_error.unwrap() - 2.0 / 62.0).abs() < 1e-15);
        assert_eq!(m.extra.get("bead_height"), Some(&10.0));
        let e = capillary_metric("contact_angle_deg", &d, &[]).unwrap_err();
        assert!(e.contains("fibre.0.contact_angle_reference_deg"), "{e}");
        assert!(capillary_metric("drag_ratio", &d, &c).is_err());
    }
}
