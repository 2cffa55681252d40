//! Lagrangian fibre models served as a co-simulation component.
//!
//! - [`cohesive_beam`]: L2020 cohesive beam (quaternion beads; stretch, bend, twist);
//! - [`bead_spring`]: S2023 bead-spring chain (stretch, bend), 2D or 3D;
//! - [`fibre`]: one fibre's state, bead mass and inertia, the split symplectic integrator;
//! - [`self_contact`]: optional excluded volume between non-neighbouring beads;
//! - [`wall_contact`]: optional contact of the beads with the walls' faces;
//! - [`self_overlap`]: the `self_overlap` diagnostic, how deep a fibre's beads reach into
//!   each other (cell list, checked only when the beads may have met);
//! - [`bead_pairs`]: a cell list over the beads of all fibres that knows the periodic box;
//! - [`fibre_contact`]: optional excluded volume between fibres;
//! - [`fibre_overlap`]: the `fibre_overlap` diagnostic, how deep beads of two fibres reach
//!   into each other;
//! - [`stability`]: the beam-stiffness time-step limit and the mass-weighted stiffness matrix;
//! - [`spm_exchange`], [`spm_exchange_stiffness`]: light beads and stiff fibres under the
//!   explicit SPM exchange;
//! - [`config`]: the fibre node's part of a scene; `fibre_table`: one `[[fibre]]` table
//!   validated key by key;
//! - `fibre_setup`: one fibre made ready to run: built, checked against the time step
//!   (refused with the limit and the cures named), its derived values and notes;
//! - [`component`]: [`FibreComponent`], the [`cosim::Component`] the executable serves;
//! - [`quaternion`]: rotation helpers (L2020 eqs. 3-4 and appendix A).
pub mod bead_pairs;
pub mod bead_spring;
pub mod cohesive_beam;
pub mod component;
pub mod config;
pub mod energies;
pub mod fibre;
pub mod fibre_contact;
pub mod fibre_overlap;
mod fibre_setup;
mod fibre_table;
#[cfg(test)]
mod gradient_check;
pub mod near_pairs;
pub mod quaternion;
pub mod self_contact;
pub mod self_overlap;
pub mod spm_exchange;
pub mod spm_exchange_stiffness;
pub mod stability;
pub mod wall_contact;
pub mod xorshift;

pub use component::{FibreComponent, DIAGNOSTICS};
pub use config::{parse_scene, Coupling, FibreConfig, ModelKind, SceneConfig};
pub use energies::Energies;
pub use fibre::Fibre;
pub use stability::{stability_limit, StabilityLimit};
