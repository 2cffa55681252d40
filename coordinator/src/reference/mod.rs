//! Analytic and published references the metrics are compared with.
pub mod cylinder;
pub mod elastica;
pub mod jeffery;
pub mod periodic_array;
pub mod stokes_chain_2d;
pub mod stokes_chain_3d;
