//! The fibre node's side of the FPD coupling (S2023 section II C): forces out, velocities in.
use cosim::{BeadState, Component, Exchange, Phase, Port};
use fibre_node::FibreComponent;
mod common;
use common::{configure_error, configured};

/// A bent 2D bead-spring fibre under FPD: 4 beads, the third displaced off the line so
/// that stretching and bending both act, and a point load on the last bead.
const FPD_SCENE: &str = r#"
dimensions = 2
[time]
dt = 0.5
[fluid]
method = "fpd-lbm"
[[fibre]]
model = "bead-spring"
beads = 4
bead_radius = 2.0
youngs_modulus = 1.0
stretch_stiffness = 30.0
bending_stiffness = 2.0
start = [10.0, 10.0, 0.0]
direction = [1.0, 0.0, 0.0]
loads = [{ bead = -1, force = [0.0, 0.25, 0.0] }]
"#;

/// Elastic energy of the chain as the bead-spring model defines it (S2023 eq. 9 in the
/// linear bending form the code implements, REFERENCE.md section 1): the reference the
/// published forces are checked against by central differences.
fn energy(p: &[[f64; 3]], k_s: f64, k_b: f64, l0: f64) -> f64 {
    let t = |i: usize| {
        let d = [p[i + 1][0] - p[i][0], p[i + 1][1] - p[i][1]];
        let l = d[0].hypot(d[1]);
        ([d[0] / l, d[1] / l], l)
    };
    let mut u = 0.0;
    for i in 0..p.len() - 1 {
        let (_, l) = t(i);
        u += 0.5 * k_s / (l0 * l0) * (l - l0).powi(2);
    }
    for i in 0..p.len() - 2 {
        let (a, _) = t(i);
        let (b, _) = t(i + 1);
        u -= k_b * (a[0] * b[0] + a[1] * b[1]);
    }
    u
}

#[test]
fn fpd_forces_are_minus_the_energy_gradient_plus_the_loads() {
    let (mut c, mut x) = configured(FPD_SCENE);
    c.fibres_mut()[0].pos[2].y += 0.7;
    c.fibres_mut()[0].pos[1].x += 0.3;
    c.run_phase(0, Phase::FibreForces, &mut x).unwrap();
    let mut forces = Vec::new();
    let header = x.read_forces(Port::BeadForces, &mut forces).unwrap();
    assert_eq!(header.step, 0);
    assert_eq!(forces.len(), 4);

    let p: Vec<[f64; 3]> = c.fibres()[0].pos.iter().map(|v| (*v).into()).collect();
    let h = 1e-6;
    for (k, f) in forces.iter().enumerate() {
        for d in 0..2 {
            let (mut a, mut b) = (p.clone(), p.clone());
            a[k][d] += h;
            b[k][d] -= h;
            let grad = (energy(&a, 30.0, 2.0, 4.0) - energy(&b, 30.0, 2.0, 4.0)) / (2.0 * h);
            let load = if k == 3 && d == 1 { 0.25 } else { 0.0 };
            let expected = -grad + load;
            assert!(
                (f.force[d] - expected).abs() < 1e-7 * (1.0 + expected.abs()),
                "bead {k}, component {d}: published {} against -dU/dx + load = {expected}",
                f.force[d]
            );
        }
    }
    // Internal forces balance: only the load is left in the sum.
    let total: f64 = forces.iter().map(|f| f.force[1]).sum();
    assert!((total - 0.25).abs() < 1e-12, "net force {total}");
}

#[test]
fn fpd_advance_moves_the_beads_with_the_velocities_the_flow_gave() {
    let (mut c, mut x) = configured(FPD_SCENE);
    let before: Vec<[f64; 3]> = c.fibres()[0].pos.iter().map(|v| (*v).into()).collect();
    c.run_phase(0, Phase::FibreForces, &mut x).unwrap();
    // The fluid node's answer: S2023 eq. 5's bead velocities, published for step 1.
    let v: Vec<BeadState> = (0..4)
        .map(|k| {
            let mut s = BeadState::at_rest([0.0; 3]);
            s.velocity = [0.01 * k as f64, -0.02, 0.0];
            s
        })
        .collect();
    x.publish_states(Port::BeadVelocities, 1, &v).unwrap();
    c.run_phase(0, Phase::FibreAdvance, &mut x).unwrap();

    let mut states = Vec::new();
    let header = x.read_states(Port::BeadStates, &mut states).unwrap();
    assert_eq!(header.step, 1);
    for (k, ((s, r), vk)) in states.iter().zip(&before).zip(&v).enumerate() {
        for d in 0..3 {
            // R^{n+1} = R^n + dt V^{n+1} (S2023 section II C, step 3), exactly.
            let expected = r[d] + 0.5 * vk.velocity[d];
            assert_eq!(s.position[d], expected, "bead {k}, component {d}");
            assert_eq!(s.velocity[d], vk.velocity[d]);
        }
    }
}

