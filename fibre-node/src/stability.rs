//! Largest stable time step of the fibre integrator ("beam stiffness" limit).
//!
//! Linearised about the initial (straight, unloaded) configuration, the free beads obey
//! `M ü = −K u` with generalised coordinates u = bead displacements and small rotation
//! vectors (3 + 3 per bead in 3D; x, y and the rotation about z in 2D; no rotations for the
//! bead-spring model, which has no elastic torques). Position-first symplectic Euler with
//! mass-proportional damping `c` (`F_d = −c m V`, `T_d = −c I Ω`) is stable for every mode
//! when `h² ω² + 2 h c < 4`, i.e.
//! `h < h_max = 4 / (c + sqrt(c² + 4 ω_max²))` (`= 2 / ω_max` without damping),
//! where `ω_max²` is the largest eigenvalue of `M⁻¹K`. We compute it by a fixed number of
//! power iterations on the symmetric `M^{-1/2} K M^{-1/2}`, with Jacobian–vector products by
//! central finite differences of the force/torque function, from a deterministic start
//! vector (alternating bead signs, which is close to the top of a chain's spectrum, times a
//! fixed pseudo-random pattern). The result is deterministic and accurate to ~1e-3 (tests
//! compare with dense eigenvalues); configure applies a 2 % margin.
use crate::fibre::Fibre;
use crate::quaternion::{exp_half, Vec3};

/// Power iterations used.
pub const POWER_ITERATIONS: usize = 400;
/// Longest chain the power iteration runs on (see [`representative`]).
pub const MAX_ESTIMATE_BEADS: usize = 256;
/// Fraction of the computed `h_max` that `configure` accepts.
pub const SAFETY: f64 = 0.98;

/// The beam-stiffness limit of one fibre and the numbers it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct StabilityLimit {
    /// Name of the limit, "beam stiffness".
    pub name: &'static str,
    /// Largest angular frequency of the linearised internal dynamics, `ω_max`.
    pub omega_max: f64,
    /// Damping rate `c` used.
    pub damping: f64,
    /// Sub-steps per fluid step.
    pub substeps: usize,
    /// Largest stable internal step `h_max`.
    pub step_limit: f64,
    /// Largest stable `time.dt` (= `substeps · h_max · SAFETY`).
    pub dt_limit: f64,
    /// Power iterations used.
    pub iterations: usize,
    /// Generalised coordinates (free degrees of freedom).
    pub dofs: usize,
}

/// `h_max` for symplectic Euler with mass-proportional damping.
pub fn stable_step(omega_max: f64, damping: f64) -> f64 {
    if !omega_max.is_finite() {
        // Infinitely stiff (or overflowed): no step is stable.
        0.0
    } else if omega_max <= 0.0 {
        if damping > 0.0 {
            2.0 / damping
        } else {
            f64::INFINITY
        }
    } else {
        4.0 / (damping + (damping * damping + 4.0 * omega_max * omega_max).sqrt())
    }
}

#[derive(Debug, Clone, Copy)]
struct Dof {
    bead: usize,
    rotation: bool,
    axis: usize,
}

fn dofs_of(f: &Fibre) -> Vec<Dof> {
    let axes: &[usize] = if f.planar { &[0, 1] } else { &[0, 1, 2] };
    let raxes: &[usize] = if f.planar { &[2] } else { &[0, 1, 2] };
    let mut d = Vec::new();
    for b in 0..f.len() {
        if f.clamped[b] {
            continue;
        }
        for &a in axes {
            d.push(Dof {
                bead: b,
                rotation: false,
                axis: a,
            });
        }
        if f.elastic_torques {
            for &a in raxes {
                d.push(Dof {
                    bead: b,
                    rotation: true,
                    axis: a,
                });
            }
        }
    }
    d
}

