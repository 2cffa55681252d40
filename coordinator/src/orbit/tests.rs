//! Synthetic trajectories with analytic references: a rod following S2023 eq. 19, a rod
//! stopping at a given angle, an S that opens again, an S that stays folded.
use super::*;

type Samples = Vec<(f64, Vec<[f64; 3]>)>;

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// `n` beads one unit apart along a point-symmetric S (tangent angle `bend u^2`, `u` from -1
/// to 1 along the fibre), turned so that the end-to-end vector points along `theta`, centred
/// at `centre`. `bend = 0` is a straight rod.
fn s_shape(n: usize, theta: f64, bend: f64, centre: [f64; 2]) -> Vec<[f64; 3]> {
    let mut p = vec![[0.0f64; 3]; n];
    for j in 1..n {
        let u = 2.0 * (j as f64 - 0.5) / (n - 1) as f64 - 1.0;
        let phi = bend * u * u;
        p[j] = [p[j - 1][0] + phi.cos(), p[j - 1][1] + phi.sin(), 0.0];
    }
    let alpha = p[n - 1][1].atan2(p[n - 1][0]);
    let (c, s) = ((theta - alpha).cos(), (theta - alpha).sin());
    let (mx, my) = (p[n - 1][0] / 2.0, p[n - 1][1] / 2.0);
    p.iter()
        .map(|q| {
            let (x, y) = (q[0] - mx, q[1] - my);
            [centre[0] + c * x - s * y, centre[1] + s * x + c * y, 0.7]
        })
        .collect()
}

/// End-to-end over contour of `s_shape(n, _, bend, _)`.
fn ratio_of(n: usize, bend: f64) -> f64 {
    let p = s_shape(n, 0.0, bend, [0.0; 2]);
    (p[n - 1][0] - p[0][0]).hypot(p[n - 1][1] - p[0][1]) / (n - 1) as f64
}

/// The bend giving end-to-end over contour `target` (bisection; the ratio falls with bend).
fn bend_for(n: usize, target: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 6.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if ratio_of(n, mid) > target {
            lo = mid
        } else {
            hi = mid
        }
    }
    0.5 * (lo + hi)
}

/// S2023 eq. 19, the analytic reference.
fn jeffery_omega(theta: f64, gamma: f64, rc: f64) -> f64 {
    0.5 * gamma * ((1.0 - rc * rc) / (1.0 + rc * rc) * (2.0 * theta).cos() - 1.0)
}

/// `theta(t)` from S2023 eq. 19 by classical Runge-Kutta, `steps + 1` samples `dt` apart.
fn jeffery_history(gamma: f64, rc: f64, theta0: f64, dt: f64, steps: usize) -> Vec<(f64, f64)> {
    let f = |th: f64| jeffery_omega(th, gamma, rc);
    let mut th = theta0;
    let mut out = vec![(0.0, th)];
    for i in 1..=steps {
        let k1 = f(th);
        let k2 = f(th + 0.5 * dt * k1);
        let k3 = f(th + 0.5 * dt * k2);
        let k4 = f(th + dt * k3);
        th += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        out.push((i as f64 * dt, th));
    }
    out
}

/// Bead samples along `history`, with the bend `bend(t, theta)`, drifting with the flow.
fn beads_along(n: usize, history: &[(f64, f64)], bend: impl Fn(f64, f64) -> f64) -> Samples {
    history
        .iter()
        .map(|&(t, th)| (t, s_shape(n, th, bend(t, th), [3.0 + 0.1 * t, -2.0])))
        .collect()
}

const N: usize = 10;
const GAMMA: f64 = 2.0;
const RC: f64 = 0.132;

/// A rod turning by S2023 eq. 19 (r_c = 0.132, gamma = 2), starting horizontal.
fn jeffery_rod_history() -> Vec<(f64, f64)> {
    // Three full periods, 2 pi (r + 1/r) / gamma each, at 0.005 per sample.
    let full = 2.0 * PI * (1.0 / RC + RC) / GAMMA;
    jeffery_history(GAMMA, RC, PI, 0.005, (3.0 * full / 0.005) as usize)
}

