//! The run log: one MCAP file per run, JSON messages with JSON-schema schemas so that
//! Foxglove opens it directly (`foxglove.SceneUpdate` for the beads, plain JSON for plots).
//!
//! Channels: `/scene` (scene text, effects, schedule; once), `/fibre/bead_states` (every
//! exchanged bead state at the output interval, full precision), `/fibre/scene`
//! (`foxglove.SceneUpdate`: spheres and a line per fibre), `/diagnostics` (energies, speeds),
//! `/timings` (wall seconds per phase so far; the only channel that is not deterministic),
//! and with field snapshots `/fluid/vorticity` (`foxglove.CompressedImage`, the PNG of each
//! snapshot; field_snapshots.rs).
//! Log time is simulation time (scene units) times 1e9. The writer closes a chunk at every
//! output so that the file stays readable up to the last output if the run is cut short.
use cosim::BeadState;
use mcap::records::{MessageHeader, Metadata};
use serde_json::json;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

pub struct RunLog {
    writer: mcap::Writer<BufWriter<File>>,
    scene: u16,
    states: u16,
    foxglove: u16,
    diagnostics: u16,
    timings: u16,
    /// `/fluid/vorticity`, added with the first picture.
    images: Option<u16>,
    sequence: u32,
}

const OBJECT_SCHEMA: &str = r#"{"type":"object"}"#;

const IMAGE_SCHEMA: &str = r#"{"title":"foxglove.CompressedImage","type":"object","properties":{"timestamp":{"type":"object"},"frame_id":{"type":"string"},"data":{"type":"string","contentEncoding":"base64"},"format":{"type":"string"}}}"#;

const SCENE_UPDATE_SCHEMA: &str = r#"{"title":"foxglove.SceneUpdate","type":"object","properties":{"deletions":{"type":"array"},"entities":{"type":"array","items":{"type":"object","properties":{"timestamp":{"type":"object"},"frame_id":{"type":"string"},"id":{"type":"string"},"lifetime":{"type":"object"},"frame_locked":{"type":"boolean"},"metadata":{"type":"array"},"arrows":{"type":"array"},"cubes":{"type":"array"},"spheres":{"type":"array"},"cylinders":{"type":"array"},"lines":{"type":"array"},"triangles":{"type":"array"},"texts":{"type":"array"},"models":{"type":"array"}}}}}}"#;

fn mcap_err(e: mcap::McapError) -> String {
    format!("MCAP log: {e}")
}

impl RunLog {
    pub fn create(path: &Path) -> Result<Self, String> {
        let file =
            File::create(path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
        let mut writer = mcap::WriteOptions::new()
            .profile("")
            .library(concat!(
                "fibre-cosim coordinator ",
                env!("CARGO_PKG_VERSION")
            ))
            .create(BufWriter::new(file))
            .map_err(mcap_err)?;
        let mut channel = |topic: &str, schema: &str, data: &str| -> Result<u16, String> {
            let sid = writer
                .add_schema(schema, "jsonschema", data.as_bytes())
                .map_err(mcap_err)?;
            writer
                .add_channel(sid, topic, "json", &BTreeMap::new())
                .map_err(mcap_err)
        };
        let scene = channel("/scene", "fibrecosim.Scene", OBJECT_SCHEMA)?;
        let states = channel("/fibre/bead_states", "fibrecosim.BeadStates", OBJECT_SCHEMA)?;
        let foxglove = channel("/fibre/scene", "foxglove.SceneUpdate", SCENE_UPDATE_SCHEMA)?;
        let diagnostics = channel("/diagnostics", "fibrecosim.Diagnostics", OBJECT_SCHEMA)?;
        let timings = channel("/timings", "fibrecosim.Timings", OBJECT_SCHEMA)?;
        Ok(Self {
            writer,
            scene,
            states,
            foxglove,
            diagnostics,
            timings,
            images: None,
            sequence: 0,
        })
    }

    fn write(&mut self, channel: u16, time: f64, value: &serde_json::Value) -> Result<(), String> {
        self.sequence += 1;
        let t = (time.max(0.0) * 1e9).round() as u64;
        let header = MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: t,
            publish_time: t,
        };
        let data = serde_json::to_vec(value).map_err(|e| e.to_string())?;
        self.writer
            .write_to_known_channel(&header, &data)
            .map_err(mcap_err)
    }

