//! Orbit analysis of one fibre in simple shear `u = gamma y e_x` (S2023 section IV): the
//! orientation history, the tumbling period, a fit of Jeffery's angular velocity (S2023
//! eq. 19) and a classification into the orbits of S2023 section IV C.
//!
//! Conventions. The fibre lies in the x-y plane (z is ignored). Its angle `theta` is that of
//! the end-to-end vector (first bead to last) from +x, counter-clockwise positive, as in
//! S2023 ("the fiber orients to the angle around theta = 45 deg relative to the +x
//! direction"); a shear with `gamma > 0` turns it clockwise, so `theta` decreases. A fibre
//! looks the same after half a turn, so `theta` is only defined modulo 180 deg and is
//! unwrapped continuously over time. Times are in the trajectory's units, rates in the
//! inverse of them, angles in degrees in the public results (radians inside).
//!
//! Why the end-to-end vector by default: S2023 describes the shapes by the end-to-end
//! distance, and for the point-symmetric S-shapes of S2023 section IV C the end-to-end vector
//! passes through the centre, so it is the fibre's natural direction; the coordinator's
//! trajectory uses it too. The principal axis of the bead cloud ([`Orientation::PrincipalAxis`])
//! agrees with it for a straight fibre and is offered for strongly curled shapes, where the
//! end-to-end vector is short and follows the ends' wiggles.

use cosim::scene_keys::Sig;
use std::f64::consts::PI;

/// A fibre counts as folded when its end-to-end distance falls below this fraction of its
/// contour length. S2023 section IV C: rigid fibres tumble "without any visible
/// deformation", whereas in an S-turn the end-to-end distance falls "to ~10 % smaller than
/// l_c"; 0.95 sits half-way, so any fold at least half as deep as S2023's S-turn counts.
pub const FOLD_RATIO: f64 = 0.95;

/// A folded fibre counts as straightened again when its end-to-end distance comes back
/// above this fraction of its contour length (S2023 section IV C: in the S-turn "the fiber is
/// straightened again"). Kept above [`FOLD_RATIO`] so that noise near one threshold cannot
/// count as a fold followed by a straightening.
pub const STRAIGHT_RATIO: f64 = 0.98;

/// Fraction of the run, at its end, over which the fibre is tested for being stuck (S2023
/// section IV B: a stuck fibre "becomes stationary in the steady-state Couette flow", so the
/// test looks at the late, steady part of the run only).
pub const STUCK_TAIL_FRACTION: f64 = 0.2;

/// The fibre is stuck when its mean rotation rate over the tail is below this fraction of
/// the slowest rate a freely tumbling fibre ever has: by S2023 eq. 19, at theta = 0,
/// `|omega| = gamma r_c^2 / (1 + r_c^2)`, with the geometric aspect ratio `r_c = 1/N`
/// (S2023 eq. 18). A Jeffery orbit never turns slower than that at any instant, so a mean
/// rate four times smaller cannot be a tumbling fibre (of at least that aspect ratio).
pub const STUCK_RATE_FRACTION: f64 = 0.25;

/// A stuck fibre whose rate over the last half of the tail is still at least this fraction of
/// the rate over the first half (same sense, and above a tenth of the stuck threshold) is
/// not settling at an angle but creeping steadily: the analysis says so in its reason, since
/// a longer run may see it turn on. The label stays `stuck` (S2023's test is the rate).
pub const CREEP_TREND: f64 = 0.8;

/// How the fibre's direction is taken from its beads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Orientation {
    /// The end-to-end vector, first bead to last (S2023; the default).
    #[default]
    EndToEnd,
    /// The major axis of the beads' gyration tensor in the x-y plane.
    PrincipalAxis,
}

/// The orbits of S2023 section IV C (Fig. 10).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OrbitKind {
    /// Tumbles without visible deformation (S2023 regime i).
    Jeffery,
    /// Tumbles, bends to an S and is straightened again each turn (regime ii).
    STurn,
    /// Tumbles while staying folded in an S (regime iii).
    SCoiled,
    /// Stops rotating (Jeffery-stuck or S-stuck, regimes iv and v).
    Stuck,
}

