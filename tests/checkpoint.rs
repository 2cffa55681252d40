//! Checkpoint and resume (`coordinator run --checkpoint-interval N`, `--resume DIR`): a run
//! stopped at a checkpoint and resumed ends in the same bits as the run that never stopped.
mod common;
use common::*;
use coordinator::mcap_log::read_topic;
use std::path::Path;

/// Run `cfg` for `total` steps straight, and as `at` steps with a checkpoint plus a resumed
/// run to `total`; returns both output folders.
fn straight_and_resumed(
    name: &str,
    cfg: &Path,
    overrides: &[&str],
    total: u64,
    at: u64,
    extra: &[&str],
) -> (std::path::PathBuf, std::path::PathBuf) {
    let set = |steps: u64| -> Vec<String> {
        overrides
            .iter()
            .map(|s| s.to_string())
            .chain([format!("time.steps={steps}")])
            .collect()
    };
    let straight = run_scene(&format!("{name}-straight"), cfg, &set(total), extra).unwrap();
    let every = at.to_string();
    let first: Vec<&str> = extra
        .iter()
        .copied()
        .chain(["--checkpoint-interval", &every])
        .collect();
    let part = run_scene(&format!("{name}-part"), cfg, &set(at), &first).unwrap();
    let ck = part.join("checkpoint");
    let ck = ck.to_str().unwrap();
    let second: Vec<&str> = extra.iter().copied().chain(["--resume", ck]).collect();
    let resumed = run_scene(&format!("{name}-resumed"), cfg, &set(total), &second).unwrap();
    (straight, resumed)
}

/// The same bits at the end: the last logged bead states, the final diagnostics (fluid and
/// fibre) and the metrics, which need the history from before the checkpoint too.
fn assert_same_end(a: &Path, b: &Path) {
    let (sa, sb) = (summary(a), summary(b));
    assert_eq!(sa["status"], "completed", "{sa}");
    assert_eq!(sb["status"], "completed", "{sb}");
    assert_eq!(sa["steps"], sb["steps"]);
    assert_eq!(sa["time"], sb["time"]);
    assert_eq!(sa["final_diagnostics"], sb["final_diagnostics"]);
    assert_eq!(sa["metrics"], sb["metrics"]);
    assert_eq!(sa["largest_wall_overlap"], sb["largest_wall_overlap"]);
    assert_eq!(sa["largest_self_overlap"], sb["largest_self_overlap"]);
    let last = |d: &Path| {
        read_topic(&d.join("run.mcap"), "/fibre/bead_states")
            .unwrap()
            .pop()
            .expect("logged bead states")
    };
    assert_eq!(last(a), last(b));
}

/// The built-in example (SPM fluid and a cohesive-beam fibre with four sub-steps), stopped
/// between logged steps, as three processes and in one process.
#[test]
fn a_resumed_spm_run_ends_in_the_same_bits() {
    let o = [
        "output.interval=10",
        "analysis.metrics=[\"min_end_to_end_over_length\"]",
    ];
    for (layout, extra) in [
        ("processes", &[][..]),
        ("in-process", &["--in-process"][..]),
    ] {
        let (a, b) = straight_and_resumed(
            &format!("ckpt-spm-{layout}"),
            &config("spm/tumbling.toml"),
            &o,
            60,
            25,
            extra,
        );
        assert_same_end(&a, &b);
        assert_same_log(&a, &b, 25);
        let part = b.with_file_name(
            b.file_name()
                .unwrap()
                .to_str()
                .unwrap()
                .replace("-resumed-", "-part-"),
        );
        assert_wall_time_adds_up(&b, &part);
    }
}

/// A resumed run's log holds the whole run: the earlier run's outputs up to the checkpoint
/// (copied from its log), then its own. Every logged step of the straight run is there with
/// the same bits, and one more at the checkpoint's step `at` when that is not an output step
/// (both runs' last steps are logged).
fn assert_same_log(straight: &Path, resumed: &Path, at: u64) {
    for topic in ["/diagnostics", "/fibre/bead_states"] {
        let read = |d: &Path| read_topic(&d.join("run.mcap"), topic).unwrap();
        let (a, b) = (read(straight), read(resumed));
        let b: Vec<_> = b
            .into_iter()
            .filter(|m| m["step"] != at || a.iter().any(|x| x["step"] == at))
            .collect();
        assert_eq!(
            b.len(),
            a.len(),
            "{topic}: {} messages resumed, {} straight",
            b.len(),
            a.len()
        );
        assert!(
            a == b,
            "{topic}: the resumed log differs from the straight run's"
        );
    }
}

