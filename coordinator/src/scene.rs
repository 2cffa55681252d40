//! Scene files: TOML read with `--set` overrides applied first, then checked key by key.
//!
//! The coordinator owns the top-level keys (`time`, `output`, `analysis`, ...). Each node
//! owns its own tables (`[[fibre]]` for the fibre node, `[fluid]` and `[walls]` for the fluid
//! node) and refuses what it does not know when it is configured, so that a new model adds
//! keys without the coordinator or the other node changing.
use crate::shear_groups::Resolved;
use cosim::scene_keys::Num;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The scene the coordinator runs when no file is given: a fairly rigid fibre tumbling in
/// SPM Couette flow, fibre and fluid coupled (`configs/spm/tumbling.toml`).
pub const BUILT_IN_EXAMPLE: &str = include_str!("../../configs/spm/tumbling.toml");

/// A user-facing error: one sentence that names the key or path and what was expected.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct SceneError(pub String);

fn err(msg: impl Into<String>) -> SceneError {
    SceneError(msg.into())
}

/// Keys the coordinator reads. Unknown keys are refused.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name of the scene, used in logs and the summary.
    #[serde(default)]
    pub title: Option<String>,
    /// Free text describing the scene and its reference.
    #[serde(default)]
    pub description: Option<String>,
    /// 2 (motion in the x-y plane, no twist) or 3.
    #[serde(default = "default_dimensions", deserialize_with = "two_or_three")]
    pub dimensions: u8,
    pub time: TimeConfig,
    /// Fibres; read and checked by the fibre node.
    #[serde(default)]
    pub fibre: Vec<toml::Table>,
    /// The fluid; read and checked by the fluid node. Absent: no fluid, no fluid process.
    #[serde(default)]
    pub fluid: Option<toml::Table>,
    /// Moving walls; read by the fluid node. Absent: periodic.
    #[serde(default)]
    pub walls: Option<toml::Table>,
    #[serde(default)]
    pub output: OutputConfig,
    #[serde(default)]
    pub analysis: AnalysisConfig,
}

fn default_dimensions() -> u8 {
    3
}

