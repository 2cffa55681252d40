//! The bead-spring model (S2023 eqs. 9-12) on the cantilever: the mapping to Euler-Bernoulli.
//!
//! Mapping (fibre-node/src/bead_spring.rs): with the linear bending energy
//! U_b = -k_b sum t_{i+1} . t_i, small slopes give (k_b / 2) sum (dtheta)^2, the discrete form
//! of (E I / 2) int kappa^2 ds with ds = l0, so k_b = E I / l0 (l0 = 2 r_b); likewise
//! k_s / l0^2 = E A / l0. A bead-spring chain has no bead orientation, so the clamp holds
//! beads 0 and 1: the clamped end is then the middle of the first segment and the effective
//! length is L = (N_b - 1.5) l0.
mod common;
use common::*;

#[test]
fn bead_spring_cantilever_matches_euler_bernoulli_with_k_b_equal_e_i_over_l0() {
    let (beads, force) = (10usize, 4.0);
    let overrides = vec![
        "fibre.0.model=bead-spring".to_string(),
        "fibre.0.clamp=[0,1]".into(),
        format!("fibre.0.beads={beads}"),
        format!("fibre.0.loads.0.force=[0.0,{},0.0]", -force),
    ];
    let s = run_in_process(
        &config("cantilever.toml"),
        &overrides,
        "bead-spring-cantilever",
    );
    assert_eq!(s["status"], "at-rest", "{s}");
    let (over_l, _) = metric(&s, "tip_deflection_over_length");
    let l0 = 2.0;
    let deflection = over_l * l0 * (beads as f64 - 1.0);
    let ei = 1.0e4 * std::f64::consts::PI / 4.0;
    let l_eff = l0 * (beads as f64 - 1.5);
    let theory = force * l_eff.powi(3) / (3.0 * ei);
    let err = (deflection / theory - 1.0).abs();
    println!(
        "bead-spring: delta = {deflection:.6}, P L^3 / (3 E I) = {theory:.6}, error {:.3} %",
        100.0 * err
    );
    assert!(
        err < 0.05,
        "bead-spring cantilever off Euler-Bernoulli by {:.2} %",
        100.0 * err
    );
    // The bending stiffness the node derived is the mapping stated above.
    let k_b = s["derived"]["fibre.0.bending_stiffness"]
        .as_f64()
        .expect("k_b reported");
    assert!(
        (k_b - ei / l0).abs() < 1e-9 * k_b,
        "k_b = {k_b}, E I / l0 = {}",
        ei / l0
    );
}
