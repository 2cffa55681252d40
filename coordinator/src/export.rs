//! `coordinator export`: a run's MCAP log as CSV tables, for tools that read no MCAP
//! (spreadsheets, MATLAB, pandas).
//!
//! - `beads.csv` from `/fibre/bead_states`: one row per bead per logged step, `step, time,
//!   fibre, bead` and then the message's own `columns` (position, orientation quaternion,
//!   velocity, angular velocity; the scene's units);
//! - `diagnostics.csv` from `/diagnostics`: one row per logged step, `step, time` and then
//!   every other key that any message holds, in name order (an empty cell where a message
//!   lacks it; nested values flattened as `key.sub` and `key.0`);
//! - `scene.toml` from `/scene`: the scene as run, overrides applied, which `coordinator run`
//!   takes back to repeat the run.
//!
//! Numbers are written in Rust's shortest round-trip form, so a value read back is the same
//! `f64` as the one logged.
use crate::mcap_log::salvage_topics;
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The topic `beads.csv` is made from.
pub const BEAD_STATES: &str = "/fibre/bead_states";
/// The topic `diagnostics.csv` is made from.
pub const DIAGNOSTICS: &str = "/diagnostics";
/// The topic `scene.toml` is taken from.
pub const SCENE: &str = "/scene";

/// The files [`export`] writes.
pub const FILES: [&str; 3] = ["beads.csv", "diagnostics.csv", "scene.toml"];

/// The log of a run: `run` itself if it is a file, else `run/run.mcap`.
pub fn log_path(run: &Path) -> Result<PathBuf, String> {
    if run.is_dir() {
        let log = run.join("run.mcap");
        match log.is_file() {
            true => Ok(log),
            false => Err(format!(
                "{} holds no run.mcap: not a run's output folder",
                run.display()
            )),
        }
    } else if run.is_file() {
        Ok(run.to_path_buf())
    } else {
        Err(format!("no run folder or MCAP file at {}", run.display()))
    }
}

/// Forms one CSV table from a topic's messages: its text and number of data rows.
type Table = fn(&[Value]) -> Result<(String, usize), String>;

/// What [`export`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    /// The files written, with their number of data rows.
    pub files: Vec<(PathBuf, usize)>,
    /// Set when the log breaks off (the run was killed before it closed it): the tables hold
    /// what was logged before the break, and this says where it stopped.
    pub damage: Option<String>,
}

/// Write `beads.csv`, `diagnostics.csv` and `scene.toml` of the run log `log` into `out`
/// (created if missing). A file whose topic the log lacks (a run without fibres) is not
/// written.
pub fn export(log: &Path, out: &Path) -> Result<Exported, String> {
    let mut files = Vec::new();
    let tables: [(&str, Table); 3] = [
        (BEAD_STATES, bead_states_csv),
        (DIAGNOSTICS, diagnostics_csv),
        (SCENE, scene_toml),
    ];
    let (logged, damage) = salvage_topics(log, &tables.map(|(topic, _)| topic))?;
    for (((topic, table), name), messages) in tables.into_iter().zip(FILES).zip(logged) {
        if messages.is_empty() {
            continue;
        }
        let (text, rows) =
            table(&messages).map_err(|e| format!("{topic} in {}: {e}", log.display()))?;
        std::fs::create_dir_all(out)
            .map_err(|e| format!("cannot create {}: {e}", out.display()))?;
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        files.push((path, rows));
    }
    if files.is_empty() {
        return Err(format!(
            "{} holds neither {BEAD_STATES} nor {DIAGNOSTICS}: nothing to export",
            log.display()
        ));
    }
    Ok(Exported { files, damage })
}

