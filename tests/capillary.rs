//! Binary-fluid scenes through the coordinator (L2020 sections 2.4–2.6, 3.3): the Laplace
//! law of a droplet and the contact angle of a bead at a flat interface, including the hard
//! cases near 20° and 160°. Numbers and discussion: docs/validation/capillary.md.
mod common;
use common::*;
use coordinator::mcap_log::read_topic;

/// `laplace_pressure_jump` of a run: (value, reference, relative error, droplet radius,
/// the chemical-potential estimate μ Δψ).
fn laplace(s: &serde_json::Value) -> (f64, f64, f64, f64, f64) {
    let m = &s["metrics"]["laplace_pressure_jump"];
    let f = |v: &serde_json::Value| v.as_f64().unwrap_or_else(|| panic!("{m}"));
    (
        f(&m["value"]),
        f(&m["reference"]),
        f(&m["relative_error"]),
        f(&m["extra"]["droplet_radius"]),
        f(&m["extra"]["pressure_jump_mu"]),
    )
}

/// A 2D droplet (R = 16 on 64², ξ = 2) at rest: the jump of the mechanical pressure across
/// its surface is σ_AB / R within 5 % (the tolerance; measured 0.98 %, an
/// O((ξ/R)²) diffuse-interface correction: 0.26 % at R = 32), R the equimolar radius
/// measured at the end (15.55: the bulk ψ shifts with the curvature and the droplet gives
/// up the mass).
#[test]
fn laplace_2d_pressure_jump_is_sigma_over_r() {
    let s = run_in_process(
        &config("capillary/laplace_2d.toml"),
        &[],
        "capillary-laplace-2d",
    );
    let (dp, reference, rel, r, dp_mu) = laplace(&s);
    println!(
        "laplace 2D: dp = {dp:.6e}, sigma / R = {reference:.6e} (rel. {:.2} %), R = {r:.4}, \
         mu dpsi = {dp_mu:.6e}",
        100.0 * rel
    );
    assert!(rel.abs() < 0.05, "{rel}");
    assert!((15.0..16.0).contains(&r), "{r}");
    // At equilibrium μ is uniform and the jump is μ Δψ up to the second-order bulk energy.
    assert!((dp_mu / reference - 1.0).abs() < 0.05, "{dp_mu}");
}

/// An interface narrower than 0.75 grid spacings is not resolved: the same droplet at
/// ξ = 0.5 misses σ_AB / R by 16 % (measured) and the fluid node says so in a note; at ξ = 1
/// the jump is within 0.4 % (measured) and there is no note.
#[test]
fn an_unresolved_interface_misses_laplace_and_is_noted() {
    for (xi, low, high, noted) in [(0.5, 0.10, 0.25, true), (1.0, 0.0, 0.02, false)] {
        let s = run_in_process(
            &config("capillary/laplace_2d.toml"),
            &[format!("fluid.binary.xi={xi}")],
            &format!("capillary-laplace-xi-{xi}"),
        );
        let (_, _, rel, _, _) = laplace(&s);
        println!("laplace 2D at xi = {xi}: rel. {:.2} %", 100.0 * rel);
        assert!((low..high).contains(&rel.abs()), "xi = {xi}: {rel}");
        let has_note = s["notes"].as_array().unwrap().iter().any(|n| {
            n.as_str()
                .unwrap()
                .contains("does not resolve the interface")
        });
        assert_eq!(has_note, noted, "xi = {xi}: {}", s["notes"]);
    }
}

/// A 3D droplet (R = 16 on 48³, ξ = 2): the jump is 2 σ_AB / R within 5 %. 1000 steps keep
/// the test short (rel. 0.6 % here; 0.05 % at the scene's 2000 steps).
#[test]
fn laplace_3d_pressure_jump_is_two_sigma_over_r() {
    let s = run_in_process(
        &config("capillary/laplace_3d.toml"),
        &["time.steps=1000".into()],
        "capillary-laplace-3d",
    );
    let (dp, reference, rel, r, dp_mu) = laplace(&s);
    println!(
        "laplace 3D, 1000 steps: dp = {dp:.6e}, 2 sigma / R = {reference:.6e} (rel. {:.2} %), \
         R = {r:.4}, mu dpsi = {dp_mu:.6e}",
        100.0 * rel
    );
    assert!(rel.abs() < 0.05, "{rel}");
}

