//! The coordinator side: start a node, send it commands, notice when it dies.
use super::{control_service, create_node, event_service, IpcError, Names, BLOCK_SLICE};
use crate::{Command, Reply};
use iceoryx2::node::Node;
use iceoryx2::pending_response::PendingResponse;
use iceoryx2::port::client::Client;
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::{AllocationStrategy, PortFactory};
use iceoryx2::service::ipc_threadsafe;
use iceoryx2::service::port_factory::event::PortFactory as Event;
use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read};
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Child, Stdio};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

// Thread-safe flavour, so that a NodeClient can move between threads.
type Svc = ipc_threadsafe::Service;

const DEFAULT_TIMEOUT: Duration = Duration::from_secs(600);
const STARTUP_TIMEOUT: Duration = Duration::from_secs(30);
const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);
const SHUTDOWN_TIMEOUT: Duration = Duration::from_secs(10);
const EXIT_TIMEOUT: Duration = Duration::from_secs(5);
const TAIL_LINES: usize = 40;

/// Why the coordinator lost a node. Each reads as one sentence for the user.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinkError {
    #[error("node {node} died ({status}){}", tail_text(.stderr_tail))]
    Died {
        node: String,
        status: String,
        stderr_tail: String,
    },
    #[error("node {node} did not answer within {seconds} s")]
    Timeout { node: String, seconds: f64 },
    #[error("lost the link to node {node}: {message}")]
    Transport { node: String, message: String },
    #[error("could not start node {node} with {program}: {message}")]
    Spawn {
        node: String,
        program: String,
        message: String,
    },
}

fn tail_text(tail: &str) -> String {
    if tail.trim().is_empty() {
        "; it wrote nothing on stderr".into()
    } else {
        format!("; the last lines of its stderr:\n{tail}")
    }
}

/// The coordinator's handle on one node: its control link and, for a spawned node, its process.
pub struct NodeClient {
    name: String,
    timeout: Duration,
    poller: super::Poller,
    process: Option<Process>,
    pid: u32,
    client: Client<Svc, [u8], (), [u8], ()>,
    /// Requests sent and not yet answered, oldest first (replies come in this order).
    pending: VecDeque<Pending>,
    wake: Notifier<Svc>,
    replies: Listener<Svc>,
    control: super::Control<Svc>,
    _events: [Event<Svc>; 2],
    _node: Node<Svc>,
}

struct Pending {
    response: PendingResponse<Svc, [u8], (), [u8], ()>,
    sent: Instant,
    /// [`super::wait_kind`] of the request.
    kind: usize,
    /// Whether a receive has polled for it already (then it only blocks).
    polled: bool,
}

struct Process {
    child: Child,
    stderr: StderrTail,
}

impl NodeClient {
    /// Start `program serve --prefix <prefix> --name <node_name> <extra_args...>` in its own
    /// process group (a terminal Ctrl-C reaches only the coordinator) and wait until it serves.
    pub fn spawn(
        program: &Path,
        extra_args: &[String],
        prefix: &str,
        node_name: &str,
    ) -> Result<NodeClient, LinkError> {
        let failed = |message: String| LinkError::Spawn {
            node: node_name.to_string(),
            program: program.display().to_string(),
            message,
        };
        let mut client = Self::open(prefix, node_name).map_err(|e| failed(e.to_string()))?;
        let mut child = std::process::Command::new(program)
            .arg("serve")
            .args(["--prefix", prefix, "--name", node_name])
            .args(extra_args)
            .stdin(Stdio::null())
            .stderr(Stdio::piped())
            .process_group(0)
            .spawn()
            .map_err(|e| failed(e.to_string()))?;
        client.pid = child.id();
        let stderr = StderrTail::start(child.stderr.take().expect("piped"));
        client.process = Some(Process { child, stderr });
        client.wait_until_served(STARTUP_TIMEOUT)?;
        Ok(client)
    }

