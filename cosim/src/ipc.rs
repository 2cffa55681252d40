//! iceoryx2 transport: control by request-response, bulk data by publish-subscribe.
//!
//! # Services of a run
//! Every service of a run is named under one run prefix from [`new_run_prefix`]
//! (process id, clock nanoseconds and a per-process counter), so parallel runs and tests
//! never meet. For a node `N` of run `P`:
//! - `P/node/N/control`: request-response of `[u8]` JSON ([`crate::Command`] -> [`crate::Reply`]);
//! - `P/node/N/wake`: event the node waits on (a request is pending, or a new reader asks for
//!   the latest publication);
//! - `P/node/N/reply`: event the [`NodeClient`] waits on (a reply is ready);
//! - `P/port/<port>/<Record>`: one publish-subscribe service per data port and record type,
//!   `[Record]` slices with an [`crate::ExchangeHeader`] user header (see [`IpcExchange`]).
//!
//! # Waiting
//! Whoever waits (the node for a request, the coordinator for a reply) first polls shared
//! memory for about [`SPIN`] (a phase of the other side is often that short; see [`Poller`]),
//! then blocks on its iceoryx2 event listener in slices of at most [`BLOCK_SLICE`]. A wait
//! that lasted longer than [`LONG_WAIT`] one step ago (the fibre node and the coordinator
//! during a fluid phase) blocks at once: its polling would only take the CPU from the
//! threads of the phase it waits for (see [`Poller::skips_polling`]). Events are
//! latched, so a notification sent while the waiter was still polling wakes it at once; a
//! spurious wake-up costs one poll. Between slices the waiter checks that its peer is still
//! there. Nothing busy-loops unbounded.
//!
//! # Dead peers
//! - The coordinator side ([`NodeClient`]) owns the node's process: between waits it calls
//!   `try_wait` on the child and reports [`LinkError::Died`] with the exit status and the last
//!   lines of the node's stderr. For a node served by a thread ([`NodeClient::connect`]) it
//!   notices the server leaving the control service.
//! - The node side ([`serve`]) returns [`IpcError::CoordinatorGone`] when its parent process
//!   changes (the coordinator exited and the node was re-parented), when the coordinator's
//!   iceoryx2 node is dead, or when the coordinator's client left without sending `Shutdown`.
//!
//! # Stale resources
//! A normal drop releases everything: the last owner of a service removes it from `/dev/shm`
//! and `/tmp/iceoryx2` (only iceoryx2's machine-wide `iox2_*_node.*.global_mgmt` segment and
//! the empty `nodes`/`services` directories stay, by iceoryx2's design). A killed process
//! leaves its resources behind: [`cleanup_stale_resources`] (call it at coordinator start;
//! [`NodeClient`] calls it after a node crashed or had to be killed) removes those of every
//! dead iceoryx2 node; iceoryx2 also does so whenever one of our nodes is created or dropped.
//! [`resources_of_run`] lists what of a run is still there.
mod client;
mod exchange;
mod node_main;
mod serve;

pub use client::{LinkError, NodeClient};
pub use exchange::{IpcExchange, STATES_QUEUE};
pub use node_main::node_main;
pub use serve::serve;

use iceoryx2::config::Config;
use iceoryx2::node::{Node, NodeBuilder, NodeState, NodeView};
use iceoryx2::prelude::{CallbackProgression, NodeName, ServiceName, SignalHandlingMode};
use iceoryx2::service::{ipc, Service};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::OnceLock;
use std::time::Duration;

/// How long a waiter polls before it blocks on its event listener.
pub const SPIN: Duration = Duration::from_micros(50);
/// The first part of [`SPIN`], polled without yielding the CPU.
pub const SPIN_BUSY: Duration = Duration::from_micros(20);
/// The poll after a wait that had to block (see [`Poller`]).
pub const SPIN_AFTER_BLOCK: Duration = Duration::from_micros(200);
/// The longest a waiter blocks before it checks on its peer again.
pub const BLOCK_SLICE: Duration = Duration::from_millis(50);