/// `/fibre/bead_states` messages as CSV: the text and its number of data rows.
pub fn bead_states_csv(messages: &[Value]) -> Result<(String, usize), String> {
    let columns = |m: &Value| -> Result<Vec<String>, String> {
        m["columns"]
            .as_array()
            .ok_or("a message without `columns`")?
            .iter()
            .map(|c| {
                c.as_str()
                    .map(str::to_string)
                    .ok_or("a column name that is not a string".to_string())
            })
            .collect()
    };
    let names = columns(messages.first().ok_or("no messages")?)?;
    let mut text = String::from("step,time,fibre,bead");
    for n in &names {
        text.push(',');
        text.push_str(n);
    }
    text.push('\n');
    let mut rows = 0;
    for m in messages {
        let step = m["step"].as_u64().ok_or("a message without `step`")?;
        if columns(m)? != names {
            return Err(format!("the columns change at step {step}"));
        }
        let time = m["time"]
            .is_number()
            .then(|| cell(&m["time"]))
            .ok_or(format!("step {step}: no `time`"))?;
        let states = m["states"]
            .as_array()
            .ok_or(format!("step {step}: no `states`"))?;
        let per_fibre: Vec<u64> = m["beads_per_fibre"]
            .as_array()
            .ok_or(format!("step {step}: no `beads_per_fibre`"))?
            .iter()
            .map(|n| {
                n.as_u64()
                    .ok_or(format!("step {step}: a bead count that is not a count"))
            })
            .collect::<Result<_, _>>()?;
        let total: u64 = per_fibre.iter().sum();
        if total != states.len() as u64 {
            return Err(format!(
                "step {step}: {} bead states for fibres of {per_fibre:?} beads",
                states.len()
            ));
        }
        let owners = per_fibre
            .iter()
            .enumerate()
            .flat_map(|(f, &n)| (0..n).map(move |b| (f, b)));
        for ((fibre, bead), state) in owners.zip(states) {
            let values = state
                .as_array()
                .filter(|v| v.len() == names.len())
                .ok_or(format!(
                    "step {step}: fibre {fibre} bead {bead} does not have {} values",
                    names.len()
                ))?;
            let _ = write!(text, "{step},{time},{fibre},{bead}");
            for v in values {
                text.push(',');
                text.push_str(&cell(v));
            }
            text.push('\n');
            rows += 1;
        }
    }
    Ok((text, rows))
}

/// The scene of a `/scene` message (the first; a run logs one), as TOML; its "rows" are 1.
pub fn scene_toml(messages: &[Value]) -> Result<(String, usize), String> {
    let toml = messages.first().ok_or("no messages")?["toml"]
        .as_str()
        .ok_or("a message without the scene's `toml`")?;
    Ok((toml.to_string(), 1))
}