    pub fn scene(
        &mut self,
        toml: &str,
        effects: &[String],
        schedule: &[String],
    ) -> Result<(), String> {
        let v = json!({ "toml": toml, "effects": effects, "schedule": schedule });
        self.write(self.scene, 0.0, &v)?;
        let mut meta = BTreeMap::new();
        meta.insert("toml".to_string(), toml.to_string());
        meta.insert("effects".to_string(), effects.join(","));
        self.writer
            .write_metadata(&Metadata {
                name: "scene".into(),
                metadata: meta,
            })
            .map_err(mcap_err)
    }

    /// Bead states (full precision) and the matching Foxglove scene update.
    pub fn bead_states(
        &mut self,
        step: u64,
        time: f64,
        beads_per_fibre: &[usize],
        radii: &[f64],
        states: &[BeadState],
    ) -> Result<(), String> {
        let rows: Vec<Vec<f64>> = states
            .iter()
            .map(|s| {
                let mut r = Vec::with_capacity(13);
                r.extend_from_slice(&s.position);
                r.extend_from_slice(&s.orientation);
                r.extend_from_slice(&s.velocity);
                r.extend_from_slice(&s.angular_velocity);
                r
            })
            .collect();
        let v = json!({
            "step": step, "time": time, "beads_per_fibre": beads_per_fibre,
            "columns": ["x","y","z","qs","qx","qy","qz","vx","vy","vz","wx","wy","wz"],
            "states": rows,
        });
        self.write(self.states, time, &v)?;
        let stamp =
            json!({ "sec": time.floor() as i64, "nsec": ((time - time.floor()) * 1e9) as i64 });
        let mut entities = Vec::new();
        let mut start = 0;
        for (f, &n) in beads_per_fibre.iter().enumerate() {
            let beads = &states[start..start + n];
            start += n;
            let d = 2.0 * radii.get(f).copied().unwrap_or(1.0);
            let spheres: Vec<_> = beads
                .iter()
                .map(|b| {
                    let q = b.orientation;
                    json!({
                        "pose": { "position": {"x": b.position[0], "y": b.position[1], "z": b.position[2]},
                                  "orientation": {"x": q[1], "y": q[2], "z": q[3], "w": q[0]} },
                        "size": {"x": d, "y": d, "z": d},
                        "color": {"r": 0.85, "g": 0.45, "b": 0.1, "a": 1.0}
                    })
                })
                .collect();
            let points: Vec<_> = beads
                .iter()
                .map(|b| json!({"x": b.position[0], "y": b.position[1], "z": b.position[2]}))
                .collect();
            entities.push(json!({
                "timestamp": stamp, "frame_id": "world", "id": format!("fibre-{f}"),
                "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": false, "metadata": [],
                "arrows": [], "cubes": [], "spheres": spheres, "cylinders": [],
                "lines": [{
                    "type": 0,
                    "pose": {"position": {"x": 0, "y": 0, "z": 0}, "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}},
                    "thickness": 0.2, "scale_invariant": false, "points": points,
                    "color": {"r": 0.1, "g": 0.1, "b": 0.1, "a": 1.0}, "colors": [], "indices": []
                }],
                "triangles": [], "texts": [], "models": []
            }));
        }
        self.write(
            self.foxglove,
            time,
            &json!({ "deletions": [], "entities": entities }),
        )
    }

    /// A PNG picture of the fluid at `time` on `/fluid/vorticity`, for Foxglove's image panel.
    pub fn vorticity_picture(&mut self, time: f64, png: &[u8]) -> Result<(), String> {
        use base64::Engine as _;
        let channel = self.image_channel()?;
        let stamp =
            json!({ "sec": time.floor() as i64, "nsec": ((time - time.floor()) * 1e9) as i64 });
        let data = base64::engine::general_purpose::STANDARD.encode(png);
        self.write(
            channel,
            time,
            &json!({ "timestamp": stamp, "frame_id": "fluid", "data": data, "format": "png" }),
        )
    }

    /// `/fluid/vorticity`, added the first time it is needed.
    fn image_channel(&mut self) -> Result<u16, String> {
        if let Some(c) = self.images {
            return Ok(c);
        }
        let sid = self
            .writer
            .add_schema(
                "foxglove.CompressedImage",
                "jsonschema",
                IMAGE_SCHEMA.as_bytes(),
            )
            .map_err(mcap_err)?;
        let c = self
            .writer
            .add_channel(sid, "/fluid/vorticity", "json", &BTreeMap::new())
            .map_err(mcap_err)?;
        Ok(*self.images.insert(c))
    }

    pub fn diagnostics(
        &mut self,
        step: u64,
        time: f64,
        values: &[(String, f64)],
    ) -> Result<(), String> {
        let mut m = serde_json::Map::new();
        m.insert("step".into(), json!(step));
        m.insert("time".into(), json!(time));
        for (k, v) in values {
            m.insert(k.clone(), json!(v));
        }
        self.write(self.diagnostics, time, &serde_json::Value::Object(m))
    }

    pub fn timings(
        &mut self,
        step: u64,
        time: f64,
        seconds: &BTreeMap<String, f64>,
    ) -> Result<(), String> {
        self.write(
            self.timings,
            time,
            &json!({ "step": step, "seconds_per_phase": seconds }),
        )
    }

    /// Write the messages of an earlier log ([`messages_up_to`]) on this log's channels, in
    /// their order, before anything else of this run but its scene.
    pub fn copy_earlier(&mut self, messages: &[LoggedMessage]) -> Result<(), String> {
        for m in messages {
            let channel = match m.topic.as_str() {
                "/fibre/bead_states" => self.states,
                "/fibre/scene" => self.foxglove,
                "/diagnostics" => self.diagnostics,
                "/timings" => self.timings,
                "/fluid/vorticity" => self.image_channel()?,
                _ => continue,
            };
            self.sequence += 1;
            let header = MessageHeader {
                channel_id: channel,
                sequence: self.sequence,
                log_time: m.log_time,
                publish_time: m.log_time,
            };
            self.writer
                .write_to_known_channel(&header, &m.data)
                .map_err(mcap_err)?;
        }
        self.flush()
    }

    /// Close the current chunk so everything so far is readable even if the run dies.
    pub fn flush(&mut self) -> Result<(), String> {
        self.writer.flush().map_err(mcap_err)
    }

    pub fn finish(mut self, summary: &serde_json::Value) -> Result<(), String> {
        let mut meta = BTreeMap::new();
        meta.insert("summary".to_string(), summary.to_string());
        self.writer
            .write_metadata(&Metadata {
                name: "summary".into(),
                metadata: meta,
            })
            .map_err(mcap_err)?;
        self.writer.finish().map_err(mcap_err)?;
        Ok(())
    }
}

/// A message of a log as it was written: its topic, log time (ns) and JSON bytes.
#[derive(Debug, Clone, PartialEq)]
pub struct LoggedMessage {
    pub topic: String,
    pub log_time: u64,
    pub data: Vec<u8>,
}

/// The messages of the log at `path` that a run resumed at simulation time `time` does not
/// write again: the outputs before `time`, and at `time` itself the diagnostics, timings
/// and pictures (the resumed run logs the bead states of its first step, and its scene).
/// A log that breaks off gives what it holds before the break.
pub fn messages_up_to(path: &Path, time: f64) -> Result<Vec<LoggedMessage>, String> {
    let bytes = read_log(path)?;
    let t = (time.max(0.0) * 1e9).round() as u64;
    let mut out = Vec::new();
    for m in mcap::MessageStream::new(&bytes).map_err(mcap_err)? {
        let Ok(m) = m else { break };
        let keep = match m.channel.topic.as_str() {
            "/scene" => false,
            "/fibre/bead_states" | "/fibre/scene" => m.log_time < t,
            _ => m.log_time <= t,
        };
        if keep {
            out.push(LoggedMessage {
                topic: m.channel.topic.clone(),
                log_time: m.log_time,
                data: m.data.into_owned(),
            });
        }
    }
    Ok(out)
}

/// The bytes of the log at `path`, refused unless they start as an MCAP file does.
fn read_log(path: &Path) -> Result<Vec<u8>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if !bytes.starts_with(mcap::MAGIC) {
        return Err(format!(
            "{} is not an MCAP file (it does not start with the MCAP magic bytes)",
            path.display()
        ));
    }
    Ok(bytes)
}