impl OrbitKind {
    /// Label used in summaries: `jeffery`, `s-turn`, `s-coiled` or `stuck`.
    pub fn as_str(self) -> &'static str {
        match self {
            OrbitKind::Jeffery => "jeffery",
            OrbitKind::STurn => "s-turn",
            OrbitKind::SCoiled => "s-coiled",
            OrbitKind::Stuck => "stuck",
        }
    }
}

/// Why a trajectory cannot be analysed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OrbitError {
    #[error("a fibre needs at least 2 beads, sample {sample} has {beads}")]
    TooFewBeads { sample: usize, beads: usize },
    #[error("sample {sample} has {found} beads, the first one has {expected}")]
    BeadCountChanges {
        sample: usize,
        expected: usize,
        found: usize,
    },
    #[error("the orbit needs at least 3 samples, got {0}")]
    TooFewSamples(usize),
    #[error("times must increase strictly; they do not at sample {0}")]
    TimeNotIncreasing(usize),
    #[error("sample {0} holds a value that is not finite")]
    NotFinite(usize),
    #[error("the fibre has no direction at sample {0} (its beads coincide or form a ring)")]
    Degenerate(usize),
    #[error("the shear rate must be finite and positive, got {0}")]
    BadShearRate(f64),
}

/// The orientation history of one fibre.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OrientationSeries {
    /// Sample times (trajectory units).
    pub times: Vec<f64>,
    /// Fibre angle from +x, counter-clockwise positive, unwrapped (radians).
    pub theta: Vec<f64>,
    /// End-to-end distance over the contour length (the polyline through the bead centres
    /// at the same sample, so a straight fibre gives exactly 1 whatever its springs' strain).
    pub end_to_end_ratio: Vec<f64>,
}

/// One half-turn: the time between two successive passes through the reference angle
/// (90 deg modulo 180 deg), i.e. a rotation by 180 deg.
#[derive(Debug, Clone, PartialEq)]
pub struct HalfTurn {
    /// Start and end times (trajectory units), interpolated between samples.
    pub start: f64,
    pub end: f64,
    /// Smallest and largest end-to-end distance over contour length during it.
    pub min_ratio: f64,
    pub max_ratio: f64,
    /// Fibre angle where the end-to-end distance is smallest, degrees in (-90, 90].
    pub angle_at_min_deg: f64,
    /// Angle (degrees in (-90, 90]) where a folded fibre was straightened again during the
    /// half-turn, if it was (S2023 section IV C: around 45 deg in an S-turn).
    pub straightened_at_deg: Option<f64>,
}

/// Least-squares fit of S2023 eq. 19 to the measured angular velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct JefferyFit {
    /// `r_c` with the imposed shear rate: `omega = (gamma/2) (A cos 2 theta - 1)`,
    /// `A = (1 - r_c^2)/(1 + r_c^2)` fitted by linear least squares on `A`.
    pub effective_aspect_ratio: f64,
    /// The fitted `A`.
    pub coefficient: f64,
    /// Root mean square of the residual over `gamma / 2` (0 for an exact Jeffery orbit).
    pub rms_residual: f64,
    /// `r_c` from a free fit `omega = a cos 2 theta + b` (`A = -a/b`), which does not use
    /// the imposed shear rate; it differs from `effective_aspect_ratio` when the fibre feels
    /// another rotation rate than `gamma/2` (confinement, inertia).
    pub free_aspect_ratio: Option<f64>,
    /// The shear rate the free fit implies, `-2 b` (inverse time units).
    pub free_shear_rate: Option<f64>,
    /// Samples used.
    pub samples: usize,
}

