//! One run: launch the nodes, check they fit the scene, drive the fractional step, log
//! everything, and write the summary — also when a node fails or the user presses Ctrl-C.
use crate::links::{self, LinkFailure, NodeLink};
use crate::mcap_log::RunLog;
use crate::overlap_watch::{Overlap, OverlapWatch, RunWatches};
use crate::pipeline;
use crate::scene::LoadedScene;
use crate::schedule::{self, Plan};
use cosim::{
    BeadState, Command, Configured, InProcessExchange, ModelDescription, Phase, PhaseReport, Port,
    Reply,
};
use serde_json::json;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Ask the run in progress to stop cleanly at the end of the current step (Ctrl-C).
pub fn request_stop() {
    INTERRUPTED.store(true, Ordering::SeqCst);
}

#[derive(Debug, Clone)]
pub struct RunOptions {
    pub out: PathBuf,
    pub in_process: bool,
    /// Show a progress bar on a terminal.
    pub progress: bool,
    /// Print the effects, schedule and result lines.
    pub verbose: bool,
    /// How long to wait for one reply of a node before ending the run.
    pub node_timeout: std::time::Duration,
    /// Write a checkpoint to `out/checkpoint` every this many steps (and at the last step);
    /// 0: none.
    pub checkpoint_interval: u64,
    /// Continue from the checkpoint in this folder instead of starting at step 0.
    pub resume: Option<PathBuf>,
    /// As processes: run one phase at a time through the coordinator instead of pipelined
    /// batches (see `coordinator/src/pipeline.rs`).
    pub lock_step: bool,
}

impl RunOptions {
    /// Options for a run into `out`, quiet, with the default node timeout.
    pub fn quiet(out: impl Into<PathBuf>, in_process: bool) -> Self {
        Self {
            out: out.into(),
            in_process,
            progress: false,
            verbose: false,
            node_timeout: links::DEFAULT_NODE_TIMEOUT,
            checkpoint_interval: 0,
            resume: None,
            lock_step: false,
        }
    }
}

/// The outcome of a completed (or cleanly ended) run.
#[derive(Debug, Clone)]
pub struct RunResult {
    pub summary: serde_json::Value,
    pub mcap: PathBuf,
}

/// A run that failed; the MCAP log and summary written so far are still in `out`.
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct RunError {
    pub message: String,
}

pub(crate) fn fail(message: impl Into<String>) -> RunError {
    RunError {
        message: message.into(),
    }
}

/// Describe every component this build has (optionally as separate processes).
pub fn describe_all(in_process: bool) -> Result<Vec<ModelDescription>, RunError> {
    let ex = InProcessExchange::new();
    let prefix = cosim::ipc::new_run_prefix();
    let mut out = Vec::new();
    for info in links::all_components() {
        let mut link = links::start(
            &info,
            in_process.then_some(&ex),
            &prefix,
            links::DEFAULT_NODE_TIMEOUT,
        )
        .map_err(|e| fail(e.to_string()))?;
        let reply = link
            .call(&Command::Describe)
            .map_err(|e| fail(e.to_string()))?;
        let _ = link.shutdown();
        match reply {
            Reply::Description(d) => out.push(d),
            other => {
                return Err(fail(format!(
                    "{}: unexpected reply to describe: {other:?}",
                    info.name
                )))
            }
        }
    }
    Ok(out)
}

/// Check a scene fits the components: models, coupling scheme, phases, and each node's own
/// reading of its tables and time-step limits. Runs nothing.
pub fn check(scene: &LoadedScene) -> Result<(Plan, Configured, Vec<ModelDescription>), RunError> {
    let plan = schedule::plan(scene).map_err(fail)?;
    let ex = InProcessExchange::new();
    let mut nodes = start_nodes(&plan, Some(&ex), "check", links::DEFAULT_NODE_TIMEOUT)?;
    let configured = describe_and_configure(scene, &plan, &mut nodes)?;
    // The beads' start against the fluid's walls and box (a run checks it at step 0).
    for n in nodes.iter_mut() {
        n.link
            .call(&Command::CheckStart)
            .map_err(|e| fail(format!("the scene was refused: {e}")))?;
    }
    let descriptions = nodes.iter().map(|n| n.description.clone()).collect();
    Ok((plan, configured, descriptions))
}

/// One node of the run: its link and what it said it is.
pub(crate) struct Node {
    pub(crate) link: Box<dyn NodeLink>,
    pub(crate) description: ModelDescription,
}

/// Start the nodes the plan needs (fibre before fluid: the fibre node publishes the initial
/// bead states the fluid node may read when configured).
fn start_nodes(
    plan: &Plan,
    in_process: Option<&InProcessExchange>,
    prefix: &str,
    timeout: std::time::Duration,
) -> Result<Vec<Node>, RunError> {
    let mut nodes = Vec::new();
    for info in links::components_for(&plan.nodes) {
        let mut link =
            links::start(&info, in_process, prefix, timeout).map_err(|e| fail(e.to_string()))?;
        let description = describe(link.as_mut())?;
        nodes.push(Node { link, description });
    }
    Ok(nodes)
}

/// The model-description check, then `configure` on every node; their answers merged.
fn describe_and_configure(
    scene: &LoadedScene,
    plan: &Plan,
    nodes: &mut [Node],
) -> Result<Configured, RunError> {
    for effect in &plan.requested {
        if !nodes.iter().any(|n| n.description.effects.contains(effect)) {
            let have: Vec<String> = nodes
                .iter()
                .map(|n| {
                    format!(
                        "{}: {}",
                        n.description.name,
                        n.description.effects.join(", ")
                    )
                })
                .collect();
            return Err(fail(format!(
                "the scene asks for the effect `{effect}` but no component provides it ({})",
                have.join("; ")
            )));
        }
    }
    let mut all = Configured {
        notes: scene.groups.notes.clone(),
        ..Configured::default()
    };
    for n in nodes.iter_mut() {
        check_fit(scene, plan, &n.description)?;
        let c = configure(n.link.as_mut(), scene)?;
        if n.description.kind == "fibre" {
            all.beads_per_fibre = c.beads_per_fibre;
        }
        for e in c.effects {
            if !all.effects.contains(&e) {
                all.effects.push(e);
            }
        }
        all.time_step_limits.extend(c.time_step_limits);
        all.derived.extend(c.derived);
        all.notes.extend(c.notes);
    }
    Ok(all)
}

