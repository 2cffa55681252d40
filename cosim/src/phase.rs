//! Phases of the fractional step. The coordinator tells each node which phase of which step
//! to run; a node never runs a phase on its own.
use crate::Port;
use serde::{Deserialize, Serialize};

/// One phase of one step, named by the node that runs it and what it does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Phase {
    /// SPM 1: fluid advances psi (Cahn-Hilliard) with u^n.
    FluidPhaseField,
    /// SPM 2: fibre advances positions and quaternions to n+1 and publishes bead states.
    FibrePositions,
    /// SPM 3: fluid builds phi^{n+1}, computes u*, integrates the momentum exchange per bead
    /// (L2020 eqs. 35-36) and publishes the impulses.
    FluidMomentumExchange,
    /// SPM 4: fibre advances velocities with beam forces, impulses and loads; publishes states.
    FibreVelocities,
    /// SPM 5: fluid penalty and projection to u^{n+1} (L2020 eqs. 37-38).
    FluidPenalty,
    /// FPD 1: fibre computes bead forces from positions and publishes them.
    FibreForces,
    /// FPD 2: fluid spreads forces, runs one LBM step, publishes bead velocities (S2023 eq. 5).
    FluidLatticeStep,
    /// FPD 3: fibre advances positions with the velocities it received.
    FibreAdvance,
}

impl Phase {
    /// The node kind that runs this phase: `"fibre"` or `"fluid"`.
    pub fn node(self) -> &'static str {
        match self {
            Phase::FibrePositions
            | Phase::FibreVelocities
            | Phase::FibreForces
            | Phase::FibreAdvance => "fibre",
            _ => "fluid",
        }
    }

    /// What this phase of step `step` reads that the other node publishes within the same
    /// step: the port and the step the publication carries. Inputs from an earlier step
    /// (e.g. the bead states a lattice step reads) are not listed: the coordinator starts a
    /// step only when the one before it has ended.
    pub fn input(self, step: u64) -> Option<(Port, u64)> {
        match self {
            Phase::FluidMomentumExchange => Some((Port::BeadPositions, step + 1)),
            Phase::FluidPenalty => Some((Port::BeadStates, step + 1)),
            Phase::FibreVelocities => Some((Port::BeadImpulses, step + 1)),
            Phase::FluidLatticeStep => Some((Port::BeadForces, step)),
            Phase::FibreAdvance => Some((Port::BeadVelocities, step + 1)),
            Phase::FluidPhaseField | Phase::FibrePositions | Phase::FibreForces => None,
        }
    }

    /// The port this phase publishes on (when the scene has beads).
    pub fn output(self) -> Option<Port> {
        match self {
            Phase::FibrePositions => Some(Port::BeadPositions),
            Phase::FibreVelocities | Phase::FibreAdvance => Some(Port::BeadStates),
            Phase::FluidMomentumExchange => Some(Port::BeadImpulses),
            Phase::FibreForces => Some(Port::BeadForces),
            Phase::FluidLatticeStep => Some(Port::BeadVelocities),
            Phase::FluidPhaseField | Phase::FluidPenalty => None,
        }
    }

    /// Kebab-case name, as in logs and messages.
    pub fn name(self) -> &'static str {
        match self {
            Phase::FluidPhaseField => "fluid-phase-field",
            Phase::FibrePositions => "fibre-positions",
            Phase::FluidMomentumExchange => "fluid-momentum-exchange",
            Phase::FibreVelocities => "fibre-velocities",
            Phase::FluidPenalty => "fluid-penalty",
            Phase::FibreForces => "fibre-forces",
            Phase::FluidLatticeStep => "fluid-lattice-step",
            Phase::FibreAdvance => "fibre-advance",
        }
    }
}

impl std::fmt::Display for Phase {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
