//! The fluid node as its own process: serves the `cosim` interface over iceoryx2.
//!
//! Usage: `fluid-node serve --prefix PREFIX --name NAME` (started by the coordinator), or
//! `fluid-node describe` to print the model description as JSON.
use cosim::Component;
use fluid_node::FluidComponent;
use std::io::Write;
use std::process::ExitCode;

fn usage() -> ExitCode {
    eprintln!("usage: fluid-node serve --prefix PREFIX --name NAME | fluid-node describe");
    ExitCode::from(2)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("describe") => {
            let d = FluidComponent::new().describe();
            println!(
                "{}",
                serde_json::to_string_pretty(&d).expect("description serialises")
            );
            ExitCode::SUCCESS
        }
        Some("serve") => {
            let value = |flag: &str| args.windows(2).find(|w| w[0] == flag).map(|w| w[1].clone());
            let (Some(prefix), Some(name)) = (value("--prefix"), value("--name")) else {
                return usage();
            };
            let mut component = FluidComponent::new();
            match cosim::ipc::serve(&mut component, &prefix, &name) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    // The coordinator may be gone and stderr a broken pipe: never panic here.
                    let _ = writeln!(std::io::stderr(), "fluid-node: {e}");
                    ExitCode::from(1)
                }
            }
        }
        _ => usage(),
    }
}
