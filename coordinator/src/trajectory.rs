//! The history a run keeps for its metrics: fibre 0's orientation step by step (the orbit
//! metrics) and the steady metrics' quantities ([`crate::steady_watch`]).

/// Angle of fibre 0's end-to-end vector in the x-y plane (unwrapped, radians) and its length.
#[derive(Debug, Default, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Trajectory {
    pub times: Vec<f64>,
    pub angles: Vec<f64>,
    pub end_to_end: Vec<f64>,
    /// Contour length: the polyline through fibre 0's bead centres.
    pub contour: Vec<f64>,
    /// Bend: the largest distance of a bead centre of fibre 0 from its end-to-end chord
    /// (grid spacings). Absent from checkpoints written before it was kept.
    #[serde(default)]
    pub sag: Vec<f64>,
    /// A few snapshots of fibre 0's shape: time and bead centres in the x-y plane, for the
    /// orbit plot (`orbit_report`). Absent from checkpoints written before they were kept.
    #[serde(default)]
    pub shapes: Vec<(f64, Vec<[f64; 2]>)>,
    /// What the steady metrics read, sampled over the run. Absent from checkpoints written
    /// before it was kept (the change is then measured from the resume on).
    #[serde(default)]
    pub steady: crate::steady_watch::SteadyHistory,
}

/// Shape snapshots the orbit plot shows over a run.
pub const SHAPE_SNAPSHOTS: u64 = 12;

impl Trajectory {
    /// Record fibre 0 (its first `beads` states) at `time`.
    pub fn push(&mut self, time: f64, states: &[cosim::BeadState], beads: usize) {
        if beads < 2 || states.len() < beads {
            return;
        }
        let (a, b) = (states[0].position, states[beads - 1].position);
        let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let mut angle = d[1].atan2(d[0]);
        if let Some(&prev) = self.angles.last() {
            // Unwrap: the end-to-end vector turns by much less than pi per step.
            let pi2 = 2.0 * std::f64::consts::PI;
            angle += pi2 * ((prev - angle) / pi2).round();
        }
        self.times.push(time);
        self.angles.push(angle);
        self.end_to_end
            .push((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
        let contour = states[..beads]
            .windows(2)
            .map(|w| {
                let (p, q) = (w[0].position, w[1].position);
                ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2)).sqrt()
            })
            .sum();
        self.contour.push(contour);
        self.sag.push(crate::metrics::chord_sag(
            a,
            b,
            states[..beads].iter().map(|s| s.position),
        ));
    }

    /// Keep fibre 0's shape (its first `beads` states) at `time`.
    pub fn push_shape(&mut self, time: f64, states: &[cosim::BeadState], beads: usize) {
        if states.len() >= beads {
            let centres = states[..beads]
                .iter()
                .map(|s| [s.position[0], s.position[1]])
                .collect();
            self.shapes.push((time, centres));
        }
    }

    /// The history in the orbit analysis' terms: the unwrapped angle, and the end-to-end
    /// distance over the contour length at the same sample (1 for a straight fibre whatever
    /// its bonds' strain, S2023 section IV C).
    pub fn orientation_series(&self) -> crate::orbit::OrientationSeries {
        crate::orbit::OrientationSeries {
            times: self.times.clone(),
            theta: self.angles.clone(),
            end_to_end_ratio: self
                .end_to_end
                .iter()
                .zip(&self.contour)
                .map(|(e, c)| e / c)
                .collect(),
        }
    }

    /// Times at which the fibre passes through the vertical (angle = pi/2 + k pi), by linear
    /// interpolation between samples.
    pub fn vertical_crossings(&self) -> Vec<f64> {
        let pi = std::f64::consts::PI;
        let k = |a: f64| ((a - 0.5 * pi) / pi).floor();
        let mut out = Vec::new();
        for i in 1..self.angles.len() {
            let (a0, a1) = (self.angles[i - 1], self.angles[i]);
            if k(a0) != k(a1) {
                let target = 0.5 * pi + pi * k(a0).max(k(a1));
                let s = (target - a0) / (a1 - a0);
                out.push(self.times[i - 1] + s * (self.times[i] - self.times[i - 1]));
            }
        }
        out
    }

