//! Helpers shared by the fluid node's integration tests.
#![allow(dead_code)]
use cosim::{
    BeadImpulse, BeadState, Component, Configured, Exchange, InProcessExchange, Phase, PhaseReport,
    Port,
};
use fluid_node::FluidComponent;

pub fn configure(scene: &str) -> (FluidComponent, InProcessExchange, Configured) {
    let mut c = FluidComponent::new();
    let mut x = InProcessExchange::new();
    let cfg = c.configure(scene, &mut x).unwrap_or_else(|e| panic!("{e}"));
    (c, x, cfg)
}

pub fn diag(r: &PhaseReport, name: &str) -> f64 {
    r.diagnostics
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no diagnostic {name} in {r:?}"))
        .1
}

/// One fluid step without beads.
pub fn step(c: &mut FluidComponent, x: &mut InProcessExchange, n: u64) -> PhaseReport {
    c.run_phase(n, Phase::FluidMomentumExchange, x).unwrap();
    c.run_phase(n, Phase::FluidPenalty, x).unwrap()
}

/// One coupled-like step with prescribed bead states: `before` (positions n+1, velocities n)
/// for the momentum exchange, `after` (velocities n+1) for the penalty. Returns the impulses
/// and the penalty report.
pub fn bead_step(
    c: &mut FluidComponent,
    x: &mut InProcessExchange,
    n: u64,
    before: &[BeadState],
    after: &[BeadState],
) -> (Vec<BeadImpulse>, PhaseReport) {
    x.publish_states(Port::BeadPositions, n + 1, before)
        .unwrap();
    c.run_phase(n, Phase::FluidMomentumExchange, x).unwrap();
    let mut imp = Vec::new();
    x.read_impulses(Port::BeadImpulses, &mut imp).unwrap();
    x.publish_states(Port::BeadStates, n + 1, after).unwrap();
    let rep = c.run_phase(n, Phase::FluidPenalty, x).unwrap();
    (imp, rep)
}

/// Total fluid momentum rho Σ u (cell volume 1), summed in index order.
pub fn momentum(c: &FluidComponent, rho: f64) -> [f64; 3] {
    let mut m = [0.0; 3];
    for (k, comp) in c.velocity().iter().enumerate() {
        m[k] = rho * comp.iter().fold(0.0, |a, b| a + b);
    }
    m
}
