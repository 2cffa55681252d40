//! The iceoryx2 transport against the in-process one: same components, same commands, same
//! bits. Nodes are served by threads of this process (`serve` + `NodeClient::connect`).
use cosim::exchange::ExchangeError;
use cosim::ipc::{self, IpcError, IpcExchange, LinkError, NodeClient};
use cosim::{
    BeadImpulse, BeadState, Command, Component, ComponentError, Configured, Exchange,
    ExchangeHeader, InProcessExchange, ModelDescription, Phase, PhaseReport, Port, PortDescription,
    Reply,
};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

// ---------------------------------------------------------------- toy components

fn description(
    kind: &str,
    phases: Vec<Phase>,
    input: (Port, &str),
    output: (Port, &str),
) -> ModelDescription {
    let port = |(port, record): (Port, &str)| PortDescription {
        port,
        record: record.to_string(),
        description: String::new(),
    };
    ModelDescription {
        name: format!("toy-{kind}"),
        version: "0".into(),
        summary: "test component".into(),
        kind: kind.into(),
        models: vec!["toy".into()],
        coupling_schemes: vec!["spm".into()],
        effects: vec![],
        phases,
        parameters: vec![],
        inputs: vec![port(input)],
        outputs: vec![port(output)],
        notes: vec![],
    }
}

/// Beads that drift with their velocity and take the impulses the toy fluid gives them.
#[derive(Default)]
struct ToyFibre {
    beads: Vec<BeadState>,
    impulses: Vec<BeadImpulse>,
    /// A phase of this many milliseconds sleeps first (to provoke timeouts).
    slow_ms: u64,
}

impl Component for ToyFibre {
    fn describe(&self) -> ModelDescription {
        description(
            "fibre",
            vec![Phase::FibrePositions, Phase::FibreVelocities],
            (Port::BeadImpulses, "BeadImpulse"),
            (Port::BeadStates, "BeadState"),
        )
    }

    fn configure(
        &mut self,
        scene_toml: &str,
        exchange: &mut dyn Exchange,
    ) -> Result<Configured, ComponentError> {
        let scene: toml::Table =
            toml::from_str(scene_toml).map_err(|e| ComponentError::new(e.to_string()))?;
        let n = scene["beads"]
            .as_integer()
            .ok_or_else(|| ComponentError::new("beads"))? as usize;
        self.slow_ms = scene
            .get("slow_ms")
            .and_then(|v| v.as_integer())
            .unwrap_or(0) as u64;
        self.beads = (0..n)
            .map(|i| {
                let mut b = BeadState::at_rest([i as f64, 0.5 * i as f64, 0.0]);
                b.velocity = [0.1, 0.01 * i as f64, 0.0];
                b
            })
            .collect();
        exchange.publish_states(Port::BeadStates, 0, &self.beads)?;
        Ok(Configured {
            beads_per_fibre: vec![n],
            ..Default::default()
        })
    }

    fn run_phase(
        &mut self,
        step: u64,
        phase: Phase,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        std::thread::sleep(Duration::from_millis(self.slow_ms));
        let dt = 0.1;
        match phase {
            Phase::FibrePositions => {
                for b in &mut self.beads {
                    for k in 0..3 {
                        b.position[k] += dt * b.velocity[k];
                    }
                    b.orientation[1] = (b.orientation[1] + 0.01 * b.position[0]).sin();
                }
            }
            Phase::FibreVelocities => {
                let h = exchange.read_impulses(Port::BeadImpulses, &mut self.impulses)?;
                if h.step != step {
                    return Err(ComponentError::new(format!(
                        "impulses of step {} at step {step}",
                        h.step
                    )));
                }
                for (b, j) in self.beads.iter_mut().zip(&self.impulses) {
                    for k in 0..3 {
                        b.velocity[k] += j.impulse[k] / 1.7;
                        b.angular_velocity[k] += j.angular_impulse[k] / 0.3;
                    }
                }
            }
            other => {
                return Err(ComponentError::new(format!(
                    "toy fibre does not run {other}"
                )))
            }
        }
        exchange.publish_states(Port::BeadStates, step, &self.beads)?;
        let energy = self
            .beads
            .iter()
            .map(|b| b.velocity.iter().map(|v| v * v).sum::<f64>())
            .sum();
        Ok(PhaseReport {
            diagnostics: vec![("kinetic energy".into(), energy)],
            detail: Default::default(),
        })
    }

