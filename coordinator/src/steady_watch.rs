//! Whether a steady metric was read from a steady flow.
//!
//! `drag_ratio` and `drag_coefficient` read the last step and compare it with a steady
//! reference (the periodic array's drag, Dennis & Chang's C_D). A run that ends while the
//! flow still develops compares a transient, and nothing in the value says so. The history
//! keeps, at about [`SAMPLES`] evenly spaced steps, the quantity each of these metrics reads,
//! and the metric reports the quantity's change over the run's last fifth
//! ([`LAST_PART`]); past [`STEADY_CHANGE`] the summary warns.
//!
//! The FPD cylinder of configs/fpd/cylinder_drag.toml, for one: its holding force changes by
//! 0.06 % over the last fifth of its 12 800 steps, and by 2 % between steps 1600 and 2400.

use crate::metrics::lookup;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The metrics that compare the last step with a steady reference.
pub const STEADY_METRICS: [&str; 2] = ["drag_ratio", "drag_coefficient"];

/// About this many samples over a run (one every `steps / SAMPLES` steps).
pub const SAMPLES: u64 = 200;

/// The part of the run, at its end, over which the change is measured.
pub const LAST_PART: f64 = 0.2;

/// A relative change over the last part past which the flow is not steady.
pub const STEADY_CHANGE: f64 = 0.01;

/// Name of the metric's extra value that holds the change.
pub const CHANGE_EXTRA: &str = "change_over_last_fifth";

/// What a steady metric reads at one step, from the step's diagnostics, up to constant
/// factors; `None` for other metrics, or where a diagnostic is missing.
pub fn quantity(metric: &str, diagnostics: &[(String, f64)]) -> Option<f64> {
    match metric {
        // The holding force (FPD), which balances the drag once steady.
        "drag_coefficient" => lookup(diagnostics, "total_bead_force_x"),
        // The fluid's impulse on the beads over the mean flow (SPM): the drag coefficient
        // the ratio divides by its reference.
        "drag_ratio" => {
            Some(lookup(diagnostics, "total_impulse_x")? / lookup(diagnostics, "mean_velocity_x")?)
        }
        _ => None,
    }
}

/// What the quantity of a steady metric did over the run's last part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Change {
    /// `|q(t_end) - q(t_from)| / |q(t_end)|`.
    pub relative: f64,
    /// The time of the sample the change is measured from: the last at or before
    /// `(1 - LAST_PART) t_end`.
    pub from_time: f64,
    pub end_time: f64,
}

impl Change {
    /// Past [`STEADY_CHANGE`]: the summary's warning for `metric`.
    pub fn warning(&self, metric: &str) -> Option<String> {
        (self.relative > STEADY_CHANGE).then(|| {
            format!(
                "metric `{metric}` compares the last step with a steady reference, but what it \
                 reads changed by {:.2} % over the run's last fifth (time {} to {}): the flow \
                 is not yet steady; raise time.steps",
                100.0 * self.relative,
                cosim::scene_keys::Sig(self.from_time),
                cosim::scene_keys::Sig(self.end_time)
            )
        })
    }
}

/// Samples of the steady metrics' quantities: (time, value) per metric, oldest first.
#[derive(Debug, Default, Clone, PartialEq, Serialize, Deserialize)]
pub struct SteadyHistory {
    pub samples: BTreeMap<String, Vec<(f64, f64)>>,
}

impl SteadyHistory {
    /// A history for those of `metrics` that are steady metrics.
    pub fn for_metrics(metrics: &[String]) -> Self {
        let samples = metrics
            .iter()
            .filter(|m| STEADY_METRICS.contains(&m.as_str()))
            .map(|m| (m.clone(), Vec::new()))
            .collect();
        Self { samples }
    }

    /// Take step `step` (1-based) of a run of `steps` steps, at `time`: every
    /// `steps / SAMPLES` steps (the last step's value the metric reads itself).
    pub fn observe(&mut self, step: u64, steps: u64, time: f64, diagnostics: &[(String, f64)]) {
        let stride = (steps / SAMPLES).max(1);
        if !step.is_multiple_of(stride) {
            return;
        }
        for (metric, list) in &mut self.samples {
            if let Some(q) = quantity(metric, diagnostics).filter(|q| q.is_finite()) {
                list.push((time, q));
            }
        }
    }

    /// The change of `metric`'s quantity from the last sample at or before
    /// `(1 - LAST_PART) end_time` to its value `end` at `end_time`; `None` without such a
    /// sample (a run too short to say) or without a value at the end.
    pub fn change(&self, metric: &str, end_time: f64, end: Option<f64>) -> Option<Change> {
        let end = end.filter(|e| e.is_finite() && *e != 0.0)?;
        let cut = (1.0 - LAST_PART) * end_time;
        let &(from_time, from) = self
            .samples
            .get(metric)?
            .iter()
            .rev()
            .find(|(t, _)| *t <= cut && *t > 0.0)?;
        Some(Change {
            relative: ((end - from) / end).abs(),
            from_time,
            end_time,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn diag(force: f64) -> Vec<(String, f64)> {
        vec![("total_bead_force_x".to_string(), force)]
    }

    /// A force relaxing as 1 + e^{-t / tau}: over the last fifth of a run of length T it
    /// changes by (e^{-0.8 T / tau} - e^{-T / tau}) / (1 + e^{-T / tau}), the value the
    /// history reports to round-off; short runs warn, long ones do not.
    #[test]
    fn a_relaxing_force_is_steady_only_once_relaxed() {
        let tau = 100.0;
        let force = |t: f64| 1.0 + (-t / tau).exp();
        for (steps, warns) in [(200_u64, true), (2000, false)] {
            let mut h = SteadyHistory::for_metrics(&["drag_coefficient".into(), "orbit".into()]);
            assert_eq!(h.samples.len(), 1);
            for step in 1..=steps {
                let t = step as f64;
                h.observe(step, steps, t, &diag(force(t)));
            }
            let end = steps as f64;
            let c = h.change("drag_coefficient", end, Some(force(end))).unwrap();
            let exact = (force(0.8 * end) - force(end)) / force(end);
            assert!((c.relative - exact).abs() < 1e-12, "{c:?} {exact}");
            assert_eq!(c.from_time, 0.8 * end);
            assert_eq!(c.warning("drag_coefficient").is_some(), warns, "{c:?}");
        }
    }

    #[test]
    fn a_run_too_short_to_sample_says_nothing() {
        let mut h = SteadyHistory::for_metrics(&["drag_ratio".into()]);
        let d = vec![
            ("total_impulse_x".to_string(), 2.0),
            ("mean_velocity_x".to_string(), 4.0),
        ];
        h.observe(1, 1, 0.7, &d);
        assert_eq!(h.samples["drag_ratio"], vec![(0.7, 0.5)]);
        assert_eq!(h.change("drag_ratio", 0.7, Some(0.5)), None);
        assert_eq!(h.change("drag_coefficient", 0.7, Some(0.5)), None);
    }
}
