//! Eulerian solvers served as a co-simulation component: the L2020 Smoothed Profile Method.
pub mod config;
pub mod grid;
pub mod parallel;
pub mod smoothed_profile;
pub mod spectral_ns;
pub mod spm;
pub mod transform;
pub mod walls;
