//! The binary fluid coupled into the SPM step (L2020 sections 2.4–2.6): phase
//! fluid-phase-field, the capillary force of eqs. 33–34 in u* and so in the impulses of
//! eqs. 35–36. Small 2D grids, driven through an InProcessExchange with prescribed beads.
mod common;
use common::*;
use cosim::{BeadImpulse, BeadState, Component, Exchange, InProcessExchange, Phase, Port};
use fluid_node::cahn_hilliard::{sigma_ab, stratified, CahnHilliard, CahnHilliardConfig, Fluid};
use fluid_node::{FluidComponent, Grid};

/// One binary SPM step with prescribed bead states (`states` for positions n+1; the same
/// states at n for the phase field): phase field, momentum exchange, penalty. Returns the
/// impulses and the phase-field diagnostics.
fn binary_step(
    c: &mut FluidComponent,
    x: &mut InProcessExchange,
    n: u64,
    at_n: &[BeadState],
    at_n1: &[BeadState],
) -> (Vec<BeadImpulse>, Vec<(String, f64)>) {
    if !at_n.is_empty() {
        x.publish_states(Port::BeadStates, n, at_n).unwrap();
    }
    let pf = c.run_phase(n, Phase::FluidPhaseField, x).unwrap();
    let mut imp = Vec::new();
    if at_n1.is_empty() {
        step(c, x, n);
    } else {
        let (j, _) = bead_step(c, x, n, at_n1, at_n1);
        imp = j;
    }
    (imp, pf.diagnostics)
}

fn lookup(d: &[(String, f64)], name: &str) -> f64 {
    d.iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no {name} in {d:?}"))
        .1
}

/// `time.steps = 400`: the free energy is reported at logged steps only, here the last.
const FLAT: &str = "dimensions = 2\n[time]\ndt = 0.5\nsteps = 400\n[fluid]\nmethod = \"spm\"\n\
                    grid = [24, 48]\nviscosity = 0.5\n\
                    [fluid.binary]\ne0 = 0.05\nmobility = 1\ninitial = \"flat\"\n\
                    normal = 1\nposition = 12\nwidth = 24\n";

/// A flat interface with the flow coupled stays at its discrete equilibrium, within the
/// distance of the sampled tanh profile to it (the same run without flow gives the same ψ to
/// round-off: the capillary force of a flat interface is a gradient, which the projection
/// removes, so the flow stays at rest to round-off). Its excess free energy per area is
/// σ_AB = (2√2/3) e0 ξ (L2020 section 3.3).
#[test]
fn a_flat_interface_stays_at_the_tanh_profile_with_the_flow_coupled() {
    let (mut c, mut x, cfg) = configure(FLAT);
    assert!(cfg.effects.contains(&"capillarity".to_string()));
    let derived = |k: &str| lookup(&cfg.derived, k);
    let sigma = derived("fluid.binary.sigma");
    assert!((sigma - sigma_ab(0.05, 2.0)).abs() < 1e-15);
    assert_eq!(derived("fluid.binary.interface_area"), 48.0);

    let g = Grid::new(2, [24, 48, 1]);
    let mut tanh = vec![0.0; g.cells()];
    stratified(g, 2.0, 1, 12.0, 36.0, Fluid::A, &mut tanh).unwrap();
    // The same phase field without flow.
    let mut alone = CahnHilliard::new(
        g,
        CahnHilliardConfig {
            xi: 2.0,
            e0: 0.05,
            mobility: 1.0,
            dt: 0.5,
            ..CahnHilliardConfig::default()
        },
    )
    .unwrap();
    alone.set_psi(&tanh).unwrap();

    let mut diags = Vec::new();
    let mut max_speed: f64 = 0.0;
    for n in 0..400u64 {
        let (_, d) = binary_step(&mut c, &mut x, n, &[], &[]);
        diags = d;
        alone.step().unwrap();
        max_speed = max_speed.max(
            c.velocity()
                .iter()
                .flat_map(|v| v.iter())
                .fold(0.0f64, |m, v| m.max(v.abs())),
        );
    }
    let coupled = phase_field(&c);
    let to_alone = max_diff(&coupled, alone.psi());
    let to_tanh = max_diff(&coupled, &tanh);
    let area = derived("fluid.binary.interface_area");
    let measured = lookup(&diags, "free_energy") / area;
    let rel = (measured / sigma - 1.0).abs();
    eprintln!(
        "flat interface, 400 steps: max|u| = {max_speed:.2e}, max|psi - psi_no_flow| = \
         {to_alone:.2e}, max|psi - tanh| = {to_tanh:.2e}, F / area = {measured:.6e} vs sigma_AB \
         {sigma:.6e} (rel. {rel:.2e}), interface at {}",
        lookup(&diags, "interface_position")
    );
    assert!(max_speed < 1e-14, "{max_speed:e}");
    assert!(to_alone < 1e-12, "{to_alone:e}");
    assert!(to_tanh < 2e-3, "{to_tanh:e}");
    assert!(rel < 2e-3, "{rel:e}");
    assert!((lookup(&diags, "interface_position") - 12.0).abs() < 1e-9);
}

