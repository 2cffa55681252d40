//! The SPM coupling through the coordinator: fluid alone, fibre and fluid as three
//! processes, and the fibre model swapped against the same fluid-node binary.
mod common;
use common::*;
use coordinator::mcap_log::read_topic;

/// Couette flow between two moving walls: the steady profile is linear to within 1 % of the
/// wall-speed difference in the fluid region (reference: the linear profile).
#[test]
fn couette_profile_is_linear() {
    let s = run_in_process(&config("spm/couette.toml"), &[], "spm-couette");
    let err = s["metrics"]["couette_max_error"]["value"].as_f64().unwrap();
    println!("couette_max_error = {err:.3e}");
    assert!(
        err < 0.01,
        "Couette profile off by {:.2} % of the wall speed",
        100.0 * err
    );
    // Read from a steady flow: the error moved by less than 1e-3 over the last fifth
    // (coordinator/src/steady_watch.rs); 500 steps from rest are flagged.
    let change = s["metrics"]["couette_max_error"]["extra"]["change_over_last_fifth"]
        .as_f64()
        .unwrap();
    assert!(change < 1e-3, "{change}");
    let early = run_in_process(
        &config("spm/couette.toml"),
        &["time.steps=500".to_string()],
        "spm-couette-early",
    );
    let w = early["warnings"][0].as_str().unwrap_or_default();
    assert!(
        w.contains("`couette_max_error`") && w.contains("not yet steady"),
        "{early}"
    );
    let effects: Vec<&str> = s["effects"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|e| e.as_str())
        .collect();
    assert_eq!(
        effects,
        ["hydrodynamics", "walls"],
        "a fluid-only scene runs no fibre effects"
    );
}

/// A short coupled run on a small grid (fibre in shear).
fn small_shear(model: &str) -> Vec<String> {
    let mut o = vec![
        "fluid.grid=[64,64]".to_string(),
        "walls.velocity=[-0.28,0.28]".into(),
        // gamma = 0.01; k0 / (L0 eta gamma) = 75e3 as in the scene.
        "fibre.0.youngs_modulus=79.58".into(),
        "time.dt=0.25".into(),
        "fibre.0.beads=4".into(),
        "fibre.0.bead_radius=4.0".into(),
        "fibre.0.start=[32.0,20.0,0.0]".into(),
        "time.steps=60".into(),
        "output.interval=10".into(),
        "analysis.metrics=[]".into(),
        format!("fibre.0.model={model}"),
        // With bead density equal to the fluid's, chains of small beads (r_b = 4, xi = 1) are
        // unstable under the explicit SPM coupling after ~10-300 steps (issue 3 notes); 1.5
        // runs stably.
        "fibre.0.density=1.5".into(),
    ];
    if model == "bead-spring" {
        o.push("fibre.0.substeps=8".into());
    }
    o
}

fn run_cli(name: &str, overrides: &[String], extra: &[&str]) -> std::path::PathBuf {
    run_scene(name, &config("spm/jeffery_rigid.toml"), overrides, extra)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Three processes (coordinator, fibre node, fluid node) and one process give the same bits.
#[test]
fn coupled_run_is_identical_as_processes_and_in_process() {
    let o = small_shear("cohesive-beam");
    let a = run_cli("spm-layout-processes", &o, &[]);
    let b = run_cli("spm-layout-in-process", &o, &["--in-process"]);
    let sa = read_topic(&a.join("run.mcap"), "/fibre/bead_states").unwrap();
    let sb = read_topic(&b.join("run.mcap"), "/fibre/bead_states").unwrap();
    assert_eq!(sa.len(), 7);
    assert_eq!(sa, sb, "bead trajectories differ between process layouts");
    let da = read_topic(&a.join("run.mcap"), "/diagnostics").unwrap();
    let db = read_topic(&b.join("run.mcap"), "/diagnostics").unwrap();
    assert_eq!(
        da, db,
        "diagnostics (fluid energies, impulses) differ between layouts"
    );
    // The beads moved: the coupling did something.
    let x0 = sa[0]["states"][0][0].as_f64().unwrap();
    let x1 = sa[6]["states"][0][0].as_f64().unwrap();
    assert!(
        (x1 - x0).abs() > 1e-6,
        "the fibre did not move in the shear flow"
    );
}

/// Swap the fibre model in the scene; the same fluid-node executable serves both.
#[test]
fn fibre_models_swap_against_the_same_fluid_binary() {
    let fluid = bin_dir().join("fluid-node");
    let before = std::fs::metadata(&fluid).unwrap().modified().unwrap();
    for model in ["cohesive-beam", "bead-spring"] {
        let out = run_cli(&format!("spm-swap-{model}"), &small_shear(model), &[]);
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["status"], "completed", "{model}: {summary}");
        assert_eq!(summary["process_layout"], "processes");
    }
    let after = std::fs::metadata(&fluid).unwrap().modified().unwrap();
    assert_eq!(before, after, "the fluid-node binary was rebuilt");
}

/// Drag on a fixed body in a periodic array against Sangani & Acrivos (2D cylinders, c = 0.1)
/// and Zick & Homsy (3D spheres, c = 0.125), nominal radius, nu dt / xi^2 = 0.7: within 5 %.
/// The dependence on nu dt / xi^2 is documented in the scenes and fluid-node/tests/drag.rs.
#[test]
fn periodic_array_drag_2d_and_3d() {
    for scene in ["spm/array_drag_2d.toml", "spm/array_drag_3d.toml"] {
        let s = run_in_process(
            &config(scene),
            &[],
            &format!("drag-{}", scene.replace('/', "-")),
        );
        let (ratio, _) = metric(&s, "drag_ratio");
        println!("{scene}: drag / reference = {ratio:.4}");
        assert!((ratio - 1.0).abs() < 0.05, "{scene}: drag ratio {ratio}");
        let change = s["metrics"]["drag_ratio"]["extra"]["change_over_last_fifth"]
            .as_f64()
            .unwrap();
        assert!(change < 1e-3, "{scene}: {change}");
        assert_eq!(s["warnings"], serde_json::json!([]), "{scene}");
    }
}

/// The same 2D array stopped at step 300 of its 6000, while the flow still spins up: its
/// drag ratio happens to lie within 0.1 % of the reference, but what it reads changes by
/// more than 1 % over the last fifth, and the summary warns (coordinator/src/steady_watch.rs).
#[test]
fn a_drag_read_before_the_flow_is_steady_is_flagged() {
    let o = vec!["time.steps=300".to_string()];
    let s = run_in_process(&config("spm/array_drag_2d.toml"), &o, "drag-not-steady");
    let m = &s["metrics"]["drag_ratio"];
    let change = m["extra"]["change_over_last_fifth"].as_f64().unwrap();
    assert!(change > 0.01, "{m}");
    assert!(m["note"].as_str().unwrap().starts_with("not steady"), "{m}");
    let w = s["warnings"][0].as_str().unwrap();
    assert!(
        w.contains("the run is not yet steady; raise time.steps"),
        "{w}"
    );
    // docs/summary.md documents every key of the summary and of a metric.
    let doc = std::fs::read_to_string(root().join("docs").join("summary.md")).unwrap();
    let keys = s
        .as_object()
        .unwrap()
        .keys()
        .chain(m.as_object().unwrap().keys());
    for k in keys {
        assert!(
            doc.contains(&format!("`{k}`")),
            "docs/summary.md lacks `{k}`"
        );
    }
}