/// A wait that lasted longer than this is expected to be long again the next step: block at
/// once rather than poll (see [`Poller::skips_polling`]). A waiter that polls takes a core
/// from the other node's threads; at 400 us the fibre node polled through the first 200 us of
/// the fluid's 170 us exchange every step of the built-in example (96^2), and the three-process
/// overhead was 16 %, at 100 us 10 % (60 us: the same pipelined, worse lock-step). At
/// 256 x 200 the waits are milliseconds and this changes nothing.
pub const LONG_WAIT: Duration = Duration::from_micros(100);
/// Kinds of wait a [`Poller`] remembers separately (see [`wait_kind`]): room for one per
/// phase and one for everything else; a kind beyond it is never remembered (it polls).
pub const WAIT_KINDS: usize = 24;

/// Number of [`crate::Phase`] variants (the kinds of wait are numbered after them).
const PHASES: usize = 8;

/// The kind of wait that follows `command` (sent by the coordinator, or served by a node):
/// one per phase, 0 for everything else. The schedule repeats every step, so the wait after
/// a given phase lasts about as long as it did one step earlier.
pub fn wait_kind(command: &crate::Command) -> usize {
    match command {
        crate::Command::RunPhase { phase, .. } => 1 + *phase as usize,
        crate::Command::RunPhases { phases, .. } => {
            phases.last().map_or(0, |o| 1 + o.phase as usize)
        }
        _ => 0,
    }
}

/// The kind of a node's wait for the input of `phase` inside a batch
/// ([`crate::Command::RunPhases`]), apart from the waits for requests.
pub fn input_wait_kind(phase: crate::Phase) -> usize {
    1 + PHASES + phase as usize
}

/// Poll-then-block state of one waiter (the node waiting for requests, the coordinator for
/// replies).
///
/// Polls for [`SPIN`]: busily for the first [`SPIN_BUSY`], then yielding the CPU between
/// polls so that a peer the scheduler put on this core can run. After a wait that had to
/// block, the next poll lasts [`SPIN_AFTER_BLOCK`]: the peer blocked too and answers only
/// after its own wake-up, and a short window would keep both sides blocking forever.
#[derive(Debug, Clone)]
pub struct Poller {
    window: Duration,
    /// Whether the last wait of each kind lasted longer than [`LONG_WAIT`].
    long: [bool; WAIT_KINDS],
}

impl Default for Poller {
    fn default() -> Self {
        Self {
            window: SPIN,
            long: [false; WAIT_KINDS],
        }
    }
}

impl Poller {
    /// Whether a wait of `kind` should block at once: the last one lasted longer than
    /// [`LONG_WAIT`]. On a machine whose cores the other node's threads fill, polling through
    /// the first microseconds of a millisecond phase slows that phase more than the wake-up
    /// it would save (2D capillary scene, 256 x 200: three-process overhead 9 % with polling,
    /// 7 % without).
    pub fn skips_polling(&self, kind: usize) -> bool {
        self.long.get(kind).copied().unwrap_or(false)
    }

    /// Remember how long a wait of `kind` lasted.
    pub fn record(&mut self, kind: usize, waited: Duration) {
        if let Some(l) = self.long.get_mut(kind) {
            *l = waited > LONG_WAIT;
        }
    }

