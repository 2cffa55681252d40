//! How stiff a fibre may be under the explicit SPM momentum exchange (L2020 eqs. 35–38).
//!
//! The explicit exchange hands a bead, once per fluid step, the impulse of the fluid in its
//! profile measured against the velocity the last penalty imposed, `J = m_phi (u_phi − U^n)`
//! ([`crate::spm_exchange`]). For a vibrating fibre that is a drag sampled once per step at
//! the velocity the bead had at the step's start. A mode of the fibre that vibrates at a
//! good fraction of the fluid step's frequency is fed by it: the chains of
//! docs/validation/spm.md ("Stiff chains under the explicit coupling") blow up although the
//! fibre's own step (the beam-stiffness limit of [`crate::stability`]) is stable.
//!
//! # One mode
//! A normal mode of frequency `ω` (unit modal mass, coordinate `x`) is advanced over a
//! fluid step `dt` by `n` sub-steps `h = dt / n` of position-first symplectic Euler with the
//! mass-proportional damping `c` (`crate::fibre`); the corrector spreads the fluid's impulse
//! evenly over the sub-steps. If the flow around takes a fraction `k` of the profile fluid's
//! excess motion during the step, the impulse is `−k r v0` with `v0` the mode's velocity at
//! the step's start and `r` the mode's profile-to-bead ratio: the fluid in the profiles over
//! the bead inertia, weighted by where the mode's kinetic energy lies,
//! `r = s m_phi / M + (1 − s) I_phi / I` with `s` its share in translation
//! ([`crate::stability::NormalMode`]). Each sub-step is
//!
//! ```text
//! x' = x + h v,   v' = v − h ω² x' − h c v − (k r / n) v0,
//! ```
//!
//! linear in `(x, v, v0)`, so the step is the matrix `B = P A^n E` (`E`: `v0 = v` at the
//! start, `P`: keep `(x, v)`). The mode is stable while the spectral radius of `B` stays at
//! most 1. Without coupling (`r = 0`) that holds for `ω h < 2`; with it the threshold in
//! `ω dt` falls with `r` (2.24 at `k r = 1` with four sub-steps, 1.41 with one) and is zero
//! for `k r >= 2`, the light-bead limit of [`crate::spm_exchange`].
//!
//! # The flow's share `k`
//! `k` is not known a priori: it grows with `nu dt / xi^2` and depends on the profile. It
//! is calibrated on the thresholds measured by bisection of the Young's modulus in coupled
//! runs ([`MEASURED_THRESHOLDS`]): 2D and 3D cohesive beams of radius-4 beads (xi = 1, xi_c =
//! 3), densities 1 to 3, one to five sub-steps, nu dt / xi^2 = 0.25 and 0.7. [`FLOW_SHARE`]
//! is the largest `k` those thresholds imply, so the model's limit lies at or below every one
//! of them; configure then keeps the margin [`SAFETY`] below it. Held out of the fit
//! ([`HELD_OUT_THRESHOLDS`]), the share grows with the diffusion number: at xi = 2 it is
//! 0.82, 0.86, 0.94, 0.965-0.979, 0.996-1.005, 1.008-1.019 and 1.013-1.026 at
//! `nu dt / xi^2` = 0.175, 0.7, 2.5, 5, 10, 20 and 40 (the 3D chain at xi = 1: 0.84, 0.93,
//! 0.982, 1.012 and 1.024 at 0.7, 2.5, 5, 10 and 20).
//! So above the calibrated 0.7 the check takes [`FLOW_SHARE_ABOVE_CALIBRATED`], and from
//! 2.5 on a share that grows with the diffusion number ([`FLOW_SHARE_RAMP`],
//! [`flow_share`]); the fibre node reads `nu` from `fluid.viscosity / fluid.density`.
use crate::fibre::Fibre;
use crate::spm_exchange::ExchangeRatios;
use crate::stability::{normal_modes, stable_step, NormalMode, SAFETY as STEP_SAFETY};
use nalgebra::{Matrix2, Matrix3};

/// The fraction of the profile fluid's excess motion the flow is taken to absorb in one
/// step (the module's `k`), calibrated on [`MEASURED_THRESHOLDS`].
pub const FLOW_SHARE: f64 = 0.87;

/// The largest `nu dt / xi^2` of the calibration ([`MEASURED_THRESHOLDS`]): up to it the
/// check takes the flow's share [`FLOW_SHARE`].
pub const CALIBRATED_DIFFUSION_NUMBER: f64 = 0.7;

/// The flow's share above [`CALIBRATED_DIFFUSION_NUMBER`] and up to the first point of
/// [`FLOW_SHARE_RAMP`]: the flow takes more of the profile's excess motion the further it
/// diffuses in a step. The held-out thresholds there imply 0.69, 0.76 (xi = 1, at 1.5 and
/// 2.5) and 0.936-0.939 (xi = 2, at 2.5) ([`HELD_OUT_THRESHOLDS`]).
pub const FLOW_SHARE_ABOVE_CALIBRATED: f64 = 0.95;

/// `(nu dt / xi^2, k)`: from the first point on, the share grows linearly between the points
/// and by [`FLOW_SHARE_PER_DOUBLING`] per doubling of `nu dt / xi^2` beyond the last. Each
/// point lies at or above the largest share the held-out thresholds at that diffusion number
/// imply ([`HELD_OUT_THRESHOLDS`]): at 2.5, 0.932-0.939; at 5, 0.955-0.974 (the
/// `tumbling_2d.toml` fibre shortened to four and five beads, the latter the capillary test
/// scene of `tests/capillary_fibre.rs::tilted_fibre_aligns_with_a_flat_interface`, and at
/// its nine), 0.975-0.979 (`jeffery_rigid.toml`, densities 1.3 and 1.0, one or four sub-steps,
/// viscosity 1 or 10) and 0.982 (the 3D chain of `jeffery_rigid_3d.toml`); at 10,
/// 0.996-1.005 (3D 1.012); at 20, 1.008-1.019 (3D 1.024); at 40, 1.013-1.026: the flow
/// takes all of the profile's excess motion (a share above 1 is the one-mode model's
/// approximation of the fibre's modes). Near the light-bead limit (a mode's profile-to-bead ratio 1.92 at density 1.0,
/// where k r = 2 leaves no stable step) the threshold moves fast with k: k = 0.95 accepted
/// 114 % of the measured step at 5, and 150 % at 10.
pub const FLOW_SHARE_RAMP: [(f64, f64); 5] = [
    (2.5, 0.95),
    (5.0, 0.985),
    (10.0, 1.015),
    (20.0, 1.025),
    (40.0, 1.027),
];

