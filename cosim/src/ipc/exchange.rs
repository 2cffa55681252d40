//! [`IpcExchange`]: the bulk-data [`Exchange`] over iceoryx2 publish-subscribe.
use super::{create_node, service_name, IpcError};
use crate::exchange::{ExchangeError, PORTS};
use crate::{BeadForce, BeadImpulse, BeadState, Exchange, ExchangeHeader, Port, PortDescription};
use iceoryx2::node::{Node, NodeState, NodeView};
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::{AllocationStrategy, CallbackProgression, PortFactory, ZeroCopySend};
use iceoryx2::sample::Sample;
use iceoryx2::service::ipc;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSub;
use std::fmt::Debug;
use std::time::{Duration, Instant};

type Svc = ipc::Service;

/// How long a new reader waits for a serving publisher to hand over its latest publication.
const HISTORY_WAIT: Duration = Duration::from_secs(2);

/// Publications on `bead-states` a subscriber holds until it reads them: the coordinator
/// reads every step's bead states (orbit metrics) after a batch of up to this many steps
/// less two ([`crate::Exchange::read_states_of_step`]); the fibre node publishes them once a
/// step. Beyond that the oldest are dropped, and a read by step says which step it found.
pub const STATES_QUEUE: usize = 72;

/// One (port, record type): its service and this participant's ports on it, made on first use.
struct Lane<T: Record> {
    service: PubSub<Svc, [T], ExchangeHeader>,
    publisher: Option<Publisher<Svc, [T], ExchangeHeader>>,
    subscriber: Option<Subscriber<Svc, [T], ExchangeHeader>>,
    /// The latest sample received, held in shared memory until a newer one arrives.
    latest: Option<Sample<Svc, [T], ExchangeHeader>>,
    /// A sample received beyond the step a by-step read asked for
    /// ([`Exchange::read_states_of_step`]); it becomes `latest` on the next read.
    ahead: Option<Sample<Svc, [T], ExchangeHeader>>,
    /// Publications by this participant on this lane.
    sequence: u64,
    /// Sequence number of the publication this participant read last (0: none).
    read_sequence: u64,
}

#[derive(Default)]
struct Lanes {
    states: [Option<Lane<BeadState>>; PORTS],
    impulses: [Option<Lane<BeadImpulse>>; PORTS],
    forces: [Option<Lane<BeadForce>>; PORTS],
}

/// A record type that travels on ports.
trait Record: Copy + Debug + ZeroCopySend + 'static {
    const NAME: &'static str;
    fn lanes(lanes: &mut Lanes) -> &mut [Option<Lane<Self>>; PORTS];
}

impl Record for BeadState {
    const NAME: &'static str = "BeadState";
    fn lanes(lanes: &mut Lanes) -> &mut [Option<Lane<Self>>; PORTS] {
        &mut lanes.states
    }
}
impl Record for BeadImpulse {
    const NAME: &'static str = "BeadImpulse";
    fn lanes(lanes: &mut Lanes) -> &mut [Option<Lane<Self>>; PORTS] {
        &mut lanes.impulses
    }
}
impl Record for BeadForce {
    const NAME: &'static str = "BeadForce";
    fn lanes(lanes: &mut Lanes) -> &mut [Option<Lane<Self>>; PORTS] {
        &mut lanes.forces
    }
}

/// Bulk data of one participant (a node or the coordinator) of a run, through iceoryx2.
///
/// Each (port, record type) is the service `{prefix}/port/{port}/{Record}`, carrying `[Record]`
/// slices of any length with an [`ExchangeHeader`]; its history of one publication lets a
/// reader that arrives late still get the latest one. Publishers and subscribers are made on
/// the first publish or read of a port (the only allocation) and reused. Publishing loans a
/// slice in shared memory and writes the records straight into it.
///
/// iceoryx2 hands a late reader the history only when the publisher next updates its
/// connections. A reader that finds nothing therefore wakes the publishing node (its `wake`
/// event; [`crate::ipc::serve`] answers by updating its connections) and waits up to 2 s. A
/// participant that publishes without serving must either have its readers subscribe first
/// ([`IpcExchange::subscribe`]) or call [`IpcExchange::update_connections`].
pub struct IpcExchange {
    lanes: Lanes,
    prefix: String,
    /// `{prefix}/node/`: the iceoryx2 node names of serving participants start so.
    node_prefix: String,
    participant: String,
    node: Node<Svc>,
}

