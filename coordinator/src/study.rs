//! Studies: show what accuracy costs in time. A study names a base scene, the keys to vary
//! with their values, and the metric to judge; it runs every variant and writes a CSV, a
//! markdown table and a log-log PNG of relative error against wall time.
//!
//! ```toml
//! name = "cantilever"                      # file names of the outputs
//! title = "Cantilever, alpha = 2: error against beads"
//! scene = "../../configs/cantilever.toml"  # relative to the study file
//! metric = "tip_deflection_over_length"
//! output = "."                             # relative to the study file
//! processes = false                        # true: each variant as three processes
//! [set]                                    # overrides applied to every variant
//! "time.steps" = 40000
//! [[vary]]                                 # variants: the product over all [[vary]]
//! keys = ["fibre.0.beads", "fibre.0.loads.0.force"]   # or key = "..." with plain values
//! values = [[5, [0.0, -1.0, 0.0]], [10, [0.0, -0.2, 0.0]]]
//! [convergence]                            # optional: no analytic reference, a refinement
//! key = "fibre.0.beads"                    # varied key giving the resolution (larger = finer)
//! order = 1.0                              # assumed order of convergence (default 1)
//! [curve]                                  # optional: the metric against a derived number
//! x = "fluid.particle_shear_reynolds"      # a key of the summary's `derived` values
//! [diagram]                                # optional: a regime map (S2023 Fig. 10a)
//! x = "fibre.0.bending_number"             # derived values, as for [curve]; log_x, log_y
//! y = "fluid.confinement"
//! ```
//!
//! With `[diagram]` the study draws `NAME_diagram.png`: every variant at (x, y), coloured by
//! the label of a classifying metric (`orbit`: jeffery, s-turn, s-coiled, stuck; `wrap`).
//!
//! With `[curve]` the study also draws `NAME_curve.png`, the metric against `x` with its
//! reference, and the table gets a column for `x`: for sweeps over a physical parameter,
//! where error against wall time says little.
//!
//! With `[convergence]` the reference of every variant is the Richardson extrapolation of the
//! metric from the two finest variants, `v_f + (v_f - v_c) / ((n_f / n_c)^order - 1)`, so the
//! table and the plot show each variant's distance from the estimated converged value.
//!
//! `coordinator study FILE --replot` rebuilds the table and plots from the runs a previous
//! `study` left in `runs/study/<name>/<variant>/summary.json` (under the current folder, not
//! beside the study file), without running anything;
//! `--jobs N` runs N variants at once as separate `coordinator run` processes ([`Runs`]).
use crate::runner::{self, RunOptions};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Study {
    pub name: String,
    #[serde(default)]
    pub title: Option<String>,
    pub scene: PathBuf,
    pub metric: String,
    #[serde(default = "dot")]
    pub output: PathBuf,
    /// Run the variants as separate processes instead of in-process.
    #[serde(default)]
    pub processes: bool,
    #[serde(default)]
    pub set: BTreeMap<String, toml::Value>,
    pub vary: Vec<Vary>,
    /// A regime map: every variant at (x, y), coloured by the metric's label.
    #[serde(default)]
    pub diagram: Option<Diagram>,
    /// A refinement study: the reference is extrapolated from the two finest variants.
    #[serde(default)]
    pub convergence: Option<Convergence>,
    /// The metric against a number the nodes derive (a parameter sweep).
    #[serde(default)]
    pub curve: Option<Curve>,
}

/// `[curve]`: the abscissa of a metric-against-parameter plot, the name of a number the
/// nodes derive and report in the summary (`derived`), like the axes of `[diagram]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Curve {
    pub x: String,
    #[serde(default)]
    pub log_x: bool,
    #[serde(default)]
    pub log_y: bool,
}

/// `[convergence]`: which varied key measures the resolution, and the assumed order.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Convergence {
    /// A key of a `[[vary]]` entry whose values grow as the discretisation is refined
    /// (points per bead radius, beads per fibre, ...).
    pub key: String,
    /// Order p of the error, `v(n) - v_inf ~ n^-p`.
    #[serde(default = "first_order")]
    pub order: f64,
}

fn first_order() -> f64 {
    1.0
}

/// `[diagram]`: axes of a regime map (e.g. S2023 Fig. 10a, the orbit over K and C), each the
/// name of a number the nodes derive and report in the summary (`derived`), so that an axis
/// can be a dimensionless group that several varied keys set together.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Diagram {
    pub x: String,
    pub y: String,
    #[serde(default)]
    pub log_x: bool,
    #[serde(default)]
    pub log_y: bool,
}

