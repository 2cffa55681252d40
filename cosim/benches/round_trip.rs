//! Round trips through iceoryx2 between two threads of this process.
//!
//! - `exchange_round_trip/N`: A publishes N bead states and notifies; B wakes, reads them,
//!   publishes N bead impulses and notifies; A wakes and reads them. Both wait as the
//!   transport does: poll for 50 us (`ipc::Poller`), then block on an event.
//! - `control_round_trip`: `Command::RunPhase` -> `Reply::PhaseDone` through `serve` and
//!   `NodeClient` (JSON both ways, wake and reply events).
use cosim::ipc::{self, IpcExchange, NodeClient};
use cosim::{
    BeadImpulse, BeadState, Command, Component, ComponentError, Configured, Exchange,
    ModelDescription, Phase, PhaseReport, Port, Reply,
};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;

type Iox = iceoryx2::service::ipc::Service;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// One side's doorbell: a listener for its own event and a notifier for the other's.
struct Bell {
    listener: Listener<Iox>,
    poller: ipc::Poller,
    notifier: Notifier<Iox>,
    _node: Node<Iox>,
}

impl Bell {
    fn new(prefix: &str, me: &str, other: &str) -> Bell {
        let node = NodeBuilder::new()
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .config(&Config::default())
            .create::<Iox>()
            .unwrap();
        let event = |who: &str| {
            node.service_builder(&format!("{prefix}/bench/{who}").as_str().try_into().unwrap())
                .event()
                .open_or_create()
                .unwrap()
        };
        Bell {
            listener: event(me).listener_builder().create().unwrap(),
            notifier: event(other).notifier_builder().create().unwrap(),
            poller: ipc::Poller::default(),
            _node: node,
        }
    }

    /// Wait as the transport does (poll for 50 us, then block on the event); false if `stop`
    /// was raised.
    fn wait(&mut self, exchange: &IpcExchange, port: Port, stop: &AtomicBool) -> bool {
        let unread = || Ok::<_, ()>(exchange.has_unread(port).then_some(()));
        if self.poller.poll(unread).unwrap().is_some() {
            return true;
        }
        self.poller.blocked();
        while !exchange.has_unread(port) {
            if stop.load(Ordering::Relaxed) {
                return false;
            }
            self.listener
                .timed_wait(|_| {}, Duration::from_millis(100))
                .unwrap();
        }
        true
    }
}

/// B: answer every batch of bead states with as many impulses.
fn echo(prefix: String, stop: Arc<AtomicBool>, ready: std::sync::mpsc::Sender<()>) {
    let mut b = IpcExchange::new(&prefix, "b").unwrap();
    b.subscribe(Port::BeadStates, "BeadState").unwrap();
    let mut bell = Bell::new(&prefix, "b", "a");
    ready.send(()).unwrap();
    let (mut states, mut impulses) = (Vec::new(), Vec::new());
    while bell.wait(&b, Port::BeadStates, &stop) {
        let h = b.read_states(Port::BeadStates, &mut states).unwrap();
        impulses.clear();
        impulses.extend(states.iter().map(|s| BeadImpulse {
            impulse: s.velocity,
            angular_impulse: s.angular_velocity,
        }));
        b.publish_impulses(Port::BeadImpulses, h.step, &impulses)
            .unwrap();
        bell.notifier.notify().unwrap();
    }
}

fn exchange_round_trip(c: &mut Criterion) {
    let prefix = ipc::new_run_prefix();
    let stop = Arc::new(AtomicBool::new(false));
    let (ready_tx, ready_rx) = std::sync::mpsc::channel();
    let echo_thread = {
        let (prefix, stop) = (prefix.clone(), stop.clone());
        std::thread::spawn(move || echo(prefix, stop, ready_tx))
    };
    ready_rx.recv().unwrap();
    let mut a = IpcExchange::new(&prefix, "a").unwrap();
    a.subscribe(Port::BeadImpulses, "BeadImpulse").unwrap();
    let mut bell = Bell::new(&prefix, "a", "b");
    let mut impulses = Vec::new();
    let mut step = 0;

    let mut group = c.benchmark_group("exchange_round_trip");
    for n in [10usize, 100, 1000] {
        let states: Vec<BeadState> = (0..n)
            .map(|i| BeadState::at_rest([i as f64, 0.0, 0.0]))
            .collect();
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |bench, &n| {
            bench.iter(|| {
                step += 1;
                a.publish_states(Port::BeadStates, step, &states).unwrap();
                bell.notifier.notify().unwrap();
                assert!(bell.wait(&a, Port::BeadImpulses, &AtomicBool::new(false)));
                let h = a.read_impulses(Port::BeadImpulses, &mut impulses).unwrap();
                assert_eq!((h.step, impulses.len()), (step, n));
            })
        });
    }
    group.finish();

    stop.store(true, Ordering::Relaxed);
    bell.notifier.notify().unwrap();
    echo_thread.join().unwrap();
    drop((a, bell));
    assert!(ipc::resources_of_run(&prefix).is_empty());
}

/// Answers every phase at once.
struct Idle;

impl Component for Idle {
    fn describe(&self) -> ModelDescription {
        serde_json::from_str(
            r#"{"name":"idle","version":"0","summary":"","kind":"fibre","models":[],
            "coupling_schemes":[],"effects":[],"phases":[],"parameters":[],"inputs":[],
            "outputs":[],"notes":[]}"#,
        )
        .unwrap()
    }
    fn configure(&mut self, _: &str, _: &mut dyn Exchange) -> Result<Configured, ComponentError> {
        Ok(Configured::default())
    }
    fn run_phase(
        &mut self,
        step: u64,
        _: Phase,
        _: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        Ok(PhaseReport {
            diagnostics: vec![("step".into(), step as f64)],
            detail: Default::default(),
        })
    }
    fn save_state(&self) -> Result<Vec<u8>, ComponentError> {
        Ok(Vec::new())
    }
    fn restore_state(&mut self, _: &[u8]) -> Result<(), ComponentError> {
        Ok(())
    }
}

fn control_round_trip(c: &mut Criterion) {
    let prefix = ipc::new_run_prefix();
    let node = {
        let prefix = prefix.clone();
        std::thread::spawn(move || ipc::serve(&mut Idle, &prefix, "idle"))
    };
    let mut client = NodeClient::connect(&prefix, "idle").unwrap();
    let mut step = 0;
    c.bench_function("control_round_trip", |bench| {
        bench.iter(|| {
            step += 1;
            let command = Command::RunPhase {
                step,
                phase: Phase::FibrePositions,
                detail: Default::default(),
            };
            let reply = client.call(&command).unwrap();
            assert!(matches!(reply, Reply::PhaseDone(_)));
        })
    });
    client.shutdown().unwrap();
    node.join().unwrap().unwrap();
    assert!(ipc::resources_of_run(&prefix).is_empty());
}

fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .sample_size(30)
}

criterion_group! {
    name = benches;
    config = config();
    targets = exchange_round_trip, control_round_trip
}
criterion_main!(benches);