/// Hard case (issue: stability): a stiff fibre, k0 / (L0 eta gamma) = 1e6, in shear with
/// sub-cycling (the fibre node asks for at least 5 sub-steps) runs 20 000 steps: nothing turns
/// NaN (the coordinator stops a run on any non-finite diagnostic) and the elastic energy
/// stays bounded: its maximum over the second half is no larger than twice that over the
/// first half. The fibre's bonds carry Kelvin-Voigt damping, tau = 0.005 (a tenth of a
/// sub-step; the fastest bending mode loses ~0.3 of its amplitude per fluid step, the
/// tumbling is not damped); without it see the ignored test below.
#[test]
fn stiff_fibre_in_shear_with_subcycling_stays_bounded() {
    stiff_fibre_run(0.005, "explicit");
}

/// The hard case's overrides: `small_shear`'s beam at k0 / (L0 eta gamma) = 1e6 with five
/// sub-steps, 20 000 steps.
fn stiff_fibre_overrides(internal_damping: f64, exchange: &str) -> Vec<String> {
    let mut o = small_shear("cohesive-beam");
    // gamma = 0.56 / 56 = 0.01, k0 = pi r_b E / 2 = 1e6 eta gamma L0 -> E = 1591.5.
    o.retain(|s| !s.starts_with("time.steps") && !s.starts_with("output.interval"));
    o.extend([
        "fibre.0.youngs_modulus=1591.5".into(),
        "fibre.0.substeps=5".into(),
        format!("fibre.0.internal_damping={internal_damping}"),
        format!("fibre.0.exchange=\"{exchange}\""),
        "time.steps=20000".into(),
        "output.interval=200".into(),
    ]);
    o
}

fn stiff_fibre_run(internal_damping: f64, exchange: &str) {
    let o = stiff_fibre_overrides(internal_damping, exchange);
    let cfg = config("spm/jeffery_rigid.toml");
    let name = format!(
        "spm-stiff-{}-{exchange}",
        (internal_damping * 1e3).round() as u32
    );
    let out = out_dir(&name);
    let s = run_in_process(&cfg, &o, &name);
    assert_eq!(s["status"], "completed", "{s}");
    let k = s["derived"]["fluid.k0_over_l0_eta_gamma"].as_f64().unwrap();
    assert!((k / 1e6 - 1.0).abs() < 1e-3, "k0 / (L0 eta gamma) = {k}");
    let d = read_topic(&out.join("run.mcap"), "/diagnostics").unwrap();
    let e: Vec<f64> = d
        .iter()
        .map(|v| v["elastic_energy"].as_f64().unwrap())
        .collect();
    assert!(e.iter().all(|x| x.is_finite()));
    let half = e.len() / 2;
    let first = e[..half].iter().cloned().fold(0.0, f64::max);
    let second = e[half..].iter().cloned().fold(0.0, f64::max);
    println!("max elastic energy: first half {first:.3e}, second half {second:.3e}");
    assert!(
        second <= 2.0 * first + 1e-12,
        "elastic energy grows: {first:.3e} -> {second:.3e}"
    );
}

/// The same without internal damping under the explicit exchange: the once-per-step impulse
/// samples the stiff chain's fast vibration (omega dt up to 6.9) and feeds it; run, it blew
/// up at step ~245 (max|u| dt > 1) with 5, 10 or 20 sub-steps alike. It is refused before
/// step 0 (fibre-node/src/spm_exchange_stiffness.rs), naming the growing mode, the limit and
/// the cures. The implicit exchange (next test) runs it, and so does internal damping.
#[test]
fn stiff_fibre_in_shear_without_internal_damping_is_refused_before_step_0() {
    let o = stiff_fibre_overrides(0.0, "explicit");
    let name = "spm-stiff-0-explicit";
    let e = run_scene(
        name,
        &config("spm/jeffery_rigid.toml"),
        &o,
        &["--in-process"],
    )
    .expect_err("the explicit undamped hard case must be refused");
    for s in [
        "fibre.0 is too stiff for the explicit SPM momentum exchange at time.dt = 0.25",
        "fibre.0.exchange = \"implicit\"",
        "fibre.0.internal_damping = ",
        "lower time.dt to at most",
    ] {
        assert!(e.contains(s), "{s:?} missing from: {e}");
    }
    // Refused before step 0: no step was taken, and nothing was written into --out.
    let dir = run_dir(name);
    assert!(!dir.join("summary.json").exists() && !dir.join("run.mcap").exists());
}

/// The same undamped chain with the implicit exchange (`fibre.0.exchange = "implicit"`,
/// fibre-node/src/fibre.rs): the fluid's drag acts on the bead velocities it produces, so it
/// damps the vibration instead of feeding it. Measured: largest elastic energy 1.39e-4 over
/// the first half, 1.36e-4 over the second (with damping instead: 1.39e-4, 1.33e-4).
#[test]
fn stiff_fibre_with_the_implicit_exchange_stays_bounded_without_damping() {
    stiff_fibre_run(0.0, "implicit");
}

/// The summary of a run of bead radius 4 warns once, naming `fibre.0.{key} = true`, exactly
/// when the contact was off and the largest overlap passed a hundredth of the radius
/// (coordinator/src/overlap_watch.rs).
fn assert_one_warning_without_contact(
    s: &serde_json::Value,
    contact: bool,
    largest: f64,
    key: &str,
) {
    let warned = s["warnings"].as_array().unwrap();
    assert_eq!(warned.len(), usize::from(!contact && largest > 0.04), "{s}");
    if let Some(w) = warned.first() {
        let text = format!("fibre.0.{key} = true");
        assert!(w.as_str().unwrap().contains(&text), "{w}");
    }
}

