//! The coordinator: reads a scene, derives the effects, launches the nodes (or links them
//! in), enforces the order of the fractional step, logs to MCAP and writes the summary.
//! `study` runs a scene over a grid of parameter values and reports error against cost.
pub mod capillary_metrics;
pub mod checkpoint;
pub mod energy_watch;
pub mod export;
mod field_plot;
mod field_snapshots;
pub mod interface_metrics;
pub mod links;
pub mod mcap_log;
pub mod metrics;
pub mod orbit;
pub mod orbit_report;
pub mod overlap_watch;
mod pipeline;
pub mod plot;
pub mod reference;
pub mod runner;
pub mod scene;
pub mod schedule;
pub mod shear_groups;
pub mod steady_watch;
pub mod study;
pub mod trajectory;
