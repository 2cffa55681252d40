//! Print one topic of a run's MCAP log as JSON lines (one message per line), for plotting
//! or post-processing outside the coordinator:
//!
//!     cargo run --release -p coordinator --example dump_topic -- runs/latest/run.mcap /fibre/bead_states
//!
//! A log that breaks off (the run was killed before it could close it) is read up to its last
//! complete record; a warning on stderr says so, and the exit status is 3.
use coordinator::mcap_log::salvage_topic;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [path, topic] = args.as_slice() else {
        eprintln!("usage: dump_topic RUN.mcap TOPIC (e.g. /fibre/bead_states, /diagnostics)");
        std::process::exit(2);
    };
    match salvage_topic(std::path::Path::new(path), topic) {
        Ok((messages, damage)) => {
            use std::io::Write;
            let mut out = std::io::stdout().lock();
            let n = messages.len();
            for m in messages {
                // A closed pipe (`| head`) ends the listing quietly.
                if writeln!(out, "{m}").is_err() {
                    return;
                }
            }
            if let Some(e) = damage {
                eprintln!(
                    "warning: {path} breaks off ({e}); printed the {n} messages of {topic} before the break"
                );
                std::process::exit(3);
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