impl IpcExchange {
    /// The exchange of `participant` (e.g. `"fibre"`, `"coordinator"`) in run `prefix`.
    pub fn new(prefix: &str, participant: &str) -> Result<Self, IpcError> {
        let names = super::Names::new(prefix, participant)?;
        Ok(Self {
            lanes: Lanes::default(),
            prefix: prefix.to_string(),
            node_prefix: format!("{prefix}/node/"),
            participant: participant.to_string(),
            node: create_node(&names.node)?,
        })
    }

    pub fn participant(&self) -> &str {
        &self.participant
    }

    pub(crate) fn node(&self) -> &Node<Svc> {
        &self.node
    }

    /// Subscribe to `port` now, so that every later publication reaches this participant
    /// even if its publisher does not serve. `record` is `"BeadState"`, `"BeadImpulse"` or
    /// `"BeadForce"`, as in [`PortDescription::record`].
    pub fn subscribe(&mut self, port: Port, record: &str) -> Result<(), ExchangeError> {
        match record {
            BeadState::NAME => self.subscriber::<BeadState>(port).map(drop),
            BeadImpulse::NAME => self.subscriber::<BeadImpulse>(port).map(drop),
            BeadForce::NAME => self.subscriber::<BeadForce>(port).map(drop),
            other => Err(ExchangeError::Transport {
                port: port.name(),
                message: format!("unknown record type {other:?}"),
            }),
        }
    }

    /// [`IpcExchange::subscribe`] to each of a model description's inputs (records of
    /// another name are left to be subscribed on first read).
    pub fn subscribe_inputs(&mut self, inputs: &[PortDescription]) -> Result<(), ExchangeError> {
        let known = [BeadState::NAME, BeadImpulse::NAME, BeadForce::NAME];
        inputs
            .iter()
            .filter(|p| known.contains(&p.record.as_str()))
            .try_for_each(|p| self.subscribe(p.port, &p.record))
    }

    /// Whether a publication this participant has not read yet waits on `port` (for any
    /// record type it reads there). Cheap (no system call): poll it before blocking.
    pub fn has_unread(&self, port: Port) -> bool {
        fn pending<T: Record>(lane: &Option<Lane<T>>) -> bool {
            let subscriber = lane.as_ref().and_then(|l| l.subscriber.as_ref());
            subscriber.is_some_and(|s| s.has_samples().unwrap_or(false))
        }
        let i = port as usize;
        pending(&self.lanes.states[i])
            || pending(&self.lanes.impulses[i])
            || pending(&self.lanes.forces[i])
    }

    /// Hand the latest publication of each of this participant's ports to readers that
    /// subscribed since its last publication.
    /// Whether `port` holds a publication of step `step` or later that this participant has
    /// not read yet (what a phase of a pipelined batch waits for, see
    /// [`crate::protocol::Awaited`]). Receives what has arrived; never blocks.
    pub fn has_fresh(&mut self, port: Port, step: u64) -> Result<bool, ExchangeError> {
        fn fresh<T: Record>(
            lane: &mut Option<Lane<T>>,
            port: Port,
            step: u64,
        ) -> Result<bool, ExchangeError> {
            let Some(lane) = lane.as_mut().filter(|l| l.subscriber.is_some()) else {
                return Ok(false);
            };
            lane.drain(port)?;
            Ok(lane.latest.as_ref().is_some_and(|s| {
                let h = s.user_header();
                h.step >= step && h.sequence > lane.read_sequence
            }))
        }
        let i = port as usize;
        Ok(fresh(&mut self.lanes.states[i], port, step)?
            || fresh(&mut self.lanes.impulses[i], port, step)?
            || fresh(&mut self.lanes.forces[i], port, step)?)
    }

    pub fn update_connections(&self) {
        fn update<T: Record>(lanes: &[Option<Lane<T>>; PORTS]) {
            for lane in lanes.iter().flatten() {
                if let Some(p) = &lane.publisher {
                    let _ = p.update_connections();
                }
            }
        }
        update(&self.lanes.states);
        update(&self.lanes.impulses);
        update(&self.lanes.forces);
    }