/// Tolerance 1 % on r_c (from eq. 19 and from the period) and on the period.
#[test]
fn jeffery_rod_gives_its_aspect_ratio_and_period() {
    // A 0.5 % breathing of the end-to-end distance: rigid "without visible deformation".
    let b = bend_for(N, 0.995);
    let samples = beads_along(N, &jeffery_rod_history(), |_, th| {
        b * (2.0 * th).sin().abs()
    });
    let a = analyse(&samples, GAMMA, Orientation::EndToEnd).unwrap();
    assert_eq!(a.kind, OrbitKind::Jeffery, "{}", a.reason);
    let fit = a.jeffery_fit.clone().unwrap();
    let r = 1.0 / RC;
    let half = PI * (r + 1.0 / r) / GAMMA;
    let t = a.half_turn_period.unwrap();
    eprintln!(
        "jeffery: r_c fit {:.5} (free {:.5}, gamma {:.5}), rms {:.2e}; r_c period {:.5}; \
         T {t:.4} vs {half:.4}; full 2T {:.4} vs 2 pi (r+1/r)/gamma {:.4}; half-turns {}; \
         min ratio {:.4}; net {:.1} deg",
        fit.effective_aspect_ratio,
        fit.free_aspect_ratio.unwrap(),
        fit.free_shear_rate.unwrap(),
        fit.rms_residual,
        a.period_aspect_ratio.unwrap(),
        2.0 * t,
        2.0 * half,
        a.half_turns.len(),
        a.min_ratio,
        a.net_rotation_deg
    );
    assert!(rel(fit.effective_aspect_ratio, RC) < 0.01);
    assert!(rel(fit.free_aspect_ratio.unwrap(), RC) < 0.01);
    assert!(rel(fit.free_shear_rate.unwrap(), GAMMA) < 0.01);
    assert!(rel(t, half) < 0.01);
    assert!(rel(2.0 * t, 2.0 * PI * (r + 1.0 / r) / GAMMA) < 0.01);
    assert!(rel(a.period_aspect_ratio.unwrap(), RC) < 0.01);
    assert!(a.half_turns.len() >= 5);
    assert!(a.net_rotation_deg < -900.0, "clockwise");
    assert!(a.stuck_angle_deg.is_none() && a.folds == 0);
}

/// The first fifth of the same rod's first half-turn: still labelled by what it did (straight,
/// turning), but the note says the run is too short to rule out a fold or a stop.
#[test]
fn a_run_short_of_a_half_turn_says_so() {
    let history = jeffery_rod_history();
    let full = 2.0 * PI * (1.0 / RC + RC) / GAMMA;
    let short = &history[..(0.1 * full / 0.005) as usize];
    let a = analyse(
        &beads_along(N, short, |_, _| 0.0),
        GAMMA,
        Orientation::EndToEnd,
    )
    .unwrap();
    assert_eq!(a.kind, OrbitKind::Jeffery, "{}", a.reason);
    assert!(a.net_rotation_deg.abs() < 180.0);
    assert!(a.reason.contains("less than a half-turn"), "{}", a.reason);
    let whole = analyse(
        &beads_along(N, &history, |_, _| 0.0),
        GAMMA,
        Orientation::EndToEnd,
    );
    let whole = whole.unwrap();
    assert!(!whole.reason.contains("half-turn"), "{}", whole.reason);
}

/// Another aspect ratio, principal-axis orientation: the fit is not tied to one value.
#[test]
fn jeffery_fit_follows_the_aspect_ratio() {
    let rc = 0.3;
    let hist = jeffery_history(1.0, rc, 0.4, 0.01, 6000);
    let samples = beads_along(6, &hist, |_, _| 0.0);
    let a = analyse(&samples, 1.0, Orientation::PrincipalAxis).unwrap();
    let fit = a.jeffery_fit.unwrap();
    eprintln!("r_c 0.3: fit {:.5}", fit.effective_aspect_ratio);
    assert!(rel(fit.effective_aspect_ratio, rc) < 0.01);
    assert_eq!(a.kind, OrbitKind::Jeffery);
}

/// The analysis of a straight rod at angle `theta(t)`, sampled every 0.05 over 100 time units.
fn straight_rod(theta: impl Fn(f64) -> f64) -> OrbitAnalysis {
    let hist: Vec<(f64, f64)> = (0..=2000)
        .map(|i| {
            let t = i as f64 * 0.05;
            (t, theta(t))
        })
        .collect();
    analyse(
        &beads_along(N, &hist, |_, _| 0.0),
        GAMMA,
        Orientation::EndToEnd,
    )
    .unwrap()
}