/// Beyond the last point of [`FLOW_SHARE_RAMP`], where nothing was measured, the share keeps
/// growing by this much per doubling of `nu dt / xi^2`: the measured shares of density-1
/// beads grew by 0.015 and 0.007 per doubling from 10 to 40 (1.004, 1.019, 1.026).
pub const FLOW_SHARE_PER_DOUBLING: f64 = 0.01;

/// The flow's share `k` the check takes for a fluid step of diffusion number
/// `nu dt / xi^2` (`None`: unknown, the share at the last measured point).
pub fn flow_share(diffusion_number: Option<f64>) -> f64 {
    let (d_last, k_last) = FLOW_SHARE_RAMP[FLOW_SHARE_RAMP.len() - 1];
    let Some(d) = diffusion_number else {
        return k_last;
    };
    if d <= CALIBRATED_DIFFUSION_NUMBER * (1.0 + 1e-12) {
        return FLOW_SHARE;
    }
    if d <= FLOW_SHARE_RAMP[0].0 {
        return FLOW_SHARE_ABOVE_CALIBRATED;
    }
    FLOW_SHARE_RAMP.windows(2).find(|w| d <= w[1].0).map_or(
        k_last + FLOW_SHARE_PER_DOUBLING * (d / d_last).log2(),
        |w| {
            let ((d0, k0), (d1, k1)) = (w[0], w[1]);
            k0 + (k1 - k0) * (d - d0) / (d1 - d0)
        },
    )
}

/// One threshold measured in coupled runs: Young's modulus bisected between a run that
/// completes `steps` steps and one that the fluid node stops (advective CFL abort). Fluid
/// density 1, bead spacing 2 r_b.
#[derive(Debug, Clone, Copy)]
pub struct MeasuredThreshold {
    pub dimensions: u8,
    /// `fibre.N.model`.
    pub model: &'static str,
    pub beads: usize,
    pub bead_radius: f64,
    /// `fluid.xi` and `fluid.xi_cutoff`.
    pub xi: f64,
    pub xi_cutoff: f64,
    /// `fibre.N.bead_spin = "chord"` (bead-spring chains).
    pub chord: bool,
    /// Bead density.
    pub density: f64,
    pub substeps: usize,
    /// Fluid step.
    pub dt: f64,
    /// `fluid.viscosity` (1 but in the capillary scene).
    pub viscosity: f64,
    /// Young's modulus of the last run that completed.
    pub runs: f64,
    /// Young's modulus of the first run that failed.
    pub fails: f64,
    pub steps: usize,
}

impl MeasuredThreshold {
    /// The fluid step's diffusion number `nu dt / xi^2`.
    pub fn diffusion_number(&self) -> f64 {
        self.viscosity * self.dt / (self.xi * self.xi)
    }

    /// The flow's share the check takes for this case.
    pub fn share(&self) -> f64 {
        flow_share(Some(self.diffusion_number()))
    }
}

const fn beam(
    dimensions: u8,
    beads: usize,
    density: f64,
    substeps: usize,
    dt: f64,
    [runs, fails]: [f64; 2],
    steps: usize,
) -> MeasuredThreshold {
    MeasuredThreshold {
        dimensions,
        model: "cohesive-beam",
        beads,
        bead_radius: 4.0,
        xi: 1.0,
        xi_cutoff: 3.0,
        chord: false,
        density,
        substeps,
        dt,
        viscosity: 1.0,
        runs,
        fails,
        steps,
    }
}

/// The thresholds [`FLOW_SHARE`] is calibrated on: cohesive beams of radius-4 beads,
/// xi = 1, xi_c = 3, in the small SPM shear scenes of `tests/spm.rs` (2D: 64 x 64, four
/// beads, walls at +-0.28; 3D: 48 x 64 x 32, two beads, walls at +-0.21875);
/// docs/validation/spm.md, "The explicit exchange's stiffness limit".
pub const MEASURED_THRESHOLDS: [MeasuredThreshold; 7] = [
    beam(2, 4, 1.5, 5, 0.25, [208.85, 213.43], 1500),
    beam(2, 4, 1.0, 4, 0.25, [95.76, 97.86], 1500),
    beam(2, 4, 1.5, 1, 0.25, [79.53, 84.25], 1500),
    beam(2, 4, 1.5, 4, 0.7, [24.56, 25.73], 800),
    beam(2, 4, 3.0, 4, 0.25, [507.6, 524.4], 1500),
    beam(3, 2, 1.1, 4, 0.7, [51.76, 52.50], 600),
    beam(3, 2, 1.5, 4, 0.7, [117.9, 120.9], 600),
];

/// `t` with radius-6 beads (`configs/spm/jeffery_rigid.toml`).
const fn radius_6(t: MeasuredThreshold) -> MeasuredThreshold {
    MeasuredThreshold {
        bead_radius: 6.0,
        ..t
    }
}

/// `t` with radius-6 beads and the capillary scenes' wider profile (xi = 2, xi_c = 5).
const fn wide(t: MeasuredThreshold) -> MeasuredThreshold {
    MeasuredThreshold {
        xi: 2.0,
        xi_cutoff: 5.0,
        ..radius_6(t)
    }
}