    fn lane<T: Record>(&mut self, port: Port) -> Result<&mut Lane<T>, ExchangeError> {
        let slot = &mut T::lanes(&mut self.lanes)[port as usize];
        if slot.is_none() {
            let name = format!("{}/port/{}/{}", self.prefix, port.name(), T::NAME);
            let transport = |message: String| ExchangeError::Transport {
                port: port.name(),
                message,
            };
            let service = self
                .node
                .service_builder(&service_name(&name).map_err(|e| transport(e.to_string()))?)
                .publish_subscribe::<[T]>()
                .user_header::<ExchangeHeader>()
                .history_size(1)
                .subscriber_max_buffer_size(if port == Port::BeadStates {
                    STATES_QUEUE
                } else {
                    2
                })
                .subscriber_max_borrowed_samples(3)
                .enable_safe_overflow(true)
                .max_publishers(2)
                .max_subscribers(8)
                .open_or_create()
                .map_err(|e| transport(format!("cannot open service {name}: {e:?}")))?;
            *slot = Some(Lane {
                service,
                publisher: None,
                subscriber: None,
                latest: None,
                ahead: None,
                sequence: 0,
                read_sequence: 0,
            });
        }
        Ok(slot.as_mut().expect("just filled"))
    }

    fn subscriber<T: Record>(&mut self, port: Port) -> Result<&mut Lane<T>, ExchangeError> {
        let lane = self.lane::<T>(port)?;
        if lane.subscriber.is_none() {
            lane.subscriber = Some(
                lane.service
                    .subscriber_builder()
                    .create()
                    .map_err(|e| transport(port, "cannot subscribe", e))?,
            );
        }
        Ok(lane)
    }

    fn publish<T: Record>(
        &mut self,
        port: Port,
        step: u64,
        data: &[T],
    ) -> Result<(), ExchangeError> {
        let lane = self.lane::<T>(port)?;
        if lane.publisher.is_none() {
            lane.publisher = Some(
                lane.service
                    .publisher_builder()
                    .initial_max_slice_len(data.len().max(1))
                    .allocation_strategy(AllocationStrategy::PowerOfTwo)
                    .create()
                    .map_err(|e| transport(port, "cannot create publisher", e))?,
            );
        }
        let publisher = lane.publisher.as_ref().expect("just made");
        let mut sample = publisher
            .loan_slice_uninit(data.len())
            .map_err(|e| transport(port, "cannot loan shared memory", e))?;
        *sample.user_header_mut() = ExchangeHeader {
            step,
            sequence: lane.sequence + 1,
        };
        sample
            .write_from_slice(data)
            .send()
            .map_err(|e| transport(port, "cannot send", e))?;
        lane.sequence += 1;
        Ok(())
    }

    fn read<T: Record>(
        &mut self,
        port: Port,
        out: &mut Vec<T>,
    ) -> Result<ExchangeHeader, ExchangeError> {
        self.subscriber::<T>(port)?;
        // Re-borrow: `subscriber` ended its borrow of self; split fields now.
        let lane = T::lanes(&mut self.lanes)[port as usize]
            .as_mut()
            .expect("subscribed");
        lane.drain(port)?;
        if lane.latest.is_none() {
            // A new reader: the history reaches it when a publisher updates its connections.
            if let Some(own) = &lane.publisher {
                let _ = own.update_connections();
                lane.drain(port)?;
            }
            let others = lane.service.dynamic_config().number_of_publishers()
                - usize::from(lane.publisher.is_some());
            if lane.latest.is_none() && others > 0 {
                let own = *self.node.id();
                if wake_publishers(&self.node, &lane.service, own, &self.node_prefix) == 0 {
                    return Err(ExchangeError::Transport {
                        port: port.name(),
                        message: "its publisher does not serve, so its latest publication \
                                  cannot reach this new reader (subscribe before it publishes)"
                            .into(),
                    });
                }
                lane.wait_for_history(port)?;
            }
        }
        let sample = lane
            .latest
            .as_ref()
            .ok_or(ExchangeError::NothingPublished(port.name()))?;
        out.clear();
        out.extend_from_slice(sample.payload());
        let header = *sample.user_header();
        lane.read_sequence = header.sequence;
        Ok(header)
    }
}

impl<T: Record> Lane<T> {
    /// Receive everything pending, keeping only the newest sample.
    fn drain(&mut self, port: Port) -> Result<(), ExchangeError> {
        self.drain_to_step(port, u64::MAX)
    }

    /// Receive pending samples up to the newest of step `step` or earlier; the first sample
    /// of a later step is kept in `ahead` and receiving stops there.
    fn drain_to_step(&mut self, port: Port, step: u64) -> Result<(), ExchangeError> {
        match self.ahead.take() {
            Some(a) if a.user_header().step > step => {
                self.ahead = Some(a);
                return Ok(());
            }
            Some(a) => self.latest = Some(a),
            None => {}
        }
        let subscriber = self.subscriber.as_ref().expect("subscribed");
        while let Some(sample) = subscriber
            .receive()
            .map_err(|e| transport(port, "cannot receive", e))?
        {
            if sample.user_header().step > step {
                self.ahead = Some(sample);
                break;
            }
            self.latest = Some(sample);
        }
        Ok(())
    }

