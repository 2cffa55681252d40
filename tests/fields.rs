//! Field snapshots for ParaView (`output.fields_interval`): the fluid's fields and the beads as
//! VTK XML files, listed with their times in `fields.pvd`. Checked here by reading the files
//! back (`cosim::vtk::read_arrays`; its unit test checks the layout the format defines)
//! against what the scene prescribes: the walls' velocity, the solid profile, the FPD
//! viscosity ratio.
mod common;
use common::*;
use std::path::Path;

/// The Float64 arrays of a snapshot file, by name.
fn arrays(path: &Path) -> Vec<(String, Vec<f64>)> {
    cosim::vtk::read_arrays(path).unwrap_or_else(|e| panic!("{e}"))
}

fn array<'a>(a: &'a [(String, Vec<f64>)], name: &str) -> &'a [f64] {
    &a.iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no array {name}"))
        .1
}

/// The built-in example's scene (SPM, 96 x 96, walls at -+0.0275, beads of radius 4), 200
/// steps with a snapshot every 100: files at steps 0, 100 and 200, the same bytes in one
/// process and in three and after a resume, a picture of each, the walls' slabs moving at the
/// wall speed, the profile 1 inside the beads.
#[test]
fn spm_snapshots_hold_the_flow_and_the_beads_in_either_layout() {
    let cfg = config("spm/tumbling.toml");
    let set = [
        "time.steps=200".to_string(),
        "output.fields_interval=100".to_string(),
    ];
    let procs = run_scene("fields-spm-procs", &cfg, &set, &[]).unwrap();
    let inproc = run_scene("fields-spm-inproc", &cfg, &set, &["--in-process"]).unwrap();
    let pvd = std::fs::read_to_string(procs.join("fields.pvd")).unwrap();
    for step in ["00000000", "00000100", "00000200"] {
        for (kind, ext) in [("fluid", "vti"), ("beads", "vtp")] {
            let f = format!("fields/{kind}_{step}.{ext}");
            assert!(pvd.contains(&format!("file=\"{f}\"")), "{pvd}");
            assert_eq!(
                std::fs::read(procs.join(&f)).unwrap(),
                std::fs::read(inproc.join(&f)).unwrap(),
                "{f} differs between the layouts"
            );
        }
    }
    // Each 2D fluid snapshot is drawn too (vorticity, beads), and logged for Foxglove.
    let png = std::fs::read(procs.join("fields/fluid_00000200.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let images =
        coordinator::mcap_log::read_topic(&procs.join("run.mcap"), "/fluid/vorticity").unwrap();
    assert_eq!(images.len(), 3);
    let last = &images[2];
    assert_eq!(last["format"], "png");
    assert_eq!(last["timestamp"]["sec"], 140);
    use base64::Engine as _;
    let logged = base64::engine::general_purpose::STANDARD
        .decode(last["data"].as_str().unwrap())
        .unwrap();
    assert_eq!(logged, png);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(procs.join("summary.json")).unwrap())
            .unwrap();
    assert!(s["files"]
        .as_array()
        .unwrap()
        .contains(&"fields.pvd".into()));

    let fluid = arrays(&procs.join("fields/fluid_00000200.vti"));
    let (n, u, phi) = (
        96,
        array(&fluid, "velocity"),
        array(&fluid, "solid_fraction"),
    );
    assert_eq!((u.len(), phi.len()), (3 * n * n, n * n));
    // Inside the top wall's slab (y = 95) the fluid moves with the wall: the penalty holds
    // it there to round-off (walls.velocity = [-0.0275, 0.0275]).
    let top = 95 * n + 10;
    assert!(
        (u[3 * top] - 0.0275).abs() < 1e-4,
        "u_x in the top wall: {}",
        u[3 * top]
    );
    assert_eq!(u[3 * top + 2], 0.0);
    assert!(phi.iter().all(|p| (0.0..=1.0 + 1e-12).contains(p)));
    // The profile is 1 at each bead's centre (nearest node; r_b = 4, xi = 1).
    let beads = arrays(&procs.join("fields/beads_00000200.vtp"));
    let centres = array(&beads, "Points");
    assert_eq!(array(&beads, "radius"), [4.0; 6]);
    for c in centres.chunks(3) {
        let k = c[1].round() as usize * n + c[0].round() as usize;
        assert!(phi[k] > 0.99, "phi at the bead centre {c:?}: {}", phi[k]);
    }

    // Stopped at step 100 and resumed into the same folder: the series runs on, and the
    // snapshot of step 200 is the same file as without the stop.
    let part = run_scene(
        "fields-spm-resumed",
        &cfg,
        &["time.steps=100".into(), "output.fields_interval=100".into()],
        &["--checkpoint-interval", "100"],
    )
    .unwrap();
    let ck = part.join("checkpoint");
    let mut c = run_command(&cfg, &part);
    c.args([
        "--set",
        "time.steps=200",
        "--set",
        "output.fields_interval=100",
    ]);
    let o = c.arg("--resume").arg(&ck).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(part.join("fields.pvd")).unwrap(),
        pvd
    );
    assert_eq!(
        std::fs::read(part.join("fields/fluid_00000200.vti")).unwrap(),
        std::fs::read(procs.join("fields/fluid_00000200.vti")).unwrap()
    );
    for d in [procs, inproc, part] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// An FPD lattice: velocity, density, the viscosity of S2023 eq. 1 (eta_s = r_eta eta_f at a
/// bead's centre, eta_f far from it) and the solid fraction.
#[test]
fn fpd_snapshots_hold_the_lattice_fields() {
    let cfg = config("fpd/jeffery_rigid.toml");
    let set = [
        "time.steps=20".to_string(),
        "output.fields_interval=20".to_string(),
        "analysis.metrics=[]".to_string(),
    ];
    let out = run_scene("fields-fpd", &cfg, &set, &[]).unwrap();
    let f = arrays(&out.join("fields/fluid_00000020.vti"));
    let (nx, ny) = (100, 200);
    let (nu, rho, phi) = (
        array(&f, "viscosity"),
        array(&f, "density"),
        array(&f, "solid_fraction"),
    );
    assert_eq!(array(&f, "velocity").len(), 3 * nx * ny);
    let beads = arrays(&out.join("fields/beads_00000020.vtp"));
    let c = &array(&beads, "Points")[..3];
    let k = c[1].round() as usize * nx + c[0].round() as usize;
    // Kinematic viscosity nu_f = eta_f / rho = 0.5, r_eta = 100 (the scene).
    assert!(phi[k] > 0.99, "{}", phi[k]);
    assert!(
        (nu[k] / 50.0 - 1.0).abs() < 0.02,
        "viscosity at a bead centre: {}",
        nu[k]
    );
    assert!(
        (nu[10] - 0.5).abs() < 1e-12,
        "viscosity far from the fibre: {}",
        nu[10]
    );
    assert!(rho.iter().all(|r| (r - 1.0).abs() < 0.01));
    let _ = std::fs::remove_dir_all(out);
}

/// A 3D grid (the 20^3 periodic array of `array_drag_3d.toml`): the fields on every node, and
/// a picture of the middle plane.
#[test]
fn three_d_snapshots_hold_the_whole_grid() {
    let set = [
        "time.steps=2".to_string(),
        "output.fields_interval=2".to_string(),
    ];
    let out = run_scene("fields-3d", &config("spm/array_drag_3d.toml"), &set, &[]).unwrap();
    let f = arrays(&out.join("fields/fluid_00000002.vti"));
    assert_eq!(array(&f, "velocity").len(), 3 * 20 * 20 * 20);
    assert_eq!(array(&f, "solid_fraction").len(), 20 * 20 * 20);
    assert!(out.join("fields/fluid_00000002.png").exists());
    let _ = std::fs::remove_dir_all(out);
}

/// `output.fields_interval = 0` turns a scene's snapshots off (the built-in example has them);
/// a negative interval is refused with the key named; a scene without the key writes none.
#[test]
fn a_zero_fields_interval_writes_no_fields() {
    let off = run_scene(
        "fields-zero",
        &config("spm/tumbling.toml"),
        &[
            "time.steps=2".to_string(),
            "output.fields_interval=0".to_string(),
        ],
        &[],
    )
    .unwrap();
    let e = run_scene(
        "fields-negative",
        &config("spm/tumbling.toml"),
        &["output.fields_interval=-1".to_string()],
        &[],
    )
    .unwrap_err();
    assert!(e.contains("output.fields_interval"), "{e}");
    let none = run_scene(
        "fields-none",
        &config("spm/couette.toml"),
        &["time.steps=2".to_string()],
        &[],
    )
    .unwrap();
    for out in [off, none] {
        assert!(!out.join("fields.pvd").exists() && !out.join("fields").exists());
        let _ = std::fs::remove_dir_all(out);
    }
}
