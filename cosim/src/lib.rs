//! The component interface shared by every node of the co-simulation.
//!
//! Nothing in here computes physics. It holds:
//! - [`types`]: the small `#[repr(C)]` records exchanged between nodes (bead states,
//!   time-integrated impulses, forces), zero-copy sendable through iceoryx2;
//! - [`description`]: the FMU-style model description a node answers to `describe`;
//! - [`phase`]: the phases of the fractional step and the schedules built from them;
//! - [`protocol`]: control commands from the coordinator and the replies of a node;
//! - [`component`]: the [`Component`] trait every node implements and
//!   the one dispatch function both transports share;
//! - [`profile`]: the smoothed profile of one bead (L2020 eq. 25) and its integrals, the one
//!   definition both nodes use;
//! - [`scene_keys`]: reading a node's scene tables with errors naming the dotted key;
//! - [`exchange`]: the bulk-data [`Exchange`] trait and its in-process
//!   implementation; [`ipc`]: the iceoryx2 implementation of control and bulk data;
//! - [`vtk`]: VTK XML files (fields, beads, time collections) for ParaView.
pub mod component;
pub mod description;
pub mod effects;
pub mod exchange;
pub mod ipc;
pub mod phase;
pub mod profile;
pub mod protocol;
pub mod scene_keys;
pub mod types;
pub mod vtk;

pub use component::{dispatch, Component, ComponentError};
pub use description::{ModelDescription, ParameterDescription, PortDescription};
pub use exchange::{Exchange, ExchangeHeader, InProcessExchange, Port};
pub use phase::Phase;
pub use protocol::{
    Awaited, Command, Configured, Detail, FullReports, PhaseOrder, PhaseReport, Reply, TimedReport,
};
pub use types::{BeadForce, BeadImpulse, BeadState};
