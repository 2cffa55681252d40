//! The fluid node as a component: description, configuration, refusals, phase order,
//! save/restore and determinism.
mod common;
use common::*;
use cosim::{Component, Exchange, InProcessExchange, Phase, Port};
use fluid_node::{FluidComponent, COUETTE_DIAGNOSTIC, DIAGNOSTICS, EXCHANGE_DIAGNOSTICS};

#[test]
fn description_names_the_contract() {
    let d = FluidComponent::new().describe();
    assert_eq!(d.name, "fluid-node");
    assert_eq!(d.kind, "fluid");
    assert_eq!(d.models, vec!["spm", "fpd-lbm"]);
    assert_eq!(d.coupling_schemes, vec!["spm", "fpd"]);
    assert_eq!(d.effects, vec!["hydrodynamics", "walls", "capillarity"]);
    assert_eq!(
        d.phases,
        vec![
            Phase::FluidPhaseField,
            Phase::FluidMomentumExchange,
            Phase::FluidPenalty,
            Phase::FluidLatticeStep
        ]
    );
    assert_eq!(d.inputs[0].port, Port::BeadStates);
    assert_eq!(d.outputs[0].port, Port::BeadImpulses);
    for key in [
        "fluid.method",
        "fluid.grid",
        "fluid.viscosity",
        "fluid.density",
        "fluid.xi",
        "fluid.xi_cutoff",
        "fluid.body_force",
        "fluid.initial_velocity",
        "walls.velocity",
        "walls.thickness",
        "fibre.N.bead_radius",
    ] {
        let p = d
            .parameters
            .iter()
            .find(|p| p.key == key)
            .unwrap_or_else(|| panic!("{key}"));
        assert!(!p.unit.is_empty());
    }
    assert!(d.render().contains("fluid-node"));
}

#[test]
fn configure_reports_effects_limits_and_derived_numbers() {
    let (_, _, cfg) = configure(FIBRE_SCENE);
    assert!(cfg.beads_per_fibre.is_empty());
    assert_eq!(cfg.effects, vec!["hydrodynamics", "walls"]);
    let limit = |name: &str| {
        cfg.time_step_limits
            .iter()
            .find(|(n, _)| n == name)
            .unwrap()
            .1
    };
    assert!((limit("advective CFL") - 0.5 / 0.02).abs() < 1e-12);
    let derived = |name: &str| cfg.derived.iter().find(|(n, _)| n == name).unwrap().1;
    // Gap 40 - 2 * 4 = 32, shear rate 0.04 / 32, fibre length 2 * 3 * 3 = 18.
    let gamma = 0.04 / 32.0;
    assert!((derived("fluid.shear_rate") - gamma).abs() < 1e-15);
    assert!((derived("fluid.reynolds") - gamma * 18.0 * 18.0).abs() < 1e-12);
    assert!((derived("fluid.confinement") - 18.0 / 32.0).abs() < 1e-15);
    // S2023 eq. 18: Re_ps = rho gamma l_c^2 / (4 eta), a quarter of the Reynolds number on l_c.
    let re_ps = derived("fluid.particle_shear_reynolds");
    assert!((re_ps - derived("fluid.reynolds") / 4.0).abs() < 1e-15);
    let k0 = std::f64::consts::PI * 3.0 * 100.0 / 2.0;
    assert!((derived("fluid.k0_over_l0_eta_gamma") - k0 / gamma).abs() < 1e-6);
    assert_eq!(derived("fluid.spm_diffusion_number"), 0.5);

    // No walls, no fibres: nothing to report but the fluid's own numbers.
    let (_, _, cfg) =
        configure("[time]\ndt = 1\n[fluid]\nmethod = \"spm\"\ngrid = [8, 8, 8]\nviscosity = 0.1\n");
    assert!(cfg.effects.is_empty() && cfg.time_step_limits.is_empty());
}

