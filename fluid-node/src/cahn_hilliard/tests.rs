use super::limits::{bulk_curvature_bound, max_wavenumber_squared, min_stabilisation};
use super::*;
use std::f64::consts::{PI, SQRT_2};

/// Eq. 31: ψ* makes ψ0 a stationary point of the bulk energy inside a solid (φ = 1), and a
/// minimum (`g' = 3ψ0² + 2 > 0`).
#[test]
fn psi_star_puts_the_bulk_minimum_at_psi0() {
    for psi0 in [-1.0, -0.6, -0.2, 0.0, 0.3, 0.75, 1.0] {
        let g = bulk_derivative(psi0, 1.0, psi_star(psi0));
        assert!(g.abs() < 1e-15, "{psi0}: {g:e}");
    }
    assert_eq!(psi_star(0.0), 0.0);
    assert!((psi_star(1.0) - 1.0).abs() < 1e-15);
}

/// L2020 section 3.3: σ_AB = √8 σ0 / 3 with σ0 = e0 L0, i.e. ξ = L0 = 1.
#[test]
fn sigma_ab_is_l2020s_value() {
    assert!((sigma_ab(1.0, 1.0) - 8f64.sqrt() / 3.0).abs() < 1e-15);
    assert!((sigma_ab(2.0, 3.0) - 6.0 * 2.0 * SQRT_2 / 3.0).abs() < 1e-14);
}

/// Eq. 41: Pe = U0 L0 / D0 with D0 = e0 M.
#[test]
fn mobility_from_peclet_inverts_eq_41() {
    let (pe, u0, l0, e0) = (1.0, 0.02, 1.0, 0.5);
    let m = mobility_from_peclet(pe, u0, l0, e0).unwrap();
    let cfg = CahnHilliardConfig {
        e0,
        mobility: m,
        ..Default::default()
    };
    assert!((u0 * l0 / cfg.diffusivity() - pe).abs() < 1e-15);
    let e = mobility_from_peclet(0.0, u0, l0, e0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "cahn-hilliard: peclet = 0 is invalid: must be finite and positive"
    );
}

#[test]
fn bad_input_is_refused_with_named_errors() {
    let g = Grid::new(2, [8, 6, 1]);
    let bad = CahnHilliardConfig {
        xi: 0.0,
        ..Default::default()
    };
    assert!(matches!(
        CahnHilliard::new(g, bad),
        Err(CahnHilliardError::InvalidParameter { name: "xi", .. })
    ));
    let bad = CahnHilliardConfig {
        stabilisation: f64::NAN,
        ..Default::default()
    };
    assert!(CahnHilliard::new(g, bad).is_err());
    let g4 = Grid {
        dims: 4,
        nx: 4,
        ny: 4,
        nz: 4,
    };
    assert!(matches!(
        CahnHilliard::new(g4, CahnHilliardConfig::default()),
        Err(CahnHilliardError::InvalidGrid { .. })
    ));
    let mut ch = CahnHilliard::new(g, CahnHilliardConfig::default()).unwrap();
    assert_eq!(
        ch.set_psi(&[0.0; 5]).unwrap_err().to_string(),
        "cahn-hilliard: psi has 5 values where the grid has 48"
    );
    let one = vec![vec![0.0; 48]];
    assert!(matches!(
        ch.step_advected(&one),
        Err(CahnHilliardError::FieldLength { .. })
    ));
    let short = vec![vec![0.0; 48], vec![0.0; 47]];
    assert!(ch.step_advected(&short).is_err());
    let mut f = vec![vec![0.0; 48]; 1];
    assert!(ch.capillary_force(&mut f).is_err());
    assert!(ch.set_dt(-1.0).is_err());
    assert_eq!(ch.steps(), 0);
}

/// A uniform bulk phase is a fixed point: μ = 0, no force, nothing moves; the state
/// survives a round trip through its spectrum.
#[test]
fn uniform_bulk_is_at_rest_and_the_state_round_trips() {
    let g = Grid::new(3, [6, 5, 4]);
    let mut ch = CahnHilliard::new(g, CahnHilliardConfig::default()).unwrap();
    ch.set_psi(&vec![1.0; g.cells()]).unwrap();
    ch.step().unwrap();
    assert!(ch.psi().iter().all(|p| (p - 1.0).abs() < 1e-15));
    assert!(ch.chemical_potential().iter().all(|m| m.abs() < 1e-15));
    let mut f = vec![vec![1.0; g.cells()]; 3];
    ch.capillary_force(&mut f).unwrap();
    assert!(f.iter().flatten().all(|v| v.abs() < 1e-15));
    let fe = ch.free_energy();
    assert!(fe.total.abs() < 1e-13);
    let psi: Vec<f64> = (0..g.cells()).map(|i| (i as f64 * 0.37).sin()).collect();
    ch.set_psi(&psi).unwrap();
    let spec = ch.psi_spectrum().to_vec();
    let mut other = CahnHilliard::new(g, CahnHilliardConfig::default()).unwrap();
    other.set_psi_spectrum(&spec).unwrap();
    assert_eq!(other.psi(), ch.psi());
    assert!((ch.mean_psi() - psi.iter().sum::<f64>() / g.cells() as f64).abs() < 1e-15);
}

