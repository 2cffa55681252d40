//! How the coordinator reaches a node: linked into this process, or as a separate process
//! through iceoryx2. Both call the same `cosim::dispatch`, so results are the same bits.
use cosim::{Command, Component, Exchange, InProcessExchange, Reply};
use std::path::PathBuf;

/// Why a call to a node failed, for the user.
#[derive(Debug, thiserror::Error)]
pub enum LinkFailure {
    #[error("{0}")]
    Ipc(#[from] cosim::ipc::LinkError),
    #[error("node `{node}` answered: {message}")]
    Refused { node: String, message: String },
    #[error("{0}")]
    Setup(String),
}

/// One node as the coordinator sees it.
pub trait NodeLink {
    fn name(&self) -> &str;
    /// Send a command and wait for the reply. A `Reply::Error` becomes `LinkFailure::Refused`.
    fn call(&mut self, command: &Command) -> Result<Reply, LinkFailure>;
    /// Send a command without waiting for its reply (see [`NodeLink::receive_within`]).
    fn send(&mut self, command: &Command) -> Result<(), LinkFailure>;
    /// The reply to the command sent last, if it comes within `limit`. A `Reply::Error`
    /// becomes `LinkFailure::Refused`.
    fn receive_within(&mut self, limit: std::time::Duration) -> Result<Option<Reply>, LinkFailure>;
    /// End the node (and its process, if any).
    fn shutdown(self: Box<Self>) -> Result<(), LinkFailure>;
}

fn refused(node: &str, reply: Reply) -> Result<Reply, LinkFailure> {
    match reply {
        Reply::Error(message) => Err(LinkFailure::Refused {
            node: node.to_string(),
            // Nodes name themselves in their messages (for a node run alone); the failure
            // names the node already.
            message: message
                .strip_prefix(&format!("{node}: "))
                .map_or(message.clone(), str::to_string),
        }),
        r => Ok(r),
    }
}

/// A component linked into the coordinator's process.
pub struct InProcessLink {
    name: String,
    component: Box<dyn Component>,
    exchange: InProcessExchange,
    /// The reply to the command sent last (it runs when sent).
    reply: Option<Reply>,
}

impl InProcessLink {
    pub fn new(name: &str, component: Box<dyn Component>, exchange: InProcessExchange) -> Self {
        Self {
            name: name.to_string(),
            component,
            exchange,
            reply: None,
        }
    }
}

impl NodeLink for InProcessLink {
    fn name(&self) -> &str {
        &self.name
    }
    fn call(&mut self, command: &Command) -> Result<Reply, LinkFailure> {
        let (reply, _) =
            cosim::dispatch(self.component.as_mut(), &mut self.exchange, command.clone());
        refused(&self.name, reply)
    }
    fn send(&mut self, command: &Command) -> Result<(), LinkFailure> {
        let (reply, _) =
            cosim::dispatch(self.component.as_mut(), &mut self.exchange, command.clone());
        self.reply = Some(reply);
        Ok(())
    }
    fn receive_within(&mut self, _: std::time::Duration) -> Result<Option<Reply>, LinkFailure> {
        match self.reply.take() {
            Some(r) => refused(&self.name, r).map(Some),
            None => Err(LinkFailure::Setup(format!(
                "node `{}`: no command is waiting for a reply",
                self.name
            ))),
        }
    }
    fn shutdown(self: Box<Self>) -> Result<(), LinkFailure> {
        Ok(())
    }
}

/// A node running as its own process, reached through iceoryx2.
pub struct ProcessLink {
    name: String,
    client: cosim::ipc::NodeClient,
    /// The link broke (the node died or stopped answering): do not ask it to shut down,
    /// dropping the client kills the process.
    broken: bool,
}

impl ProcessLink {
    pub fn spawn(
        name: &str,
        program: &std::path::Path,
        prefix: &str,
        timeout: std::time::Duration,
    ) -> Result<Self, LinkFailure> {
        let mut client = cosim::ipc::NodeClient::spawn(program, &[], prefix, name)?;
        client.set_timeout(timeout);
        Ok(Self {
            name: name.to_string(),
            client,
            broken: false,
        })
    }
}

impl NodeLink for ProcessLink {
    fn name(&self) -> &str {
        &self.name
    }
    fn call(&mut self, command: &Command) -> Result<Reply, LinkFailure> {
        let reply = self
            .client
            .call(command)
            .inspect_err(|_| self.broken = true)?;
        refused(&self.name, reply)
    }
    fn send(&mut self, command: &Command) -> Result<(), LinkFailure> {
        self.client
            .send(command)
            .inspect_err(|_| self.broken = true)
            .map_err(LinkFailure::from)
    }
    fn receive_within(&mut self, limit: std::time::Duration) -> Result<Option<Reply>, LinkFailure> {
        match self.client.receive_within(limit) {
            Ok(Some(r)) => refused(&self.name, r).map(Some),
            Ok(None) => Ok(None),
            Err(e) => {
                self.broken = true;
                Err(e.into())
            }
        }
    }
    fn shutdown(self: Box<Self>) -> Result<(), LinkFailure> {
        if !self.broken {
            self.client.shutdown()?;
        }
        Ok(())
    }
}

/// The components this build knows, by node kind.
pub struct ComponentInfo {
    /// Node name in messages and service names.
    pub name: &'static str,
    /// Executable serving it.
    pub executable: &'static str,
    /// Build it linked into this process.
    pub build: fn() -> Box<dyn Component>,
}

pub fn fibre_component() -> ComponentInfo {
    ComponentInfo {
        name: "fibre-node",
        executable: "fibre-node",
        build: || Box::new(fibre_node::FibreComponent::new()),
    }
}

pub fn fluid_component() -> ComponentInfo {
    ComponentInfo {
        name: "fluid-node",
        executable: "fluid-node",
        build: || Box::new(fluid_node::FluidComponent::new()),
    }
}

/// Every component this build has.
pub fn all_components() -> Vec<ComponentInfo> {
    vec![fibre_component(), fluid_component()]
}

/// The components for the node kinds a plan needs, in the plan's order.
pub fn components_for(kinds: &[&str]) -> Vec<ComponentInfo> {
    kinds
        .iter()
        .filter_map(|k| match *k {
            "fibre" => Some(fibre_component()),
            "fluid" => Some(fluid_component()),
            _ => None,
        })
        .collect()
}

/// Where node executables are looked for: `FIBRECOSIM_NODE_DIR` if set, else the directory
/// of the coordinator's own executable.
pub fn executable_path(executable: &str) -> Result<PathBuf, LinkFailure> {
    let dir = match std::env::var_os("FIBRECOSIM_NODE_DIR") {
        Some(d) => PathBuf::from(d),
        None => std::env::current_exe()
            .ok()
            .and_then(|p| p.parent().map(|d| d.to_path_buf()))
            .unwrap_or_else(|| PathBuf::from(".")),
    };
    // Test harnesses live one level below the binaries (target/release/deps).
    for candidate in [dir.join(executable), dir.join("..").join(executable)] {
        if candidate.is_file() {
            return Ok(candidate);
        }
    }
    Err(LinkFailure::Setup(format!(
        "cannot find the `{executable}` executable in {} (build it with `cargo build --release --workspace`, \
         set FIBRECOSIM_NODE_DIR, or run with --in-process)",
        dir.display()
    )))
}

/// How long the coordinator waits for a node's reply before declaring it unresponsive.
pub const DEFAULT_NODE_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(600);

/// Start one component, in this process or as its own process.
pub fn start(
    info: &ComponentInfo,
    in_process: Option<&InProcessExchange>,
    prefix: &str,
    timeout: std::time::Duration,
) -> Result<Box<dyn NodeLink>, LinkFailure> {
    match in_process {
        Some(ex) => Ok(Box::new(InProcessLink::new(
            info.name,
            (info.build)(),
            ex.clone(),
        ))),
        None => {
            let program = executable_path(info.executable)?;
            Ok(Box::new(ProcessLink::spawn(
                info.name, &program, prefix, timeout,
            )?))
        }
    }
}

/// The coordinator's own view of the bulk data (to log bead states).
pub fn coordinator_exchange(
    in_process: Option<&InProcessExchange>,
    prefix: &str,
) -> Result<Box<dyn Exchange>, LinkFailure> {
    match in_process {
        Some(ex) => Ok(Box::new(ex.clone())),
        None => Ok(Box::new(
            cosim::ipc::IpcExchange::new(prefix, "coordinator").map_err(|e| {
                LinkFailure::Setup(format!("cannot open the bulk-data exchange: {e}"))
            })?,
        )),
    }
}
