//! Wall time of one whole coupled run, in-process against three processes (coordinator,
//! fibre node, fluid node, coupled through iceoryx2): what the process layout costs.
//!
//! Each sample is one `coordinator run SCENE --quiet` from start to exit, timed from outside,
//! so the two node processes' start-up is in it. The scenes:
//! - `spm_2d_256x200_18_beads`: `configs/spm/coupled_2d.toml`, 1000 steps (the size of the
//!   `spm_step` bench, ~1.3 ms a step);
//! - `capillary_2d_256x200_18_beads`: `configs/capillary/encapsulation_2d.toml` at Ec = 40
//!   (as in docs/performance.md), 500 steps: the same grid and fibre with the binary fluid
//!   of L2020 (~2.7 ms a step);
//! - `spm_3d_128x120x120_10_beads`: `configs/spm/coupled_3d.toml`, 20 steps (~90 ms a step);
//! - `fpd_jeffery_rigid_100x200`: `configs/fpd/jeffery_rigid.toml`, 3000 lattice steps;
//! - `builtin_example_96x96`: `configs/spm/tumbling.toml`, 4000 steps (0.3 ms a step, where
//!   the fixed cost per step of the coupling shows most).
//!
//! Criterion times each layout in a block of samples of its own, and on a shared machine the
//! load can change between blocks. So after criterion's report the bench takes 7 more pairs
//! of runs per scene, in-process then three processes, and prints:
//! - the overhead of each pair of whole runs and their median;
//! - the start-up of each layout (the same run with one step, median of 7);
//! - the overhead per step: each pair's run times less the start-ups, median over pairs.
//!   This is what a long run pays; the benchmark's short runs pay the start-up on top.
//! - the overhead per step that the fluid's phases do not explain: from each run's
//!   summary.json, its wall time less the seconds inside the fluid node's phases (which a
//!   change of the machine's speed between the two runs of a pair moves most), the two
//!   layouts' difference less the start-ups, over the in-process step; median over pairs,
//!   with a bootstrap 95 % interval of the median (5000 resamples, fixed seed).
//!
//! `COUPLED_RUN_PAIRS=N` takes N pairs instead of 7 (the interval narrows as 1 / sqrt N).
//!
//! `cargo bench --bench coupled_run` (builds the node executables first; about 5 minutes);
//! a filter such as `-- builtin` times and pairs only the matching scenes. Figures in
//! docs/performance.md, "Coupling overhead".
#[path = "../tests/common/mod.rs"]
mod common;
use common::{bin_dir, root, run_command};
use criterion::{Criterion, SamplingMode};
use std::path::Path;
use std::sync::Mutex;
use std::time::{Duration, Instant};

struct Case {
    name: &'static str,
    scene: &'static str,
    overrides: &'static [&'static str],
    /// Rough wall time of one run, seconds: sets criterion's measurement time so that
    /// 10 samples of one run each fit.
    seconds: f64,
}

const CASES: [Case; 5] = [
    Case {
        name: "spm_2d_256x200_18_beads",
        scene: "configs/spm/coupled_2d.toml",
        overrides: &[],
        seconds: 1.3,
    },
    Case {
        name: "capillary_2d_256x200_18_beads",
        scene: "configs/capillary/encapsulation_2d.toml",
        overrides: &[
            "time.steps=500",
            "output.interval=250",
            "analysis.metrics=[]",
            "fluid.viscosity=1.0",
            "time.dt=1.0",
            "fibre.0.youngs_modulus=0.424413",
        ],
        seconds: 1.4,
    },
    Case {
        name: "spm_3d_128x120x120_10_beads",
        scene: "configs/spm/coupled_3d.toml",
        overrides: &[],
        seconds: 2.0,
    },
    Case {
        name: "fpd_jeffery_rigid_100x200",
        scene: "configs/fpd/jeffery_rigid.toml",
        overrides: &[
            "time.steps=3000",
            "output.interval=1000",
            "analysis.metrics=[]",
        ],
        seconds: 1.4,
    },
    Case {
        name: "builtin_example_96x96",
        scene: "configs/spm/tumbling.toml",
        overrides: &[
            "time.steps=4000",
            "output.interval=1000",
            "analysis.metrics=[]",
            // The coupling alone, as measured before the scene had field snapshots.
            "output.fields_interval=0",
        ],
        seconds: 1.4,
    },
];

