//! Eulerian solvers served as a co-simulation component: the L2020 Smoothed Profile Method.
pub mod grid;
pub mod parallel;
pub mod spectral_ns;
pub mod transform;