    /// Link to node `node_name` of run `prefix` served by a thread of this process.
    pub fn connect(prefix: &str, node_name: &str) -> Result<NodeClient, LinkError> {
        let mut client = Self::open(prefix, node_name).map_err(|e| LinkError::Transport {
            node: node_name.to_string(),
            message: e.to_string(),
        })?;
        client.pid = std::process::id();
        client.wait_until_served(CONNECT_TIMEOUT)?;
        Ok(client)
    }

    fn open(prefix: &str, node_name: &str) -> Result<Self, IpcError> {
        let names = Names::new(prefix, node_name)?;
        let node = create_node::<Svc>(&format!("{prefix}/client/{node_name}"))?;
        let wake = event_service(&node, &names.wake)?;
        let reply = event_service(&node, &names.reply)?;
        let control = control_service(&node, &names.control)?;
        Ok(Self {
            name: node_name.to_string(),
            timeout: DEFAULT_TIMEOUT,
            poller: super::Poller::default(),
            process: None,
            pid: 0,
            pending: VecDeque::new(),
            client: control
                .client_builder()
                .initial_max_slice_len(super::CONTROL_INITIAL_BYTES)
                .allocation_strategy(AllocationStrategy::PowerOfTwo)
                .create()
                .map_err(IpcError::iox("create the control client"))?,
            wake: wake
                .notifier_builder()
                .create()
                .map_err(IpcError::iox("create the wake notifier"))?,
            replies: reply
                .listener_builder()
                .create()
                .map_err(IpcError::iox("create the reply listener"))?,
            control,
            _events: [wake, reply],
            _node: node,
        })
    }

    fn wait_until_served(&mut self, limit: Duration) -> Result<(), LinkError> {
        let start = Instant::now();
        let mut pause = Duration::from_micros(100);
        while self.control.dynamic_config().number_of_servers() == 0 {
            check_alive(&mut self.process, &self.name)?;
            if start.elapsed() > limit {
                return Err(LinkError::Timeout {
                    node: self.name.clone(),
                    seconds: limit.as_secs_f64(),
                });
            }
            std::thread::sleep(pause);
            pause = (pause * 2).min(Duration::from_millis(20));
        }
        Ok(())
    }

    /// The overall limit for one [`NodeClient::call`] (default 600 s).
    pub fn set_timeout(&mut self, timeout: Duration) {
        self.timeout = timeout;
    }

    /// Send `command` and wait for the node's reply. Requests still unanswered are dropped
    /// first (their replies are not waited for).
    pub fn call(&mut self, command: &Command) -> Result<Reply, LinkError> {
        self.pending.clear();
        self.send(command)?;
        self.receive()
    }

    /// Send `command` without waiting for the reply; [`NodeClient::receive`] or
    /// [`NodeClient::receive_within`] collects the replies in the order the requests went.
    pub fn send(&mut self, command: &Command) -> Result<(), LinkError> {
        let lost = |message: String| LinkError::Transport {
            node: self.name.clone(),
            message,
        };
        let bytes = command.to_bytes();
        // Notifications left from earlier replies would only cause spurious wake-ups.
        let _ = self.replies.try_wait(|_| {});
        let pending = self
            .client
            .loan_slice_uninit(bytes.len())
            .map_err(|e| lost(format!("cannot loan memory for a request: {e:?}")))?
            .write_from_slice(&bytes)
            .send()
            .map_err(|e| lost(format!("cannot send a request: {e:?}")))?;
        if pending.number_of_server_connections() == 0 {
            check_alive(&mut self.process, &self.name)?;
            return Err(lost("the node is not serving".into()));
        }
        self.wake
            .notify()
            .map_err(|e| lost(format!("cannot wake the node: {e:?}")))?;
        self.pending.push_back(Pending {
            response: pending,
            sent: Instant::now(),
            kind: super::wait_kind(command),
            polled: false,
        });
        Ok(())
    }