/// Everything the orbit analysis found, with the numbers each decision rests on.
#[derive(Debug, Clone, PartialEq)]
pub struct OrbitAnalysis {
    /// The orbit (S2023 section IV C).
    pub kind: OrbitKind,
    /// For a stuck fibre: `jeffery-stuck` if straight at the end, `s-stuck` if folded.
    pub stuck_kind: Option<&'static str>,
    /// For a stuck fibre: its final angle, degrees in (-90, 90] (S2023 reports 4.6 to 20.4).
    pub stuck_angle_deg: Option<f64>,
    /// Net rotation over the run, degrees (negative: clockwise, as the shear drives it).
    pub net_rotation_deg: f64,
    /// Mean rotation rate over the last [`STUCK_TAIL_FRACTION`] of the run and the stuck
    /// threshold it was compared with (degrees per time unit).
    pub tail_rate_deg: f64,
    pub stuck_threshold_deg: f64,
    /// Rate over the last half of that tail over the rate over its first half (`None` if the
    /// first is zero): near 0 for a fibre settling at an angle, near 1 for a steady creep.
    pub tail_rate_trend: Option<f64>,
    /// Complete half-turns (rotations by 180 deg between passes through 90 deg).
    pub half_turns: Vec<HalfTurn>,
    /// S2023's tumbling period T, the mean time to rotate 180 deg over the complete
    /// half-turns; `None` without one. (A full Jeffery period, 360 deg, is twice this.)
    pub half_turn_period: Option<f64>,
    /// `gamma T` for that T (S2023 Fig. 5, 8 normalisation).
    pub period_gamma: Option<f64>,
    /// `r_c` from the period: an exact Jeffery orbit turns by 180 deg in
    /// `gamma T = pi (r + 1/r)`, `r = 1/r_c` (S2023 eq. 19 integrated).
    pub period_aspect_ratio: Option<f64>,
    /// Fit of S2023 eq. 19 (`None` for a stuck fibre, fewer than 3 interior samples, or a
    /// fitted coefficient outside (-1, 1], which no aspect ratio gives).
    pub jeffery_fit: Option<JefferyFit>,
    /// Smallest, largest and last end-to-end distance over contour length.
    pub min_ratio: f64,
    pub max_ratio: f64,
    pub final_ratio: f64,
    /// Times the fibre folded (below [`FOLD_RATIO`]) and was straightened again (above
    /// [`STRAIGHT_RATIO`]).
    pub folds: usize,
    pub straightenings: usize,
    /// Rotation (degrees, unsigned) during the last folded stretch.
    pub last_fold_rotation_deg: Option<f64>,
    /// The rule that decided `kind`, in words.
    pub reason: String,
}

/// Mean of directions (degrees, modulo 180): the angle of the mean of the doubled-angle unit
/// vectors, halved, so that -89 and +89 deg average to 90, not 0. `None` without any.
fn mean_direction_deg(angles: impl Iterator<Item = f64>) -> Option<f64> {
    let (mut s, mut c, mut n) = (0.0, 0.0, 0usize);
    for a in angles {
        let t = 2.0 * a.to_radians();
        s += t.sin();
        c += t.cos();
        n += 1;
    }
    (n > 0).then(|| direction_deg(0.5 * s.atan2(c)))
}

impl OrbitAnalysis {
    /// Mean direction (degrees) at which the end-to-end distance is smallest, over the
    /// half-turns in which the fibre folded (below [`FOLD_RATIO`]); `None` if it never did.
    pub fn fold_angle_deg(&self) -> Option<f64> {
        mean_direction_deg(
            self.half_turns
                .iter()
                .filter(|h| h.min_ratio < FOLD_RATIO)
                .map(|h| h.angle_at_min_deg),
        )
    }

    /// Mean direction (degrees) at which a folded fibre was straightened again, over the
    /// half-turns in which that happened (S2023 section IV C: near 45 deg in an S-turn).
    pub fn straightened_at_deg(&self) -> Option<f64> {
        mean_direction_deg(self.half_turns.iter().filter_map(|h| h.straightened_at_deg))
    }

