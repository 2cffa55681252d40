//! Checkpoints: a run's full state at the end of a step, so that it can be resumed later and
//! continue bit for bit as if it had not stopped (DESIGN.md: nodes save and restore their
//! state, the FMI get/set-state analogue).
//!
//! A checkpoint is a folder (`OUT/checkpoint` by default):
//! - `run.json`: the step and time reached, the scene text it was made with, the bead states
//!   of step 0 and the orientation history of fibre 0 (what the metrics need from the part of
//!   the run already done), and the wall seconds spent from step 0 to the checkpoint over
//!   all pieces of the run;
//! - `NODE.state`: each node's `SaveState` answer, as it gave it; `run.json` records its
//!   CRC-32 (`state_crc32`), and a resume refuses a state file that does not match, so that a
//!   damaged file or one from another checkpoint is named instead of resumed.
//!
//! Writing replaces the folder's files one by one through temporary names, the node states
//! first and `run.json` last, so that a run stopped while writing leaves the previous
//! checkpoint's files or the new ones, never a truncated file; a folder left with some new
//! and some old files fails the checksums.
use crate::trajectory::Trajectory;
use cosim::BeadState;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Format tag of `run.json`.
pub const FORMAT: &str = "fibre-cosim checkpoint 1";

/// What the coordinator keeps of a run at a checkpoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunCheckpoint {
    pub format: String,
    /// Steps done: the run resumes with step `step` (0-based), at time `time`.
    pub step: u64,
    pub time: f64,
    /// The scene text the run was configured with.
    pub scene_toml: String,
    /// Bead states of step 0, as bit patterns (13 per bead: position, orientation, velocity,
    /// angular velocity).
    pub initial: Vec<[u64; 13]>,
    pub trajectory: Trajectory,
    /// Wall seconds from step 0 to this checkpoint, summed over every piece of the run; absent
    /// when a piece did not record it (checkpoints written before this field existed).
    #[serde(default)]
    pub wall_seconds: Option<f64>,
    /// The largest `wall_overlap`, `self_overlap` and `fibre_overlap` from step 0 to this
    /// checkpoint (fields `wall_watch`, `self_watch` and `fibre_watch`), and the energy a
    /// closed fibre system started with (`energy_watch`).
    #[serde(flatten)]
    pub watches: crate::overlap_watch::RunWatches,
    /// CRC-32 (IEEE) of each node's state file, by node name, set by [`write()`]; absent in
    /// checkpoints written before it existed, whose states are then read unchecked.
    #[serde(default)]
    pub state_crc32: std::collections::BTreeMap<String, u32>,
}

fn bits(s: &BeadState) -> [u64; 13] {
    let mut out = [0u64; 13];
    let values = s
        .position
        .iter()
        .chain(&s.orientation)
        .chain(&s.velocity)
        .chain(&s.angular_velocity);
    for (o, v) in out.iter_mut().zip(values) {
        *o = v.to_bits();
    }
    out
}

fn state(b: &[u64; 13]) -> BeadState {
    let v = |i: usize| f64::from_bits(b[i]);
    BeadState {
        position: [v(0), v(1), v(2)],
        orientation: [v(3), v(4), v(5), v(6)],
        velocity: [v(7), v(8), v(9)],
        angular_velocity: [v(10), v(11), v(12)],
    }
}

impl RunCheckpoint {
    pub fn new(
        step: u64,
        time: f64,
        scene_toml: &str,
        initial: &[BeadState],
        trajectory: &Trajectory,
        wall_seconds: Option<f64>,
        watches: crate::overlap_watch::RunWatches,
    ) -> Self {
        Self {
            format: FORMAT.into(),
            step,
            time,
            scene_toml: scene_toml.into(),
            initial: initial.iter().map(bits).collect(),
            trajectory: trajectory.clone(),
            wall_seconds,
            watches,
            state_crc32: Default::default(),
        }
    }

    pub fn initial_states(&self) -> Vec<BeadState> {
        self.initial.iter().map(state).collect()
    }
}