/// `1 / sqrt(m)` of each coordinate: the bead's mass or moment of inertia.
fn inv_sqrt_masses(fibre: &Fibre, dofs: &[Dof]) -> Vec<f64> {
    dofs.iter()
        .map(|d| {
            1.0 / if d.rotation {
                fibre.inertia
            } else {
                fibre.mass
            }
            .sqrt()
        })
        .collect()
}

/// Generalised internal forces at `base` displaced by `s u` (u in generalised coordinates).
fn forces_at(work: &mut Fibre, base: &Fibre, dofs: &[Dof], u: &[f64], s: f64, out: &mut [f64]) {
    work.pos.copy_from_slice(&base.pos);
    work.quat.copy_from_slice(&base.quat);
    for (d, &x) in dofs.iter().zip(u) {
        if d.rotation {
            let mut phi = Vec3::zeros();
            phi[d.axis] = s * x;
            work.quat[d.bead] = exp_half(&phi) * work.quat[d.bead];
        } else {
            work.pos[d.bead][d.axis] += s * x;
        }
    }
    work.internal_forces();
    for (d, o) in dofs.iter().zip(out.iter_mut()) {
        *o = if d.rotation {
            work.torque[d.bead][d.axis]
        } else {
            work.force[d.bead][d.axis]
        };
    }
}

/// Largest eigenvalue `ω_max²` of `M⁻¹K` at the fibre's current configuration (power
/// iteration, [`POWER_ITERATIONS`] steps), and the number of generalised coordinates.
pub fn max_eigenvalue(fibre: &Fibre, iterations: usize) -> (f64, usize) {
    let dofs = dofs_of(fibre);
    let n = dofs.len();
    if n == 0 {
        return (0.0, 0);
    }
    let mut work = fibre.clone();
    let inv_sqrt_mass = inv_sqrt_masses(fibre, &dofs);
    // Deterministic start: alternating sign per bead times a fixed pseudo-random pattern.
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut y: Vec<f64> = dofs
        .iter()
        .map(|d| {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let r = 0.5 + (seed >> 11) as f64 / (1u64 << 53) as f64;
            if d.bead % 2 == 0 {
                r
            } else {
                -r
            }
        })
        .collect();
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let ny = norm(&y);
    y.iter_mut().for_each(|x| *x /= ny);
    let mut u = vec![0.0; n];
    let mut fp = vec![0.0; n];
    let mut fm = vec![0.0; n];
    let scale = fibre.rest_length() * 1e-6;
    let mut lambda = 0.0;
    for _ in 0..iterations {
        for k in 0..n {
            u[k] = y[k] * inv_sqrt_mass[k];
        }
        let umax = u.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let s = scale / umax;
        forces_at(&mut work, fibre, &dofs, &u, s, &mut fp);
        forces_at(&mut work, fibre, &dofs, &u, -s, &mut fm);
        // A y = M^{-1/2} K u, K u = −(F(+) − F(−)) / 2s.
        let mut dot = 0.0;
        for k in 0..n {
            let a = -(fp[k] - fm[k]) / (2.0 * s) * inv_sqrt_mass[k];
            fp[k] = a;
            dot += a * y[k];
        }
        lambda = dot;
        let na = norm(&fp);
        if na == 0.0 {
            return (0.0, n);
        }
        for k in 0..n {
            y[k] = fp[k] / na;
        }
    }
    if !lambda.is_finite() {
        // Stiffnesses so large that the forces overflow: no step is stable (a NaN would
        // otherwise read as a fibre with no stiffness at all).
        return (f64::INFINITY, n);
    }
    (lambda.max(0.0), n)
}

/// The chain the estimate runs on: the fibre itself, or for a fibre longer than
/// [`MAX_ESTIMATE_BEADS`] its first `MAX_ESTIMATE_BEADS` beads with no clamps and no loads.
/// For a straight uniform fibre (as configure builds them) that is an upper bound of the
/// full fibre's `ω_max²` up to O(1/256²): clamping beads takes a principal submatrix and a
/// free end removes a positive semi-definite element term, and neither raises the largest
/// eigenvalue (Cauchy interlacing), while the top of a uniform chain's spectrum converges to
/// the infinite chain's as 1/N².
pub fn representative(fibre: &Fibre) -> std::borrow::Cow<'_, Fibre> {
    first_beads(fibre, MAX_ESTIMATE_BEADS)
}