fn shutdown_all(nodes: Vec<Node>) -> Result<(), LinkFailure> {
    let mut first_error = Ok(());
    for n in nodes {
        let r = n.link.shutdown();
        if first_error.is_ok() {
            first_error = r;
        }
    }
    first_error
}

fn describe(link: &mut dyn NodeLink) -> Result<ModelDescription, RunError> {
    match link
        .call(&Command::Describe)
        .map_err(|e| fail(e.to_string()))?
    {
        Reply::Description(d) => Ok(d),
        other => Err(fail(format!(
            "{}: unexpected reply to describe: {other:?}",
            link.name()
        ))),
    }
}

fn configure(link: &mut dyn NodeLink, scene: &LoadedScene) -> Result<Configured, RunError> {
    match link
        .call(&Command::Configure {
            scene_toml: scene.toml.clone(),
        })
        .map_err(|e| fail(format!("the scene was refused: {e}")))?
    {
        Reply::Configured(c) => Ok(c),
        other => Err(fail(format!(
            "{}: unexpected reply to configure: {other:?}",
            link.name()
        ))),
    }
}

/// The model-description check done before step 0 (the FMI-style compatibility check).
pub fn check_fit(scene: &LoadedScene, plan: &Plan, d: &ModelDescription) -> Result<(), RunError> {
    let fibres = if d.kind == "fibre" {
        scene.scene.fibre.as_slice()
    } else {
        &[]
    };
    for (i, f) in fibres.iter().enumerate() {
        let model = f.get("model").and_then(|m| m.as_str()).unwrap_or("");
        if !model.is_empty() && !d.models.iter().any(|m| m == model) {
            return Err(fail(format!(
                "key `fibre.{i}.model`: `{model}` is not a model of {}{} (it has: {})",
                d.name,
                cosim::scene_keys::did_you_mean(model, d.models.iter().map(String::as_str)),
                d.models.join(", ")
            )));
        }
    }
    if !d.coupling_schemes.contains(&plan.coupling) {
        return Err(fail(format!(
            "{} does not support the coupling scheme `{}` (it supports: {})",
            d.name,
            plan.coupling,
            d.coupling_schemes.join(", ")
        )));
    }
    for p in plan.schedule.iter().filter(|p| p.node() == d.kind) {
        if !d.phases.contains(p) {
            return Err(fail(format!(
                "{} does not serve the phase `{p}` the schedule needs",
                d.name
            )));
        }
    }
    Ok(())
}

/// Remove the files an earlier run derived from its log in `dir` (its orbit, its exported
/// tables and scene): the new run rewrites the log, and they would pass for the new run's.
/// `keep`, the scene file being run (an exported `scene.toml` run again into its own
/// folder), stays.
fn remove_stale_outputs(dir: &Path, keep: Option<&Path>) {
    let kept = keep.and_then(|k| k.canonicalize().ok());
    for f in crate::orbit_report::FILES
        .iter()
        .chain(&crate::export::FILES)
    {
        let path = dir.join(f);
        if kept.is_none() || path.canonicalize().ok() != kept {
            let _ = std::fs::remove_file(path);
        }
    }
}

fn writable_dir(out: &Path) -> Result<(), RunError> {
    std::fs::create_dir_all(out).map_err(|e| {
        fail(format!(
            "--out {}: cannot create the output directory: {e}",
            out.display()
        ))
    })?;
    let probe = out.join(".write-test");
    std::fs::write(&probe, b"").map_err(|e| {
        fail(format!(
            "--out {}: the output directory is not writable: {e}",
            out.display()
        ))
    })?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

fn radii(scene: &LoadedScene) -> Vec<f64> {
    scene
        .scene
        .fibre
        .iter()
        .map(|f| match f.get("bead_radius") {
            Some(toml::Value::Float(r)) => *r,
            Some(toml::Value::Integer(r)) => *r as f64,
            _ => 1.0,
        })
        .collect()
}

/// The summary's warnings about beads inside a wall (scenes with walls), inside each other
/// and inside another fibre's (scenes with two fibres or more; `overlap_watch.rs`).
fn overlap_warnings(scene: &LoadedScene, watches: &RunWatches) -> Vec<String> {
    let radius = radii(scene).into_iter().fold(f64::INFINITY, f64::min);
    let without = |what: Overlap| -> Vec<usize> {
        let on = toml::Value::Boolean(true);
        (0..scene.scene.fibre.len())
            .filter(|&n| scene.scene.fibre[n].get(what.contact_key()) != Some(&on))
            .collect()
    };
    let mut out = Vec::new();
    if scene.scene.walls.is_some() {
        out.extend(
            watches
                .wall_watch
                .warning(Overlap::Wall, radius, &without(Overlap::Wall)),
        );
    }
    let what = Overlap::SelfOverlap;
    out.extend(watches.self_watch.warning(what, radius, &without(what)));
    if scene.scene.fibre.len() > 1 {
        let what = Overlap::FibreOverlap;
        out.extend(watches.fibre_watch.warning(what, radius, &without(what)));
    }
    out
}

/// Largest applied load magnitude over all fibres (scale for the rest criterion).
fn largest_load(scene: &LoadedScene) -> f64 {
    let mut m: f64 = 0.0;
    for f in &scene.scene.fibre {
        if let Some(toml::Value::Array(loads)) = f.get("loads") {
            for l in loads.iter().filter_map(|l| l.as_table()) {
                if let Some(toml::Value::Array(v)) = l.get("force") {
                    let s: f64 = v
                        .iter()
                        .filter_map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)))
                        .map(|x| x * x)
                        .sum();
                    m = m.max(s.sqrt());
                }
            }
        }
    }
    m
}

/// Run a scene to the end, writing `out/run.mcap` and `out/summary.json`.
pub fn run(scene: &LoadedScene, opts: &RunOptions) -> Result<RunResult, RunError> {
    // Drive the run from a thread of rayon's pool: with the components linked in, every
    // parallel loop of the fluid's step then starts on a worker instead of handing its work
    // to the pool and sleeping until it is done (two context switches per loop, about a
    // hundred per 2D step). The fluid-node process does the same (src/bin/fluid-node.rs).
    rayon::scope(|_| run_on_this_thread(scene, opts))
}

