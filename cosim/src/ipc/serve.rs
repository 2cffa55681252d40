//! The node side: answer the coordinator's commands until `Shutdown`.
use super::{control_service, event_service, IpcError, IpcExchange, Names, BLOCK_SLICE};
use crate::{Awaited, Command, Component, FullReports, PhaseOrder, Reply, TimedReport};
use iceoryx2::active_request::ActiveRequest;
use iceoryx2::node::NodeState;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::server::Server;
use iceoryx2::prelude::{AllocationStrategy, CallbackProgression, PortFactory};
use iceoryx2::service::ipc;
use std::collections::VecDeque;

type Svc = ipc::Service;
type Control = super::Control<Svc>;
type Request = ActiveRequest<Svc, [u8], (), [u8], ()>;

/// Serve `component` as node `node_name` of run `prefix` until the coordinator sends
/// [`Command::Shutdown`] (then `Ok`), or until the coordinator is gone (then
/// [`IpcError::CoordinatorGone`]). Signals are left to the coordinator.
pub fn serve(component: &mut dyn Component, prefix: &str, node_name: &str) -> Result<(), IpcError> {
    let names = Names::new(prefix, node_name)?;
    let mut exchange = IpcExchange::new(prefix, node_name)?;
    // Inputs subscribed up front receive every publication, whoever publishes.
    exchange
        .subscribe_inputs(&component.describe().inputs)
        .map_err(IpcError::iox("subscribe to the inputs"))?;
    let node = exchange.node();
    let wake = event_service(node, &names.wake)?;
    let listener = wake
        .listener_builder()
        .create()
        .map_err(IpcError::iox("create the wake listener"))?;
    let reply = event_service(node, &names.reply)?;
    let replied = reply
        .notifier_builder()
        .create()
        .map_err(IpcError::iox("create the reply notifier"))?;
    let control = control_service(node, &names.control)?;
    // The server comes last: once it is there, the coordinator may send.
    let server = control
        .server_builder()
        .initial_max_slice_len(super::CONTROL_INITIAL_BYTES)
        .allocation_strategy(AllocationStrategy::PowerOfTwo)
        .create()
        .map_err(IpcError::iox("create the control server"))?;
    let mut watch = Watch::new(node_name);
    let mut poller = super::Poller::default();
    // The kind of the wait in progress: named by the command served before it.
    let mut kind = 0;
    // Requests received but not served yet, in order: batches that came while a batch waited
    // for its input, or the request a waiting batch gave way to.
    let mut queue: VecDeque<Request> = VecDeque::new();
    let mut wake_peers = Peers::default();

    loop {
        let waiting = std::time::Instant::now();
        let request = match queue.pop_front() {
            Some(r) => r,
            None => next_request(
                &server,
                &listener,
                &control,
                &exchange,
                &mut watch,
                (&mut poller, kind),
            )?,
        };
        poller.record(kind, waiting.elapsed());
        watch.seen_client = true;
        let (reply, done) = match Command::from_bytes(request.payload()) {
            Ok(command) => {
                kind = super::wait_kind(&command);
                match command {
                    Command::RunPhases {
                        step,
                        phases,
                        steps,
                        full_reports,
                    } => {
                        let mut batch = Batch {
                            server: &server,
                            listener: &listener,
                            control: &control,
                            replied: &replied,
                            watch: &mut watch,
                            poller: &mut poller,
                            peers: &mut wake_peers,
                            queue: &mut queue,
                            prefix,
                        };
                        let reply = batch.run(
                            component,
                            &mut exchange,
                            (step, steps),
                            full_reports,
                            &phases,
                        )?;
                        (reply, false)
                    }
                    other => crate::dispatch(component, &mut exchange, other),
                }
            }
            Err(message) => (Reply::Error(message), false),
        };
        answer(request, &reply, &replied, &mut watch, &control)?;
        if done {
            return Ok(());
        }
    }
}

/// Send `reply` to `request` and notify the coordinator.
fn answer(
    request: Request,
    reply: &Reply,
    replied: &Notifier<Svc>,
    watch: &mut Watch,
    control: &Control,
) -> Result<(), IpcError> {
    let bytes = reply.to_bytes();
    let sent = request
        .loan_slice_uninit(bytes.len())
        .map_err(IpcError::iox("loan memory for a reply"))
        .and_then(|r| {
            r.write_from_slice(&bytes)
                .send()
                .map_err(IpcError::iox("send a reply"))
        });
    drop(request);
    let sent = sent.and_then(|()| {
        replied
            .notify()
            .map(drop)
            .map_err(IpcError::iox("notify the coordinator"))
    });
    if let Err(e) = sent {
        // Most likely the coordinator went away meanwhile; say so if it did.
        watch.check(control)?;
        return Err(e);
    }
    Ok(())
}

