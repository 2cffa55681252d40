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
//! [set]                                    # overrides applied to every variant
//! "time.steps" = 40000
//! [[vary]]                                 # variants: the product over all [[vary]]
//! keys = ["fibre.0.beads", "fibre.0.loads.0.force"]   # or key = "..." with plain values
//! values = [[5, [0.0, -1.0, 0.0]], [10, [0.0, -0.2, 0.0]]]
//! ```
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
    /// The metric's label, for a categorical metric (`orbit`).
    pub class: Option<String>,
    /// The diagram's coordinates, read from the summary's derived values.
    pub point: Option<(f64, f64)>,
}

/// Read and run a study file; returns the markdown table.
pub fn run_file(path: &Path, out: Option<&Path>) -> Result<String, String> {
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
            format!(
                "{}: key `{}`: {}",
                path.display(),
                e.path(),
                e.inner().to_string().trim()
            )
        })?;
    let base = path.parent().unwrap_or(Path::new("."));
    let out_dir = out
        .map(Path::to_path_buf)
        .unwrap_or_else(|| base.join(&study.output));
    run(&study, &base.join(&study.scene), &out_dir)
}

fn toml_inline(v: &toml::Value) -> String {
    v.to_string()
}

/// Run every variant of `study` on `scene_path`; write `<name>.csv`, `.md`, `.png` to `out`.
pub fn run(study: &Study, scene_path: &Path, out: &Path) -> Result<String, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
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
    let mut rows = Vec::new();
    for (i, assignment) in variants.iter().enumerate() {
        let mut overrides = fixed.clone();
        overrides.extend(
            assignment
                .iter()
                .map(|(k, v)| format!("{k}={}", toml_inline(v))),
        );
        // Label a variant by the first key of each [[vary]] entry; the others follow it.
        let label = assignment
            .iter()
            .filter(|(k, _)| {
                study
                    .vary
                    .iter()
                    .any(|v| v.key.as_ref() == Some(k) || v.keys.first() == Some(k))
            })
            .map(|(k, v)| format!("{}={}", k.rsplit('.').next().unwrap_or(k), toml_inline(v)))
            .collect::<Vec<_>>()
            .join(" ");
        let scene = crate::scene::load(Some(scene_path), &overrides)
            .map_err(|e| format!("variant {label}: {e}"))?;
        if !scene.scene.analysis.metrics.contains(&study.metric) {
            return Err(format!(
                "the study's metric `{}` is not in the scene's analysis.metrics",
                study.metric
            ));
        }
        let run_dir = PathBuf::from("runs")
            .join("study")
            .join(&study.name)
            .join(i.to_string());
        let opts = RunOptions::quiet(run_dir, !study.processes);
        eprintln!(
            "study {}: variant {}/{}: {label}",
            study.name,
            i + 1,
            variants.len()
        );
        let result = match runner::run(&scene, &opts) {
            Ok(r) => r,
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
                    class: None,
                    point: None,
                });
                continue;
            }
            Err(e) => return Err(format!("variant {label}: {e}")),
        };
        let s = &result.summary;
        let m = &s["metrics"][&study.metric];
        let point = study
            .diagram
            .as_ref()
            .and_then(|d| Some((s["derived"][&d.x].as_f64()?, s["derived"][&d.y].as_f64()?)));
        rows.push(Row {
            label,
            value: m["value"].as_f64().unwrap_or(f64::NAN),
            reference: m["reference"].as_f64(),
            relative_error: m["relative_error"].as_f64(),
            wall_seconds: s["wall_seconds"].as_f64().unwrap_or(0.0),
            steps: s["steps"].as_u64().unwrap_or(0),
            status: s["status"].as_str().unwrap_or("").to_string(),
            class: m["label"].as_str().map(str::to_string),
            point,
        });
    }
    let csv = render_csv(&rows);
    std::fs::write(out.join(format!("{}.csv", study.name)), &csv).map_err(|e| e.to_string())?;
    let title = study.title.clone().unwrap_or_else(|| study.name.clone());
    let md = render_markdown(&title, &study.metric, &rows);
    std::fs::write(out.join(format!("{}.md", study.name)), &md).map_err(|e| e.to_string())?;
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
        crate::plot::error_against_time(
            &out.join(format!("{}.png", study.name)),
            &title,
            &format!("relative error of {}", study.metric),
            &points,
        )?;
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
        crate::plot::regime_map(
            &out.join(format!("{}_diagram.png", study.name)),
            &title,
            (&d.x, d.log_x),
            (&d.y, d.log_y),
            &points,
        )?;
    }
    Ok(md)
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{v:.6}"))
}

pub fn render_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "variant,value,reference,relative_error,wall_seconds,steps,status,class,x,y\n",
    );
    for r in rows {
        let _ = writeln!(
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
    }
    s
}

pub fn render_markdown(title: &str, metric: &str, rows: &[Row]) -> String {
    let mut s = format!("### {title}\n\n| variant | {metric} | reference | relative error | wall time (s) | steps | status |\n|---|---|---|---|---|---|---|\n");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.3} | {} | {} |",
            r.label,
            match &r.class {
                Some(c) => format!("{c} ({})", r.value),
                None => format!("{:.6}", r.value),
            },
            fmt_opt(r.reference),
            r.relative_error
                .map_or(String::new(), |e| format!("{:.3} %", 100.0 * e)),
            r.wall_seconds,
            r.steps,
            r.status
        );
    }
    s
}