/// The fibre itself if it has at most `n` beads, else its first `n` beads with no clamps and
/// no loads.
fn first_beads(fibre: &Fibre, n: usize) -> std::borrow::Cow<'_, Fibre> {
    if fibre.len() <= n {
        return std::borrow::Cow::Borrowed(fibre);
    }
    let mut f = fibre.clone();
    f.pos.truncate(n);
    f.quat.truncate(n);
    f.vel.truncate(n);
    f.omega.truncate(n);
    f.force.truncate(n);
    f.torque.truncate(n);
    f.clamped = vec![false; n];
    f.loads.clear();
    std::borrow::Cow::Owned(f)
}

/// Longest chain [`mass_weighted_stiffness_matrix`] forms (a dense eigenproblem of up to
/// 6 x 32 unknowns for its modes).
pub const MAX_MODE_BEADS: usize = 32;

/// Dense `M^{-1/2} K M^{-1/2}` of the fibre's free coordinates, by central finite differences
/// of the force/torque function (symmetric up to the differencing error); and the coordinates.
fn mass_weighted_stiffness(fibre: &Fibre) -> (nalgebra::DMatrix<f64>, Vec<Dof>) {
    let dofs = dofs_of(fibre);
    let n = dofs.len();
    let mut work = fibre.clone();
    let mut a = nalgebra::DMatrix::zeros(n, n);
    let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
    let w = inv_sqrt_masses(fibre, &dofs);
    let s = fibre.rest_length() * 1e-6;
    let mut u = vec![0.0; n];
    for c in 0..n {
        u.iter_mut().for_each(|x| *x = 0.0);
        u[c] = 1.0;
        forces_at(&mut work, fibre, &dofs, &u, s, &mut fp);
        forces_at(&mut work, fibre, &dofs, &u, -s, &mut fm);
        for r in 0..n {
            a[(r, c)] = -(fp[r] - fm[r]) / (2.0 * s) * w[r] * w[c];
        }
    }
    (a, dofs)
}

/// `M^{-1/2} K M^{-1/2}` of the free coordinates of the fibre about its current (initial)
/// configuration, symmetrised, and whether each coordinate is a rotation: of the fibre
/// itself, or for a fibre longer than [`MAX_MODE_BEADS`] of its first `MAX_MODE_BEADS`
/// beads with no clamps (a uniform chain's spectrum, branch by branch, is then sampled at
/// 32 wavenumbers; its top lies within O(1/32²) of the full fibre's).
pub fn mass_weighted_stiffness_matrix(fibre: &Fibre) -> (nalgebra::DMatrix<f64>, Vec<bool>) {
    let f = first_beads(fibre, MAX_MODE_BEADS);
    let (a, dofs) = mass_weighted_stiffness(&f);
    (
        (&a + a.transpose()) * 0.5,
        dofs.iter().map(|d| d.rotation).collect(),
    )
}

/// The beam-stiffness limit of a fibre about its current (initial) configuration.
pub fn stability_limit(fibre: &Fibre, substeps: usize) -> StabilityLimit {
    let (lambda, dofs) = max_eigenvalue(&representative(fibre), POWER_ITERATIONS);
    let omega_max = lambda.sqrt();
    // Kelvin-Voigt damping acts on a mode of frequency omega as a rate tau omega^2; the
    // limit falls with omega, so the fastest mode binds.
    let damping = if fibre.internal_damping == 0.0 {
        fibre.damping // not 0 x inf for an overflowed omega_max
    } else {
        fibre.damping + fibre.internal_damping * omega_max * omega_max
    };
    let step_limit = stable_step(omega_max, damping);
    StabilityLimit {
        name: "beam stiffness",
        omega_max,
        damping,
        substeps,
        step_limit,
        dt_limit: step_limit * SAFETY * substeps as f64,
        iterations: POWER_ITERATIONS,
        dofs,
    }
}