    fn save_state(&self) -> Result<Vec<u8>, ComponentError> {
        let mut out = Vec::new();
        for b in &self.beads {
            for x in b
                .position
                .iter()
                .chain(&b.orientation)
                .chain(&b.velocity)
                .chain(&b.angular_velocity)
            {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        Ok(out)
    }

    fn restore_state(&mut self, state: &[u8]) -> Result<(), ComponentError> {
        let x: Vec<f64> = state
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        self.beads = x
            .chunks_exact(13)
            .map(|c| BeadState {
                position: c[0..3].try_into().unwrap(),
                orientation: c[3..7].try_into().unwrap(),
                velocity: c[7..10].try_into().unwrap(),
                angular_velocity: c[10..13].try_into().unwrap(),
            })
            .collect();
        Ok(())
    }
}

/// Reads bead states, answers with a drag-like impulse per bead.
#[derive(Default)]
struct ToyFluid {
    states: Vec<BeadState>,
    impulses: Vec<BeadImpulse>,
    phases_run: u64,
}

impl Component for ToyFluid {
    fn describe(&self) -> ModelDescription {
        description(
            "fluid",
            vec![Phase::FluidMomentumExchange],
            (Port::BeadStates, "BeadState"),
            (Port::BeadImpulses, "BeadImpulse"),
        )
    }

    fn configure(
        &mut self,
        _scene: &str,
        _exchange: &mut dyn Exchange,
    ) -> Result<Configured, ComponentError> {
        Ok(Configured::default())
    }

    fn run_phase(
        &mut self,
        step: u64,
        phase: Phase,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        if phase != Phase::FluidMomentumExchange {
            return Err(ComponentError::new(format!(
                "toy fluid does not run {phase}"
            )));
        }
        let h = exchange.read_states(Port::BeadStates, &mut self.states)?;
        if h.step != step {
            return Err(ComponentError::new(format!(
                "states of step {} at step {step}",
                h.step
            )));
        }
        self.phases_run += 1;
        self.impulses.clear();
        self.impulses
            .extend(self.states.iter().map(|b| BeadImpulse {
                impulse: [
                    -0.3 * b.velocity[0] + 0.01 * b.position[1].sin(),
                    -0.3 * b.velocity[1],
                    0.0,
                ],
                angular_impulse: [0.0, 0.0, 0.02 * b.position[0].cos()],
            }));
        exchange.publish_impulses(Port::BeadImpulses, step, &self.impulses)?;
        let total = self.impulses.iter().map(|j| j.impulse[0]).sum();
        Ok(PhaseReport {
            diagnostics: vec![
                ("total impulse".into(), total),
                ("phases".into(), self.phases_run as f64),
            ],
            detail: Default::default(),
        })
    }

    fn save_state(&self) -> Result<Vec<u8>, ComponentError> {
        Ok(self.phases_run.to_le_bytes().to_vec())
    }

    fn restore_state(&mut self, state: &[u8]) -> Result<(), ComponentError> {
        self.phases_run = u64::from_le_bytes(
            state
                .try_into()
                .map_err(|_| ComponentError::new("bad state"))?,
        );
        Ok(())
    }
}

// ---------------------------------------------------------------- the same script, two ways

/// What the coordinator does: send commands to nodes, read the bead states.
trait Coordinator {
    fn call(&mut self, node: &str, command: Command) -> Reply;
    fn read_states(&mut self) -> (ExchangeHeader, Vec<BeadState>);
}

struct InProcess {
    fibre: ToyFibre,
    fluid: ToyFluid,
    exchange: InProcessExchange,
}

impl Coordinator for InProcess {
    fn call(&mut self, node: &str, command: Command) -> Reply {
        let component: &mut dyn Component = if node == "fibre" {
            &mut self.fibre
        } else {
            &mut self.fluid
        };
        cosim::dispatch(component, &mut self.exchange.clone(), command).0
    }
    fn read_states(&mut self) -> (ExchangeHeader, Vec<BeadState>) {
        let mut out = Vec::new();
        (
            self.exchange
                .read_states(Port::BeadStates, &mut out)
                .unwrap(),
            out,
        )
    }
}

struct Ipc {
    fibre: NodeClient,
    fluid: NodeClient,
    /// Made on the first read, after the fibre published: a late subscriber.
    exchange: Option<IpcExchange>,
    prefix: String,
}

impl Coordinator for Ipc {
    fn call(&mut self, node: &str, command: Command) -> Reply {
        let client = if node == "fibre" {
            &mut self.fibre
        } else {
            &mut self.fluid
        };
        client.call(&command).unwrap()
    }
    fn read_states(&mut self) -> (ExchangeHeader, Vec<BeadState>) {
        let prefix = self.prefix.clone();
        let exchange = self
            .exchange
            .get_or_insert_with(|| IpcExchange::new(&prefix, "coordinator").unwrap());
        let mut out = Vec::new();
        (
            exchange.read_states(Port::BeadStates, &mut out).unwrap(),
            out,
        )
    }
}

fn step(c: &mut dyn Coordinator, n: u64, log: &mut Vec<String>) {
    for (node, phase) in [
        ("fibre", Phase::FibrePositions),
        ("fluid", Phase::FluidMomentumExchange),
        ("fibre", Phase::FibreVelocities),
    ] {
        log.push(format!(
            "{:?}",
            c.call(
                node,
                Command::RunPhase {
                    step: n,
                    phase,
                    detail: Default::default(),
                }
            )
        ));
    }
    let (h, states) = c.read_states();
    log.push(format!("{h:?} {states:?}"));
}

/// The whole script; returns everything the coordinator saw.
fn script(c: &mut dyn Coordinator, beads: usize) -> Vec<String> {
    let mut log = Vec::new();
    for node in ["fibre", "fluid"] {
        log.push(format!("{:?}", c.call(node, Command::Describe)));
        let scene_toml = format!("beads = {beads}");
        log.push(format!(
            "{:?}",
            c.call(node, Command::Configure { scene_toml })
        ));
    }
    let (h, states) = c.read_states();
    log.push(format!("{h:?} {states:?}"));
    for n in 1..=3 {
        step(c, n, &mut log);
    }
    let saved: Vec<Reply> = ["fibre", "fluid"]
        .map(|node| c.call(node, Command::SaveState))
        .into();
    log.push(format!("{saved:?}"));
    let mut first = Vec::new();
    for n in 4..=5 {
        step(c, n, &mut first);
    }
    for (node, reply) in ["fibre", "fluid"].into_iter().zip(saved) {
        let Reply::State(state) = reply else {
            panic!("{reply:?}")
        };
        assert_eq!(c.call(node, Command::RestoreState { state }), Reply::Ok);
    }
    let mut again = Vec::new();
    for n in 4..=5 {
        step(c, n, &mut again);
    }
    // After a restore the same steps give the same phase reports and bead states; only the
    // publication sequence numbers go on counting.
    let without_sequence = |log: &[String]| -> Vec<String> {
        log.iter()
            .map(|l| {
                l.split_once(" } ")
                    .map_or(l.clone(), |(_, rest)| rest.to_string())
            })
            .collect()
    };
    assert_eq!(without_sequence(&first), without_sequence(&again));
    log.extend(first);
    log.extend(again);
    log
}

fn in_process_log(beads: usize) -> Vec<String> {
    script(
        &mut InProcess {
            fibre: ToyFibre::default(),
            fluid: ToyFluid::default(),
            exchange: InProcessExchange::new(),
        },
        beads,
    )
}

fn serve_thread<C: Component + Default>(
    prefix: &str,
    name: &str,
) -> JoinHandle<Result<(), IpcError>> {
    let (prefix, name) = (prefix.to_string(), name.to_string());
    std::thread::spawn(move || ipc::serve(&mut C::default(), &prefix, &name))
}

fn ipc_log(beads: usize) -> Vec<String> {
    let prefix = ipc::new_run_prefix();
    let threads = [
        serve_thread::<ToyFibre>(&prefix, "fibre"),
        serve_thread::<ToyFluid>(&prefix, "fluid"),
    ];
    let mut c = Ipc {
        fibre: NodeClient::connect(&prefix, "fibre").unwrap(),
        fluid: NodeClient::connect(&prefix, "fluid").unwrap(),
        exchange: None,
        prefix: prefix.clone(),
    };
    let log = script(&mut c, beads);
    let Ipc {
        fibre,
        fluid,
        exchange,
        ..
    } = c;
    fibre.shutdown().unwrap();
    fluid.shutdown().unwrap();
    drop(exchange);
    for t in threads {
        t.join().unwrap().unwrap();
    }
    assert_eq!(
        ipc::resources_of_run(&prefix),
        Vec::<String>::new(),
        "left behind"
    );
    log
}

// ---------------------------------------------------------------- tests

#[test]
fn ipc_run_matches_in_process_run_bit_for_bit() {
    for beads in [1, 7, 300] {
        let expected = in_process_log(beads);
        let got = ipc_log(beads);
        assert_eq!(got.len(), expected.len());
        for (g, e) in got.iter().zip(&expected) {
            assert_eq!(g, e);
        }
    }
}

#[test]
fn parallel_runs_do_not_interfere() {
    let expected = in_process_log(5);
    let runs: Vec<_> = (0..3).map(|_| std::thread::spawn(|| ipc_log(5))).collect();
    for run in runs {
        assert_eq!(run.join().unwrap(), expected);
    }
}

#[test]
fn late_subscriber_gets_latest_publication_from_a_serving_node() {
    let prefix = ipc::new_run_prefix();
    let thread = serve_thread::<ToyFibre>(&prefix, "fibre");
    let mut fibre = NodeClient::connect(&prefix, "fibre").unwrap();
    fibre
        .call(&Command::Configure {
            scene_toml: "beads = 4".into(),
        })
        .unwrap();
    let mut out = Vec::new();
    for n in 1..=2 {
        fibre
            .call(&Command::RunPhase {
                step: n,
                phase: Phase::FibrePositions,
                detail: Default::default(),
            })
            .unwrap();
        // A reader that arrives after the publication.
        let mut late = IpcExchange::new(&prefix, &format!("late{n}")).unwrap();
        let h = late.read_states(Port::BeadStates, &mut out).unwrap();
        assert_eq!((h.step, h.sequence, out.len()), (n, n + 1, 4));
    }
    fibre.shutdown().unwrap();
    thread.join().unwrap().unwrap();
    assert!(ipc::resources_of_run(&prefix).is_empty());
}

#[test]
fn exchange_without_serving_publisher() {
    let prefix = ipc::new_run_prefix();
    let mut a = IpcExchange::new(&prefix, "a").unwrap();
    let mut early = IpcExchange::new(&prefix, "early").unwrap();
    let mut out = Vec::new();
    assert_eq!(
        early.read_states(Port::BeadStates, &mut out),
        Err(ExchangeError::NothingPublished("bead-states"))
    );
    let few: Vec<BeadState> = (0..10).map(|i| BeadState::at_rest([i as f64; 3])).collect();
    let many: Vec<BeadState> = (0..5000)
        .map(|i| BeadState::at_rest([i as f64; 3]))
        .collect();
    a.publish_states(Port::BeadStates, 1, &few).unwrap();
    a.publish_states(Port::BeadStates, 2, &many).unwrap(); // grows the shared memory
    let h = early.read_states(Port::BeadStates, &mut out).unwrap();
    assert_eq!((h.step, h.sequence), (2, 2));
    assert_eq!(out, many);
    // Reading again without a new publication returns the latest again.
    assert_eq!(
        early
            .read_states(Port::BeadStates, &mut out)
            .unwrap()
            .sequence,
        2
    );

    // A late reader of a publisher that does not serve is told so, until the publisher
    // updates its connections.
    let mut late = IpcExchange::new(&prefix, "late").unwrap();
    let err = late.read_states(Port::BeadStates, &mut out).unwrap_err();
    assert!(err.to_string().contains("does not serve"), "{err}");
    a.update_connections();
    assert_eq!(
        late.read_states(Port::BeadStates, &mut out)
            .unwrap()
            .sequence,
        2
    );
    assert_eq!(out, many);

    // A participant reads its own publications too.
    assert_eq!(
        a.read_states(Port::BeadStates, &mut out).unwrap().sequence,
        2
    );

    // Ports and record types are separate services.
    assert!(late
        .read_impulses(Port::BeadStates, &mut Vec::new())
        .is_err());
    drop((a, early, late));
    assert!(ipc::resources_of_run(&prefix).is_empty());
}

/// The coordinator of a pipelined run reads the bead states of step n after the fibre node
/// may already have published those of n + 1: a by-step read gets n's and keeps n + 1's for
/// the next read; a step no longer (or not yet) there is an error, never the wrong data.
#[test]
fn a_by_step_read_gets_its_step_while_a_newer_one_waits() {
    let prefix = ipc::new_run_prefix();
    let mut fibre = IpcExchange::new(&prefix, "fibre").unwrap();
    let mut coordinator = IpcExchange::new(&prefix, "coordinator").unwrap();
    coordinator
        .subscribe(Port::BeadStates, "BeadState")
        .unwrap();
    let at = |x: f64| vec![BeadState::at_rest([x; 3])];
    let mut out = Vec::new();
    fibre.publish_states(Port::BeadStates, 0, &at(0.0)).unwrap();
    let h = coordinator
        .read_states_of_step(Port::BeadStates, 0, &mut out)
        .unwrap();
    assert_eq!((h.step, out.clone()), (0, at(0.0)));
    fibre.publish_states(Port::BeadStates, 1, &at(1.0)).unwrap();
    fibre.publish_states(Port::BeadStates, 2, &at(2.0)).unwrap();
    let h = coordinator
        .read_states_of_step(Port::BeadStates, 1, &mut out)
        .unwrap();
    assert_eq!((h.step, out.clone()), (1, at(1.0)));
    // Step 1 again: still there.
    coordinator
        .read_states_of_step(Port::BeadStates, 1, &mut out)
        .unwrap();
    assert_eq!(out, at(1.0));
    fibre.publish_states(Port::BeadStates, 3, &at(3.0)).unwrap();
    let h = coordinator
        .read_states_of_step(Port::BeadStates, 2, &mut out)
        .unwrap();
    assert_eq!((h.step, out.clone()), (2, at(2.0)));
    // Step 5 is not published yet: the newest (3) is found instead, and said so.
    let e = coordinator
        .read_states_of_step(Port::BeadStates, 5, &mut out)
        .unwrap_err();
    assert_eq!(
        e,
        ExchangeError::NotAtStep {
            port: "bead-states",
            wanted: 5,
            found: 3
        }
    );
    // A plain read gets the latest.
    assert_eq!(
        coordinator
            .read_states(Port::BeadStates, &mut out)
            .unwrap()
            .step,
        3
    );
    // Gone: publications older than the one read last.
    let e = coordinator
        .read_states_of_step(Port::BeadStates, 2, &mut out)
        .unwrap_err();
    assert!(
        matches!(e, ExchangeError::NotAtStep { found: 3, .. }),
        "{e}"
    );
    drop((fibre, coordinator));
    assert!(ipc::resources_of_run(&prefix).is_empty());
}

#[test]
fn node_whose_process_dies_is_reported_with_status_and_stderr() {
    let dir = std::env::temp_dir().join(ipc::new_run_prefix());
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("dying-node");
    std::fs::write(
        &script,
        "#!/bin/sh\necho \"starting with $*\" >&2\necho 'fatal: the scene has no fibre' >&2\nexit 3\n",
    )
    .unwrap();
    std::fs::set_permissions(&script, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();

    let prefix = ipc::new_run_prefix();
    let start = Instant::now();
    let err = NodeClient::spawn(&script, &["--extra".into()], &prefix, "fibre")
        .err()
        .unwrap();
    assert!(
        start.elapsed() < Duration::from_secs(3),
        "took {:?}",
        start.elapsed()
    );
    let LinkError::Died {
        node,
        status,
        stderr_tail,
    } = &err
    else {
        panic!("{err:?}")
    };
    assert_eq!(node, "fibre");
    assert!(status.contains('3'), "{status}");
    assert!(
        stderr_tail.contains(&format!(
            "starting with serve --prefix {prefix} --name fibre --extra"
        )),
        "{stderr_tail}"
    );
    assert!(
        stderr_tail.contains("fatal: the scene has no fibre"),
        "{stderr_tail}"
    );
    let message = err.to_string();
    assert!(
        message.starts_with("node fibre died (exit status: 3)"),
        "{message}"
    );

    let missing = NodeClient::spawn(&dir.join("no-such-node"), &[], &prefix, "fluid")
        .err()
        .unwrap();
    assert!(matches!(missing, LinkError::Spawn { .. }), "{missing:?}");
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(ipc::resources_of_run(&prefix).is_empty());
}

#[test]
fn serve_returns_when_the_coordinator_goes_away() {
    let prefix = ipc::new_run_prefix();
    let thread = serve_thread::<ToyFluid>(&prefix, "fluid");
    let mut fluid = NodeClient::connect(&prefix, "fluid").unwrap();
    assert!(matches!(
        fluid.call(&Command::Describe).unwrap(),
        Reply::Description(_)
    ));
    let start = Instant::now();
    drop(fluid); // no Shutdown
    let err = thread.join().unwrap().unwrap_err();
    assert!(
        start.elapsed() < Duration::from_secs(2),
        "took {:?}",
        start.elapsed()
    );
    assert!(matches!(err, IpcError::CoordinatorGone { .. }), "{err}");
    assert!(ipc::resources_of_run(&prefix).is_empty());
}

#[test]
fn a_late_reply_after_a_timeout_is_not_mistaken_for_the_next_one() {
    let prefix = ipc::new_run_prefix();
    let thread = serve_thread::<ToyFibre>(&prefix, "fibre");
    let mut fibre = NodeClient::connect(&prefix, "fibre").unwrap();
    let configure = Command::Configure {
        scene_toml: "beads = 2\nslow_ms = 300".into(),
    };
    assert!(matches!(
        fibre.call(&configure).unwrap(),
        Reply::Configured(_)
    ));
    fibre.set_timeout(Duration::from_millis(50));
    let err = fibre
        .call(&Command::RunPhase {
            step: 1,
            phase: Phase::FibrePositions,
            detail: Default::default(),
        })
        .unwrap_err();
    assert!(matches!(err, LinkError::Timeout { .. }), "{err:?}");
    assert_eq!(err.to_string(), "node fibre did not answer within 0.05 s");
    fibre.set_timeout(Duration::from_secs(10));
    assert!(matches!(
        fibre.call(&Command::Describe).unwrap(),
        Reply::Description(_)
    ));
    fibre.shutdown().unwrap();
    thread.join().unwrap().unwrap();
    assert!(ipc::resources_of_run(&prefix).is_empty());
}

#[test]
fn run_prefixes_are_unique_and_usable() {
    let a = ipc::new_run_prefix();
    let b = ipc::new_run_prefix();
    assert_ne!(a, b);
    assert!(a.len() < 40, "{a}");
    assert!(IpcExchange::new(&a, "bad/name").is_err());
    // Nothing of this test run is dead, so at most others' leftovers are cleaned.
    let _ = ipc::cleanup_stale_resources();
}

#[test]
fn node_client_can_move_between_threads() {
    fn send<T: Send>() {}
    send::<NodeClient>();
    send::<LinkError>();
}
