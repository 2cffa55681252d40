//! The `main` of every node executable: `NODE serve --prefix PREFIX --name NAME` serves a
//! component over iceoryx2 (started by the coordinator); `NODE describe` prints its model
//! description as JSON.
use crate::Component;
use std::io::Write;
use std::process::ExitCode;

/// Run a node executable named `program` from its command-line `args` (without `argv[0]`).
/// `component` is built only when needed.
pub fn node_main<C: Component>(
    program: &str,
    args: &[String],
    component: impl FnOnce() -> C,
) -> ExitCode {
    let text = format!(
        "usage: {program} serve --prefix PREFIX --name NAME | {program} describe\n\
         The coordinator starts {program} itself and serves it the scene: to run one, use \
         `coordinator run SCENE`; `{program} describe` prints the keys and phases it offers."
    );
    let usage = || {
        let _ = writeln!(std::io::stderr(), "{text}");
        ExitCode::from(2)
    };
    match args.first().map(String::as_str) {
        Some("-h" | "--help" | "help") => {
            let _ = writeln!(std::io::stdout(), "{text}");
            ExitCode::SUCCESS
        }
        Some("describe") => {
            let d = component().describe();
            let text = serde_json::to_string_pretty(&d).expect("a description always serialises");
            let _ = writeln!(std::io::stdout(), "{text}");
            ExitCode::SUCCESS
        }
        Some("serve") => {
            let value = |flag: &str| args.windows(2).find(|w| w[0] == flag).map(|w| w[1].clone());
            let (Some(prefix), Some(name)) = (value("--prefix"), value("--name")) else {
                return usage();
            };
            let mut c = component();
            // Started by hand rather than by the coordinator (whose nodes write to a pipe),
            // say what it waits for instead of waiting silently.
            if std::io::IsTerminal::is_terminal(&std::io::stderr()) {
                let _ = writeln!(
                    std::io::stderr(),
                    "{program}: serving as `{name}` of run `{prefix}`, waiting for its \
                     coordinator (Ctrl-C to stop); the coordinator starts its nodes itself: \
                     `coordinator run SCENE`"
                );
            }
            match super::serve(&mut c, &prefix, &name) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    // The coordinator may be gone and stderr a broken pipe: never panic here.
                    let _ = writeln!(std::io::stderr(), "{program}: {e}");
                    ExitCode::from(1)
                }
            }
        }
        _ => usage(),
    }
}