/// `dimensions`, read as any whole number so that 300 or -1 is told "expected 2 or 3" (read as
/// a byte, 300 would be told "expected a whole number (0 to 255)").
fn two_or_three<'de, D: serde::Deserializer<'de>>(d: D) -> Result<u8, D::Error> {
    cosim::scene_keys::two_or_three(i64::deserialize(d)?).map_err(serde::de::Error::custom)
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeConfig {
    /// Time step, in the scene's time unit. Must be positive and below every node's limit.
    pub dt: f64,
    /// Number of steps to run (upper bound when `rest_tolerance` is set).
    pub steps: u64,
    /// Stop early once the fibres are at rest: the largest bead speed times dt, and the
    /// largest net force on a free bead relative to the largest applied load, both below
    /// this value. Absent: run all steps.
    #[serde(default)]
    pub rest_tolerance: Option<f64>,
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct OutputConfig {
    /// Steps between logged bead states and diagnostics (default: steps / 200, at least 1).
    #[serde(default)]
    pub interval: Option<u64>,
    /// Steps between snapshots of the fields and beads as VTK files for ParaView
    /// (`DIR/fields.pvd`, `DIR/fields/`; also at step 0 and the last step). Absent or 0: none
    /// (0 turns off a scene's snapshots from the command line).
    #[serde(default)]
    pub fields_interval: Option<u64>,
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct AnalysisConfig {
    /// Observables to compute at the end of the run, by name (see `coordinator::metrics`).
    #[serde(default)]
    pub metrics: Vec<String>,
}

/// A scene after overrides and checks, with the text the nodes receive.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    pub scene: Scene,
    /// The scene as TOML text after `--set` overrides and with S2023's flow groups replaced
    /// by the keys they set ([`crate::shear_groups`]): what every node is configured with.
    pub toml: String,
    /// What resolving S2023's flow groups set, for `check`, the start of a run and the
    /// summary's `notes`.
    pub groups: Resolved,
    /// Where it came from (`None` for the built-in example).
    pub path: Option<PathBuf>,
}

impl LoadedScene {
    pub fn name(&self) -> String {
        if let Some(t) = &self.scene.title {
            return t.clone();
        }
        match &self.path {
            Some(p) => p
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            None => "built-in example".into(),
        }
    }

    /// Steps between field snapshots (0: none).
    pub fn fields_interval(&self) -> u64 {
        self.scene.output.fields_interval.unwrap_or(0)
    }

    /// What the run's field snapshots will be, for `check` and the start of a run: `None`
    /// without `output.fields_interval`.
    pub fn fields_summary(&self) -> Option<String> {
        let every = self.fields_interval();
        let steps = self.scene.time.steps;
        (every > 0).then(|| {
            // Step 0, every multiple of `every`, and the last step if it is not one.
            let count = 1 + steps / every + u64::from(!steps.is_multiple_of(every));
            format!(
                "from step 0 every {every} steps and at the last: {count} snapshots (fields.pvd)"
            )
        })
    }

    /// Steps between outputs.
    pub fn output_interval(&self) -> u64 {
        self.scene
            .output
            .interval
            .unwrap_or((self.scene.time.steps / 200).max(1))
            .max(1)
    }
}

/// Read a scene file (or the built-in example when `path` is `None`) and apply overrides.
pub fn load(path: Option<&Path>, overrides: &[String]) -> Result<LoadedScene, SceneError> {
    let text = match path {
        Some(p) => std::fs::read_to_string(p)
            .map_err(|e| err(format!("cannot read scene file {}: {e}", p.display())))?,
        None => BUILT_IN_EXAMPLE.to_string(),
    };
    let origin = path.map_or("the built-in example".to_string(), |p| {
        p.display().to_string()
    });
    from_text(&text, &origin, overrides).map(|(scene, toml, groups)| LoadedScene {
        scene,
        toml,
        groups,
        path: path.map(Path::to_path_buf),
    })
}

/// Parse TOML text, apply `--set PATH=VALUE` overrides, resolve S2023's flow groups, check
/// the coordinator's keys.
pub fn from_text(
    text: &str,
    origin: &str,
    overrides: &[String],
) -> Result<(Scene, String, Resolved), SceneError> {
    let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
        err(format!(
            "{origin} is not valid TOML: {}",
            e.to_string().trim()
        ))
    })?;
    let confinement_set = overrides.iter().any(|o| {
        o.split_once('=')
            .is_some_and(|(k, _)| k.trim() == "fluid.confinement")
    });
    let original = confinement_set.then(|| table.clone());
    let mut value = toml::Value::Table(table);
    let mut replaced = Vec::new();
    for o in overrides {
        apply_override(&mut value, o)?;
        if let (toml::Value::Table(t), Some((path, _))) = (&mut value, o.split_once('=')) {
            replaced.extend(crate::shear_groups::supersede(t, path.trim()));
        }
    }
    let override_notes = match (&original, &value) {
        (Some(o), toml::Value::Table(t)) => crate::shear_groups::confinement_override_notes(o, t),
        _ => Vec::new(),
    };
    let mut groups = match &mut value {
        toml::Value::Table(t) => crate::shear_groups::resolve(t).map_err(err)?,
        _ => Resolved::default(),
    };
    groups.notes.extend(override_notes);
    groups.lines.splice(0..0, replaced);
    let toml_text =
        toml::to_string(&value).map_err(|e| err(format!("cannot re-serialise the scene: {e}")))?;
    let scene = parse_checked(value, origin)?;
    Ok((scene, toml_text, groups))
}

fn parse_checked(value: toml::Value, origin: &str) -> Result<Scene, SceneError> {
    let scene: Scene = serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        err(key_message(
            origin,
            &path,
            &e.into_inner().to_string(),
            (
                &["fibre"],
                &["time", "output", "analysis", "fluid", "walls"],
            ),
        ))
    })?;
    check_ranges(&scene)?;
    Ok(scene)
}