/// The K = 0.01 coil of S2023's Fig. 7 scene at C = 0.87 under SPM
/// (`configs/spm/s2023_fig7_chord.toml`, r_b = 4), 12 000 steps: the fibre buckles and folds,
/// and nothing keeps its beads apart, so two of them pass into each other (measured: the
/// `self_overlap` diagnostic 0.85 grid spacings by step 12 000, 7.6 of the diameter 8 over
/// the whole run). With `fibre.0.self_contact = true` they stay apart (0.016 at most over
/// the whole run). S2023 report that their FPD beads never overlapped; ours under FPD do not
/// either (docs/validation/spm.md, "Beads passing through each other"). Reference: the
/// beads' spheres, from the logged bead states. Tolerances: without contact the overlap must
/// pass a tenth of the radius, with it stay below a hundredth; the summary's largest value
/// (every step) is at least the largest in the log (every 500 steps).
#[test]
fn self_overlap_is_reported_and_kept_down_by_self_contact() {
    let run = |contact: bool| {
        let o = overrides(
            &[
                "fibre.0.bending_number=0.01",
                "fluid.confinement=0.87",
                "time.steps=12000",
                "output.interval=500",
                "analysis.metrics=[]",
            ],
            &[format!("fibre.0.self_contact={contact}")],
        );
        let name = format!("spm-self-overlap-{contact}");
        let s = run_in_process(&config("spm/s2023_fig7_chord.toml"), &o, &name);
        assert_eq!(s["status"], "completed", "{s}");
        let log = run_dir(&name).join("run.mcap");
        // The deepest overlap of beads i, j >= i + 2 in the logged states (r_b = 4).
        let mut from_states: f64 = 0.0;
        for m in read_topic(&log, "/fibre/bead_states").unwrap() {
            let b = bead_xy(&m);
            for i in 0..b.len() {
                for j in i + 2..b.len() {
                    let d = (b[i].0 - b[j].0).hypot(b[i].1 - b[j].1);
                    from_states = from_states.max(8.0 - d);
                }
            }
        }
        let logged = read_topic(&log, "/diagnostics")
            .unwrap()
            .iter()
            .map(|v| v["self_overlap"].as_f64().unwrap())
            .fold(0.0, f64::max);
        assert!(
            (logged - from_states.max(0.0)).abs() < 1e-9,
            "{logged} vs {from_states}"
        );
        let largest = s["largest_self_overlap"]["value"].as_f64().unwrap();
        assert!(largest >= logged, "{largest} vs {logged}");
        assert_one_warning_without_contact(&s, contact, largest, "self_contact");
        largest
    };
    let free = run(false);
    let held = run(true);
    println!("largest self overlap: free {free:.4}, with self contact {held:.5}");
    assert!(
        free > 0.4,
        "without contact the beads overlapped only {free}"
    );
    assert!(held < 0.04, "with contact the beads overlapped {held}");
}