    /// Poll until `poll` yields something or the window has passed (then `Ok(None)`: block).
    pub fn poll<T, E>(
        &mut self,
        mut poll: impl FnMut() -> Result<Option<T>, E>,
    ) -> Result<Option<T>, E> {
        let start = std::time::Instant::now();
        loop {
            if let Some(x) = poll()? {
                self.window = SPIN;
                return Ok(Some(x));
            }
            let elapsed = start.elapsed();
            if elapsed >= self.window {
                return Ok(None);
            }
            if elapsed < SPIN_BUSY {
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
    }

    /// The wait after the last [`Poller::poll`] had to block.
    pub fn blocked(&mut self) {
        self.window = SPIN_AFTER_BLOCK;
    }
}

/// An error of the node side of the transport.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IpcError {
    #[error("iceoryx2 could not {action}: {message}")]
    Iceoryx { action: String, message: String },
    #[error("node {node} stops because its coordinator is gone: {reason}")]
    CoordinatorGone { node: String, reason: String },
    #[error("{what} {name:?} is not usable as an iceoryx2 name: {reason}")]
    InvalidName {
        what: &'static str,
        name: String,
        reason: String,
    },
}

impl IpcError {
    pub(crate) fn iox<E: std::fmt::Debug>(action: impl Into<String>) -> impl FnOnce(E) -> Self {
        let action = action.into();
        move |e| IpcError::Iceoryx {
            action,
            message: format!("{e:?}"),
        }
    }

    /// [`IpcError::iox`] with the action formed only on failure: for calls made every step.
    pub(crate) fn iox_with<E: std::fmt::Debug>(
        action: impl FnOnce() -> String,
    ) -> impl FnOnce(E) -> Self {
        move |e| IpcError::iox(action())(e)
    }
}

/// iceoryx2's defaults (`/tmp/iceoryx2`, `/dev/shm/iox2_*`), the same in every process of a
/// run; iceoryx2.toml files are ignored, which also spares each process a warning on stderr.
pub(crate) fn config() -> &'static Config {
    static CONFIG: OnceLock<Config> = OnceLock::new();
    CONFIG.get_or_init(Config::default)
}

/// A fresh prefix for the services of one run, unique on this machine for practical purposes.
pub fn new_run_prefix() -> String {
    static COUNTER: AtomicU32 = AtomicU32::new(0);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    format!(
        "cosim-{:x}-{:x}-{}",
        std::process::id(),
        nanos & 0xffff_ffff_ffff,
        COUNTER.fetch_add(1, Ordering::Relaxed)
    )
}

/// Removes the stale resources of every dead iceoryx2 node on this machine (a process that
/// was killed before it could release them). Returns how many dead nodes were cleaned.
pub fn cleanup_stale_resources() -> usize {
    let mut cleaned = 0;
    let _ = Node::<ipc::Service>::list(config(), |state| {
        if let NodeState::Dead(view) = state {
            if view.try_remove_stale_resources().is_ok() {
                cleaned += 1;
            }
        }
        CallbackProgression::Continue
    });
    cleaned
}

/// Names of the iceoryx2 services and nodes of run `prefix` that still exist (empty once a
/// run has released everything; tests use it to check cleanup).
pub fn resources_of_run(prefix: &str) -> Vec<String> {
    let under = format!("{prefix}/");
    let mut found = Vec::new();
    let _ = ipc::Service::list(config(), |details| {
        let name = details.static_details.name().as_str();
        if name.starts_with(&under) {
            found.push(format!("service {name}"));
        }
        CallbackProgression::Continue
    });
    let _ = Node::<ipc::Service>::list(config(), |state| {
        let name = match &state {
            NodeState::Alive(v) => v.details().as_ref().map(|d| d.name().to_string()),
            NodeState::Dead(v) => v.details().as_ref().map(|d| d.name().to_string()),
            _ => None,
        };
        if let Some(name) = name.filter(|n| n.starts_with(&under)) {
            found.push(format!("node {name}"));
        }
        CallbackProgression::Continue
    });
    found
}

/// Service and node names of one participant of a run.
pub(crate) struct Names {
    pub node: String,
    pub control: String,
    pub wake: String,
    pub reply: String,
}