/// The topics of the messages in the log at `path`, in the order they first appear (up to
/// a break, as [`salvage_topics`] reads).
pub fn topics(path: &Path) -> Result<Vec<String>, String> {
    let bytes = read_log(path)?;
    let mut out: Vec<String> = Vec::new();
    for m in mcap::MessageStream::new(&bytes).map_err(mcap_err)? {
        let Ok(m) = m else { break };
        if !out.contains(&m.channel.topic) {
            out.push(m.channel.topic.clone());
        }
    }
    Ok(out)
}

/// Read back the messages of one topic as JSON values (used by tests and studies).
pub fn read_topic(path: &Path, topic: &str) -> Result<Vec<serde_json::Value>, String> {
    let (messages, damage) = salvage_topic(path, topic)?;
    match damage {
        None => Ok(messages),
        Some(e) => Err(e),
    }
}

/// Like [`read_topic`], but a log that breaks off (a run killed with SIGKILL, or a full disk,
/// never writes the footer) gives the messages of every complete record before the break,
/// with the reason it stopped there. Errors only when the file cannot be read at all.
pub fn salvage_topic(
    path: &Path,
    topic: &str,
) -> Result<(Vec<serde_json::Value>, Option<String>), String> {
    let (mut out, damage) = salvage_topics(path, &[topic])?;
    Ok((out.pop().unwrap_or_default(), damage))
}

