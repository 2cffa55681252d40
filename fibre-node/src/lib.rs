//! Lagrangian fibre models served as a co-simulation component.
pub mod bead_spring;
pub mod cohesive_beam;
pub mod config;
pub mod energies;
pub mod fibre;
pub mod quaternion;
pub mod stability;
