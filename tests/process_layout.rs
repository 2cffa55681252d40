//! Determinism across process layouts: the same scene as separate processes (iceoryx2) and
//! linked into one process gives bit-identical bead trajectories in the MCAP log.
mod common;
use common::*;
use coordinator::mcap_log::read_topic;

fn run_cli(layout: &str, extra: &[&str]) -> std::path::PathBuf {
    let out = out_dir(&format!("layout-{layout}"));
    let cfg = config("cantilever.toml");
    let mut args = vec![
        "run",
        cfg.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "time.steps=400",
        "--set",
        "output.interval=20",
    ];
    args.extend_from_slice(extra);
    let o = coordinator(&args);
    assert!(
        o.status.success(),
        "{layout}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

#[test]
fn processes_and_in_process_give_identical_bead_trajectories() {
    let a = run_cli("processes", &[]);
    let b = run_cli("in-process", &["--in-process"]);
    let sa = read_topic(&a.join("run.mcap"), "/fibre/bead_states").unwrap();
    let sb = read_topic(&b.join("run.mcap"), "/fibre/bead_states").unwrap();
    assert_eq!(sa.len(), 21, "expected the initial state and 20 outputs");
    assert_eq!(sa, sb, "bead trajectories differ between process layouts");
    // JSON numbers print the shortest representation that reads back to the same f64, so
    // equal values mean equal bits; check the text as well.
    let text = |v: &Vec<serde_json::Value>| serde_json::to_string(v).unwrap();
    assert_eq!(text(&sa), text(&sb));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["process_layout"], "processes");
    let d = read_topic(&a.join("run.mcap"), "/diagnostics").unwrap();
    assert_eq!(d.len(), 20);
}
