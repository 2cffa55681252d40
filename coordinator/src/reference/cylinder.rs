//! Steady drag coefficient of an isolated circular cylinder, `C_D = F / (rho U^2 d / 2)` per
//! unit length (REFERENCE.md section 2).

/// Dennis & Chang (1970), steady numerical solutions: Re -> C_D.
const DENNIS_CHANG: [(f64, f64); 3] = [(10.0, 2.846), (20.0, 2.045), (40.0, 1.522)];

/// Lamb's Oseen-flow drag, `C_D = 8 pi / (Re (2.002 - ln Re))`, valid for Re << 1.
pub fn lamb(re: f64) -> f64 {
    8.0 * std::f64::consts::PI / (re * (2.002 - re.ln()))
}

/// The reference C_D at Reynolds number `re = U d / nu`, with its source: Dennis & Chang
/// where tabulated (to 1e-6 relative), Lamb's law for Re <= 1, none between.
pub fn drag_coefficient(re: f64) -> Option<(f64, &'static str)> {
    if let Some(&(_, cd)) = DENNIS_CHANG
        .iter()
        .find(|(r, _)| (r - re).abs() <= 1e-6 * r)
    {
        return Some((cd, "Dennis & Chang 1970, steady numerical solution"));
    }
    if re > 0.0 && re <= 1.0 {
        return Some((
            lamb(re),
            "Lamb, Oseen flow: C_D = 8 pi / (Re (2.002 - ln Re)), Re << 1",
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tabulated_and_lamb() {
        assert_eq!(drag_coefficient(20.000000000000004).unwrap().0, 2.045);
        assert!(drag_coefficient(15.0).is_none());
        // Lamb at Re = 1: 8 pi / 2.002.
        assert!(
            (drag_coefficient(1.0).unwrap().0 - 8.0 * std::f64::consts::PI / 2.002).abs() < 1e-12
        );
        assert!((lamb(0.1) - 58.386).abs() < 1e-3, "{}", lamb(0.1));
    }
}
