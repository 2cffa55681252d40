//! Whether a steady metric was read from a steady state.
//!
//! Some metrics read the last step and compare it with the reference of a steady state: the
//! drag of a held body (`drag_ratio`, `drag_coefficient`: the periodic array's drag, Dennis &
//! Chang's C_D), the Couette profile between walls (`couette_max_error`) and the equilibria
//! of a binary fluid (`surface_tension`, `laplace_pressure_jump`, `contact_angle_deg`: L2020
//! section 3.3); others read the shape a fibre relaxes to at an interface (`final_tilt_deg`,
//! `wrap`, `curvature_radius_over_droplet_radius`: L2020 sections 3.4-3.5, worked out from
//! fibre 0's bead centres by [`crate::interface_metrics::InterfaceGeometry`]). A run that
//! ends while the state still changes compares a transient, and nothing in the value says
//! so. The history keeps, at about [`SAMPLES`] evenly spaced steps and at every logged step,
//! the quantity each of these metrics reads, and the metric reports the quantity's change over
//! the run's last fifth ([`LAST_PART`]) and, where that change slows down, how much further
//! an exponential approach through three of its samples would go ([`exponential_remainder`]:
//! a slow drift moves little over the last fifth but has far to go). Past [`STEADY_CHANGE`]
//! (relative; for an angle [`STEADY_DEGREES`], for the Couette error, already a fraction of
//! the wall speeds, [`STEADY_ERROR`]), either one, the summary warns.
//!
//! Measured on the shipped scenes: the FPD cylinder of configs/fpd/cylinder_drag.toml changes
//! its holding force by 0.11 % over the last fifth of its 12 800 steps (2 % between steps
//! 1600 and 2400), the Lamb cylinder by 0.28 % (0.08 % to come); configs/capillary/
//! contact_angle.toml, a smoke run of 8000 steps whose bead is still sinking, moves its angle
//! by 0.68 deg over its last fifth, and by 0.27 deg over the last fifth of the 128 000 steps
//! its comment suggests (0.12 deg to come: steady). configs/capillary/encapsulation_2d.toml
//! as written (L2020's eta = 10, 40 000 steps) ends with the fibre still bending around its
//! droplet (w 40 %, R_c 8.5 % over the last fifth).

use crate::interface_metrics::{InterfaceGeometry, INTERFACE_METRICS};
use crate::metrics::lookup;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The metrics that compare the last step with the reference of a steady state, or read
/// the state a relaxation ends in.
pub const STEADY_METRICS: [&str; 9] = [
    "drag_ratio",
    "drag_coefficient",
    "couette_max_error",
    "surface_tension",
    "laplace_pressure_jump",
    "contact_angle_deg",
    "final_tilt_deg",
    "wrap",
    "curvature_radius_over_droplet_radius",
];

/// About this many samples over a run (one every `steps / SAMPLES` steps), besides the
/// logged steps (where the diagnostics that cost a pass of their own are reported).
pub const SAMPLES: u64 = 200;

/// The part of the run, at its end, over which the change is measured.
pub const LAST_PART: f64 = 0.2;

/// A relative change over the last part past which the state is not steady.
pub const STEADY_CHANGE: f64 = 0.01;

/// A change of an angle over the last part (degrees) past which it is not steady.
pub const STEADY_DEGREES: f64 = 0.5;

/// A change of the Couette error (a fraction of the wall-speed difference) over the last
/// part past which the flow is not steady: a tenth of the 1 % the profile is held to.
pub const STEADY_ERROR: f64 = 1e-3;

/// Name of the metric's extra value that holds the change (relative; degrees for an angle;
/// for the Couette error, its own change).
pub const CHANGE_EXTRA: &str = "change_over_last_fifth";

/// Name of the metric's extra value that holds the change still to come were the approach
/// exponential ([`Change::remaining`]), in the change's measure.
pub const REMAINING_EXTRA: &str = "estimated_remaining_change";