    /// Named scalars for a summary (`effective_aspect_ratio`, `stuck_angle_deg`, ...).
    pub fn scalars(&self) -> Vec<(&'static str, f64)> {
        let mut out = vec![
            ("net_rotation_deg", self.net_rotation_deg),
            ("half_turns", self.half_turns.len() as f64),
            ("min_end_to_end_over_contour", self.min_ratio),
            ("final_end_to_end_over_contour", self.final_ratio),
        ];
        let optional = [
            ("half_turn_period", self.half_turn_period),
            ("half_turn_period_gamma", self.period_gamma),
            ("period_aspect_ratio", self.period_aspect_ratio),
            ("stuck_angle_deg", self.stuck_angle_deg),
            (
                "tail_rate_trend",
                self.tail_rate_trend
                    .filter(|_| self.kind == OrbitKind::Stuck),
            ),
            ("fold_angle_deg", self.fold_angle_deg()),
            ("straightened_at_deg", self.straightened_at_deg()),
            (
                "effective_aspect_ratio",
                self.jeffery_fit.as_ref().map(|f| f.effective_aspect_ratio),
            ),
        ];
        out.extend(optional.iter().filter_map(|(k, v)| v.map(|v| (*k, v))));
        out
    }
}

/// Reduce an angle (radians) to degrees in (-90, 90]: the fibre's direction modulo 180 deg.
pub fn direction_deg(theta: f64) -> f64 {
    let d = theta.to_degrees().rem_euclid(180.0);
    if d > 90.0 {
        d - 180.0
    } else {
        d
    }
}

/// Angle (radians, in (-pi, pi]) and contour length of one sample's beads.
fn angle_and_lengths(p: &[[f64; 3]], how: Orientation) -> (f64, f64, f64) {
    let n = p.len();
    let (dx, dy) = (p[n - 1][0] - p[0][0], p[n - 1][1] - p[0][1]);
    let contour: f64 = p
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    let angle = match how {
        Orientation::EndToEnd => dy.atan2(dx),
        Orientation::PrincipalAxis => {
            let (mx, my) = p.iter().fold((0.0, 0.0), |(a, b), q| (a + q[0], b + q[1]));
            let (mx, my) = (mx / n as f64, my / n as f64);
            let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
            for q in p {
                let (x, y) = (q[0] - mx, q[1] - my);
                sxx += x * x;
                sxy += x * y;
                syy += y * y;
            }
            // Equal eigenvalues: no major axis.
            if (sxx - syy).hypot(2.0 * sxy) <= 1e-12 * (sxx + syy) {
                f64::NAN
            } else {
                0.5 * (2.0 * sxy).atan2(sxx - syy)
            }
        }
    };
    (angle, dx.hypot(dy), contour)
}

/// The orientation history of a fibre from `(time, bead positions)` samples.
///
/// The angle is unwrapped modulo 180 deg: between two samples the fibre is assumed to turn
/// by less than 90 deg, so the history is continuous across the branch cut of `atan2` and
/// across a reversal of the beads' order.
pub fn orientation_series<P: AsRef<[[f64; 3]]>>(
    samples: &[(f64, P)],
    how: Orientation,
) -> Result<OrientationSeries, OrbitError> {
    if samples.len() < 3 {
        return Err(OrbitError::TooFewSamples(samples.len()));
    }
    let expected = samples[0].1.as_ref().len();
    let mut s = OrientationSeries::default();
    for (i, (time, beads)) in samples.iter().enumerate() {
        let p = beads.as_ref();
        if p.len() < 2 {
            return Err(OrbitError::TooFewBeads {
                sample: i,
                beads: p.len(),
            });
        }
        if p.len() != expected {
            return Err(OrbitError::BeadCountChanges {
                sample: i,
                expected,
                found: p.len(),
            });
        }
        if !time.is_finite() || p.iter().flatten().any(|x| !x.is_finite()) {
            return Err(OrbitError::NotFinite(i));
        }
        if s.times.last().is_some_and(|&t| *time <= t) {
            return Err(OrbitError::TimeNotIncreasing(i));
        }
        let (mut angle, e2e, contour) = angle_and_lengths(p, how);
        if contour <= 0.0 || !angle.is_finite() || e2e <= 1e-9 * contour {
            return Err(OrbitError::Degenerate(i));
        }
        if let Some(&prev) = s.theta.last() {
            angle += PI * ((prev - angle) / PI).round();
        }
        s.times.push(*time);
        s.theta.push(angle);
        s.end_to_end_ratio.push(e2e / contour);
    }
    Ok(s)
}