/// A loaded fibre pressed onto a held one (`configs/spm/fibres_resting.toml`: 2D SPM, fluid
/// at rest, 3-bead cohesive beams of radius 3, a load F = 0.005 on each bead of the upper
/// one), 8000 steps. With `fibre.N.fibre_contact` on both it comes to rest on the held fibre,
/// each bead on the one below, and the contact spring k_c = pi E r_b / 2 (the axial bond
/// stiffness, L2020 eq. 11) is compressed by F / k_c = 0.10610 (measured 0.106115 at step
/// 8000, 0.1061033 at 30 000). Reference: the static balance F = k_c delta; tolerance 1e-3
/// relative (what is left of the settling). The logged bead states give the same overlap,
/// and the three-process run the same bits. Without the contact the upper fibre falls
/// through the held one at about 4e-4 grid spacings a step (2.4 deep by step 8000; measured
/// to pass clean through by step 17 000), and the summary warns.
#[test]
fn a_fibre_rests_on_another_through_the_contact_between_fibres() {
    let cfg = config("spm/fibres_resting.toml");
    let common = ["time.steps=8000", "output.interval=1000"];
    let on = run_in_process(&cfg, &overrides(&common, &[]), "spm-fibres-resting");
    assert_eq!(on["status"], "completed", "{on}");
    let settled = on["final_diagnostics"]["fibre_overlap"].as_f64().unwrap();
    let want = 0.005 / (std::f64::consts::PI * 0.01 * 3.0 / 2.0);
    println!("fibre overlap at rest: {settled:.6} (F / k_c = {want:.6})");
    assert!((settled / want - 1.0).abs() < 1e-3, "{settled} vs {want}");
    assert_one_warning_without_contact(&on, true, settled, "fibre_contact");
    // The last logged states: fibre 0 is beads 0-2, fibre 1 beads 3-5.
    let log = run_dir("spm-fibres-resting").join("run.mcap");
    let states = read_topic(&log, "/fibre/bead_states").unwrap();
    let b = bead_xy(states.last().unwrap());
    let mut from_states = f64::NEG_INFINITY;
    for p in &b[..3] {
        for q in &b[3..] {
            from_states = from_states.max(6.0 - (p.0 - q.0).hypot(p.1 - q.1));
        }
    }
    assert!(
        (from_states - settled).abs() < 1e-9,
        "{from_states} vs {settled}"
    );
    // Three processes: the same bits.
    let dir = run_scene(
        "spm-fibres-resting-processes",
        &cfg,
        &overrides(&common, &[]),
        &[],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let processes = summary(&dir);
    assert_eq!(
        processes["final_diagnostics"], on["final_diagnostics"],
        "three processes against one"
    );
    assert_eq!(
        processes["largest_fibre_overlap"],
        on["largest_fibre_overlap"]
    );
    // Without the contact.
    let off = [
        "fibre.0.fibre_contact=false".to_string(),
        "fibre.1.fibre_contact=false".to_string(),
    ];
    let s = run_in_process(&cfg, &overrides(&common, &off), "spm-fibres-through");
    let through = s["largest_fibre_overlap"]["value"].as_f64().unwrap();
    assert!(
        through > 2.0,
        "without contact the fibres overlapped only {through}"
    );
    assert_one_warning_without_contact(&s, false, through, "fibre_contact");
    let w = s["warnings"][0].as_str().unwrap();
    assert!(w.contains("fibre.1.fibre_contact = true"), "{w}");
}

/// Two short fibres meeting end to end in the built-in example's Couette flow
/// (`configs/spm/fibres_in_shear.toml`), 12 000 steps. The SPM fluid between them does not
/// keep them apart: without `fibre.N.fibre_contact` their near beads sink 6.90 of their
/// diameter 8 into each other (measured, step 11 445) and the pair turns as one body. With
/// the contact they touch, 0.016 deep at most (0.4 % of the radius). Reference: the beads'
/// spheres. Tolerances: without contact past half the radius, with it below a hundredth of
/// it (the summary's warning threshold).
#[test]
fn fibres_meeting_in_shear_sink_into_each_other_unless_the_contact_holds_them() {
    let run = |contact: bool| {
        let o = overrides(
            &["time.steps=12000"],
            &[
                format!("fibre.0.fibre_contact={contact}"),
                format!("fibre.1.fibre_contact={contact}"),
            ],
        );
        let name = format!("spm-fibres-in-shear-{contact}");
        let s = run_in_process(&config("spm/fibres_in_shear.toml"), &o, &name);
        assert_eq!(s["status"], "completed", "{s}");
        let largest = s["largest_fibre_overlap"]["value"].as_f64().unwrap();
        assert_one_warning_without_contact(&s, contact, largest, "fibre_contact");
        largest
    };
    let (free, held) = (run(false), run(true));
    println!("largest fibre overlap: free {free:.4}, with the contact {held:.5}");
    assert!(
        free > 2.0,
        "without contact the fibres overlapped only {free}"
    );
    assert!(held < 0.04, "with contact the fibres overlapped {held}");
}

/// A fibre lying along the bottom wall of the built-in example (`configs/spm/tumbling.toml`,
/// 96^2, slabs of 4: face at y = 3.5), bead 0 touching it (y = 7.5 + 0.5), 14 000 steps.
/// Nothing in SPM keeps a bead out of a wall slab: the fibre tilts and its leading end sinks
/// into the wall, 0.76 grid units by step 14 000 and 2.08 by step 40 000 (measured). With
/// `fibre.0.wall_contact = true` the contact spring (the axial bond stiffness,
/// pi E r_b / 2 = 2.94) holds it at the face: measured 0.0032 at most here, 0.0046 over
/// 80 000 steps, while the other end rises off the wall. Reference: the wall's face, from the geometry.
/// Tolerances: without contact the bead must reach 0.5 past the face (an eighth of its
/// radius), with it stay within 0.02 (a two-hundredth).
#[test]
fn wall_contact_keeps_a_bead_out_of_the_wall_slab() {
    let run = |contact: bool| {
        let o = overrides(
            &[
                "fibre.0.start=[20.0,8.0,0.0]",
                "fibre.0.direction=[1.0,0.0,0.0]",
                "time.steps=14000",
                "output.interval=200",
                "output.fields_interval=0",
                "analysis.metrics=[]",
            ],
            &[format!("fibre.0.wall_contact={contact}")],
        );
        let name = format!("spm-wall-contact-{contact}");
        let s = run_in_process(&config("spm/tumbling.toml"), &o, &name);
        assert_eq!(s["status"], "completed", "{s}");
        let log = run_dir(&name).join("run.mcap");
        let d = read_topic(&log, "/diagnostics").unwrap();
        let deepest = d
            .iter()
            .map(|v| v["wall_overlap"].as_f64().unwrap())
            .fold(0.0, f64::max);
        let contact_energy = d
            .iter()
            .map(|v| v["contact_energy"].as_f64().unwrap())
            .fold(0.0, f64::max);
        // The overlap measured again from the logged bead states (r_b = 4, face at 3.5).
        let states = read_topic(&log, "/fibre/bead_states").unwrap();
        let lowest = states
            .iter()
            .flat_map(|m| bead_xy(m).into_iter().map(|(_, y)| y))
            .fold(f64::INFINITY, f64::min);
        assert!(lowest.is_finite());
        // The summary keeps the largest overlap of every step, not only of the logged ones,
        // and warns past a hundredth of the radius without the contact, a tenth with it
        // (coordinator/src/overlap_watch.rs).
        let largest = s["largest_wall_overlap"]["value"].as_f64().unwrap();
        assert!(
            largest >= deepest && largest < deepest + 0.05,
            "{largest} vs {deepest}"
        );
        assert_one_warning_without_contact(&s, contact, largest, "wall_contact");
        (deepest, 4.0 - (lowest - 3.5), contact_energy)
    };
    let (free, free_states, free_energy) = run(false);
    let (held, held_states, held_energy) = run(true);
    println!("largest overlap with the wall: free {free:.4} ({free_states:.4} from the states), with contact {held:.5} ({held_states:.5})");
    assert!(free > 0.5, "without contact the bead sank only {free}");
    assert!((free - free_states).abs() < 1e-9, "{free} vs {free_states}");
    assert_eq!(free_energy, 0.0, "no contact energy without contact");
    assert!(held < 0.02, "with contact the bead sank {held}");
    assert!(held > 0.0 && held_energy > 0.0, "the contact never acted");
}

/// The 3D Jeffery orbit at CI size: `jeffery_rigid_3d.toml` shrunk to two beads (r_b = 4,
/// 48 x 64 x 32, gap 56, C = 0.29, rho gamma L_c^2 / eta = 0.5, k0 / (L0 eta gamma) = 75e3,
/// 1900 steps, about 10 s), against the same rigid pair of touching spheres in unbounded 3D
/// Stokes flow (coordinator/src/reference/stokes_chain_3d.rs, gamma T = 15.61). With the
/// explicit exchange this stiff pair fails the CFL check at step 19 (spm.md, "Stiff chains
/// under the explicit coupling"), so it runs with the implicit one, which gives the same
/// periods in 2D (18.340 against 18.327). Measured 14.77 (-5.4 %): at r_b = 4 the 3D SPM
/// chains turn faster than the Stokes chain (-9.2 % for three beads, -5.1 % at r_b = 6;
/// spm.md, "Jeffery orbit in 3D"). Tolerance 10 %, the for the Jeffery periods.
/// The same pair as a bead-spring chain with `bead_spin = "chord"` (beads turned with their
/// bond) must tumble as the beam does: measured 14.760 against 14.766, tolerance 1 %. (With
/// free spins the pair rolls and tumbles in 23.1, +48 %: spm.md.)
#[test]
fn jeffery_period_of_a_two_sphere_chain_against_3d_stokes() {
    let o = [
        "fibre.0.beads=2",
        "fluid.grid=[48,64,32]",
        "walls.velocity=[-0.21875,0.21875]",
        "fibre.0.youngs_modulus=93.3",
        "fibre.0.start=[24.0,28.0,16.0]",
        "fibre.0.exchange=\"implicit\"",
        "time.steps=1900",
    ];
    let b = coordinator::reference::stokes_chain_3d::chain_bretherton(2);
    let stokes = coordinator::reference::stokes_chain_3d::period_gamma(b);
    let t = jeffery_period("spm/jeffery_rigid_3d.toml", &o, "spm-jeffery-3d-2", stokes);
    println!("3D, N_b = 2: gamma T = {t:.4}, 3D Stokes {stokes:.4}");
    assert!((t / stokes - 1.0).abs() < 0.10, "gamma T {t} vs {stokes}");
    let chord = [
        &o[..],
        &[
            "fibre.0.model=\"bead-spring\"",
            "fibre.0.bead_spin=\"chord\"",
        ],
    ]
    .concat();
    let name = "spm-jeffery-3d-2-chord";
    let c = jeffery_period("spm/jeffery_rigid_3d.toml", &chord, name, stokes);
    println!("3D, N_b = 2, bead-spring turned with its chord: gamma T = {c:.4}");
    assert!(
        (c / t - 1.0).abs() < 0.01,
        "chord-locked gamma T {c} vs the beam's {t}"
    );
}

/// A pair tilted 45 degrees out of the shear plane, towards the vorticity axis, so that its
/// beads spin about their bond as well as across it: the part `bead_spin = "chord"` leaves
/// free (fibre/chord_spin.rs). Jeffery (1922): an axisymmetric body in Stokes shear spins
/// about its axis p at half the vorticity's component along it, omega . p = -gamma p_z / 2
/// here (u_x = gamma y, vorticity -gamma z). The chord-locked bead-spring pair must keep to
/// that within 0.01 gamma from step 100 on (measured within 0.002 gamma; a bead that kept
/// only its chord's rate would have omega . p = 0, off by 0.24-0.35 gamma), and follow the
/// cohesive beam's orbit: direction within 2e-3 and bead angular velocities within 0.01 gamma
/// of the beam's over 600 steps (measured 4e-4 and 1e-3 gamma; free rollers drift 0.06 off by
/// step 100 and turn towards the flow).
#[test]
fn a_tilted_chord_locked_pair_spins_about_its_bond_as_jeffery_and_the_beam_say() {
    tilted_chord_chain_against_jeffery_and_the_beam(2, "[24.0,28.0,20.0]", "spm-tilted-pair", 2e-3);
}

/// The same with three beads, so that the middle one is interior: `fibre/chord_spin.rs`
/// splits its angular impulse between its two bonds, half each, and turns it at the mean rate
/// of both (at an end, all to the one bond); the chain stays straight, so both rates agree
/// and what this checks is the split. Same references and tolerances, except direction
/// within 3e-3 of the beam's (measured 1.2e-3, largest at step 100). Measured over 600 steps:
/// omega . p within 0.0026 gamma of Jeffery's (the middle bead; the ends within 0.0022), bead
/// angular velocities within 2.3e-3 gamma of the beam's. A middle bead that passed all of its
/// angular impulse to each bond (w = 1) fails at step 100 (direction 0.011 off the beam's).
#[test]
fn a_tilted_chord_locked_three_bead_chain_spins_about_its_axis_as_jeffery_and_the_beam_say() {
    tilted_chord_chain_against_jeffery_and_the_beam(
        3,
        "[24.0,26.0,18.0]",
        "spm-tilted-three",
        3e-3,
    );
}

/// A chain of `beads` tilted 45 degrees from the shear plane towards the vorticity, bead 0 at
/// `start` (midpoint near the centre of the gap), run as a cohesive beam and as a chord-locked
/// bead-spring chain (runs `{name}-beam`, `{name}-chord`): every bead's spin about the chain's
/// axis against Jeffery's, and each bead's angular velocity and the axis against the beam's
/// (`turn`: largest component of the difference in direction allowed).
fn tilted_chord_chain_against_jeffery_and_the_beam(
    beads: usize,
    start: &str,
    name: &str,
    turn: f64,
) {
    let beads_key = format!("fibre.0.beads={beads}");
    let start_key = format!("fibre.0.start={start}");
    let o = [
        beads_key.as_str(),
        "fluid.grid=[48,64,48]",
        "walls.velocity=[-0.21875,0.21875]",
        "fibre.0.youngs_modulus=93.3",
        start_key.as_str(),
        "fibre.0.direction=[0.0,0.70710678,0.70710678]",
        "fibre.0.exchange=\"implicit\"",
        "time.steps=600",
        "output.interval=100",
    ];
    let cfg = config("spm/jeffery_rigid_3d.toml");
    let run = |extra: &[&str], name: &str| {
        let o: Vec<String> = o.iter().chain(extra).map(|s| s.to_string()).collect();
        let summary = run_in_process(&cfg, &o, name);
        let states = read_topic(&run_dir(name).join("run.mcap"), "/fibre/bead_states");
        (summary, states.unwrap())
    };
    let (summary, beam) = run(&[], &format!("{name}-beam"));
    let gamma = summary["derived"]["fluid.shear_rate"].as_f64().unwrap();
    let (_, chord) = run(
        &[
            "fibre.0.model=\"bead-spring\"",
            "fibre.0.bead_spin=\"chord\"",
        ],
        &format!("{name}-chord"),
    );
    assert_eq!(beam.len(), 7);
    assert_eq!(chord.len(), 7);
    let row = |m: &serde_json::Value, b: usize| -> Vec<f64> {
        let r = m["states"][b].as_array().unwrap();
        r.iter().map(|v| v.as_f64().unwrap()).collect()
    };
    let axis = |m: &serde_json::Value| -> [f64; 3] {
        let (a, b) = (row(m, 0), row(m, beads - 1));
        let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        [d[0] / n, d[1] / n, d[2] / n]
    };
    for (mb, mc) in beam.iter().zip(&chord).skip(1) {
        let step = mc["step"].as_u64().unwrap();
        let (pb, pc) = (axis(mb), axis(mc));
        let off = (0..3).map(|k| (pb[k] - pc[k]).abs()).fold(0.0, f64::max);
        assert!(
            off < turn,
            "step {step}: direction {pc:?}, the beam's {pb:?}"
        );
        for bead in 0..beads {
            let (wb, wc) = (&row(mb, bead)[10..13], &row(mc, bead)[10..13]);
            let spin: f64 = (0..3).map(|k| wc[k] * pc[k]).sum();
            let jeffery = -0.5 * gamma * pc[2];
            println!(
                "step {step}, bead {bead}: omega . p = {:.4} gamma, Jeffery {:.4}",
                spin / gamma,
                jeffery / gamma
            );
            assert!(
                (spin - jeffery).abs() < 0.01 * gamma,
                "step {step}, bead {bead}: omega . p = {spin}, Jeffery's {jeffery}"
            );
            for k in 0..3 {
                assert!(
                    (wb[k] - wc[k]).abs() < 0.01 * gamma,
                    "step {step}, bead {bead}: omega {wc:?}, the beam's {wb:?}"
                );
            }
        }
    }
}

/// `tumbling_period_gamma` of `cfg` with the overrides `o`, in-process, after checking that
/// its reference is `stokes`.
fn jeffery_period(cfg: &str, o: &[&str], name: &str, stokes: f64) -> f64 {
    let o: Vec<String> = o.iter().map(|s| s.to_string()).collect();
    let s = run_in_process(&config(cfg), &o, name);
    let (t, reference) = metric(&s, "tumbling_period_gamma");
    assert_eq!(reference, stokes);
    t
}

/// `jeffery_rigid.toml` at N_b = 3 (the overrides of docs/validation/spm.md).
const JEFFERY_THREE_BEADS: [&str; 5] = [
    "fibre.0.beads=3",
    "walls.velocity=[-0.07465278,0.07465278]",
    "fibre.0.youngs_modulus=6.90772569",
    "time.steps=19428",
    "fibre.0.start=[90.0,78.0,0.0]",
];

/// L2020 Fig. 7 at N_b = 3: `jeffery_rigid.toml` with the overrides of docs/validation/spm.md
/// (180^2, r_b = 6, rho gamma L_c^2 / eta = 0.5, 19 428 steps, about 30 s): the full Jeffery
/// period against the same rigid chain in unbounded 2D Stokes flow
/// (coordinator/src/reference/stokes_chain_2d.rs). Measured 18.327 against 18.366 (-0.2 %);
/// tolerance 5 %, the size of the confinement and inertia effects over N_b = 3-9 (spm.md).
#[test]
fn jeffery_period_of_a_three_bead_chain_against_2d_stokes() {
    let o = JEFFERY_THREE_BEADS;
    let b = coordinator::reference::stokes_chain_2d::chain_bretherton(3);
    let stokes = coordinator::reference::stokes_chain_2d::period_gamma(b);
    let t = jeffery_period("spm/jeffery_rigid.toml", &o, "spm-jeffery-3", stokes);
    println!("N_b = 3: gamma T = {t:.4}, 2D Stokes {stokes:.4}");
    assert!((t / stokes - 1.0).abs() < 0.05, "gamma T {t} vs {stokes}");
}

/// Largest distance of a bead from the end-to-end line, and end-to-end distance, per logged
/// state (2D, grid spacings).
fn chord_shape(dir: &std::path::Path) -> Vec<(f64, f64)> {
    read_topic(&dir.join("run.mcap"), "/fibre/bead_states")
        .unwrap()
        .iter()
        .map(|s| {
            let xs = bead_xy(s);
            let (a, b) = (xs[0], xs[xs.len() - 1]);
            let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
            let off = xs
                .iter()
                .map(|p| ((b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)).abs() / len)
                .fold(0.0, f64::max);
            (off, len)
        })
        .collect()
}

/// `flexible_shear.toml` (L2020's flexible fibre) started 0.6 deg off the compressional axis
/// with an S-shaped seed of 0.5 grid spacings, turned through the quadrant (12 000 steps,
/// in-process), with the overrides `extra`: its output folder.
fn seeded_compressional_run(name: &str, extra: &[&str]) -> std::path::PathBuf {
    let mut o: Vec<String> = [
        "fibre.0.initial_bend=0.5",
        "fibre.0.start=[128.58,52.22,0.0]",
        "fibre.0.direction=[-0.7145,0.6997,0.0]",
        "time.steps=12000",
        "output.interval=500",
        "analysis.metrics=[\"min_end_to_end_over_length\"]",
    ]
    .map(String::from)
    .to_vec();
    o.extend(extra.iter().map(|s| s.to_string()));
    run_scene(
        name,
        &config("spm/flexible_shear.toml"),
        &o,
        &["--in-process"],
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Buckling in the compressional quadrant (the snaking of L2020 Fig. 6), seeded: a 10-bead
/// fibre (flexible_shear.toml: r_b = 6, 180^2, gamma = 1.389e-4) starts 0.6 deg off the
/// compressional axis with an S-shaped offset of 0.5 grid spacings (`fibre.0.initial_bend`)
/// and turns through the quadrant (12 000 steps). Reference: slender-body theory puts the
/// onset of buckling in shear at eta gamma L^4 / (E I) of order 300 (Becker & Shelley 2001).
/// - Far above it (bead-spring, k_b = 9.6e-4, S2023's K = 1e-3: eta gamma L^4 / (E I) =
///   2.4e6) the seed grows: measured 0.49 -> 4.46 grid spacings off the chord, end-to-end
///   down to 0.984. Tolerance: grows at least 4-fold, end-to-end below 0.99.
/// - Below it (cohesive beam at L2020's flexible k0 / (L0 eta gamma) = 15e3: 84) the seed
///   decays: measured 0.0198 off the chord at the end (0.014-0.02 from step 3000 on).
///   Tolerance: under a tenth of the seed at the end.
///
/// So L2020's "flexible" fibre is on the stiff side here and does not snake (the issue's
/// 15e3 / 75e3 pair is not reproduced; docs/validation/spm.md).
#[test]
fn a_seeded_fibre_buckles_only_above_the_slender_body_threshold() {
    let run = seeded_compressional_run;
    let soft = chord_shape(&run(
        "spm-seeded-soft",
        &[
            "fibre.0.model=bead-spring",
            "fibre.0.bending_stiffness=0.00095552",
            "fibre.0.substeps=8",
        ],
    ));
    let stiff = chord_shape(&run("spm-seeded-stiff", &[]));
    let seed = soft[0].0;
    assert!((seed - 0.4924).abs() < 1e-3, "seed {seed}");
    let grown = soft.iter().map(|s| s.0).fold(0.0, f64::max);
    let shortest = soft.iter().map(|s| s.1).fold(f64::MAX, f64::min) / soft[0].1;
    println!("soft: off the chord {seed:.3} -> {grown:.3}, end-to-end down to {shortest:.4}");
    assert!(grown > 4.0 * seed, "{grown}");
    assert!(shortest < 0.99, "{shortest}");
    let last = stiff.last().unwrap().0;
    println!("stiff: off the chord {seed:.3} -> {last:.4} at the end");
    assert!(last < 0.1 * seed, "{last}");
}

/// S2023's Fig. 7 SPM scenes started on the compressional axis (135 deg, centred in the gap)
/// and run to the vertical: 1600 steps, the last state logged.
const COMPRESSIONAL_START: [&str; 5] = [
    "time.steps=1600",
    "output.interval=1600",
    "fibre.0.start=[125.5,58.5,0.0]",
    "fibre.0.direction=[-1.0,1.0,0.0]",
    "analysis.metrics=[]",
];

/// S2023's Fig. 7 fibre (K = 3.3) under SPM, started on the compressional axis, at the
/// output step nearest the vertical (1600 steps, 93 deg): as a cohesive beam, its beads tied
/// to the beam, it bends as the quasi-static 2D Stokes estimate for a chain of locked discs
/// says (`stokes_chain_2d::chain_bending_moments` and `s_deflection_per_load`; measured 0.77
/// of it with the implicit exchange, 0.96 with the explicit one, at dt = 1), while the
/// bead-spring chain of the same bending rigidity, whose beads turn freely with the fluid
/// like rollers, bends a tenth as much (0.07). The same bead-spring chain with each bead
/// turned with its bonds (`fibre.0.bead_spin = "chord"`, the fluid's torques passed to the
/// chain as couples) bends as the beam does under either exchange, light beads included.
/// `check` notes the rollers, and only them. (docs/validation/fpd.md, "S2023's Fig. 7 scene
/// with SPM".)
#[test]
fn a_bead_spring_chain_under_spm_bends_like_rollers_and_a_cohesive_beam_as_stokes_says() {
    use coordinator::reference::stokes_chain_2d as bem;
    let (_, moments) = bem::chain_bending_moments(10, 1.0, 64, false);
    let per_load = bem::s_deflection_per_load(&moments);
    let bend = |scene: &str, test: &str, extra: &[String]| {
        let o = overrides(&COMPRESSIONAL_START, extra);
        let s = run_in_process(&config(scene), &o, test);
        let states = read_topic(&run_dir(test).join("run.mcap"), "/fibre/bead_states").unwrap();
        let p = bead_xy(&states[1]);
        let ((x0, y0), (x1, y1)) = (p[0], p[p.len() - 1]);
        let chord = (x1 - x0).hypot(y1 - y0);
        let sag = p
            .iter()
            .map(|&(x, y)| ((x1 - x0) * (y - y0) - (y1 - y0) * (x - x0)).abs() / chord)
            .fold(0.0, f64::max);
        // The estimate at this angle: L (mu E L^3 / EI) times the chain's S per unit load,
        // E = (gamma / 2) |cos 2 theta| the strain rate across the fibre's axis.
        let d = &s["derived"];
        let theta = (y1 - y0).atan2(x1 - x0);
        let e = 0.5 * d["fluid.shear_rate"].as_f64().unwrap().abs() * (2.0 * theta).cos().abs();
        // Both scenes have fluid density 1, so the dynamic viscosity is the kinematic one.
        let (mu, ei, l) = (
            d["fluid.kinematic_viscosity"].as_f64().unwrap(),
            d["fibre.0.bending_rigidity"].as_f64().unwrap(),
            80.0,
        );
        let estimate = per_load * l * mu * e * l.powi(3) / ei;
        println!(
            "{scene}: theta {:.1} deg, bend {sag:.4}, estimate {estimate:.4}",
            theta.to_degrees()
        );
        sag / estimate
    };
    let beam = bend("spm/s2023_fig7_twin_beam.toml", "spm-twin-beam-bend", &[]);
    let rollers = bend("spm/s2023_fig7_twin.toml", "spm-twin-rollers-bend", &[]);
    // The same chain with each bead turned with its bonds (`bead_spin = "chord"`): the
    // fluid's torques reach the chain as couples, as through a cohesive beam's joints.
    let locked = bend(
        "spm/s2023_fig7_twin.toml",
        "spm-twin-locked-bend",
        &[
            "fibre.0.bead_spin=\"chord\"".into(),
            "fibre.0.exchange=\"explicit\"".into(),
        ],
    );
    // The same with the implicit exchange (the twin's own and the beam's), for neutrally
    // buoyant beads and for beads ten times lighter than the fluid, which the explicit
    // exchange refuses. At dt = 1 the two exchanges bend this start-up differently (explicit
    // 0.97 / 0.96 of the estimate for chain / beam, implicit 0.77 / 0.77; at dt = 0.25 1.27 /
    // 1.25 and 1.04 / 1.03, a smaller nu dt / xi^2 making the beads hydrodynamically
    // larger; at a fixed nu dt / xi^2 the two stay 1.25 apart as dt and xi are refined, the
    // implicit exchange adding the profile's fluid to each bead's inertia: docs/validation),
    // so the chain is compared with the beam under the same exchange.
    let implicit = bend(
        "spm/s2023_fig7_twin.toml",
        "spm-twin-locked-implicit-bend",
        &["fibre.0.bead_spin=\"chord\"".into()],
    );
    let light = bend(
        "spm/s2023_fig7_twin.toml",
        "spm-twin-locked-light-bend",
        &[
            "fibre.0.bead_spin=\"chord\"".into(),
            "fibre.0.density=0.1".into(),
        ],
    );
    assert!(
        (implicit / beam - 1.0).abs() < 0.05,
        "chord-locked chain, implicit: {implicit} of the Stokes estimate, the beam {beam}"
    );
    assert!(
        (0.6..1.2).contains(&light),
        "chord-locked chain of light beads, implicit: {light} of the Stokes estimate"
    );
    assert!(
        (0.6..1.2).contains(&beam),
        "cohesive beam: {beam} of the Stokes estimate"
    );
    assert!(
        (0.6..1.2).contains(&locked),
        "bead-spring chain turned with its chords: {locked} of the Stokes estimate"
    );
    let beam_explicit = bend(
        "spm/s2023_fig7_twin_beam.toml",
        "spm-twin-beam-explicit-bend",
        &["fibre.0.exchange=\"explicit\"".into()],
    );
    assert!(
        (locked / beam_explicit - 1.0).abs() < 0.05,
        "chord-locked chain, explicit: {locked} of the Stokes estimate, the beam {beam_explicit}"
    );
    assert!(
        rollers < 0.25,
        "bead-spring chain: {rollers} of the Stokes estimate"
    );
    let notes = |scene: &str| {
        let out = coordinator(&["check", config(scene).to_str().unwrap()]);
        String::from_utf8(out.stdout).unwrap()
    };
    assert!(notes("spm/s2023_fig7_twin.toml").contains("train of rollers"));
    assert!(!notes("spm/s2023_fig7_twin_beam.toml").contains("rollers"));
    let out = coordinator(&[
        "check",
        config("spm/s2023_fig7_twin.toml").to_str().unwrap(),
        "--set",
        "fibre.0.bead_spin=\"chord\"",
        "--set",
        "fibre.0.exchange=\"explicit\"",
    ]);
    assert!(out.status.success(), "{out:?}");
    assert!(!String::from_utf8(out.stdout).unwrap().contains("rollers"));
}

/// What the implicit exchange is (docs/validation/spm.md, "What the implicit exchange is"):
/// taking the fluid's impulse as a drag at the new velocity makes the fluid in a bead's
/// profile part of its inertia; with one sub-step a kick is algebraically the explicit one
/// for a bead of mass M + m_phi (the fibre node's unit test
/// `one_implicit_kick_is_an_explicit_kick_of_a_bead_carrying_its_profiles_fluid`). Through the
/// whole coupled run: the cohesive beam of S2023's Fig. 7 scene, started on the compressional
/// axis (1600 steps, one sub-step), at bead density 3 under the implicit exchange ends where
/// the same beam at density 3 + m_phi / V ends under the explicit one, within 1e-3 of the
/// largest bead displacement (measured 2.1e-4: the spins, I + I_phi against the heavier
/// bead's own, differ), while at density 3 under both it ends 3.1e-2 apart. The summary
/// reports the heavier bead's mass as `fibre.0.effective_bead_mass`.
#[test]
fn the_implicit_exchange_moves_a_bead_as_the_explicit_one_carrying_its_profiles_fluid() {
    let end = |test: &str, extra: &[String]| {
        let o = overrides(&COMPRESSIONAL_START, extra);
        let s = run_in_process(&config("spm/s2023_fig7_twin_beam.toml"), &o, test);
        let states = read_topic(&run_dir(test).join("run.mcap"), "/fibre/bead_states").unwrap();
        (s, bead_xy(&states[0]), bead_xy(&states[1]))
    };
    let (s, start, implicit) = end("spm-implicit-heavy", &["fibre.0.density=3.0".into()]);
    let d = &s["derived"];
    let (mass, ratio) = (
        d["fibre.0.bead_mass"].as_f64().unwrap(),
        d["fibre.0.profile_to_bead_mass"].as_f64().unwrap(),
    );
    let effective = d["fibre.0.effective_bead_mass"].as_f64().unwrap();
    assert!((effective - mass * (1.0 + ratio)).abs() < 1e-12 * effective);
    // The explicit bead that carries the profile's fluid: density 3 + m_phi / V.
    let (_, _, carrying) = end(
        "spm-explicit-carrying",
        &[
            "fibre.0.exchange=\"explicit\"".into(),
            format!("fibre.0.density={:?}", 3.0 * (1.0 + ratio)),
        ],
    );
    let (_, _, own) = end(
        "spm-explicit-heavy",
        &[
            "fibre.0.exchange=\"explicit\"".into(),
            "fibre.0.density=3.0".into(),
        ],
    );
    let dist = |a: &[(f64, f64)], b: &[(f64, f64)]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (p.0 - q.0).hypot(p.1 - q.1))
            .fold(0.0, f64::max)
    };
    let moved = dist(&implicit, &start);
    let (apart, same_density) = (dist(&implicit, &carrying), dist(&implicit, &own));
    println!(
        "largest displacement {moved:.4}: implicit against the carrying explicit bead {apart:.3e}, \
         against the explicit bead of the same density {same_density:.3e}"
    );
    assert!(apart < 1e-3 * moved, "{apart} of {moved}");
    assert!(same_density > 1e-2 * moved, "{same_density} of {moved}");
}

/// S2023's groups under SPM (coordinator/src/shear_groups.rs, cosim::scene_keys::wall_shear):
/// `configs/spm/s2023_fig7_twin.toml` gives C = 0.5, Re_ps = 1.5, K = 3.3, K_s = 480 and a
/// centred fibre, and the gap they are defined on is the rows between the wall slabs,
/// ny - 2 T. They resolve to the keys the scene used to write out by hand (grid 200 x 168 with
/// slabs of 4, eta = 2/3, k_b = 4.4, k_s = 128, bead 0 at [64, 83.5]), the nodes report the
/// groups back to 1e-12, the scene given by those keys runs the same bits, and the same
/// groups on FPD's `flexible_shear.toml` give the same gap, shear rate, viscosity and
/// stiffnesses: one scene, two methods.
#[test]
fn s2023_groups_give_the_spm_twin_the_flow_of_the_fpd_scene() {
    let common = ["time.steps=40", "output.interval=20", "analysis.metrics=[]"];
    let with = |extra: &[String]| overrides(&common, extra);
    let twin = config("spm/s2023_fig7_twin.toml");
    let a = run_in_process(&twin, &with(&[]), "spm-groups");
    let d = &a["derived"];
    let num = |d: &serde_json::Value, k: &str| {
        d[k].as_f64().unwrap_or_else(|| panic!("derived {k}: {d}"))
    };
    let close = |x: f64, want: f64| (x - want).abs() <= 1e-12 * want.abs();
    assert_eq!(num(d, "fluid.gap"), 160.0);
    let (eta, kb, ks) = (
        num(d, "fluid.kinematic_viscosity"),
        num(d, "fibre.0.bending_stiffness"),
        num(d, "fibre.0.stretch_stiffness"),
    );
    assert!(close(eta, 2.0 / 3.0), "eta = {eta}");
    assert!(close(kb, 4.4), "k_b = {kb}");
    assert!(close(ks, 128.0), "k_s = {ks}");
    assert!(close(num(d, "fluid.confinement"), 0.5));
    assert!(close(num(d, "fluid.particle_shear_reynolds"), 1.5));
    assert!(close(num(d, "fibre.0.bending_number"), 3.3));
    assert!(close(num(d, "fibre.0.stretch_number"), 480.0));
    let lines = a["groups"].as_array().unwrap();
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert!(
        lines[0].as_str().unwrap().contains("[200, 168]"),
        "{lines:?}"
    );

    let by_keys = with(&[
        "fluid.grid=[200,168]".into(),
        format!("fluid.viscosity={eta}"),
        format!("fibre.0.bending_stiffness={kb}"),
        format!("fibre.0.stretch_stiffness={ks}"),
        "fibre.0.start=[64.0,83.5,0.0]".into(),
    ]);
    run_in_process(&twin, &by_keys, "spm-groups-by-keys");
    let states =
        |name: &str| read_topic(&run_dir(name).join("run.mcap"), "/fibre/bead_states").unwrap();
    let sa = states("spm-groups");
    assert_eq!(sa.len(), 3);
    assert_eq!(
        sa,
        states("spm-groups-by-keys"),
        "the scene given by its groups and by its keys ran differently"
    );

    // The FPD scene with the same groups: the same flow and fibre.
    let fpd = run_in_process(
        &config("fpd/flexible_shear.toml"),
        &with(&[
            "fluid.grid=[200]".into(),
            "fluid.confinement=0.5".into(),
            "fluid.particle_shear_reynolds=1.5".into(),
            "fibre.0.bending_number=3.3".into(),
            "fibre.0.stretch_number=480".into(),
            "fibre.0.centred=true".into(),
            "time.steps=2".into(),
        ]),
        "spm-groups-fpd",
    );
    let f = &fpd["derived"];
    for k in [
        "fluid.gap",
        "fluid.shear_rate",
        "fluid.kinematic_viscosity",
        "fibre.0.bending_stiffness",
        "fibre.0.stretch_stiffness",
        "fibre.0.bending_number",
        "fibre.0.stretch_number",
        "fluid.confinement",
        "fluid.particle_shear_reynolds",
    ] {
        assert_eq!(num(d, k), num(f, k), "{k}: spm against fpd-lbm");
    }
}

// The criteria this code does not meet, kept visible: each runs the named scene and
// asserts the criterion as issue 3 states it. Run them with `-- --ignored`.

/// Issue 3: L2020 Fig. 7's period within 10 % of REFERENCE.md section 2 (N_b = 3: 21.8), the
/// run of `jeffery_period_of_a_three_bead_chain_against_2d_stokes`.
#[test]
#[ignore = "fails: gamma T 18.33 at N_b = 3, 15.8 % below REFERENCE.md's 21.8 (16-47 % for \
            N_b = 3-9) and 0.2 % from the 2D Stokes chain; the table reads Harris & Pittman's \
            law inverted; docs/validation/spm.md, The 2D reference"]
