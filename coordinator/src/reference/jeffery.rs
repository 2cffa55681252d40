//! Jeffery orbits of a rigid elongated body in simple shear (REFERENCE.md section 2;
//! L2020 appendix B).
//!
//! L2020 compares its chains with Jeffery's period `gamma T = 2 pi (e + 1/e)` (eq. B.1), the
//! chain of N_b beads standing for a cylinder of aspect ratio N_b whose equivalent ellipse
//! comes from Harris & Pittman (1975), `1.14 x^0.844`. That law gives the *ellipse's* aspect
//! ratio from the *cylinder's*, `e = 1.14 N_b^0.844`: a blunt cylinder turns like a less
//! elongated ellipse (Cox 1971), e.g. 5.17 for N_b = 6. REFERENCE.md section 2 tabulates the
//! law read the other way round, `N_b = 1.14 e^0.844` (e = 7.16 for N_b = 6), which makes the
//! chain turn like an ellipse *more* elongated than itself. The independent 2D check in S2023
//! (FPD, a rigid 10-bead chain fitted by Jeffery's law with r_c = 0.132, i.e. e = 7.6) agrees
//! with the first reading (7.98) and not with the second (13.1), so [`chain_period_gamma`] is
//! the first; [`chain_period_gamma_table`] reproduces REFERENCE.md's numbers for comparison.

/// gamma T of a full Jeffery period (a turn by 2 pi) of an ellipse of aspect ratio `e`
/// (L2020 eq. B.1).
fn ellipse_period_gamma(e: f64) -> f64 {
    2.0 * std::f64::consts::PI * (e + 1.0 / e)
}

/// Aspect ratio of the ellipse equivalent to a chain of `beads` touching beads (a cylinder
/// of aspect ratio N_b): Harris & Pittman, `e = 1.14 N_b^0.844`.
pub fn chain_equivalent_aspect_ratio(beads: usize) -> f64 {
    cylinder_equivalent_aspect_ratio(beads as f64)
}

/// Harris & Pittman's equivalent ellipse of a cylinder of aspect ratio `aspect`,
/// `e = 1.14 aspect^0.844`.
fn cylinder_equivalent_aspect_ratio(aspect: f64) -> f64 {
    1.14 * aspect.powf(0.844)
}

/// gamma T of a full Jeffery period for a cylinder of aspect ratio `aspect` (length over
/// width), with Harris & Pittman's equivalent ellipse `e = 1.14 aspect^0.844`: for a chain of
/// beads spaced apart, the cylinder that envelops it.
pub fn cylinder_period_gamma(aspect: f64) -> f64 {
    ellipse_period_gamma(cylinder_equivalent_aspect_ratio(aspect))
}

/// gamma T of a full Jeffery period (a turn by 2 pi) for a chain of `beads` beads, with the
/// equivalent ellipse of [`chain_equivalent_aspect_ratio`].
pub fn chain_period_gamma(beads: usize) -> f64 {
    ellipse_period_gamma(chain_equivalent_aspect_ratio(beads))
}

/// REFERENCE.md section 2's gamma T: the same law solved for the ellipse,
/// `e = (N_b / 1.14)^(1/0.844)` (see the module documentation for why it is not used).
pub fn chain_period_gamma_table(beads: usize) -> f64 {
    ellipse_period_gamma((beads as f64 / 1.14).powf(1.0 / 0.844))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of touching beads is a cylinder of aspect ratio N_b; spacing the beads apart
    /// lengthens it and slows its turn.
    #[test]
    fn a_chain_is_the_cylinder_that_envelops_it() {
        for n in 2..=16 {
            assert_eq!(cylinder_period_gamma(n as f64), chain_period_gamma(n));
        }
        assert!(cylinder_period_gamma(7.25) > chain_period_gamma(6));
    }

    /// REFERENCE.md section 2 table: N_b 3 -> 21.8, ..., 9 -> 73.2.
    #[test]
    fn table_reading_matches_reference_md() {
        let table = [
            (3, 21.8),
            (4, 29.2),
            (5, 37.3),
            (6, 45.8),
            (7, 54.7),
            (8, 63.8),
            (9, 73.2),
        ];
        for (n, t) in table {
            let v = chain_period_gamma_table(n);
            assert!((v - t).abs() < 0.06, "N_b {n}: {v}");
        }
    }

    /// Harris & Pittman's law: the equivalent ellipse of a cylinder is less elongated than
    /// the cylinder (above N_b ~ 2), and S2023's fitted 10-bead chain (e = 1 / 0.132 = 7.58)
    /// lies within 6 % of it.
    #[test]
    fn equivalent_ellipse_of_a_chain() {
        assert!((chain_equivalent_aspect_ratio(6) - 5.172).abs() < 1e-3);
        assert!((chain_period_gamma(6) - 33.71).abs() < 0.01);
        for n in 3..=10 {
            assert!(chain_equivalent_aspect_ratio(n) < n as f64);
        }
        let s2023 = 1.0 / 0.132;
        assert!((chain_equivalent_aspect_ratio(10) / s2023 - 1.0).abs() < 0.06);
    }
}