/// Angular velocity `d theta / dt` at each sample (radians per time unit): second-order
/// central differences on the (possibly uneven) time grid, one-sided at the two ends.
pub fn angular_velocity(times: &[f64], theta: &[f64]) -> Vec<f64> {
    let n = times.len().min(theta.len());
    if n < 2 {
        return vec![0.0; n];
    }
    (0..n)
        .map(|i| {
            if i == 0 || i == n - 1 {
                let (a, b) = if i == 0 { (0, 1) } else { (n - 2, n - 1) };
                return (theta[b] - theta[a]) / (times[b] - times[a]);
            }
            let (h0, h1) = (times[i] - times[i - 1], times[i + 1] - times[i]);
            (h0 * h0 * theta[i + 1] - h1 * h1 * theta[i - 1] - (h0 * h0 - h1 * h1) * theta[i])
                / (h0 * h1 * (h0 + h1))
        })
        .collect()
}

/// Times at which the fibre passes through the reference angle 90 deg (modulo 180 deg) in
/// the sense of its net rotation, interpolated linearly between samples. Only new levels
/// count, so jitter back and forth across one level is a single pass.
pub fn reference_crossings(times: &[f64], theta: &[f64]) -> Vec<f64> {
    let n = times.len().min(theta.len());
    if n < 2 {
        return Vec::new();
    }
    let sense = (theta[n - 1] - theta[0]).signum();
    // Level index: theta in [pi/2 + k pi, pi/2 + (k+1) pi), counted along the rotation.
    let level = |a: f64| (sense * (a - 0.5 * PI) / PI).floor();
    let mut reached = level(theta[0]);
    let mut out = Vec::new();
    for i in 1..n {
        let k = level(theta[i]);
        while k > reached {
            reached += 1.0;
            let target = 0.5 * PI + sense * reached * PI;
            let s = (target - theta[i - 1]) / (theta[i] - theta[i - 1]);
            out.push(times[i - 1] + s.clamp(0.0, 1.0) * (times[i] - times[i - 1]));
        }
    }
    out
}

/// `r_c` from the Jeffery coefficient `A = (1 - r_c^2)/(1 + r_c^2)`.
fn aspect_from_coefficient(a: f64) -> Option<f64> {
    (a > -1.0 && a <= 1.0).then(|| ((1.0 - a) / (1.0 + a)).sqrt())
}

/// Fit S2023 eq. 19 to the pairs `(theta, omega)`.
fn fit_jeffery(theta: &[f64], omega: &[f64], gamma: f64) -> Option<JefferyFit> {
    let (mut scc, mut scy, mut sc, mut sw, mut n) = (0.0, 0.0, 0.0, 0.0, 0usize);
    for (t, w) in theta.iter().zip(omega) {
        let c = (2.0 * t).cos();
        // Eq. 19 rearranged: 2 omega / gamma + 1 = A cos 2 theta, linear in A.
        let y = 2.0 * w / gamma + 1.0;
        scc += c * c;
        scy += c * y;
        sc += c;
        sw += w;
        n += 1;
    }
    if n < 3 || scc <= 0.0 {
        return None;
    }
    let a = scy / scc;
    let rms = (theta
        .iter()
        .zip(omega)
        .map(|(t, w)| (2.0 * w / gamma + 1.0 - a * (2.0 * t).cos()).powi(2))
        .sum::<f64>()
        / n as f64)
        .sqrt();
    // Free fit omega = p cos 2 theta + q by ordinary least squares.
    let nf = n as f64;
    let var = scc - sc * sc / nf;
    let scw: f64 = theta
        .iter()
        .zip(omega)
        .map(|(t, w)| (2.0 * t).cos() * w)
        .sum();
    let (free_aspect_ratio, free_shear_rate) = if var > 1e-12 * nf {
        let p = (scw - sc * sw / nf) / var;
        let q = (sw - p * sc) / nf;
        (
            (q < 0.0).then(|| aspect_from_coefficient(-p / q)).flatten(),
            Some(-2.0 * q),
        )
    } else {
        (None, None)
    };
    Some(JefferyFit {
        effective_aspect_ratio: aspect_from_coefficient(a)?,
        coefficient: a,
        rms_residual: rms,
        free_aspect_ratio,
        free_shear_rate,
        samples: n,
    })
}

