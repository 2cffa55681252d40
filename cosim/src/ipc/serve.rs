//! The node side: answer the coordinator's commands until `Shutdown`.
use super::{control_service, event_service, IpcError, IpcExchange, Names, BLOCK_SLICE};
use crate::{Command, Component, Reply};
use iceoryx2::active_request::ActiveRequest;
use iceoryx2::node::NodeState;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::server::Server;
use iceoryx2::prelude::{AllocationStrategy, CallbackProgression, PortFactory};
use iceoryx2::service::ipc;

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

    loop {
        let waiting = std::time::Instant::now();
        let request = next_request(
            &server,
            &listener,
            &control,
            &exchange,
            &mut watch,
            (&mut poller, kind),
        )?;
        poller.record(kind, waiting.elapsed());
        watch.seen_client = true;
        let (reply, done) = match Command::from_bytes(request.payload()) {
            Ok(command) => {
                kind = super::wait_kind(&command);
                crate::dispatch(component, &mut exchange, command)
            }
            Err(message) => (Reply::Error(message), false),
        };
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
            watch.check(&control)?;
            return Err(e);
        }
        if done {
            return Ok(());
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
