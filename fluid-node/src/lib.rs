//! Eulerian solvers served as a co-simulation component: the Smoothed Profile Method of
//! L2020 (Lecrivain et al. 2020) on a periodic pseudo-spectral Navier–Stokes solver.
//!
//! - [`spectral_ns`]: the flow solver (exact viscous decay, dealiased advection, projection;
//!   L2020 eq. 34) on [`transform`]'s planned real FFTs over a [`grid::Grid`];
//! - [`cahn_hilliard`]: the ternary Cahn–Hilliard phase field of L2020 (eqs. 27–34),
//!   semi-implicit spectral step, capillary force, wall equilibria for the contact angle;
//! - [`binary_fluid`]: `[fluid.binary]`, the phase field coupled into the SPM step (phase
//!   fluid-phase-field and the capillary force in u* of eq. 34);
//! - [`smoothed_profile`]: a bead's truncated tanh profile (L2020 eq. 25);
//! - [`spm`]: the solid fraction (eq. 26), momentum exchange (eqs. 35–36), penalty (37–38);
//! - [`walls`]: two moving slabs normal to y and the Couette reference;
//! - [`fpd`]: the fluid particle dynamics coupling of S2023 (bead profiles, viscosity
//!   field, spread forces, bead velocities) on [`mrt_d2q9`];
//! - [`fpd_lbm`]: `fluid.method = "fpd-lbm"`, the FPD phase of the fluid node on the lattice;
//! - [`mrt_d2q9`]: a standalone MRT lattice Boltzmann D2Q9 solver with per-node viscosity and
//!   Guo forcing, bounce-back walls (the flow solver of FPD on MRT-LBM, S2023);
//! - [`start_geometry`]: the beads' first positions checked against the walls, each other
//!   and the periodic box;
//! - [`stability`]: time-step limits; [`config`]: the `[fluid]`/`[walls]` part of a scene;
//! - [`component`]: [`FluidComponent`], the [`cosim::Component`] the executable serves;
//!   [`field_output`]: its fields as VTK files for ParaView, written between steps.
pub mod binary_fluid;
pub mod cahn_hilliard;
pub mod component;
pub mod config;
pub mod field_output;
pub mod fpd;
pub mod fpd_lbm;
pub mod grain_tuner;
pub mod grid;
pub mod mrt_d2q9;
pub mod parallel;
pub mod saved_state;
pub mod smoothed_profile;
pub mod spectral_ns;
pub mod spm;
pub mod stability;
pub mod start_geometry;
pub mod transform;
pub mod walls;

pub use component::{FluidComponent, COUETTE_DIAGNOSTIC, DIAGNOSTICS, EXCHANGE_DIAGNOSTICS};
pub use config::{parse_scene, FluidConfig};
pub use grid::Grid;
pub use spectral_ns::SpectralNs;