const LAYOUTS: [(&str, bool); 2] = [("in_process", true), ("processes", false)];

/// Pairs of runs in the paired comparison after criterion's report.
const PAIRS: usize = 7;

/// The cases criterion timed in this run of the bench.
static TIMED: Mutex<Vec<&'static str>> = Mutex::new(Vec::new());

/// One run's wall time, and its summary's wall seconds and seconds inside the fluid node's
/// phases.
struct Timed {
    outside: Duration,
    wall: f64,
    fluid: f64,
    steps: u64,
}

fn run_timed(case: &Case, in_process: bool, out: &Path, extra: &[&str]) -> Timed {
    let outside = run_once(case, in_process, out, extra);
    let text = std::fs::read_to_string(out.join("summary.json")).expect("the run's summary");
    let s: serde_json::Value = serde_json::from_str(&text).expect("summary.json is JSON");
    let fluid = s["seconds_per_phase"]
        .as_object()
        .expect("seconds_per_phase")
        .iter()
        .filter(|(k, _)| k.starts_with("fluid-"))
        .map(|(_, v)| v.as_f64().unwrap_or(0.0))
        .sum();
    Timed {
        outside,
        wall: s["wall_seconds"].as_f64().expect("wall_seconds"),
        fluid,
        steps: s["steps"].as_u64().expect("steps"),
    }
}

fn run_once(case: &Case, in_process: bool, out: &Path, extra: &[&str]) -> Duration {
    let mut c = run_command(&root().join(case.scene), out);
    for o in case.overrides.iter().chain(extra) {
        c.args(["--set", o]);
    }
    if in_process {
        c.arg("--in-process");
    }
    let t = Instant::now();
    let o = c.output().expect("start the coordinator");
    let dt = t.elapsed();
    assert!(
        o.status.success(),
        "{} failed: {}",
        case.name,
        String::from_utf8_lossy(&o.stderr)
    );
    dt
}

fn bench(c: &mut Criterion, out: &Path) {
    for case in &CASES {
        let mut group = c.benchmark_group(format!("coupled_run/{}", case.name));
        group
            .sample_size(10)
            .sampling_mode(SamplingMode::Flat)
            .warm_up_time(Duration::from_secs_f64(case.seconds))
            .measurement_time(Duration::from_secs_f64(12.0 * case.seconds));
        for (layout, in_process) in LAYOUTS {
            group.bench_function(layout, |b| {
                b.iter_custom(|iters| {
                    let mut timed = TIMED.lock().unwrap();
                    if !timed.contains(&case.name) {
                        timed.push(case.name);
                    }
                    drop(timed);
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        total += run_once(case, in_process, out, &[]);
                    }
                    total
                })
            });
        }
        group.finish();
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// A bootstrap 95 % interval of the median of `v`: 5000 resamples with replacement, drawn
/// by a fixed xorshift sequence so that the same figures give the same interval.
fn median_interval(v: &[f64]) -> (f64, f64) {
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x % v.len() as u64) as usize
    };
    let mut medians: Vec<f64> = (0..5000)
        .map(|_| median((0..v.len()).map(|_| v[next()]).collect()))
        .collect();
    medians.sort_by(f64::total_cmp);
    (medians[125], medians[4874])
}

