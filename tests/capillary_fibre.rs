//! Fibres at fluidic interfaces (L2020 sections 3.4-3.5), on small grids: the scenes of
//! `configs/capillary/` shrunk so that each test runs in well under a minute in release.
//! The paper-size numbers are in docs/validation/capillary.md.
mod common;
use common::*;

fn set(pairs: &[(&str, &str)]) -> Vec<String> {
    pairs.iter().map(|(k, v)| format!("{k}={v}")).collect()
}

fn diagnostic(summary: &serde_json::Value, key: &str) -> f64 {
    summary["final_diagnostics"][key]
        .as_f64()
        .unwrap_or_else(|| panic!("final diagnostic `{key}` missing: {summary}"))
}

/// Whether the summary warns that `metric` was read from a state still changing.
fn warns_not_steady(summary: &serde_json::Value, metric: &str) -> bool {
    summary["warnings"].as_array().is_some_and(|w| {
        w.iter().any(|w| {
            w.as_str()
                .is_some_and(|w| w.contains(&format!("`{metric}`")) && w.contains("not yet steady"))
        })
    })
}

/// Every final diagnostic is a finite number (no NaN or blow-up anywhere in the run: the
/// coordinator stops a run whose diagnostics go non-finite, and the status says so).
fn assert_bounded(summary: &serde_json::Value) {
    assert_eq!(summary["status"], "completed", "{summary}");
    for (k, v) in summary["final_diagnostics"].as_object().unwrap() {
        let x = v.as_f64().unwrap_or(f64::NAN);
        assert!(x.is_finite(), "final diagnostic {k} = {v}");
    }
    // The order parameter stays near its bulk values +-1 (the tanh profile with beads
    // overshoots slightly; a blow-up would not).
    let m = diagnostic(summary, "max_abs_psi");
    assert!(m < 1.2, "max |psi| = {m}");
}

/// L2020 section 3.4 (Fig. 9) on a 64^2 grid with N_b = 5 (tumbling_2d.toml has 128^2,
/// N_b = 9): a neutral fibre (psi0 = 0, Ec = 10) tilted by 50 degrees across a flat
/// interface ends aligned with it. Measured: 1.5 deg after t = 50000 (1.6 at time.dt = 2,
/// which the explicit exchange's stiffness check refuses since its flow share grows with
/// nu dt / xi^2: docs/validation/spm.md; this fibre runs there at 91 % of its measured
/// threshold step, the check accepts up to 1.89). Tolerance: L2020's "aligns", taken as
/// final_tilt_deg < 5.
/// Psi mass: the slab is symmetric, mean psi = 0, kept by the spectral step to round-off.
#[test]
fn tilted_fibre_aligns_with_a_flat_interface() {
    let s = run_in_process(
        &config("capillary/tumbling_2d.toml"),
        &set(&[
            ("fluid.grid", "[64, 64]"),
            ("fibre.0.beads", "5"),
            ("fluid.binary.position", "32.0"),
            // The centre (32, 32) - 24 (cos 50, sin 50).
            ("fibre.0.start", "[16.573097, 13.614933, 0.0]"),
            ("time.dt", "1.8"),
            ("time.steps", "27778"),
            ("output.interval", "5000"),
        ]),
        "capillary_tumbling_small",
    );
    assert_bounded(&s);
    let tilt = &s["metrics"]["final_tilt_deg"];
    let (value, initial) = (
        tilt["value"].as_f64().unwrap(),
        tilt["extra"]["initial_tilt_deg"].as_f64().unwrap(),
    );
    assert!((initial - 50.0).abs() < 1e-5, "initial tilt {initial}");
    assert!(value < 5.0, "final tilt {value} deg: {tilt}");
    // Still turning at the end: the tilt fell by 2.4 deg over the last fifth (from 3.9 deg),
    // past the 0.5 deg a steady state allows, and the summary says so
    // (coordinator/src/steady_watch.rs).
    let change = tilt["extra"]["change_over_last_fifth"].as_f64().unwrap();
    assert!(
        change > 0.5 && change < initial,
        "tilt change {change} deg: {tilt}"
    );
    assert!(warns_not_steady(&s, "final_tilt_deg"), "{}", s["warnings"]);
    let mean = diagnostic(&s, "mean_psi");
    assert!(mean.abs() < 1e-12, "mean psi drifted to {mean}");
}