/// `t` in a fluid of viscosity `viscosity` (density 1).
const fn viscous(viscosity: f64, t: MeasuredThreshold) -> MeasuredThreshold {
    MeasuredThreshold { viscosity, ..t }
}

/// Thresholds measured after the calibration, on what it did not see: a bead-spring chain,
/// radius-6 beads (`configs/spm/jeffery_rigid.toml` with four beads), the wider profile of
/// the capillary scenes (xi = 2, xi_c = 5), the three-bead 3D chain of
/// `configs/spm/jeffery_rigid_3d.toml` (also at `nu dt / xi^2` = 2.5 to 20), and (from the
/// sixth on) fluid steps with `nu dt / xi^2` = 0.7 to 40 (`jeffery_rigid.toml`, four beads
/// of density 1.0 or 1.3, the Young's modulus bisected in 1500-step in-process runs,
/// `time.dt`, `fluid.xi`, `fluid.xi_cutoff`, `fluid.viscosity` and `fibre.0.substeps` as
/// listed; and `configs/capillary/tumbling_2d.toml` at time.dt = 2: the capillary test
/// scene of `tests/capillary_fibre.rs::tilted_fibre_aligns_with_a_flat_interface`, 64 x 64
/// with five beads, the same with four, and the scene itself, nine beads on 128 x 128).
pub const HELD_OUT_THRESHOLDS: [MeasuredThreshold; 30] = [
    MeasuredThreshold {
        model: "bead-spring",
        ..beam(2, 4, 1.0, 4, 0.25, [202.3, 210.3], 1500)
    },
    MeasuredThreshold {
        model: "bead-spring",
        chord: true,
        ..beam(2, 4, 1.0, 4, 0.25, [207.3, 218.6], 1500)
    },
    radius_6(beam(2, 4, 1.0, 4, 0.7, [25.54, 26.55], 1500)),
    wide(beam(2, 4, 1.3, 4, 0.7, [21.81, 22.78], 1500)),
    beam(3, 3, 1.1, 4, 0.7, [36.0, 37.03], 600),
    wide(beam(2, 4, 1.3, 4, 10.0, [0.08585, 0.08682], 1500)),
    wide(beam(2, 4, 1.3, 4, 20.0, [0.01947, 0.01979], 1500)),
    radius_6(beam(2, 4, 1.3, 4, 2.5, [2.735, 2.765], 1500)),
    wide(beam(2, 4, 1.3, 1, 2.8, [0.5018, 0.5117], 1500)),
    radius_6(beam(2, 4, 1.0, 2, 1.5, [4.216, 4.295], 1500)),
    wide(beam(2, 4, 1.0, 4, 10.0, [0.02143, 0.02159], 1500)),
    wide(beam(2, 4, 1.0, 4, 20.0, [0.003306, 0.003336], 1500)),
    viscous(10.0, wide(beam(2, 5, 1.0, 1, 2.0, [0.1268, 0.1275], 1500))),
    wide(beam(2, 4, 1.3, 4, 40.0, [0.004627, 0.004658], 1500)),
    wide(beam(2, 4, 1.0, 4, 40.0, [0.0004796, 0.0004829], 1500)),
    wide(beam(2, 4, 1.0, 1, 20.0, [0.0012375, 0.0012442], 1500)),
    wide(beam(2, 4, 1.0, 1, 10.0, [0.008091, 0.008172], 1500)),
    wide(beam(2, 4, 1.0, 1, 40.0, [0.0001779, 0.0001797], 1500)),
    viscous(
        2.0,
        wide(beam(2, 4, 1.0, 4, 40.0, [0.0002872, 0.0002887], 1500)),
    ),
    viscous(
        2.0,
        wide(beam(2, 4, 1.3, 4, 40.0, [0.004480, 0.004503], 1500)),
    ),
    beam(3, 3, 1.1, 4, 2.5, [1.896, 1.910], 600),
    beam(3, 3, 1.1, 8, 5.0, [0.3716, 0.3749], 600),
    viscous(2.0, beam(3, 3, 1.1, 8, 5.0, [0.2873, 0.2888], 600)),
    viscous(4.0, beam(3, 3, 1.1, 8, 5.0, [0.2525, 0.2538], 600)),
    viscous(
        10.0,
        wide(beam(2, 4, 1.0, 1, 2.0, [0.13225, 0.13320], 1500)),
    ),
    viscous(
        10.0,
        wide(beam(2, 9, 1.0, 1, 2.0, [0.11785, 0.11870], 1500)),
    ),
    viscous(10.0, wide(beam(2, 9, 1.0, 1, 1.0, [0.7435, 0.7484], 1500))),
    viscous(10.0, wide(beam(2, 4, 1.0, 1, 2.0, [0.1313, 0.1322], 1500))),
    viscous(
        4.0,
        wide(beam(2, 4, 1.0, 4, 40.0, [0.0001943, 0.0001953], 1500)),
    ),
    viscous(
        4.0,
        wide(beam(2, 4, 1.3, 4, 40.0, [0.004409, 0.004433], 1500)),
    ),
];

/// Fraction of the model's limit that configure accepts.
pub const SAFETY: f64 = 0.95;

/// The model is explored up to this `ω dt`; a mode stable that far is not limited by the
/// coupling (the fibre's own limit, `ω h < 2`, still applies).
pub const MAX_OMEGA_DT: f64 = 8.0;

/// Points of the scan for the first instability before it is bisected.
const SCAN_POINTS: usize = 800;