fn run_on_this_thread(scene: &LoadedScene, opts: &RunOptions) -> Result<RunResult, RunError> {
    INTERRUPTED.store(false, Ordering::SeqCst);
    let created = !opts.out.exists();
    writable_dir(&opts.out)?;
    // A scene refused before the run starts leaves no folder the run made.
    let refused = |e: RunError| {
        if created {
            let _ = std::fs::remove_dir(&opts.out);
        }
        e
    };
    let plan = schedule::plan(scene).map_err(fail).map_err(refused)?;
    // A checkpoint that does not fit the scene is refused before anything changes.
    let checkpoint = match &opts.resume {
        Some(dir) => Some(check_resume(scene, dir, scene.scene.time.steps).map_err(refused)?),
        None => None,
    };
    let started = Instant::now();

    let ex = InProcessExchange::new();
    let in_process = opts.in_process.then_some(&ex);
    if !opts.in_process {
        cosim::ipc::cleanup_stale_resources();
    }
    let prefix = cosim::ipc::new_run_prefix();
    let mut nodes = start_nodes(&plan, in_process, &prefix, opts.node_timeout).map_err(refused)?;
    let configured = match describe_and_configure(scene, &plan, &mut nodes) {
        Ok(c) => c,
        Err(e) => {
            let _ = shutdown_all(nodes);
            return Err(refused(e));
        }
    };

    // The nodes accept the scene: only now does the run replace what an earlier run left in
    // --out (a refused scene leaves it as it was). A resumed run's log starts with the
    // earlier log's steps up to the checkpoint, read before run.mcap is replaced.
    let mcap_path = opts.out.join("run.mcap");
    let earlier = match (&opts.resume, &checkpoint) {
        (Some(dir), Some(ck)) => earlier_log(dir, ck.time),
        _ => None,
    };
    remove_stale_outputs(&opts.out, scene.path.as_deref());
    let mut log = match RunLog::create(&mcap_path) {
        Ok(log) => log,
        Err(e) => {
            let _ = shutdown_all(nodes);
            return Err(fail(e));
        }
    };

    let mut state = RunState {
        started: Some(started),
        wall_before: Some(0.0),
        configured,
        ..RunState::default()
    };
    let outcome = drive(
        scene,
        opts,
        &plan,
        (&mut nodes, checkpoint, earlier.as_deref()),
        in_process,
        &prefix,
        &mut log,
        &mut state,
    );
    let shutdown = shutdown_all(nodes);

    let wall = started.elapsed().as_secs_f64();
    let (status, error) = match (&outcome, &shutdown) {
        (Err(e), _) => ("failed", Some(e.message.clone())),
        (Ok(s), Err(e)) => (*s, Some(format!("shutting down the nodes: {e}"))),
        (Ok(s), Ok(())) => (*s, None),
    };
    let summary = state.summary(scene, &plan, opts, status, error.as_deref(), wall);
    let write_summary = std::fs::write(
        opts.out.join("summary.json"),
        serde_json::to_string_pretty(&summary).unwrap(),
    );
    log.finish(&summary).map_err(fail)?;
    write_summary.map_err(|e| {
        fail(format!(
            "cannot write {}: {e}",
            opts.out.join("summary.json").display()
        ))
    })?;
    if let Some(e) = error {
        return Err(fail(format!(
            "{e}\n(the log written so far is in {})",
            opts.out.display()
        )));
    }
    Ok(RunResult {
        summary,
        mcap: mcap_path,
    })
}

/// What the run has learned so far; enough to write a summary at any point.
#[derive(Default)]
struct RunState {
    configured: Configured,
    effects: Vec<String>,
    steps_done: u64,
    time: f64,
    /// Seconds per phase: as the coordinator saw them (lock-step), or inside the nodes from
    /// the arrival of a phase's input to its end (pipelined).
    seconds_per_phase: BTreeMap<String, f64>,
    /// Whether the steps after the first were pipelined (see `pipeline.rs`).
    pipelined: bool,
    /// Pipelined runs: seconds each phase waited inside its node for the other node's input.
    seconds_waiting: BTreeMap<String, f64>,
    /// Pipelined runs: the most steps sent to the nodes as one batch.
    largest_batch: u64,
    last_diagnostics: Vec<(String, f64)>,
    /// The largest `wall_overlap`, `self_overlap` and `fibre_overlap` the fibre node reported,
    /// over every step.
    watches: RunWatches,
    metrics: BTreeMap<String, crate::metrics::Metric>,
    /// Metrics asked for that could not be computed, with the reason.
    metric_errors: BTreeMap<String, String>,
    /// Steady metrics read while the flow still changed ([`crate::steady_watch`]).
    steady_warnings: Vec<String>,
    /// Files written next to the log and the summary (`orbit.csv`, `orbit.png`).
    files: Vec<String>,
    /// Files that could not be written, with the reason; the run still completes.
    file_errors: BTreeMap<String, String>,
    dimensionless: BTreeMap<String, f64>,
    /// When this piece of the run started.
    started: Option<Instant>,
    /// Wall seconds of the pieces before this one (0 for a run from step 0; None when resumed
    /// from a checkpoint that did not record them).
    wall_before: Option<f64>,
    /// The checkpoint's step, for a resumed run.
    resumed_from: Option<u64>,
}

impl RunState {
    /// Wall seconds from step 0 to now over every piece of the run, if known.
    fn wall_since_step_0(&self) -> Option<f64> {
        let now = self.started.map(|t| t.elapsed().as_secs_f64())?;
        self.wall_before.map(|b| b + now)
    }

