//! The model description a node answers to `describe` (the analogue of an FMU's
//! modelDescription.xml): who it is, what it can couple to, what it computes, what it takes.
use serde::{Deserialize, Serialize};

/// Everything the coordinator needs to check that a scene's components fit together.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelDescription {
    /// Component name, e.g. `"fibre-node"`.
    pub name: String,
    /// Component version (the crate version).
    pub version: String,
    /// One line saying what the component computes.
    pub summary: String,
    /// Node kind: `"fibre"` or `"fluid"`.
    pub kind: String,
    /// Models this component can run, as named in the scene (e.g. `"cohesive-beam"`).
    pub models: Vec<String>,
    /// Coupling schemes supported: `"none"` (alone), `"spm"`, `"fpd"`.
    pub coupling_schemes: Vec<String>,
    /// Effects the component can compute (see [`crate::effects`]).
    pub effects: Vec<String>,
    /// Phases the component serves.
    pub phases: Vec<crate::Phase>,
    /// Scene parameters the component reads, with units and defaults.
    pub parameters: Vec<ParameterDescription>,
    /// Data the component reads from other nodes.
    pub inputs: Vec<PortDescription>,
    /// Data the component publishes.
    pub outputs: Vec<PortDescription>,
    /// Free-text notes, e.g. how the component sub-cycles its stiff internal dynamics.
    pub notes: Vec<String>,
}

/// One scene parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterDescription {
    /// Dotted scene path, with `N` for a fibre index (e.g. `"fibre.N.youngs_modulus"`).
    pub key: String,
    /// Unit, in the scene's units (e.g. `"mass / (length time^2)"`), or `"1"`.
    pub unit: String,
    /// Default value as TOML text, or `None` when the key is required.
    pub default: Option<String>,
    /// What it means.
    pub description: String,
}

/// A parameter description from its parts (`default: None` when the key is required).
pub fn parameter(
    key: &str,
    unit: &str,
    default: Option<&str>,
    description: &str,
) -> ParameterDescription {
    ParameterDescription {
        key: key.into(),
        unit: unit.into(),
        default: default.map(Into::into),
        description: description.into(),
    }
}

/// One input or output port.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PortDescription {
    /// Port name (see [`crate::Port`]).
    pub port: crate::Port,
    /// Record type carried, e.g. `"BeadState"`.
    pub record: String,
    /// What it carries and when.
    pub description: String,
}

impl ModelDescription {
    /// Human-readable multi-line rendering, as `coordinator describe` prints it.
    pub fn render(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} {} ({} node): {}",
            self.name, self.version, self.kind, self.summary
        );
        let _ = writeln!(s, "  models:           {}", self.models.join(", "));
        let _ = writeln!(
            s,
            "  coupling schemes: {}",
            self.coupling_schemes.join(", ")
        );
        let _ = writeln!(s, "  effects:          {}", self.effects.join(", "));
        let phases: Vec<&str> = self.phases.iter().map(|p| p.name()).collect();
        let _ = writeln!(s, "  phases:           {}", phases.join(", "));
        let _ = writeln!(s, "  inputs:");
        for p in &self.inputs {
            let _ = writeln!(
                s,
                "    {:<18} [{}] {}",
                p.port.name(),
                p.record,
                p.description
            );
        }
        let _ = writeln!(s, "  outputs:");
        for p in &self.outputs {
            let _ = writeln!(
                s,
                "    {:<18} [{}] {}",
                p.port.name(),
                p.record,
                p.description
            );
        }
        let _ = writeln!(s, "  parameters:");
        for p in &self.parameters {
            let default = p.default.as_deref().unwrap_or("(required)");
            let _ = writeln!(
                s,
                "    {:<28} [{}] default {}: {}",
                p.key, p.unit, default, p.description
            );
        }
        for n in &self.notes {
            let _ = writeln!(s, "  note: {n}");
        }
        s
    }
}
