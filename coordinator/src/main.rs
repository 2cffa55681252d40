//! Command-line interface. Every failure ends with one clear message and a non-zero exit
//! code, never a panic trace.
use clap::{Parser, Subcommand};
use coordinator::{export, runner, scene, study};
use cosim::scene_keys::Sig;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "coordinator",
    version,
    about = "Co-simulation of flexible fibres in fluids"
)]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Run a scene (the built-in example when CONFIG is omitted).
    Run {
        /// Scene file (TOML).
        config: Option<PathBuf>,
        /// Override a key by its dotted path, e.g. --set fibre.0.beads=12 (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Output directory for run.mcap and summary.json.
        #[arg(long, default_value = "runs/latest")]
        out: PathBuf,
        /// Link all components into this process instead of running them as processes.
        #[arg(long)]
        in_process: bool,
        /// No progress bar and no start-up lines.
        #[arg(long, short)]
        quiet: bool,
        /// Seconds to wait for one reply of a node before ending the run as unresponsive.
        #[arg(
            long,
            value_name = "SECONDS",
            default_value_t = 600.0,
            allow_negative_numbers = true
        )]
        node_timeout: f64,
        /// Save the run's full state to OUT/checkpoint every N steps, at the last step and
        /// on Ctrl-C or SIGTERM (0: no checkpoints).
        #[arg(long, value_name = "N", default_value_t = 0, allow_negative_numbers = true, value_parser = steps_or_none)]
        checkpoint_interval: u64,
        /// Continue the run from a checkpoint folder (OUT/checkpoint of an earlier run),
        /// with the same scene; time.steps, [output] and [analysis] may differ.
        #[arg(long, value_name = "DIR")]
        resume: Option<PathBuf>,
        /// As processes: hand every phase out and back through the coordinator, one at a
        /// time, instead of sending each node its phases of a step at once (same results;
        /// slower; for comparison and debugging).
        #[arg(long, conflicts_with = "in_process")]
        lock_step: bool,
    },
    /// Check a scene, print its effects, schedule and time-step limits; run nothing.
    Check {
        /// Scene file (TOML); the built-in example when omitted.
        config: Option<PathBuf>,
        /// Override a key by its dotted path, as for `run` (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
    },
    /// Print each component's model description.
    Describe {
        /// Ask the components linked into this process rather than as processes.
        #[arg(long)]
        in_process: bool,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Run a study: a scene over lists of parameter values, error against wall time.
    Study {
        /// Study file (TOML).
        study: PathBuf,
        /// Output directory (default: the one the study file names).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Rebuild the table and plots from the runs an earlier `study` of this file left in
        /// runs/study/NAME/, without running anything.
        #[arg(long)]
        replot: bool,
        /// Run this many variants at once, each as its own `coordinator run` (same results;
        /// the wall times then include the runs' contention, so keep 1 for cost plots).
        #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = job_count)]
        jobs: u16,
        /// Check every variant as `coordinator check` does and run nothing (--out and --jobs
        /// may stay on the command line: nothing is written).
        #[arg(long, conflicts_with = "replot")]
        check: bool,
    },
    /// Write a run's logged bead states and diagnostics as CSV (beads.csv, diagnostics.csv)
    /// and its scene as run (scene.toml), or print one topic of its log as JSON lines.
    Export {
        /// A run's output folder (holding run.mcap) or an MCAP file.
        #[arg(default_value = "runs/latest")]
        run: PathBuf,
        /// Folder for the files (default: the run's folder).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print this topic (e.g. /fibre/bead_states, /diagnostics, /timings, /scene) as
        /// JSON lines on standard output instead, one message a line.
        #[arg(long, value_name = "TOPIC", conflicts_with = "out")]
        topic: Option<String>,
    },
}

/// `--checkpoint-interval`: a whole number of steps, 0 for none.
fn steps_or_none(text: &str) -> Result<u64, String> {
    text.trim()
        .parse()
        .map_err(|_| "expected a whole number of steps, 0 (no checkpoints) or more".to_string())
}

/// `--jobs`: how many variants at once, at least 1.
fn job_count(text: &str) -> Result<u16, String> {
    match text.trim().parse::<u16>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!(
            "expected a whole number of variants to run at once, from 1 to {}",
            u16::MAX
        )),
    }
}

fn main() -> ExitCode {
    // Behave like other command-line tools when the reader of stdout goes away (`| head`):
    // end quietly instead of panicking on a broken pipe.
    // SAFETY: setting a signal disposition to its default at start-up, before any thread.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let _ = ctrlc::set_handler(runner::request_stop);
    match execute(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::from(2)
        }
    }
}

