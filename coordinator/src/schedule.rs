//! From a scene to the effects it calls for and the phases of one step (DESIGN.md, "The
//! fractional step"): only what the scene needs runs.
use crate::scene::LoadedScene;
use cosim::{effects, Phase};

/// What a scene needs, before any node is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Effects the scene asks for at the scene level (the nodes add their own when configured).
    pub requested: Vec<String>,
    /// Phases of one step, in order.
    pub schedule: Vec<Phase>,
    /// Coupling scheme: `"none"` without a fluid, else the fluid method's (`"spm"`).
    pub coupling: String,
    /// Node kinds to launch, in start order: `"fibre"`, `"fluid"`.
    pub nodes: Vec<&'static str>,
}

/// Derive the plan, or say exactly what is missing.
pub fn plan(scene: &LoadedScene) -> Result<Plan, String> {
    let s = &scene.scene;
    let has_fibres = !s.fibre.is_empty();
    let Some(fluid) = &s.fluid else {
        if s.walls.is_some() {
            return Err("the scene has [walls] but no [fluid]: walls act through the fluid".into());
        }
        if !has_fibres {
            return Err(
                "the scene has nothing to simulate: add a [[fibre]] or a [fluid] table".into(),
            );
        }
        return Ok(Plan {
            requested: Vec::new(),
            schedule: vec![Phase::FibrePositions, Phase::FibreVelocities],
            coupling: "none".into(),
            nodes: vec!["fibre"],
        });
    };
    let method = match fluid.get("method") {
        Some(toml::Value::String(m)) => m.as_str(),
        Some(other) => {
            return Err(format!(
                "key `fluid.method`: expected a string such as \"spm\", got {other}"
            ))
        }
        None => return Err("key `fluid.method`: missing (expected \"spm\")".into()),
    };
    if method != "spm" {
        return Err(format!(
            "key `fluid.method`: `{method}` is not available in this build (available: spm)"
        ));
    }
    let binary = fluid.contains_key("binary");
    let mut requested = vec![effects::HYDRODYNAMICS.to_string()];
    if binary {
        requested.push(effects::CAPILLARITY.to_string());
    }
    if s.walls.is_some() {
        requested.push(effects::WALLS.to_string());
    }
    // SPM (L2020 section 2.6): psi first (binary fluids only), then the fibre positions, the
    // momentum exchange, the fibre velocities and the penalty.
    let mut schedule = Vec::new();
    if binary {
        schedule.push(Phase::FluidPhaseField);
    }
    if has_fibres {
        schedule.push(Phase::FibrePositions);
    }
    schedule.push(Phase::FluidMomentumExchange);
    if has_fibres {
        schedule.push(Phase::FibreVelocities);
    }
    schedule.push(Phase::FluidPenalty);
    let mut nodes = Vec::new();
    if has_fibres {
        nodes.push("fibre");
    }
    nodes.push("fluid");
    Ok(Plan {
        requested,
        schedule,
        coupling: "spm".into(),
        nodes,
    })
}