#[test]
fn bad_scenes_are_refused_with_the_key_and_never_panic() {
    let mut c = FluidComponent::new();
    let mut x = InProcessExchange::new();
    let cases: &[(&str, &str)] = &[
        ("viscosity = 1.0", "viscosity = -1"),
        (
            "method = \"spm\"",
            "method = \"spm\"\nbinary = { mobility = 1 }",
        ),
        ("grid = [48, 40]", "grid = [48, 40, 3]"),
        (
            "velocity = [-0.02, 0.02]",
            "velocity = [-0.02, 0.02]\ncolour = 3",
        ),
        ("dt = 0.5", "dt = 30"),
        ("dt = 0.5", "dt = 0.5\n[fluid.extra]"),
        ("dt = 0.5", "dt = [0.5"),
        ("bead_radius = 3", "bead_radius = 30"),
    ];
    let want = [
        "fluid.viscosity: expected a positive number, got -1",
        "fluid.binary.initial is required and missing",
        "fluid.grid: a 2D scene expects [nx, ny], got [48, 40, 3]",
        "walls.colour: unknown key (set to 3); expected one of `velocity`, `thickness`",
        "time step too large for the fluid (advective CFL limit): time.dt = 30 exceeds 25 (",
        "fluid.extra: unknown key (set to a table)",
        "the scene is not valid TOML",
        "fibre.0.bead_radius: 30 plus fluid.xi_cutoff 3 needs a grid of at least 68 nodes",
    ];
    for ((from, to), want) in cases.iter().zip(want) {
        let scene = FIBRE_SCENE.replacen(from, to, 1);
        let e = c.configure(&scene, &mut x).unwrap_err().0;
        assert!(e.starts_with(want), "{to}\n got: {e}\nwant: {want}");
        // A refused scene leaves nothing configured.
        assert!(c.run_phase(0, Phase::FluidPenalty, &mut x).is_err());
    }
}

#[test]
fn phases_run_in_order_and_inputs_are_checked() {
    let (mut c, mut x, _) = configure(FIBRE_SCENE);
    // Penalty before exchange.
    let e = c.run_phase(0, Phase::FluidPenalty, &mut x).unwrap_err().0;
    assert!(e.contains("before fluid-momentum-exchange"), "{e}");
    // No bead states published yet.
    let e = c
        .run_phase(0, Phase::FluidMomentumExchange, &mut x)
        .unwrap_err()
        .0;
    assert!(e.contains("no publication"), "{e}");
    // States of the wrong step.
    x.publish_states(Port::BeadPositions, 0, &fibre_states(0, 0.0))
        .unwrap();
    let e = c
        .run_phase(0, Phase::FluidMomentumExchange, &mut x)
        .unwrap_err()
        .0;
    assert!(e.contains("expects the bead states of step 1"), "{e}");
    // Wrong number of beads.
    x.publish_states(Port::BeadPositions, 1, &fibre_states(0, 0.0)[..2])
        .unwrap();
    let e = c
        .run_phase(0, Phase::FluidMomentumExchange, &mut x)
        .unwrap_err()
        .0;
    assert_eq!(
        e,
        "fluid-node: 2 bead states received, the scene's fibres have 3 beads"
    );
    // Non-finite position.
    let mut bad = fibre_states(0, 0.0);
    bad[1].position[0] = f64::NAN;
    x.publish_states(Port::BeadPositions, 1, &bad).unwrap();
    let e = c
        .run_phase(0, Phase::FluidMomentumExchange, &mut x)
        .unwrap_err()
        .0;
    assert!(
        e.starts_with("fluid-node: bead 1 has a non-finite position"),
        "{e}"
    );
    // A good step, then exchange twice.
    x.publish_states(Port::BeadPositions, 1, &fibre_states(0, 0.0))
        .unwrap();
    let r = c
        .run_phase(0, Phase::FluidMomentumExchange, &mut x)
        .unwrap();
    let names: Vec<&str> = r.diagnostics.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, EXCHANGE_DIAGNOSTICS);
    let mut imp = Vec::new();
    let h = x.read_impulses(Port::BeadImpulses, &mut imp).unwrap();
    assert_eq!((h.step, imp.len()), (1, 3));
    let e = c
        .run_phase(1, Phase::FluidMomentumExchange, &mut x)
        .unwrap_err()
        .0;
    assert!(e.contains("still pending"), "{e}");
    // The penalty reads the states of fibre-velocities, on their own port.
    x.publish_states(Port::BeadStates, 1, &fibre_states(0, 0.0))
        .unwrap();
    let r = c.run_phase(0, Phase::FluidPenalty, &mut x).unwrap();
    let names: Vec<&str> = r.diagnostics.iter().map(|(n, _)| n.as_str()).collect();
    let mut want = DIAGNOSTICS.to_vec();
    want.push(COUETTE_DIAGNOSTIC);
    assert_eq!(names, want);
    let e = c
        .run_phase(1, Phase::FluidPhaseField, &mut x)
        .unwrap_err()
        .0;
    assert!(
        e.starts_with("fluid-node: fluid-phase-field needs a binary fluid ([fluid.binary])"),
        "{e}"
    );
    // 2D: angular impulses along z only.
    assert!(imp
        .iter()
        .all(|j| j.angular_impulse[0] == 0.0 && j.angular_impulse[1] == 0.0));
    assert!(imp.iter().any(|j| j.angular_impulse[2] != 0.0));
}

