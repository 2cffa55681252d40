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

/// `coordinator study --jobs 3` runs the variants at once, each as its own `coordinator run`,
/// and ends with the values of the same study run one variant after another, and with the
/// same bead trajectories.
#[test]
fn a_study_run_in_parallel_gives_the_values_of_one_run_after_another() {
    let dir = out_dir("study-jobs");
    std::fs::create_dir_all(&dir).unwrap();
    let name = format!("jobs_test_{}", std::process::id());
    let study = dir.join("study.toml");
    std::fs::write(
        &study,
        format!(
            "name = \"{name}\"\nscene = {:?}\nmetric = \"tip_deflection_over_length\"\n\
             [set]\n\"time.steps\" = 600\n\"output.interval\" = 100\n\
             [[vary]]\nkey = \"fibre.0.beads\"\nvalues = [4, 6, 8]\n",
            config("cantilever.toml").to_str().unwrap()
        ),
    )
    .unwrap();
    let runs = root().join("runs").join("study").join(&name);
    let run = |jobs: &str, out: &str| {
        let out = dir.join(out);
        let o = coordinator(&[
            "study",
            study.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--jobs",
            jobs,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let csv = std::fs::read_to_string(out.join(format!("{name}.csv"))).unwrap();
        let states: Vec<_> = (0..3)
            .map(|i| {
                read_topic(
                    &runs.join(i.to_string()).join("run.mcap"),
                    "/fibre/bead_states",
                )
            })
            .map(Result::unwrap)
            .collect();
        // variant and value columns; the wall times differ.
        let values: Vec<String> = csv
            .lines()
            .map(|l| l.split(',').take(2).collect::<Vec<_>>().join(","))
            .collect();
        (values, states)
    };
    let (one_by_one, states_1) = run("1", "one");
    let (parallel, states_3) = run("3", "three");
    // --replot reads the runs under the folder the study ran from, and says so elsewhere.
    let replot = |cwd: &std::path::Path| {
        std::process::Command::new(bin_dir().join("coordinator"))
            .args(["study", study.to_str().unwrap(), "--replot", "--out"])
            .arg(dir.join("replot"))
            .current_dir(cwd)
            .output()
            .unwrap()
    };
    let here = replot(&root());
    let stdout = String::from_utf8_lossy(&here.stdout);
    assert!(
        here.status.success(),
        "{}",
        String::from_utf8_lossy(&here.stderr)
    );
    assert!(
        stdout.contains(&format!("runs in runs/study/{name}/")),
        "{stdout}"
    );
    let elsewhere = replot(&dir);
    let err = String::from_utf8_lossy(&elsewhere.stderr);
    assert!(!elsewhere.status.success());
    assert!(
        err.contains("a study keeps its runs in") && err.contains("run --replot from that folder"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&runs);
    assert_eq!(one_by_one.len(), 4, "{one_by_one:?}");
    assert_eq!(one_by_one, parallel);
    assert_eq!(states_1, states_3, "bead trajectories differ");
}