    fn wait_for_history(&mut self, port: Port) -> Result<(), ExchangeError> {
        let start = Instant::now();
        let mut pause = Duration::from_micros(20);
        while start.elapsed() < HISTORY_WAIT {
            self.drain(port)?;
            if self.latest.is_some() {
                return Ok(());
            }
            std::thread::sleep(pause);
            pause = (pause * 2).min(Duration::from_millis(5));
        }
        Err(ExchangeError::Transport {
            port: port.name(),
            message: format!(
                "its publisher did not hand over its latest publication within {} s",
                HISTORY_WAIT.as_secs()
            ),
        })
    }
}

/// Notify the `wake` event of every other serving node on `service`; returns how many.
fn wake_publishers<T: Record>(
    node: &Node<Svc>,
    service: &PubSub<Svc, [T], ExchangeHeader>,
    own: iceoryx2::identifiers::UniqueNodeId,
    node_prefix: &str,
) -> usize {
    let mut names = Vec::new();
    let _ = service.nodes(|state| {
        if let NodeState::Alive(view) = state {
            if *view.id() != own {
                if let Some(d) = view.details() {
                    names.push(d.name().as_str().to_string());
                }
            }
        }
        CallbackProgression::Continue
    });
    let mut woken = 0;
    for name in names.iter().filter(|n| n.starts_with(node_prefix)) {
        let Ok(wake) = service_name(&format!("{name}/wake")) else {
            continue;
        };
        let Ok(event) = node.service_builder(&wake).event().open() else {
            continue;
        };
        if let Ok(notifier) = event.notifier_builder().create() {
            woken += notifier.notify().unwrap_or(0).min(1);
        }
    }
    woken
}

fn transport(port: Port, what: &str, e: impl Debug) -> ExchangeError {
    ExchangeError::Transport {
        port: port.name(),
        message: format!("{what}: {e:?}"),
    }
}

impl Exchange for IpcExchange {
    fn publish_states(
        &mut self,
        port: Port,
        step: u64,
        data: &[BeadState],
    ) -> Result<(), ExchangeError> {
        self.publish(port, step, data)
    }
    fn read_states(
        &mut self,
        port: Port,
        out: &mut Vec<BeadState>,
    ) -> Result<ExchangeHeader, ExchangeError> {
        self.read(port, out)
    }
    fn read_states_of_step(
        &mut self,
        port: Port,
        step: u64,
        out: &mut Vec<BeadState>,
    ) -> Result<ExchangeHeader, ExchangeError> {
        self.subscriber::<BeadState>(port)?;
        let lane = self.lanes.states[port as usize]
            .as_mut()
            .expect("subscribed");
        lane.drain_to_step(port, step)?;
        let not_at = |found: u64| ExchangeError::NotAtStep {
            port: port.name(),
            wanted: step,
            found,
        };
        let header = match (&lane.latest, &lane.ahead) {
            (Some(sample), _) => {
                out.clear();
                out.extend_from_slice(sample.payload());
                *sample.user_header()
            }
            (None, Some(later)) => return Err(not_at(later.user_header().step)),
            // A new reader: the history path of `read`.
            (None, None) => self.read(port, out)?,
        };
        if header.step != step {
            return Err(not_at(header.step));
        }
        if let Some(lane) = self.lanes.states[port as usize].as_mut() {
            lane.read_sequence = lane.read_sequence.max(header.sequence);
        }
        Ok(header)
    }
    fn publish_impulses(
        &mut self,
        port: Port,
        step: u64,
        data: &[BeadImpulse],
    ) -> Result<(), ExchangeError> {
        self.publish(port, step, data)
    }
    fn read_impulses(
        &mut self,
        port: Port,
        out: &mut Vec<BeadImpulse>,
    ) -> Result<ExchangeHeader, ExchangeError> {
        self.read(port, out)
    }
    fn publish_forces(
        &mut self,
        port: Port,
        step: u64,
        data: &[BeadForce],
    ) -> Result<(), ExchangeError> {
        self.publish(port, step, data)
    }
    fn read_forces(
        &mut self,
        port: Port,
        out: &mut Vec<BeadForce>,
    ) -> Result<ExchangeHeader, ExchangeError> {
        self.read(port, out)
    }
}
