//! Print one topic of a run's MCAP log as JSON lines (one message per line), for plotting
//! or post-processing outside the coordinator:
//!
//!     cargo run --release -p coordinator --example dump_topic -- runs/latest/run.mcap /fibre/bead_states
use coordinator::mcap_log::read_topic;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [path, topic] = args.as_slice() else {
        eprintln!("usage: dump_topic RUN.mcap TOPIC (e.g. /fibre/bead_states, /diagnostics)");
        std::process::exit(2);
    };
    match read_topic(std::path::Path::new(path), topic) {
        Ok(messages) => {
            use std::io::Write;
            let mut out = std::io::stdout().lock();
            for m in messages {
                // A closed pipe (`| head`) ends the listing quietly.
                if writeln!(out, "{m}").is_err() {
                    return;
                }
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