/// What a steady metric reads at one step, from the step's diagnostics, up to constant
/// factors; `None` for other metrics (the interface metrics read the bead centres:
/// [`SteadyHistory::observe`]), or where a diagnostic is missing (those that cost a pass of
/// their own are reported at logged steps only).
pub fn quantity(metric: &str, diagnostics: &[(String, f64)]) -> Option<f64> {
    let d = |k: &str| lookup(diagnostics, k);
    match metric {
        // The holding force (FPD), which balances the drag once steady.
        "drag_coefficient" => d("total_bead_force_x"),
        // The fluid's impulse on the beads over the mean flow (SPM): the drag coefficient
        // the ratio divides by its reference.
        "drag_ratio" => Some(d("total_impulse_x")? / d("mean_velocity_x")?),
        // The free energy over a fixed interface area.
        "surface_tension" => d("free_energy"),
        // The jump over sigma / R: the ratio the metric compares, times sigma.
        "laplace_pressure_jump" => Some(d("pressure_jump")? * d("droplet_radius")?),
        "contact_angle_deg" => d("contact_angle_deg"),
        "couette_max_error" => d("couette_max_error"),
        _ => None,
    }
}

/// How a quantity's change is measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Measure {
    /// Relative to its last value, against [`STEADY_CHANGE`].
    Relative,
    /// An angle, in degrees, against [`STEADY_DEGREES`].
    Degrees,
    /// An error that is already a fraction of a scale (the Couette error: of the wall
    /// speeds), as it is, against [`STEADY_ERROR`].
    Fraction,
}

fn measure(metric: &str) -> Measure {
    match metric {
        m if m.ends_with("_deg") => Measure::Degrees,
        "couette_max_error" => Measure::Fraction,
        _ => Measure::Relative,
    }
}

/// What the quantity of a steady metric did over the run's last part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Change {
    /// `|q(t_end) - q(t_from)|`, over `|q(t_end)|` where `measure` is relative.
    pub amount: f64,
    pub measure: Measure,
    /// The time of the sample the change is measured from: the last at or before
    /// `(1 - LAST_PART) t_end`.
    pub from_time: f64,
    pub end_time: f64,
    /// How much further the quantity would move, in the same measure, were its approach
    /// exponential, q(t) = q_inf + A e^{-lambda t} through the samples at `from_time`,
    /// half-way and the end ([`exponential_remainder`]); `None` where the last fifth does
    /// not show such an approach (no change, a change of sign, or no slowing down).
    pub remaining: Option<f64>,
}

