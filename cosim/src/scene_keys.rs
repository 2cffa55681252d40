//! Reading a node's own tables of a scene with errors that name the dotted key: shared by
//! every node so that all of them word bad input the same way.
use serde::Deserialize;

/// Turn a serde error at `path` (relative to `prefix`) into a user message naming the key.
pub fn serde_message(prefix: &str, path: &serde_path_to_error::Path, msg: &str) -> String {
    let mut full = prefix.to_string();
    for seg in path.iter() {
        match seg {
            serde_path_to_error::Segment::Seq { index } => full.push_str(&format!(".{index}")),
            serde_path_to_error::Segment::Map { key } => full.push_str(&format!(".{key}")),
            serde_path_to_error::Segment::Enum { variant } => full.push_str(&format!(".{variant}")),
            serde_path_to_error::Segment::Unknown => {}
        }
    }
    // toml appends "in `key`" lines; the first line is serde's message.
    let msg = msg.lines().next().unwrap_or("").trim_end();
    let quoted = msg.split('`').nth(1).unwrap_or("");
    if msg.starts_with("unknown field ") {
        // "unknown field `foo`, expected one of `a`, `b`": the path ends at the key itself;
        // report the table holding it.
        let table = full
            .strip_suffix(&format!(".{quoted}"))
            .unwrap_or(&full)
            .to_string();
        let expected = msg
            .split_once(", expected ")
            .map(|(_, e)| format!(" (expected {e})"))
            .unwrap_or_default();
        return format!("{table}: unknown key `{quoted}`{expected}");
    }
    if msg.starts_with("missing field ") {
        return format!("{full}.{quoted}: required key is missing");
    }
    let msg = msg
        .replace("expected f64", "expected a number")
        .replace("expected i64", "expected an integer")
        .replace("expected an array of length 3", "expected [x, y, z]")
        .replace("expected a sequence", "expected an array");
    format!("{full}: {msg}")
}

/// Deserialize the table `v` found at the dotted path `prefix`.
pub fn deserialize_at<T: for<'de> Deserialize<'de>>(
    prefix: &str,
    v: toml::Value,
) -> Result<T, String> {
    serde_path_to_error::deserialize(v).map_err(|e| {
        let path = e.path().clone();
        let inner = e.into_inner();
        serde_message(prefix, &path, &inner.to_string())
    })
}

/// A TOML value as a user reads it in a message.
pub fn describe_value(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("the string {s:?}"),
        toml::Value::Table(_) => "a table".into(),
        toml::Value::Array(_) => "an array".into(),
        other => other.to_string(),
    }
}

/// `v` if it is a finite positive number, else a message naming `path`.
pub fn positive(path: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{path}: expected a positive number, got {v}"))
    }
}

/// The scene's text parsed as TOML.
pub fn parse_table(scene_toml: &str) -> Result<toml::Table, String> {
    scene_toml
        .parse()
        .map_err(|e: toml::de::Error| format!("the scene is not valid TOML: {e}"))
}

/// The top-level `dimensions` every node reads: 2 or 3, default 3.
pub fn dimensions(table: &toml::Table) -> Result<u8, String> {
    match table.get("dimensions") {
        None => Ok(3),
        Some(toml::Value::Integer(2)) => Ok(2),
        Some(toml::Value::Integer(3)) => Ok(3),
        Some(v) => Err(format!(
            "dimensions: expected 2 or 3, got {}",
            describe_value(v)
        )),
    }
}

/// The `time.dt` every node reads: required, positive.
pub fn time_step(table: &toml::Table) -> Result<f64, String> {
    match table.get("time") {
        None => Err("time.dt: required key is missing (no [time] table)".into()),
        Some(toml::Value::Table(t)) => match t.get("dt") {
            None => Err("time.dt: required key is missing".into()),
            Some(toml::Value::Float(x)) => positive("time.dt", *x),
            Some(toml::Value::Integer(i)) => positive("time.dt", *i as f64),
            Some(v) => Err(format!(
                "time.dt: expected a positive number, got {}",
                describe_value(v)
            )),
        },
        Some(v) => Err(format!("time: expected a table, got {}", describe_value(v))),
    }
}
