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
    /// Run one phase of one step, reporting with `detail` (in full when absent).
    RunPhase {
        step: u64,
        phase: Phase,
        #[serde(default)]
        detail: Detail,
    },
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
        /// Which of the steps report in full (all of them when absent).
        #[serde(default)]
        full_reports: FullReports,
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
    /// Check the initial bead states (published at configure) against what this node knows
    /// of the scene, e.g. a fluid's walls and box; answered by `Ok` or an error. `check`
    /// asks it after configure; a run checks the same when it first reads the beads.
    CheckStart,
    /// Release resources and end the serving loop.
    Shutdown,
}

fn one_step() -> u64 {
    1
}

/// How much a phase reports ([`PhaseReport`]).
///
/// Some diagnostics are checks for the log that cost a pass over a field (the fluid's
/// largest divergence costs an inverse transform, 10-15 % of a 2D SPM step): the coordinator
/// asks for them only at the steps it logs or may end at, and for the others asks for a brief
/// report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Detail {
    /// Every diagnostic the node has for the phase.
    #[default]
    Full,
    /// At least what the node checks each step anyway (a fluid's speed for its CFL abort) and
    /// what comes free with the step; the node leaves out what costs a pass of its own.
    Brief,
}

/// Which steps of a [`Command::RunPhases`] batch report in full ([`Detail::Full`]): step
/// `s` (n -> n+1) does if `every` divides `s + 1` or `s` is `last`; the others report
/// briefly. The default, `every = 1`, reports every step in full.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FullReports {
    /// At least 1 (0 is read as 1).
    pub every: u64,
    pub last: Option<u64>,
}

impl Default for FullReports {
    fn default() -> Self {
        Self {
            every: 1,
            last: None,
        }
    }
}

impl FullReports {
    /// The detail of step `step`'s reports.
    pub fn detail(&self, step: u64) -> Detail {
        if (step + 1).is_multiple_of(self.every.max(1)) || self.last == Some(step) {
            Detail::Full
        } else {
            Detail::Brief
        }
    }
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
    #[serde(with = "named_values")]
    pub time_step_limits: Vec<(String, f64)>,
    /// Dimensionless numbers and derived quantities worth reporting, by name.
    #[serde(with = "named_values")]
    pub derived: Vec<(String, f64)>,
    /// Advice for the user on a scene the node runs but may resolve poorly (not an error):
    /// printed before the run and by `coordinator check`, kept in the summary.
    #[serde(default)]
    pub notes: Vec<String>,
}

/// What a node reports after one phase: scalar diagnostics by name, in a fixed order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct PhaseReport {
    #[serde(with = "named_values")]
    pub diagnostics: Vec<(String, f64)>,
    /// [`Detail::Brief`] if the node left diagnostics out; a node that always reports in full
    /// says [`Detail::Full`] whatever it was asked.
    #[serde(default)]
    pub detail: Detail,
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

/// Named numbers across the link. JSON has no NaN or infinity (serde_json would write null,
/// which then fails to read as a number): a value that is not finite (a diverged
/// diagnostic, an unbounded limit) crosses as the string `"NaN"`, `"inf"` or `"-inf"`, and
/// a null reads as NaN. Finite values are written as before, to the last bit.
mod named_values {
    use serde::de::{self, Deserializer, Visitor};
    use serde::ser::Serializer;
    use serde::{Deserialize, Serialize};

    struct Wire(f64);

