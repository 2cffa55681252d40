//! The FPD coupling (S2023 section II C, `fluid.method = "fpd-lbm"`) through the coordinator:
//! fibre node and lattice fluid node as three processes and in one process.
mod common;
use common::*;
use coordinator::mcap_log::read_topic;

fn run_cli(name: &str, overrides: &[&str], extra: &[&str]) -> Result<std::path::PathBuf, String> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    run_scene(name, &config("fpd/fibre_in_shear.toml"), &o, extra)
}

fn angle(state: &serde_json::Value) -> f64 {
    let p = bead_xy(state);
    let (a, b) = (p[0], p[p.len() - 1]);
    (b.1 - a.1).atan2(b.0 - a.0).to_degrees()
}

/// Three processes and one process give the same bits, and the fibre, started across the
/// flow, turns clockwise as a shear flow turns it.
#[test]
fn fpd_run_is_identical_as_processes_and_in_process() {
    let short = ["time.steps=3000"];
    let a = run_cli("fpd-layout-processes", &short, &[]).unwrap();
    let b = run_cli("fpd-layout-in-process", &short, &["--in-process"]).unwrap();
    let sa = read_topic(&a.join("run.mcap"), "/fibre/bead_states").unwrap();
    let sb = read_topic(&b.join("run.mcap"), "/fibre/bead_states").unwrap();
    assert_eq!(sa.len(), 7);
    assert_eq!(sa, sb, "bead trajectories differ between process layouts");
    let (first, last) = (angle(&sa[0]), angle(&sa[6]));
    println!("fibre angle {first:.2} -> {last:.2} deg");
    assert!(
        first == 90.0 && last < 45.0,
        "the fibre should turn clockwise from the vertical, went {first} -> {last}"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    // S2023 eq. 18 from the scene: l_c = 40, H = 64, gamma = 0.04 / 64, eta_f = 0.5.
    let d = &summary["derived"];
    let close = |k: &str, v: f64| {
        let got = d[k].as_f64().unwrap_or(f64::NAN);
        assert!(
            (got - v).abs() < 1e-12 * v.abs().max(1.0),
            "{k} = {got}, expected {v}"
        );
    };
    close("fluid.confinement", 40.0 / 64.0);
    close("fluid.particle_shear_reynolds", 0.000625 * 1600.0 / 2.0);
    close(
        "fluid.bending_number",
        2.0 * 1.65 / (0.5 * 0.000625 * 1600.0),
    );
}

/// Without a fibre the lattice carries plane Couette flow: started from rest it relaxes to
/// the linear profile between the bounce-back walls (reference: the linear profile; the
/// viscous time H^2 / nu is 8192 steps, so 6 of them leave e^-6 of the first mode).
#[test]
fn fpd_couette_without_fibres_is_linear() {
    let out = run_cli(
        "fpd-couette",
        &[
            "fibre=[]",
            "fluid.initial_velocity=\"rest\"",
            "time.steps=50000",
            "analysis.metrics=[\"couette_max_error\"]",
        ],
        &["--in-process"],
    )
    .unwrap();
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let err = summary["metrics"]["couette_max_error"]["value"]
        .as_f64()
        .unwrap();
    println!("couette_max_error = {err:.3e}");
    assert!(
        err < 0.01,
        "Couette profile off by {:.3} % of the wall speed",
        100.0 * err
    );
}

/// What FPD cannot carry is refused before step 0 with the reason.
#[test]
fn fpd_refuses_what_it_cannot_carry() {
    let e = run_cli(
        "fpd-refuse-beam",
        &[
            "fibre=[{model=\"cohesive-beam\", beads=3, bead_radius=4.0, youngs_modulus=1.0, \
             start=[48.0, 24.0, 0.0]}]",
        ],
        &["--in-process"],
    )
    .unwrap_err();
    assert!(
        e.contains("cannot run under fluid.method = \"fpd-lbm\""),
        "{e}"
    );
    let e = run_cli("fpd-refuse-dt", &["time.dt=0.5"], &["--in-process"]).unwrap_err();
    assert!(
        e.contains("time.dt = 0.5") && e.contains("lattice units"),
        "{e}"
    );
    let e = run_cli(
        "fpd-refuse-mach",
        &["walls.velocity=[-0.3,0.3]"],
        &["--in-process"],
    )
    .unwrap_err();
    assert!(e.contains("Mach number"), "{e}");
    // Walls at +-0.05 over nu = 0.005: cell Reynolds number 10, above the measured limit 8
    // (fluid-node/src/fpd_lbm.rs, MAX_CELL_REYNOLDS).
    let e = run_cli(
        "fpd-refuse-cell-reynolds",
        &["walls.velocity=[-0.05,0.05]", "fluid.viscosity=0.005"],
        &["--in-process"],
    )
    .unwrap_err();
    assert!(
        e.contains("cell Reynolds number max|u| dx / nu = 10.000") && e.contains("exceeds 8"),
        "{e}"
    );
}

/// A bead-spring fibre too stiff for the explicit FPD coupling is refused before step 0,
/// with the stiffness it may have; the stiffest fibre the limit accepts runs bounded. Checked
/// at r_xi = 1/128, where the limit lies closest under the measured threshold (10 %,
/// fibre-node/src/stability.rs, `fpd_margin`), and at 1/2, where the margin grows with
/// r_xi. Without the limit, k_s = 1e4 reaches Mach 26 by step 6.
#[test]
fn fpd_stiffness_limit_refuses_too_stiff_and_accepts_what_runs() {
    let scene = config("fpd/jeffery_rigid.toml");
    let path = scene.to_str().unwrap();
    let e = run_scene(
        "fpd-too-stiff",
        &scene,
        &["fibre.0.stretch_stiffness=1e4".into()],
        &["--in-process"],
    )
    .unwrap_err();
    assert!(
        e.contains("fibre.0 is too stiff for the explicit FPD coupling")
            && e.contains("fibre.0.stretch_stiffness (k_s = 10000) to at most"),
        "{e}"
    );
    // The scene's fibre: k_s = 16, K = 3.3. omega_max^2 is linear in (k_s, K), so scaling
    // both by dt_limit^2 puts the fibre at the limit.
    let limit = |r_xi: f64, scale: f64| -> Result<f64, String> {
        let sets = [
            format!("fluid.interface_ratio={r_xi}"),
            format!("fibre.0.stretch_stiffness={}", 16.0 * scale),
            format!("fibre.0.bending_number={}", 3.3 * scale),
        ];
        let mut args = vec!["check", path];
        for s in &sets {
            args.extend(["--set", s.as_str()]);
        }
        let o = coordinator(&args);
        if !o.status.success() {
            return Err(String::from_utf8_lossy(&o.stderr).into_owned());
        }
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        let line = text
            .lines()
            .find(|l| l.contains("FPD fibre stiffness (fibre.0): dt <="))
            .unwrap_or_else(|| panic!("no FPD stiffness limit in: {text}"));
        Ok(line.rsplit(' ').next().unwrap().parse().unwrap())
    };
    for r_xi in [1.0 / 128.0, 0.5] {
        let edge = limit(r_xi, 1.0).unwrap().powi(2);
        let e = limit(r_xi, 1.02 * edge).unwrap_err();
        assert!(e.contains("too stiff for the explicit FPD coupling"), "{e}");
        let at = 0.995 * edge;
        assert!(limit(r_xi, at).unwrap() >= 1.0);
        let dir = run_scene(
            &format!("fpd-stiff-edge-{r_xi}"),
            &scene,
            &[
                format!("fluid.interface_ratio={r_xi}"),
                format!("fibre.0.stretch_stiffness={}", 16.0 * at),
                format!("fibre.0.bending_number={}", 3.3 * at),
                "time.steps=6000".into(),
                "analysis.metrics=[]".into(),
            ],
            &["--in-process"],
        )
        .unwrap_or_else(|e| panic!("r_xi = {r_xi}, k_s = {}: {e}", 16.0 * at));
        let s = summary(&dir);
        let mach = s["final_diagnostics"]["max_mach"].as_f64().unwrap();
        println!(
            "r_xi = {r_xi}: k_s up to {:.1}, final Mach {mach:.4}",
            16.0 * edge
        );
        // The walls' own Mach number is 0.087; a growing mode would pass the 0.7 abort.
        assert!(mach < 0.1, "r_xi = {r_xi}: Mach {mach}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// `fibre.N.bending_number` (S2023 eq. 18) sets k_b in the fibre node; the fluid node,
/// given that k_b instead, derives the same K from its own shear rate and viscosity.
#[test]
fn bending_number_round_trips_through_both_nodes() {
    let cfg = config("fpd/jeffery_rigid.toml");
    let steps = vec![
        "time.steps=1".to_string(),
        "analysis.metrics=[]".to_string(),
    ];
    let a = run_in_process(&cfg, &steps, "fpd-bending-number");
    let kb = a["derived"]["fibre.0.bending_stiffness"].as_f64().unwrap();
    // l_c = 10 x 4, gamma = 0.1 / 200, eta_f = 0.5: k_b = 3.3 x 0.5 x 5e-4 x 1600 / 2.
    assert!((kb - 0.66).abs() < 1e-12, "k_b = {kb}");
    let text = std::fs::read_to_string(&cfg).unwrap();
    assert!(text.contains("\nbending_number = 3.3\n"));
    let dir = out_dir("fpd-bending-stiffness-scene");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        text.replace(
            "\nbending_number = 3.3\n",
            &format!("\nbending_stiffness = {kb:?}\n"),
        ),
    )
    .unwrap();
    let b = run_in_process(&scene, &steps, "fpd-bending-stiffness");
    let k = b["derived"]["fluid.bending_number"].as_f64().unwrap();
    assert!((k - 3.3).abs() < 1e-12, "K = {k}");
}

/// S2023's Couette sandwich (Fig. 2, eqs. 13-14): the lattice's largest deviation from the
/// sharp profile of eq. 13 equals, within 2e-3 of the wall-speed difference, that of the
/// continuum diffuse-viscosity problem (steady Couette: du/dz = sigma / eta(z), integrated by
/// the midpoint rule on 2e5 cells). The deviation itself is a property of the diffuse
/// profile: 5 % at r_eta = 100, xi / H = 0.01 (docs/validation/fpd.md).
#[test]
fn couette_sandwich_matches_the_diffuse_viscosity_solution() {
    let cfg = config("fpd/couette_sandwich.toml");
    let s = run_in_process(&cfg, &[], "fpd-couette-sandwich");
    let lattice = s["metrics"]["couette_max_error"]["value"].as_f64().unwrap();
    let (h, r, xi) = (200.0_f64, 100.0, 2.0);
    let (zl, zr) = (h / 3.0, h - h / 3.0);
    let phi = |z: f64| {
        if z <= 0.5 * h {
            0.5 * (((zl - z) / xi).tanh() + 1.0)
        } else {
            0.5 * (((z - zr) / xi).tanh() + 1.0)
        }
    };
    let n = 200_000;
    let dz = h / n as f64;
    let inv: Vec<f64> = (0..n)
        .map(|i| 1.0 / (1.0 + (r - 1.0) * phi((i as f64 + 0.5) * dz)))
        .collect();
    let total: f64 = inv.iter().sum();
    let (mut acc, mut continuum) = (0.0, 0.0_f64);
    for (i, v) in inv.iter().enumerate() {
        acc += v;
        let z = (i as f64 + 0.5) * dz;
        let u = acc / total; // 0 .. 1 across the gap
        let exact = ((z - zl) / (zr - zl)).clamp(0.0, 1.0);
        continuum = continuum.max((u - exact).abs());
    }
    println!("sandwich: lattice {lattice:.5}, continuum {continuum:.5}");
    assert!(
        (lattice - continuum).abs() < 2e-3,
        "lattice {lattice} vs continuum {continuum}"
    );
}

/// The issue's hard case, all at once: r_eta = 1000, Re_ps = 10 (eta_f = 0.025, tau = 0.575)
/// and C = 0.9 (l_c = 40 in a gap of 44). It runs 20 000 steps bounded: no NaN (the run
/// would stop), beads inside the gap, bonds within 5 % of their rest length, Mach number far
/// below the lattice's limit. And it ends stuck, as S2023 find every fibre above Re_cr ~ 2.2
/// (Fig. 5b) or C_cr ~ 0.7 (Fig. 5c): measured stuck at 11.95 deg after turning 78 deg.
#[test]
fn fpd_hard_case_stays_bounded() {
    let name = "fpd-hard-case";
    let o: Vec<String> = [
        "fluid.viscosity_ratio=1000.0",
        "fluid.viscosity=0.025",
        "fluid.grid=[96,44]",
        "walls.velocity=[-0.01375,0.01375]",
        "fibre.0.start=[48.0,5.5,0.0]",
        "analysis.metrics=[\"orbit\"]",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let s = run_in_process(&config("fpd/fibre_in_shear.toml"), &o, name);
    let d = &s["derived"];
    assert!((d["fluid.particle_shear_reynolds"].as_f64().unwrap() - 10.0).abs() < 1e-9);
    assert!((d["fluid.confinement"].as_f64().unwrap() - 40.0 / 44.0).abs() < 1e-12);
    assert_eq!(s["status"], "completed");
    let mach = s["final_diagnostics"]["max_mach"].as_f64().unwrap();
    assert!(mach < 0.1, "max Mach {mach}");
    let dir = run_dir(name);
    let states = read_topic(&dir.join("run.mcap"), "/fibre/bead_states").unwrap();
    let p = bead_xy(states.last().unwrap());
    for (i, q) in p.iter().enumerate() {
        assert!(
            q.0.is_finite() && q.1 > -0.5 && q.1 < 43.5,
            "bead {i} at {q:?}"
        );
    }
    for w in p.windows(2) {
        let l = (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1);
        assert!((l - 8.0).abs() < 0.4, "bond length {l}");
    }
    println!("hard case: orbit {}", s["metrics"]["orbit"]["label"]);
    assert_eq!(s["metrics"]["orbit"]["label"], "stuck");
}

/// S2023 section IV C at Re_ps = 1.5 on a coarse lattice (d = 4, as
/// docs/validation/fpd_shape_diagram.study.toml): at C = 0.5 a stiff fibre (K = 3.3) tumbles
/// as a Jeffery orbit and a floppy one (K = 3.3e-5) coils into an S (S2023 Fig. 7a i, iii);
/// at C = 0.87 the stiff fibre gets stuck (S2023 Fig. 7b-4: stuck at Re_ps = 6; Fig. 5c:
/// C_cr ~ 0.7 at Re_ps = 1.5).
#[test]
fn fpd_orbits_fall_in_s2023_regimes() {
    let run = |name: &str, k: f64, c_row: usize| {
        // S2023's groups (`s2023_groups_set_the_keys_they_stand_for`): C = 0.5 and 0.87 give
        // H = 80 and 46 (C = 0.8696); gamma t = 60 is 600 H steps; K_s = 240 is k_s = 48 eta_f.
        let rows = [(0.5, 48000), (0.87, 27600)];
        let (c, steps) = rows[c_row];
        let o: Vec<String> = vec![
            "fibre.0.bead_radius=2.0".into(),
            format!("fibre.0.bending_number={k}"),
            "fluid.grid=[100]".into(),
            format!("fluid.confinement={c}"),
            "fluid.particle_shear_reynolds=1.5".into(),
            "fibre.0.stretch_number=240".into(),
            "fibre.0.centred=true".into(),
            format!("time.steps={steps}"),
            "output.interval=5000".into(),
            "analysis.metrics=[\"orbit\",\"stuck_angle_deg\"]".into(),
        ];
        let s = run_in_process(&config("fpd/flexible_shear.toml"), &o, name);
        check_orbit_files(&run_dir(name), &s);
        let m = &s["metrics"]["orbit"];
        println!(
            "K = {k}, C = {:.3}: {} ({}), stuck angle {}",
            s["derived"]["fluid.confinement"],
            m["label"],
            m["note"],
            s["metrics"]["stuck_angle_deg"]["value"]
        );
        m["label"].as_str().unwrap().to_string()
    };
    assert_eq!(run("fpd-orbit-rigid", 3.3, 0), "jeffery");
    assert_eq!(run("fpd-orbit-floppy", 3.3e-5, 0), "s-coiled");
    assert_eq!(run("fpd-orbit-confined", 3.3, 1), "stuck");
}

/// S2023's groups in place of the keys they set (eq. 18 and section II C;
/// coordinator/src/shear_groups.rs, fibre-node/src/config.rs): the d = 4 scene of the shape
/// diagram given as C = 0.5, Re_ps = 1.5, K = 3.3 and K_s = 240 is resolved to the gap
/// H = l_c / C = 80, eta_f = rho gamma l_c^2 / (4 Re_ps) = 1/3 (gamma = 0.1 / 80, l_c = 40),
/// k_s = K_s eta_f V0 l0 = 48 eta_f (V0 = 0.05, l0 = 4) and k_b = K eta_f gamma l_c^2 / 2,
/// the values the C = 0.5 rows of the shape-diagram studies wrote out by hand before they were
/// given by the groups (eta_f 0.333333, k_s 16), and `fibre.0.centred` puts bead 0 at those
/// rows' [32, 39.5]
/// (midpoint x = nx / 2, y = (H - 1) / 2); the
/// nodes report back the groups asked for; and the same scene given by those keys runs the
/// same bits.
#[test]
fn s2023_groups_set_the_keys_they_stand_for() {
    let common = [
        "fibre.0.bead_radius=2.0",
        "time.steps=1500",
        "output.interval=500",
        "analysis.metrics=[]",
    ];
    let with = |extra: &[String]| overrides(&common, extra);
    let groups = with(&[
        "fluid.grid=[100]".into(),
        "fluid.confinement=0.5".into(),
        "fluid.particle_shear_reynolds=1.5".into(),
        "fibre.0.bending_number=3.3".into(),
        "fibre.0.stretch_number=240".into(),
        "fibre.0.centred=true".into(),
    ]);
    let cfg = config("fpd/flexible_shear.toml");
    let a = run_in_process(&cfg, &groups, "fpd-groups");
    let d = &a["derived"];
    let num = |k: &str| d[k].as_f64().unwrap_or_else(|| panic!("derived {k}: {d}"));
    let (eta, ks, kb) = (
        num("fluid.viscosity"),
        num("fibre.0.stretch_stiffness"),
        num("fibre.0.bending_stiffness"),
    );
    let gamma = 0.1 / 80.0;
    let close = |x: f64, want: f64| (x - want).abs() <= 1e-12 * want.abs();
    assert_eq!(num("fluid.gap"), 80.0);
    assert_eq!(num("fluid.confinement"), 0.5);
    assert!(close(eta, 1.0 / 3.0), "eta_f = {eta}");
    assert!(close(ks, 48.0 * eta), "k_s = {ks}");
    assert!(close(kb, 0.5 * 3.3 * eta * gamma * 1600.0), "k_b = {kb}");
    assert!(close(num("fluid.particle_shear_reynolds"), 1.5));
    assert!(close(num("fibre.0.bending_number"), 3.3));
    assert!(close(num("fibre.0.stretch_number"), 240.0));
    // Two overrides replaced the scene file's keys; two groups were resolved.
    let lines: Vec<&str> = a["groups"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    assert_eq!(lines.len(), 5, "{lines:?}");
    assert!(
        lines[2].contains("replaces the scene's fibre.0.start"),
        "{lines:?}"
    );
    assert!(
        lines[0].contains("replaces the scene's fluid.viscosity"),
        "{lines:?}"
    );
    assert!(
        lines[1].contains("replaces the scene's fibre.0.stretch_stiffness"),
        "{lines:?}"
    );
    assert!(lines[3].contains("fluid.grid = [100, 80]"), "{lines:?}");

    let by_keys = with(&[
        "fluid.grid=[100,80]".into(),
        format!("fluid.viscosity={eta}"),
        format!("fibre.0.bending_stiffness={kb}"),
        format!("fibre.0.stretch_stiffness={ks}"),
        "fibre.0.start=[32.0,39.5,0.0]".into(),
    ]);
    let b = run_in_process(&cfg, &by_keys, "fpd-groups-by-keys");
    let states =
        |name: &str| read_topic(&run_dir(name).join("run.mcap"), "/fibre/bead_states").unwrap();
    let (sa, sb) = (states("fpd-groups"), states("fpd-groups-by-keys"));
    assert_eq!(sa.len(), 4);
    assert_eq!(
        sa, sb,
        "the scene given by its groups and by its keys ran differently"
    );
    // Given k_b, the fluid node works K out on its own as well.
    let mut db = b["derived"].clone();
    let k = db.as_object_mut().unwrap().remove("fluid.bending_number");
    assert!(close(k.and_then(|k| k.as_f64()).unwrap(), 3.3));
    assert_eq!(a["derived"], db);
}

/// `orbit.csv` and `orbit.png` (coordinator/src/orbit_report.rs) next to a summary with orbit
/// metrics: the rows span the run (every sample, or every k-th one and the last), the
/// end-to-end column reaches the summary's smallest end-to-end distance (exactly when no
/// sample was left out), the direction passes through the vertical once more than the run
/// has complete half-turns, and the plot is a PNG.
fn check_orbit_files(dir: &std::path::Path, s: &serde_json::Value) {
    assert_eq!(s["files"], serde_json::json!(["orbit.csv", "orbit.png"]));
    let csv = std::fs::read_to_string(dir.join("orbit.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time,gamma_t,theta_deg,direction_deg,omega_over_gamma,end_to_end_over_contour"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let steps = s["steps"].as_u64().unwrap() as usize;
    let stride = (steps + 1).div_ceil(coordinator::orbit_report::MAX_ROWS);
    assert_eq!(rows.len(), steps.div_ceil(stride) + 1);
    let last = &rows[rows.len() - 1];
    let gamma = s["derived"]["fluid.shear_rate"].as_f64().unwrap().abs();
    assert_eq!(last[0], s["time"].as_f64().unwrap());
    assert!((last[1] - gamma * last[0]).abs() < 1e-12 * last[1].max(1.0));
    let orbit = &s["metrics"]["orbit"]["extra"];
    let min_e2e = rows.iter().map(|r| r[5]).fold(f64::INFINITY, f64::min);
    let reported = orbit["min_end_to_end_over_contour"].as_f64().unwrap();
    assert!(
        min_e2e >= reported && min_e2e - reported < 2e-3,
        "{min_e2e} vs {reported}"
    );
    if stride == 1 {
        assert_eq!(min_e2e, reported);
    }
    // A pass through the vertical: the direction jumps by about 180 deg between rows.
    let passes = rows
        .windows(2)
        .filter(|w| (w[1][3] - w[0][3]).abs() > 90.0)
        .count();
    let half_turns = orbit["half_turns"].as_f64().unwrap() as usize;
    assert!(
        passes == half_turns + 1 || (half_turns == 0 && passes <= 1),
        "{passes} passes through the vertical, {half_turns} half-turns"
    );
    let png = std::fs::read(dir.join("orbit.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // IHDR: width and height, big-endian, of the four-panel figure.
    let dim = |at: usize| u32::from_be_bytes(png[at..at + 4].try_into().unwrap());
    assert_eq!((dim(16), dim(20)), (900, 1450));
}

/// The S-turn fibre of S2023 Fig. 7 (K = 0.33, C = 0.5, Re_ps = 1.5, d = 4) on one lattice at
/// three wall speeds U (viscosity scaled with U to keep Re_ps): the same physical scene at
/// lattice Mach numbers 0.043, 0.087 and 0.173. The lattice's compressibility error is
/// O(Ma^2), and so must be the change of the smallest end-to-end distance: the observed order
/// from the three runs is checked to lie within 1.5-2.5 (measured 1.8). Then the
/// classification docs/validation/fpd.md reports: an S-turn at Ma = 0.173 (end-to-end 0.930),
/// and a Jeffery orbit both at Ma = 0.043 and in the Richardson-extrapolated limit Ma -> 0
/// (0.958), above the fold threshold of 0.95 (coordinator/src/orbit.rs).
#[test]
fn s_turn_fold_converges_as_the_mach_number_squared() {
    let run = |u: f64| {
        let eta = 20.0 * u / 3.0;
        let steps = (2400.0 / u).round() as u64;
        let o: Vec<String> = vec![
            "fibre.0.bead_radius=2.0".into(),
            "fibre.0.bending_number=0.33".into(),
            "fluid.grid=[100, 80]".into(),
            format!("fluid.viscosity={eta}"),
            format!("walls.velocity=[{}, {u}]", -u),
            format!("fibre.0.stretch_stiffness={}", 48.0 * eta),
            "fibre.0.start=[32.0, 39.5, 0.0]".into(),
            format!("time.steps={steps}"),
            "output.interval=4000".into(),
            "analysis.metrics=[\"orbit\"]".into(),
        ];
        let s = run_in_process(
            &config("fpd/flexible_shear.toml"),
            &o,
            &format!("fpd-mach-{u}"),
        );
        let m = &s["metrics"]["orbit"];
        let e = m["extra"]["min_end_to_end_over_contour"].as_f64().unwrap();
        println!(
            "U = {u}, Ma = {:.3}: {} ({}), min end-to-end / contour {e:.4}",
            s["derived"]["fluid.mach"].as_f64().unwrap(),
            m["label"],
            m["note"]
        );
        let notes = s["notes"].as_array().unwrap().len();
        (e, m["label"].as_str().unwrap().to_string(), notes)
    };
    let (e1, l1, n1) = run(0.025);
    let (e2, _, n2) = run(0.05);
    let (e3, l3, n3) = run(0.1);
    // Above Ma = 0.1 the summary carries a note saying so (fpd_lbm::NOTE_MACH).
    assert_eq!((n1, n2, n3), (0, 0, 1));
    // Ma doubles from run to run: the differences shrink by 2^p.
    let order = ((e2 - e3) / (e1 - e2)).log2();
    println!("observed order in Ma: {order:.2}");
    assert!((1.5..=2.5).contains(&order), "order {order}");
    let limit = e1 + (e1 - e2) / 3.0;
    println!("extrapolated to Ma = 0: {limit:.4}");
    assert_eq!(l3, "s-turn");
    assert_eq!(l1, "jeffery");
    assert!(limit > 0.95, "limit {limit}");
}

/// `coordinator check` shows the note on the Mach number for a scene with a fibre above
/// Ma = 0.1 (the paper-resolution scene, walls at -+0.1: Ma 0.173), and none at 0.087.
#[test]
fn check_notes_a_high_lattice_mach_number() {
    let text = |scene: &str| {
        let cfg = config(scene);
        let out = coordinator(&["check", cfg.to_str().unwrap()]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let high = text("fpd/fig7_jeffery_paper_resolution.toml");
    assert!(
        high.contains("note:     fluid (fpd-lbm): the lattice Mach number is 0.173"),
        "{high}"
    );
    assert!(!text("fpd/flexible_shear.toml").contains("note:"));
}

/// S2023 Fig. 4 on a small box: a held cylinder (d = 4) in a uniform stream at Re = 10
/// and 20, against Dennis & Chang 1970 (C_D = 2.846, 2.045). The box is 32 d x 32 d, the cylinder 12 d
/// downstream of the sponge: wall blockage (d / H = 1/32) and the short upstream run raise
/// C_D by about 4 % here (docs/validation/fpd.md: 2-3 % in a 64 d box), so the tolerance is
/// 6 %. Also checks that the held bead has not moved.
#[test]
fn held_cylinder_drag_against_dennis_and_chang() {
    let small = |eta: &str, name: &str| {
        let o: Vec<String> = [
            "fluid.grid=[128,128]",
            "fibre.0.bead_radius=2.0",
            "fibre.0.start=[48.0,63.5,0.0]",
            "fluid.stream.sponge=8",
            "time.steps=3000",
            "output.interval=1000",
            eta,
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        run_in_process(&config("fpd/cylinder_drag.toml"), &o, name)
    };
    let s = small("fluid.viscosity=0.02", "fpd-cylinder-re10");
    assert!((s["derived"]["fluid.stream.reynolds"].as_f64().unwrap() - 10.0).abs() < 1e-9);
    let (cd, reference) = metric(&s, "drag_coefficient");
    assert_eq!(reference, 2.846);
    println!("Re 10: C_D = {cd:.4} (Dennis & Chang {reference})");
    assert!(
        (cd / reference - 1.0).abs() < 0.06,
        "C_D {cd} vs {reference}"
    );
    let dir = run_dir("fpd-cylinder-re10");
    let states = read_topic(&dir.join("run.mcap"), "/fibre/bead_states").unwrap();
    for st in &states {
        assert_eq!(bead_xy(st)[0], (48.0, 63.5), "the held bead moved");
    }
    let change = s["metrics"]["drag_coefficient"]["extra"]["change_over_last_fifth"]
        .as_f64()
        .unwrap();
    println!("Re 10: change over the last fifth {change:.2e}");
    assert!(change < 0.01, "{change}");
    let s20 = small("fluid.viscosity=0.01", "fpd-cylinder-re20");
    let (cd20, reference20) = metric(&s20, "drag_coefficient");
    println!("Re 20: C_D = {cd20:.4} (Dennis & Chang {reference20})");
    assert!(
        (cd20 / reference20 - 1.0).abs() < 0.06,
        "C_D {cd20} vs {reference20}"
    );
}

/// Lamb's Oseen law for a held cylinder at Re = 0.5 (`configs/fpd/cylinder_lamb.toml`,
/// d = 4 in a 128 d box): C_D within 5 % of 8 pi / (Re (2.002 - ln Re)) = 18.65, the
/// tolerance of the Dennis & Chang test above (measured 18.005, -3.5 %, 50 d / U). At Re = 1
/// Lamb's first-order law is itself 28 % above the second order (12.55 against 9.8), and the
/// lattice lies between them (docs/validation/fpd.md), so Re = 1 is not asserted.
#[test]
fn held_cylinder_drag_against_lamb_at_re_one_half() {
    let s = run_in_process(&config("fpd/cylinder_lamb.toml"), &[], "fpd-cylinder-lamb");
    assert!((s["derived"]["fluid.stream.reynolds"].as_f64().unwrap() - 0.5).abs() < 1e-9);
    let (cd, reference) = metric(&s, "drag_coefficient");
    let lamb = 8.0 * std::f64::consts::PI / (0.5 * (2.002 - 0.5f64.ln()));
    assert!((reference - lamb).abs() < 1e-12, "{reference} vs {lamb}");
    println!("Re 0.5: C_D = {cd:.4} (Lamb {reference:.4})");
    assert!(
        (cd / reference - 1.0).abs() < 0.05,
        "C_D {cd} vs {reference}"
    );
}

/// How fast a bent fibre straightens at rest (`configs/fpd/bending_relaxation.toml`, its
/// fibre ten times stiffer so that the runs are short): against the fluid's drag alone the
/// 1/e time would not depend on r_eta once the beads are rigid. Under FPD the neck where two
/// touching beads' profiles overlap is r_eta times more viscous than the fluid and is
/// sheared by every bend, so for touching beads the time grows with r_eta (measured: 317 at
/// r_eta = 100, 1496 at 1000, a ratio of 4.7), while beads 6 grid spacings apart, with no
/// viscous neck, barely notice r_eta (510 and 587, 1.15). SPM's rigid beads, touching, have
/// no such neck and straighten faster than FPD's at r_eta = 100 (185).
/// (docs/validation/fpd.md, "How fast a bent fibre straightens".)
#[test]
fn fpd_bending_is_damped_by_the_viscous_neck_between_touching_beads() {
    let time = |scene: &str, set: &[&str], test: &str| {
        let mut o: Vec<String> = vec!["fibre.0.bending_stiffness=4.4".into()];
        o.extend(set.iter().map(|s| s.to_string()));
        let s = run_in_process(&config(scene), &o, test);
        let t = s["metrics"]["bend_relaxation_time"]["value"].as_f64();
        t.unwrap_or_else(|| panic!("{test}: no bend_relaxation_time: {}", s["metric_errors"]))
    };
    let fpd = "fpd/bending_relaxation.toml";
    let touching = ["time.steps=3000"];
    let t100 = time(
        fpd,
        &[touching[0], "fluid.viscosity_ratio=100.0"],
        "fpd-bend-touch-100",
    );
    let t1000 = time(
        fpd,
        &[touching[0], "fluid.viscosity_ratio=1000.0"],
        "fpd-bend-touch-1000",
    );
    let apart = ["time.steps=2000", "fibre.0.spacing=14.0"];
    let g100 = time(
        fpd,
        &[apart[0], apart[1], "fluid.viscosity_ratio=100.0"],
        "fpd-bend-gap-100",
    );
    let g1000 = time(
        fpd,
        &[apart[0], apart[1], "fluid.viscosity_ratio=1000.0"],
        "fpd-bend-gap-1000",
    );
    let spm = time(
        "spm/bending_relaxation.toml",
        &["time.steps=1000"],
        "spm-bend-touch",
    );
    println!("touching: {t100:.1} / {t1000:.1}; apart: {g100:.1} / {g1000:.1}; SPM {spm:.1}");
    assert!(
        t1000 / t100 > 3.0,
        "touching beads: r_eta 1000 / 100 = {}",
        t1000 / t100
    );
    assert!(
        g1000 / g100 < 1.4,
        "beads apart: r_eta 1000 / 100 = {}",
        g1000 / g100
    );
    assert!(
        spm < 0.8 * t100,
        "SPM {spm} against FPD {t100} at r_eta 100"
    );
}

// The issue's criteria this code does not meet, kept visible: each runs the named scene and
// asserts the criterion as issue 5 states it. Run them with `-- --ignored`.

/// Issue 5: the sandwich's profile within 2 % of V0 of eq. 13 at r_eta >= 50, xi / H <= 0.01
/// (`configs/fpd/couette_sandwich.toml`: r_eta 100, xi / H 0.01).
#[test]
#[ignore = "fails: couette_max_error 0.0507 at r_eta 100, xi/H 0.01; the exact diffuse-viscosity \
            solution gives the same (test above), and sharp interfaces alone 1/(r_eta + 2); \
            docs/validation/fpd.md, Couette sandwich"]
fn couette_sandwich_within_two_percent_of_eq_13() {
    let s = run_in_process(
        &config("fpd/couette_sandwich.toml"),
        &[],
        "fpd-sandwich-criterion",
    );
    let e = s["metrics"]["couette_max_error"]["value"].as_f64().unwrap();
    assert!(e <= 0.02, "couette_max_error {e}");
}

/// Issue 5: the rigid fibre's fitted r_c (S2023 eq. 19) between 0.10 and 0.16 at
/// S2023's r_xi = 0.125 (`configs/fpd/jeffery_rigid.toml`, about 40 s).
#[test]
#[ignore = "fails: r_c 0.213 at r_xi 0.125 (the bead's hydrodynamic radius is a + 1.9 xi); \
            0.157 at r_xi 1/128 (jeffery_rigid_sharp.toml); docs/validation/fpd.md, Rigid fibre"]
fn rigid_fibre_aspect_ratio_within_the_issue_bounds_at_s2023_r_xi() {
    let s = run_in_process(&config("fpd/jeffery_rigid.toml"), &[], "fpd-rc-criterion");
    let r = s["metrics"]["effective_aspect_ratio"]["value"]
        .as_f64()
        .unwrap();
    assert!((0.10..=0.16).contains(&r), "r_c {r}");
}

/// Issue 5: S2023's S-turn at K = 0.33, Re_ps = 1.5, C = 0.5
/// (`configs/fpd/flexible_shear.toml`, d = 8, lattice Mach 0.087, about 40 s).
#[test]
#[ignore = "fails: orbit jeffery, the fibre folds to 0.953 of its contour (fold threshold 0.95); \
            ~0.96 in the incompressible limit, s-turn only at lattice Mach >= 0.13; \
            docs/validation/fpd.md, Which K gives S2023's S-turn"]
fn k_one_third_fibre_makes_the_s_turn() {
    let s = run_in_process(
        &config("fpd/flexible_shear.toml"),
        &[],
        "fpd-s-turn-criterion",
    );
    let m = &s["metrics"]["orbit"];
    assert_eq!(m["label"], "s-turn", "{m}");
}