fn jeffery_period_of_a_three_bead_chain_against_reference_md() {
    let o: Vec<String> = JEFFERY_THREE_BEADS.map(String::from).to_vec();
    let s = run_in_process(
        &config("spm/jeffery_rigid.toml"),
        &o,
        "spm-jeffery-reference-md",
    );
    let t = s["metrics"]["tumbling_period_gamma"]["value"]
        .as_f64()
        .unwrap();
    assert!((t / 21.8 - 1.0).abs() < 0.10, "gamma T {t} vs 21.8");
}

/// Issue 3: at L2020's k0 / (L0 eta gamma) = 15e3 the fibre snakes (L2020 Fig. 6). The
/// seeded start of `a_seeded_fibre_buckles_only_above_the_slender_body_threshold`, which
/// gives a buckling instability every chance: the S-shaped seed must grow.
#[test]
#[ignore = "fails: the seed decays, 0.49 -> 0.02 grid spacings off the chord (2D Stokes puts \
            the fibre at eta gamma L^4 / (E I) = 84, on the stiff side); \
            docs/validation/spm.md, Flexible versus rigid"]
fn l2020_flexible_fibre_snakes_at_15e3() {
    let shape = chord_shape(&seeded_compressional_run("spm-snaking-criterion", &[]));
    let seed = shape[0].0;
    let grown = shape.iter().map(|s| s.0).fold(0.0, f64::max);
    assert!(
        grown > 4.0 * seed,
        "off the chord {seed} -> at most {grown}"
    );
}
