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