/// A serde error at `path` of the file `origin` (a scene or a study) in plain words, naming
/// the key: an unknown key with a guess at the one meant, a missing one, or a value of the
/// wrong kind ([`cosim::scene_keys::plain_words`]). `arrays_of_tables` and `tables` name the
/// keys written `[[key]]` and `[key]`, so that one written with the other brackets is told
/// how to write it.
pub fn key_message(
    origin: &str,
    path: &str,
    inner: &str,
    (arrays_of_tables, tables): (&[&str], &[&str]),
) -> String {
    let (first, _) = cosim::scene_keys::message_line(inner);
    let whole_file = path == "." || path.is_empty();
    let at = if whole_file {
        format!("{origin}: ")
    } else {
        format!("{origin}: key `{path}`: ")
    };
    if let Some(unknown) = cosim::scene_keys::unknown_key(inner) {
        return format!("{at}{unknown}");
    }
    if let Some(field) = first
        .strip_prefix("missing field `")
        .and_then(|r| r.split('`').next())
    {
        let full = if whole_file {
            field.to_string()
        } else {
            format!("{path}.{field}")
        };
        return format!("{origin}: key `{full}` is required and missing");
    }
    // A table written [[key]]: serde reads its fields as the entries of an array.
    if let Some((table, _)) = path.split_once('[') {
        if tables.contains(&table) {
            return format!(
                "{origin}: key `{table}`: expected a table, got an array of tables (written \
                 [{table}], with one bracket)"
            );
        }
    }
    let plain = cosim::scene_keys::plain_words(inner);
    let hint = if arrays_of_tables.contains(&path) && plain.starts_with("expected an array") {
        format!(" (each entry is a table written [[{path}]], with two brackets)")
    } else if tables.contains(&path) && plain.starts_with("expected a table, got an array") {
        format!(" (written [{path}], with one bracket)")
    } else {
        String::new()
    };
    format!("{at}{plain}{hint}")
}

fn check_ranges(s: &Scene) -> Result<(), SceneError> {
    if !(s.time.dt.is_finite() && s.time.dt > 0.0) {
        return Err(err(format!(
            "key `time.dt`: expected a positive number, got {}",
            Num(s.time.dt)
        )));
    }
    if s.time.steps == 0 {
        return Err(err("key `time.steps`: expected at least 1 step, got 0"));
    }
    if let Some(tol) = s.time.rest_tolerance {
        if !(tol.is_finite() && tol > 0.0) {
            return Err(err(format!(
                "key `time.rest_tolerance`: expected a positive number, got {}",
                Num(tol)
            )));
        }
    }
    if s.output.interval == Some(0) {
        return Err(err("key `output.interval`: expected at least 1, got 0"));
    }
    for m in &s.analysis.metrics {
        if !crate::metrics::known().any(|k| k == m) {
            return Err(err(format!(
                "key `analysis.metrics`: unknown metric `{m}`{} (known: {})",
                cosim::scene_keys::did_you_mean(m, crate::metrics::known()),
                crate::metrics::known().collect::<Vec<_>>().join(", ")
            )));
        }
        if let Some(why) = crate::metrics::unmet_need(m, s) {
            return Err(err(format!("key `analysis.metrics`: metric `{m}` {why}")));
        }
    }
    Ok(())
}

/// The coordinator's tables a scene may leave out, which `--set` may start
/// (`--set output.fields_interval=100` on a scene without `[output]`).
pub const OPTIONAL_TABLES: &[&str] = &["output", "analysis"];

/// Apply one `PATH=VALUE` override. PATH is dotted, array indices are numbers
/// (`fibre.0.beads`); VALUE is a TOML value (`12`, `1e-3`, `[-0.01, 0.01]`, `"bead-spring"`),
/// or a bare word taken as a string. Every component of PATH but the last must exist, except
/// the optional tables [`OPTIONAL_TABLES`], which are started.
pub fn apply_override(root: &mut toml::Value, spec: &str) -> Result<(), SceneError> {
    let (path, raw) = spec.split_once('=').ok_or_else(|| {
        err(format!(
            "--set {spec}: expected PATH=VALUE, e.g. fibre.0.beads=12"
        ))
    })?;
    let path = path.trim();
    let value = parse_value(raw.trim()).map_err(|e| err(format!("--set {spec}: {e}")))?;
    let parts: Vec<&str> = path.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(err(format!("--set {spec}: `{path}` is not a dotted path")));
    }
    let mut cur: &mut toml::Value = root;
    for (i, part) in parts.iter().enumerate() {
        let last = i + 1 == parts.len();
        let so_far = parts[..=i].join(".");
        cur = match cur {
            toml::Value::Table(t) => {
                if last {
                    t.insert((*part).to_string(), value);
                    return Ok(());
                }
                // The coordinator's optional tables may be absent from the scene: start them.
                if i == 0 && OPTIONAL_TABLES.contains(part) && !t.contains_key(*part) {
                    t.insert((*part).to_string(), toml::Value::Table(toml::Table::new()));
                }
                if !t.contains_key(*part) {
                    return Err(err(format!(
                        "--set {spec}: the scene has no `{so_far}`{} (it has: {})",
                        cosim::scene_keys::did_you_mean(part, t.keys().map(String::as_str)),
                        keys(t)
                    )));
                }
                t.get_mut(*part).expect("checked above")
            }
            toml::Value::Array(a) => {
                let n = a.len();
                let idx: usize = part.parse().map_err(|_| {
                    err(format!(
                        "--set {spec}: `{so_far}`: expected an array index 0..{n}, got `{part}`"
                    ))
                })?;
                if idx >= n {
                    return Err(err(format!(
                        "--set {spec}: `{so_far}` does not exist (the array has {n} element{})",
                        if n == 1 { "" } else { "s" }
                    )));
                }
                if last {
                    a[idx] = value;
                    return Ok(());
                }
                &mut a[idx]
            }
            _ => {
                return Err(err(format!(
                    "--set {spec}: `{}` is a value, not a table or array",
                    parts[..i].join(".")
                )))
            }
        };
    }
    Ok(())
}