    fn summary(
        &self,
        scene: &LoadedScene,
        plan: &Plan,
        opts: &RunOptions,
        status: &str,
        error: Option<&str>,
        wall: f64,
    ) -> serde_json::Value {
        let diagnostics: serde_json::Map<String, serde_json::Value> = self
            .last_diagnostics
            .iter()
            .map(|(k, v)| (k.clone(), json!(v)))
            .collect();
        let limits: serde_json::Map<String, serde_json::Value> = self
            .configured
            .time_step_limits
            .iter()
            .map(|(k, v)| (k.clone(), json!(v)))
            .collect();
        let derived: serde_json::Map<String, serde_json::Value> = self
            .configured
            .derived
            .iter()
            .map(|(k, v)| (k.clone(), json!(v)))
            .collect();
        // How far a bead reached into a wall (scenes with walls and fibres), into another bead
        // of its fibre (scenes with fibres) and into a bead of another fibre (two fibres or
        // more; `overlap_watch.rs`).
        let has_fibres = !scene.scene.fibre.is_empty();
        let largest = |w: &OverlapWatch| json!({ "value": w.largest, "step": w.step });
        let largest_wall_overlap =
            (scene.scene.walls.is_some() && has_fibres).then(|| largest(&self.watches.wall_watch));
        let largest_self_overlap = has_fibres.then(|| largest(&self.watches.self_watch));
        let largest_fibre_overlap =
            (scene.scene.fibre.len() > 1).then(|| largest(&self.watches.fibre_watch));
        let mut warnings = overlap_warnings(scene, &self.watches);
        warnings.extend(self.steady_warnings.iter().cloned());
        // A scene that runs to rest but ran out of steps first: its static metrics are of
        // a fibre still moving.
        if let (Some(tol), "completed") = (scene.scene.time.rest_tolerance, status) {
            warnings.push(format!(
                "the run reached time.steps = {} before coming to rest (time.rest_tolerance = \
                 {}): the fibres were still moving, and metrics of a state at rest describe \
                 the last step instead; raise time.steps",
                scene.scene.time.steps,
                cosim::scene_keys::Num(tol)
            ));
        }
        json!({
            "scene": scene.name(),
            "scene_file": scene.path.as_ref().map(|p| p.display().to_string()),
            "status": status,
            "error": error,
            "effects": self.effects,
            "schedule": plan.schedule.iter().map(|p| p.name()).collect::<Vec<_>>(),
            "process_layout": if opts.in_process { "in-process" } else { "processes" },
            "pipelined": self.pipelined,
            "seconds_waiting_for_input": self.seconds_waiting,
            "largest_batch_steps": self.largest_batch,
            "steps": self.steps_done,
            "steps_requested": scene.scene.time.steps,
            "dt": scene.scene.time.dt,
            "time": self.time,
            "wall_seconds": wall,
            "wall_seconds_since_step_0": self.wall_before.map(|b| b + wall),
            "resumed_from_step": self.resumed_from,
            "seconds_per_phase": self.seconds_per_phase,
            "beads_per_fibre": self.configured.beads_per_fibre,
            "time_step_limits": limits,
            "derived": derived,
            "groups": scene.groups.lines,
            "notes": self.configured.notes,
            "dimensionless": self.dimensionless,
            "final_diagnostics": diagnostics,
            "largest_wall_overlap": largest_wall_overlap,
            "largest_self_overlap": largest_self_overlap,
            "largest_fibre_overlap": largest_fibre_overlap,
            "warnings": warnings,
            "metrics": self.metrics,
            "metric_errors": self.metric_errors,
            "files": self.files,
            "file_errors": self.file_errors,
        })
    }
}