/// Write `run` and the nodes' states into `dir`, with the states' checksums in `run.json`.
pub fn write(
    dir: &Path,
    mut run: RunCheckpoint,
    nodes: &[(String, Vec<u8>)],
) -> Result<(), String> {
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("cannot create the checkpoint folder {}: {e}", dir.display()))?;
    run.state_crc32 = nodes
        .iter()
        .map(|(n, s)| (n.clone(), crc32fast::hash(s)))
        .collect();
    let json = serde_json::to_vec_pretty(&run)
        .map_err(|e| format!("cannot serialise the checkpoint: {e}"))?;
    let mut files: Vec<(String, &[u8])> = nodes
        .iter()
        .map(|(n, s)| (format!("{n}.state"), s.as_slice()))
        .collect();
    files.push(("run.json".into(), &json));
    for (name, bytes) in files {
        let path = dir.join(&name);
        let tmp = dir.join(format!(".{name}.tmp"));
        std::fs::write(&tmp, bytes)
            .and_then(|()| std::fs::rename(&tmp, &path))
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    Ok(())
}

/// Read `run.json` from `dir`.
pub fn read_run(dir: &Path) -> Result<RunCheckpoint, String> {
    let path = dir.join("run.json");
    let text = std::fs::read(&path).map_err(|e| {
        format!(
            "cannot read {} (resume from the checkpoint folder a run wrote with \
             --checkpoint-interval): {e}",
            path.display()
        )
    })?;
    let run: RunCheckpoint = serde_json::from_slice(&text)
        .map_err(|e| format!("{} is not a checkpoint: {e}", path.display()))?;
    if run.format != FORMAT {
        return Err(format!(
            "{} has format {:?}, this build reads {FORMAT:?}",
            path.display(),
            run.format
        ));
    }
    Ok(run)
}

/// Read node `name`'s saved state from `dir`, checked against the CRC-32 `run` recorded.
pub fn read_node(dir: &Path, run: &RunCheckpoint, name: &str) -> Result<Vec<u8>, String> {
    let path = dir.join(format!("{name}.state"));
    let state = std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if let Some(&want) = run.state_crc32.get(name) {
        let got = crc32fast::hash(&state);
        if got != want {
            return Err(format!(
                "{} does not match the checksum run.json recorded for it (CRC-32 {got:08x}, \
                 recorded {want:08x}): the file is damaged or belongs to another checkpoint; \
                 resume from an intact checkpoint or start the run again",
                path.display()
            ));
        }
    }
    Ok(state)
}

/// The scene without the keys a resumed run may change: `time.steps`, `[output]` and
/// `[analysis]`. Everything else must be as the checkpoint was made.
fn physics_of(scene_toml: &str) -> Result<toml::Table, String> {
    let mut t: toml::Table = scene_toml
        .parse()
        .map_err(|e| format!("the scene is not valid TOML: {e}"))?;
    if let Some(toml::Value::Table(time)) = t.get_mut("time") {
        time.remove("steps");
    }
    t.remove("output");
    t.remove("analysis");
    Ok(t)
}

