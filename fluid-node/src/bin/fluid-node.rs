//! The fluid node as its own process: serves the `cosim` interface over iceoryx2.
//!
//! Usage: `fluid-node serve --prefix PREFIX --name NAME` (started by the coordinator), or
//! `fluid-node describe` to print the model description as JSON.
use fluid_node::FluidComponent;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    cosim::ipc::node_main("fluid-node", &args, FluidComponent::new)
}