#[allow(clippy::too_many_arguments)]
fn drive(
    scene: &LoadedScene,
    opts: &RunOptions,
    plan: &Plan,
    (nodes, checkpoint, earlier): (
        &mut [Node],
        Option<crate::checkpoint::RunCheckpoint>,
        Option<&[crate::mcap_log::LoggedMessage]>,
    ),
    in_process: Option<&InProcessExchange>,
    prefix: &str,
    log: &mut RunLog,
    st: &mut RunState,
) -> Result<&'static str, RunError> {
    let owner = phase_owners(plan, nodes)?;
    st.effects = plan.effects(&st.configured.effects);
    let schedule_names: Vec<String> = plan.schedule.iter().map(|p| p.name().to_string()).collect();
    if opts.verbose {
        announce(scene, opts, &schedule_names, prefix, st);
    }
    log.scene(&scene.toml, &st.effects, &schedule_names)
        .map_err(fail)?;
    if let Some(messages) = earlier {
        log.copy_earlier(messages).map_err(fail)?;
    }

    let mut exchange =
        links::coordinator_exchange(in_process, prefix).map_err(|e| fail(e.to_string()))?;
    let radii = radii(scene);
    let beads = st.configured.beads_per_fibre.clone();
    let has_beads = !beads.is_empty();
    let track = has_beads
        && scene
            .scene
            .analysis
            .metrics
            .iter()
            .any(|m| crate::metrics::needs_trajectory(m));
    let dt = scene.scene.time.dt;
    let steps = scene.scene.time.steps;
    let Start {
        first_step,
        mut states,
        initial,
        mut trajectory,
        resumed,
    } = start(
        checkpoint,
        opts,
        nodes,
        (&mut *exchange, log),
        (&beads, &radii, track),
        st,
    )?;
    let shape_every = (steps / crate::trajectory::SHAPE_SNAPSHOTS).max(1);
    // A checkpoint from before the steady history was kept starts it at the resume.
    if trajectory.steady.samples.is_empty() {
        trajectory.steady =
            crate::steady_watch::SteadyHistory::for_metrics(&scene.scene.analysis.metrics);
    }
    trajectory
        .steady
        .set_geometry(crate::interface_metrics::InterfaceGeometry::of(
            &scene.scene,
            &st.configured.derived,
        ));

    let interval = scene.output_interval();
    let load_scale = largest_load(scene);
    let bar = progress_bar(opts.progress, steps);
    bar.set_position(first_step);
    let mut status = "completed";
    // Pipelined batches need nodes that can wait for each other's publications (processes)
    // and a fluid that already holds the bead states of the step: from the second step on.
    // A node alone (a fluid without fibres, a fibre without fluid) waits for nothing; its
    // batches save it a request and a reply per phase.
    let mut batching = (!opts.in_process && !opts.lock_step).then(|| {
        let names: Vec<String> = nodes.iter().map(|n| n.link.name().to_string()).collect();
        Batching::new(pipeline::Batches::new(&plan.schedule, &owner, &names))
    });
    st.pipelined = batching.is_some();
    let every = opts.checkpoint_interval;
    // FPD walls bounce back at the lattice's ends; SPM walls are slabs in a periodic box.
    let periodic_y = plan.coupling != "fpd" || scene.scene.walls.is_none();
    let mut snapshots =
        crate::field_snapshots::Snapshots::new(&opts.out, scene.fields_interval(), periodic_y);
    let fields_every = snapshots.as_ref().map_or(0, |s| s.every());
    if let Some(snap) = snapshots.as_mut() {
        if resumed {
            snap.keep_earlier(st.time);
        } else {
            snap.write((first_step, st.time), nodes, (&beads, &radii), &states, log)?;
        }
    }
    let rests = scene.scene.time.rest_tolerance.is_some();
    // Diagnostics that cost a pass of their own (the fluid's divergence, a droplet's radius
    // and pressure) are asked for only where the log or the run's end needs them: at the
    // logged steps and the last, and at every step of a run that may stop at rest or was
    // interrupted. A run stops only after a step reported in full.
    let full_reports = |interrupted: bool| cosim::FullReports {
        every: if rests || interrupted { 1 } else { interval },
        last: steps.checked_sub(1),
    };
    let cadence = Cadence {
        steps,
        interval,
        checkpoint_every: every,
        fields_every,
        rests,
    };
    // Nothing feeds the fibres energy: a growth of it is an instability (energy_watch.rs).
    let closed = crate::energy_watch::applies(&st.effects);
    for step in first_step..steps {
        let full = full_reports(INTERRUPTED.load(Ordering::SeqCst));
        // The steps after the first go in batches where the run is pipelined.
        let (reports, next_sent) = match &mut batching {
            Some(b) if step > first_step || b.has_ahead() => {
                b.reports_of_step(step, cadence, full, nodes, st, opts.node_timeout, dt)?
            }
            _ => {
                let reports = run_step_lock_step(
                    (step, full.detail(step)),
                    &plan.schedule,
                    &owner,
                    nodes,
                    &mut st.seconds_per_phase,
                )?;
                (reports, false)
            }
        };
        let in_full = reports.iter().all(|r| r.detail == cosim::Detail::Full);
        let report = merge_reports(reports);
        st.steps_done = step + 1;
        st.time = (step + 1) as f64 * dt;
        let blowup = if let Some((k, v)) = report.iter().find(|(_, v)| !v.is_finite()) {
            Some(format!("{k} = {v}; where the flow or the fibres diverged,"))
        } else if closed {
            st.watches
                .energy_watch
                .observe(step + 1, &report)
                .map(|b| format!("{};", b.describe()))
        } else {
            None
        };
        if let Some(cause) = blowup {
            log.diagnostics(step + 1, st.time, &report).map_err(fail)?;
            let limits: Vec<String> = st
                .configured
                .time_step_limits
                .iter()
                .map(|(name, dt)| format!("{name} {}", cosim::scene_keys::Sig(*dt)))
                .collect();
            return Err(fail(format!(
                "the run became unstable at step {}: {cause} lower time.dt = {} (its limits: {})",
                step + 1,
                cosim::scene_keys::Sig(dt),
                if limits.is_empty() {
                    "none known".to_string()
                } else {
                    limits.join(", ")
                }
            )));
        }
        st.watches.observe(step + 1, &report);
        st.last_diagnostics = report;
        let at_rest = scene
            .scene
            .time
            .rest_tolerance
            .is_some_and(|tol| is_at_rest(&st.last_diagnostics, tol, load_scale));
        // With the next step's batch out, Ctrl-C ends the run after that step; after a brief
        // report, after the next, which reports in full.
        let stop = INTERRUPTED.load(Ordering::SeqCst) && !next_sent && in_full;
        let last = step + 1 == steps || at_rest || stop;
        let log_due = (step + 1) % interval == 0 || last;
        let sample = (step + 1, steps, log_due);
        let snapshot_due = snapshots.as_ref().is_some_and(|s| s.due(step + 1, last));
        let states_due = has_beads
            && (track || log_due || snapshot_due || trajectory.steady.reads_beads_at(sample));
        // By step: with the next batches out, the fibre node may have published step n + 2's.
        if states_due {
            exchange
                .read_states_of_step(Port::BeadStates, step + 1, &mut states)
                .map_err(|e| fail(format!("reading bead states at step {}: {e}", step + 1)))?;
        }
        if track {
            trajectory.push(st.time, &states, beads[0]);
            if (step + 1) % shape_every == 0 {
                trajectory.push_shape(st.time, &states, beads[0]);
            }
        }
        let fibre0 = if states_due {
            fibre_zero(&states, &beads)
        } else {
            &[]
        };
        trajectory
            .steady
            .observe(sample, st.time, &st.last_diagnostics, fibre0);
        if log_due {
            let logged_states = has_beads.then_some((&beads[..], &radii[..], &states[..]));
            log_step(log, step + 1, logged_states, st)?;
        }
        if let (Some(snap), true) = (snapshots.as_mut(), snapshot_due) {
            snap.write((step + 1, st.time), nodes, (&beads, &radii), &states, log)?;
        }
        bar.inc(1);
        if every > 0 && ((step + 1) % every == 0 || step + 1 == steps || stop) {
            let run = crate::checkpoint::RunCheckpoint::new(
                step + 1,
                st.time,
                &scene.toml,
                &initial,
                &trajectory,
                st.wall_since_step_0(),
                st.watches,
            );
            save_checkpoint(&opts.out.join("checkpoint"), run, nodes)?;
        }
        if stop {
            status = "interrupted";
            break;
        }
        if at_rest {
            status = "at-rest";
            break;
        }
    }
    bar.finish_and_clear();
    if let Some(snap) = &snapshots {
        st.files.extend(snap.files());
        if let Some(e) = &snap.picture_error {
            st.file_errors.insert("fields png".into(), e.clone());
        }
    }
    let end = RunEnd {
        initial: &initial,
        trajectory: &trajectory,
        track,
        beads: &beads,
    };
    conclude(scene, opts, plan, &mut *exchange, end, st)?;
    Ok(status)
}

/// Where a run starts: step 0, or a checkpoint's step.
struct Start {
    first_step: u64,
    /// The bead states at `first_step`, as read from the fibre node and logged.
    states: Vec<BeadState>,
    /// The bead states at step 0, which the metrics compare with.
    initial: Vec<BeadState>,
    trajectory: crate::trajectory::Trajectory,
    resumed: bool,
}

/// Read the first bead states and log them; a resumed run takes its step, time, trajectory
/// and overlap watches from the checkpoint (`--resume`), a fresh one starts its trajectory.
fn start(
    checkpoint: Option<crate::checkpoint::RunCheckpoint>,
    opts: &RunOptions,
    nodes: &mut [Node],
    (exchange, log): (&mut dyn cosim::Exchange, &mut RunLog),
    (beads, radii, track): (&[usize], &[f64], bool),
    st: &mut RunState,
) -> Result<Start, RunError> {
    let mut states: Vec<BeadState> = Vec::new();
    let mut trajectory = crate::trajectory::Trajectory::default();
    let resumed = match (&opts.resume, checkpoint) {
        (Some(dir), Some(ck)) => Some(restore(dir, ck, nodes)?),
        _ => None,
    };
    let first_step = resumed.as_ref().map_or(0, |ck| ck.step);
    if let Some(ck) = &resumed {
        st.time = ck.time;
        st.steps_done = ck.step;
        st.wall_before = ck.wall_seconds;
        st.resumed_from = Some(ck.step);
        trajectory = ck.trajectory.clone();
        st.watches = ck.watches;
    }
    if !beads.is_empty() {
        exchange
            .read_states(Port::BeadStates, &mut states)
            .map_err(|e| fail(format!("reading the initial bead states: {e}")))?;
        log.bead_states(first_step, st.time, beads, radii, &states)
            .map_err(fail)?;
    }
    // The metrics compare with step 0, which a resumed run has from its checkpoint.
    let initial = match &resumed {
        Some(ck) => ck.initial_states(),
        None => states.clone(),
    };
    if track && resumed.is_none() {
        trajectory.push(0.0, &states, beads[0]);
        trajectory.push_shape(0.0, &states, beads[0]);
    }
    Ok(Start {
        first_step,
        states,
        initial,
        trajectory,
        resumed: resumed.is_some(),
    })
}

