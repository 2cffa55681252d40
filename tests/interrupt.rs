//! Ctrl-C (SIGINT to the coordinator), or SIGTERM (`kill`, `timeout`, a batch system), ends a
//! run cleanly: the nodes are shut down, the summary says `interrupted`, and the MCAP log is
//! complete and readable.
mod common;
use common::*;
use coordinator::mcap_log::read_topic;

#[test]
fn sigint_ends_the_run_cleanly() {
    ends_the_run_cleanly("-INT");
}

#[test]
fn sigterm_ends_the_run_cleanly() {
    ends_the_run_cleanly("-TERM");
}

fn ends_the_run_cleanly(signal: &str) {
    let out = out_dir(&format!("interrupt{signal}"));
    let cfg = config("cantilever.toml");
    let child = run_command(&cfg, &out)
        .args([
            "--set",
            "time.steps=100000000",
            "--set",
            "output.interval=1000",
            "--set",
            "time.rest_tolerance=1e-300",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the run is under way (first outputs logged), then interrupt it.
    let o = signal_when_logged(child, &out, 20_000, signal);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("interrupted at step"), "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "interrupted");
    let steps = summary["steps"].as_u64().unwrap();
    let states = read_topic(&out.join("run.mcap"), "/fibre/bead_states").expect("MCAP readable");
    assert_eq!(
        states.last().unwrap()["step"].as_u64().unwrap(),
        steps,
        "last logged state is the last step"
    );
}