fn keys(t: &toml::Table) -> String {
    let v: Vec<&str> = t.keys().map(String::as_str).collect();
    if v.is_empty() {
        "nothing".into()
    } else {
        v.join(", ")
    }
}

/// A `--set` value: TOML, or a bare word taken as a string; an array, inline table or quoted
/// string that is not valid TOML is refused (it is no bare word).
fn parse_value(raw: &str) -> Result<toml::Value, String> {
    let doc = format!("v = {raw}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => Ok(t
            .remove("v")
            .unwrap_or(toml::Value::String(raw.to_string()))),
        Err(e) if raw.starts_with(['[', '{', '"', '\'']) => Err(format!(
            "`{raw}` is not a valid TOML value: {}",
            e.message().trim()
        )),
        Err(_) => Ok(toml::Value::String(raw.to_string())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> toml::Value {
        toml::Value::Table(text.parse().unwrap())
    }

    #[test]
    fn overrides_reach_nested_arrays_and_tables() {
        let mut v = table("[time]\ndt = 1.0\n[[fibre]]\nbeads = 3\nloads = [{ bead = -1, force = [0.0, 1.0, 0.0] }]\n");
        apply_override(&mut v, "fibre.0.beads=12").unwrap();
        apply_override(&mut v, "time.dt=1e-3").unwrap();
        apply_override(&mut v, "fibre.0.loads.0.force=[0.0,-2.5,0.0]").unwrap();
        apply_override(&mut v, "fibre.0.model=bead-spring").unwrap();
        assert_eq!(v["fibre"][0]["beads"].as_integer(), Some(12));
        assert_eq!(v["time"]["dt"].as_float(), Some(1e-3));
        assert_eq!(v["fibre"][0]["loads"][0]["force"][1].as_float(), Some(-2.5));
        assert_eq!(v["fibre"][0]["model"].as_str(), Some("bead-spring"));
    }

    #[test]
    fn overrides_of_missing_paths_name_them() {
        let mut v = table("[time]\ndt = 1.0\n[[fibre]]\nbeads = 3\n");
        let e = apply_override(&mut v, "fibre.1.beads=4").unwrap_err().0;
        assert!(e.contains("fibre.1") && e.contains("1 element"), "{e}");
        let e = apply_override(&mut v, "walls.velocity=[0.1]")
            .unwrap_err()
            .0;
        assert!(e.contains("`walls`"), "{e}");
        let e = apply_override(&mut v, "time.dt.x=2").unwrap_err().0;
        assert!(e.contains("time.dt"), "{e}");
        let e = apply_override(&mut v, "time.dt").unwrap_err().0;
        assert!(e.contains("PATH=VALUE"), "{e}");
        // The coordinator's optional tables are started; others are not.
        apply_override(&mut v, "output.fields_interval=100").unwrap();
        assert_eq!(v["output"]["fields_interval"].as_integer(), Some(100));
        apply_override(&mut v, "analysis.metrics=[\"tip_rotation\"]").unwrap();
        assert!(apply_override(&mut v, "outputs.interval=3").is_err());
        let e = apply_override(&mut v, "fibre.0.start=[48, 28")
            .unwrap_err()
            .0;
        assert!(e.contains("not a valid TOML value"), "{e}");
    }

    #[test]
    fn the_built_in_example_is_valid() {
        let s = load(None, &[]).unwrap();
        assert_eq!(s.scene.dimensions, 2);
        assert!(!s.scene.fibre.is_empty());
        assert!(s.scene.fluid.is_some() && s.scene.walls.is_some());
    }

    #[test]
    fn unknown_and_out_of_range_keys_are_refused() {
        let base = "[time]\ndt = 0.1\nsteps = 3\n";
        let e = from_text(&format!("{base}speed = 2\n"), "s", &[])
            .unwrap_err()
            .0;
        assert!(e.contains("time") && e.contains("speed"), "{e}");
        let e = from_text(&base.replace("0.1", "-0.1"), "s", &[])
            .unwrap_err()
            .0;
        assert!(e.contains("time.dt") && e.contains("-0.1"), "{e}");
        let e = from_text(&format!("dimensions = 4\n{base}"), "s", &[])
            .unwrap_err()
            .0;
        assert_eq!(e, "s: key `dimensions`: expected 2 or 3, got 4");
    }

    /// A metric the scene's tables cannot give is refused with what it needs.
    #[test]
    fn metrics_the_scene_cannot_give_are_refused() {
        let base = "[time]\ndt = 0.1\nsteps = 3\n[[fibre]]\nbeads = 3\n";
        let e = |m: &str| {
            from_text(
                &format!("{base}[analysis]\nmetrics = [\"{m}\"]\n"),
                "s",
                &[],
            )
            .err()
            .map(|e| e.0)
        };
        assert!(e("tip_rotation").is_none());
        assert!(e("drag_ratio").unwrap().contains("needs a fluid ([fluid])"));
        assert!(e("orbit").unwrap().contains("needs a fluid"));
        assert!(e("laplace_pressure_jump")
            .unwrap()
            .contains("[fluid.binary]"));
        let walls = |m: &str| {
            from_text(
                &format!("{base}[fluid]\ngrid = [8, 8]\n[analysis]\nmetrics = [\"{m}\"]\n"),
                "s",
                &[],
            )
            .err()
            .map(|e| e.0)
        };
        assert!(walls("tumbling_period_gamma")
            .unwrap()
            .contains("needs walls"));
        assert!(walls("drag_ratio").is_none());
        // One bead is no chain: no tip, no end-to-end vector, no orbit.
        let one = base.replace("beads = 3", "beads = 1");
        for m in ["tip_rotation", "min_end_to_end_over_length"] {
            let e = from_text(&format!("{one}[analysis]\nmetrics = [\"{m}\"]\n"), "s", &[])
                .unwrap_err()
                .0;
            assert_eq!(
                e,
                format!(
                    "key `analysis.metrics`: metric `{m}` needs fibre 0 to be a chain of 2 beads \
                     or more (a single bead has no ends to tell apart)"
                )
            );
        }
    }

    /// Values of the wrong kind and tables with the wrong brackets are named in plain words,
    /// without serde's type names (u64, struct TimeConfig, a sequence).
    #[test]
    fn wrong_kinds_and_brackets_are_told_plainly() {
        let base = "[time]\ndt = 0.1\nsteps = 3\n";
        let e = |text: &str| from_text(text, "s", &[]).unwrap_err().0;
        for (text, want) in [
            (
                base.replace("3", "1.5"),
                "s: key `time.steps`: expected a whole number (0 or more), got 1.5",
            ),
            (
                base.replace("3", "\"3\""),
                "s: key `time.steps`: expected a whole number (0 or more), got the text \"3\" \
                 (numbers are written without quotes)",
            ),
            (
                format!("dimensions = 300\n{base}"),
                "s: key `dimensions`: expected 2 or 3, got 300",
            ),
            (
                format!("dimensions = -1\n{base}"),
                "s: key `dimensions`: expected 2 or 3, got -1",
            ),
            (
                format!("dimensions = 2.5\n{base}"),
                "s: key `dimensions`: expected a whole number, got 2.5",
            ),
            (
                format!("{base}[fibre]\nbeads = 3\n"),
                "s: key `fibre`: expected an array, got a table (each entry is a table written \
                 [[fibre]], with two brackets)",
            ),
            (
                base.replace("[time]", "[[time]]"),
                "s: key `time`: expected a table, got an array of tables (written [time], with \
                 one bracket)",
            ),
            (
                base.replace("steps = 3\n", ""),
                "s: key `time.steps` is required and missing",
            ),
            (
                "title = \"x\"\n".into(),
                "s: key `time` is required and missing",
            ),
        ] {
            assert_eq!(e(&text), want);
        }
    }
}