#[test]
fn a_runaway_flow_stops_with_the_advective_limit_named() {
    let (mut c, mut x, _) = configure(
        "dimensions = 2\n[time]\ndt = 1\n[fluid]\nmethod = \"spm\"\ngrid = [16, 16]\n\
         viscosity = 0.01\nbody_force = [0.3, 0]\n",
    );
    let mut err = None;
    for n in 0..10 {
        c.run_phase(n, Phase::FluidMomentumExchange, &mut x)
            .unwrap();
        if let Err(e) = c.run_phase(n, Phase::FluidPenalty, &mut x) {
            err = Some((n, e.0));
            break;
        }
    }
    let (n, e) = err.expect("the run should stop");
    assert_eq!(n, 3);
    assert!(
        e.starts_with("fluid-node: the flow became unstable at step 3 (advective CFL limit)"),
        "{e}"
    );
}

/// A sub-cycled fibre corrects its positions after the impulses, so the penalty may place
/// the beads elsewhere than the momentum exchange did, their boxes reaching rows on which the
/// exchange did not bring the real u* up to date. The penalty must see u* there too: the
/// same bits as a node restored between the phases, whose u* is whole.
#[test]
fn penalty_at_corrected_positions_sees_the_whole_u_star() {
    let mut moved = fibre_states(3, 1e-3);
    for b in &mut moved {
        b.position[1] += 2.5;
    }
    let [(a, _), (b, _)] = penalty_in_both(&moved);
    let bits = |c: &FluidComponent| {
        c.velocity()
            .iter()
            .flatten()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b));
}

/// Steps 0-2, then step 3's momentum exchange; then step 3's penalty with `penalty_states`
/// in that node and in one restored from a save made between the two phases. Asserts the
/// two reports equal; returns both nodes with their exchanges.
fn penalty_in_both(
    penalty_states: &[cosim::BeadState],
) -> [(FluidComponent, InProcessExchange); 2] {
    let (mut a, mut xa, _) = configure(FIBRE_SCENE);
    run(&mut a, &mut xa, 0, 3);
    xa.publish_states(Port::BeadPositions, 4, &fibre_states(3, 0.0))
        .unwrap();
    a.run_phase(3, Phase::FluidMomentumExchange, &mut xa)
        .unwrap();
    let mid = a.save_state().unwrap();
    let (mut b, mut xb, _) = configure(FIBRE_SCENE);
    b.restore_state(&mid).unwrap();
    let mut reports = Vec::new();
    for (c, x) in [(&mut a, &mut xa), (&mut b, &mut xb)] {
        x.publish_states(Port::BeadStates, 4, penalty_states)
            .unwrap();
        reports.push(c.run_phase(3, Phase::FluidPenalty, x).unwrap());
    }
    assert_eq!(reports[0], reports[1]);
    [(a, xa), (b, xb)]
}

#[test]
fn save_and_restore_are_bit_exact_also_mid_step() {
    let (mut a, mut xa, _) = configure(FIBRE_SCENE);
    run(&mut a, &mut xa, 0, 5);
    let saved = a.save_state().unwrap();
    let reference = run(&mut a, &mut xa, 5, 5);

    let (mut b, mut xb, _) = configure(FIBRE_SCENE);
    b.restore_state(&saved).unwrap();
    assert_eq!(run(&mut b, &mut xb, 5, 5), reference);

    // Saved between the two phases of a step (u* pending).
    let [(mut a, mut xa), (mut b, mut xb)] = penalty_in_both(&fibre_states(3, 1e-3));
    assert_eq!(run(&mut a, &mut xa, 4, 2), run(&mut b, &mut xb, 4, 2));

    // Refusals.
    let e = b.restore_state(b"junk").unwrap_err().0;
    assert!(e.starts_with("fluid-node: not a saved fluid state"), "{e}");
    let (mut other, _, _) = configure(&FIBRE_SCENE.replace("[48, 40]", "[48, 42]"));
    let e = other.restore_state(&saved).unwrap_err().0;
    assert!(e.contains("saved state is of a 2D grid [48, 40, 1]"), "{e}");
    let e = FluidComponent::new().restore_state(&saved).unwrap_err().0;
    assert!(e.contains("configure with the same scene"), "{e}");
    let mut cut = saved.clone();
    cut.truncate(saved.len() - 8);
    assert!(b.restore_state(&cut).is_err());
}