/// With a uniform ψ and any φ the gradient term vanishes and the double-well and solid terms
/// equal their densities summed; the density per node sums to the total.
#[test]
fn free_energy_terms_match_their_densities() {
    let g = Grid::new(2, [10, 8, 1]);
    let mut ch = CahnHilliard::new(g, CahnHilliardConfig::default()).unwrap();
    let psi0 = 0.4;
    ch.set_psi(&vec![psi0; g.cells()]).unwrap();
    for (i, f) in ch.phi_mut().iter_mut().enumerate() {
        *f = (i % 3) as f64 / 2.0;
    }
    ch.set_uniform_affinity(0.1);
    let fe = ch.free_energy();
    let n = g.cells() as f64;
    assert!((fe.double_well - n * 0.25 * (1.0 - psi0 * psi0).powi(2)).abs() < 1e-12);
    let phi2: f64 = ch.phi().iter().map(|f| f * f).sum();
    assert!((fe.solid - 1.5 * phi2 * (psi0 - psi_star(0.1)).powi(2)).abs() < 1e-12);
    assert!(fe.gradient.abs() < 1e-12);
    let mut dens = vec![0.0; g.cells()];
    ch.free_energy_density(&mut dens).unwrap();
    assert!((dens.iter().sum::<f64>() - fe.total).abs() < 1e-12);
}

#[test]
fn initial_states_have_the_tanh_profile_where_expected() {
    let g = Grid::new(2, [40, 30, 1]);
    let xi = 1.5;
    let w = SQRT_2 * xi;
    let mut psi = vec![0.0; g.cells()];
    // A in 20 <= y < 5 (wrapping): interfaces at y = 20 and y = 5.
    stratified(g, xi, 1, 20.0, 5.0, Fluid::A, &mut psi).unwrap();
    assert_eq!(psi[g.index(3, 20, 0)], 0.0);
    assert!((psi[g.index(3, 22, 0)] - (2.0 / w).tanh()).abs() < 1e-15);
    assert!((psi[g.index(3, 7, 0)] + (2.0 / w).tanh()).abs() < 1e-15);
    assert!(psi[g.index(0, 28, 0)] > 0.99 && psi[g.index(0, 12, 0)] < -0.99);
    assert!(stratified(g, xi, 2, 0.0, 1.0, Fluid::A, &mut psi).is_err());

    droplet(g, xi, [38.0, 15.0, 0.0], 6.0, Fluid::B, &mut psi).unwrap();
    // Across the periodic boundary: x = 2 is 4 nodes from the centre.
    assert!((psi[g.index(2, 15, 0)] + (2.0 / w).tanh()).abs() < 1e-14);
    assert!(psi[g.index(20, 15, 0)] > 0.99);

    half_droplet(
        g,
        xi,
        [20.0, 10.0, 0.0],
        [0.0, 2.0, 0.0],
        8.0,
        Fluid::A,
        &mut psi,
    )
    .unwrap();
    assert!((psi[g.index(20, 14, 0)] - (4.0 / w).tanh()).abs() < 1e-14);
    assert!(psi[g.index(20, 6, 0)] < -0.9, "below the base: other fluid");
    assert_eq!(psi[g.index(20, 18, 0)], 0.0);
    assert!(half_droplet(g, xi, [0.0; 3], [0.0; 3], 8.0, Fluid::A, &mut psi).is_err());

    let g3 = Grid::new(3, [12, 12, 12]);
    let mut p3 = vec![0.0; g3.cells()];
    half_droplet(
        g3,
        1.0,
        [6.0, 6.0, 3.0],
        [0.0, 0.0, 1.0],
        5.0,
        Fluid::A,
        &mut p3,
    )
    .unwrap();
    assert!(p3[g3.index(6, 6, 6)] > 0.8 && p3[g3.index(6, 6, 1)] < -0.8);
    assert!(p3[g3.index(6, 11, 6)] < 0.0 && p3[g3.index(6, 9, 6)] > 0.0);
}

#[test]
fn time_step_limits_follow_the_linear_analysis() {
    let g = Grid::new(3, [8, 9, 10]);
    let k2 = max_wavenumber_squared(g);
    let k_odd = 2.0 * PI * 4.0 / 9.0;
    assert!((k2 - (2.0 * PI * PI + k_odd * k_odd)).abs() < 1e-12);
    assert!((bulk_curvature_bound(1.0) - 5.63).abs() < 1e-12);
    assert!((min_stabilisation(0.0) - 1.315).abs() < 1e-12);
    let cfg = CahnHilliardConfig::default();
    // Default S = 3 covers φ <= 1: no diffusive limit, only the flow's.
    assert!(time_step_limits(g, &cfg, 0.0, 1.0).is_empty());
    let with_flow = time_step_limits(g, &cfg, 0.1, 1.0);
    assert_eq!(with_flow.len(), 2);
    assert!((with_flow[0].dt_max - 5.0).abs() < 1e-12);
    assert!((with_flow[1].dt_max - 400.0).abs() < 1e-9);
    // S = 1 < 5.63 / 2: c = 3.63, worst k² = c / (2 ξ²) (inside the grid's range).
    let weak = CahnHilliardConfig {
        stabilisation: 1.0,
        ..Default::default()
    };
    let c: f64 = 5.63 - 2.0;
    let expect = 2.0 / (c * c / 16.0);
    assert!((max_stable_dt(g, &weak, 0.0, 1.0) - expect).abs() < 1e-9);
    let e = check_time_step(
        g,
        &CahnHilliardConfig {
            dt: 10.0,
            ..cfg.clone()
        },
        0.1,
        1.0,
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "cahn-hilliard: time step too large (phase-field advective CFL limit): dt = 10 exceeds 5 \
         (max|u| dt / dx <= 0.5 with max|u| = 0.1, dx = 1)"
    );
}
