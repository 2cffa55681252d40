//! Records exchanged between nodes, one per bead, in fibre order then bead order.
//!
//! Units are the scene's units throughout: lengths in grid spacings, times in the scene's
//! time unit (L2020 uses Delta and a reference time; S2023 uses d and d / V0). Vectors are
//! in the laboratory (inertial) frame. In a 2D scene the z components are zero.
use iceoryx2::prelude::ZeroCopySend;

/// Kinematic state of one bead.
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("fibrecosim::BeadState")]
pub struct BeadState {
    /// Centre of mass X (L2020 eq. 2), grid units.
    pub position: [f64; 3],
    /// Unit quaternion q = [q_s, q_x, q_y, q_z] rotating the body frame onto the laboratory
    /// frame (L2020 eq. 1). Identity for models without orientation (bead-spring).
    pub orientation: [f64; 4],
    /// Translational velocity V, grid units per time unit.
    pub velocity: [f64; 3],
    /// Angular velocity Omega in the laboratory frame, radians per time unit.
    pub angular_velocity: [f64; 3],
}

/// Time-integrated hydrodynamic (and capillary) force and torque on one bead over one fluid
/// step (L2020 eqs. 35-36): the fibre node never needs the forces themselves.
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("fibrecosim::BeadImpulse")]
pub struct BeadImpulse {
    /// Integral of the force over the step: mass times grid units per time unit.
    pub impulse: [f64; 3],
    /// Integral of the torque over the step, laboratory frame.
    pub angular_impulse: [f64; 3],
}

/// Force on one bead, as the FPD coupling spreads it on the grid (S2023 eqs. 4, 10).
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("fibrecosim::BeadForce")]
pub struct BeadForce {
    /// Force, mass times grid units per time unit squared (per unit depth in 2D).
    pub force: [f64; 3],
}

impl BeadState {
    /// A bead at rest at `position` with the identity orientation.
    pub fn at_rest(position: [f64; 3]) -> Self {
        Self {
            position,
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
        }
    }
}
