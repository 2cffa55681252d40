//! Contact between fibres (`fibre.N.fibre_contact`) in the fibre node alone: what the
//! lockstep of the fibres keeps and changes.
use cosim::{Component, InProcessExchange, Phase, PhaseReport};
use fibre_node::FibreComponent;
mod common;
use common::{configure_error, configured};

fn step(c: &mut FibreComponent, x: &mut InProcessExchange, n: u64) -> PhaseReport {
    c.run_phase(n, Phase::FibrePositions, x).unwrap();
    c.run_phase(n, Phase::FibreVelocities, x).unwrap()
}

fn diag(r: &PhaseReport, name: &str) -> f64 {
    r.diagnostics.iter().find(|(n, _)| n == name).unwrap().1
}

/// Two 3D bead-spring fibres of 4 beads (radius 1, spacing 2; contact stiffness
/// k_s / l0^2 = 40 / 4 = 10) crossing at right angles, `extra` appended to both.
fn crossing(extra: &str) -> String {
    let fibre = |start: &str, dir: &str| {
        format!(
            "[[fibre]]\nmodel = \"bead-spring\"\nbeads = 4\nbead_radius = 1.0\n\
             youngs_modulus = 1.0\nstretch_stiffness = 40.0\nbending_stiffness = 5.0\n\
             substeps = 4\nstart = {start}\ndirection = {dir}\n{extra}\n"
        )
    };
    format!(
        "dimensions = 3\n[time]\ndt = 0.1\n{}{}",
        fibre("[0.0, 0.0, 0.0]", "[1.0, 0.0, 0.0]"),
        fibre("[3.0, -3.0, 3.0]", "[0.0, 1.0, 0.0]")
    )
}

/// Total momentum of the fibres, sum m V.
fn momentum(c: &FibreComponent) -> [f64; 3] {
    let mut p = [0.0; 3];
    for f in c.fibres() {
        for v in &f.vel {
            for k in 0..3 {
                p[k] += f.mass * v[k];
            }
        }
    }
    p
}

/// The second fibre thrown at the first, no damping, no fluid. The contact is a
/// conservative central force, so the total momentum is kept to round-off, and the energy
/// (kinetic + elastic, the contact's included) to the first-order error of the symplectic
/// Euler steps, which halves with the step (checked at dt 0.1 and 0.05, ratio 1.6-2.5).
/// Equal fibres colliding head on exchange their momentum: the thrown one stops, the other
/// leaves at about its speed (the rest goes into vibrations). Without the contact the
/// thrown fibre passes through, its beads 2 - sqrt(2) deep in the other's (the geometry). References: the conservation laws,
/// the elastic collision of equal masses.
#[test]
fn colliding_fibres_keep_momentum_and_energy_and_exchange_momentum() {
    let run = |contact: bool, dt: f64| {
        let scene = crossing(&format!("fibre_contact = {contact}"))
            .replace("dt = 0.1", &format!("dt = {dt}"));
        let (mut c, mut x) = configured(&scene);
        for v in c.fibres_mut()[1].vel.iter_mut() {
            v.z = -0.2;
        }
        let p0 = momentum(&c);
        let e0 = c.fibres().iter().map(|f| f.kinetic_energy()).sum::<f64>();
        let (mut deepest, mut drift): (f64, f64) = (0.0, 0.0);
        let mut touched = false;
        for n in 0..(30.0 / dt).round() as u64 {
            let r = step(&mut c, &mut x, n);
            deepest = deepest.max(diag(&r, "fibre_overlap"));
            touched |= diag(&r, "contact_energy") > 0.0;
            let e = diag(&r, "kinetic_energy") + diag(&r, "elastic_energy");
            drift = drift.max((e - e0).abs() / e0);
            let p = momentum(&c);
            for k in 0..3 {
                assert!((p[k] - p0[k]).abs() < 1e-12, "step {n}: {p:?} vs {p0:?}");
            }
        }
        let vz = |f: usize| c.fibres()[f].vel.iter().map(|v| v.z).sum::<f64>() / 4.0;
        (deepest, drift, touched, [vz(0), vz(1)])
    };
    let (deepest, drift, touched, vz) = run(true, 0.1);
    let (_, drift_half, _, _) = run(true, 0.05);
    println!(
        "with contact: deepest {deepest:.4}, energy drift {drift:.2e} (dt/2: {drift_half:.2e}), \
         vz after {vz:?}"
    );
    assert!(touched && deepest > 0.01, "they never touched: {deepest}");
    assert!(deepest < 0.5, "{deepest}");
    assert!(
        drift < 2e-2 && (1.6..2.5).contains(&(drift / drift_half)),
        "{drift} {drift_half}"
    );
    assert!(vz[0] < -0.15 && vz[1].abs() < 0.05, "{vz:?}");
    let (deepest, _, touched, vz) = run(false, 0.1);
    // The beads at y = +-1 pass those at x = 2 and 4 sqrt(2) apart across: 2 - sqrt(2) deep.
    let through = 2.0 - 2f64.sqrt();
    assert!(
        !touched && (deepest - through).abs() < 1e-9,
        "{deepest} {touched}"
    );
    assert!(vz[0] == 0.0 && (vz[1] + 0.2).abs() < 1e-12, "{vz:?}");
}

/// Fibres that never meet step as they do without the contact: the lockstep of their
/// sub-steps changes no fibre's arithmetic (damping, loads, a clamp and 3 sub-steps).
#[test]
fn fibres_apart_step_as_without_the_contact() {
    let far = |contact: bool| {
        crossing(&format!(
            "fibre_contact = {contact}\ndamping = 0.3\nclamp = [0]\n\
             loads = [{{ bead = -1, force = [0.0, 0.3, -0.2] }}]"
        ))
        .replace("substeps = 4", "substeps = 3")
        .replace("[3.0, -3.0, 3.0]", "[3.0, -3.0, 30.0]")
    };
    let (mut a, mut xa) = configured(&far(true));
    let (mut b, mut xb) = configured(&far(false));
    for n in 0..200 {
        let ra = step(&mut a, &mut xa, n);
        step(&mut b, &mut xb, n);
        assert_eq!(diag(&ra, "fibre_overlap"), 0.0);
        assert_eq!(diag(&ra, "contact_energy"), 0.0);
        for (fa, fb) in a.fibres().iter().zip(b.fibres()) {
            assert!(fa.pos == fb.pos && fa.vel == fb.vel, "step {n}");
        }
    }
    assert!(a.fibres()[1].pos[3].y > 0.5, "the load moved nothing");
}

#[test]
fn refuses_a_lone_fibre_contact_and_unequal_substeps() {
    let one = crossing("").replacen("substeps = 4", "substeps = 4\nfibre_contact = true", 1);
    let e = configure_error(&one);
    assert!(
        e.contains("fibre.0.fibre_contact = true: no other fibre of the scene has it"),
        "{e}"
    );
    let unequal = crossing("fibre_contact = true").replacen("substeps = 4", "substeps = 2", 1);
    let e = configure_error(&unequal);
    assert!(
        e.contains("need the same fibre.N.substeps (fibre.0.substeps = 2, fibre.1.substeps = 4)"),
        "{e}"
    );
}
