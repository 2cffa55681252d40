//! Names of the effects a scene can call for and a component can provide.
//!
//! Effects are plain strings so that a new component can announce a new effect without the
//! others being rebuilt; the constants below are the ones the project's components know.

/// Stretching and bending of a fibre (L2020 eqs. 11-17, 21-24; S2023 eqs. 9-12).
pub const BEAM_ELASTICITY: &str = "beam-elasticity";
/// Torsion of a fibre about its axis (L2020 eqs. 19-20). 3D only.
pub const TWIST: &str = "twist";
/// Rotational dynamics of beads (quaternions, L2020 eqs. 3, 6).
pub const BEAD_ROTATION: &str = "bead-rotation";
/// Point forces and torques on beads (`fibre.N.loads`).
pub const EXTERNAL_LOADS: &str = "external-loads";
/// Beads held fixed (`fibre.N.clamp`).
pub const CLAMP: &str = "clamp";
/// Viscous damping for quasi-static scenes (`fibre.N.damping`).
pub const DAMPING: &str = "damping";
/// Hydrodynamic coupling with a fluid node.
pub const HYDRODYNAMICS: &str = "hydrodynamics";
/// Capillary forces from a second fluid.
pub const CAPILLARITY: &str = "capillarity";
/// Moving walls.
pub const WALLS: &str = "walls";