/// Refuse to resume a checkpoint with a scene that differs in more than the run length,
/// the output and the analysis, naming the first difference.
pub fn check_scene(checkpoint: &RunCheckpoint, scene_toml: &str) -> Result<(), String> {
    let (a, b) = (physics_of(&checkpoint.scene_toml)?, physics_of(scene_toml)?);
    if a == b {
        return Ok(());
    }
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    let first = keys
        .into_iter()
        .find(|k| a.get(*k) != b.get(*k))
        .map_or(String::new(), |k| format!(" (first difference in `{k}`)"));
    Err(format!(
        "the scene differs from the one the checkpoint was made with{first}; a resumed run may \
         change only time.steps, [output] and [analysis]"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bead_states_survive_bit_for_bit() {
        let s = BeadState {
            position: [1.0 / 3.0, -0.0, f64::MIN_POSITIVE],
            orientation: [0.1, 0.2, 0.3, 0.9],
            velocity: [1e-300, 2.5, -7.0],
            angular_velocity: [0.0, 0.0, std::f64::consts::PI],
        };
        let back = state(&bits(&s));
        assert_eq!(bits(&back), bits(&s));
    }

    /// A checkpoint written before `wall_seconds` existed still reads, with the wall time
    /// unknown (the resumed run's `wall_seconds_since_step_0` is then null).
    #[test]
    fn a_checkpoint_without_wall_seconds_reads_as_unknown() {
        let c = RunCheckpoint::new(
            3,
            1.5,
            "",
            &[],
            &Trajectory::default(),
            Some(12.5),
            Default::default(),
        );
        let mut v = serde_json::to_value(&c).unwrap();
        assert_eq!(v["wall_seconds"], 12.5);
        v.as_object_mut().unwrap().remove("wall_seconds");
        let old: RunCheckpoint = serde_json::from_value(v).unwrap();
        assert_eq!(old.wall_seconds, None);
        assert_eq!((old.step, old.time), (3, 1.5));
    }

    /// The largest overlaps travel with the checkpoint (the resumed summary's
    /// `largest_wall_overlap`, `largest_self_overlap` and `largest_fibre_overlap` are over
    /// both pieces), and so does the energy reference of a closed fibre system (a resumed
    /// run judges a blow-up as the uninterrupted run would); an older checkpoint without them
    /// reads as clear.
    #[test]
    fn the_watches_are_kept_across_a_resume() {
        use crate::overlap_watch::{OverlapWatch, RunWatches};
        let watches = RunWatches {
            wall_watch: OverlapWatch {
                largest: 0.7572,
                step: 13_800,
            },
            self_watch: OverlapWatch {
                largest: 1.25,
                step: 900,
            },
            fibre_watch: OverlapWatch {
                largest: 0.5,
                step: 42,
            },
            energy_watch: crate::energy_watch::EnergyWatch {
                reference: Some(12.5),
                step: 1,
            },
        };
        let c = RunCheckpoint::new(3, 1.5, "", &[], &Trajectory::default(), None, watches);
        let mut v = serde_json::to_value(&c).unwrap();
        assert_eq!(v["wall_watch"]["largest"], 0.7572);
        assert_eq!(v["self_watch"]["step"], 900);
        assert_eq!(v["fibre_watch"]["step"], 42);
        assert_eq!(v["energy_watch"]["reference"], 12.5);
        let back: RunCheckpoint = serde_json::from_value(v.clone()).unwrap();
        assert_eq!(back.watches, watches);
        v.as_object_mut().unwrap().remove("fibre_watch");
        v.as_object_mut().unwrap().remove("self_watch");
        v.as_object_mut().unwrap().remove("energy_watch");
        let older: RunCheckpoint = serde_json::from_value(v.clone()).unwrap();
        assert_eq!(older.watches.wall_watch, watches.wall_watch);
        assert_eq!(older.watches.self_watch, Default::default());
        assert_eq!(older.watches.fibre_watch, Default::default());
        assert_eq!(older.watches.energy_watch, Default::default());
        v.as_object_mut().unwrap().remove("wall_watch");
        let oldest: RunCheckpoint = serde_json::from_value(v).unwrap();
        assert_eq!(oldest.watches, Default::default());
    }

    /// Each state's checksum travels in run.json: the states read back as written, a
    /// changed byte or a state from elsewhere is refused, and a checkpoint from before the
    /// checksums reads unchecked.
    #[test]
    fn node_states_are_checked_against_their_checksums() {
        let dir = std::env::temp_dir().join(format!("ck-crc-{}", std::process::id()));
        let run = RunCheckpoint::new(
            2,
            1.0,
            "",
            &[],
            &Trajectory::default(),
            None,
            Default::default(),
        );
        let states = vec![
            ("fluid-node".to_string(), vec![1u8, 2, 3, 4]),
            ("fibre-node".to_string(), vec![9u8; 40]),
        ];
        write(&dir, run.clone(), &states).unwrap();
        let back = read_run(&dir).unwrap();
        assert_eq!(back.state_crc32.len(), 2);
        assert_eq!(read_node(&dir, &back, "fibre-node").unwrap(), vec![9u8; 40]);
        std::fs::write(dir.join("fluid-node.state"), [1u8, 2, 3, 5]).unwrap();
        let e = read_node(&dir, &back, "fluid-node").unwrap_err();
        assert!(
            e.contains("fluid-node.state does not match the checksum"),
            "{e}"
        );
        assert_eq!(
            read_node(&dir, &run, "fluid-node").unwrap(),
            vec![1u8, 2, 3, 5]
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_resumed_scene_may_change_only_length_output_and_analysis() {
        let base =
            "[time]\ndt = 0.5\nsteps = 10\n[output]\ninterval = 5\n[fluid]\nviscosity = 1.0\n";
        let c = RunCheckpoint::new(
            4,
            2.0,
            base,
            &[],
            &Trajectory::default(),
            None,
            Default::default(),
        );
        let longer = base
            .replace("steps = 10", "steps = 40")
            .replace("interval = 5", "interval = 2");
        assert!(check_scene(&c, &longer).is_ok());
        let e = check_scene(&c, &base.replace("dt = 0.5", "dt = 0.25")).unwrap_err();
        assert!(e.contains("`time`"), "{e}");
        let e = check_scene(&c, &base.replace("viscosity = 1.0", "viscosity = 2.0")).unwrap_err();
        assert!(e.contains("`fluid`"), "{e}");
    }
}