/// A resumed run's summary counts the wall time from step 0 over both pieces: its own, plus
/// what the checkpoint recorded (which the first piece spent before writing it).
fn assert_wall_time_adds_up(resumed: &Path, part: &Path) {
    let (r, p) = (summary(resumed), summary(part));
    let ck: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(part.join("checkpoint").join("run.json")).unwrap(),
    )
    .unwrap();
    let before = ck["wall_seconds"]
        .as_f64()
        .expect("checkpoint wall_seconds");
    let own = p["wall_seconds"].as_f64().unwrap();
    assert!(before > 0.0 && before <= own, "{before} of {own}");
    assert_eq!(p["wall_seconds_since_step_0"], p["wall_seconds"]);
    assert_eq!(p["resumed_from_step"], serde_json::Value::Null);
    assert_eq!(r["resumed_from_step"], 25);
    let total = r["wall_seconds_since_step_0"].as_f64().unwrap();
    let this = r["wall_seconds"].as_f64().unwrap();
    assert!(
        ((total - this) - before).abs() <= 1e-9 * total,
        "{total} - {this} != {before}"
    );
}

/// A binary fluid (psi saved with the velocity) and the tilt metric, which reads the
/// initial bead states kept in the checkpoint.
#[test]
fn a_resumed_capillary_run_ends_in_the_same_bits() {
    let (a, b) = straight_and_resumed(
        "ckpt-capillary",
        &config("capillary/tumbling_2d.toml"),
        &["output.interval=10"],
        40,
        17,
        &["--in-process"],
    );
    assert_same_end(&a, &b);
    assert_same_log(&a, &b, 17);
}

/// A fibre alone: `min_end_to_end_over_length` reads the history from before the checkpoint
/// (this test fails if the resumed run does not get it back).
#[test]
fn a_resumed_fibre_run_keeps_its_history() {
    let (a, b) = straight_and_resumed(
        "ckpt-cantilever",
        &config("cantilever.toml"),
        &[
            "output.interval=100",
            "time.rest_tolerance=1e-300",
            "analysis.metrics=[\"tip_deflection_over_length\", \"min_end_to_end_over_length\"]",
        ],
        600,
        250,
        &["--in-process"],
    );
    assert_same_end(&a, &b);
    assert_same_log(&a, &b, 250);
}

/// An FPD lattice (populations saved, viscosity and force fields rebuilt from the beads) with
/// a bead-spring fibre, free and with a held bead (its integrated displacement is saved).
#[test]
fn a_resumed_fpd_run_ends_in_the_same_bits() {
    for (name, clamp) in [("free", "[]"), ("held", "[2]")] {
        let c = format!("fibre.0.clamp={clamp}");
        let (a, b) = straight_and_resumed(
            &format!("ckpt-fpd-{name}"),
            &config("fpd/fibre_in_shear.toml"),
            &["output.interval=10", &c],
            60,
            23,
            &[],
        );
        assert_same_end(&a, &b);
        assert_same_log(&a, &b, 23);
    }
}

/// What a resume refuses, with the reason: another physical scene, a run already as long as
/// the checkpoint, a folder that holds no checkpoint.
#[test]
fn resume_refuses_what_does_not_fit() {
    let cfg = config("spm/tumbling.toml");
    let o = |s: &[&str]| -> Vec<String> { s.iter().map(|x| x.to_string()).collect() };
    let part = run_scene(
        "ckpt-refuse-part",
        &cfg,
        &o(&["time.steps=10", "analysis.metrics=[]"]),
        &["--in-process", "--checkpoint-interval", "10"],
    )
    .unwrap();
    let ck = part.join("checkpoint");
    let ck = ck.to_str().unwrap();
    let resume = |name: &str, set: &[&str]| {
        run_scene(name, &cfg, &o(set), &["--in-process", "--resume", ck]).unwrap_err()
    };
    let e = resume(
        "ckpt-refuse-dt",
        &["time.steps=20", "time.dt=0.5", "analysis.metrics=[]"],
    );
    assert!(e.contains("first difference in `time`"), "{e}");
    let e = resume(
        "ckpt-refuse-steps",
        &["time.steps=10", "analysis.metrics=[]"],
    );
    assert!(
        e.contains("checkpoint is at step 10") && e.contains("raise time.steps"),
        "{e}"
    );
    let e = run_scene(
        "ckpt-refuse-none",
        &cfg,
        &o(&["time.steps=20"]),
        &["--in-process", "--resume", part.to_str().unwrap()],
    )
    .unwrap_err();
    assert!(e.contains("run.json"), "{e}");
}
