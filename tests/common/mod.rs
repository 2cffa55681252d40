//! Shared helpers for the workspace-level tests.
#![allow(dead_code)]
use coordinator::runner::{self, RunOptions};
use coordinator::scene;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn config(name: &str) -> PathBuf {
    root().join("configs").join(name)
}

/// The `summary.json` a run wrote into `dir`.
pub fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// The output directory of one test in this test process (see [`out_dir`]).
pub fn run_dir(test: &str) -> PathBuf {
    root()
        .join("target")
        .join("test-runs")
        .join(format!("{test}-{}", std::process::id()))
}

/// A fresh output directory for one test. The directories that earlier test processes, no
/// longer running, left for the same test go too: each run's folder stays for a look after
/// a failure, until the test runs again.
pub fn out_dir(test: &str) -> PathBuf {
    let d = run_dir(test);
    let _ = std::fs::remove_dir_all(&d);
    let prefix = format!("{test}-");
    let entries = d.parent().and_then(|p| std::fs::read_dir(p).ok());
    for e in entries.into_iter().flatten().flatten() {
        let name = e.file_name();
        let pid = name
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .and_then(|p| p.parse::<u32>().ok());
        if let Some(pid) = pid {
            let running = Path::new("/proc").join(pid.to_string()).exists();
            if pid != std::process::id() && !running {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    }
    d
}

/// Run a scene in-process through the coordinator library; returns summary.json.
/// `--set` overrides: the `common` ones, then `extra`.
pub fn overrides(common: &[&str], extra: &[String]) -> Vec<String> {
    common
        .iter()
        .map(|s| s.to_string())
        .chain(extra.iter().cloned())
        .collect()
}

pub fn run_in_process(cfg: &Path, overrides: &[String], test: &str) -> serde_json::Value {
    let scene = scene::load(Some(cfg), overrides).unwrap_or_else(|e| panic!("{e}"));
    let opts = RunOptions::quiet(out_dir(test), true);
    runner::run(&scene, &opts)
        .unwrap_or_else(|e| panic!("{e}"))
        .summary
}

/// The (x, y) bead positions of one `/fibre/bead_states` message (grid spacings).
pub fn bead_xy(message: &serde_json::Value) -> Vec<(f64, f64)> {
    message["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| (b[0].as_f64().unwrap(), b[1].as_f64().unwrap()))
        .collect()
}

pub fn metric(summary: &serde_json::Value, name: &str) -> (f64, f64) {
    let m = &summary["metrics"][name];
    (
        m["value"].as_f64().expect("metric value"),
        m["reference"].as_f64().expect("metric reference"),
    )
}

/// Directory of the release binaries (coordinator, fibre node, fluid node), built once per
/// test process (cargo's freshness check makes this cheap when they are up to date).
pub fn bin_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let status = Command::new(cargo)
            .args([
                "build",
                "--release",
                "--bins",
                "-p",
                "fibre-node",
                "-p",
                "fluid-node",
                "-p",
                "coordinator",
            ])
            .current_dir(root())
            .status()
            .expect("run cargo build");
        assert!(status.success(), "building the node binaries failed");
        let target = std::env::var_os("CARGO_TARGET_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| root().join("target"));
        target.join("release")
    })
}

/// Run the coordinator executable with arguments.
pub fn coordinator(args: &[&str]) -> Output {
    Command::new(bin_dir().join("coordinator"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("start coordinator")
}

/// `coordinator run CFG --quiet --out OUT` as a command to add to (overrides, environment)
/// and start.
pub fn run_command(cfg: &Path, out: &Path) -> Command {
    let mut c = Command::new(bin_dir().join("coordinator"));
    c.arg("run")
        .arg(cfg)
        .args(["--quiet", "--out"])
        .arg(out)
        .current_dir(root());
    c
}

/// `coordinator run CFG --quiet --out <out_dir(name)> --set O... EXTRA...`: the output
/// directory on success, the coordinator's standard error otherwise.
pub fn run_scene(
    name: &str,
    cfg: &Path,
    overrides: &[String],
    extra: &[&str],
) -> Result<PathBuf, String> {
    let out = out_dir(name);
    let mut c = run_command(cfg, &out);
    for o in overrides {
        c.args(["--set", o]);
    }
    let o = c.args(extra).output().expect("start coordinator");
    if o.status.success() {
        Ok(out)
    } else {
        Err(String::from_utf8_lossy(&o.stderr).into_owned())
    }
}

/// Wait until the run writing into `out` is under way (its MCAP log has reached `bytes`,
/// within 60 s), then send the coordinator `child` SIGINT (Ctrl-C) and collect its output.
pub fn interrupt_when_logged(child: std::process::Child, out: &Path, bytes: u64) -> Output {
    signal_when_logged(child, out, bytes, "-INT")
}

/// [`interrupt_when_logged`] with the signal `signal` (`kill`'s option: `-INT`, `-TERM`).
pub fn signal_when_logged(
    child: std::process::Child,
    out: &Path,
    bytes: u64,
    signal: &str,
) -> Output {
    let t0 = std::time::Instant::now();
    while std::fs::metadata(out.join("run.mcap")).map_or(0, |m| m.len()) < bytes {
        assert!(
            t0.elapsed() < std::time::Duration::from_secs(60),
            "the run did not start"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let pid = child.id().to_string();
    assert!(Command::new("kill")
        .args([signal, &pid])
        .status()
        .unwrap()
        .success());
    child.wait_with_output().unwrap()
}