/// Which node runs each phase of the schedule (an index into `nodes`).
fn phase_owners(plan: &Plan, nodes: &[Node]) -> Result<Vec<usize>, RunError> {
    plan.schedule
        .iter()
        .map(|p| {
            nodes
                .iter()
                .position(|n| n.description.kind == p.node())
                .ok_or_else(|| fail(format!("no node of kind `{}` runs the phase {p}", p.node())))
        })
        .collect()
}

/// Log step `step`: the bead states where the run has beads (`(beads per fibre, radii,
/// states)`), the diagnostics and the seconds per phase so far; then flush, so that a run
/// cut short keeps what it logged.
fn log_step(
    log: &mut RunLog,
    step: u64,
    beads: Option<(&[usize], &[f64], &[BeadState])>,
    st: &RunState,
) -> Result<(), RunError> {
    if let Some((beads, radii, states)) = beads {
        log.bead_states(step, st.time, beads, radii, states)
            .map_err(fail)?;
    }
    log.diagnostics(step, st.time, &st.last_diagnostics)
        .map_err(fail)?;
    log.timings(step, st.time, &st.seconds_per_phase)
        .map_err(fail)?;
    log.flush().map_err(fail)
}

/// Print what the run is about to do: scene, effects, schedule, layout, snapshots, the
/// scene's dimensionless groups and the nodes' notes.
fn announce(
    scene: &LoadedScene,
    opts: &RunOptions,
    schedule_names: &[String],
    prefix: &str,
    st: &RunState,
) {
    eprintln!("scene:    {}", scene.name());
    eprintln!("effects:  {}", st.effects.join(", "));
    eprintln!("schedule: {}", schedule_names.join(" -> "));
    eprintln!(
        "layout:   {}",
        if opts.in_process {
            "in-process".to_string()
        } else {
            format!("processes (run prefix {prefix})")
        }
    );
    if let Some(f) = scene.fields_summary() {
        eprintln!("fields:   {f}");
    }
    for g in &scene.groups.lines {
        eprintln!("group:    {g}");
    }
    for n in &st.configured.notes {
        eprintln!("note:     {n}");
    }
}

/// One step's diagnostics from its phases' reports, one value per name in the order the
/// names first appear: a later phase's report replaces an earlier one's.
fn merge_reports(reports: Vec<PhaseReport>) -> Vec<(String, f64)> {
    let mut report: Vec<(String, f64)> = Vec::new();
    for r in reports {
        for (k, v) in r.diagnostics {
            match report.iter_mut().find(|(name, _)| *name == k) {
                Some(slot) => slot.1 = v,
                None => report.push((k, v)),
            }
        }
    }
    report
}

/// What the end of the run's loop hands to [`conclude`].
struct RunEnd<'a> {
    /// The bead states of step 0 (from the checkpoint in a resumed run).
    initial: &'a [BeadState],
    /// Fibre 0's trajectory, followed where a metric needs it (`track`).
    trajectory: &'a crate::trajectory::Trajectory,
    track: bool,
    beads: &'a [usize],
}

/// Fibre 0's states among `states` (fibres in order, `beads` each); empty without fibres.
fn fibre_zero<'a>(states: &'a [cosim::BeadState], beads: &[usize]) -> &'a [cosim::BeadState] {
    &states[..beads.first().map_or(0, |&n| n.min(states.len()))]
}

/// After the last step: the final bead states (and SPM impulses), the metrics, and the orbit
/// files where a metric followed the trajectory in a wall shear.
fn conclude(
    scene: &LoadedScene,
    opts: &RunOptions,
    plan: &Plan,
    exchange: &mut dyn cosim::Exchange,
    end: RunEnd,
    st: &mut RunState,
) -> Result<(), RunError> {
    let RunEnd {
        initial,
        trajectory,
        track,
        beads,
    } = end;
    let has_beads = !beads.is_empty();
    let mut states = Vec::new();
    if has_beads {
        exchange
            .read_states(Port::BeadStates, &mut states)
            .map_err(|e| fail(format!("reading the final bead states: {e}")))?;
    }
    let mut impulses = Vec::new();
    // Impulses exist under SPM only (FPD exchanges forces and velocities).
    if plan.coupling == "spm" && has_beads {
        exchange
            .read_impulses(Port::BeadImpulses, &mut impulses)
            .map_err(|e| fail(format!("reading the final impulses: {e}")))?;
    }
    let steady =
        trajectory
            .steady
            .changes(st.time, &st.last_diagnostics, fibre_zero(&states, beads));
    let ctx = crate::metrics::Context {
        scene: &scene.scene,
        beads_per_fibre: beads,
        derived: &st.configured.derived,
        initial,
        last: &states,
        diagnostics: &st.last_diagnostics,
        impulses: &impulses,
        trajectory,
        steady: &steady,
    };
    (st.metrics, st.metric_errors) =
        crate::metrics::compute_each(&scene.scene.analysis.metrics, &ctx, &mut st.dimensionless);
    st.steady_warnings = crate::steady_watch::STEADY_METRICS
        .iter()
        .filter(|m| st.metrics.contains_key(**m))
        .filter_map(|m| steady.get(*m)?.warning(m))
        .collect();
    // The orbit the metrics rest on, as files: needs the trajectory and a wall shear.
    let gamma = crate::metrics::lookup(&st.configured.derived, "fluid.shear_rate").map(f64::abs);
    if let (true, Some(gamma)) = (track, gamma) {
        let series = trajectory.orientation_series();
        let reference = st
            .metrics
            .get("effective_aspect_ratio")
            .and_then(|m| m.reference.map(|r| (r, m.reference_source.as_str())));
        let title = scene.name();
        let shapes = &trajectory.shapes;
        match crate::orbit_report::write(
            &opts.out, &series, shapes, beads[0], gamma, &title, reference,
        ) {
            Ok(files) => st.files.extend(files),
            Err(e) => {
                st.file_errors.insert("orbit".into(), e);
            }
        }
    }
    Ok(())
}