fn dot() -> PathBuf {
    PathBuf::from(".")
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vary {
    #[serde(default)]
    pub key: Option<String>,
    #[serde(default)]
    pub keys: Vec<String>,
    pub values: Vec<toml::Value>,
}

impl Vary {
    /// Each value as a list of (key, value) assignments.
    fn assignments(&self, i: usize) -> Result<Vec<Vec<(String, toml::Value)>>, String> {
        let keys: Vec<String> = match (&self.key, self.keys.is_empty()) {
            (Some(k), true) => vec![k.clone()],
            (None, false) => self.keys.clone(),
            _ => return Err(format!("vary.{i}: give either `key` or `keys`")),
        };
        if self.values.is_empty() {
            return Err(format!(
                "vary.{i}.values: expected at least one value (an empty list makes no variants)"
            ));
        }
        // The same value twice would run the same variants twice.
        for (j, v) in self.values.iter().enumerate() {
            if let Some(k) = self.values[..j].iter().position(|w| w == v) {
                return Err(format!(
                    "vary.{i}.values: {} is given twice (entries {k} and {j}), which would run \
                     the same variants twice; give each value once",
                    toml_inline(v)
                ));
            }
        }
        self.values
            .iter()
            .enumerate()
            .map(|(j, v)| {
                if keys.len() == 1 {
                    return Ok(vec![(keys[0].clone(), v.clone())]);
                }
                match v {
                    toml::Value::Array(a) if a.len() == keys.len() => {
                        Ok(keys.iter().cloned().zip(a.iter().cloned()).collect())
                    }
                    _ => Err(format!(
                        "vary.{i}.values.{j}: expected a list of {} values, one per key",
                        keys.len()
                    )),
                }
            })
            .collect()
    }

    /// The keys that label this entry's rows: the first, then, while two rows still read
    /// alike, the next key that tells the most of them apart (a key that follows another,
    /// such as the steps that follow a gap, adds nothing and is left out).
    fn label_keys(&self, i: usize) -> Result<Vec<String>, String> {
        let rows = self.assignments(i)?;
        let Some(first) = rows.first() else {
            return Ok(Vec::new());
        };
        let all: Vec<&String> = first.iter().map(|(k, _)| k).collect();
        let distinct = |keys: &[&String]| {
            let mut seen: Vec<String> = rows
                .iter()
                .map(|r| {
                    r.iter()
                        .filter(|(k, _)| keys.contains(&k))
                        .map(|(_, v)| toml_inline(v))
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .collect();
            seen.sort();
            seen.dedup();
            seen.len()
        };
        let mut chosen = vec![all[0]];
        while distinct(&chosen) < rows.len() {
            let with = |k: &String| {
                let mut c = chosen.clone();
                c.push(k);
                distinct(&c)
            };
            // The most rows told apart; the earliest key on a tie.
            let best = all
                .iter()
                .enumerate()
                .filter(|(_, k)| !chosen.contains(k))
                .max_by_key(|(j, k)| (with(k), std::cmp::Reverse(*j)));
            match best {
                Some((_, k)) if with(k) > distinct(&chosen) => chosen.push(k),
                _ => break,
            }
        }
        Ok(all
            .into_iter()
            .filter(|k| chosen.contains(k))
            .cloned()
            .collect())
    }
}

/// One row of the study's table.
#[derive(Debug, Clone)]
pub struct Row {
    pub label: String,
    pub value: f64,
    pub reference: Option<f64>,
    pub relative_error: Option<f64>,
    pub wall_seconds: f64,
    pub steps: u64,
    pub status: String,
    /// How many warnings the run's summary has (beads in a wall, a state not yet steady,
    /// ...): shown next to the status in the markdown table.
    pub warnings: usize,
    /// The metric's label, for a categorical metric (`orbit`).
    pub class: Option<String>,
    /// The diagram's coordinates, read from the summary's derived values.
    pub point: Option<(f64, f64)>,
    /// The value of the `[convergence]` key in this variant.
    pub resolution: Option<f64>,
    /// The `[curve]` abscissa, read from the summary's derived values.
    pub curve_x: Option<f64>,
}

/// Read a study file; returns the study and the directory its relative paths start from.
fn load(path: &Path) -> Result<(Study, PathBuf), String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read study file {}: {e}", path.display()))?;
    let study: Study =
        serde_path_to_error::deserialize(toml::Deserializer::parse(&text).map_err(|e| {
            format!(
                "{} is not valid TOML: {}",
                path.display(),
                e.to_string().trim()
            )
        })?)
        .map_err(|e| {
            let msg = crate::scene::key_message(
                &path.display().to_string(),
                &e.path().to_string(),
                &e.inner().to_string(),
                (&["vary"], &["set", "diagram", "convergence", "curve"]),
            );
            // A scene given where a study was meant.
            match text.parse::<toml::Table>() {
                Ok(t) if t.contains_key("time") && !t.contains_key("vary") => format!(
                    "{msg}; {} looks like a scene (it has [time]): run it with `coordinator \
                     run`, or name it as `scene` in a study file",
                    path.display()
                ),
                _ => msg,
            }
        })?;
    // The name names the study's files and its runs' folder.
    if study.name.is_empty()
        || study
            .name
            .contains(|c: char| c == '/' || c == '\\' || c.is_control())
        || study.name == "."
        || study.name == ".."
    {
        return Err(format!(
            "{}: key `name`: expected a file name (no `/`), got \"{}\"",
            path.display(),
            study.name
        ));
    }
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    Ok((study, base))
}

/// Read and run a study file (or, with `replot`, reuse its previous runs); returns the
/// markdown table and a line naming the files written.
pub fn run_file(path: &Path, out: Option<&Path>, runs: Runs) -> Result<String, String> {
    let (study, base) = load(path)?;
    // Without `./` in the middle of the names printed (`output = "."`).
    let out_dir = out.map(Path::to_path_buf).unwrap_or_else(|| {
        base.join(&study.output)
            .components()
            .filter(|c| !matches!(c, std::path::Component::CurDir))
            .collect()
    });
    run(&study, &base.join(&study.scene), &out_dir, runs)
}

/// Check a study file without running it: it parses, and every variant's scene passes
/// `coordinator check` (its overrides apply, the nodes accept it, the time step is within
/// the limits) with the study's metric among its metrics. Returns the number of variants.
pub fn check_file(path: &Path) -> Result<usize, String> {
    let (study, base) = load(path)?;
    let variants = prepare(&study, &base.join(&study.scene))?;
    for v in &variants {
        let (_, configured, _) =
            runner::check(&v.scene).map_err(|e| format!("variant {}: {e}", v.label))?;
        // The plot's axes are derived values (a run reports the same ones `check` does).
        let axes = study.curve.iter().map(|c| ("curve.x", &c.x)).chain(
            study
                .diagram
                .iter()
                .flat_map(|d| [("diagram.x", &d.x), ("diagram.y", &d.y)]),
        );
        for (key, name) in axes {
            if !configured.derived.iter().any(|(k, _)| k == name) {
                let known: Vec<&str> = configured.derived.iter().map(|(k, _)| k.as_str()).collect();
                return Err(format!(
                    "{key} = `{name}` is not among the derived values of variant {}{} (they are: \
                     {})",
                    v.label,
                    cosim::scene_keys::did_you_mean(name, known.iter().copied()),
                    known.join(", ")
                ));
            }
        }
    }
    Ok(variants.len())
}

/// How a study gets the runs of its variants.
#[derive(Debug, Clone, Copy)]
pub enum Runs<'a> {
    /// One variant after another, in this process: wall times free of contention.
    OneByOne,
    /// The runs an earlier study of the same file left in `runs/study/<name>/` (`--replot`).
    Reuse,
    /// `jobs` variants at once, each a `coordinator run` of the executable `exe`, its output
    /// in `runs/study/<name>/<variant>/run.log`. Results are the same bits; the wall times
    /// then include the contention between the runs.
    Parallel { exe: &'a Path, jobs: usize },
}

/// One variant of a study, ready to run.
struct Variant {
    label: String,
    overrides: Vec<String>,
    scene: crate::scene::LoadedScene,
    run_dir: PathBuf,
    resolution: Option<f64>,
}

/// Run the variants as `coordinator run` processes of `exe`, `jobs` at a time; each one's
/// standard output and error go to `run.log` in its run directory.
fn run_in_parallel(
    study: &Study,
    scene_path: &Path,
    variants: &[Variant],
    exe: &Path,
    jobs: usize,
) -> Result<(), String> {
    let mut running: Vec<(usize, std::process::Child)> = Vec::new();
    let mut next = 0;
    while next < variants.len() || !running.is_empty() {
        while running.len() < jobs.max(1) && next < variants.len() {
            let v = &variants[next];
            std::fs::create_dir_all(&v.run_dir)
                .map_err(|e| format!("cannot create {}: {e}", v.run_dir.display()))?;
            // A summary left by an earlier study must not pass for this run's.
            let _ = std::fs::remove_file(v.run_dir.join("summary.json"));
            let log = std::fs::File::create(v.run_dir.join("run.log"))
                .map_err(|e| format!("cannot write {}: {e}", v.run_dir.display()))?;
            let mut c = std::process::Command::new(exe);
            c.arg("run")
                .arg(scene_path)
                .arg("--quiet")
                .arg("--out")
                .arg(&v.run_dir);
            if !study.processes {
                c.arg("--in-process");
            }
            for o in &v.overrides {
                c.arg("--set").arg(o);
            }
            let err = log.try_clone().map_err(|e| e.to_string())?;
            let child = c
                .stdout(log)
                .stderr(err)
                .spawn()
                .map_err(|e| format!("cannot start {}: {e}", exe.display()))?;
            eprintln!(
                "study {}: variant {}/{} started: {}",
                study.name,
                next + 1,
                variants.len(),
                v.label
            );
            running.push((next, child));
            next += 1;
        }
        // Reap whatever has finished; the rest keep running.
        let mut i = 0;
        let mut reaped = false;
        while i < running.len() {
            match running[i].1.try_wait() {
                Ok(Some(status)) => {
                    let (k, _) = running.swap_remove(i);
                    eprintln!(
                        "study {}: variant {}/{} done ({status}): {}",
                        study.name,
                        k + 1,
                        variants.len(),
                        variants[k].label
                    );
                    reaped = true;
                }
                Ok(None) => i += 1,
                Err(e) => return Err(format!("waiting for a study run: {e}")),
            }
        }
        if !reaped {
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }
    Ok(())
}

/// The last non-empty line of a run's log, to say why a parallel run left no summary.
fn last_log_line(run_dir: &Path) -> String {
    std::fs::read_to_string(run_dir.join("run.log"))
        .ok()
        .and_then(|t| {
            t.lines()
                .rev()
                .find(|l| !l.trim().is_empty())
                .map(str::to_string)
        })
        .unwrap_or_default()
}

fn toml_inline(v: &toml::Value) -> String {
    v.to_string()
}

/// A key set by `[set]` or varied by one `[[vary]]` entry only: a second would override the
/// first in every variant, so that variants meant to differ ran the same scene.
fn one_owner_per_key(study: &Study) -> Result<(), String> {
    let mut owner: BTreeMap<&str, String> = study
        .set
        .keys()
        .map(|k| (k.as_str(), "set by [set]".to_string()))
        .collect();
    for (i, v) in study.vary.iter().enumerate() {
        for k in v.key.iter().chain(&v.keys) {
            if let Some(first) = owner.insert(k, format!("varied by vary.{i}")) {
                return Err(format!(
                    "vary.{i}: `{k}` is already {first}, and the later would override the \
                     earlier in every variant; give each key in one place"
                ));
            }
        }
    }
    Ok(())
}

/// Every variant of `study`: its overrides, label and loaded scene, in the order of the
/// table (the last `[[vary]]` entry varies fastest).
fn prepare(study: &Study, scene_path: &Path) -> Result<Vec<Variant>, String> {
    one_owner_per_key(study)?;
    let mut variants: Vec<Vec<(String, toml::Value)>> = vec![Vec::new()];
    for (i, v) in study.vary.iter().enumerate() {
        let options = v.assignments(i)?;
        variants = variants
            .into_iter()
            .flat_map(|prev| {
                options.iter().map(move |o| {
                    let mut p = prev.clone();
                    p.extend(o.iter().cloned());
                    p
                })
            })
            .collect();
    }
    let fixed: Vec<String> = study
        .set
        .iter()
        .map(|(k, v)| format!("{k}={}", toml_inline(v)))
        .collect();
    let label_keys: Vec<String> = study
        .vary
        .iter()
        .enumerate()
        .map(|(i, v)| v.label_keys(i))
        .collect::<Result<Vec<_>, _>>()?
        .concat();
    let mut prepared = Vec::with_capacity(variants.len());
    for (i, assignment) in variants.iter().enumerate() {
        let mut overrides = fixed.clone();
        overrides.extend(
            assignment
                .iter()
                .map(|(k, v)| format!("{k}={}", toml_inline(v))),
        );
        // Label a variant by the keys that tell each [[vary]] entry's rows apart.
        let label = assignment
            .iter()
            .filter(|(k, _)| label_keys.contains(k))
            .map(|(k, v)| format!("{}={}", k.rsplit('.').next().unwrap_or(k), toml_inline(v)))
            .collect::<Vec<_>>()
            .join(" ");
        let scene = crate::scene::load(Some(scene_path), &overrides)
            .map_err(|e| format!("variant {label}: {e}"))?;
        if !scene.scene.analysis.metrics.contains(&study.metric) {
            let asked = &scene.scene.analysis.metrics;
            return Err(format!(
                "the study's metric `{}` is not in the scene's analysis.metrics{} (the scene \
                 asks for: {}; add it with [set] \"analysis.metrics\" = [...])",
                study.metric,
                cosim::scene_keys::did_you_mean(&study.metric, asked.iter().map(String::as_str)),
                if asked.is_empty() {
                    "none".to_string()
                } else {
                    asked.join(", ")
                }
            ));
        }
        let run_dir = PathBuf::from("runs")
            .join("study")
            .join(&study.name)
            .join(i.to_string());
        let resolution = match &study.convergence {
            Some(c) => Some(
                assignment
                    .iter()
                    .find(|(k, _)| *k == c.key)
                    .and_then(|(_, v)| v.as_float().or(v.as_integer().map(|i| i as f64)))
                    .ok_or_else(|| {
                        format!(
                            "convergence.key `{}` must be a varied key with numeric values",
                            c.key
                        )
                    })?,
            ),
            None => None,
        };
        prepared.push(Variant {
            label,
            overrides,
            scene,
            run_dir,
            resolution,
        });
    }
    Ok(prepared)
}

/// Run every variant of `study` on `scene_path` as `runs` says (or read the summaries of an
/// earlier run of it); write `<name>.csv`, `.md`, `.png` to `out`; returns the markdown table.
pub fn run(study: &Study, scene_path: &Path, out: &Path, runs: Runs) -> Result<String, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let prepared = prepare(study, scene_path)?;
    let count = prepared.len();
    if let Runs::Parallel { exe, jobs } = runs {
        run_in_parallel(study, scene_path, &prepared, exe, jobs)?;
    }
    let mut rows = Vec::new();
    for (i, v) in prepared.into_iter().enumerate() {
        let label = v.label.clone();
        let resolution = v.resolution;
        match variant_summary(study, (i, count), v, runs) {
            Ok(summary) => rows.push(row(study, label, resolution, &summary)?),
            // A map over parameters meets variants the method cannot carry: keep the row
            // (with the reason on standard error) instead of losing the study.
            Err(e) if study.diagram.is_some() => {
                eprintln!("study {}: variant {label} failed: {e}", study.name);
                rows.push(Row {
                    label,
                    value: f64::NAN,
                    reference: None,
                    relative_error: None,
                    wall_seconds: 0.0,
                    steps: 0,
                    status: "failed".into(),
                    warnings: 0,
                    class: None,
                    point: None,
                    resolution,
                    curve_x: None,
                });
            }
            Err(e) => return Err(format!("variant {label}: {e}")),
        }
    }
    let mut note = String::new();
    if let Some(c) = &study.convergence {
        let limit = extrapolate(&rows, c.order)?;
        for r in rows.iter_mut().filter(|r| r.value.is_finite()) {
            r.reference = Some(limit);
            r.relative_error = Some(((r.value - limit) / limit).abs());
        }
        note = format!(
            "\nReference: {limit:.6}, the Richardson extrapolation (order {}) of the two finest \
             variants in `{}`; the relative error of each variant is its distance from it.\n",
            c.order, c.key
        );
    }
    write_outputs(study, &rows, &note, out)
}

/// The summary of variant `i` of `count`: run now, or read from its run directory (where
/// the parallel runs or an earlier study left it).
fn variant_summary(
    study: &Study,
    (i, count): (usize, usize),
    v: Variant,
    runs: Runs,
) -> Result<serde_json::Value, runner::RunError> {
    let Variant {
        label,
        scene,
        run_dir,
        ..
    } = v;
    match runs {
        Runs::OneByOne => {
            eprintln!("study {}: variant {}/{}: {label}", study.name, i + 1, count);
            let opts = RunOptions::quiet(run_dir, !study.processes);
            runner::run(&scene, &opts).map(|r| r.summary)
        }
        Runs::Reuse => {
            let path = run_dir.join("summary.json");
            if !path.is_file() {
                // The runs lie under the folder the study ran from, not beside its file.
                let here = std::env::current_dir().map_or("the current folder".to_string(), |d| {
                    d.display().to_string()
                });
                return Err(runner::RunError {
                    message: format!(
                        "--replot: there is no {} under {here}: a study keeps its runs in \
                         runs/study/{}/ under the folder it ran from; run --replot from that \
                         folder, or run the study once without --replot",
                        path.display(),
                        study.name
                    ),
                });
            }
            read_summary(&path).map_err(|e| runner::RunError {
                message: format!("--replot: {e}"),
            })
        }
        Runs::Parallel { .. } => {
            // A run that failed after step 0 writes its summary (status `failed`, the
            // error); one refused before writes none, and its log's last line says why.
            read_summary(&run_dir.join("summary.json"))
                .map_err(|e| runner::RunError {
                    message: format!("{e}; its log ends: {}", last_log_line(&run_dir)),
                })
                .and_then(|s| match s["status"].as_str() {
                    Some("failed") => Err(runner::RunError {
                        message: s["error"].as_str().unwrap_or("failed").to_string(),
                    }),
                    _ => Ok(s),
                })
        }
    }
}

/// The table row of a variant from its summary `s`: the metric's value, reference and error,
/// and the diagram's and curve's coordinates from the derived values.
fn row(
    study: &Study,
    label: String,
    resolution: Option<f64>,
    s: &serde_json::Value,
) -> Result<Row, String> {
    let m = &s["metrics"][&study.metric];
    // A run that completed without the study's metric (too short for a period, ...): keep
    // the row, say why.
    let status = match s["metric_errors"][&study.metric].as_str() {
        Some(why) => {
            eprintln!("study {}: variant {label}: {why}", study.name);
            "no metric".to_string()
        }
        None => s["status"].as_str().unwrap_or("").to_string(),
    };
    let warnings = s["warnings"].as_array().map_or(0, Vec::len);
    for w in s["warnings"].as_array().into_iter().flatten() {
        eprintln!(
            "study {}: variant {label}: warning: {}",
            study.name,
            w.as_str().unwrap_or_default()
        );
    }
    let point = study
        .diagram
        .as_ref()
        .and_then(|d| Some((s["derived"][&d.x].as_f64()?, s["derived"][&d.y].as_f64()?)));
    let curve_x = match &study.curve {
        Some(c) => Some(s["derived"][&c.x].as_f64().ok_or_else(|| {
            format!(
                "variant {label}: curve.x `{}` is not among the summary's derived values",
                c.x
            )
        })?),
        None => None,
    };
    Ok(Row {
        label,
        value: m["value"].as_f64().unwrap_or(f64::NAN),
        reference: m["reference"].as_f64(),
        relative_error: m["relative_error"].as_f64(),
        wall_seconds: s["wall_seconds"].as_f64().unwrap_or(0.0),
        steps: s["steps"].as_u64().unwrap_or(0),
        status,
        warnings,
        class: m["label"].as_str().map(str::to_string),
        point,
        resolution,
        curve_x,
    })
}

/// The study's files in `out`: `<name>.csv` and `.md` (the table, the keys its labels leave
/// out, then `note`), `.png` (error against wall time, where the metric has a reference),
/// `_curve.png` and `_diagram.png` where the study asks for them. Returns the markdown table
/// followed by a line naming the files written.
fn write_outputs(study: &Study, rows: &[Row], note: &str, out: &Path) -> Result<String, String> {
    let mut written = vec![
        out.join(format!("{}.csv", study.name)),
        out.join(format!("{}.md", study.name)),
    ];
    let curve_name = study.curve.as_ref().map(|c| c.x.as_str());
    let write = |path: &Path, text: &str| {
        std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
    };
    write(&written[0], &render_csv(rows, curve_name))?;
    let title = study.title.clone().unwrap_or_else(|| study.name.clone());
    let md = render_markdown(&title, &study.metric, rows, curve_name) + &unlabelled(study) + note;
    write(&written[1], &md)?;
    let points: Vec<crate::plot::CostPoint> = rows
        .iter()
        .filter_map(|r| {
            r.relative_error.map(|e| crate::plot::CostPoint {
                wall_seconds: r.wall_seconds,
                error: e,
                label: r.label.clone(),
            })
        })
        .collect();
    // A categorical metric (no reference) has no error to plot.
    if !points.is_empty() {
        let png = out.join(format!("{}.png", study.name));
        crate::plot::error_against_time(
            &png,
            &title,
            &format!("relative error of {}", study.metric),
            &points,
        )?;
        written.push(png);
    }
    if let Some(c) = &study.curve {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .filter_map(|r| Some((r.curve_x?, r.value)))
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        // One reference line when every row has the same one (an analytic or published value).
        let refs: Vec<f64> = rows.iter().filter_map(|r| r.reference).collect();
        let reference = refs
            .first()
            .copied()
            .filter(|r0| refs.iter().all(|r| r == r0) && refs.len() == rows.len());
        let png = out.join(format!("{}_curve.png", study.name));
        crate::plot::metric_against(
            &png,
            &title,
            (&c.x, c.log_x),
            (&study.metric, c.log_y),
            &points,
            reference,
        )?;
        written.push(png);
    }
    if let Some(d) = &study.diagram {
        let points: Vec<crate::plot::ClassPoint> = rows
            .iter()
            .filter_map(|r| {
                let (x, y) = r.point?;
                Some(crate::plot::ClassPoint {
                    x,
                    y,
                    class: r.class.clone().unwrap_or_else(|| r.status.clone()),
                })
            })
            .collect();
        let png = out.join(format!("{}_diagram.png", study.name));
        crate::plot::regime_map(&png, &title, (&d.x, d.log_x), (&d.y, d.log_y), &points)?;
        written.push(png);
    }
    let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    Ok(format!(
        "{md}\nwrote {}\nruns in runs/study/{}/ (--replot reads them from this folder)",
        names.join(", "),
        study.name
    ))
}

fn read_summary(path: &Path) -> Result<serde_json::Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        format!(
            "cannot read {} (run the study once without --replot): {e}",
            path.display()
        )
    })?;
    serde_json::from_str(&text).map_err(|e| format!("{} is not JSON: {e}", path.display()))
}

