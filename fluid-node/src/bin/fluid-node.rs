//! The fluid node as its own process: serves the `cosim` interface over iceoryx2.
//!
//! Usage: `fluid-node serve --prefix PREFIX --name NAME` (started by the coordinator), or
//! `fluid-node describe` to print the model description as JSON.
use fluid_node::FluidComponent;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    // Serve from a thread of rayon's pool: every parallel loop of a step then starts on a
    // worker instead of handing its work to the pool and sleeping until it is done, which
    // cost two context switches per loop (about a hundred per 2D step).
    rayon::scope(|_| cosim::ipc::node_main("fluid-node", &args, FluidComponent::new))
}