/// Spectral radius of one fluid step of the one-mode model (module documentation) at
/// `ω dt = omega_dt`, `c dt = damping_dt`, coupling `k r = ratio`, `n = substeps`.
pub fn one_mode_growth(omega_dt: f64, damping_dt: f64, ratio: f64, substeps: usize) -> f64 {
    let n = substeps.max(1);
    let (h, hc) = (omega_dt / n as f64, damping_dt / n as f64);
    // In the mode's time unit 1/omega (v stands for v / omega): x' = x + h v,
    // v' = v - h x' - hc v - (ratio / n) v0, with v0 carried along unchanged.
    let a = Matrix3::new(
        1.0,
        h,
        0.0,
        -h,
        1.0 - h * h - hc,
        -ratio / n as f64,
        0.0,
        0.0,
        1.0,
    );
    let p = power(a, n);
    let b = Matrix2::new(
        p[(0, 0)],
        p[(0, 1)] + p[(0, 2)],
        p[(1, 0)],
        p[(1, 1)] + p[(1, 2)],
    );
    spectral_radius(&b)
}

fn power(mut a: Matrix3<f64>, mut n: usize) -> Matrix3<f64> {
    let mut p = Matrix3::identity();
    while n > 0 {
        if n & 1 == 1 {
            p *= a;
        }
        a = a * a;
        n >>= 1;
    }
    p
}

fn spectral_radius(b: &Matrix2<f64>) -> f64 {
    let tr = b[(0, 0)] + b[(1, 1)];
    let det = b[(0, 0)] * b[(1, 1)] - b[(0, 1)] * b[(1, 0)];
    let disc = tr * tr - 4.0 * det;
    if disc < 0.0 {
        det.abs().sqrt()
    } else {
        let s = disc.sqrt();
        (0.5 * (tr + s)).abs().max((0.5 * (tr - s)).abs())
    }
}

/// The first fluid step `dt` at which a mode of frequency `omega` grows under the model,
/// with the mass-proportional damping rate `damping` and the coupling `k r = ratio`,
/// searched up to `min(MAX_OMEGA_DT, omega below)` in `ω dt`; `None` if it is stable there.
pub fn first_unstable_step(
    omega: f64,
    damping: f64,
    ratio: f64,
    substeps: usize,
    below: f64,
) -> Option<f64> {
    let grows = |x: f64| one_mode_growth(x, damping * x / omega, ratio, substeps) > 1.0 + 1e-9;
    let end = MAX_OMEGA_DT.min(omega * below);
    let dx = MAX_OMEGA_DT / SCAN_POINTS as f64;
    let mut lo = 0.0;
    while lo < end {
        let x = (lo + dx).min(end);
        if grows(x) {
            let mut hi = x;
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if grows(mid) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return Some(lo / omega);
        }
        lo = x;
    }
    None
}

/// The explicit exchange's stiffness limit of one fibre: its first instability.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExchangeStiffnessLimit {
    /// The largest `time.dt` accepted below it: [`SAFETY`] times the model's first
    /// instability.
    pub dt_limit: f64,
    /// The mode that binds.
    pub mode: NormalMode,
    /// Its coupling `k r` (module documentation).
    pub ratio: f64,
    /// `ω dt` at which the model lets it grow.
    pub omega_dt: f64,
}

/// A mode's coupling `k r`: the flow's share times the profile-to-bead ratios weighted by
/// where its kinetic energy lies.
fn mode_ratio(m: &NormalMode, ratios: ExchangeRatios, share: f64) -> f64 {
    share * (m.translation * ratios.mass + (1.0 - m.translation) * ratios.inertia)
}

/// The limit over the fibre's `modes` (fastest first, [`crate::stability::normal_modes`]),
/// for beads whose profiles hold `ratios` of their mass and moment of inertia, damping rate
/// `damping`, Kelvin-Voigt time `internal_damping` (a mode's rate is `c + tau omega^2`) and
/// `substeps`. `None` if no mode grows below `MAX_OMEGA_DT`.
pub fn limit(
    modes: &[NormalMode],
    ratios: ExchangeRatios,
    damping: f64,
    internal_damping: f64,
    substeps: usize,
    share: f64,
) -> Option<ExchangeStiffnessLimit> {
    let mut best: Option<(f64, NormalMode, f64)> = None;
    for m in modes {
        let ratio = mode_ratio(m, ratios, share);
        let c = damping + internal_damping * m.omega * m.omega;
        let below = best.map_or(f64::INFINITY, |b| b.0);
        if let Some(dt) = first_unstable_step(m.omega, c, ratio, substeps, below) {
            if dt < below {
                best = Some((dt, *m, ratio));
            }
        }
    }
    best.map(|(dt, mode, ratio)| ExchangeStiffnessLimit {
        dt_limit: SAFETY * dt,
        mode,
        ratio,
        omega_dt: mode.omega * dt,
    })
}

/// The largest growth per fluid step of any mode for the fluid steps from `dt` to
/// `dt / SAFETY` (nine of them, evenly spaced) with the flow's share `share`
/// ([`flow_share`]), and the mode it is of.
/// Above 1 the scene's step, or one within the margin above it, lets that mode grow.
pub fn largest_growth(
    modes: &[NormalMode],
    ratios: ExchangeRatios,
    damping: f64,
    internal_damping: f64,
    (substeps, share): (usize, f64),
    dt: f64,
) -> Option<(f64, NormalMode)> {
    let mut worst: Option<(f64, NormalMode)> = None;
    for m in modes {
        let ratio = mode_ratio(m, ratios, share);
        let c = damping + internal_damping * m.omega * m.omega;
        for j in 0..9 {
            let h = dt * (1.0 + (1.0 / SAFETY - 1.0) * j as f64 / 8.0);
            let g = one_mode_growth(m.omega * h, c * h, ratio, substeps);
            if worst.is_none_or(|w| g > w.0) {
                worst = Some((g, *m));
            }
        }
    }
    worst
}

/// What the model says of a fibre at the scene's fluid step ([`check`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ExchangeStiffness {
    /// No mode grows below `ω dt` = [`MAX_OMEGA_DT`].
    Unlimited,
    /// The step is within the limit.
    Within(ExchangeStiffnessLimit),
    /// The step lies above the first instability, where the fibre's damping holds every
    /// mode again (with a [`SAFETY`] margin above the step): it runs, but lowering the step
    /// or the damping may not.
    AboveInStableWindow(ExchangeStiffnessLimit),
}