/// A rod turning clockwise from 180 deg and stopping at 12 deg (exponential approach, rate
/// gamma/5).
fn rod_stopping_at_12_degrees() -> OrbitAnalysis {
    let stop = 12f64.to_radians();
    straight_rod(|t| stop + (PI - stop) * (-GAMMA * t / 5.0).exp())
}

/// That rod is stuck at 12 +- 0.5 deg, with no complete half-turn, so no period.
#[test]
fn rod_stopping_at_12_degrees_is_stuck() {
    let a = rod_stopping_at_12_degrees();
    eprintln!(
        "stuck: angle {:?}, tail rate {:.2e} < {:.2e} deg/time, {}",
        a.stuck_angle_deg, a.tail_rate_deg, a.stuck_threshold_deg, a.reason
    );
    assert_eq!(a.kind, OrbitKind::Stuck);
    assert!((a.stuck_angle_deg.unwrap() - 12.0).abs() < 0.5);
    assert_eq!(a.stuck_kind, Some("jeffery-stuck"));
    assert!(a.half_turn_period.is_none() && a.half_turns.is_empty());
    assert!(a.jeffery_fit.is_none());
    assert!((a.net_rotation_deg + 168.0).abs() < 0.5);
}

/// A rod creeping clockwise at a steady half, or a twentieth, of the stuck threshold's rate:
/// both are `stuck` by S2023's rate test, but the analysis tells the steady creep from the
/// exponential approach of `rod_stopping_at_12_degrees` (trend near 1 against near 0) and
/// says so in its reason when the creep is above a tenth of the threshold.
#[test]
fn steady_creep_is_told_from_settling() {
    let creep = |fraction: f64| {
        let rc = 1.0 / N as f64;
        let threshold = STUCK_RATE_FRACTION * GAMMA * rc * rc / (1.0 + rc * rc);
        straight_rod(|t| 10f64.to_radians() - fraction * threshold * t)
    };
    let a = creep(0.5);
    eprintln!("{}", a.reason);
    assert_eq!(a.kind, OrbitKind::Stuck);
    assert!((a.tail_rate_trend.unwrap() - 1.0).abs() < 1e-6);
    assert!(a.reason.contains("steady creep"), "{}", a.reason);
    let scalars = a.scalars();
    assert!(scalars.iter().any(|(k, _)| *k == "tail_rate_trend"));
    // Below a tenth of the threshold the creep is not worth a word.
    let a = creep(0.05);
    assert_eq!(a.kind, OrbitKind::Stuck);
    assert!(!a.reason.contains("steady creep"), "{}", a.reason);
    // The exponential approach to 12 deg (rate gamma / 5): the rate falls over the
    // half-tail of 10 time units by e^-4.
    let a = rod_stopping_at_12_degrees();
    let trend = a.tail_rate_trend.unwrap();
    assert!(trend > 0.0 && trend < CREEP_TREND, "trend {trend}");
    assert!(!a.reason.contains("steady creep"), "{}", a.reason);
}

/// S2023 Fig. 9(c): a folded fibre turning counter-clockwise by 20 deg and sticking there.
#[test]
fn folded_fibre_turning_counter_clockwise_is_s_stuck() {
    let b = bend_for(N, 0.8);
    let hist: Vec<(f64, f64)> = (0..=1000)
        .map(|i| {
            let t = i as f64 * 0.1;
            (t, 20f64.to_radians() * (1.0 - (-t / 4.0).exp()))
        })
        .collect();
    let a = analyse(
        &beads_along(N, &hist, |_, _| b),
        GAMMA,
        Orientation::EndToEnd,
    )
    .unwrap();
    assert_eq!(a.kind, OrbitKind::Stuck);
    assert_eq!(a.stuck_kind, Some("s-stuck"));
    assert!((a.stuck_angle_deg.unwrap() - 20.0).abs() < 0.5);
    assert!(a.net_rotation_deg > 19.0);
}

