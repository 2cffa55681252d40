//! The trait every node implements, and the one function that maps a command onto it.
//! Both transports (iceoryx2 and in-process) call [`dispatch`], so a component behaves the
//! same, bit for bit, whichever way it is linked.
use crate::{Command, Configured, Detail, Exchange, ModelDescription, Phase, PhaseReport, Reply};

/// An error a component reports to the user: one clear sentence, no panic.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ComponentError(pub String);

impl ComponentError {
    pub fn new(msg: impl Into<String>) -> Self {
        Self(msg.into())
    }
}

impl From<crate::exchange::ExchangeError> for ComponentError {
    fn from(e: crate::exchange::ExchangeError) -> Self {
        Self(e.to_string())
    }
}

/// A co-simulation component (a fibre model, a fluid solver).
///
/// Setup allocates; [`Component::run_phase`] should not.
pub trait Component {
    /// The model description (does not depend on the scene).
    fn describe(&self) -> ModelDescription;

    /// Read the scene, build the initial state, check the time step against the component's
    /// own stability limits, and publish the initial bead states through `exchange`.
    fn configure(
        &mut self,
        scene_toml: &str,
        exchange: &mut dyn Exchange,
    ) -> Result<Configured, ComponentError>;

    /// Run one phase of one step, reading inputs from and publishing outputs to `exchange`.
    fn run_phase(
        &mut self,
        step: u64,
        phase: Phase,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError>;

    /// [`Component::run_phase`], reporting with `detail`: a component whose reports include
    /// diagnostics that cost a pass of their own leaves them out of a [`Detail::Brief`]
    /// report. Default: every report in full.
    fn run_phase_with(
        &mut self,
        step: u64,
        phase: Phase,
        detail: Detail,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        let _ = detail;
        self.run_phase(step, phase, exchange)
    }

    /// The full state, serialised, such that `restore_state` brings it back exactly.
    fn save_state(&self) -> Result<Vec<u8>, ComponentError>;

    /// Replace the full state by one from `save_state`.
    fn restore_state(&mut self, state: &[u8]) -> Result<(), ComponentError>;

    /// Write the component's fields (a fluid's velocity, solid fraction, ...) at the end of
    /// `step`, time `time`, as files in the existing directory `dir`; return their names
    /// relative to `dir`. Called between steps, never inside one; it must not change the
    /// state. Default: no fields, no files.
    fn write_fields(
        &mut self,
        _step: u64,
        _time: f64,
        _dir: &std::path::Path,
    ) -> Result<Vec<String>, ComponentError> {
        Ok(Vec::new())
    }

    /// After a successful [`Component::restore_state`] through [`dispatch`]: publish what
    /// the other nodes read from this one at the step the state was saved (the fibre node's
    /// bead states), so that a resumed run starts from the same publications as the run that
    /// saved it. Default: nothing.
    fn publish_restored(&mut self, _exchange: &mut dyn Exchange) -> Result<(), ComponentError> {
        Ok(())
    }

    /// After [`Component::configure`] of every node: check the initial bead states the
    /// fibre node published against this component's part of the scene (a fluid's walls
    /// and box). Asked by `check` only; a run checks the same when it first reads the
    /// beads. Default: nothing to check.
    fn check_start(&mut self, _exchange: &mut dyn Exchange) -> Result<(), ComponentError> {
        Ok(())
    }
}

/// Run one command on a component. Returns the reply and whether the serving loop should end.
pub fn dispatch(
    component: &mut dyn Component,
    exchange: &mut dyn Exchange,
    command: Command,
) -> (Reply, bool) {
    let as_reply = |r: Result<Reply, ComponentError>| r.unwrap_or_else(|e| Reply::Error(e.0));
    match command {
        Command::Describe => (Reply::Description(component.describe()), false),
        Command::Configure { scene_toml } => (
            as_reply(
                component
                    .configure(&scene_toml, exchange)
                    .map(Reply::Configured),
            ),
            false,
        ),
        Command::RunPhase {
            step,
            phase,
            detail,
        } => (
            as_reply(
                component
                    .run_phase_with(step, phase, detail, exchange)
                    .map(Reply::PhaseDone),
            ),
            false,
        ),
        // A batch has to wait for other nodes between its phases, which only a transport
        // shared between processes can do (`ipc::serve`).
        Command::RunPhases { .. } => (
            Reply::Error("a batch of phases (run-phases) is served over iceoryx2 only".into()),
            false,
        ),
        Command::SaveState => (as_reply(component.save_state().map(Reply::State)), false),
        Command::RestoreState { state } => (
            as_reply(
                component
                    .restore_state(&state)
                    .and_then(|()| component.publish_restored(exchange))
                    .map(|()| Reply::Ok),
            ),
            false,
        ),
        Command::WriteFields { step, time, dir } => (
            as_reply(
                component
                    .write_fields(step, time, std::path::Path::new(&dir))
                    .map(Reply::Files),
            ),
            false,
        ),
        Command::CheckStart => (
            as_reply(component.check_start(exchange).map(|()| Reply::Ok)),
            false,
        ),
        Command::Shutdown => (Reply::Ok, true),
    }
}
