//! Jeffery orbits of a rigid elongated body in simple shear (REFERENCE.md section 2;
//! L2020 appendix B).

/// gamma T for a chain of `beads` beads: the chain is a cylinder of aspect ratio e_c = N_b,
/// whose equivalent ellipse has e_p from e_c = 1.14 e_p^0.844, and gamma T = 2 pi (e_p + 1/e_p).
pub fn chain_period_gamma(beads: usize) -> f64 {
    let e_p = (beads as f64 / 1.14).powf(1.0 / 0.844);
    2.0 * std::f64::consts::PI * (e_p + 1.0 / e_p)
}

#[cfg(test)]
mod tests {
    /// REFERENCE.md section 2 table: N_b 3 -> 21.8, ..., 9 -> 73.2.
    #[test]
    fn matches_reference_table() {
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
            assert!(
                (super::chain_period_gamma(n) - t).abs() < 0.06,
                "N_b {n}: {}",
                super::chain_period_gamma(n)
            );
        }
    }
}