    /// Wait for the reply to the oldest request not yet answered, up to the overall timeout
    /// ([`NodeClient::set_timeout`]) counted from when it was sent.
    pub fn receive(&mut self) -> Result<Reply, LinkError> {
        loop {
            if let Some(reply) = self.receive_within(BLOCK_SLICE)? {
                return Ok(reply);
            }
            let sent = self.pending.front().map_or_else(Instant::now, |p| p.sent);
            if sent.elapsed() >= self.timeout {
                self.pending.pop_front();
                return Err(LinkError::Timeout {
                    node: self.name.clone(),
                    seconds: self.timeout.as_secs_f64(),
                });
            }
        }
    }

    /// The reply to the oldest request not yet answered, if it comes within `limit` (`Ok(None)`
    /// if not; the request stays pending). Polls first, unless this kind of wait was long last
    /// time; a zero `limit` only looks whether the reply is there.
    pub fn receive_within(&mut self, limit: Duration) -> Result<Option<Reply>, LinkError> {
        let name = self.name.clone();
        let lost = |message: String| LinkError::Transport {
            node: name.clone(),
            message,
        };
        let Some(p) = self.pending.front_mut() else {
            return Err(lost("no request is waiting for a reply".into()));
        };
        let start = Instant::now();
        let done = |p: &mut Pending, poller: &mut super::Poller, bytes: &[u8]| {
            poller.record(p.kind, p.sent.elapsed());
            Reply::from_bytes(bytes).map_err(&lost)
        };
        if limit.is_zero() {
            let Some(r) = p.response.receive().map_err(|e| lost(format!("{e:?}")))? else {
                check_alive(&mut self.process, &self.name)?;
                return Ok(None);
            };
            let reply = done(p, &mut self.poller, r.payload());
            self.pending.pop_front();
            return reply.map(Some);
        }
        if !p.polled {
            p.polled = true;
            if !self.poller.skips_polling(p.kind) {
                let receive = || p.response.receive().map_err(|e| lost(format!("{e:?}")));
                if let Some(r) = self.poller.poll(receive)? {
                    let reply = done(p, &mut self.poller, r.payload());
                    self.pending.pop_front();
                    return reply.map(Some);
                }
            }
            self.poller.blocked();
        }
        loop {
            if let Some(r) = p.response.receive().map_err(|e| lost(format!("{e:?}")))? {
                let reply = done(p, &mut self.poller, r.payload());
                self.pending.pop_front();
                return reply.map(Some);
            }
            let left = limit.saturating_sub(start.elapsed());
            if left.is_zero() {
                return Ok(None);
            }
            // A signal (the user's Ctrl-C, handled by the coordinator) interrupts the wait;
            // that is a spurious wake-up, not a lost link.
            match self.replies.timed_wait(|_| {}, left.min(BLOCK_SLICE)) {
                Ok(_) | Err(ListenerWaitError::InterruptSignal) => {}
                Err(e) => return Err(lost(format!("cannot wait for a reply: {e:?}"))),
            }
            if let Some(r) = p.response.receive().map_err(|e| lost(format!("{e:?}")))? {
                let reply = done(p, &mut self.poller, r.payload());
                self.pending.pop_front();
                return reply.map(Some);
            }
            check_alive(&mut self.process, &self.name)?;
            if !p.response.is_connected() {
                // The reply may have landed just before the server let go of the request.
                let last = p.response.receive().map_err(|e| lost(format!("{e:?}")))?;
                self.pending.pop_front();
                return match last {
                    Some(r) => Reply::from_bytes(r.payload()).map(Some).map_err(&lost),
                    None => Err(lost("the node stopped serving without answering".into())),
                };
            }
        }
    }