/// Wake-up notifiers of the other nodes of the run, by name, made on first use.
#[derive(Default)]
struct Peers(Vec<(String, Notifier<Svc>)>);

impl Peers {
    fn wake(
        &mut self,
        node: &iceoryx2::node::Node<Svc>,
        prefix: &str,
        name: &str,
    ) -> Result<(), IpcError> {
        if !self.0.iter().any(|(n, _)| n == name) {
            let names = Names::new(prefix, name)?;
            let notifier = event_service(node, &names.wake)?
                .notifier_builder()
                .create()
                .map_err(IpcError::iox_with(|| {
                    format!("create a wake notifier for node {name}")
                }))?;
            self.0.push((name.to_string(), notifier));
        }
        let (_, notifier) = self.0.iter().find(|(n, _)| n == name).expect("just made");
        notifier
            .notify()
            .map(drop)
            .map_err(IpcError::iox_with(|| format!("wake node {name}")))
    }
}

/// What a batch of phases ([`Command::RunPhases`]) needs from the serving loop.
struct Batch<'a> {
    server: &'a Server<Svc, [u8], (), [u8], ()>,
    listener: &'a Listener<Svc>,
    control: &'a Control,
    replied: &'a Notifier<Svc>,
    watch: &'a mut Watch,
    poller: &'a mut super::Poller,
    peers: &'a mut Peers,
    /// Requests that arrive during a wait, for the serving loop: batches, kept for later, or
    /// the request the batch gave way to.
    queue: &'a mut VecDeque<Request>,
    prefix: &'a str,
}

impl Batch<'_> {
    /// Run the phases in order, each once its input is there, for `steps` consecutive steps
    /// from `first`, reporting in full at the steps `full_reports` names; wake the node that
    /// waits for a phase's output. Returns the reply. If a request other than a batch comes
    /// while a phase waits for its input, the coordinator has given up on this step (e.g. the
    /// other node failed): the batch ends there with an error, the batches queued behind it
    /// are answered with an error unserved, and that request is left in the queue.
    fn run(
        &mut self,
        component: &mut dyn Component,
        exchange: &mut IpcExchange,
        (first, steps): (u64, u64),
        full_reports: FullReports,
        phases: &[PhaseOrder],
    ) -> Result<Reply, IpcError> {
        let steps = steps.max(1);
        let mut reports = Vec::with_capacity(phases.len() * steps as usize);
        for (j, order) in (0..steps).flat_map(|j| phases.iter().map(move |o| (j, o))) {
            let step = first + j;
            let phase = order.phase;
            let mut waited = 0.0;
            if let Some(mut awaited) = order.awaits {
                awaited.step += j;
                let kind = super::input_wait_kind(phase);
                let start = std::time::Instant::now();
                let interrupted = self.wait_for_input(exchange, awaited, kind)?;
                let elapsed = start.elapsed();
                self.poller.record(kind, elapsed);
                waited = elapsed.as_secs_f64();
                if let Some(request) = interrupted {
                    for queued in self.queue.drain(..) {
                        let message = "abandoned: an earlier batch gave way to a new request";
                        let reply = Reply::Error(message.into());
                        answer(queued, &reply, self.replied, self.watch, self.control)?;
                    }
                    self.queue.push_back(request);
                    return Ok(Reply::PhasesFailed {
                        step,
                        message: format!(
                            "phase {phase} of step {step} was still waiting for its input \
                             ({} of step {}) when a new request came",
                            awaited.port.name(),
                            awaited.step
                        ),
                    });
                }
            }
            let start = std::time::Instant::now();
            let detail = full_reports.detail(step);
            let command = Command::RunPhase {
                step,
                phase,
                detail,
            };
            let (reply, _) = crate::dispatch(component, exchange, command);
            let failed = |message| Ok(Reply::PhasesFailed { step, message });
            let report = match reply {
                Reply::PhaseDone(r) => r,
                Reply::Error(m) => return failed(format!("phase {phase}: {m}")),
                other => return failed(format!("phase {phase}: unexpected reply {other:?}")),
            };
            reports.push(TimedReport {
                report,
                seconds: start.elapsed().as_secs_f64(),
                waited,
            });
            if let Some(peer) = &order.then_wake {
                self.peers.wake(exchange.node(), self.prefix, peer)?;
            }
        }
        Ok(Reply::PhasesDone(reports))
    }

    /// Poll for the awaited publication (unless this kind of wait is long), then block on the
    /// wake event, which both the producing node and the coordinator notify.
    fn wait_for_input(
        &mut self,
        exchange: &mut IpcExchange,
        awaited: Awaited,
        kind: usize,
    ) -> Result<Option<Request>, IpcError> {
        let Awaited { port, step } = awaited;
        // The message is formed only on failure: this runs every step.
        let lost = |e| IpcError::iox_with(|| format!("read port {}", port.name()))(e);
        if !self.poller.skips_polling(kind) {
            let fresh = || exchange.has_fresh(port, step).map(|f| f.then_some(()));
            if self.poller.poll(fresh).map_err(lost)?.is_some() {
                return Ok(None);
            }
        }
        self.poller.blocked();
        loop {
            if exchange.has_fresh(port, step).map_err(lost)? {
                return Ok(None);
            }
            if let Some(r) = self
                .server
                .receive()
                .map_err(IpcError::iox("receive a request"))?
            {
                // The next step's batch, sent early: it waits its turn. Anything else
                // (shutdown, a state request) means the coordinator gave up on this step.
                if matches!(
                    Command::from_bytes(r.payload()),
                    Ok(Command::RunPhases { .. })
                ) {
                    self.queue.push_back(r);
                    continue;
                }
                return Ok(Some(r));
            }
            let woken = match self.listener.timed_wait(|_| {}, BLOCK_SLICE) {
                Err(iceoryx2::port::listener::ListenerWaitError::InterruptSignal) => 0,
                other => other.map_err(IpcError::iox("wait for an input"))?,
            };
            exchange.update_connections();
            if woken == 0 {
                self.watch.check(self.control)?;
            }
        }
    }
}