fn execute(cmd: Cmd) -> Result<(), String> {
    match cmd {
        Cmd::Run {
            config,
            set,
            out,
            in_process,
            quiet,
            node_timeout,
            checkpoint_interval,
            resume,
            lock_step,
        } => {
            if !(node_timeout.is_finite() && node_timeout > 0.0) {
                return Err(format!(
                    "--node-timeout: expected a positive number of seconds, got {node_timeout}"
                ));
            }
            let opts = runner::RunOptions {
                out,
                in_process,
                progress: !quiet,
                verbose: !quiet,
                node_timeout: std::time::Duration::from_secs_f64(node_timeout),
                checkpoint_interval,
                resume,
                lock_step,
            };
            run(config.as_deref(), &set, &opts)
        }
        Cmd::Check { config, set } => check(config.as_deref(), &set),
        Cmd::Describe { in_process, json } => {
            let all = runner::describe_all(in_process).map_err(|e| e.to_string())?;
            for d in all {
                if json {
                    println!(
                        "{}",
                        serde_json::to_string_pretty(&d).map_err(|e| e.to_string())?
                    );
                } else {
                    print!("{}", d.render());
                }
            }
            Ok(())
        }
        Cmd::Study {
            study, check: true, ..
        } => {
            let n = study::check_file(&study)?;
            println!(
                "ok: {n} variant{} of {} check{}; nothing was run",
                if n == 1 { "" } else { "s" },
                study.display(),
                if n == 1 { "s" } else { "" }
            );
            Ok(())
        }
        Cmd::Study {
            study,
            out,
            replot,
            jobs,
            check: false,
        } => run_study(&study, out.as_deref(), replot, jobs),
        Cmd::Export { run, out, topic } => export_run(&run, out, topic.as_deref()),
    }
}

/// `coordinator run`: the scene (the built-in example without a file), its result printed.
fn run(
    config: Option<&std::path::Path>,
    set: &[String],
    opts: &runner::RunOptions,
) -> Result<(), String> {
    let scene = scene::load(config, set).map_err(|e| e.to_string())?;
    let out = &opts.out;
    let result = runner::run(&scene, opts).map_err(|e| e.to_string())?;
    print_result(&result.summary, out);
    if result.summary["status"] == "interrupted" {
        return Err(format!(
            "interrupted at step {} (Ctrl-C or SIGTERM); the log and summary so far are in {}",
            result.summary["steps"],
            out.display()
        ));
    }
    Ok(())
}

/// `coordinator check`: the scene validated by every node it needs, and what it would run.
fn check(config: Option<&std::path::Path>, set: &[String]) -> Result<(), String> {
    let scene = scene::load(config, set).map_err(|e| e.to_string())?;
    let (plan, configured, descriptions) = runner::check(&scene).map_err(|e| e.to_string())?;
    println!("scene:    {}", scene.name());
    println!("effects:  {}", plan.effects(&configured.effects).join(", "));
    let phases: Vec<&str> = plan.schedule.iter().map(|p| p.name()).collect();
    println!("schedule: {}", phases.join(" -> "));
    for d in &descriptions {
        println!("node:     {} {} ({})", d.name, d.version, d.kind);
    }
    println!("beads:    {:?}", configured.beads_per_fibre);
    println!(
        "steps:    {} x dt {}",
        scene.scene.time.steps, scene.scene.time.dt
    );
    if let Some(f) = scene.fields_summary() {
        println!("fields:   {f}");
    }
    for g in &scene.groups.lines {
        println!("group:    {g}");
    }
    for (name, limit) in &configured.time_step_limits {
        println!("limit:    {name}: dt <= {}", Sig(*limit));
    }
    for (name, v) in &configured.derived {
        println!("derived:  {name} = {}", Sig(*v));
    }
    for n in &configured.notes {
        println!("note:     {n}");
    }
    println!("ok: the scene is valid; nothing was run");
    Ok(())
}

/// `coordinator study`: every variant run (or reused with `--replot`), the report printed.
fn run_study(
    study: &std::path::Path,
    out: Option<&std::path::Path>,
    replot: bool,
    jobs: u16,
) -> Result<(), String> {
    let exe = std::env::current_exe()
        .map_err(|e| format!("cannot find this executable for --jobs: {e}"))?;
    let runs = match (replot, jobs) {
        (true, 1) => study::Runs::Reuse,
        (true, _) => return Err("--replot runs nothing: leave out --jobs".into()),
        (false, 1) => study::Runs::OneByOne,
        (false, j) => study::Runs::Parallel {
            exe: &exe,
            jobs: j as usize,
        },
    };
    let report = study::run_file(study, out, runs).map_err(|e| e.to_string())?;
    println!("{report}");
    Ok(())
}

