//! Bulk data between nodes: per-bead records published on named ports.
//!
//! A port has one publisher and any number of readers. A reader always gets the latest
//! publication together with its [`ExchangeHeader`], so the step it belongs to can be checked.
//! [`InProcessExchange`] keeps the latest publication of each port in memory; the iceoryx2
//! implementation is in [`crate::ipc`].
use crate::{BeadForce, BeadImpulse, BeadState};
use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::rc::Rc;

/// Named data ports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Port {
    /// Fibre -> fluid, coordinator: bead states ([`BeadState`]) at configure, after
    /// `fibre-velocities` and after `fibre-advance`.
    BeadStates,
    /// Fluid -> fibre: time-integrated hydrodynamic force and torque ([`BeadImpulse`]).
    BeadImpulses,
    /// Fibre -> fluid: bead forces for the FPD coupling ([`BeadForce`]).
    BeadForces,
    /// Fluid -> fibre: bead velocities from the flow for the FPD coupling ([`BeadState`]).
    BeadVelocities,
    /// Fibre -> fluid: bead states after `fibre-positions` (positions n+1, velocities n), a
    /// port of their own so that they never overwrite the states other readers still need.
    BeadPositions,
}

/// Number of [`Port`]s; per-port tables are arrays of this length, indexed by `port as usize`.
pub const PORTS: usize = Port::ALL.len();

impl Port {
    pub const ALL: [Port; 5] = [
        Port::BeadStates,
        Port::BeadImpulses,
        Port::BeadForces,
        Port::BeadVelocities,
        Port::BeadPositions,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Port::BeadStates => "bead-states",
            Port::BeadImpulses => "bead-impulses",
            Port::BeadForces => "bead-forces",
            Port::BeadVelocities => "bead-velocities",
            Port::BeadPositions => "bead-positions",
        }
    }
}