impl ExchangeStiffness {
    /// The limit the scene's step is within, for the list of time-step limits.
    pub fn limit(&self) -> Option<f64> {
        match self {
            Self::Within(l) => Some(l.dt_limit),
            _ => None,
        }
    }

    /// Advice for a step that runs above the first instability.
    pub fn note(&self, p: &str) -> Option<String> {
        let Self::AboveInStableWindow(l) = self else {
            return None;
        };
        Some(format!(
            "{p}: under the explicit SPM momentum exchange its mode of omega = {:.6e} grows \
             from time.dt = {:.6e} (omega dt = {:.3}); at this time.dt the fibre's damping \
             ({p}.damping, {p}.internal_damping) holds every mode again, so it runs, but a \
             smaller time.dt or less damping may not (docs/validation/spm.md, \"The explicit \
             exchange's stiffness limit\")",
            l.mode.omega,
            l.dt_limit / SAFETY,
            l.omega_dt
        ))
    }
}

/// The explicit exchange's stiffness check of `fibre` (free beads; ratios `r` of its
/// profiles to its beads) at the fluid step `dt`: every mode must stay bounded from `dt` to
/// `dt / SAFETY` ([`largest_growth`]), else the refusal names the mode, the limit and the
/// cures. `p` is the key prefix (`fibre.N`); `omega_max` the power iteration's (over the
/// whole fibre), to which the modes are raised where a long fibre's first
/// [`crate::stability::MAX_MODE_BEADS`] beads fall short of it.
pub fn check(
    p: &str,
    (fibre, density): (&Fibre, f64),
    omega_max: f64,
    r: ExchangeRatios,
    (dt, share): (f64, f64),
) -> Result<ExchangeStiffness, String> {
    let mut modes = normal_modes(fibre);
    if let Some(top) = modes.first().map(|m| m.omega) {
        let raise = (omega_max / top).max(1.0);
        modes.iter_mut().for_each(|m| m.omega *= raise);
    }
    let (c, n) = (fibre.damping, fibre.substeps);
    let growth = |tau: f64| largest_growth(&modes, r, c, tau, (n, share), dt);
    let lim = limit(&modes, r, c, fibre.internal_damping, n, share);
    let worst = growth(fibre.internal_damping);
    let Some((g, mode)) = worst.filter(|w| w.0 > 1.0 + 1e-9) else {
        return Ok(match lim {
            None => ExchangeStiffness::Unlimited,
            Some(l) if dt <= l.dt_limit => ExchangeStiffness::Within(l),
            Some(l) => ExchangeStiffness::AboveInStableWindow(l),
        });
    };
    // The Kelvin-Voigt time that lets the exchange and the fibre's own step run at dt.
    let damping = (0..=48)
        .map(|k| dt * 10f64.powf(-4.0 + k as f64 / 8.0))
        .filter(|&tau| tau > fibre.internal_damping)
        .find(|&tau| {
            let own = stable_step(omega_max, c + tau * omega_max * omega_max);
            own * STEP_SAFETY * n as f64 >= dt && growth(tau).is_none_or(|w| w.0 <= 1.0)
        })
        .map_or(String::new(), |tau| {
            format!(", give the bonds internal damping ({p}.internal_damping = {tau:.3e} or more)")
        });
    // Heavier beads: f times the density divides every ratio by f and every mode's omega by
    // sqrt f (the beads' mass and moment of inertia both grow with it, bead_inertia "solid"
    // or "profile"), which also relaxes the fibre's own step.
    let carries = |f: f64| {
        let (w, tau) = (omega_max / f.sqrt(), fibre.internal_damping);
        let own = stable_step(w, c + tau * w * w);
        let slower: Vec<_> = modes
            .iter()
            .map(|m| NormalMode {
                omega: m.omega / f.sqrt(),
                ..*m
            })
            .collect();
        let lighter = ExchangeRatios {
            mass: r.mass / f,
            inertia: r.inertia / f,
        };
        own * STEP_SAFETY * n as f64 >= dt
            && largest_growth(&slower, lighter, c, tau, (n, share), dt)
                .is_none_or(|w| w.0 <= 1.0 + 1e-9)
    };
    // The first of 5 % steps that carries the fibre, then bisected down to 0.01 % (a factor
    // that passes is kept).
    let heavier = (1..=64)
        .map(|j| 1.05f64.powi(j))
        .find(|&f| carries(f))
        .map(|mut f| {
            let mut below = f / 1.05;
            while f / below > 1.0001 {
                let mid = (f * below).sqrt();
                if carries(mid) {
                    f = mid;
                } else {
                    below = mid;
                }
            }
            f
        })
        .map_or(String::new(), |f| {
            // Rounded up, so that the density named passes too.
            let at_least = (density * f * 1e4).ceil() / 1e4;
            format!(", raise {p}.density to at least {at_least:.4}")
        });
    let lower = lim.map_or(String::new(), |l| {
        format!(
            ", lower time.dt to at most {:.6e} (the first instability, omega dt = {:.3} of its \
             mode of omega = {:.6e}, times {SAFETY}) or scale all of the fibre's stiffnesses by \
             at most {:.4e}",
            l.dt_limit,
            l.omega_dt,
            l.mode.omega,
            (l.dt_limit / dt).powi(2)
        )
    });
    Err(format!(
        "{p} is too stiff for the explicit SPM momentum exchange at time.dt = {dt:?}: the \
         fluid's impulse, taken once a step at the velocity of the step's start (L2020 eqs. \
         35-36), feeds its mode of omega = {:.6e} (omega dt = {:.3}; {:.0} % of its kinetic \
         energy in translation, flow share times profile-to-bead ratio k r = {:.3}), which \
         grows by {g:.4} a step at this time.dt or up to {:.0} % above it (a one-mode model \
         with the flow share k = {share} for this nu dt / xi^2, docs/validation/spm.md \
         \"The explicit exchange's stiffness limit\"); set {p}.exchange = \"implicit\" (no \
         such limit){damping}{heavier}{lower}",
        mode.omega,
        mode.omega * dt,
        100.0 * mode.translation,
        mode_ratio(&mode, r, share),
        100.0 * (1.0 / SAFETY - 1.0),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::parse_scene;
    use crate::quaternion::Vec3;
    use crate::spm_exchange::ratios;

    /// The fibre of a measured case at Young's modulus `e`: its modes and profile-to-bead
    /// ratios.
    fn case(t: &MeasuredThreshold, e: f64) -> (Vec<NormalMode>, ExchangeRatios) {
        let (f, r) = case_fibre(t, e, "");
        (normal_modes(&f), r)
    }

    /// The flow share at which the model's first instability (less the margin) falls on
    /// the measured threshold `t` (at the geometric mean of its two moduli), by bisection.
    fn implied_share(t: &MeasuredThreshold) -> f64 {
        let (modes, r) = case(t, (t.runs * t.fails).sqrt());
        let model = |k: f64| {
            limit(&modes, r, 0.0, 0.0, t.substeps, k).map_or(f64::INFINITY, |l| l.dt_limit / SAFETY)
        };
        // The model's limit falls with k, to none at all past the light-bead limit k r = 2.
        let (mut lo, mut hi) = (0.0, 1.5);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if model(mid) > t.dt {
                lo = mid
            } else {
                hi = mid
            }
        }
        lo
    }

    #[test]
    #[ignore = "exploration: prints the flow share each measured threshold implies"]
    fn implied_flow_shares() {
        for t in MEASURED_THRESHOLDS.iter().chain(&HELD_OUT_THRESHOLDS) {
            let e = (t.runs * t.fails).sqrt();
            let (modes, r) = case(t, e);
            let lo = implied_share(t);
            let l1 = limit(&modes, r, 0.0, 0.0, t.substeps, 1.0).unwrap();
            let acc = limit(&modes, r, 0.0, 0.0, t.substeps, t.share()).unwrap();
            println!(
                "{} {}D N={} r_b={} xi={} rho={} n={} dt={} (nu dt/xi^2 {}): omega_max dt = {:.3}, k = {:.3}; k=1: limit omega dt {:.3} (mode omega dt at scene {:.3}, s {:.3}, kr {:.3}); the check (k = {:.4}) accepts omega_max dt {:.3} = {:.3} of the measured",
                t.model, t.dimensions, t.beads, t.bead_radius, t.xi, t.density, t.substeps, t.dt, t.diffusion_number(), modes[0].omega * t.dt, lo,
                modes[0].omega * l1.dt_limit / SAFETY, l1.mode.omega * t.dt, l1.mode.translation, l1.ratio,
                t.share(), modes[0].omega * acc.dt_limit, acc.dt_limit / t.dt
            );
        }
    }

    /// The share steps up above the calibrated diffusion number and grows along the ramp,
    /// never below the share any measured threshold implies at its diffusion number (the
    /// smallest margins: 0.982 at 5 against 0.985, 1.012 at 10 against 1.015, 1.024 at 20
    /// against 1.025, 1.026 at 40 against 1.027).
    #[test]
    fn the_flow_share_grows_with_the_diffusion_number() {
        assert_eq!(flow_share(Some(0.25)), FLOW_SHARE);
        assert_eq!(flow_share(Some(0.7)), FLOW_SHARE);
        assert_eq!(flow_share(Some(0.71)), FLOW_SHARE_ABOVE_CALIBRATED);
        assert_eq!(flow_share(Some(2.5)), FLOW_SHARE_ABOVE_CALIBRATED);
        assert!((flow_share(Some(3.75)) - 0.9675).abs() < 1e-12);
        assert_eq!(flow_share(Some(5.0)), 0.985);
        assert_eq!(flow_share(Some(10.0)), 1.015);
        assert_eq!(flow_share(Some(20.0)), 1.025);
        assert_eq!(flow_share(Some(40.0)), 1.027);
        assert!((flow_share(Some(80.0)) - 1.037).abs() < 1e-12);
        assert_eq!(flow_share(None), 1.027);
        let mut last = 0.0;
        for i in 0..=200 {
            let k = flow_share(Some(0.06 * i as f64));
            assert!(k >= last, "{k} after {last}");
            last = k;
        }
        let mut above = 0;
        for t in MEASURED_THRESHOLDS.iter().chain(&HELD_OUT_THRESHOLDS) {
            let implied = implied_share(t);
            assert!(
                implied <= t.share(),
                "{t:?}: implies {implied}, the check takes {}",
                t.share()
            );
            above += usize::from(t.diffusion_number() > FLOW_SHARE_RAMP[0].0);
        }
        assert_eq!(
            above, 17,
            "the measured cases above 2.5: eight at 5, four at 10, three at 20, two at 40"
        );
    }

    /// One sub-step matches the closed form: `B = [[1, x], [−x, 1 − x² − r]]` with `x = ω dt`
    /// has `det = 1 − r` and `tr = 2 − x² − r`, and Jury's condition `|tr| <= 1 + det` puts
    /// the first instability at `x = sqrt(4 − 2 r)`.
    #[test]
    fn one_sub_step_matches_the_closed_form() {
        for r in [0.0, 0.1, 0.5, 1.0, 1.5, 1.9] {
            let omega = 2.5;
            let dt = first_unstable_step(omega, 0.0, r, 1, f64::INFINITY).unwrap();
            let exact = (4.0 - 2.0 * r).sqrt();
            assert!(
                // The growth tolerance, 1e-9, moves the crossing by as much.
                (omega * dt - exact).abs() < 1e-8,
                "r = {r}: {} vs {exact}",
                omega * dt
            );
        }
        // At r >= 2 the drag alone overshoots: no stable step.
        assert!(first_unstable_step(1.0, 0.0, 2.1, 4, f64::INFINITY).unwrap() < 1e-2);
        // Damping only raises it.
        let (plain, damped) = (
            first_unstable_step(1.0, 0.0, 1.0, 4, f64::INFINITY).unwrap(),
            first_unstable_step(1.0, 0.5, 1.0, 4, f64::INFINITY).unwrap(),
        );
        assert!(damped > plain, "{damped} vs {plain}");
    }

    /// `fibre` advanced `steps` fluid steps of `dt`, each bead given once per step the
    /// impulse of a fluid at rest that takes all of its profile's excess motion (k = 1):
    /// `J = −m_phi U^n`, `J_ang = −I_phi Omega^n`, with `U^n`, `Omega^n` the velocities the
    /// predictor publishes (those of the step's start). Returns the fibre's energy (kinetic
    /// plus elastic) at the end over that at the start, which is a deterministic mix of
    /// every mode.
    fn energy_gain(mut f: Fibre, dt: f64, m_phi: f64, i_phi: f64, steps: usize) -> f64 {
        for k in 0..f.len() {
            let s = [1.0, -0.6, 0.35, -0.9, 0.7][k % 5];
            f.vel[k] = Vec3::new(1e-3 * s, 0.8e-3 * s * s, 0.0);
            f.omega[k] = Vec3::new(0.0, 0.0, 0.3e-3 * s);
        }
        f.compute_forces();
        let energy = |f: &Fibre| f.kinetic_energy() + f.energies.total();
        let e0 = energy(&f);
        let mut imp = vec![cosim::BeadImpulse::default(); f.len()];
        for _ in 0..steps {
            f.advance_positions(dt);
            for (k, j) in imp.iter_mut().enumerate() {
                j.impulse = (-m_phi * f.vel[k]).into();
                j.angular_impulse = (-i_phi * f.omega[k]).into();
            }
            f.advance_velocities(dt, Some(&imp), true);
        }
        energy(&f) / e0
    }

    /// The first `dt` at which [`energy_gain`] over 3000 steps exceeds 1 (or overflows),
    /// bisected between `lo` (stable) and `hi` (grows).
    fn measured_threshold(f: &Fibre, m_phi: f64, i_phi: f64, mut lo: f64, mut hi: f64) -> f64 {
        let grows = |dt: f64| !(energy_gain(f.clone(), dt, m_phi, i_phi, 3000) <= 1.0);
        assert!(!grows(lo) && grows(hi));
        for _ in 0..20 {
            let mid = 0.5 * (lo + hi);
            if grows(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// The fibre's own integrator (sub-steps, predictor-corrector, the impulse spread over
    /// the sub-steps) fed the explicit exchange's drag goes unstable where the model says.
    /// A bead-spring chain has translational modes only, so each mode's ratio is exactly the
    /// mass ratio and the model is exact (tolerance 1 %, the bisection's and growth
    /// detection's resolution). A cohesive beam's modes mix translation and rotation, which
    /// the drag treats with different ratios; the model weights them by the mode's kinetic
    /// energy (module documentation) and is approximate (tolerance 5 %).
    #[test]
    fn the_fibre_integrator_goes_unstable_where_the_model_says() {
        for (model, substeps, density, tolerance) in [
            ("bead-spring", 4, 1.0, 0.01),
            ("bead-spring", 1, 1.5, 0.01),
            ("cohesive-beam", 4, 1.5, 0.05),
            ("cohesive-beam", 5, 1.0, 0.05),
        ] {
            let t = MeasuredThreshold {
                model,
                ..beam(2, 4, density, substeps, 1.0, [100.0, 100.0], 0)
            };
            let (f, r) = case_fibre(&t, 100.0, "");
            let modes = normal_modes(&f);
            let predicted = limit(&modes, r, 0.0, 0.0, substeps, 1.0).unwrap();
            let predicted = predicted.dt_limit / SAFETY;
            let measured = measured_threshold(
                &f,
                r.mass * f.mass,
                r.inertia * f.inertia,
                0.5 * predicted,
                1.5 * predicted,
            );
            println!("{model}, {substeps} sub-steps, density {density}: measured {measured:.5}, model {predicted:.5}");
            assert!(
                (measured / predicted - 1.0).abs() < tolerance,
                "{model} n = {substeps}: {measured} vs {predicted}"
            );
        }
    }

    /// The fibre of a measured case at Young's modulus `e`, as configure builds it.
    fn case_fibre(t: &MeasuredThreshold, e: f64, extra: &str) -> (Fibre, ExchangeRatios) {
        let s = parse_scene(&format!(
            "dimensions = {}\n[time]\ndt = {}\n[fluid]\nxi = {:?}\nxi_cutoff = {:?}\n[[fibre]]\nmodel = \"{}\"\nbeads = {}\nbead_radius = {:?}\nyoungs_modulus = {e:?}\ndensity = {:?}\nsubsteps = {}\n{}{extra}",
            t.dimensions, t.dt, t.xi, t.xi_cutoff, t.model, t.beads, t.bead_radius, t.density, t.substeps,
            if t.chord { "bead_spin = \"chord\"\n" } else { "" }
        ))
        .unwrap();
        let f = Fibre::straight(&s.fibres[0], s.dimensions, true);
        let r = ratios(
            s.spm_profile.unwrap(),
            1.0,
            t.bead_radius,
            t.dimensions as usize,
            f.mass,
            f.inertia,
        );
        (f, r)
    }

    fn check_case(t: &MeasuredThreshold, e: f64, extra: &str) -> Result<ExchangeStiffness, String> {
        let (f, r) = case_fibre(t, e, extra);
        let omega_max = crate::stability::stability_limit(&f, t.substeps).omega_max;
        check("fibre.0", (&f, t.density), omega_max, r, (t.dt, t.share()))
    }

    /// Whether the check accepts 60 % of the last Young's modulus of `t` that ran.
    fn accepts_most_of_the_last_run(t: &MeasuredThreshold) -> Result<(), String> {
        match check_case(t, 0.6 * t.runs, "") {
            Ok(ExchangeStiffness::Within(l)) if l.dt_limit >= t.dt => Ok(()),
            other => Err(format!("{t:?}: {other:?}")),
        }
    }

    /// The nine-bead capillary fibre (`tumbling_2d.toml` at time.dt = 2): the one case the
    /// check is far too strict on ([`accepts_most_of_the_nine_bead_capillary_fibre`]).
    fn nine_beads(t: &MeasuredThreshold) -> bool {
        t.beads == 9 && t.dt == 2.0
    }

    /// Every measured threshold, those calibrated on and those held out: the check refuses
    /// the first Young's modulus that failed, and accepts 60 % of the last that ran (the
    /// accepted step lies 6-21 % under the measured one; 60 % in modulus is 77 % in step),
    /// but for the nine-bead fibre below.
    #[test]
    fn refuses_every_measured_failure_and_accepts_below_it() {
        for t in MEASURED_THRESHOLDS.iter().chain(&HELD_OUT_THRESHOLDS) {
            let e = check_case(t, t.fails, "").unwrap_err();
            assert!(
                e.contains("too stiff for the explicit SPM momentum exchange"),
                "{e}"
            );
            if !nine_beads(t) {
                accepts_most_of_the_last_run(t).unwrap();
            }
        }
    }

    /// NOT met: on the nine-bead fibre of `tumbling_2d.toml` at time.dt = 2 (nu dt / xi^2 =
    /// 5, density 1) the check accepts 66 % of the measured threshold step, 44 % of its
    /// modulus. The share a fibre's threshold implies falls with its length there (four
    /// beads 0.975, five 0.965, nine 0.955) while the modelled ratio r of its limiting mode
    /// rises (1.92, 1.94, 1.97), so that k r at the threshold stays near 1.88 (at 2.5: 1.81
    /// for four and nine beads, k 0.939 and 0.920; there the check accepts 79 %): the one-mode
    /// model over-weights the rotation of a long fibre's fastest modes near the light-bead
    /// limit, and the check, calibrated on four beads, refuses long fibres it could carry.
    #[test]
    #[ignore = "the check is a third too strict on long fibres near the light-bead limit (docs/validation/spm.md, k grows with nu dt / xi^2)"]
    fn accepts_most_of_the_nine_bead_capillary_fibre() {
        let nine: Vec<_> = HELD_OUT_THRESHOLDS
            .iter()
            .filter(|t| nine_beads(t))
            .collect();
        assert_eq!(nine.len(), 1);
        accepts_most_of_the_last_run(nine[0]).unwrap();
    }

    /// Heavier beads are a cure the refusal names: near the light-bead limit (density 1.0,
    /// xi = 2, nu dt / xi^2 = 5 to 40) a few per cent more density lets the measured failing
    /// modulus pass, and the density it names does pass the check.
    #[test]
    fn the_refusal_names_a_density_that_passes() {
        let mut seen = 0;
        for t in HELD_OUT_THRESHOLDS
            .iter()
            .filter(|t| t.density == 1.0 && t.xi == 2.0 && t.diffusion_number() >= 5.0)
        {
            let e = check_case(t, t.fails, "").unwrap_err();
            let named = e
                .split("raise fibre.0.density to at least ")
                .nth(1)
                .and_then(|rest| rest.split(',').next())
                .and_then(|v| v.parse::<f64>().ok())
                .unwrap_or_else(|| panic!("no density cure in: {e}"));
            assert!(named > 1.0 && named < 1.2, "{t:?}: {named}");
            let heavier = MeasuredThreshold {
                density: named,
                ..*t
            };
            assert!(
                check_case(&heavier, t.fails, "").is_ok(),
                "{t:?} at {named}"
            );
            seen += 1;
        }
        assert_eq!(seen, 10, "the density-1.0 cases at nu dt / xi^2 >= 5");
    }

    /// The hard case of docs/validation/spm.md (`tests/spm.rs::stiff_fibre_run`, k0 / (L0
    /// eta gamma) = 1e6, five sub-steps, density 1.5): refused without internal damping,
    /// naming the limit and the cures; with the damping of the test that runs it (tau =
    /// 0.005) every mode is held at dt = 0.25, above the first instability (a note, no limit).
    /// Measured: tau = 0.002 fails at step 1246, 0.0025 runs 6000 steps; the model wants at
    /// least 0.002-0.0033 (it suggests the first value of its grid that holds).
    #[test]
    fn the_hard_case_is_refused_without_damping_and_runs_with_it() {
        let t = beam(2, 4, 1.5, 5, 0.25, [0.0, 0.0], 0);
        let e = check_case(&t, 1591.5, "").unwrap_err();
        for s in [
            "fibre.0 is too stiff for the explicit SPM momentum exchange at time.dt = 0.25",
            "fibre.0.exchange = \"implicit\"",
            "fibre.0.internal_damping = 3.334e-3 or more",
            "lower time.dt to at most 8.187",
        ] {
            assert!(e.contains(s), "{s:?} missing from: {e}");
        }
        assert!(check_case(&t, 1591.5, "internal_damping = 0.002\n").is_err());
        let held = check_case(&t, 1591.5, "internal_damping = 0.005\n").unwrap();
        assert!(
            matches!(held, ExchangeStiffness::AboveInStableWindow(_)),
            "{held:?}"
        );
        assert!(held.limit().is_none());
        assert!(held
            .note("fibre.0")
            .unwrap()
            .contains("holds every mode again"));
    }
}
