//! Fibre 0's orbit as files next to the run's log, for a run that tracked its trajectory
//! (any orbit or period metric) in a wall shear:
//!
//! - `orbit.csv`: one row per sample (every step, thinned to at most [`MAX_ROWS`] rows): time,
//!   `gamma t`, the unwrapped angle and the direction (degrees), the angular velocity over
//!   the shear rate, and the end-to-end distance over the contour length;
//! - `orbit.png`: S2023 Fig. 5a (the angular velocity against the direction, without the
//!   first and last samples, with eq. 19 for the fitted and the geometric aspect ratio) above
//!   the direction and the end-to-end distance against `gamma t`, and snapshots of the
//!   fibre's shape along `gamma t` (S2023 Fig. 7a).
//!
//! Angles follow [`crate::orbit`]: from +x, counter-clockwise positive, so the shear turns
//! the fibre towards negative angles and `omega / gamma` is negative.

use crate::orbit::{angular_velocity, direction_deg, OrientationSeries};
use std::fmt::Write as _;
use std::path::Path;

/// The files [`write()`] writes.
pub const FILES: [&str; 2] = ["orbit.csv", "orbit.png"];

/// Most rows `orbit.csv` holds: longer runs keep every k-th sample (the angular velocity is
/// taken from all samples first).
pub const MAX_ROWS: usize = 20_000;

/// The orbit, sample by sample, in the units of the files.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OrbitRows {
    /// Time (the scene's units).
    pub time: Vec<f64>,
    /// Time times the shear rate.
    pub gamma_t: Vec<f64>,
    /// Angle of the end-to-end vector, unwrapped (degrees).
    pub theta_deg: Vec<f64>,
    /// The same, as a direction in (-90, 90] degrees (S2023 Fig. 5a's abscissa).
    pub direction_deg: Vec<f64>,
    /// `(d theta / dt) / gamma`; S2023 eq. 19 gives `((A cos 2 theta) - 1) / 2`.
    pub omega_over_gamma: Vec<f64>,
    /// End-to-end distance over the contour through the bead centres.
    pub end_to_end: Vec<f64>,
}

impl OrbitRows {
    /// Rows of `s` in a shear of rate `gamma` (> 0), every `stride`-th sample plus the last.
    pub fn new(s: &OrientationSeries, gamma: f64, stride: usize) -> Self {
        let n = s
            .times
            .len()
            .min(s.theta.len())
            .min(s.end_to_end_ratio.len());
        let omega = angular_velocity(&s.times[..n], &s.theta[..n]);
        let stride = stride.max(1);
        let mut keep: Vec<usize> = (0..n).step_by(stride).collect();
        if n > 0 && keep.last() != Some(&(n - 1)) {
            keep.push(n - 1);
        }
        let mut r = OrbitRows::default();
        for i in keep {
            r.time.push(s.times[i]);
            r.gamma_t.push(gamma * s.times[i]);
            r.theta_deg.push(s.theta[i].to_degrees());
            r.direction_deg.push(direction_deg(s.theta[i]));
            r.omega_over_gamma.push(omega[i] / gamma);
            r.end_to_end.push(s.end_to_end_ratio[i]);
        }
        r
    }

    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// The points of S2023 Fig. 5a, `(direction, omega / gamma)`, without the first and the
    /// last sample: their angular velocity is a one-sided difference, and the first is the
    /// fibre's start from rest (0 where eq. 19 may ask for -1), not a point of the orbit.
    /// The Jeffery fit leaves out the same two (`crate::orbit`).
    pub fn orbit_points(&self) -> Vec<(f64, f64)> {
        let n = self.len();
        (1..n.saturating_sub(1))
            .map(|i| (self.direction_deg[i], self.omega_over_gamma[i]))
            .filter(|(_, w)| w.is_finite())
            .collect()
    }

    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// The rows as CSV with a header line; full precision (Rust's shortest round-trip form).
    pub fn csv(&self) -> String {
        let mut out = String::from(
            "time,gamma_t,theta_deg,direction_deg,omega_over_gamma,end_to_end_over_contour\n",
        );
        for i in 0..self.len() {
            let _ = writeln!(
                out,
                "{},{},{},{},{},{}",
                self.time[i],
                self.gamma_t[i],
                self.theta_deg[i],
                self.direction_deg[i],
                self.omega_over_gamma[i],
                self.end_to_end[i]
            );
        }
        out
    }
}

/// S2023 eq. 19 over the shear rate: `omega / gamma = ((1 - r^2)/(1 + r^2) cos 2 theta - 1) / 2`.
pub fn jeffery_omega_over_gamma(aspect_ratio: f64, theta_deg: f64) -> f64 {
    let r2 = aspect_ratio * aspect_ratio;
    0.5 * ((1.0 - r2) / (1.0 + r2) * (2.0 * theta_deg.to_radians()).cos() - 1.0)
}