/// ψ of the configured component, read back through a saved state (the component keeps
/// it private): the trailing spectrum, inverse-transformed by a fresh solver.
fn phase_field(c: &FluidComponent) -> Vec<f64> {
    let state = c.save_state().unwrap();
    let nl = state.iter().position(|&b| b == b'\n').unwrap();
    let g = c.grid().unwrap();
    let body = &state[nl + 1..];
    let psi = &body[g.dims * g.modes() * 16..];
    let spectrum: Vec<_> = psi
        .chunks_exact(16)
        .map(|b| {
            rustfft::num_complex::Complex64::new(
                f64::from_le_bytes(b[..8].try_into().unwrap()),
                f64::from_le_bytes(b[8..].try_into().unwrap()),
            )
        })
        .collect();
    let mut ch = CahnHilliard::new(g, CahnHilliardConfig::default()).unwrap();
    ch.set_psi_spectrum(&spectrum).unwrap();
    ch.psi().to_vec()
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

fn moving_bead(t: f64) -> Vec<BeadState> {
    let v = [0.03, 0.06, 0.0];
    vec![BeadState {
        position: [10.0 + v[0] * t, 4.0 + v[1] * t, 0.0],
        orientation: [1.0, 0.0, 0.0, 0.0],
        velocity: v,
        angular_velocity: [0.0, 0.0, 0.01],
    }]
}

/// The mean of ψ is conserved to round-off over many steps while a bead of affinity 0.3
/// crosses the interface (L2020 eq. 32 in conservative form: the k = 0 mode is untouched).
#[test]
fn mean_psi_is_conserved_with_a_moving_bead() {
    let scene = "dimensions = 2\n[time]\ndt = 0.5\n[fluid]\nmethod = \"spm\"\n\
                 grid = [32, 48]\nviscosity = 0.5\nxi = 2\nxi_cutoff = 5\n\
                 [fluid.binary]\ne0 = 0.05\nmobility = 1\ninitial = \"flat\"\n\
                 normal = 1\nposition = 16\nwidth = 20\n\
                 [[fibre]]\nbeads = 1\nbead_radius = 4\naffinity = 0.3\n";
    let (mut c, mut x, cfg) = configure(scene);
    assert!((lookup(&cfg.derived, "fibre.0.psi_star") - (0.6 + 0.027) / 3.0).abs() < 1e-15);
    let dt = 0.5;
    let mut first = None;
    let mut worst: f64 = 0.0;
    let mut max_abs: f64 = 0.0;
    let steps = 600u64;
    for n in 0..steps {
        let (imp, d) = binary_step(
            &mut c,
            &mut x,
            n,
            &moving_bead(n as f64 * dt),
            &moving_bead((n + 1) as f64 * dt),
        );
        assert!(imp[0].impulse.iter().all(|v| v.is_finite()));
        let m = lookup(&d, "mean_psi");
        let m0 = *first.get_or_insert(m);
        worst = worst.max(((m - m0) / m0).abs());
        max_abs = max_abs.max(lookup(&d, "max_abs_psi"));
    }
    // The real-space mean, summed from the field.
    let psi = phase_field(&c);
    let real_mean = psi.iter().sum::<f64>() / psi.len() as f64;
    let m0 = first.unwrap();
    let real = ((real_mean - m0) / m0).abs();
    eprintln!(
        "moving bead, {steps} steps: mean psi {m0:.15} (expected (20 - 28) / 48 = -0.1667), \
         relative drift {worst:.1e} (spectral), {real:.1e} (real-space sum); max|psi| \
         {max_abs:.4}"
    );
    assert!((m0 + 8.0 / 48.0).abs() < 1e-3);
    assert!(worst < 1e-12 && real < 1e-12);
    assert!(max_abs < 1.2);
}

fn held_bead() -> Vec<BeadState> {
    vec![BeadState::at_rest([24.0, 24.0, 0.0])]
}

fn held_scene(affinity: f64, binary: bool) -> String {
    let b = if binary {
        "[fluid.binary]\ne0 = 0.1\nmobility = 1\ninitial = \"flat\"\nnormal = 1\nposition = 24\n"
    } else {
        ""
    };
    format!(
        "dimensions = 2\n[time]\ndt = 0.5\n[fluid]\nmethod = \"spm\"\ngrid = [48, 48]\n\
         viscosity = 1\nxi = 2\nxi_cutoff = 5\n{b}\
         [[fibre]]\nbeads = 1\nbead_radius = 6\naffinity = {affinity}\n"
    )
}

/// Total impulse on a held bead centred on the interface after `steps` steps.
fn held_impulse(affinity: f64, binary: bool, steps: u64) -> [f64; 3] {
    let (mut c, mut x, _) = configure(&held_scene(affinity, binary));
    let s = held_bead();
    let mut last = [0.0; 3];
    for n in 0..steps {
        let imp = if binary {
            binary_step(&mut c, &mut x, n, &s, &s).0
        } else {
            bead_step(&mut c, &mut x, n, &s, &s).0
        };
        last = imp[0].impulse;
    }
    last
}

/// A bead held on a flat interface receives the capillary force through the momentum
/// exchange: towards fluid A (+y) for ψ0 > 0, the mirror image for -ψ0 (the scene is
/// antisymmetric under y -> 48 - y, ψ -> -ψ), none for ψ0 = 0 and none along x (mirror
/// symmetry), to round-off; the same scene without [fluid.binary] gives no impulse at all.
#[test]
fn a_bead_at_an_interface_receives_the_capillary_impulse() {
    let steps = 60;
    let up = held_impulse(0.5, true, steps);
    let down = held_impulse(-0.5, true, steps);
    let neutral = held_impulse(0.0, true, steps);
    let single = held_impulse(0.5, false, steps);
    eprintln!(
        "held bead, {steps} steps: J(psi0 = 0.5) = {up:.3?}, J(-0.5) = {down:.3?}, J(0) = \
         {neutral:.3?}, without the binary fluid {single:.3?}"
    );
    assert!(up[1] > 0.0, "{up:?}");
    let scale = up[1].abs();
    assert!((up[1] + down[1]).abs() < 1e-9 * scale, "{up:?} {down:?}");
    assert!(neutral[1].abs() < 1e-9 * scale, "{neutral:?}");
    assert!(up[0].abs() < 1e-9 * scale && down[0].abs() < 1e-9 * scale);
    assert!(
        single.iter().all(|v| v.abs() < 1e-15 * scale.max(1.0)),
        "{single:?}"
    );
}

/// configure refuses a time step above the phase-field limits and the capillary limit,
/// naming the limit, and unknown keys of [fluid.binary], naming the accepted ones.
#[test]
fn refusals_name_the_limit_or_the_key() {
    let refuse = |scene: String| {
        let mut c = FluidComponent::new();
        let mut x = InProcessExchange::new();
        match c.configure(&scene, &mut x) {
            Ok(_) => panic!("accepted:\n{scene}"),
            Err(e) => e.0,
        }
    };
    // S = 1 < g'max / 2 = 2.815: the semi-implicit step has a diffusive limit.
    let e = refuse(
        FLAT.replace("dt = 0.5", "dt = 5")
            .replace("e0 = 0.05", "e0 = 1\nstabilisation = 1"),
    );
    assert!(
        e.contains("time step too large (Cahn-Hilliard stabilisation limit): dt = 5 exceeds"),
        "{e}"
    );
    // sigma = 18.9, eta = 0.01: the capillary limit (Galusinski & Vigneaux 2008) is 0.026.
    let e = refuse(
        FLAT.replace("viscosity = 0.5", "viscosity = 0.01")
            .replace("e0 = 0.05", "e0 = 10"),
    );
    assert!(
        e.starts_with(
            "time step too large for the binary fluid (capillary limit): time.dt = 0.5 exceeds 0.0258"
        ),
        "{e}"
    );
    let e = refuse(FLAT.replace("mobility = 1", "mobility = 1\ncolour = \"blue\""));
    assert!(
        e.starts_with(
            "fluid.binary.colour: unknown key (set to the string \"blue\"); expected one of \
             `xi`, `e0`, `sigma`, `mobility`, `peclet`, `velocity_scale`, `stabilisation`, \
             `wall_affinity`, `initial`, `normal`, `position`, `width`, `centre`, `radius`, \
             `inside`"
        ),
        "{e}"
    );
    let e = refuse(FLAT.replace("mobility = 1", "peclet = 1"));
    assert!(
        e.starts_with("fluid.binary.peclet: needs the velocity scale U0"),
        "{e}"
    );
}

/// L2020 eqs. 39–42 from the scene: Re = rho U0 / eta, We = rho U0^2 / e0, Pe = U0 / (e0 M)
/// (L0 = 1, sigma0 = e0 L0), Ec = pi r_b E / (2 e0); `peclet` sets M = U0 / (Pe e0).
#[test]
fn dimensionless_numbers_follow_the_scene() {
    let scene = "dimensions = 2\n[time]\ndt = 0.5\n[fluid]\nmethod = \"spm\"\ngrid = [48, 48]\n\
                 viscosity = 10\nxi = 2\nxi_cutoff = 5\n\
                 [fluid.binary]\ne0 = 0.1\nvelocity_scale = 0.1\npeclet = 1\n\
                 initial = \"droplet\"\ncentre = [24, 30]\nradius = 8\n\
                 [[fibre]]\nbeads = 2\nbead_radius = 3\nyoungs_modulus = 2\naffinity = -0.2\n";
    let (_, _, cfg) = configure(scene);
    let d = |k: &str| lookup(&cfg.derived, k);
    eprintln!("{:?}", cfg.derived);
    assert!((d("fluid.binary.reynolds") - 0.01).abs() < 1e-15);
    assert!((d("fluid.binary.weber") - 0.1).abs() < 1e-15);
    assert!((d("fluid.binary.peclet") - 1.0).abs() < 1e-12);
    assert!((d("fluid.binary.mobility") - 1.0).abs() < 1e-12);
    assert!((d("fibre.0.elastocapillary") - std::f64::consts::PI * 3.0 * 2.0 / 0.2).abs() < 1e-12);
    assert!((d("fibre.0.psi_star") - (-0.4 - 0.008) / 3.0).abs() < 1e-15);
    assert!(cfg.time_step_limits.iter().any(|(n, _)| n == "capillary"));
}

/// A bead circling through a droplet: radius 6 about the box centre, angular speed 0.01
/// (speed 0.06), so it enters and leaves the droplet on every turn.
fn circling_bead(t: f64) -> Vec<BeadState> {
    let (w, r) = (0.01, 6.0);
    let (s, c) = (w * t).sin_cos();
    vec![BeadState {
        position: [16.0 + r * c, 16.0 + r * s, 0.0],
        orientation: [1.0, 0.0, 0.0, 0.0],
        velocity: [-r * w * s, r * w * c, 0.0],
        angular_velocity: [0.0, 0.0, 0.0],
    }]
}

/// The mean of ψ is conserved to 1e-12 (relative) over 10⁴ coupled steps of a droplet
/// (R = 8 on 32²) stirred by a bead of affinity -0.5 that circles through it, eight turns
/// (L2020 eq. 32 in conservative form: the k = 0 mode is never changed, so the drift is
/// round-off of the real-space sum only).
#[test]
fn mean_psi_is_conserved_over_ten_thousand_steps_of_a_stirred_droplet() {
    let scene = "dimensions = 2\n[time]\ndt = 0.5\n[fluid]\nmethod = \"spm\"\n\
                 grid = [32, 32]\nviscosity = 0.5\nxi = 2\nxi_cutoff = 5\n\
                 [fluid.binary]\ne0 = 0.05\nmobility = 1\ninitial = \"droplet\"\n\
                 centre = [16, 16]\nradius = 8\n\
                 [[fibre]]\nbeads = 1\nbead_radius = 3\naffinity = -0.5\n";
    let (mut c, mut x, _) = configure(scene);
    let dt = 0.5;
    let steps = 10_000u64;
    let mut first = None;
    let mut worst: f64 = 0.0;
    let mut max_abs: f64 = 0.0;
    for n in 0..steps {
        let (imp, d) = binary_step(
            &mut c,
            &mut x,
            n,
            &circling_bead(n as f64 * dt),
            &circling_bead((n + 1) as f64 * dt),
        );
        assert!(imp[0].impulse.iter().all(|v| v.is_finite()), "step {n}");
        let m = lookup(&d, "mean_psi");
        let m0 = *first.get_or_insert(m);
        worst = worst.max(((m - m0) / m0).abs());
        max_abs = max_abs.max(lookup(&d, "max_abs_psi"));
    }
    let psi = phase_field(&c);
    let real_mean = psi.iter().sum::<f64>() / psi.len() as f64;
    let m0 = first.unwrap();
    let real = ((real_mean - m0) / m0).abs();
    let speed = c
        .velocity()
        .iter()
        .flat_map(|v| v.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    eprintln!(
        "stirred droplet, {steps} steps: mean psi {m0:.15}, relative drift {worst:.1e} \
         (spectral), {real:.1e} (real-space sum); max|psi| {max_abs:.4}, max|u| at the end \
         {speed:.3e}"
    );
    assert!(worst < 1e-12 && real < 1e-12, "{worst:e} {real:e}");
    assert!(max_abs < 1.2, "{max_abs}");
}