/// The hard case of L2020 section 3.5 (Fig. 12, full wrap at low Ec) on a 128 x 100 grid:
/// N_b = 10, Ec = 1, a half-disk droplet of radius 28 (eq. 45 radius 17, circumference
/// about the fibre length 108). Eta = 1 (Re = 0.1) and dt = 2 for speed. The fibre closes
/// around the droplet (its end beads within 4 r_b: `wrap` = full; measured end-to-end 17
/// at t = 20000, R_c / R_droplet = 1.09) while nothing blows up and the mean of psi stays
/// at its initial value (the spectral Cahn-Hilliard step conserves it; tolerance 1e-12
/// relative, round-off).
#[test]
fn full_encapsulation_stays_bounded_and_conserves_psi() {
    let small = [
        ("fluid.grid", "[128, 100]"),
        ("fibre.0.beads", "10"),
        ("fibre.0.start", "[10.0, 40.0, 0.0]"),
        ("fluid.binary.centre", "[64.0, 46.0]"),
        ("fluid.binary.radius", "28.0"),
        ("fluid.viscosity", "1.0"),
        ("fibre.0.youngs_modulus", "0.0106103"),
        ("time.dt", "2.0"),
    ];
    // Mean psi after one step is the initial one (the step conserves it exactly).
    let mut one = small.to_vec();
    one.push(("time.steps", "1"));
    let first = run_in_process(
        &config("capillary/encapsulation_2d.toml"),
        &set(&one),
        "capillary_encapsulation_first",
    );
    let mut long = small.to_vec();
    long.extend([("time.steps", "10000"), ("output.interval", "5000")]);
    let s = run_in_process(
        &config("capillary/encapsulation_2d.toml"),
        &set(&long),
        "capillary_encapsulation_small",
    );
    assert_bounded(&s);
    let (m0, m1) = (diagnostic(&first, "mean_psi"), diagnostic(&s, "mean_psi"));
    assert!((m1 - m0).abs() <= 1e-12 * m0.abs(), "mean psi {m0} -> {m1}");
    let wrap = &s["metrics"]["wrap"];
    assert_eq!(wrap["label"], "full", "{wrap}");
    // Full, but the ends still close: w grew by 4.9 % over the last fifth, and the summary
    // says that the wrap is not yet steady; R_c had settled to 0.95 %.
    assert!(warns_not_steady(&s, "wrap"), "{}", s["warnings"]);
    assert!(!warns_not_steady(
        &s,
        "curvature_radius_over_droplet_radius"
    ));
    let ratio = &s["metrics"]["curvature_radius_over_droplet_radius"];
    let r = ratio["value"].as_f64().unwrap();
    // L2020 section 3.5: upon encapsulation R_c is "very close to the droplet radius"
    // (measured 1.09; the 20 % tolerance is our reading of "very close").
    assert!((r - 1.0).abs() < 0.2, "R_c / R_droplet = {r}: {ratio}");
}

/// Light beads under the explicit SPM exchange (fibre-node/src/spm_exchange.rs). The
/// tumbling scene's beads (r_b = 6, xi = 2, xi_c = 5, 2D) at density 0.8: the fluid in a
/// bead's profile has 1.985 / 0.8 = 2.482 times the sharp disc's moment of inertia, above the
/// limit 2, so the scene is refused before step 0 with the ratio and both cures named
/// (before the check, this run blew up at step 48 with the CFL error). With
/// `bead_inertia = "profile"` the ratio is 1 / 0.8 = 1.25 and the same beads run 2000 steps
/// bounded; so do they with their solid inertia under the implicit exchange
/// (`exchange = "implicit"`, fibre-node/src/fibre.rs), which has no such limit.
#[test]
fn light_beads_are_refused_or_given_the_inertia_of_their_profile() {
    let light = [
        ("fibre.0.density", "0.8"),
        ("time.steps", "2000"),
        ("output.interval", "1000"),
    ];
    let e = run_scene(
        "capillary_light_beads_refused",
        &config("capillary/tumbling_2d.toml"),
        &set(&light),
        &["--in-process"],
    )
    .unwrap_err();
    for s in [
        "2.482 times the bead's moment of inertia",
        "limit 2",
        "fibre.0.density to at least",
        "fibre.0.bead_inertia = \"profile\"",
        "fibre.0.exchange = \"implicit\"",
    ] {
        assert!(e.contains(s), "{s:?} missing from: {e}");
    }
    let mut implicit = light.to_vec();
    implicit.push(("fibre.0.exchange", "\"implicit\""));
    let s = run_in_process(
        &config("capillary/tumbling_2d.toml"),
        &set(&implicit),
        "capillary_light_beads_implicit_exchange",
    );
    assert_bounded(&s);
    let mut profile = light.to_vec();
    profile.push(("fibre.0.bead_inertia", "\"profile\""));
    let s = run_in_process(
        &config("capillary/tumbling_2d.toml"),
        &set(&profile),
        "capillary_light_beads_profile_inertia",
    );
    assert_bounded(&s);
    let ratio = s["derived"]["fibre.0.profile_to_bead_inertia"]
        .as_f64()
        .unwrap();
    assert!((ratio - 1.25).abs() < 1e-12, "{ratio}");
}