/// Overrides making `contact_angle.toml` small: 64², ξ = 2 (phase field and bead profile),
/// ξ_c = 5, r_b = 8, η = 1 and M = 4 (Pe = 0.25) for a faster approach; the bead starts
/// with its centre on the interface (y = 32, fluid A above).
fn small_contact_angle(affinity: f64, steps: u64) -> Vec<String> {
    [
        "fluid.grid=[64,64]",
        "fluid.xi=2.0",
        "fluid.xi_cutoff=5.0",
        "fluid.binary.xi=2.0",
        "fluid.viscosity=1.0",
        "fluid.binary.peclet=0.25",
        "fluid.binary.position=32.0",
        "fibre.0.bead_radius=8.0",
        "fibre.0.start=[32.0,32.0,0.0]",
        "output.interval=250",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([
        format!("fibre.0.affinity={affinity}"),
        format!("time.steps={steps}"),
    ])
    .collect()
}

struct ContactRun {
    angle: f64,
    reference: f64,
    height: f64,
    /// Largest |mean ψ - mean ψ at the first log| over the logged steps.
    mass_drift: f64,
    /// Largest max |ψ| over the logged steps.
    max_psi: f64,
}

fn contact_angle_run(affinity: f64, steps: u64, test: &str) -> ContactRun {
    let s = run_in_process(
        &config("capillary/contact_angle.toml"),
        &small_contact_angle(affinity, steps),
        test,
    );
    assert_eq!(s["status"], "completed", "{s}");
    let m = &s["metrics"]["contact_angle_deg"];
    // run_in_process wrote into out_dir(test) (calling out_dir again would empty it).
    let dir = run_dir(test);
    let log = read_topic(&dir.join("run.mcap"), "/diagnostics").unwrap();
    let first = log[0]["mean_psi"].as_f64().unwrap();
    let mut mass_drift: f64 = 0.0;
    let mut max_psi: f64 = 0.0;
    for d in &log {
        mass_drift = mass_drift.max((d["mean_psi"].as_f64().unwrap() - first).abs());
        max_psi = max_psi.max(d["max_abs_psi"].as_f64().unwrap());
    }
    ContactRun {
        angle: m["value"].as_f64().unwrap(),
        reference: m["reference"].as_f64().unwrap(),
        height: m["extra"]["bead_height"].as_f64().unwrap(),
        mass_drift,
        max_psi,
    }
}

/// Boundedness of a hard case: no NaN (the run completes: the coordinator stops on a
/// non-finite diagnostic), ψ within its physical range, mean ψ conserved (it starts at 0 to
/// round-off, so the drift is absolute: 1e-12 of the bulk |ψ| = 1), the bead within one
/// interface width (2√2 ξ) of touching the interface.
fn check_bounded(c: &ContactRun, r_b: f64, xi: f64) {
    assert!(c.max_psi < 1.1, "max |psi| = {}", c.max_psi);
    assert!(c.mass_drift < 1e-12, "mean psi drift {:e}", c.mass_drift);
    assert!(
        c.height.abs() < r_b + 2.0 * 2f64.sqrt() * xi,
        "h = {}",
        c.height
    );
}

/// Hard cases, ψ0 = ±0.76 (Young's-law references 19.8° and 160.2° with the 1D wall
/// equilibria): the run stays bounded and conserves ψ. The angle is reported, not held to
/// the reference: with r_b / ξ = 4 the bead passes Young's height and leaves the interface
/// on the side it prefers (h > r_b, geometric angle 0° / 180° after 6000 steps; see
/// docs/validation/capillary.md).
#[test]
fn contact_angles_near_20_and_160_deg_stay_bounded() {
    for (affinity, near) in [(0.76, 20.0), (-0.76, 160.0)] {
        let c = contact_angle_run(affinity, 6000, &format!("capillary-hard-{affinity}"));
        println!(
            "psi0 = {affinity}: theta_A = {:.2} deg after 6000 steps, reference {:.2} \
             (off by {:+.2}), h = {:.3}, mean psi drift {:.1e}, max |psi| {:.4}",
            c.angle,
            c.reference,
            c.angle - c.reference,
            c.height,
            c.mass_drift,
            c.max_psi
        );
        assert!((c.reference - near).abs() < 1.0, "{}", c.reference);
        check_bounded(&c, 8.0, 2.0);
    }
}

/// In the range (references 40°–140°), ψ0 = 0.3: Young's angle 63.74°, reached
/// within 3° (63.96° after 8000 steps, still approaching from above).
#[test]
fn contact_angle_64_deg_within_3_deg() {
    let c = contact_angle_run(0.3, 8000, "capillary-angle-64");
    println!(
        "psi0 = 0.3: theta_A = {:.3} deg, reference {:.3}, h = {:.3}",
        c.angle, c.reference, c.height
    );
    check_bounded(&c, 8.0, 2.0);
    assert!((c.angle - c.reference).abs() < 3.0);
}

/// The low end of the range, ψ0 = 0.55 (Young's angle 40.20°), in the issue's own
/// scene (`contact_angle.toml`: r_b = 20, ξ = 3, ξ_c = 15, 128², η = 10) at dt = 1 instead of
/// 0.5 to halve the steps. Measured: θ_A = 41.60 / 40.58 / 40.31° at steps 45 000 / 60 000 /
/// 75 000, settling at about 40.2°. The equilibrium depends on dt (capillary.md, "Contact
/// angle at the issue's resolution": 38.66° at the scene's dt = 0.5 after 400 000 steps,
/// about 41.6° at dt = 2), by less than the 3°. Tolerance: the 3°, and the
/// bead settled (under 0.5° in the last 15 000 steps).
#[test]
fn contact_angle_40_deg_within_3_deg_at_the_scene_resolution() {
    let set: Vec<String> = [
        "fibre.0.affinity=0.55",
        "time.dt=1.0",
        "time.steps=75000",
        "output.interval=15000",
    ]
    .map(String::from)
    .to_vec();
    let test = "capillary-angle-40-scene";
    let s = run_in_process(&config("capillary/contact_angle.toml"), &set, test);
    assert_eq!(s["status"], "completed", "{s}");
    let m = &s["metrics"]["contact_angle_deg"];
    let (angle, reference) = (
        m["value"].as_f64().unwrap(),
        m["reference"].as_f64().unwrap(),
    );
    let dir = run_dir(test);
    let log = read_topic(&dir.join("run.mcap"), "/diagnostics").unwrap();
    let at = |i: usize| log[i]["contact_angle_deg"].as_f64().unwrap();
    let (before, last) = (at(log.len() - 2), at(log.len() - 1));
    println!(
        "theta_A = {angle:.3} deg (reference {reference:.3}), {before:.3} 15000 steps earlier"
    );
    assert!((reference - 40.2).abs() < 0.1, "{reference}");
    assert!((last - angle).abs() < 1e-9);
    assert!(
        (angle - reference).abs() < 3.0,
        "{angle} against {reference}"
    );
    assert!(
        (before - last).abs() < 0.5,
        "not settled: {before} -> {last}"
    );
    // The summary's own steadiness measure is this one: the change since step 60 000, the
    // start of the last fifth (coordinator/src/steady_watch.rs), within its 0.5 deg.
    let change = m["extra"]["change_over_last_fifth"].as_f64().unwrap();
    assert!((change - (before - last).abs()).abs() < 1e-12, "{change}");
    assert_eq!(s["warnings"], serde_json::json!([]));
}

/// The same angle with r_b = 8, ξ = 2 (r_b / ξ = 4, the small grid of the tests above): the
/// bead overshoots Young's height, 34.5° after 12000 steps and still falling.
#[test]
#[ignore = "fails: r_b / xi = 4 overshoots Young's angle at 40 deg (34.5 deg after 12000 steps; the scene's r_b / xi = 6.7 passes, test above); docs/validation/capillary.md"]
fn contact_angle_40_deg_within_3_deg_at_r_b_over_xi_4() {
    let c = contact_angle_run(0.55, 12000, "capillary-angle-40");
    println!(
        "psi0 = 0.55: theta_A = {:.3} deg, reference {:.3}, h = {:.3}",
        c.angle, c.reference, c.height
    );
    check_bounded(&c, 8.0, 2.0);
    assert!((c.angle - c.reference).abs() < 3.0);
}

/// Effects (issue: "a single-fluid scene spends no time in Cahn-Hilliard"): the SPM step of
/// a single fluid has no `fluid-phase-field` phase and no time spent in it; with
/// `[fluid.binary]` the phase runs first in every step.
#[test]
fn phase_field_runs_only_with_a_second_fluid() {
    let short = ["time.steps=5".to_string(), "output.interval=5".to_string()];
    let single = run_in_process(&config("spm/couette.toml"), &short, "single-fluid-effects");
    let binary = run_in_process(
        &config("capillary/flat_interface.toml"),
        &short,
        "binary-fluid-effects",
    );
    let phases = |s: &serde_json::Value| -> Vec<String> {
        s["schedule"]
            .as_array()
            .expect("schedule")
            .iter()
            .map(|p| p.as_str().expect("phase name").to_string())
            .collect()
    };
    let (a, b) = (phases(&single), phases(&binary));
    assert!(!a.iter().any(|p| p == "fluid-phase-field"), "{a:?}");
    assert!(single["seconds_per_phase"]
        .get("fluid-phase-field")
        .is_none());
    assert_eq!(
        b.first().map(String::as_str),
        Some("fluid-phase-field"),
        "{b:?}"
    );
    assert!(
        binary["seconds_per_phase"]["fluid-phase-field"]
            .as_f64()
            .unwrap()
            > 0.0
    );
}