#[test]
fn fpd_advance_checks_what_it_reads() {
    let (mut c, mut x) = configured(FPD_SCENE);
    c.run_phase(0, Phase::FibreForces, &mut x).unwrap();
    let three = vec![BeadState::at_rest([0.0; 3]); 3];
    x.publish_states(Port::BeadVelocities, 1, &three).unwrap();
    let e = c.run_phase(0, Phase::FibreAdvance, &mut x).unwrap_err();
    assert!(
        e.to_string()
            .contains("3 bead velocities received for 4 beads"),
        "{e}"
    );

    let four = vec![BeadState::at_rest([0.0; 3]); 4];
    x.publish_states(Port::BeadVelocities, 7, &four).unwrap();
    let e = c.run_phase(0, Phase::FibreAdvance, &mut x).unwrap_err();
    assert!(
        e.to_string()
            .contains("read bead velocities of step 7 (expected 1)"),
        "{e}"
    );
}

#[test]
fn phases_of_the_other_coupling_are_refused() {
    let (mut c, mut x) = configured(FPD_SCENE);
    let e = c.run_phase(0, Phase::FibrePositions, &mut x).unwrap_err();
    assert!(
        e.to_string()
            .contains("does not belong to the fpd coupling"),
        "{e}"
    );

    // A thin profile (xi = 0.2) keeps these radius-2 beads within the SPM exchange limit.
    let spm = FPD_SCENE.replace("\"fpd-lbm\"", "\"spm\"\nxi = 0.2");
    let (mut c, mut x) = configured(&spm);
    let e = c.run_phase(0, Phase::FibreForces, &mut x).unwrap_err();
    assert!(
        e.to_string()
            .contains("does not belong to the spm coupling"),
        "{e}"
    );
}

#[test]
fn what_fpd_cannot_carry_is_refused_with_the_reason() {
    let beam = FPD_SCENE
        .replace("bead-spring", "cohesive-beam")
        .replace("stretch_stiffness = 30.0\nbending_stiffness = 2.0\n", "");
    let e = configure_error(&beam);
    assert!(
        e.contains("fibre.0.model = \"cohesive-beam\" cannot run under fluid.method = \"fpd-lbm\"")
            && e.contains("no bead rotation"),
        "{e}"
    );
    let e = configure_error(&format!("{FPD_SCENE}substeps = 4\n"));
    assert!(e.contains("fibre.0.substeps = 4"), "{e}");
    // A clamp is carried: the bead is held by a force (fibre.rs `hold_under_fpd`; its
    // dynamics are tested there and, with a fluid, in tests/fpd.rs).
    configured(&format!("{FPD_SCENE}clamp = [0]\n"));
}

#[test]
fn the_description_offers_fpd() {
    let d = FibreComponent::new().describe();
    assert!(d.coupling_schemes.iter().any(|s| s == "fpd"));
    assert!(d.phases.contains(&Phase::FibreForces) && d.phases.contains(&Phase::FibreAdvance));
}

/// Under FPD the contact between fibres (`fibre.N.fibre_contact`) is one more force the
/// fibre node publishes: a second fibre 3 above the first (beads of radius 2, so each bead
/// 1 deep in the one below it, and the diagonal neighbours 5 apart, clear) adds k_c * 1
/// along y to each pair, k_c = k_s / l0^2 = 30 / 16 (the axial bond stiffness, S2023
/// eq. 11). Reference: the contact law; exact to round-off.
#[test]
fn fpd_forces_carry_the_contact_between_fibres() {
    let forces = |contact: bool| {
        let second = FPD_SCENE
            .split("[[fibre]]")
            .nth(1)
            .unwrap()
            .replace("start = [10.0, 10.0, 0.0]", "start = [10.0, 13.0, 0.0]");
        let scene = format!("{FPD_SCENE}[[fibre]]{second}").replace(
            "loads = [",
            &format!("fibre_contact = {contact}\nloads = ["),
        );
        let (mut c, mut x) = configured(&scene);
        c.run_phase(0, Phase::FibreForces, &mut x).unwrap();
        let mut f = Vec::new();
        x.read_forces(Port::BeadForces, &mut f).unwrap();
        f
    };
    let (with, without) = (forces(true), forces(false));
    assert_eq!(with.len(), 8);
    for k in 0..8 {
        let sign = if k < 4 { -1.0 } else { 1.0 };
        let dy = with[k].force[1] - without[k].force[1];
        assert!((dy - sign * 30.0 / 16.0).abs() < 1e-12, "bead {k}: {dy}");
        assert_eq!(with[k].force[0], without[k].force[0], "bead {k}");
    }
}