#[test]
fn runs_repeat_bit_for_bit_with_any_number_of_threads() {
    let scene = FIBRE_SCENE.replace("[48, 40]", "[320, 256]");
    let with_threads = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let (mut c, mut x, _) = configure(&scene);
            run(&mut c, &mut x, 0, 4)
        })
    };
    let one = with_threads(1);
    assert_eq!(one, with_threads(1));
    assert_eq!(one, with_threads(2));
    assert_eq!(one, with_threads(3));
}

#[test]
fn fluid_alone_runs_without_bead_states_and_initial_couette_is_steady() {
    let (mut c, mut x, _) = configure(
        "dimensions = 3\n[time]\ndt = 1\n[fluid]\nmethod = \"spm\"\ngrid = [8, 48, 8]\n\
         viscosity = 1\ninitial_velocity = \"couette\"\n[walls]\nvelocity = [0, 0.01]\n",
    );
    let first = step(&mut c, &mut x, 0);
    let mut last = first.clone();
    for n in 1..200 {
        last = step(&mut c, &mut x, n);
    }
    // Starts at the linear profile; the SPM walls then settle within a fraction of a percent.
    eprintln!(
        "initial Couette: error {:.2e} after one step, {:.2e} after 200",
        diag(&first, "couette_max_error"),
        diag(&last, "couette_max_error")
    );
    assert!(diag(&last, "couette_max_error") < 2e-3);
    assert!((diag(&last, "mean_velocity_y")).abs() < 1e-17);
    assert!(diag(&last, "max_divergence") < 1e-15);
    assert!((diag(&last, "max_fluid_speed") - 0.01).abs() < 1e-3);
}

/// A brief report (`cosim::Detail::Brief`, asked for at the steps a run does not log) leaves
/// out exactly the diagnostics that cost a pass of their own (the divergence, the Couette
/// error, the free energy and the droplet's), keeps the others bit for bit and changes no bit
/// of the flow or the phase field.
#[test]
fn brief_reports_leave_out_the_costly_diagnostics_and_change_nothing_else() {
    use cosim::Detail;
    let scene = "dimensions = 2\n[time]\ndt = 0.5\nsteps = 12\n[fluid]\nmethod = \"spm\"\n\
                 grid = [32, 32]\nviscosity = 0.5\nxi = 2\nxi_cutoff = 5\n\
                 [fluid.binary]\ne0 = 0.05\nmobility = 1\ninitial = \"droplet\"\n\
                 centre = [16, 16]\nradius = 8\n[walls]\nvelocity = [0, 0.01]\n";
    let (mut full, mut xf, _) = configure(scene);
    let (mut brief, mut xb, _) = configure(scene);
    let phases = [
        Phase::FluidPhaseField,
        Phase::FluidMomentumExchange,
        Phase::FluidPenalty,
    ];
    let left_out = [
        "max_divergence",
        COUETTE_DIAGNOSTIC,
        "free_energy",
        "droplet_radius",
        "pressure_jump",
        "pressure_jump_mu",
    ];
    let mut seen = Vec::new();
    for n in 0..12 {
        // Full at every third step, as at logged steps.
        let detail = if n % 3 == 2 {
            Detail::Full
        } else {
            Detail::Brief
        };
        for phase in phases {
            let f = full.run_phase(n, phase, &mut xf).unwrap();
            let b = brief.run_phase_with(n, phase, detail, &mut xb).unwrap();
            assert_eq!(f.detail, Detail::Full);
            if detail == Detail::Full || phase == Phase::FluidMomentumExchange {
                assert_eq!(b, f, "step {n}, {phase}");
                continue;
            }
            assert_eq!(b.detail, Detail::Brief);
            let kept: Vec<_> = f
                .diagnostics
                .iter()
                .filter(|(k, _)| !left_out.contains(&k.as_str()))
                .cloned()
                .collect();
            assert_eq!(b.diagnostics, kept, "step {n}, {phase}");
            for (k, _) in &f.diagnostics {
                if left_out.contains(&k.as_str()) && !seen.contains(k) {
                    seen.push(k.clone());
                }
            }
        }
    }
    // Every costly diagnostic was there in full and left out in brief.
    seen.sort();
    let mut expected = left_out.map(String::from).to_vec();
    expected.sort();
    assert_eq!(seen, expected);
    // The whole saved state: the flow's and the phase field's spectra.
    assert_eq!(full.save_state().unwrap(), brief.save_state().unwrap());
}