/// `/diagnostics` messages as CSV: the text and its number of data rows.
pub fn diagnostics_csv(messages: &[Value]) -> Result<(String, usize), String> {
    let flat: Vec<BTreeMap<String, String>> = messages
        .iter()
        .map(|m| {
            let mut cells = BTreeMap::new();
            flatten("", m, &mut cells);
            cells
        })
        .collect();
    let first = ["step", "time"];
    let keys: BTreeSet<&str> = flat
        .iter()
        .flat_map(BTreeMap::keys)
        .map(String::as_str)
        .filter(|k| !first.contains(k))
        .collect();
    let header: Vec<&str> = first.iter().copied().chain(keys).collect();
    let mut text = header.join(",");
    text.push('\n');
    for cells in &flat {
        let row: Vec<&str> = header
            .iter()
            .map(|h| cells.get(*h).map_or("", String::as_str))
            .collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    Ok((text, flat.len()))
}

/// The leaves of `v` as cells by dotted key.
fn flatten(prefix: &str, v: &Value, out: &mut BTreeMap<String, String>) {
    let key = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match v {
        Value::Object(map) => map.iter().for_each(|(k, x)| flatten(&key(k), x, out)),
        Value::Array(xs) => xs
            .iter()
            .enumerate()
            .for_each(|(i, x)| flatten(&key(&i.to_string()), x, out)),
        leaf => {
            out.insert(prefix.to_string(), cell(leaf));
        }
    }
}

/// One CSV cell: numbers as logged (integers as integers, floats in shortest round-trip
/// form), `null` empty, text quoted where it needs it.
fn cell(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::Number(n) => match (n.as_u64(), n.as_i64(), n.as_f64()) {
            (Some(u), _, _) => u.to_string(),
            (_, Some(i), _) => i.to_string(),
            (_, _, Some(x)) => format!("{x:?}"),
            _ => n.to_string(),
        },
        Value::Bool(b) => b.to_string(),
        Value::String(s) if s.contains([',', '"', '\n']) => {
            format!("\"{}\"", s.replace('"', "\"\""))
        }
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn states(step: u64, per_fibre: &[u64], x0: f64) -> Value {
        let n: u64 = per_fibre.iter().sum();
        json!({
            "beads_per_fibre": per_fibre,
            "columns": ["x", "y", "vx"],
            "states": (0..n).map(|i| vec![x0 + i as f64, 0.1 * i as f64, -1e-20]).collect::<Vec<_>>(),
            "step": step,
            "time": step as f64 * 0.5,
        })
    }

    #[test]
    fn bead_rows_name_their_fibre_and_bead_and_keep_every_bit() {
        let x = 0.1 + 0.2; // not a short decimal: must come back as the same f64
        let m = [states(0, &[2, 1], x), states(10, &[2, 1], 1.0)];
        let (text, rows) = bead_states_csv(&m).unwrap();
        assert_eq!(rows, 6);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "step,time,fibre,bead,x,y,vx");
        assert_eq!(lines.len(), 7);
        let first: Vec<&str> = lines[1].split(',').collect();
        assert_eq!(&first[..4], &["0", "0.0", "0", "0"]);
        assert_eq!(first[4].parse::<f64>().unwrap().to_bits(), x.to_bits());
        assert_eq!(first[6].parse::<f64>().unwrap(), -1e-20);
        // The third bead belongs to the second fibre, as its first bead.
        assert!(lines[3].starts_with("0,0.0,1,0,"), "{}", lines[3]);
        assert!(lines[6].starts_with("10,5.0,1,0,"), "{}", lines[6]);
    }

    #[test]
    fn inconsistent_bead_messages_are_refused_with_the_step() {
        let mut bad = states(20, &[2], 0.0);
        bad["beads_per_fibre"] = json!([3]);
        let e = bead_states_csv(&[states(0, &[2], 0.0), bad]).unwrap_err();
        assert!(e.contains("step 20") && e.contains("2 bead states"), "{e}");
        let mut short = states(30, &[2], 0.0);
        short["states"][1] = json!([1.0, 2.0]);
        let e = bead_states_csv(&[short]).unwrap_err();
        assert!(e.contains("fibre 0 bead 1"), "{e}");
        let mut renamed = states(40, &[2], 0.0);
        renamed["columns"] = json!(["x", "y", "vy"]);
        let e = bead_states_csv(&[states(0, &[2], 0.0), renamed]).unwrap_err();
        assert!(e.contains("columns change at step 40"), "{e}");
    }

    #[test]
    fn diagnostics_take_the_union_of_keys_and_flatten_nested_values() {
        let m = [
            json!({"step": 0, "time": 0.0, "kinetic_energy": 1.5, "per_fibre": [1.0, 2.0]}),
            json!({"step": 5, "time": 2.5, "kinetic_energy": 1.25, "max_divergence": 3e-15,
                   "note": "a, \"b\""}),
        ];
        let (text, rows) = diagnostics_csv(&m).unwrap();
        assert_eq!(rows, 2);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "step,time,kinetic_energy,max_divergence,note,per_fibre.0,per_fibre.1"
        );
        assert_eq!(lines[1], "0,0.0,1.5,,,1.0,2.0");
        assert_eq!(lines[2], "5,2.5,1.25,3e-15,\"a, \"\"b\"\"\",,");
    }
}