/// The stiffness limit of a bead-spring fibre under FPD (S2023 section II C), about its
/// initial configuration.
///
/// Under FPD a bead has no inertia of its own: its force is spread over its profile as a
/// force density (S2023 eq. 4) and it moves with the profile-weighted flow (eq. 5), one
/// lattice step later. At the lattice's shortest time scales the force accelerates the fluid
/// the bead displaces, so the explicit loop "forces from positions, flow, positions from
/// flow" behaves like position-first symplectic Euler with the bead's fluid mass
/// `fluid_mass = rho pi a^2` (2D): stable while `dt < 2 / ω_max`, with `ω_max` the chain's
/// fastest mode with that mass on every bead. The real threshold differs from that by a factor that
/// depends on the interface ratio r_xi = xi / d, measured (fluid viscosity, r_eta, a and
/// rho did not move it); the limit is [`fpd_margin`]`(r_xi) · 2 / ω_max`, 10 % under the
/// measured threshold. `fibre` should be straight: the thresholds were measured on straight
/// chains, and a bent start fails at the same stiffness though its `ω_max` is higher.
pub fn fpd_stiffness_limit(fibre: &Fibre, fluid_mass: f64, interface_ratio: f64) -> StabilityLimit {
    let mut f = representative(fibre).into_owned();
    f.mass = fluid_mass;
    f.damping = 0.0;
    f.internal_damping = 0.0;
    let mut lim = stability_limit(&f, 1);
    lim.name = "FPD fibre stiffness";
    lim.dt_limit = lim.step_limit * fpd_margin(interface_ratio);
    lim
}

/// The stability thresholds of the FPD coupling measured against r_xi, as fractions of
/// `2 / ω_max` (bead mass `rho pi a^2`): the lower of the stretching and the bending mode of
/// a 10-bead fibre, d = 4, bisected over 6000-step runs (docs/validation/fpd.md, "Fibre
/// stiffness under FPD"; d = 8, 3 beads, rho = 4, eta_f from 0.125 to 2 and r_eta from 25
/// to 1000 gave the same or higher).
pub const FPD_MEASURED_THRESHOLDS: [(f64, f64); 7] = [
    (1.0 / 128.0, 0.719),
    (1.0 / 32.0, 0.742),
    (1.0 / 16.0, 0.790),
    (1.0 / 8.0, 0.859),
    (3.0 / 16.0, 0.983),
    (1.0 / 4.0, 1.186),
    (1.0 / 2.0, 2.191),
];

/// Safety factor between a measured threshold and the limit [`fpd_margin`] applies.
pub const FPD_THRESHOLD_MARGIN: f64 = 1.1;