    impl Serialize for Wire {
        fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            let x = self.0;
            if x.is_finite() {
                s.serialize_f64(x)
            } else if x.is_nan() {
                s.serialize_str("NaN")
            } else if x > 0.0 {
                s.serialize_str("inf")
            } else {
                s.serialize_str("-inf")
            }
        }
    }

    impl<'de> Deserialize<'de> for Wire {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct V;
            impl Visitor<'_> for V {
                type Value = Wire;
                fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                    f.write_str("a number, \"NaN\", \"inf\" or \"-inf\"")
                }
                fn visit_f64<E: de::Error>(self, x: f64) -> Result<Wire, E> {
                    Ok(Wire(x))
                }
                fn visit_i64<E: de::Error>(self, x: i64) -> Result<Wire, E> {
                    Ok(Wire(x as f64))
                }
                fn visit_u64<E: de::Error>(self, x: u64) -> Result<Wire, E> {
                    Ok(Wire(x as f64))
                }
                fn visit_unit<E: de::Error>(self) -> Result<Wire, E> {
                    Ok(Wire(f64::NAN))
                }
                fn visit_str<E: de::Error>(self, v: &str) -> Result<Wire, E> {
                    match v {
                        "NaN" => Ok(Wire(f64::NAN)),
                        "inf" => Ok(Wire(f64::INFINITY)),
                        "-inf" => Ok(Wire(f64::NEG_INFINITY)),
                        _ => Err(E::invalid_value(de::Unexpected::Str(v), &self)),
                    }
                }
            }
            d.deserialize_any(V)
        }
    }

    pub fn serialize<S: Serializer>(values: &[(String, f64)], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(values.iter().map(|(k, x)| (k, Wire(*x))))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<(String, f64)>, D::Error> {
        let wire: Vec<(String, Wire)> = Vec::deserialize(d)?;
        Ok(wire.into_iter().map(|(k, w)| (k, w.0)).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_reports_name_the_multiples_of_every_and_the_last_step() {
        let f = FullReports {
            every: 5,
            last: Some(12),
        };
        let full: Vec<u64> = (0..20).filter(|&s| f.detail(s) == Detail::Full).collect();
        // Steps n -> n+1 with n + 1 = 5, 10, 15, 20, and step 12 (the last).
        assert_eq!(full, vec![4, 9, 12, 14, 19]);
        let all = FullReports::default();
        assert!((0..20).all(|s| all.detail(s) == Detail::Full));
        let zero = FullReports {
            every: 0,
            last: None,
        };
        assert!((0..20).all(|s| zero.detail(s) == Detail::Full));
    }

    /// A diagnostic that is not finite crosses the link (JSON has no NaN): NaN, inf and
    /// -inf come back as they went, finite values to the last bit, and a null reads as NaN.
    #[test]
    fn values_that_are_not_finite_cross_the_link() {
        let report = PhaseReport {
            diagnostics: vec![
                ("a".into(), f64::NAN),
                ("b".into(), f64::INFINITY),
                ("c".into(), f64::NEG_INFINITY),
                ("d".into(), 0.1 + 0.2),
                ("e".into(), -0.0),
            ],
            detail: Detail::Full,
        };
        let back: PhaseReport =
            serde_json::from_slice(&serde_json::to_vec(&report).unwrap()).unwrap();
        let bits = |r: &PhaseReport| -> Vec<u64> {
            r.diagnostics.iter().map(|(_, x)| x.to_bits()).collect()
        };
        assert!(back.diagnostics[0].1.is_nan());
        assert_eq!(bits(&back)[1..], bits(&report)[1..]);
        let r: PhaseReport =
            serde_json::from_str(r#"{"diagnostics":[["a",null],["b",2]]}"#).unwrap();
        assert!(r.diagnostics[0].1.is_nan() && r.diagnostics[1].1 == 2.0);
        assert!(serde_json::from_str::<PhaseReport>(r#"{"diagnostics":[["a","x"]]}"#).is_err());
    }

    /// Commands and reports without the detail fields read as full reports.
    #[test]
    fn absent_detail_reads_as_full() {
        let c = Command::from_bytes(br#"{"run-phase":{"step":3,"phase":"fluid-penalty"}}"#);
        assert_eq!(
            c.unwrap(),
            Command::RunPhase {
                step: 3,
                phase: Phase::FluidPenalty,
                detail: Detail::Full
            }
        );
        let c = Command::from_bytes(br#"{"run-phases":{"step":3,"phases":[]}}"#).unwrap();
        let Command::RunPhases { full_reports, .. } = c else {
            panic!("{c:?}")
        };
        assert_eq!(full_reports, FullReports::default());
        let r: PhaseReport = serde_json::from_str(r#"{"diagnostics":[["a",1.0]]}"#).unwrap();
        assert_eq!(r.detail, Detail::Full);
        let brief = Command::RunPhase {
            step: 1,
            phase: Phase::FluidPenalty,
            detail: Detail::Brief,
        };
        assert_eq!(Command::from_bytes(&brief.to_bytes()).unwrap(), brief);
    }
}