/// `coordinator export`: a run's log as CSV files and its scene, or one topic as JSON lines;
/// a log cut short is exported up to its break, with a warning.
fn export_run(
    run: &std::path::Path,
    out: Option<PathBuf>,
    topic: Option<&str>,
) -> Result<(), String> {
    let log = export::log_path(run)?;
    let damage = match topic {
        Some(topic) => {
            use std::io::Write;
            let (messages, damage) = coordinator::mcap_log::salvage_topic(&log, topic)?;
            if messages.is_empty() && damage.is_none() {
                let have = coordinator::mcap_log::topics(&log)?;
                return Err(format!(
                    "{} has no messages on {topic} (its topics: {})",
                    log.display(),
                    have.join(", ")
                ));
            }
            let mut stdout = std::io::stdout().lock();
            for m in messages {
                writeln!(stdout, "{m}").map_err(|e| format!("cannot print: {e}"))?;
            }
            damage
        }
        None => {
            let dir = out.unwrap_or_else(|| log.parent().unwrap_or(run).to_path_buf());
            let done = export::export(&log, &dir)?;
            for (path, rows) in &done.files {
                match path.extension().is_some_and(|e| e == "csv") {
                    true => println!(
                        "wrote {} ({rows} row{})",
                        path.display(),
                        if *rows == 1 { "" } else { "s" }
                    ),
                    false => println!("wrote {}", path.display()),
                }
            }
            done.damage
        }
    };
    if let Some(e) = damage {
        eprintln!(
            "warning: {} breaks off ({e}): exported what was logged before the break",
            log.display()
        );
    }
    Ok(())
}

fn print_result(summary: &serde_json::Value, out: &std::path::Path) {
    // A resumed run counts its steps from step 0 and its seconds from the resume.
    let resumed = summary["resumed_from_step"]
        .as_u64()
        .map_or(String::new(), |n| {
            format!(", steps {n} to {} in this run", summary["steps"])
        });
    println!(
        "{}: {} steps in {:.2} s ({}{resumed})",
        summary["status"].as_str().unwrap_or("?"),
        summary["steps"],
        summary["wall_seconds"].as_f64().unwrap_or(0.0),
        summary["process_layout"].as_str().unwrap_or("")
    );
    if let Some(m) = summary["metrics"].as_object() {
        for (name, v) in m {
            match (v["reference"].as_f64(), v["relative_error"].as_f64()) {
                (Some(r), Some(e)) => {
                    let value = v["value"].as_f64().unwrap_or(f64::NAN);
                    if r == 0.0 {
                        // Metric::with_reference keeps the absolute error there.
                        println!(
                            "  {name} = {} (reference 0, absolute error {})",
                            Sig(value),
                            Sig(e)
                        );
                    } else {
                        println!(
                            "  {name} = {} (reference {}, relative error {:.2} %)",
                            Sig(value),
                            Sig(r),
                            100.0 * e
                        );
                    }
                    if let Some(note) = v["note"].as_str().filter(|n| !n.is_empty()) {
                        println!("    {note}");
                    }
                }
                _ => match v["label"].as_str() {
                    Some(label) => {
                        println!("  {name} = {label} ({})", v["note"].as_str().unwrap_or(""))
                    }
                    None => match (v["value"].as_f64(), v["note"].as_str()) {
                        (Some(x), _) => println!("  {name} = {}", Sig(x)),
                        // No value (JSON null): the note says why (a fibre not stuck, no
                        // complete half-turn).
                        (None, Some(note)) if !note.is_empty() => {
                            println!("  {name}: none ({note})")
                        }
                        (None, _) => println!("  {name} = {}", v["value"]),
                    },
                },
            }
        }
    }
    if let Some(m) = summary["metric_errors"].as_object() {
        for (name, why) in m {
            println!("  {name}: not computed: {}", why.as_str().unwrap_or(""));
        }
    }
    if let Some(m) = summary["file_errors"].as_object() {
        for (name, why) in m {
            println!(
                "  {name} files: not written: {}",
                why.as_str().unwrap_or("")
            );
        }
    }
    if let Some(w) = summary["warnings"].as_array() {
        for w in w.iter().filter_map(|w| w.as_str()) {
            println!("warning: {w}");
        }
    }
    let mut files = vec!["run.mcap".to_string(), "summary.json".to_string()];
    if let Some(extra) = summary["files"].as_array() {
        files.extend(extra.iter().filter_map(|f| f.as_str().map(String::from)));
    }
    let files: Vec<String> = files
        .iter()
        .map(|f| format!("{}/{f}", out.display()))
        .collect();
    println!("wrote {}", files.join(", "));
}
