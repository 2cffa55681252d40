//! The smoothed profile of one bead (L2020 eq. 25) and its integrals, shared by the fluid
//! node (which places the profiles on the grid) and the fibre node (which sizes the bead's
//! inertia against the fluid its profile exchanges momentum with).
//!
//! Volume of a profile. The profile is symmetric about the bead surface, so in 1D it holds
//! exactly the sharp volume; in 2D and 3D the curvature adds a second-order excess. Without
//! the cut-off, with `w = sqrt(2) xi` and `∫ s (phi - H)(s) ds = pi² w² / 24 = pi² xi² / 12`:
//!
//! ```text
//! 2D:  ∫ phi dA = pi r²          (1 + pi² xi² / (6 r²))
//! 3D:  ∫ phi dV = 4/3 pi r³      (1 + pi² xi² / (2 r²))
//! ```
//!
//! i.e. +4.6 % (2D) and +13.7 % (3D) for r = 6, xi = 1. The cut-off at xi_c = 3 xi (L2020)
//! removes more of the outer tail than it adds inside: the truncated profile holds +4.2 %
//! (2D) and +12.5 % (3D) for r = 6, xi = 1; +15.4 % (2D) for r = 6, xi = 2, xi_c = 5.
//!
//! The moment of inertia grows faster, since the excess sits at the rim: the truncated
//! profile of r = 6, xi = 2, xi_c = 5 holds 1.99 (2D) and 2.85 (3D) times the moment of
//! the sharp disc or sphere, 1.25 and 1.44 for xi = 1, xi_c = 3 ([`profile_moment`]).
use std::f64::consts::{PI, SQRT_2};

/// Default `fluid.xi` (interface width, grid units; L2020 uses 1 and 2).
pub const DEFAULT_XI: f64 = 1.0;
/// Default `fluid.xi_cutoff` in units of `fluid.xi` (L2020: xi = 1, xi_c = 3).
pub const DEFAULT_CUTOFF_OVER_XI: f64 = 3.0;
/// Default FPD interface ratio r_xi = xi / d (`fluid.interface_ratio`; S2023's 0.125).
pub const DEFAULT_FPD_INTERFACE_RATIO: f64 = 0.125;

/// L2020 eq. 25 as a function of the signed distance `s` into the solid (`s = r_b - |x - X|`
/// for a bead): 1 beyond `cutoff` inside, 0 beyond `cutoff` outside,
/// `1/2 + 1/2 tanh(s / (sqrt(2) xi))` in between.
#[inline]
pub fn interface(s: f64, xi: f64, cutoff: f64) -> f64 {
    if s > cutoff {
        1.0
    } else if s < -cutoff {
        0.0
    } else {
        0.5 + 0.5 * (s / (SQRT_2 * xi)).tanh()
    }
}

/// Largest step the cut-off may leave in a profile (its distance from 0 or 1 at
/// `|s| = cutoff`) before configure says so: L2020's xi_c = 2.5 xi leaves 0.028, 3 xi 0.014.
pub const TRUNCATION_STEP_NOTED: f64 = 0.03;

/// A note for a scene whose cut-off truncates the profile (L2020 eq. 25) where it still
/// differs from 0 and 1 by more than [`TRUNCATION_STEP_NOTED`]: every bead's surface then
/// carries a jump of that size, which no refinement of the grid removes.
pub fn truncation_note(xi: f64, cutoff: f64) -> Option<String> {
    let step = 1.0 - interface(cutoff, xi, f64::INFINITY);
    (step > TRUNCATION_STEP_NOTED).then(|| {
        format!(
            "fluid.xi_cutoff = {cutoff} is {:.2} fluid.xi: the profile (L2020 eq. 25) is cut \
             off where it is still {step:.3} from 0 and 1, so each bead's and wall's profile \
             jumps by that much at r_b +- xi_c; L2020 uses xi_c = 2.5 xi and 3 xi (steps \
             0.028 and 0.014; the default is 3 xi)",
            cutoff / xi
        )
    })
}