/// The converged value estimated from the two finest completed variants: with
/// v(n) = v_inf + a n^-p, v_inf = v_f + (v_f - v_c) / ((n_f / n_c)^p - 1).
pub fn extrapolate(rows: &[Row], order: f64) -> Result<f64, String> {
    let mut pts: Vec<(f64, f64)> = rows
        .iter()
        .filter_map(|r| Some((r.resolution?, r.value)))
        .filter(|(n, v)| n.is_finite() && *n > 0.0 && v.is_finite())
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (Some(&(nf, vf)), Some(&(nc, vc))) = (pts.last(), pts.iter().rev().nth(1)) else {
        return Err("[convergence] needs at least two completed variants".into());
    };
    let ratio = (nf / nc).powf(order);
    if !(order > 0.0 && ratio > 1.0) {
        return Err(format!(
            "[convergence]: the two finest variants must differ in resolution and the order \
             be positive (n {nc} and {nf}, order {order})"
        ));
    }
    Ok(vf + (vf - vc) / (ratio - 1.0))
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{v:.6}"))
}

/// The rows as CSV; with a `[curve]` (named `curve`) a last column `curve_x` holds its abscissa.
pub fn render_csv(rows: &[Row], curve: Option<&str>) -> String {
    let mut s =
        String::from("variant,value,reference,relative_error,wall_seconds,steps,status,class,x,y");
    s.push_str(if curve.is_some() { ",curve_x\n" } else { "\n" });
    for r in rows {
        let _ = write!(
            s,
            "\"{}\",{},{},{},{:.4},{},{},{},{},{}",
            r.label,
            r.value,
            r.reference.map_or(String::new(), |v| v.to_string()),
            r.relative_error.map_or(String::new(), |v| v.to_string()),
            r.wall_seconds,
            r.steps,
            r.status,
            r.class.as_deref().unwrap_or(""),
            r.point.map_or(String::new(), |p| p.0.to_string()),
            r.point.map_or(String::new(), |p| p.1.to_string()),
        );
        if curve.is_some() {
            let _ = write!(s, ",{}", r.curve_x.map_or(String::new(), |v| v.to_string()));
        }
        s.push('\n');
    }
    s
}