/// The distance `|q_inf - q2|` still to go of q(t) = q_inf + A e^{-lambda t}, lambda > 0,
/// through three samples `(t, q)` in time order; `None` where no such curve passes through
/// them: the two differences of unlike sign or zero, or the later one not smaller, per unit
/// time, than a straight line allows (d2 / d1 >= h2 / h1). With h = t1 - t0 = t2 - t1 this
/// is Aitken's delta-squared: |d2| r / (1 - r), r = d2 / d1.
pub fn exponential_remainder(samples: [(f64, f64); 3]) -> Option<f64> {
    let [(t0, q0), (t1, q1), (t2, q2)] = samples;
    let (h1, h2) = (t1 - t0, t2 - t1);
    let (d1, d2) = (q1 - q0, q2 - q1);
    let r = d2 / d1;
    if !(h1 > 0.0 && h2 > 0.0 && r > 0.0 && r < h2 / h1) {
        return None;
    }
    // d2 / d1 = e^{-lambda h1} (1 - e^{-lambda h2}) / (1 - e^{-lambda h1}) falls from
    // h2 / h1 (lambda -> 0) to 0 (lambda -> inf): bisect on lambda h1 in log space.
    let ratio = |x: f64| {
        let y = x * h2 / h1;
        (-x).exp() * (-(-y).exp_m1()) / (-(-x).exp_m1())
    };
    let (mut lo, mut hi) = (1e-12_f64.ln(), 700.0_f64.ln());
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if ratio(mid.exp()) > r {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let lambda_h2 = (0.5 * (lo + hi)).exp() * h2 / h1;
    Some((d2 / lambda_h2.exp_m1()).abs())
}

impl Change {
    fn limit(&self) -> f64 {
        match self.measure {
            Measure::Relative => STEADY_CHANGE,
            Measure::Degrees => STEADY_DEGREES,
            Measure::Fraction => STEADY_ERROR,
        }
    }

    /// The change over the last fifth, or the change still to come were the approach
    /// exponential ([`Self::remaining`]: a slow drift), past [`STEADY_CHANGE`]
    /// ([`STEADY_DEGREES`] for an angle, [`STEADY_ERROR`] for the Couette error).
    pub fn exceeds(&self) -> bool {
        self.amount > self.limit() || self.remaining.is_some_and(|r| r > self.limit())
    }

    /// Why the state is not steady, in words, past the limit: "1.29 % change over the
    /// run's last fifth" and, where the approach looks exponential, the change to come.
    pub fn not_steady(&self) -> Option<String> {
        if !self.exceeds() {
            return None;
        }
        let mut words = format!("{} change over the run's last fifth", self.words());
        if let Some(r) = self.remaining {
            words += &format!(
                " and, slowing as an exponential approach does, {} still to come",
                self.in_words(r)
            );
        }
        Some(words)
    }

    /// The change in words: "1.29 %", "0.69 deg", or "2.1e-3 of the wall speeds".
    pub fn words(&self) -> String {
        self.in_words(self.amount)
    }

    fn in_words(&self, x: f64) -> String {
        match self.measure {
            Measure::Relative => format!("{:.2} %", 100.0 * x),
            Measure::Degrees => format!("{:.2} deg", x),
            Measure::Fraction => format!("{:.1e} of the wall speeds", x),
        }
    }

    /// Past the limit: the summary's warning for `metric`.
    pub fn warning(&self, metric: &str) -> Option<String> {
        let why = self.not_steady()?;
        Some(format!(
            "metric `{metric}` reads a steady state at the last step, but what it reads \
             shows {why} (time {} to {}): the run is not yet steady; raise time.steps",
            cosim::scene_keys::Sig(self.from_time),
            cosim::scene_keys::Sig(self.end_time)
        ))
    }
}

/// Samples of the steady metrics' quantities: (time, value) per metric, oldest first.
#[derive(Debug, Default, Clone, PartialEq, Serialize, Deserialize)]
pub struct SteadyHistory {
    pub samples: BTreeMap<String, Vec<(f64, f64)>>,
    /// What the interface metrics read besides the bead centres; set by the run
    /// ([`Self::set_geometry`]), at a resume too.
    #[serde(skip)]
    geometry: Option<InterfaceGeometry>,
}

/// Whether `metric` is read from fibre 0's bead centres rather than from the diagnostics.
fn reads_beads(metric: &str) -> bool {
    INTERFACE_METRICS.contains(&metric)
}

/// Bead centres of `fibre0` (fibre 0's states), or `None` with fewer than two.
fn centres(fibre0: &[cosim::BeadState]) -> Option<Vec<[f64; 3]>> {
    (fibre0.len() >= 2).then(|| fibre0.iter().map(|s| s.position).collect())
}

impl SteadyHistory {
    /// A history for those of `metrics` that are steady metrics.
    pub fn for_metrics(metrics: &[String]) -> Self {
        let samples = metrics
            .iter()
            .filter(|m| STEADY_METRICS.contains(&m.as_str()))
            .map(|m| (m.clone(), Vec::new()))
            .collect();
        Self {
            samples,
            geometry: None,
        }
    }

    /// Give the history what its interface metrics read besides the bead centres.
    pub fn set_geometry(&mut self, geometry: InterfaceGeometry) {
        self.geometry = Some(geometry);
    }

    /// What `metric` reads: from the diagnostics, or, for an interface metric, from fibre 0's
    /// bead centres `points` (`None` without them or without the geometry).
    fn value_of(
        &self,
        metric: &str,
        diagnostics: &[(String, f64)],
        points: Option<&[[f64; 3]]>,
    ) -> Option<f64> {
        if reads_beads(metric) {
            self.geometry.as_ref()?.value(metric, points?).ok()
        } else {
            quantity(metric, diagnostics)
        }
    }

    /// Whether step `step` (1-based) of a run of `steps` steps is sampled: every
    /// `steps / SAMPLES` steps and the `logged` steps.
    fn due((step, steps, logged): (u64, u64, bool)) -> bool {
        logged || step.is_multiple_of((steps / SAMPLES).max(1))
    }

    /// Whether [`Self::observe`] needs fibre 0's bead states at this step.
    pub fn reads_beads_at(&self, sample: (u64, u64, bool)) -> bool {
        Self::due(sample) && self.samples.keys().any(|m| reads_beads(m))
    }

    /// Take step `step` (1-based) of a run of `steps` steps, at `time`, where it is due
    /// (every `steps / SAMPLES` steps and the `logged` steps), from the step's diagnostics
    /// and fibre 0's bead states `fibre0` (needed where [`Self::reads_beads_at`] says so).
    pub fn observe(
        &mut self,
        sample: (u64, u64, bool),
        time: f64,
        diagnostics: &[(String, f64)],
        fibre0: &[cosim::BeadState],
    ) {
        if !Self::due(sample) {
            return;
        }
        let points = centres(fibre0);
        let values: Vec<Option<f64>> = self
            .samples
            .keys()
            .map(|m| self.value_of(m, diagnostics, points.as_deref()))
            .collect();
        for (list, q) in self.samples.values_mut().zip(values) {
            if let Some(q) = q.filter(|q| q.is_finite()) {
                list.push((time, q));
            }
        }
    }

    /// The change of every metric of the history, at the end of a run at `end_time` with the
    /// last step's `diagnostics` and fibre 0's states `fibre0` ([`Self::change`]); a metric
    /// too short to say is left out.
    pub fn changes(
        &self,
        end_time: f64,
        diagnostics: &[(String, f64)],
        fibre0: &[cosim::BeadState],
    ) -> BTreeMap<String, Change> {
        let points = centres(fibre0);
        self.samples
            .keys()
            .filter_map(|m| {
                let end = self.value_of(m, diagnostics, points.as_deref());
                Some((m.clone(), self.change(m, end_time, end)?))
            })
            .collect()
    }

    /// The change of `metric`'s quantity from the last sample at or before
    /// `(1 - LAST_PART) end_time` to its value `end` at `end_time`; `None` without such a
    /// sample (a run too short to say) or without a value at the end.
    pub fn change(&self, metric: &str, end_time: f64, end: Option<f64>) -> Option<Change> {
        let measure = measure(metric);
        let relative = measure == Measure::Relative;
        let end = end.filter(|e| e.is_finite() && (!relative || *e != 0.0))?;
        let cut = (1.0 - LAST_PART) * end_time;
        let &(from_time, from) = self
            .samples
            .get(metric)?
            .iter()
            .rev()
            .find(|(t, _)| *t <= cut && *t > 0.0)?;
        let scale = if relative { end.abs() } else { 1.0 };
        let half = 0.5 * (from_time + end_time);
        let remaining = self.samples[metric]
            .iter()
            .rev()
            .find(|(t, _)| *t <= half && *t > from_time)
            .and_then(|&mid| exponential_remainder([(from_time, from), mid, (end_time, end)]))
            .map(|r| r / scale);
        Some(Change {
            amount: (end - from).abs() / scale,
            measure,
            from_time,
            end_time,
            remaining,
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
                h.observe((step, steps, false), t, &diag(force(t)), &[]);
            }
            let end = steps as f64;
            let c = h.change("drag_coefficient", end, Some(force(end))).unwrap();
            let exact = (force(0.8 * end) - force(end)) / force(end);
            assert!((c.amount - exact).abs() < 1e-12, "{c:?} {exact}");
            assert_eq!(c.from_time, 0.8 * end);
            assert_eq!(c.warning("drag_coefficient").is_some(), warns, "{c:?}");
            // What is left of e^{-t / tau} at the end, relative to the force then; to the
            // round-off of differences of values near 1 (left = 2e-9 at 2000 steps).
            let left = (force(end) - 1.0) / force(end);
            let r = c.remaining.unwrap();
            assert!((r - left).abs() < 1e-6 * left, "{r} {left}");
        }
    }

    /// The exponential through three samples, equally spaced or not, gives back what is left
    /// of it; a straight line, an approach that speeds up, a turn back or no change give no
    /// estimate.
    #[test]
    fn the_exponential_remainder_is_exact_for_an_exponential() {
        let q = |t: f64| 3.0 - 2.0 * (-t / 7.0).exp();
        for ts in [[10.0, 15.0, 20.0], [10.0, 13.5, 20.0], [1.0, 30.0, 31.0]] {
            let r = exponential_remainder(ts.map(|t| (t, q(t)))).unwrap();
            let left = 3.0 - q(ts[2]);
            assert!((r - left).abs() < 1e-9 * left, "{ts:?}: {r} against {left}");
        }
        let none = |qs: [f64; 3]| exponential_remainder([(0.0, qs[0]), (1.0, qs[1]), (2.0, qs[2])]);
        assert_eq!(none([0.0, 1.0, 2.0]), None, "straight line");
        assert_eq!(none([0.0, 1.0, 3.0]), None, "speeding up");
        assert_eq!(none([0.0, 1.0, 0.5]), None, "turning back");
        assert_eq!(none([1.0, 1.0, 1.0]), None, "no change");
        // Aitken's delta-squared where the spacing is equal: |d2| r / (1 - r).
        let r = none([0.0, 1.0, 1.5]).unwrap();
        assert!((r - 0.5).abs() < 1e-12, "{r}");
    }

    /// An angle's change is in degrees, against STEADY_DEGREES; a quantity reported only at
    /// logged steps is sampled there.
    #[test]
    fn an_angle_is_steady_within_half_a_degree() {
        let mut h = SteadyHistory::for_metrics(&["contact_angle_deg".into()]);
        let d = |a: f64| vec![("contact_angle_deg".to_string(), a)];
        // 1000 steps: samples every 5 steps; logged every 500 (also on the stride).
        for step in 1..=1000_u64 {
            let logged = step % 500 == 0;
            h.observe(
                (step, 1000, logged),
                step as f64,
                &d(90.0 - 0.004 * step as f64),
                &[],
            );
        }
        let c = h.change("contact_angle_deg", 1000.0, Some(86.0)).unwrap();
        assert!(
            c.measure == Measure::Degrees && (c.amount - 0.8).abs() < 1e-9,
            "{c:?}"
        );
        assert!(c.exceeds() && c.words() == "0.80 deg");
        let still = h.change("contact_angle_deg", 1000.0, Some(86.6)).unwrap();
        assert!(!still.exceeds(), "{still:?}");
        // A diagnostic of logged steps only: sampled at those, off the stride.
        let mut h = SteadyHistory::for_metrics(&["surface_tension".into()]);
        let e = vec![("free_energy".to_string(), 2.0)];
        h.observe((333, 1000, true), 333.0, &e, &[]);
        h.observe((334, 1000, false), 334.0, &[], &[]);
        assert_eq!(h.samples["surface_tension"], vec![(333.0, 2.0)]);
    }

    /// An interface metric is read from fibre 0's bead centres at every sample, by the same
    /// code as the metric (`InterfaceGeometry::value`): a two-bead fibre whose tilt to a flat
    /// interface (normal y) relaxes as 10 e^{-t / tau} deg changes over the last fifth by
    /// 10 (e^{-0.8 T / tau} - e^{-T / tau}) deg, to round-off; a run of 2 tau warns, one of
    /// 20 tau does not. Without the geometry nothing is sampled.
    #[test]
    fn a_relaxing_tilt_is_read_from_the_bead_centres() {
        let text = "dimensions = 2\n[time]\ndt = 1.0\nsteps = 1\n\
                    [fluid.binary]\ninitial = \"flat\"\n\
                    [[fibre]]\nbead_radius = 1.0\n";
        let (scene, _, _) = crate::scene::from_text(text, "test", &[]).unwrap();
        let geometry = InterfaceGeometry::of(&scene, &[]);
        let tau = 100.0;
        let tilt = |t: f64| 10.0 * (-t / tau).exp();
        let beads = |t: f64| {
            let a = tilt(t).to_radians();
            [[0.0; 3], [a.cos(), a.sin(), 0.0]].map(|position| cosim::BeadState {
                position,
                ..Default::default()
            })
        };
        for (steps, warns) in [(200_u64, true), (2000, false)] {
            let metrics = ["final_tilt_deg".to_string()];
            let mut h = SteadyHistory::for_metrics(&metrics);
            h.set_geometry(geometry.clone());
            let mut bare = SteadyHistory::for_metrics(&metrics);
            for step in 1..=steps {
                let (t, sample) = (step as f64, (step, steps, step == steps));
                assert_eq!(h.reads_beads_at(sample), bare.reads_beads_at(sample));
                h.observe(sample, t, &[], &beads(t));
                bare.observe(sample, t, &[], &beads(t));
            }
            let end = steps as f64;
            let c = h.changes(end, &[], &beads(end))["final_tilt_deg"];
            let exact = tilt(0.8 * end) - tilt(end);
            assert!((c.amount - exact).abs() < 1e-9, "{c:?} {exact}");
            assert_eq!(c.measure, Measure::Degrees);
            assert_eq!(c.exceeds(), warns, "{c:?}");
            assert!(bare.samples["final_tilt_deg"].is_empty());
            assert!(bare.changes(end, &[], &beads(end)).is_empty());
        }
    }

    #[test]
    fn a_run_too_short_to_sample_says_nothing() {
        let mut h = SteadyHistory::for_metrics(&["drag_ratio".into()]);
        let d = vec![
            ("total_impulse_x".to_string(), 2.0),
            ("mean_velocity_x".to_string(), 4.0),
        ];
        h.observe((1, 1, false), 0.7, &d, &[]);
        assert_eq!(h.samples["drag_ratio"], vec![(0.7, 0.5)]);
        assert_eq!(h.change("drag_ratio", 0.7, Some(0.5)), None);
        assert_eq!(h.change("drag_coefficient", 0.7, Some(0.5)), None);
    }
}
