//! From a scene to the effects it calls for and the phases of one step.
use crate::scene::LoadedScene;
use cosim::{effects, Phase};

/// What a scene needs, before any node is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Effects the scene asks for at the scene level (the nodes add their own when configured).
    pub requested: Vec<String>,
    /// Phases of one step, in order.
    pub schedule: Vec<Phase>,
    /// Coupling scheme: `"none"` without a fluid.
    pub coupling: String,
    /// Node kinds to launch: `"fibre"`, `"fluid"`.
    pub nodes: Vec<&'static str>,
}

/// Derive the plan, or say exactly what this build cannot provide.
pub fn plan(scene: &LoadedScene) -> Result<Plan, String> {
    let s = &scene.scene;
    let mut requested = Vec::new();
    if s.fluid.is_some() {
        requested.push(effects::HYDRODYNAMICS.to_string());
        if s.fluid.as_ref().is_some_and(|f| f.contains_key("binary")) {
            requested.push(effects::CAPILLARITY.to_string());
        }
    }
    if s.walls.is_some() {
        requested.push(effects::WALLS.to_string());
    }
    // This build has a fibre node only; a fluid node arrives as its own executable.
    let missing: Vec<&String> = requested.iter().collect();
    if !missing.is_empty() {
        let names: Vec<&str> = missing.iter().map(|s| s.as_str()).collect();
        return Err(format!(
            "the scene asks for {} ([fluid]/[walls] tables) but no component of this build provides {}: \
             this build has no fluid node; remove those tables to run the fibres alone",
            names.join(", "),
            if names.len() == 1 { "it" } else { "them" }
        ));
    }
    if s.fibre.is_empty() {
        return Err("the scene has nothing to simulate: add at least one [[fibre]] table".into());
    }
    Ok(Plan {
        requested,
        schedule: vec![Phase::FibrePositions, Phase::FibreVelocities],
        coupling: "none".into(),
        nodes: vec!["fibre"],
    })
}