/// When the coordinator needs the nodes between two steps: the run's length, its output,
/// checkpoint and snapshot intervals (0: none), and whether it may stop at rest.
#[derive(Clone, Copy)]
struct Cadence {
    steps: u64,
    interval: u64,
    checkpoint_every: u64,
    fields_every: u64,
    rests: bool,
}

impl Cadence {
    /// Whether the batch after the one ending at `step` may go out before the coordinator
    /// has seen `step` (pipeline.rs): only if nothing can end the run or save it between the
    /// two, that is not before the last step, a checkpoint, a snapshot, a possible stop at
    /// rest, or after Ctrl-C.
    fn may_send_next(&self, step: u64) -> bool {
        let at = |every: u64| every != 0 && (step + 1).is_multiple_of(every);
        step + 1 < self.steps
            && !self.rests
            && !at(self.checkpoint_every)
            && !at(self.fields_every)
            && !INTERRUPTED.load(Ordering::SeqCst)
    }
}

/// The pipelined batches of a run as processes, and the reports of the steps the nodes ran
/// ahead of the coordinator's loop.
struct Batching {
    batches: pipeline::Batches,
    /// Reports of the steps the nodes ran ahead of the loop in a multi-step batch.
    ahead: std::collections::VecDeque<Vec<PhaseReport>>,
    /// Wall time of one step of the last batch (how many steps the next may hold).
    step_wall: Option<f64>,
}

impl Batching {
    fn new(batches: pipeline::Batches) -> Self {
        Self {
            batches,
            ahead: Default::default(),
            step_wall: None,
        }
    }

    fn has_ahead(&self) -> bool {
        !self.ahead.is_empty()
    }

    /// The phases' reports of `step`, from a batch already run or from a new one, and whether
    /// the nodes are already past it (so it cannot be the last).
    #[allow(clippy::too_many_arguments)]
    fn reports_of_step(
        &mut self,
        step: u64,
        cadence: Cadence,
        full: cosim::FullReports,
        nodes: &mut [Node],
        st: &mut RunState,
        node_timeout: Duration,
        dt: f64,
    ) -> Result<(Vec<PhaseReport>, bool), RunError> {
        if let Some(reports) = self.ahead.pop_front() {
            return Ok((reports, self.has_ahead()));
        }
        let b = &mut self.batches;
        // Several steps in one batch where the coordinator needs nothing in between; a single
        // step may send the next one early (then that one is single too), unless the next is
        // to be a batch of several.
        let single = cadence.rests || INTERRUPTED.load(Ordering::SeqCst) || !b.can_hold_steps();
        let step_wall = self.step_wall;
        let steps_from = |s| {
            if single {
                1
            } else {
                let every = [cadence.checkpoint_every, cadence.fields_every];
                batch_steps(s, cadence.steps, cadence.interval, every, step_wall)
            }
        };
        let count = if b.sent_early(step) {
            1
        } else {
            steps_from(step)
        };
        let send_next = cadence.may_send_next(step) && count == 1 && steps_from(step + 1) == 1;
        st.largest_batch = st.largest_batch.max(count);
        let t0 = Instant::now();
        let mut reports = b
            .run_steps(
                (step, count, full),
                send_next,
                nodes,
                (&mut st.seconds_per_phase, &mut st.seconds_waiting),
                node_timeout,
            )
            .map_err(|(e, done)| {
                st.steps_done = done;
                st.time = done as f64 * dt;
                e
            })?;
        self.step_wall = Some(t0.elapsed().as_secs_f64() / count as f64);
        let next_sent = b.sent_early(step + 1);
        self.ahead.extend(reports.drain(1..));
        let reports = reports.pop().expect("a report per step");
        Ok((reports, next_sent || self.has_ahead()))
    }
}

/// The longest a multi-step batch should take: the coordinator looks at Ctrl-C and the
/// nodes' health between batches.
const BATCH_SECONDS: f64 = 0.05;
/// Most steps in one batch.
const MAX_BATCH_STEPS: u64 = 64;
// The bead states of every step of a batch wait in the coordinator's queue until it reads
// them (orbit metrics), with one more step sent early.
const _: () = assert!(MAX_BATCH_STEPS + 2 <= cosim::ipc::STATES_QUEUE as u64);

/// How many steps from `step` the nodes may run in one batch ([`pipeline::Batches::run_steps`]):
/// up to the next step whose end the coordinator logs (`interval`) or checkpoints or
/// snapshots (`every`: those intervals, 0 for never), the last step, and [`BATCH_SECONDS`] of
/// wall time at `step_wall` seconds a step (one step while that is unknown). Each batch saves the coordinator a request and a reply
/// to each node per step, the system calls and wake-ups of which take a core from the nodes'
/// threads on a small machine.
fn batch_steps(
    step: u64,
    steps: u64,
    interval: u64,
    every: [u64; 2],
    step_wall: Option<f64>,
) -> u64 {
    let Some(wall) = step_wall else {
        return 1;
    };
    // Steps up to and including the next one whose end is a multiple of `n` (0: none).
    let until = |n: u64| step.checked_div(n).map_or(u64::MAX, |k| (k + 1) * n - step);
    let by_time = if wall > 0.0 {
        (BATCH_SECONDS / wall)
            .floor()
            .clamp(1.0, MAX_BATCH_STEPS as f64) as u64
    } else {
        MAX_BATCH_STEPS
    };
    by_time
        .min(until(interval.max(1)))
        .min(until(every[0]))
        .min(until(every[1]))
        .min(steps.saturating_sub(step))
        .max(1)
}

/// One step with one phase at a time: the coordinator hands each phase to its node and waits
/// for the reply. Returns the phases' reports in schedule order.
fn run_step_lock_step(
    (step, detail): (u64, cosim::Detail),
    schedule: &[Phase],
    owner: &[usize],
    nodes: &mut [Node],
    seconds: &mut BTreeMap<String, f64>,
) -> Result<Vec<PhaseReport>, RunError> {
    let mut reports = Vec::with_capacity(schedule.len());
    for (&phase, &o) in schedule.iter().zip(owner) {
        let t0 = Instant::now();
        let node = &mut nodes[o].link;
        let reply = node
            .call(&Command::RunPhase {
                step,
                phase,
                detail,
            })
            .map_err(|e| node_failed(node.name(), step, &format!("phase {phase}: "), e))?;
        *seconds.entry(phase.name().to_string()).or_default() += t0.elapsed().as_secs_f64();
        if let Reply::PhaseDone(r) = reply {
            reports.push(r);
        }
    }
    Ok(reports)
}

