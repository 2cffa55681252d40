//! The fibre node as its own process: serves the `cosim` interface over iceoryx2.
//!
//! Usage: `fibre-node serve --prefix PREFIX --name NAME` (started by the coordinator), or
//! `fibre-node describe` to print the model description as JSON.
//!
//! Testing hooks: with `FIBRECOSIM_FAULT=exit-at-step:N` in the environment the node writes a
//! line to stderr and exits with status 3 when asked to run a phase of step N; with
//! `FIBRECOSIM_FAULT=hang-at-step:N` it stops answering there; with
//! `FIBRECOSIM_FAULT=refuse-at-step:N` its `fibre-velocities` of step N fails with an error.
//! They let the coordinator's handling of a dying, unresponsive or failing node be tested.
use cosim::{
    Component, ComponentError, Configured, Exchange, ModelDescription, Phase, PhaseReport,
};
use fibre_node::FibreComponent;
use std::io::Write;
use std::process::ExitCode;

enum Fault {
    Exit,
    Hang,
    Refuse,
}

struct FaultAt {
    inner: FibreComponent,
    fault: Option<(Fault, u64)>,
}

impl Component for FaultAt {
    fn describe(&self) -> ModelDescription {
        self.inner.describe()
    }
    fn configure(
        &mut self,
        scene: &str,
        ex: &mut dyn Exchange,
    ) -> Result<Configured, ComponentError> {
        self.inner.configure(scene, ex)
    }
    fn run_phase(
        &mut self,
        step: u64,
        phase: Phase,
        ex: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        match &self.fault {
            Some((Fault::Exit, at)) if *at == step => {
                let _ = writeln!(
                    std::io::stderr(),
                    "fibre-node: injected fault at step {step}, phase {phase}"
                );
                std::process::exit(3);
            }
            Some((Fault::Hang, at)) if *at == step => loop {
                std::thread::sleep(std::time::Duration::from_secs(3600));
            },
            Some((Fault::Refuse, at)) if *at == step && phase == Phase::FibreVelocities => {
                return Err(ComponentError::new(format!(
                    "fibre-node: injected refusal at step {step}, phase {phase}"
                )));
            }
            _ => {}
        }
        self.inner.run_phase(step, phase, ex)
    }
    fn save_state(&self) -> Result<Vec<u8>, ComponentError> {
        self.inner.save_state()
    }
    fn restore_state(&mut self, state: &[u8]) -> Result<(), ComponentError> {
        self.inner.restore_state(state)
    }
    fn publish_restored(&mut self, ex: &mut dyn Exchange) -> Result<(), ComponentError> {
        self.inner.publish_restored(ex)
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let fault = std::env::var("FIBRECOSIM_FAULT").ok().and_then(|f| {
        let (kind, n) = f.split_once("-at-step:")?;
        let kind = match kind {
            "exit" => Fault::Exit,
            "hang" => Fault::Hang,
            "refuse" => Fault::Refuse,
            _ => return None,
        };
        Some((kind, n.parse().ok()?))
    });
    cosim::ipc::node_main("fibre-node", &args, || FaultAt {
        inner: FibreComponent::new(),
        fault,
    })
}