    /// Full Jeffery period (a rotation by 2 pi; the chain looks the same after pi, so it is
    /// twice the mean time between successive passes through the vertical).
    pub fn period(&self) -> Option<f64> {
        let c = self.vertical_crossings();
        (c.len() >= 2).then(|| 2.0 * (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64)
    }

    /// Time for fibre 0's bend ([`Trajectory::sag`]) to fall to 1/e of its initial value:
    /// the first crossing, interpolated in log(sag) between samples. Err when the fibre
    /// starts straight, or when the bend has not fallen that far by the end of the run.
    pub fn bend_relaxation_time(&self) -> Result<f64, String> {
        if self.times.is_empty() {
            return Err("needs a fibre of at least 2 beads".into());
        }
        if self.sag.len() != self.times.len() {
            return Err("no bend history (a run resumed from a checkpoint written \
                        before it was kept)"
                .into());
        }
        let (s0, t0) = (self.sag[0], self.times[0]);
        let e2e0 = self.end_to_end[0];
        if s0 <= 1e-6 * e2e0 {
            return Err(format!(
                "fibre 0 starts straight (bend {}); give it fibre.0.initial_bend",
                cosim::scene_keys::Sig(s0)
            ));
        }
        let target = s0 / std::f64::consts::E;
        for i in 1..self.sag.len() {
            let (a, b) = (self.sag[i - 1], self.sag[i]);
            if b <= target {
                let (ta, tb) = (self.times[i - 1], self.times[i]);
                // Interpolate log(sag), linear in time for an exponential decay.
                let s = if b > 0.0 && a > b {
                    (a.ln() - target.ln()) / (a.ln() - b.ln())
                } else {
                    1.0
                };
                return Ok(ta + s * (tb - ta) - t0);
            }
        }
        Err(format!(
            "the bend fell from {s0:.4} to {:.4}, not to 1/e of its start; run longer",
            self.sag[self.sag.len() - 1]
        ))
    }

    /// Smallest end-to-end distance over the run, over the initial one.
    pub fn min_end_to_end_ratio(&self) -> Option<f64> {
        let first = *self.end_to_end.first()?;
        Some(
            self.end_to_end
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min)
                / first,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cosim::BeadState;

    /// A rod turning at a steady rate: period 2 pi / rate, whatever the sampling.
    #[test]
    fn steady_rotation_gives_its_period() {
        let rate = -0.37;
        let mut t = Trajectory::default();
        for i in 0..4000 {
            let time = i as f64 * 0.01;
            let a = 0.2 + rate * time;
            let s = [
                BeadState::at_rest([0.0; 3]),
                BeadState::at_rest([a.cos(), a.sin(), 0.0]),
            ];
            t.push(time, &s, 2);
        }
        let p = t.period().unwrap();
        assert!(
            (p - 2.0 * std::f64::consts::PI / rate.abs()).abs() < 1e-6,
            "{p}"
        );
        assert!((t.min_end_to_end_ratio().unwrap() - 1.0).abs() < 1e-12);
        assert!(t
            .bend_relaxation_time()
            .unwrap_err()
            .contains("starts straight"));
        let none = Trajectory::default().bend_relaxation_time().unwrap_err();
        assert!(none.contains("needs a fibre"), "{none}");
    }

    /// A three-bead fibre whose middle bead decays as exp(-t / tau) off the chord, sampled
    /// coarsely: the 1/e time comes back exactly (log-linear interpolation), and a run cut
    /// before it says so.
    #[test]
    fn exponential_bend_gives_its_relaxation_time() {
        let tau = 37.5;
        let mut t = Trajectory::default();
        for i in 0..=20 {
            let time = 5.0 + 7.0 * i as f64;
            let h = 2.0 * (-(time - 5.0) / tau).exp();
            let s = [
                BeadState::at_rest([0.0, 0.0, 0.0]),
                BeadState::at_rest([1.0, h, 0.0]),
                BeadState::at_rest([2.0, 0.0, 0.0]),
            ];
            t.push(time, &s, 3);
            if i == 4 {
                let err = t.bend_relaxation_time().unwrap_err();
                assert!(err.contains("run longer"), "{err}");
            }
        }
        assert!((t.sag[0] - 2.0).abs() < 1e-12);
        let got = t.bend_relaxation_time().unwrap();
        assert!((got - tau).abs() < 1e-9 * tau, "{got}");
    }
}
