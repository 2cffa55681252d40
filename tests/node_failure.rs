//! A node that dies mid-run: the run ends with an error naming the node, the step, the
//! phase, its exit status and the tail of its stderr, and the MCAP log stays readable.
mod common;
use common::*;
use coordinator::mcap_log::read_topic;

#[test]
fn a_dying_fibre_node_is_reported_and_the_log_stays_readable() {
    let out = out_dir("node-failure");
    let cfg = config("cantilever.toml");
    let o = run_command(&cfg, &out)
        .args(["--set", "time.steps=100", "--set", "output.interval=10"])
        .env("FIBRECOSIM_FAULT", "exit-at-step:25")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(!err.contains("panicked"), "{err}");
    for needle in [
        "fibre-node",
        "step 25",
        "fibre-positions",
        "3",
        "injected fault",
    ] {
        assert!(err.contains(needle), "message lacks `{needle}`: {err}");
    }
    let states = read_topic(&out.join("run.mcap"), "/fibre/bead_states").expect("MCAP readable");
    assert_eq!(
        states.len(),
        3,
        "initial state and the outputs at steps 10 and 20"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "failed");
    assert_eq!(summary["steps"], 25);
}

#[test]
fn an_unresponsive_fibre_node_ends_the_run_after_the_timeout() {
    let out = out_dir("node-hang");
    let cfg = config("cantilever.toml");
    let t0 = std::time::Instant::now();
    let o = run_command(&cfg, &out)
        .args(["--node-timeout", "1", "--set", "time.steps=100"])
        .env("FIBRECOSIM_FAULT", "hang-at-step:7")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        t0.elapsed() < std::time::Duration::from_secs(30),
        "took {:?}",
        t0.elapsed()
    );
    for needle in [
        "fibre-node",
        "step 7",
        "fibre-positions",
        "did not answer within 1",
    ] {
        assert!(err.contains(needle), "message lacks `{needle}`: {err}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "failed");
}

/// Two fibres that meet with `fibre_contact`, with no fluid and no loads: nothing feeds them
/// energy. At a time step just under the beam-stiffness limit (0.0113) the contact stiffens
/// them past it and the integration grows slowly, staying finite (to 5e5 times its energy
/// in 20 000 steps): the energy watch ends the run as unstable once the energy passes 1000
/// times its value after step 1. At half the step the same collision keeps its energy within
/// 10 % and completes (src/energy_watch.rs).
#[test]
fn a_closed_fibre_system_that_gains_energy_is_unstable() {
    let fibre = |start: &str, direction: &str| {
        format!(
            "[[fibre]]\nmodel = \"cohesive-beam\"\nbeads = 10\nbead_radius = 1.0\n\
             youngs_modulus = 1.0e4\ndensity = 1.0\nstart = {start}\ndirection = {direction}\n\
             fibre_contact = true\nself_contact = true\n"
        )
    };
    let text = format!(
        "dimensions = 2\n[time]\ndt = 0.01\nsteps = 20000\n[output]\ninterval = 200\n{}{}",
        fibre("[0.0, 0.0, 0.0]", "[1.0, 0.0, 0.0]"),
        fibre("[5.0, 0.3, 0.0]", "[0.0, 1.0, 0.0]")
    );
    let dir = out_dir("energy-blowup-scene");
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = dir.join("scene.toml");
    std::fs::write(&cfg, text).unwrap();

    let out = out_dir("energy-blowup");
    let o = run_command(&cfg, &out).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    for needle in ["unstable at step", "energy", "times its value", "time.dt"] {
        assert!(err.contains(needle), "message lacks `{needle}`: {err}");
    }
    let s = summary(&out);
    assert_eq!(s["status"], "failed");
    assert!(s["steps"].as_u64().unwrap() < 20000, "{s}");

    let out = run_scene(
        "energy-stable",
        &cfg,
        &["time.dt=0.005".into(), "time.steps=4000".into()],
        &[],
    )
    .expect("the same collision at half the step is stable");
    assert_eq!(summary(&out)["status"], "completed");
}