/// The error for a node that failed during `step`; `context` names the phase if known.
pub(crate) fn node_failed(node: &str, step: u64, context: &str, e: LinkFailure) -> RunError {
    let detail = match &e {
        LinkFailure::Refused { message, .. } => message.clone(),
        other => other.to_string(),
    };
    fail(format!(
        "node `{node}` failed at step {step}, {context}{detail}"
    ))
}

/// Ask every node for its state and write the checkpoint.
fn save_checkpoint(
    dir: &Path,
    run: crate::checkpoint::RunCheckpoint,
    nodes: &mut [Node],
) -> Result<(), RunError> {
    let mut saved = Vec::with_capacity(nodes.len());
    for n in nodes.iter_mut() {
        let name = n.link.name().to_string();
        match n.link.call(&Command::SaveState) {
            Ok(Reply::State(bytes)) => saved.push((name, bytes)),
            Ok(other) => {
                return Err(fail(format!(
                    "checkpoint at step {}: node `{name}` answered {other:?} to save-state",
                    run.step
                )))
            }
            Err(e) => return Err(fail(format!("checkpoint at step {}: {e}", run.step))),
        }
    }
    crate::checkpoint::write(dir, run, &saved).map_err(fail)
}

/// Read the checkpoint in `dir` and check that it fits this scene.
fn check_resume(
    scene: &LoadedScene,
    dir: &Path,
    steps: u64,
) -> Result<crate::checkpoint::RunCheckpoint, RunError> {
    let ck = crate::checkpoint::read_run(dir).map_err(fail)?;
    crate::checkpoint::check_scene(&ck, &scene.toml).map_err(fail)?;
    if ck.step >= steps {
        return Err(fail(format!(
            "the checkpoint is at step {}, the scene asks for {steps} steps: nothing to resume \
             (raise time.steps)",
            ck.step
        )));
    }
    Ok(ck)
}

/// The log of the run that wrote the checkpoint in `dir` (its run directory's `run.mcap`)
/// up to the checkpoint's time `time`, to open the resumed run's log; `None` where there is
/// none to read (it was moved, or never written).
fn earlier_log(dir: &Path, time: f64) -> Option<Vec<crate::mcap_log::LoggedMessage>> {
    let path = dir.parent()?.join("run.mcap");
    crate::mcap_log::messages_up_to(&path, time).ok()
}

/// Restore every node from the checkpoint `ck` in `dir` (see [`check_resume`]).
fn restore(
    dir: &Path,
    ck: crate::checkpoint::RunCheckpoint,
    nodes: &mut [Node],
) -> Result<crate::checkpoint::RunCheckpoint, RunError> {
    for n in nodes.iter_mut() {
        let name = n.link.name().to_string();
        let state = crate::checkpoint::read_node(dir, &ck, &name).map_err(fail)?;
        n.link
            .call(&Command::RestoreState { state })
            .map_err(|e| fail(format!("resuming node `{name}` at step {}: {e}", ck.step)))?;
    }
    Ok(ck)
}

/// At rest: the largest net force on a free bead is below `tol` times the largest load, and
/// the kinetic energy is below `tol^2` times the elastic energy (both dimensionless, so that
/// neither a turning point nor a pass through equilibrium is mistaken for rest).
fn is_at_rest(report: &[(String, f64)], tol: f64, load_scale: f64) -> bool {
    let (Some(force), Some(kinetic), Some(elastic)) = (
        crate::metrics::lookup(report, "max_net_force"),
        crate::metrics::lookup(report, "kinetic_energy"),
        crate::metrics::lookup(report, "elastic_energy"),
    ) else {
        return false;
    };
    let force_ok = if load_scale > 0.0 {
        force <= tol * load_scale
    } else {
        true
    };
    force_ok && kinetic <= tol * tol * elastic.max(f64::MIN_POSITIVE)
}

fn progress_bar(show: bool, steps: u64) -> indicatif::ProgressBar {
    if !show {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(steps);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {pos}/{len} steps, eta {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_outputs_are_removed_and_nothing_else_but_the_scene_being_run() {
        let dir = std::env::temp_dir().join(format!("run-stale-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let derived: Vec<&str> = crate::orbit_report::FILES
            .iter()
            .chain(&crate::export::FILES)
            .copied()
            .collect();
        for f in derived.iter().chain(&["summary.json"]) {
            std::fs::write(dir.join(f), "x").unwrap();
        }
        remove_stale_outputs(&dir, None);
        assert!(derived.iter().all(|f| !dir.join(f).exists()));
        assert!(dir.join("summary.json").exists());
        remove_stale_outputs(&dir, None); // nothing left to remove: no error
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, "x").unwrap();
        std::fs::write(dir.join("orbit.csv"), "x").unwrap();
        remove_stale_outputs(&dir, Some(&scene));
        assert!(scene.exists() && !dir.join("orbit.csv").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A batch ends at the next logged step, checkpoint, snapshot or the last step, holds about
    /// BATCH_SECONDS of steps, and is one step while the step's wall time is unknown.
    #[test]
    fn batches_end_where_the_coordinator_needs_the_nodes() {
        let ms = Some(1e-3);
        assert_eq!(batch_steps(3, 1000, 500, [0, 0], None), 1);
        assert_eq!(batch_steps(3, 1000, 500, [0, 0], ms), 50);
        assert_eq!(batch_steps(490, 1000, 500, [0, 0], ms), 10);
        assert_eq!(batch_steps(499, 1000, 500, [0, 0], ms), 1);
        assert_eq!(
            batch_steps(500, 1000, 500, [0, 0], Some(1e-6)),
            MAX_BATCH_STEPS
        );
        assert_eq!(batch_steps(95, 1000, 500, [100, 0], ms), 5);
        assert_eq!(batch_steps(95, 1000, 500, [0, 60], ms), 25);
        assert_eq!(batch_steps(95, 1000, 500, [100, 60], ms), 5);
        assert_eq!(batch_steps(998, 1000, 500, [0, 0], ms), 2);
        assert_eq!(batch_steps(10, 1000, 1, [0, 0], ms), 1);
        assert_eq!(batch_steps(10, 1000, 500, [0, 0], Some(0.09)), 1);
    }
}