/// Sent with every publication: which step and phase produced it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
#[type_name("fibrecosim::ExchangeHeader")]
pub struct ExchangeHeader {
    /// Step index n of the state published (0 = initial state).
    pub step: u64,
    /// Sequence number of the publication on this port, starting at 1.
    pub sequence: u64,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExchangeError {
    #[error("port {0} has had no publication yet")]
    NothingPublished(&'static str),
    #[error("port {port}: {message}")]
    Transport { port: &'static str, message: String },
    #[error("port {port}: wanted the publication of step {wanted}, found step {found}")]
    NotAtStep {
        port: &'static str,
        wanted: u64,
        found: u64,
    },
}

/// Bulk-data transport, as seen by one participant (a node or the coordinator).
///
/// `read_*` copies the latest publication into `out` (resized as needed; reuse the same
/// vector to avoid allocation) and returns its header.
pub trait Exchange {
    fn publish_states(
        &mut self,
        port: Port,
        step: u64,
        data: &[BeadState],
    ) -> Result<(), ExchangeError>;
    fn read_states(
        &mut self,
        port: Port,
        out: &mut Vec<BeadState>,
    ) -> Result<ExchangeHeader, ExchangeError>;
    /// The publication of step `step` on `port`, even if a newer one has arrived since: the
    /// coordinator reads the bead states of a step while the nodes may already be on the
    /// next ones (pipelined runs, batches of steps). Reading by step in increasing order
    /// sees every publication a transport holds: those older than the one asked for are gone
    /// after the read, later ones stay (between processes, up to
    /// [`crate::ipc::STATES_QUEUE`] on `bead-states`). The default reads the latest and
    /// checks its step.
    fn read_states_of_step(
        &mut self,
        port: Port,
        step: u64,
        out: &mut Vec<BeadState>,
    ) -> Result<ExchangeHeader, ExchangeError> {
        let h = self.read_states(port, out)?;
        if h.step == step {
            Ok(h)
        } else {
            Err(ExchangeError::NotAtStep {
                port: port.name(),
                wanted: step,
                found: h.step,
            })
        }
    }
    fn publish_impulses(
        &mut self,
        port: Port,
        step: u64,
        data: &[BeadImpulse],
    ) -> Result<(), ExchangeError>;
    fn read_impulses(
        &mut self,
        port: Port,
        out: &mut Vec<BeadImpulse>,
    ) -> Result<ExchangeHeader, ExchangeError>;
    fn publish_forces(
        &mut self,
        port: Port,
        step: u64,
        data: &[BeadForce],
    ) -> Result<(), ExchangeError>;
    fn read_forces(
        &mut self,
        port: Port,
        out: &mut Vec<BeadForce>,
    ) -> Result<ExchangeHeader, ExchangeError>;
}

#[derive(Default)]
struct Slot<T> {
    header: Option<ExchangeHeader>,
    data: Vec<T>,
}

impl<T: Copy> Slot<T> {
    fn publish(&mut self, step: u64, data: &[T]) {
        let sequence = self.header.map_or(1, |h| h.sequence + 1);
        self.header = Some(ExchangeHeader { step, sequence });
        self.data.clear();
        self.data.extend_from_slice(data);
    }
    fn read(&self, port: Port, out: &mut Vec<T>) -> Result<ExchangeHeader, ExchangeError> {
        let h = self
            .header
            .ok_or(ExchangeError::NothingPublished(port.name()))?;
        out.clear();
        out.extend_from_slice(&self.data);
        Ok(h)
    }
}

#[derive(Default)]
struct Slots {
    states: [Slot<BeadState>; PORTS],
    impulses: [Slot<BeadImpulse>; PORTS],
    forces: [Slot<BeadForce>; PORTS],
}

/// Components linked into one process share one of these (cloning shares the storage).
#[derive(Clone, Default)]
pub struct InProcessExchange {
    slots: Rc<RefCell<Slots>>,
}

impl InProcessExchange {
    pub fn new() -> Self {
        Self::default()
    }
}

fn index(port: Port) -> usize {
    port as usize
}

impl Exchange for InProcessExchange {
    fn publish_states(
        &mut self,
        port: Port,
        step: u64,
        data: &[BeadState],
    ) -> Result<(), ExchangeError> {
        self.slots.borrow_mut().states[index(port)].publish(step, data);
        Ok(())
    }
    fn read_states(
        &mut self,
        port: Port,
        out: &mut Vec<BeadState>,
    ) -> Result<ExchangeHeader, ExchangeError> {
        self.slots.borrow().states[index(port)].read(port, out)
    }
    fn publish_impulses(
        &mut self,
        port: Port,
        step: u64,
        data: &[BeadImpulse],
    ) -> Result<(), ExchangeError> {
        self.slots.borrow_mut().impulses[index(port)].publish(step, data);
        Ok(())
    }
    fn read_impulses(
        &mut self,
        port: Port,
        out: &mut Vec<BeadImpulse>,
    ) -> Result<ExchangeHeader, ExchangeError> {
        self.slots.borrow().impulses[index(port)].read(port, out)
    }
    fn publish_forces(
        &mut self,
        port: Port,
        step: u64,
        data: &[BeadForce],
    ) -> Result<(), ExchangeError> {
        self.slots.borrow_mut().forces[index(port)].publish(step, data);
        Ok(())
    }
    fn read_forces(
        &mut self,
        port: Port,
        out: &mut Vec<BeadForce>,
    ) -> Result<ExchangeHeader, ExchangeError> {
        self.slots.borrow().forces[index(port)].read(port, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn in_process_exchange_returns_latest_publication_with_header() {
        let mut a = InProcessExchange::new();
        let mut b = a.clone();
        let mut out = Vec::new();
        assert!(b.read_states(Port::BeadStates, &mut out).is_err());
        a.publish_states(Port::BeadStates, 0, &[BeadState::at_rest([1.0, 2.0, 3.0])])
            .unwrap();
        a.publish_states(Port::BeadStates, 1, &[BeadState::at_rest([4.0, 5.0, 6.0])])
            .unwrap();
        let h = b.read_states(Port::BeadStates, &mut out).unwrap();
        assert_eq!(
            h,
            ExchangeHeader {
                step: 1,
                sequence: 2
            }
        );
        assert_eq!(out, vec![BeadState::at_rest([4.0, 5.0, 6.0])]);
    }
}
