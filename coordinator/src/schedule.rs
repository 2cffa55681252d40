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
    /// Coupling scheme: `"none"` without a fluid, else the fluid method's (`"spm"`, `"fpd"`).
    pub coupling: String,
    /// Node kinds to launch, in start order: `"fibre"`, `"fluid"`.
    pub nodes: Vec<&'static str>,
}

impl Plan {
    /// The effects the run has: those the scene asks for, then those the nodes added when
    /// configured (`node_effects`), each once.
    pub fn effects(&self, node_effects: &[String]) -> Vec<String> {
        let mut effects = self.requested.clone();
        for e in node_effects {
            if !effects.contains(e) {
                effects.push(e.clone());
            }
        }
        effects
    }
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
    if method == "fpd-lbm" {
        return fpd_plan(s, has_fibres);
    }
    if method != "spm" {
        return Err(format!(
            "key `fluid.method`: `{method}` is not a fluid method{} (available: spm, fpd-lbm)",
            cosim::scene_keys::did_you_mean(method, ["spm", "fpd-lbm"])
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

/// FPD on MRT-LBM (S2023 section II C; DESIGN.md): the fibre's forces, one lattice step, the
/// fibre's positions moved with the bead velocities of the new flow.
fn fpd_plan(s: &crate::scene::Scene, has_fibres: bool) -> Result<Plan, String> {
    if s.fluid.as_ref().is_some_and(|f| f.contains_key("binary")) {
        return Err(
            "[fluid.binary] needs fluid.method = \"spm\": the capillary model (L2020) is not \
             part of the FPD method"
                .into(),
        );
    }
    let mut requested = vec![effects::HYDRODYNAMICS.to_string()];
    if s.walls.is_some() {
        requested.push(effects::WALLS.to_string());
    }
    let mut schedule = Vec::new();
    let mut nodes = Vec::new();
    if has_fibres {
        schedule.push(Phase::FibreForces);
        nodes.push("fibre");
    }
    schedule.push(Phase::FluidLatticeStep);
    if has_fibres {
        schedule.push(Phase::FibreAdvance);
    }
    nodes.push("fluid");
    Ok(Plan {
        requested,
        schedule,
        coupling: "fpd".into(),
        nodes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan_of(text: &str) -> Result<Plan, String> {
        let (scene, toml, groups) = crate::scene::from_text(text, "test scene", &[]).unwrap();
        plan(&LoadedScene {
            scene,
            toml,
            groups,
            path: None,
        })
    }

    const FIBRE: &str = "[[fibre]]\nmodel = \"bead-spring\"\nbeads = 3\nbead_radius = 1.0\n\
                         youngs_modulus = 1.0\n";

    #[test]
    fn spm_runs_the_five_phases_and_skips_what_the_scene_lacks() {
        let p = plan_of(&format!(
            "[time]\ndt = 1.0\nsteps = 1\n[fluid]\nmethod = \"spm\"\n{FIBRE}"
        ))
        .unwrap();
        assert_eq!(p.coupling, "spm");
        assert_eq!(
            p.schedule,
            vec![
                Phase::FibrePositions,
                Phase::FluidMomentumExchange,
                Phase::FibreVelocities,
                Phase::FluidPenalty
            ]
        );
        assert_eq!(p.nodes, vec!["fibre", "fluid"]);
    }

    #[test]
    fn fpd_runs_forces_lattice_step_advance() {
        let text = format!(
            "[time]\ndt = 1.0\nsteps = 1\n[fluid]\nmethod = \"fpd-lbm\"\n[walls]\nvelocity = [-0.01, 0.01]\n{FIBRE}"
        );
        let p = plan_of(&text).unwrap();
        assert_eq!(p.coupling, "fpd");
        assert_eq!(
            p.schedule,
            vec![
                Phase::FibreForces,
                Phase::FluidLatticeStep,
                Phase::FibreAdvance
            ]
        );
        assert_eq!(p.requested, vec![effects::HYDRODYNAMICS, effects::WALLS]);
        // Without fibres only the lattice steps.
        let p = plan_of("[time]\ndt = 1.0\nsteps = 1\n[fluid]\nmethod = \"fpd-lbm\"\n").unwrap();
        assert_eq!(p.schedule, vec![Phase::FluidLatticeStep]);
        assert_eq!(p.nodes, vec!["fluid"]);
    }

    #[test]
    fn unknown_methods_and_capillarity_under_fpd_are_refused() {
        let e = plan_of("[time]\ndt = 1.0\nsteps = 1\n[fluid]\nmethod = \"lbm\"\n").unwrap_err();
        assert!(
            e.contains("`lbm` is not a fluid method (available: spm, fpd-lbm)"),
            "{e}"
        );
        let e =
            plan_of("[time]\ndt = 1.0\nsteps = 1\n[fluid]\nmethod = \"fpd-lbm\"\n[fluid.binary]\n")
                .unwrap_err();
        assert!(
            e.contains("[fluid.binary] needs fluid.method = \"spm\""),
            "{e}"
        );
    }
}