/// [`salvage_topic`] for several topics in one pass over the log: the messages of each, in
/// the order of `topics`.
pub fn salvage_topics(
    path: &Path,
    topics: &[&str],
) -> Result<(Vec<Vec<serde_json::Value>>, Option<String>), String> {
    let bytes = read_log(path)?;
    let mut out = vec![Vec::new(); topics.len()];
    for m in mcap::MessageStream::new(&bytes).map_err(mcap_err)? {
        let m = match m {
            Ok(m) => m,
            Err(e) => return Ok((out, Some(mcap_err(e)))),
        };
        if let Some(i) = topics.iter().position(|t| *t == m.channel.topic) {
            out[i].push(serde_json::from_slice(&m.data).map_err(|e| e.to_string())?);
        }
    }
    Ok((out, None))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run killed before `finish` leaves a log without a footer; `salvage_topic` still reads
    /// every output before the break, and `read_topic` refuses it.
    #[test]
    fn a_log_that_breaks_off_is_read_up_to_its_last_complete_chunk() {
        let path = std::env::temp_dir().join(format!(
            "fibre-cosim-salvage-{}-{}.mcap",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_nanos())
                .unwrap_or(0)
        ));
        let mut log = RunLog::create(&path).unwrap();
        log.scene("title = \"t\"", &[], &[]).unwrap();
        for step in 1..=20u64 {
            let values = vec![("energy".to_string(), step as f64 * 0.5)];
            log.diagnostics(step, step as f64, &values).unwrap();
            log.flush().unwrap();
        }
        log.finish(&json!({})).unwrap();
        let whole = read_topic(&path, "/diagnostics").unwrap();
        assert_eq!(whole.len(), 20);

        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let (got, damage) = salvage_topic(&path, "/diagnostics").unwrap();
        std::fs::remove_file(&path).unwrap();
        assert!(damage.is_some(), "a cut log must say so");
        assert!(!got.is_empty() && got.len() < 20, "{} messages", got.len());
        assert_eq!(got[..], whole[..got.len()], "salvaged messages differ");
    }
}