/// Bent to an S while compressed (theta between 135 and 45 deg modulo 180), end-to-end down
/// to 0.9 of the contour at 90 deg, straight again at 45 deg (S2023 section IV C).
#[test]
fn s_that_opens_at_45_degrees_is_an_s_turn() {
    let b = bend_for(N, 0.9);
    let bend = |_: f64, th: f64| b * (-(2.0 * th).cos()).max(0.0).sqrt();
    let a = analyse(
        &beads_along(N, &jeffery_rod_history(), bend),
        GAMMA,
        Orientation::EndToEnd,
    )
    .unwrap();
    eprintln!("s-turn: {}; half-turns:", a.reason);
    for h in &a.half_turns {
        eprintln!(
            "  min {:.4} at {:.1} deg, max {:.4}, straightened at {:?}",
            h.min_ratio, h.angle_at_min_deg, h.max_ratio, h.straightened_at_deg
        );
    }
    assert_eq!(a.kind, OrbitKind::STurn, "{}", a.reason);
    assert!((a.min_ratio - 0.9).abs() < 0.005);
    assert!(a.folds >= 5 && a.straightenings >= 5);
    for h in &a.half_turns {
        assert!((h.min_ratio - 0.9).abs() < 0.005 && h.max_ratio > 0.999);
        let at = h.straightened_at_deg.unwrap();
        assert!(at > 45.0 && at < 60.0, "straightened at {at}");
    }
    // The summary's means: folded deepest at the vertical (either side of 90 deg averages to
    // 90, not 0), straightened between 45 and 60 deg.
    let fold = a.fold_angle_deg().unwrap();
    assert!((fold.abs() - 90.0).abs() < 2.0, "fold angle {fold}");
    let at = a.straightened_at_deg().unwrap();
    assert!(at > 45.0 && at < 60.0, "straightened at {at}");
    let names: Vec<&str> = a.scalars().iter().map(|(k, _)| *k).collect();
    assert!(names.contains(&"fold_angle_deg") && names.contains(&"straightened_at_deg"));
}

/// Folds within the first quarter turn and keeps an S (end-to-end 0.55 +- 0.05 of the
/// contour) while it tumbles like a shorter rod (r_c = 0.35).
#[test]
fn permanently_folded_s_is_s_coiled() {
    let b = bend_for(N, 0.55);
    let hist = jeffery_history(GAMMA, 0.35, PI, 0.005, 6000);
    let bend = |t: f64, th: f64| b * (1.0 - (-GAMMA * t).exp()) * (1.0 + 0.05 * (2.0 * th).cos());
    let a = analyse(&beads_along(N, &hist, bend), GAMMA, Orientation::EndToEnd).unwrap();
    eprintln!(
        "s-coiled: {}; ratio {:.3}..{:.3}; {} half-turns, gamma T {:?}",
        a.reason,
        a.min_ratio,
        a.max_ratio,
        a.half_turns.len(),
        a.period_gamma
    );
    assert_eq!(a.kind, OrbitKind::SCoiled, "{}", a.reason);
    assert!(a.half_turns.len() >= 2);
    assert!(a.half_turns.iter().all(|h| h.max_ratio < 0.7));
    assert_eq!(a.straightenings, 0);
}

/// An S-turn fibre that stays folded after a few turns is s-coiled: the last fold outlasts a
/// half-turn.
#[test]
fn s_turn_that_stops_opening_is_s_coiled() {
    let b = bend_for(N, 0.9);
    let t_switch = 40.0;
    let bend = |t: f64, th: f64| {
        if t < t_switch {
            b * (-(2.0 * th).cos()).max(0.0).sqrt()
        } else {
            b
        }
    };
    let a = analyse(
        &beads_along(N, &jeffery_rod_history(), bend),
        GAMMA,
        Orientation::EndToEnd,
    )
    .unwrap();
    assert_eq!(a.kind, OrbitKind::SCoiled, "{}", a.reason);
    assert!(a.straightenings >= 1 && a.last_fold_rotation_deg.unwrap() >= 180.0);
}

/// A rod turning counter-clockwise at a steady 20 deg per sample from 150 deg, with its beads
/// listed in reverse order every other sample: the angle stays continuous across the 180 deg
/// branch cut and the reversals, turns +800 deg, and each half-turn lasts 9 samples.
#[test]
fn unwrapping_across_the_branch_cut_and_bead_reversal() {
    let samples: Samples = (0..=40)
        .map(|i| {
            let mut p = s_shape(4, (150.0 + 20.0 * i as f64).to_radians(), 0.0, [0.0; 2]);
            if i % 2 == 1 {
                p.reverse();
            }
            (i as f64, p)
        })
        .collect();
    for how in [Orientation::EndToEnd, Orientation::PrincipalAxis] {
        let s = orientation_series(&samples, how).unwrap();
        for w in s.theta.windows(2) {
            assert!(((w[1] - w[0]).to_degrees() - 20.0).abs() < 1e-9);
        }
        let a = analyse_series(&s, 4, 1.0).unwrap();
        assert!((a.net_rotation_deg - 800.0).abs() < 1e-9);
        assert!((a.half_turn_period.unwrap() - 9.0).abs() < 1e-9);
        assert_eq!(a.half_turns.len(), 3);
        assert_eq!(a.kind, OrbitKind::Jeffery);
    }
}