    /// Send `Shutdown`, wait (bounded) for the process to exit, kill it if it does not.
    pub fn shutdown(mut self) -> Result<(), LinkError> {
        self.timeout = self.timeout.min(SHUTDOWN_TIMEOUT);
        let answer = self.call(&Command::Shutdown);
        let exit = match self.process.as_mut() {
            Some(p) => wait_for_exit(&mut p.child, EXIT_TIMEOUT),
            None => None,
        };
        match answer? {
            Reply::Ok => {}
            Reply::Error(message) => {
                return Err(LinkError::Transport {
                    node: self.name.clone(),
                    message: format!("it refused to shut down: {message}"),
                })
            }
            other => {
                return Err(LinkError::Transport {
                    node: self.name.clone(),
                    message: format!("unexpected reply to shutdown: {other:?}"),
                })
            }
        }
        match (exit, self.process.as_mut()) {
            (Some(status), Some(p)) if !status.success() => Err(LinkError::Died {
                node: self.name.clone(),
                status: status.to_string(),
                stderr_tail: p.stderr.text(Duration::from_secs(1)),
            }),
            (None, Some(_)) => Err(LinkError::Timeout {
                node: self.name.clone(),
                seconds: EXIT_TIMEOUT.as_secs_f64(),
            }),
            _ => Ok(()),
        }
    }

    /// Process id of the node (this process for a node served by a thread).
    pub fn pid(&self) -> u32 {
        self.pid
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The last lines the node wrote on stderr (empty for a node served by a thread).
    pub fn stderr_tail(&self) -> String {
        self.process
            .as_ref()
            .map_or_else(String::new, |p| p.stderr.text(Duration::ZERO))
    }
}

impl Drop for NodeClient {
    fn drop(&mut self) {
        if let Some(p) = self.process.as_mut() {
            let clean_exit = match p.child.try_wait() {
                Ok(Some(status)) => status.success(),
                _ => {
                    let _ = p.child.kill();
                    let _ = p.child.wait();
                    false
                }
            };
            if !clean_exit {
                // A killed or crashed node could not release its shared memory.
                super::cleanup_stale_resources();
            }
        }
    }
}

/// `Err(Died)` once the spawned process has exited.
fn check_alive(process: &mut Option<Process>, node: &str) -> Result<(), LinkError> {
    let Some(p) = process.as_mut() else {
        return Ok(());
    };
    match p.child.try_wait() {
        Ok(None) => Ok(()),
        Ok(Some(status)) => Err(LinkError::Died {
            node: node.to_string(),
            status: status.to_string(),
            stderr_tail: p.stderr.text(Duration::from_secs(1)),
        }),
        Err(e) => Err(LinkError::Transport {
            node: node.to_string(),
            message: format!("cannot query its process: {e}"),
        }),
    }
}

/// Wait for exit up to `limit`; kill after that. `None` if it had to be killed.
fn wait_for_exit(child: &mut Child, limit: Duration) -> Option<std::process::ExitStatus> {
    let start = Instant::now();
    while start.elapsed() < limit {
        if let Ok(Some(status)) = child.try_wait() {
            return Some(status);
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

/// The last lines of a child's stderr, collected by a background thread.
struct StderrTail {
    lines: Arc<Mutex<VecDeque<String>>>,
    thread: JoinHandle<()>,
}

impl StderrTail {
    fn start(stderr: impl Read + Send + 'static) -> Self {
        let lines = Arc::new(Mutex::new(VecDeque::new()));
        let sink = Arc::clone(&lines);
        let thread = std::thread::spawn(move || {
            let mut reader = BufReader::new(stderr);
            let mut line = Vec::new();
            while reader.read_until(b'\n', &mut line).is_ok_and(|n| n > 0) {
                let text = String::from_utf8_lossy(&line).trim_end().to_string();
                let mut lines = sink.lock().unwrap_or_else(|e| e.into_inner());
                if lines.len() == TAIL_LINES {
                    lines.pop_front();
                }
                lines.push_back(text);
                line.clear();
            }
        });
        Self { lines, thread }
    }

    /// The tail, after waiting up to `wait` for the pipe to close (the process has exited).
    fn text(&self, wait: Duration) -> String {
        let start = Instant::now();
        while !self.thread.is_finished() && start.elapsed() < wait {
            std::thread::sleep(Duration::from_millis(1));
        }
        let lines = self.lines.lock().unwrap_or_else(|e| e.into_inner());
        lines
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>()
            .join("\n")
    }
}