/// Runs of the two layouts taken turn about, so that a change in the machine's load between
/// criterion's blocks of samples does not show as overhead (see the module's doc); for the
/// cases criterion timed (a filter on the command line leaves the others out).
fn paired_overheads(out: &Path) {
    let timed = TIMED.lock().unwrap().clone();
    if timed.is_empty() {
        return;
    }
    let n_pairs = std::env::var("COUPLED_RUN_PAIRS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or(PAIRS);
    println!("\ncoupled_run: {n_pairs} pairs of runs taken turn about, three processes over one");
    for case in CASES.iter().filter(|c| timed.contains(&c.name)) {
        let run = |in_process: bool, extra: &[&str]| run_timed(case, in_process, out, extra);
        let start_up: Vec<(Timed, Timed)> = (0..n_pairs)
            .map(|_| (run(true, &["time.steps=1"]), run(false, &["time.steps=1"])))
            .collect();
        let s_in = median(start_up.iter().map(|p| p.0.outside.as_secs_f64()).collect());
        let s_ps = median(start_up.iter().map(|p| p.1.outside.as_secs_f64()).collect());
        // The same from the summaries' wall seconds, for the per-phase estimate.
        let w_in = median(start_up.iter().map(|p| p.0.wall).collect());
        let w_ps = median(start_up.iter().map(|p| p.1.wall).collect());
        // Turn about: odd pairs run three processes first, so that a drift of the machine's
        // speed within a pair does not always favour one layout.
        let timed_pairs: Vec<(Timed, Timed)> = (0..n_pairs)
            .map(|k| {
                if k % 2 == 0 {
                    (run(true, &[]), run(false, &[]))
                } else {
                    let ps = run(false, &[]);
                    (run(true, &[]), ps)
                }
            })
            .collect();
        let pairs: Vec<(f64, f64)> = timed_pairs
            .iter()
            .map(|(i, p)| (i.outside.as_secs_f64(), p.outside.as_secs_f64()))
            .collect();
        let steps = timed_pairs[0].0.steps;
        // Seconds per pair that three processes add outside the fluid's phases, start-ups off.
        let extra: Vec<f64> = timed_pairs
            .iter()
            .map(|(i, p)| (p.wall - p.fluid) - (i.wall - i.fluid) - (w_ps - w_in))
            .collect();
        let unexplained: Vec<f64> = timed_pairs
            .iter()
            .zip(&extra)
            .map(|((i, _), e)| 100.0 * e / (i.wall - w_in))
            .collect();
        let (lo, hi) = median_interval(&unexplained);
        let mut whole: Vec<f64> = pairs.iter().map(|(i, p)| 100.0 * (p / i - 1.0)).collect();
        whole.sort_by(f64::total_cmp);
        let per_step = median(
            pairs
                .iter()
                .map(|(i, p)| 100.0 * ((p - s_ps) / (i - s_in) - 1.0))
                .collect(),
        );
        let list: Vec<String> = whole.iter().map(|o| format!("{o:+.1}")).collect();
        println!("  {}", case.name);
        println!(
            "    whole runs: in-process {:.3} s, processes {:.3} s (medians); overhead {} %, median {:+.1} %",
            median(pairs.iter().map(|p| p.0).collect()),
            median(pairs.iter().map(|p| p.1).collect()),
            list.join(" / "),
            median(whole.clone())
        );
        println!(
            "    start-up (one step): in-process {s_in:.3} s, processes {s_ps:.3} s; overhead per step without it: median {per_step:+.1} %"
        );
        let mut sorted = unexplained.clone();
        sorted.sort_by(f64::total_cmp);
        let per_step_us: Vec<f64> = extra.iter().map(|e| 1e6 * e / steps as f64).collect();
        println!(
            "    not in the fluid's phases ({steps} steps): {:.0} us a step more as processes (median), overhead per step median {:+.2} % (95 % interval of the median {lo:+.2} ... {hi:+.2} %; pairs {:+.1} ... {:+.1} %)",
            median(per_step_us),
            median(unexplained.clone()),
            sorted[0],
            sorted[sorted.len() - 1]
        );
    }
}

fn main() {
    // Build (or find up to date) the executables before anything is timed.
    bin_dir();
    let out = root()
        .join("target")
        .join("bench-runs")
        .join(format!("coupled_run-{}", std::process::id()));
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c, &out);
    c.final_summary();
    // `cargo test --benches` runs each benchmark once (`--test`) to see that it works: no
    // timing, so no paired runs either.
    if !std::env::args().any(|a| a == "--test" || a == "--list") {
        paired_overheads(&out);
    }
    let _ = std::fs::remove_dir_all(&out);
}
