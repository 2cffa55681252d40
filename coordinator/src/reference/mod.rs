//! Analytic and published references the metrics are compared with.
pub mod elastica;