/// Analyse a fibre's orbit from `(time, bead positions)` samples in a shear of rate
/// `shear_rate` (inverse time units, > 0; the flow `u = gamma y e_x` turns fibres clockwise).
pub fn analyse<P: AsRef<[[f64; 3]]>>(
    samples: &[(f64, P)],
    shear_rate: f64,
    how: Orientation,
) -> Result<OrbitAnalysis, OrbitError> {
    let series = orientation_series(samples, how)?;
    analyse_series(&series, samples[0].1.as_ref().len(), shear_rate)
}

/// Analyse an orientation history of a fibre of `beads` beads (see [`analyse`]); if the
/// three vectors differ in length, only their common length is used.
pub fn analyse_series(
    s: &OrientationSeries,
    beads: usize,
    shear_rate: f64,
) -> Result<OrbitAnalysis, OrbitError> {
    let gamma = shear_rate;
    let n = usable_samples(s, beads, gamma)?;
    let (t, th, r) = (&s.times[..n], &s.theta[..n], &s.end_to_end_ratio[..n]);
    let tail = Tail::of(t, th, beads, gamma);
    let folds = Folds::of(r, th);

    // Half-turns between successive passes through 90 deg.
    let crossings = reference_crossings(t, th);
    let half_turns: Vec<HalfTurn> = crossings
        .windows(2)
        .map(|w| half_turn(t, th, r, &folds.state, w[0], w[1]))
        .collect();
    let half_turn_period = (crossings.len() >= 2)
        .then(|| (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64);
    let period_gamma = half_turn_period.map(|p| gamma * p);
    // gamma T = pi (r + 1/r): r = (x + sqrt(x^2 - 4)) / 2 with x = gamma T / pi >= 2.
    let period_aspect_ratio = period_gamma
        .map(|g| g / PI)
        .filter(|&x| x >= 2.0)
        .map(|x| 2.0 / (x + (x * x - 4.0).sqrt()));

    let jeffery_fit = if tail.stuck {
        None
    } else {
        let omega = angular_velocity(t, th);
        fit_jeffery(&th[1..n - 1], &omega[1..n - 1], gamma)
    };

    let (min_ratio, max_ratio) = r
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let (kind, reason) = classify(&tail, &folds, min_ratio, beads);
    // A label is only as good as the run is long: a straight fibre that has not yet turned
    // through a half-turn may still fold or stick further on.
    let net_rotation_deg = (th[n - 1] - th[0]).to_degrees();
    let reason = if !tail.stuck && net_rotation_deg.abs() < 180.0 {
        format!(
            "{reason}; the run turned the fibre through {:.0} deg only, less than a \
             half-turn: a longer run may still fold or stick",
            net_rotation_deg.abs()
        )
    } else {
        reason
    };
    let stuck_kind = tail.stuck.then(|| {
        if r[tail.start..].iter().any(|&x| x < FOLD_RATIO) {
            "s-stuck"
        } else {
            "jeffery-stuck"
        }
    });

    Ok(OrbitAnalysis {
        kind,
        stuck_kind,
        stuck_angle_deg: tail.stuck.then(|| direction_deg(th[n - 1])),
        net_rotation_deg,
        tail_rate_deg: tail.rate.to_degrees(),
        stuck_threshold_deg: tail.threshold.to_degrees(),
        tail_rate_trend: tail.trend,
        half_turns,
        half_turn_period,
        period_gamma,
        period_aspect_ratio,
        jeffery_fit,
        min_ratio,
        max_ratio,
        final_ratio: r[n - 1],
        folds: folds.folds,
        straightenings: folds.straightenings,
        last_fold_rotation_deg: folds.last_fold_rotation_deg,
        reason,
    })
}

/// How many samples of `s` the analysis can use (the common length of its vectors), or why
/// it cannot: a bad shear rate, fewer than 2 beads or 3 samples, a value that is not finite,
/// times that do not increase.
fn usable_samples(s: &OrientationSeries, beads: usize, gamma: f64) -> Result<usize, OrbitError> {
    if !(gamma.is_finite() && gamma > 0.0) {
        return Err(OrbitError::BadShearRate(gamma));
    }
    if beads < 2 {
        return Err(OrbitError::TooFewBeads { sample: 0, beads });
    }
    let n = s
        .times
        .len()
        .min(s.theta.len())
        .min(s.end_to_end_ratio.len());
    if n < 3 {
        return Err(OrbitError::TooFewSamples(n));
    }
    let (t, th, r) = (&s.times[..n], &s.theta[..n], &s.end_to_end_ratio[..n]);
    if let Some(i) = (0..n).find(|&i| !(t[i].is_finite() && th[i].is_finite() && r[i].is_finite()))
    {
        return Err(OrbitError::NotFinite(i));
    }
    if let Some(i) = (1..n).find(|&i| t[i] <= t[i - 1]) {
        return Err(OrbitError::TimeNotIncreasing(i));
    }
    Ok(n)
}

/// The stuck test on the run's tail (its last [`STUCK_TAIL_FRACTION`]): the mean rotation
/// rate there against the slowest free Jeffery rate (S2023 eq. 19 at theta = 0 with
/// r_c = 1/N), and whether a stuck fibre is settling or creeping.
struct Tail {
    /// First sample of the tail.
    start: usize,
    /// Mean rotation rate over the tail (rad per time unit).
    rate: f64,
    /// [`STUCK_RATE_FRACTION`] of the slowest free Jeffery rate.
    threshold: f64,
    stuck: bool,
    /// The rate over the tail's second half over that over its first half.
    trend: Option<f64>,
    /// Stuck, but the rate is not falling: a steady creep.
    creeping: bool,
    /// The rates over the tail's first and second halves.
    early: f64,
    late: f64,
}

impl Tail {
    fn of(t: &[f64], th: &[f64], beads: usize, gamma: f64) -> Self {
        let n = t.len();
        let tail_start = t[n - 1] - STUCK_TAIL_FRACTION * (t[n - 1] - t[0]);
        let start = t
            .iter()
            .position(|&x| x >= tail_start)
            .unwrap_or(0)
            .min(n - 2);
        let rate = (th[n - 1] - th[start]) / (t[n - 1] - t[start]);
        let rc_geo = 1.0 / beads as f64;
        let threshold = STUCK_RATE_FRACTION * gamma * rc_geo * rc_geo / (1.0 + rc_geo * rc_geo);
        let stuck = rate.abs() < threshold;
        // The tail in two halves: is the rate falling (settling) or steady (creeping)?
        let mid = t
            .iter()
            .position(|&x| x >= 0.5 * (t[start] + t[n - 1]))
            .unwrap_or(n - 1)
            .clamp(start + 1, n - 1);
        let rate_over = |a: usize, b: usize| (th[b] - th[a]) / (t[b] - t[a]);
        let (early, late) = if mid < n - 1 {
            (rate_over(start, mid), rate_over(mid, n - 1))
        } else {
            (rate, rate)
        };
        let trend = (early != 0.0).then(|| late / early);
        let creeping =
            stuck && trend.is_some_and(|x| x >= CREEP_TREND) && late.abs() >= 0.1 * threshold;
        Self {
            start,
            rate,
            threshold,
            stuck,
            trend,
            creeping,
            early,
            late,
        }
    }
}

/// Folds and straightenings of the end-to-end ratio `r`, with hysteresis between
/// [`FOLD_RATIO`] and [`STRAIGHT_RATIO`].
struct Folds {
    /// Whether the fibre is folded at each sample.
    state: Vec<bool>,
    folds: usize,
    straightenings: usize,
    /// How far the fibre turned during its last fold (degrees).
    last_fold_rotation_deg: Option<f64>,
}

impl Folds {
    fn of(r: &[f64], th: &[f64]) -> Self {
        let (mut folded, mut folds, mut straightenings) = (false, 0usize, 0usize);
        let mut fold_start = 0usize;
        let mut last_fold: Option<(usize, usize)> = None;
        let mut state = Vec::with_capacity(r.len());
        for (i, &ri) in r.iter().enumerate() {
            if !folded && ri < FOLD_RATIO {
                folded = true;
                folds += 1;
                fold_start = i;
            } else if folded && ri >= STRAIGHT_RATIO {
                folded = false;
                straightenings += 1;
                last_fold = Some((fold_start, i));
            }
            state.push(folded);
        }
        if folded {
            last_fold = Some((fold_start, r.len() - 1));
        }
        Self {
            state,
            folds,
            straightenings,
            last_fold_rotation_deg: last_fold.map(|(a, b)| (th[b] - th[a]).abs().to_degrees()),
        }
    }
}

/// The orbit of S2023 section IV C and the reason, with the numbers it rests on: stuck by
/// the tail's rate; else jeffery without a fold; s-coiled where the fibre never
/// straightened or its last fold lasted a half-turn; else s-turn.
fn classify(tail: &Tail, folds: &Folds, min_ratio: f64, beads: usize) -> (OrbitKind, String) {
    let last_fold = folds.last_fold_rotation_deg;
    let fold_text = |d: Option<f64>| format!("{:.1} deg", d.unwrap_or(0.0));
    if tail.stuck {
        let creep = if tail.creeping {
            format!(
                "; but the rate is not falling ({} deg per time unit over the last \
                 half of that, {} before): a steady creep, not settling at an angle; \
                 a longer run may see it turn on",
                Sig(tail.late.abs().to_degrees()),
                Sig(tail.early.abs().to_degrees())
            )
        } else {
            String::new()
        };
        let reason = format!(
            "mean rate over the last {:.0} % of the run {} deg per time unit < {} \
             ({} x the slowest Jeffery rate for r_c = 1/{beads})",
            100.0 * STUCK_TAIL_FRACTION,
            Sig(tail.rate.abs().to_degrees()),
            Sig(tail.threshold.to_degrees()),
            STUCK_RATE_FRACTION
        );
        (OrbitKind::Stuck, reason + &creep)
    } else if folds.folds == 0 {
        (
            OrbitKind::Jeffery,
            format!("end-to-end / contour stays >= {min_ratio:.4} (fold threshold {FOLD_RATIO})"),
        )
    } else if folds.straightenings == 0 {
        (
            OrbitKind::SCoiled,
            format!(
                "folded below {FOLD_RATIO} and never back above {STRAIGHT_RATIO} (turned {} while folded)",
                fold_text(last_fold)
            ),
        )
    } else if last_fold.is_some_and(|d| d >= 180.0) {
        (
            OrbitKind::SCoiled,
            format!(
                "the last fold lasted a half-turn or more ({}) without straightening",
                fold_text(last_fold)
            ),
        )
    } else {
        (
            OrbitKind::STurn,
            format!(
                "{} folds below {FOLD_RATIO}, {} straightenings above \
                 {STRAIGHT_RATIO}; the last fold lasted {}",
                folds.folds,
                folds.straightenings,
                fold_text(last_fold)
            ),
        )
    }
}

/// Shape statistics of the half-turn between times `a` and `b`; `folded` is the fold state
/// of each sample (with hysteresis), so a fold begun in the previous half-turn counts.
fn half_turn(t: &[f64], th: &[f64], r: &[f64], folded: &[bool], a: f64, b: f64) -> HalfTurn {
    let (mut min_ratio, mut max_ratio, mut at_min) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
    let mut straightened_at_deg = None;
    for i in (0..t.len()).filter(|&i| t[i] >= a && t[i] <= b) {
        if r[i] < min_ratio {
            min_ratio = r[i];
            at_min = th[i];
        }
        max_ratio = max_ratio.max(r[i]);
        if i > 0 && folded[i - 1] && !folded[i] && straightened_at_deg.is_none() {
            straightened_at_deg = Some(direction_deg(th[i]));
        }
    }
    HalfTurn {
        start: a,
        end: b,
        min_ratio,
        max_ratio,
        angle_at_min_deg: direction_deg(at_min),
        straightened_at_deg,
    }
}

#[cfg(test)]
mod tests;