/// Distance from the surface, in units of `xi`, beyond which [`interface`] is exactly 0 or 1
/// in double precision (`tanh(x)` rounds to 1 for `x > 19.1`, and `28 / sqrt 2 = 19.8`).
pub const SATURATED_OVER_XI: f64 = 28.0;

/// `∫ w(r) phi(r)` over the plane (`dims = 2`, per unit depth) or space (`dims = 3`) for a
/// radial weight `w`: the sharp core analytically (`core`), the interface shell
/// `[r_b - xi_c, r_b + xi_c]` by Simpson quadrature along the radius.
fn radial_integral(
    radius: f64,
    xi: f64,
    cutoff: f64,
    dims: usize,
    core: impl Fn(f64) -> f64,
    weight: impl Fn(f64) -> f64,
) -> f64 {
    // Beyond SATURATED_OVER_XI xi the profile is exactly 0 or 1 in double precision, so a
    // longer cut-off changes nothing but the quadrature's step (and a huge one would make it
    // miss the interface and overflow the weights).
    let reach = cutoff.min(SATURATED_OVER_XI * xi);
    let (a, b) = ((radius - reach).max(0.0), radius + reach);
    let n = 20_000;
    let h = (b - a) / n as f64;
    let f = |r: f64| {
        let shell = if dims == 2 {
            2.0 * PI * r
        } else {
            4.0 * PI * r * r
        };
        shell * weight(r) * interface(radius - r, xi, cutoff)
    };
    let mut s = f(a) + f(b);
    for i in 1..n {
        s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    core(a) + s * h / 3.0
}

/// `∫ phi_i` of one bead's truncated profile (L2020 eq. 25) over the plane (`dims = 2`, per
/// unit depth) or space (`dims = 3`).
pub fn profile_volume(radius: f64, xi: f64, cutoff: f64, dims: usize) -> f64 {
    let core = |a: f64| {
        if dims == 2 {
            PI * a * a
        } else {
            4.0 / 3.0 * PI * a.powi(3)
        }
    };
    radial_integral(radius, xi, cutoff, dims, core, |_| 1.0)
}

/// `∫ phi_i d²` of one bead's truncated profile, with `d` the distance from an axis through
/// the centre (the z axis in 2D, per unit depth; any axis in 3D, where the mean of `d²` over
/// a shell of radius r is `2 r² / 3`): the moment of inertia of the profile at unit density.
pub fn profile_moment(radius: f64, xi: f64, cutoff: f64, dims: usize) -> f64 {
    let core = |a: f64| {
        if dims == 2 {
            PI * a.powi(4) / 2.0
        } else {
            8.0 / 15.0 * PI * a.powi(5)
        }
    };
    let weight = |r: f64| if dims == 2 { r * r } else { 2.0 / 3.0 * r * r };
    radial_integral(radius, xi, cutoff, dims, core, weight)
}

/// Bead radius, in interface widths `xi`, below which configure notes that the profile no
/// longer describes a solid bead: at `r_b = 2 xi` the profile reaches only 0.944 at the
/// centre. The validated resolutions have `r_b >= 3 xi` (L2020's capillary scenes: 6 and 2).
pub const SMALL_BEAD_OVER_XI: f64 = 2.0;

/// A note for a fibre (`path`, e.g. `fibre.0`) whose beads are under
/// [`SMALL_BEAD_OVER_XI`] interface widths: the profile (L2020 eq. 25) never reaches 1 inside
/// such a bead, and the fluid it moves is that of a bead of another radius.
pub fn small_bead_note(
    path: &str,
    radius: f64,
    xi: f64,
    cutoff: f64,
    dims: usize,
) -> Option<String> {
    (radius < SMALL_BEAD_OVER_XI * xi).then(|| {
        let centre = interface(radius, xi, cutoff);
        let volume = profile_volume(radius, xi, cutoff, dims);
        let equivalent = if dims == 2 {
            (volume / PI).sqrt()
        } else {
            (0.75 * volume / PI).cbrt()
        };
        format!(
            "{path}.bead_radius = {radius} is {:.2} fluid.xi: its smoothed profile (L2020 \
             eq. 25) reaches only phi = {centre:.3} at the bead's centre, so no part of the \
             bead is solid. The profile holds the volume of a sharp bead of radius \
             {equivalent:.3}, yet drags like a smaller one: a cylinder array's drag is already \
             12.6 % low at r_b = 3 xi (docs/validation/array_drag_xi.md). Lower fluid.xi \
             (with xi_cutoff) or raise the bead radius",
            radius / xi
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bead_narrower_than_two_interface_widths_is_noted() {
        assert_eq!(small_bead_note("fibre.0", 6.0, 2.0, 6.0, 2), None);
        assert_eq!(small_bead_note("fibre.0", 2.0, 1.0, 3.0, 3), None);
        let n = small_bead_note("fibre.1", 1.0, 2.0, 6.0, 2).unwrap();
        // phi(0) = 1/2 + 1/2 tanh(1 / (2 sqrt 2)) = 0.6699.
        assert!(
            n.starts_with("fibre.1.bead_radius = 1 is 0.50 fluid.xi"),
            "{n}"
        );
        assert!(n.contains("phi = 0.670 at the bead's centre"), "{n}");
        // The shell outside r_b holds more area than the one inside, so a narrow bead's
        // profile holds the fluid of a wider disc: sqrt(∫ phi dA / pi) = 2.3386 for r_b = 1,
        // xi = 2 (trapezoid rule on 2e5 intervals, independently of profile_volume).
        assert!(n.contains("a sharp bead of radius 2.339"), "{n}");
    }

    #[test]
    fn a_profile_cut_off_short_of_its_tails_is_noted() {
        // The step at the cut-off, 1/2 - 1/2 tanh(xi_c / (sqrt 2 xi)): 0.014 at L2020's
        // xi_c = 3 xi, 0.028 at 2.5 xi (xi = 2, xi_c = 5), 0.056 at 2 xi.
        assert!(truncation_note(1.0, 3.0).is_none());
        assert!(truncation_note(2.0, 5.0).is_none());
        let note = truncation_note(1.0, 2.0).expect("2 xi is noted");
        assert!(note.contains("0.056"), "{note}");
        let note = truncation_note(1.0, 0.5).expect("xi / 2 is noted");
        assert!(
            note.contains("0.330") && note.contains("0.50 fluid.xi"),
            "{note}"
        );
    }

    #[test]
    fn profile_is_in_unit_interval_and_half_at_the_surface() {
        for s in [-10.0, -3.0, -2.9, -1.0, 0.0, 0.5, 2.99, 3.0, 7.0] {
            let p = interface(s, 1.0, 3.0);
            assert!((0.0..=1.0).contains(&p));
        }
        assert_eq!(interface(0.0, 1.0, 3.0), 0.5);
        assert_eq!(interface(3.01, 1.0, 3.0), 1.0);
        assert_eq!(interface(-3.01, 1.0, 3.0), 0.0);
        // The jump at the cut-off (L2020's xi_c = 3 xi): 1 - phi(3 xi) = 1.4 %.
        assert!((1.0 - interface(3.0, 1.0, 3.0) - 0.014166).abs() < 1e-6);
    }

    /// The profile is exactly 0 and 1 from SATURATED_OVER_XI xi on, so any longer cut-off
    /// gives the same integrals; a huge one gives finite ones (it overflowed the weights).
    #[test]
    fn cut_offs_past_the_saturated_profile_change_nothing() {
        for xi in [0.5, 1.0, 2.0] {
            let s = SATURATED_OVER_XI * xi;
            assert_eq!(interface(s, xi, f64::INFINITY), 1.0);
            assert_eq!(interface(-s, xi, f64::INFINITY), 0.0);
            for dims in [2, 3] {
                let at = |c: f64| {
                    (
                        profile_volume(6.0, xi, c, dims),
                        profile_moment(6.0, xi, c, dims),
                    )
                };
                let (v, m) = at(s);
                assert!(v.is_finite() && m.is_finite());
                assert_eq!(at(2.0 * s), (v, m), "xi {xi}, {dims}D");
                assert_eq!(at(1e300), (v, m), "xi {xi}, {dims}D");
            }
        }
    }

    /// The analytic volumes of the module docs, against quadrature without truncation.
    #[test]
    fn volume_excess_follows_xi_squared_over_r_squared() {
        for (r, xi) in [(6.0f64, 1.0f64), (6.0, 2.0), (10.0, 1.0)] {
            let big = 40.0 * xi;
            let v2 = profile_volume(r, xi, big.min(r), 2);
            let v3 = profile_volume(r, xi, big.min(r), 3);
            let a2 = PI * r * r * (1.0 + PI * PI * xi * xi / (6.0 * r * r));
            let a3 = 4.0 / 3.0 * PI * r.powi(3) * (1.0 + PI * PI * xi * xi / (2.0 * r * r));
            // Neglected by the formula: phi < 1 at the centre and the tail beyond 2 r,
            // both of order exp(-sqrt(2) r / xi).
            let tail = 4.0 * (-SQRT_2 * r / xi).exp();
            assert!(
                (v2 / a2 - 1.0).abs() < tail,
                "2D r {r} xi {xi}: {v2} vs {a2}"
            );
            assert!(
                (v3 / a3 - 1.0).abs() < tail,
                "3D r {r} xi {xi}: {v3} vs {a3}"
            );
        }
    }

    /// A sharp profile (xi -> 0) has the moment of the disc, pi r^4 / 2, and of the sphere,
    /// 8 pi r^5 / 15; the first correction is second order in xi / r: with
    /// `∫ s (phi - H) ds = pi² xi² / 12` and the weight r^3 (2D) or (2/3) 4 pi r^4 (3D),
    /// the excess is pi² xi² / r² (2D, relative) and 5 pi² xi² / (3 r²) (3D).
    #[test]
    fn moment_of_a_sharp_profile_and_its_xi_squared_excess() {
        let r: f64 = 10.0;
        let (disc, sphere) = (PI * r.powi(4) / 2.0, 8.0 / 15.0 * PI * r.powi(5));
        let tiny = 1e-4;
        // The xi^2 excess is ~1e-9 here.
        assert!((profile_moment(r, tiny, 40.0 * tiny, 2) / disc - 1.0).abs() < 1e-8);
        assert!((profile_moment(r, tiny, 40.0 * tiny, 3) / sphere - 1.0).abs() < 1e-8);
        for xi in [0.25f64, 0.5] {
            let m2 = profile_moment(r, xi, 40.0 * xi, 2) / disc - 1.0;
            let m3 = profile_moment(r, xi, 40.0 * xi, 3) / sphere - 1.0;
            let e2 = PI * PI * xi * xi / (r * r);
            let e3 = 5.0 * PI * PI * xi * xi / (3.0 * r * r);
            // Next order: g'''(r) m3 / 6 against g'(r) m1 for the weight g = r^3 (2D) or r^4
            // (3D), with m3 / m1 = 7 pi^2 w^2 / 40 = 3.45 xi^2 for the tanh (Sommerfeld
            // moments of the Fermi function): 1.15 (xi / r)^2 (2D), 3.45 (xi / r)^2 (3D).
            let tol = 4.0 * (xi / r).powi(2);
            assert!((m2 / e2 - 1.0).abs() < tol, "2D xi {xi}: {m2} vs {e2}");
            assert!((m3 / e3 - 1.0).abs() < tol, "3D xi {xi}: {m3} vs {e3}");
        }
    }
}
