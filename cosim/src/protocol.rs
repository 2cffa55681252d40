//! Control messages: the coordinator sends a [`Command`], the node answers one [`Reply`].
//! Control is small and infrequent next to bulk data, so it travels as JSON.
use crate::{ModelDescription, Phase, Port};
use serde::{Deserialize, Serialize};

/// A request from the coordinator to a node.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Command {
    /// Answer with the model description.
    Describe,
    /// Read the scene (full TOML text; the node reads its own sections), build the initial
    /// state, check the time step, and publish the initial bead states.
    Configure { scene_toml: String },
    /// Run one phase of one step.
    RunPhase { step: u64, phase: Phase },
    /// Run several phases of one step in order, each after its input has arrived from
    /// another node (pipelined schedule; served over iceoryx2 only), and the same phases for
    /// the `steps - 1` steps after it: step `step + j` awaits each input `j` steps later than
    /// `phases` says. Answered by one [`Reply::PhasesDone`] with the reports step by step, or
    /// by [`Reply::PhasesFailed`] with the first phase's error and its step.
    RunPhases {
        step: u64,
        phases: Vec<PhaseOrder>,
        /// How many consecutive steps, at least 1.
        #[serde(default = "one_step")]
        steps: u64,
    },
    /// Answer with the full state, serialised (checkpoint).
    SaveState,
    /// Replace the full state by one saved earlier.
    RestoreState { state: Vec<u8> },
    /// Write the node's fields at the end of `step` (time `time`) as files into the existing
    /// directory `dir` (a path the node can open: the coordinator's output directory).
    /// Answered by [`Reply::Files`] with the names written, relative to `dir` (none for a
    /// node without fields).
    WriteFields { step: u64, time: f64, dir: String },
    /// Release resources and end the serving loop.
    Shutdown,
}

fn one_step() -> u64 {
    1
}

/// One phase of a [`Command::RunPhases`] batch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhaseOrder {
    pub phase: Phase,
    /// Wait, before running the phase, for this publication of another node.
    pub awaits: Option<Awaited>,
    /// After the phase, wake this node (its name): it awaits what the phase published.
    pub then_wake: Option<String>,
}

/// A publication a phase waits for: the first on `port` of step `step` or later that this
/// node has not read yet.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Awaited {
    pub port: Port,
    pub step: u64,
}

/// A phase's report, the seconds it ran inside the node (from the arrival of its input to its
/// end) and the seconds it waited for that input before.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct TimedReport {
    pub report: PhaseReport,
    pub seconds: f64,
    pub waited: f64,
}

/// A node's answer to one [`Command`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Reply {
    Description(ModelDescription),
    Configured(Configured),
    PhaseDone(PhaseReport),
    /// The reports of a [`Command::RunPhases`] batch, one per phase and step, in order.
    PhasesDone(Vec<TimedReport>),
    /// A [`Command::RunPhases`] batch failed at `step` (its earlier steps ran); the message
    /// says why, for the user.
    PhasesFailed {
        step: u64,
        message: String,
    },
    State(Vec<u8>),
    /// The files a [`Command::WriteFields`] wrote, relative to its directory.
    Files(Vec<String>),
    Ok,
    /// The command failed; the message says why, for the user.
    Error(String),
}

/// What a node reports after reading the scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Configured {
    /// Beads per fibre (fibre node) or empty (fluid node).
    pub beads_per_fibre: Vec<usize>,
    /// Effects the node will compute for this scene.
    pub effects: Vec<String>,
    /// Stability limits the node derived, by name, in the scene's time unit
    /// (e.g. `("beam stiffness", 0.21)`), already compared against `time.dt`.
    pub time_step_limits: Vec<(String, f64)>,
    /// Dimensionless numbers and derived quantities worth reporting, by name.
    pub derived: Vec<(String, f64)>,
    /// Advice for the user on a scene the node runs but may resolve poorly (not an error):
    /// printed before the run and by `coordinator check`, kept in the summary.
    #[serde(default)]
    pub notes: Vec<String>,
}

/// What a node reports after one phase: scalar diagnostics by name, in a fixed order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct PhaseReport {
    pub diagnostics: Vec<(String, f64)>,
}

impl Command {
    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).expect("a command always serialises")
    }
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, String> {
        serde_json::from_slice(bytes).map_err(|e| format!("malformed command: {e}"))
    }
}

impl Reply {
    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).expect("a reply always serialises")
    }
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, String> {
        serde_json::from_slice(bytes).map_err(|e| format!("malformed reply: {e}"))
    }
}