/// Poll briefly (unless this kind of wait is long), then block on the wake event in slices,
/// checking on the coordinator.
fn next_request(
    server: &Server<Svc, [u8], (), [u8], ()>,
    listener: &Listener<Svc>,
    control: &Control,
    exchange: &IpcExchange,
    watch: &mut Watch,
    (poller, kind): (&mut super::Poller, usize),
) -> Result<Request, IpcError> {
    let receive = || server.receive().map_err(IpcError::iox("receive a request"));
    if !poller.skips_polling(kind) {
        if let Some(r) = poller.poll(receive)? {
            return Ok(r);
        }
    }
    poller.blocked();
    loop {
        // A signal interrupting the wait is a spurious wake-up.
        let woken = match listener.timed_wait(|_| {}, BLOCK_SLICE) {
            Err(iceoryx2::port::listener::ListenerWaitError::InterruptSignal) => 0,
            other => other.map_err(IpcError::iox("wait for a request"))?,
        };
        // A wake-up may be a new reader asking for the latest publication.
        exchange.update_connections();
        if let Some(r) = receive()? {
            return Ok(r);
        }
        if woken == 0 {
            watch.check(control)?;
        }
    }
}

/// Tells whether the coordinator is still there.
struct Watch {
    node: String,
    parent: u32,
    seen_client: bool,
}

impl Watch {
    fn new(node: &str) -> Self {
        Self {
            node: node.to_string(),
            parent: std::os::unix::process::parent_id(),
            seen_client: false,
        }
    }

    fn check(&mut self, control: &Control) -> Result<(), IpcError> {
        let gone = |reason: &str| {
            Err(IpcError::CoordinatorGone {
                node: self.node.clone(),
                reason: reason.to_string(),
            })
        };
        if std::os::unix::process::parent_id() != self.parent {
            return gone("the parent process exited");
        }
        let mut dead = false;
        let _ = control.nodes(|state| {
            dead |= matches!(state, NodeState::Dead(_));
            CallbackProgression::Continue
        });
        if dead {
            return gone("its iceoryx2 node is dead");
        }
        let clients = control.dynamic_config().number_of_clients();
        if self.seen_client && clients == 0 {
            return gone("it disconnected without sending shutdown");
        }
        self.seen_client |= clients > 0;
        Ok(())
    }
}
