//! Lagrangian fibre models served as a co-simulation component.
pub mod energies;
pub mod quaternion;
