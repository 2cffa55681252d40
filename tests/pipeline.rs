//! Pipelined steps (coordinator/src/pipeline.rs): as processes, each node gets its phases of a
//! step in one request and waits for the other node's publications itself. The results must
//! be the bits of a lock-step run and of an in-process run, and a node that fails inside a
//! batch must end the run with its message, not leave the other node waiting. A node alone
//! runs in batches too.
mod common;
use common::*;
use coordinator::mcap_log::read_topic;
use std::time::{Duration, Instant};

/// [`run_scene`] that must succeed: the run's output directory, or a panic with the run's
/// name and the coordinator's standard error.
fn run_ok(name: &str, cfg: &std::path::Path, o: &[String], extra: &[&str]) -> std::path::PathBuf {
    run_scene(name, cfg, o, extra).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// A small binary-fluid scene with a fibre: all five SPM phases, including the phase field
/// that runs while the fibre node advances the positions.
fn small_capillary() -> Vec<String> {
    [
        "fluid.grid=[48,48]",
        "fibre.0.beads=4",
        "fluid.binary.position=24.0",
        "fibre.0.start=[12.0,10.0,0.0]",
        "time.dt=1.8",
        "time.steps=40",
        "output.interval=5",
        "analysis.metrics=[]",
    ]
    .map(String::from)
    .to_vec()
}

fn same_run(a: &std::path::Path, b: &std::path::Path, what: &str) {
    // The initial states and eight outputs; diagnostics from the first output on.
    for (topic, n) in [("/fibre/bead_states", 9), ("/diagnostics", 8)] {
        let ta = read_topic(&a.join("run.mcap"), topic).unwrap();
        let tb = read_topic(&b.join("run.mcap"), topic).unwrap();
        assert_eq!(ta.len(), n, "{topic}");
        assert_eq!(ta, tb, "{topic} differs: {what}");
    }
    // The steps between the outputs report briefly; the logged ones in full.
    for d in read_topic(&a.join("run.mcap"), "/diagnostics").unwrap() {
        assert_full(&d);
    }
}

/// `diagnostics` (a /diagnostics entry or the summary's) has those that a full report of the
/// binary fluid adds to a brief one.
fn assert_full(diagnostics: &serde_json::Value) {
    for name in ["max_divergence", "free_energy"] {
        assert!(diagnostics[name].is_f64(), "no {name} in {diagnostics}");
    }
}

#[test]
fn pipelined_lock_step_and_in_process_runs_give_the_same_bits() {
    let cfg = config("capillary/tumbling_2d.toml");
    let o = small_capillary();
    let pipelined = run_ok("pipeline-pipelined", &cfg, &o, &[]);
    let lock_step = run_ok("pipeline-lock-step", &cfg, &o, &["--lock-step"]);
    let in_process = run_ok("pipeline-in-process", &cfg, &o, &["--in-process"]);
    assert_eq!(summary(&pipelined)["pipelined"], true);
    // Between the outputs (every 5 steps) the nodes run several steps per batch.
    let largest_batch =
        |dir: &std::path::Path| summary(dir)["largest_batch_steps"].as_u64().unwrap();
    assert!((2..=5).contains(&largest_batch(&pipelined)));
    assert_eq!(largest_batch(&lock_step), 0);
    let waits = |dir: &std::path::Path| summary(dir)["seconds_waiting_for_input"].clone();
    // The phases that read the other node's output waited (or checked) for it; the others
    // and a lock-step run report nothing.
    let w = waits(&pipelined);
    for phase in [
        "fluid-momentum-exchange",
        "fibre-velocities",
        "fluid-penalty",
    ] {
        assert!(w[phase].as_f64().unwrap() >= 0.0, "{w}");
    }
    assert_eq!(w["fluid-phase-field"].as_f64(), Some(0.0), "{w}");
    assert_eq!(waits(&lock_step), serde_json::json!({}));
    assert_eq!(summary(&lock_step)["pipelined"], false);
    assert_eq!(summary(&in_process)["pipelined"], false);
    same_run(&pipelined, &lock_step, "pipelined against lock-step");
    same_run(&pipelined, &in_process, "pipelined against in-process");
    let states = read_topic(&pipelined.join("run.mcap"), "/fibre/bead_states").unwrap();
    let x = |i: usize| states[i]["states"][0][0].as_f64().unwrap();
    assert!((x(8) - x(0)).abs() > 1e-9, "the fibre did not move");
}

/// The coupled SPM scene of tests/spm.rs, as processes, with a fault injected into the fibre
/// node at step 5 (a pipelined step: only the first step of a run is lock-step). With
/// `output_interval` 1 every batch is one step; with 20, step 5 falls inside a batch of
/// several steps.
fn faulty_run(
    name: &str,
    fault: &str,
    output_interval: u64,
) -> (String, serde_json::Value, Duration) {
    let out = out_dir(name);
    let cfg = config("spm/jeffery_rigid.toml");
    let mut c = run_command(&cfg, &out);
    for o in [
        "fluid.grid=[64,64]",
        "walls.velocity=[-0.28,0.28]",
        "fibre.0.youngs_modulus=79.58",
        "time.dt=0.25",
        "fibre.0.beads=4",
        "fibre.0.bead_radius=4.0",
        "fibre.0.start=[32.0,20.0,0.0]",
        "fibre.0.density=1.5",
        "time.steps=40",
        "analysis.metrics=[]",
    ] {
        c.args(["--set", o]);
    }
    c.args(["--set", &format!("output.interval={output_interval}")]);
    let t0 = Instant::now();
    let o = c
        .args(["--node-timeout", "20"])
        .env("FIBRECOSIM_FAULT", fault)
        .output()
        .unwrap();
    let took = t0.elapsed();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    (err, summary(&out), took)
}

/// The fibre node refuses its second phase; the fluid node is then waiting for the bead
/// states that phase would have published. The run ends at once with the fibre's message.
#[test]
fn a_phase_that_fails_inside_a_batch_ends_the_run_with_its_message() {
    for interval in [1, 20] {
        let name = format!("pipeline-refuse-{interval}");
        let (err, summary, took) = faulty_run(&name, "refuse-at-step:5", interval);
        eprintln!("{err}\n{took:?}");
        assert!(!err.contains("panicked"), "{err}");
        for needle in [
            "fibre-node",
            "failed at step 5,",
            "fibre-velocities",
            "injected refusal",
        ] {
            assert!(err.contains(needle), "message lacks `{needle}`: {err}");
        }
        assert_eq!(summary["status"], "failed");
        assert_eq!(summary["steps"], 5);
        let batch = summary["largest_batch_steps"].as_u64().unwrap();
        assert!(
            if interval == 1 { batch == 1 } else { batch > 1 },
            "{summary}"
        );
        // Well inside the node timeout (20 s): nobody waited for it.
        assert!(took < Duration::from_secs(15), "took {took:?}");
    }
}

/// The fibre node dies at the start of its batch; the fluid node waits for its positions.
#[test]
fn a_node_that_dies_inside_a_batch_is_reported() {
    let (err, summary, took) = faulty_run("pipeline-exit", "exit-at-step:5", 1);
    eprintln!("{err}\n{took:?}");
    assert!(!err.contains("panicked"), "{err}");
    for needle in ["fibre-node", "failed at step 5,", "injected fault"] {
        assert!(err.contains(needle), "message lacks `{needle}`: {err}");
    }
    assert_eq!(summary["status"], "failed");
    assert!(took < Duration::from_secs(15), "took {took:?}");
    // Inside a batch of several steps the coordinator knows only the batch: the message
    // names its steps, and the summary counts those before it.
    let (err, summary, took) = faulty_run("pipeline-exit-batch", "exit-at-step:5", 20);
    eprintln!("{err}\n{took:?}");
    assert!(
        err.contains("fibre-node") && err.contains("injected fault"),
        "{err}"
    );
    let (first, last) = batch_in(&err).unwrap_or_else(|| panic!("no batch named: {err}"));
    assert!(first < last && (first..=last).contains(&5), "{err}");
    assert_eq!(summary["steps"], first);
    assert!(took < Duration::from_secs(15), "took {took:?}");
}

/// The steps of the batch a message names: "failed at step A, or later, up to B".
fn batch_in(message: &str) -> Option<(u64, u64)> {
    let rest = &message[message.find("failed at step ")? + "failed at step ".len()..];
    let (first, rest) = rest.split_once(", or later, up to ")?;
    let last: String = rest.chars().take_while(char::is_ascii_digit).collect();
    Some((first.parse().ok()?, last.parse().ok()?))
}

/// Ctrl-C while the fluid node's next batch is already out (binary fluid: it starts with the
/// phase field): the run ends after that batch's step, its checkpoint is consistent, and the
/// resumed run ends in the bits of a run that never stopped.
#[test]
fn an_interrupted_pipelined_run_resumes_to_the_same_bits() {
    let cfg = config("capillary/tumbling_2d.toml");
    let mut o = small_capillary();
    o.retain(|s| !s.starts_with("time.steps") && !s.starts_with("output.interval"));
    o.extend(["time.steps=3000".into(), "output.interval=100".into()]);
    let stopped = out_dir("pipeline-interrupted");
    let mut c = run_command(&cfg, &stopped);
    for s in &o {
        c.args(["--set", s]);
    }
    let child = c
        .args(["--checkpoint-interval", "1000"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Interrupt once the run is under way (its first outputs are logged).
    let out = interrupt_when_logged(child, &stopped, 5_000);
    let err = String::from_utf8_lossy(&out.stderr);
    let stopped_summary = summary(&stopped);
    let steps = stopped_summary["steps"].as_u64().unwrap();
    eprintln!("stopped at step {steps}: {err}");
    if stopped_summary["status"] != "interrupted" {
        // The run finished before the signal came; nothing to resume.
        assert_eq!(stopped_summary["status"], "completed", "{err}");
        return;
    }
    assert!(steps < 3000);
    // Stopped after a step that reported in full, logged last.
    assert_full(&stopped_summary["final_diagnostics"]);
    let logged = read_topic(&stopped.join("run.mcap"), "/diagnostics").unwrap();
    let last_logged = logged.last().unwrap();
    assert_eq!(last_logged["step"].as_u64(), Some(steps));
    assert_full(last_logged);
    let ck = stopped.join("checkpoint");
    let resumed = run_scene(
        "pipeline-resumed",
        &cfg,
        &o,
        &["--resume", ck.to_str().unwrap()],
    )
    .unwrap();
    let straight = run_scene("pipeline-straight", &cfg, &o, &[]).unwrap();
    let last = |dir: &std::path::Path| {
        let s = read_topic(&dir.join("run.mcap"), "/fibre/bead_states").unwrap();
        s.last().unwrap().clone()
    };
    assert_eq!(last(&resumed), last(&straight));
    let diag = |dir: &std::path::Path| summary(dir)["final_diagnostics"].clone();
    assert_eq!(diag(&resumed), diag(&straight));
}

/// A fluid without fibres runs alone as a process, in batches of several steps (it waits for
/// nobody), to the bits of the same run in-process.
#[test]
fn a_node_alone_runs_in_batches_to_the_same_bits() {
    let cfg = config("spm/couette.toml");
    let o: Vec<String> = ["time.steps=400", "output.interval=50"]
        .map(String::from)
        .to_vec();
    let alone = run_ok("pipeline-alone", &cfg, &o, &[]);
    let in_process = run_ok("pipeline-alone-in-process", &cfg, &o, &["--in-process"]);
    let (a, b) = (summary(&alone), summary(&in_process));
    assert_eq!(a["pipelined"], true);
    assert!(a["largest_batch_steps"].as_u64().unwrap() > 1, "{a}");
    assert_eq!(a["metrics"], b["metrics"]);
    let ta = read_topic(&alone.join("run.mcap"), "/diagnostics").unwrap();
    let tb = read_topic(&in_process.join("run.mcap"), "/diagnostics").unwrap();
    assert_eq!(ta.len(), 8);
    assert_eq!(ta, tb, "diagnostics differ");
}

/// A run whose metrics follow the bead states every step (the built-in example's orbit) runs
/// in batches too: the coordinator reads each step's states from its queue after the batch.
/// The orbit, step by step, is the in-process run's to the bit.
#[test]
fn orbit_metrics_read_every_step_of_a_batch() {
    let cfg = config("spm/tumbling.toml");
    let o = [
        "time.steps=300",
        "output.interval=150",
        "output.fields_interval=0",
    ]
    .map(String::from)
    .to_vec();
    let processes = run_ok("pipeline-orbit-processes", &cfg, &o, &[]);
    let in_process = run_ok("pipeline-orbit-in-process", &cfg, &o, &["--in-process"]);
    let (a, b) = (summary(&processes), summary(&in_process));
    assert!(a["largest_batch_steps"].as_u64().unwrap() > 1, "{a}");
    assert_eq!(a["metrics"], b["metrics"]);
    let orbit = |dir: &std::path::Path| std::fs::read_to_string(dir.join("orbit.csv")).unwrap();
    let (oa, ob) = (orbit(&processes), orbit(&in_process));
    // A header and one row a step from step 0.
    assert_eq!(oa.lines().count(), 302);
    assert_eq!(oa, ob);
}