/// Jitter back and forth across 90 deg counts as one pass; passes are interpolated.
#[test]
fn crossings_ignore_jitter() {
    let deg = [
        100.0, 91.0, 89.0, 91.0, 89.5, 60.0, -80.0, -89.0, -91.0, -95.0,
    ];
    let theta: Vec<f64> = deg.iter().map(|d: &f64| d.to_radians()).collect();
    let times: Vec<f64> = (0..theta.len()).map(|i| i as f64).collect();
    let c = reference_crossings(&times, &theta);
    assert_eq!(c.len(), 2, "{c:?}");
    assert!((c[0] - 1.5).abs() < 1e-12 && (c[1] - 7.5).abs() < 1e-12);
}

/// Second-order differences are exact for a quadratic, even on an uneven grid.
#[test]
fn angular_velocity_is_exact_for_a_quadratic() {
    let times = [0.0, 0.1, 0.35, 0.4, 0.9, 1.0];
    let theta: Vec<f64> = times.iter().map(|t| 2.0 - 3.0 * t + 0.5 * t * t).collect();
    let w = angular_velocity(&times, &theta);
    for i in 1..times.len() - 1 {
        assert!((w[i] - (-3.0 + times[i])).abs() < 1e-12);
    }
}

/// The four synthetic orbits get four different labels.
#[test]
fn classifier_separates_the_four_orbits() {
    let hist = jeffery_history(GAMMA, RC, PI, 0.01, 5000);
    let (b9, b5) = (bend_for(N, 0.9), bend_for(N, 0.5));
    let kinds: Vec<OrbitKind> = [
        beads_along(N, &hist, |_, _| 0.0),
        beads_along(N, &hist, |_, th| b9 * (-(2.0 * th).cos()).max(0.0)),
        beads_along(N, &hist, |_, _| b5),
        beads_along(N, &[(0.0, 0.2), (1.0, 0.21), (50.0, 0.21)], |_, _| 0.0),
    ]
    .iter()
    .map(|s| analyse(s, GAMMA, Orientation::EndToEnd).unwrap().kind)
    .collect();
    assert_eq!(
        kinds,
        [
            OrbitKind::Jeffery,
            OrbitKind::STurn,
            OrbitKind::SCoiled,
            OrbitKind::Stuck
        ]
    );
}

#[test]
fn bad_trajectories_are_errors() {
    let rod = |th: f64| s_shape(3, th, 0.0, [0.0; 2]);
    let ok: Samples = (0..5).map(|i| (i as f64, rod(0.1 * i as f64))).collect();
    assert!(analyse(&ok, 1.0, Orientation::EndToEnd).is_ok());
    let e = |s: &Samples| analyse(s, 1.0, Orientation::EndToEnd).unwrap_err();
    assert_eq!(e(&ok[..2].to_vec()), OrbitError::TooFewSamples(2));
    let one: Samples = (0..5).map(|i| (i as f64, vec![[0.0; 3]])).collect();
    assert!(matches!(e(&one), OrbitError::TooFewBeads { beads: 1, .. }));
    let mut m = ok.clone();
    m[3].1.push([9.0, 0.0, 0.0]);
    assert!(matches!(
        e(&m),
        OrbitError::BeadCountChanges { sample: 3, .. }
    ));
    let mut m = ok.clone();
    m[2].0 = 1.0;
    assert_eq!(e(&m), OrbitError::TimeNotIncreasing(2));
    let mut m = ok.clone();
    m[1].1[0][1] = f64::NAN;
    assert_eq!(e(&m), OrbitError::NotFinite(1));
    let mut m = ok.clone();
    m[4].1 = vec![[1.0, 1.0, 0.0]; 3];
    assert_eq!(e(&m), OrbitError::Degenerate(4));
    assert_eq!(
        analyse(&ok, 0.0, Orientation::EndToEnd).unwrap_err(),
        OrbitError::BadShearRate(0.0)
    );
}