/// Write `orbit.csv` and `orbit.png` into `dir` for fibre 0 of `beads` beads in a shear of
/// rate `gamma`, with snapshots of its shape (time, bead centres) drawn along `gamma t`;
/// `title` heads the plot, `reference` (`r_c` and where it comes from) is drawn next to the
/// fit. Returns the names of the files written.
pub fn write(
    dir: &Path,
    series: &OrientationSeries,
    shapes: &[(f64, Vec<[f64; 2]>)],
    beads: usize,
    gamma: f64,
    title: &str,
    reference: Option<(f64, &str)>,
) -> Result<Vec<String>, String> {
    if !(gamma.is_finite() && gamma > 0.0) {
        return Err(format!(
            "the orbit files need a positive shear rate, got {gamma}"
        ));
    }
    let n = series.times.len();
    if n < 3 {
        return Err(format!("the orbit files need at least 3 samples, got {n}"));
    }
    let rows = OrbitRows::new(series, gamma, n.div_ceil(MAX_ROWS));
    let csv = dir.join(FILES[0]);
    std::fs::write(&csv, rows.csv()).map_err(|e| format!("cannot write {}: {e}", csv.display()))?;
    // The fit is that of the metric `effective_aspect_ratio` (all samples, not the thinned rows).
    let fit = crate::orbit::analyse_series(series, beads, gamma)
        .ok()
        .and_then(|a| a.jeffery_fit)
        .map(|f| f.effective_aspect_ratio);
    let png = dir.join(FILES[1]);
    let shapes: Vec<(f64, Vec<[f64; 2]>)> =
        shapes.iter().map(|(t, c)| (gamma * t, c.clone())).collect();
    crate::plot::orbit(
        &png,
        title,
        &rows,
        &shapes,
        fit,
        1.0 / beads.max(1) as f64,
        reference,
    )?;
    Ok(FILES.map(String::from).to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// An exact Jeffery orbit (S2023 eq. 19 integrated: tan theta = -r tan(gamma t r / (1 + r^2))
    /// from theta = 0 at t = 0) gives back eq. 19's angular velocity to the second-order
    /// finite difference's accuracy, and the rows keep every sample below MAX_ROWS.
    #[test]
    fn an_exact_jeffery_orbit_gives_eq_19_back() {
        let (gamma, r) = (0.01, 0.2);
        let n = 4001;
        let t_end = PI * (r + 1.0 / r) / gamma; // one half-turn
        let mut s = OrientationSeries::default();
        for i in 0..n {
            let t = t_end * i as f64 / (n - 1) as f64;
            let phase = gamma * t * r / (1.0 + r * r);
            // Unwrapped: continued through the pass at -90 deg.
            let mut theta = -(r * phase.tan()).atan();
            if let Some(&prev) = s.theta.last() {
                theta += PI * ((prev - theta) / PI).round();
            }
            s.times.push(t);
            s.theta.push(theta);
            s.end_to_end_ratio.push(1.0);
        }
        let rows = OrbitRows::new(&s, gamma, 1);
        assert_eq!(rows.len(), n);
        let worst = (1..n - 1)
            .map(|i| {
                (rows.omega_over_gamma[i] - jeffery_omega_over_gamma(r, rows.theta_deg[i])).abs()
            })
            .fold(0.0, f64::max);
        // Eq. 19's |omega| / gamma ranges over [r^2/(1+r^2), 1/(1+r^2)] = [0.038, 0.96]; the
        // second-order differences are off by 5e-6 at 4000 samples a half-turn.
        assert!(worst < 2e-5, "largest error in omega / gamma: {worst:e}");
        assert!((rows.gamma_t[n - 1] - PI * (r + 1.0 / r)).abs() < 1e-12);
        assert!(rows.direction_deg.iter().all(|d| *d > -90.0 && *d <= 90.0));
    }

    #[test]
    fn thinned_rows_keep_the_last_sample_and_the_csv_has_one_line_each() {
        let mut s = OrientationSeries::default();
        for i in 0..10 {
            s.times.push(i as f64);
            s.theta.push(-0.01 * i as f64);
            s.end_to_end_ratio.push(1.0);
        }
        let rows = OrbitRows::new(&s, 0.5, 4);
        assert_eq!(rows.time, vec![0.0, 4.0, 8.0, 9.0]);
        assert!((rows.omega_over_gamma[1] + 0.02).abs() < 1e-12);
        // Fig. 5a's points leave out the first and the last sample.
        let points = rows.orbit_points();
        assert_eq!(points.len(), 2);
        assert_eq!(points[0], (rows.direction_deg[1], rows.omega_over_gamma[1]));
        let csv = rows.csv();
        assert_eq!(csv.lines().count(), 5);
        assert!(csv.starts_with("time,gamma_t,theta_deg"));
    }
}