/// A line under the table naming the keys of `[[vary]]` groups that the rows' labels leave
/// out (a label shows only the keys that tell its group's rows apart), so that a reader of
/// `grid=[180, 180]` knows the bead radius changed with it; empty where labels show every key.
fn unlabelled(study: &Study) -> String {
    let hidden: Vec<String> = study
        .vary
        .iter()
        .enumerate()
        .flat_map(|(i, v)| {
            let shown = v.label_keys(i).unwrap_or_default();
            v.key
                .iter()
                .chain(&v.keys)
                // The steps have a column of their own.
                .filter(|k| !shown.contains(k) && k.as_str() != "time.steps")
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
        })
        .collect();
    if hidden.is_empty() {
        String::new()
    } else {
        format!(
            "\nVaried with the keys the labels show (values in the study file): {}.\n",
            hidden.join(", ")
        )
    }
}

/// The rows as a markdown table; with a `[curve]` (named `curve`) a column for its abscissa
/// follows the variant.
pub fn render_markdown(title: &str, metric: &str, rows: &[Row], curve: Option<&str>) -> String {
    let (head, rule) = match curve {
        Some(x) => (format!(" {x} |"), "---|"),
        None => (String::new(), ""),
    };
    let mut s = format!("### {title}\n\n| variant |{head} {metric} | reference | relative error | wall time (s) | steps | status |\n|---|{rule}---|---|---|---|---|---|\n");
    for r in rows {
        let x = match curve {
            Some(_) => format!(
                " {} |",
                r.curve_x.map_or(String::new(), |v| format!("{v:.6}"))
            ),
            None => String::new(),
        };
        let _ = writeln!(
            s,
            "| {} |{x} {} | {} | {} | {:.3} | {} | {} |",
            r.label,
            match &r.class {
                // The orbit's value is only the class's code (metrics.rs); a wrap's is the
                // wrapped fraction, worth reading next to its class.
                Some(c) if metric == "orbit" => c.clone(),
                Some(c) => format!("{c} ({:.6})", r.value),
                None => format!("{:.6}", r.value),
            },
            fmt_opt(r.reference),
            r.relative_error
                .map_or(String::new(), |e| format!("{:.3} %", 100.0 * e)),
            r.wall_seconds,
            r.steps,
            match r.warnings {
                0 => r.status.clone(),
                1 => format!("{} (1 warning)", r.status),
                n => format!("{} ({n} warnings)", r.status),
            }
        );
    }
    if rows.iter().any(|r| r.warnings > 0) {
        s.push_str(
            "\nA run's warnings are in its summary.json (`warnings`), and the study printed \
             them as it ran.\n",
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(n: f64, v: f64) -> Row {
        Row {
            label: format!("n={n}"),
            value: v,
            reference: None,
            relative_error: None,
            wall_seconds: 1.0,
            steps: 1,
            status: "completed".into(),
            warnings: 0,
            class: None,
            point: None,
            resolution: Some(n),
            curve_x: None,
        }
    }

    #[test]
    fn a_variant_is_labelled_by_the_keys_that_tell_its_rows_apart() {
        let vary = |text: &str| -> Vary { toml::from_str(text).unwrap() };
        // fpd_critical_points: the gap alone repeats at C = 0.2, the Reynolds number tells
        // those rows apart, and the steps follow the gap.
        let v = vary(
            "keys = [\"fluid.confinement\", \"fluid.particle_shear_reynolds\", \"time.steps\"]\n\
             values = [[0.5, 1.5, 48000], [0.55, 1.5, 43800], [0.2, 1.0, 120000], [0.2, 2.0, 120000]]",
        );
        assert_eq!(
            v.label_keys(0).unwrap(),
            ["fluid.confinement", "fluid.particle_shear_reynolds"]
        );
        let v = vary(
            "keys = [\"fluid.confinement\", \"time.steps\"]\nvalues = [[0.3, 79800], [0.5, 48000]]",
        );
        assert_eq!(v.label_keys(0).unwrap(), ["fluid.confinement"]);
        let v = vary("key = \"fibre.0.bending_number\"\nvalues = [3.3]");
        assert_eq!(v.label_keys(0).unwrap(), ["fibre.0.bending_number"]);
        let e = vary("key = \"fibre.0.beads\"\nvalues = [4, 5, 4]")
            .label_keys(1)
            .unwrap_err();
        assert_eq!(
            e,
            "vary.1.values: 4 is given twice (entries 0 and 2), which would run the same \
             variants twice; give each value once"
        );
        // An empty list would make a study of no variants, which "passes" doing nothing.
        let e = vary("key = \"fibre.0.beads\"\nvalues = []")
            .label_keys(2)
            .unwrap_err();
        assert!(
            e.starts_with("vary.2.values: expected at least one value"),
            "{e}"
        );
    }

    /// A `[curve]` adds its abscissa as a column of the table and as the CSV's last column;
    /// without one both keep their usual columns.
    #[test]
    fn a_curve_adds_its_abscissa_to_the_table_and_the_csv() {
        let mut r = row(8.0, 0.25);
        r.curve_x = Some(1.5);
        let md = render_markdown("t", "m", std::slice::from_ref(&r), Some("fluid.re"));
        assert!(
            md.contains("| variant | fluid.re | m | reference |"),
            "{md}"
        );
        assert!(md.contains("| n=8 | 1.500000 | 0.250000 |"), "{md}");
        let csv = render_csv(std::slice::from_ref(&r), Some("fluid.re"));
        let lines: Vec<&str> = csv.lines().collect();
        assert!(lines[0].ends_with(",x,y,curve_x"));
        assert!(lines[1].ends_with(",1.5"));
        let plain = render_csv(std::slice::from_ref(&r), None);
        assert!(plain.lines().next().unwrap().ends_with(",x,y"));
        assert_eq!(plain.lines().nth(1).unwrap().split(',').count(), 10);
        assert!(!render_markdown("t", "m", &[r], None).contains("fluid.re"));
    }

    /// A study of scene `x.toml` and metric `m`, with the tables `rest`.
    fn study_of(rest: &str) -> Study {
        toml::from_str(&format!(
            "name = \"s\"\nscene = \"x.toml\"\nmetric = \"m\"\n{rest}"
        ))
        .unwrap()
    }

    /// The keys of a `[[vary]]` group that its labels leave out are named under the table.
    #[test]
    fn keys_the_labels_leave_out_are_named_under_the_table() {
        let study = |vary: &str| study_of(&format!("[[vary]]\n{vary}"));
        let grouped = study(
            "keys = [\"fluid.grid\", \"fibre.0.bead_radius\", \"time.dt\"]\n\
             values = [[[180, 180], 6.0, 0.7], [[270, 270], 9.0, 1.575]]",
        );
        assert_eq!(
            unlabelled(&grouped),
            "\nVaried with the keys the labels show (values in the study file): \
             `fibre.0.bead_radius`, `time.dt`.\n"
        );
        assert_eq!(
            unlabelled(&study("key = \"fluid.xi\"\nvalues = [1, 2]")),
            ""
        );
    }

    /// A key given twice (in [set] and a [[vary]] entry, or in two entries) is refused: the
    /// later would override the earlier, and variants meant to differ would run one scene.
    #[test]
    fn a_key_is_given_in_one_place_only() {
        let two = study_of(
            "[[vary]]\nkey = \"fibre.0.beads\"\nvalues = [4, 5]\n\
             [[vary]]\nkeys = [\"time.dt\", \"fibre.0.beads\"]\nvalues = [[0.1, 6]]\n",
        );
        assert_eq!(
            one_owner_per_key(&two).unwrap_err(),
            "vary.1: `fibre.0.beads` is already varied by vary.0, and the later would \
             override the earlier in every variant; give each key in one place"
        );
        let set = study_of("[set]\n\"time.dt\" = 0.1\n[[vary]]\nkey = \"time.dt\"\nvalues = [1]\n");
        assert!(one_owner_per_key(&set)
            .unwrap_err()
            .starts_with("vary.0: `time.dt` is already set by [set]"));
        assert!(
            one_owner_per_key(&study_of("[[vary]]\nkey = \"time.dt\"\nvalues = [1]\n")).is_ok()
        );
    }

    /// A class is shown alone for `orbit`, whose value is only the class's code, and with
    /// its value for other classifying metrics (`wrap`: the wrapped fraction).
    #[test]
    fn an_orbit_cell_shows_its_class_and_a_wrap_cell_its_fraction_too() {
        let mut r = row(8.0, 1.0);
        r.class = Some("jeffery".into());
        let md = render_markdown("t", "orbit", std::slice::from_ref(&r), None);
        assert!(md.contains("| n=8 | jeffery | "), "{md}");
        r.class = Some("full".into());
        r.value = 0.7565195983599549;
        let md = render_markdown("t", "wrap", std::slice::from_ref(&r), None);
        assert!(md.contains("| n=8 | full (0.756520) | "), "{md}");
        assert!(!md.contains("warning"));
        // A run that warned says so next to its status.
        r.warnings = 2;
        let md = render_markdown("t", "wrap", &[r], None);
        assert!(md.contains("| completed (2 warnings) |"), "{md}");
        assert!(
            md.contains("A run's warnings are in its summary.json"),
            "{md}"
        );
    }

    /// v(n) = 2 + 3 n^-p sampled at three resolutions, in any order: the two finest give
    /// v_inf = 2 to round-off for the matching order; assuming first order for second-order
    /// data overshoots the limit (here 1.875, against 2 and a finest value of 2.083).
    #[test]
    fn richardson_limit_of_a_power_law() {
        for p in [1.0, 2.0] {
            let v = |n: f64| 2.0 + 3.0 * n.powf(-p);
            let rows = [row(4.0, v(4.0)), row(2.0, v(2.0)), row(6.0, v(6.0))];
            let limit = extrapolate(&rows, p).unwrap();
            assert!((limit - 2.0).abs() < 1e-12, "order {p}: {limit}");
        }
        let v = |n: f64| 2.0 + 3.0 / (n * n);
        let first = extrapolate(&[row(4.0, v(4.0)), row(6.0, v(6.0))], 1.0).unwrap();
        assert!((first - 1.875).abs() < 1e-12, "{first}");
    }

    #[test]
    fn richardson_needs_two_distinct_resolutions() {
        assert!(extrapolate(&[row(4.0, 1.0)], 1.0).is_err());
        assert!(extrapolate(&[row(4.0, 1.0), row(4.0, 1.1)], 1.0).is_err());
        assert!(extrapolate(&[row(4.0, 1.0), row(f64::NAN, 1.1)], 1.0).is_err());
        assert!(extrapolate(&[row(2.0, 1.0), row(4.0, 1.1)], 0.0).is_err());
    }
}