impl Names {
    pub fn new(prefix: &str, participant: &str) -> Result<Self, IpcError> {
        check_name("run prefix", prefix)?;
        check_name("node name", participant)?;
        let node = format!("{prefix}/node/{participant}");
        let names = Self {
            control: format!("{node}/control"),
            wake: format!("{node}/wake"),
            reply: format!("{node}/reply"),
            node,
        };
        service_name(&names.control)?;
        node_name(&names.node)?;
        Ok(names)
    }
}

fn check_name(what: &'static str, name: &str) -> Result<(), IpcError> {
    let bad = |reason: &str| IpcError::InvalidName {
        what,
        name: name.to_string(),
        reason: reason.to_string(),
    };
    if name.is_empty() {
        return Err(bad("it is empty"));
    }
    if name.contains('/') || name.chars().any(char::is_control) {
        return Err(bad("it contains '/' or a control character"));
    }
    Ok(())
}

pub(crate) fn service_name(name: &str) -> Result<ServiceName, IpcError> {
    ServiceName::new(name).map_err(|e| IpcError::InvalidName {
        what: "service name",
        name: name.to_string(),
        reason: format!("{e:?}"),
    })
}

pub(crate) fn node_name(name: &str) -> Result<NodeName, IpcError> {
    NodeName::new(name).map_err(|e| IpcError::InvalidName {
        what: "node name",
        name: name.to_string(),
        reason: format!("{e:?}"),
    })
}

/// An iceoryx2 node that leaves signals to the coordinator (it owns Ctrl-C).
pub(crate) fn create_node<S: Service>(name: &str) -> Result<Node<S>, IpcError> {
    NodeBuilder::new()
        .name(&node_name(name)?)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .config(config())
        .create::<S>()
        .map_err(IpcError::iox(format!("create node {name}")))
}

/// Control requests and replies: JSON bytes.
pub(crate) type Control<S> =
    iceoryx2::service::port_factory::request_response::PortFactory<S, [u8], (), [u8], ()>;

/// The control service of a node; both sides open it with the same settings.
pub(crate) fn control_service<S: Service>(
    node: &Node<S>,
    name: &str,
) -> Result<Control<S>, IpcError> {
    node.service_builder(&service_name(name)?)
        .request_response::<[u8], [u8]>()
        .max_clients(2)
        .max_servers(1)
        .open_or_create()
        .map_err(IpcError::iox(format!("open service {name}")))
}

/// A wake-up event. Only event id 0 is ever sent, and a wait drains every id up to the
/// service's largest (iceoryx2's default 255: 256 atomic swaps per wait), so there is one.
pub(crate) fn event_service<S: Service>(
    node: &Node<S>,
    name: &str,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<S>, IpcError> {
    node.service_builder(&service_name(name)?)
        .event()
        .event_id_max_value(0)
        .open_or_create()
        .map_err(IpcError::iox(format!("open service {name}")))
}

/// Initial size of control messages; requests and replies grow by powers of two.
pub(crate) const CONTROL_INITIAL_BYTES: usize = 4096;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Command, Phase};

    /// A wait that lasted longer than LONG_WAIT makes the next of its kind block at once, a
    /// short one makes it poll again; kinds are told apart by the phase before them.
    #[test]
    fn long_waits_block_at_once_the_next_step() {
        let after = |phase| {
            wait_kind(&Command::RunPhase {
                step: 3,
                phase,
                detail: Default::default(),
            })
        };
        let (a, b) = (after(Phase::FibrePositions), after(Phase::FluidPenalty));
        assert!(a != b && a != wait_kind(&Command::SaveState) && a < WAIT_KINDS);
        let mut p = Poller::default();
        assert!(!p.skips_polling(a));
        p.record(a, LONG_WAIT * 3);
        p.record(b, LONG_WAIT / 3);
        assert!(p.skips_polling(a) && !p.skips_polling(b));
        p.record(a, LONG_WAIT / 2);
        assert!(!p.skips_polling(a));
        p.record(WAIT_KINDS, LONG_WAIT * 3);
        assert!(!p.skips_polling(WAIT_KINDS));
    }
}