/// The fraction of `2 / ω_max` that [`fpd_stiffness_limit`] accepts at r_xi: the measured
/// threshold ([`FPD_MEASURED_THRESHOLDS`], linear between the measured r_xi, held beyond
/// them) over [`FPD_THRESHOLD_MARGIN`].
pub fn fpd_margin(interface_ratio: f64) -> f64 {
    let t = &FPD_MEASURED_THRESHOLDS;
    let threshold = if interface_ratio <= t[0].0 {
        t[0].1
    } else if interface_ratio >= t[t.len() - 1].0 {
        t[t.len() - 1].1
    } else {
        let k = t
            .windows(2)
            .position(|w| interface_ratio <= w[1].0)
            .unwrap_or(0);
        let ((r0, f0), (r1, f1)) = (t[k], t[k + 1]);
        f0 + (f1 - f0) * (interface_ratio - r0) / (r1 - r0)
    };
    threshold / FPD_THRESHOLD_MARGIN
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The margin passes through the measured thresholds over the safety factor, between
    /// them linearly, and is held beyond them.
    #[test]
    fn fpd_margin_follows_the_measured_thresholds() {
        for (r_xi, threshold) in FPD_MEASURED_THRESHOLDS {
            assert!((fpd_margin(r_xi) * FPD_THRESHOLD_MARGIN - threshold).abs() < 1e-12);
        }
        assert!((fpd_margin(0.09375) - 0.5 * (0.790 + 0.859) / 1.1).abs() < 1e-12);
        assert_eq!(fpd_margin(1e-6), fpd_margin(1.0 / 128.0));
        assert_eq!(fpd_margin(4.0), fpd_margin(0.5));
    }
    use crate::config::parse_scene;

    fn fibre(model: &str, beads: usize, dims: u8, extra: &str) -> Fibre {
        let s = parse_scene(&format!(
            "dimensions = {dims}\n[time]\ndt = 1\n[[fibre]]\nmodel = \"{model}\"\nbeads = {beads}\nbead_radius = 1.2\nyoungs_modulus = 2.5\ndensity = 0.8\n{extra}\n"
        ))
        .unwrap();
        Fibre::straight(&s.fibres[0], s.dimensions, s.has_fluid)
    }

    /// Dense M^{-1/2} K M^{-1/2} by finite differences, largest eigenvalue.
    fn dense_max(f: &Fibre) -> f64 {
        let (a, dofs) = mass_weighted_stiffness(f);
        if dofs.is_empty() {
            return 0.0;
        }
        let sym = (&a + a.transpose()) * 0.5;
        let asym = (&a - &sym).abs().max() / a.abs().max();
        assert!(asym < 1e-6, "K not symmetric: {asym:e} {}", dofs.len());
        sym.symmetric_eigenvalues().max()
    }

    /// A stiffness whose forces overflow reads as infinitely stiff, with no stable step,
    /// not (through a NaN) as no stiffness at all.
    #[test]
    fn overflowing_stiffness_has_no_stable_step() {
        for model in ["cohesive-beam", "bead-spring"] {
            let s = parse_scene(&format!(
                "dimensions = 3\n[time]\ndt = 1\n[[fibre]]\nmodel = \"{model}\"\nbeads = 5\nbead_radius = 1.2\nyoungs_modulus = 1e300\n"
            ))
            .unwrap();
            let f = Fibre::straight(&s.fibres[0], s.dimensions, s.has_fluid);
            assert_eq!(
                max_eigenvalue(&f, POWER_ITERATIONS).0,
                f64::INFINITY,
                "{model}"
            );
            let l = stability_limit(&f, 1);
            assert_eq!(
                (l.omega_max, l.step_limit, l.dt_limit),
                (f64::INFINITY, 0.0, 0.0)
            );
            assert_eq!(l.damping, f.damping);
        }
        assert_eq!(stable_step(f64::NAN, 0.0), 0.0);
    }

    #[test]
    fn power_iteration_matches_dense_eigenvalue() {
        for (model, dims, extra) in [
            ("cohesive-beam", 3, ""),
            ("cohesive-beam", 2, ""),
            ("cohesive-beam", 3, "clamp = [0]"),
            ("bead-spring", 3, ""),
            ("bead-spring", 2, "clamp = [0, 1]"),
            ("bead-spring", 2, "bending_stiffness = 100"),
        ] {
            for beads in [2, 3, 5, 10, 40] {
                let f = fibre(model, beads, dims, extra);
                eprintln!("{model} {dims} {extra} {beads}");
                let (lp, _) = max_eigenvalue(&f, POWER_ITERATIONS);
                let ld = dense_max(&f);
                let rel = if ld > 0.0 { (lp - ld).abs() / ld } else { lp };
                assert!(
                    rel < 2e-3,
                    "{model} {dims}D {extra} N={beads}: {lp} vs {ld} ({rel:.1e})"
                );
                assert!(lp <= ld * (1.0 + 1e-6));
            }
        }
    }

    #[test]
    fn straight_chain_analytic_axial_mode() {
        // Bead-spring with negligible bending: the top mode is the axial zigzag of a free
        // chain of N beads, ω² = (2 k / m)(1 + cos(π / N)) < 4 k / m, k = k_s / l0².
        for beads in [2, 5, 10, 100] {
            let f = fibre("bead-spring", beads, 3, "bending_stiffness = 1e-9");
            let k = match f.model {
                crate::fibre::Model::BeadSpring(b) => b.spring_stiffness(),
                _ => unreachable!(),
            };
            let exact = 2.0 * k / f.mass * (1.0 + (std::f64::consts::PI / beads as f64).cos());
            let (lp, _) = max_eigenvalue(&f, POWER_ITERATIONS);
            assert!(
                (lp - exact).abs() / exact < 1e-3,
                "N={beads}: {lp} vs {exact}"
            );
            assert!(lp < 4.0 * k / f.mass);
        }
        // Cohesive beam: at least the axial bound for the same chain.
        let f = fibre("cohesive-beam", 10, 3, "");
        let ka = match f.model {
            crate::fibre::Model::CohesiveBeam(b) => b.axial,
            _ => unreachable!(),
        };
        let axial = 2.0 * ka / f.mass * (1.0 + (std::f64::consts::PI / 10.0).cos());
        let (lp, _) = max_eigenvalue(&f, POWER_ITERATIONS);
        assert!(lp >= axial * (1.0 - 1e-3), "{lp} vs axial {axial}");
    }

    #[test]
    fn limit_is_sharp() {
        // Just below the limit the energy of a kicked fibre stays bounded, just above it grows.
        for model in ["cohesive-beam", "bead-spring"] {
            let base = fibre(model, 8, 3, "");
            let lim = stability_limit(&base, 1);
            let run = |factor: f64| {
                let mut f = base.clone();
                let h = lim.step_limit * factor;
                for k in 0..f.len() {
                    let s = if k % 2 == 0 { 1.0 } else { -1.0 };
                    f.vel[k] = Vec3::new(1e-3 * s, 0.7e-3 * s, -0.4e-3 * s);
                    if f.rotates {
                        f.omega[k] = Vec3::new(0.3e-3 * s, -0.8e-3 * s, 0.5e-3 * s);
                    }
                }
                let e0 = f.kinetic_energy();
                let mut emax: f64 = 0.0;
                for _ in 0..3000 {
                    f.advance_positions(h);
                    f.advance_velocities(h, None, true);
                    emax = emax.max(f.kinetic_energy() + f.energies.total());
                }
                emax / e0
            };
            let below = run(0.97);
            let above = run(1.03);
            assert!(below < 100.0, "{model}: {below}");
            assert!(above > 1e6, "{model}: {above}");
        }
    }

    #[test]
    fn long_fibres_use_a_representative_chain() {
        for (model, extra) in [("cohesive-beam", "clamp = [0]"), ("bead-spring", "")] {
            let f = fibre(model, 1000, 3, extra);
            let (full, _) = max_eigenvalue(&f, POWER_ITERATIONS);
            let (rep, _) = max_eigenvalue(&representative(&f), POWER_ITERATIONS);
            assert!(
                rep >= full * (1.0 - 1e-4) && rep <= full * (1.0 + 2e-3),
                "{model}: {rep} vs {full}"
            );
        }
    }

    #[test]
    fn damping_limit() {
        assert_eq!(stable_step(2.0, 0.0), 1.0);
        assert_eq!(stable_step(0.0, 4.0), 0.5);
        let h = stable_step(3.0, 0.7);
        assert!((h * h * 9.0 + 2.0 * h * 0.7 - 4.0).abs() < 1e-12);
    }
}
