//! Workspace-level integration tests live in `tests/`; this crate only re-exports the members
//! so that the tests can name them in one place.
pub use coordinator;
pub use cosim;
pub use fibre_node;
pub use fluid_node;
